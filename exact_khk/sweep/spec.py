"""Sweep specification files (TOML): what to run, over which grid.

A spec names one task (:data:`~exact_khk.sweep.tasks.TASKS`), the systems (the
Lie–Poisson family over ranges of n and seeds, catalogue systems, or system
files), the points, and the grid of step sizes, arithmetics and step counts;
every combination is one task.  docs/sweeps.md lists every key::

    task = "certify"
    timeout = 120            # seconds per task (0: no limit)

    [system]
    family = "lie-poisson"
    n = "2-4"
    seeds = "0-9"

    [grid]
    eps = ["1/10", "1/7"]
    steps = 10

    [options]
    poisson_points = 2

Every problem is an :class:`~exact_khk.errors.InputError` naming the file and
the field at fault (``spec.toml: grid.eps[1]: '1/0' is not a rational
number``).  A task's *key* is a hash of its canonical parameters (rationals in
lowest terms, the normalised options, a system file by the digest of its
content): a rerun skips the tasks whose key already has a result.

>>> spec = parse_spec('task = "probe"\\n[system]\\nfamily = "lie-poisson"\\nn = [2, 3]\\nseeds = "0-1"\\n'
...                   '[grid]\\neps = ["0.1", "1/7"]\\n', origin="demo.toml")
>>> len(spec.tasks()), spec.tasks()[0].params["eps"], spec.tasks()[0].axes
(8, '1/10', {'n': 2, 'seed': 0, 'eps': '1/10'})
>>> parse_spec('task = "certify"\\n[system]\\nfamily = "lie-poisson"\\nn = 1\\nseeds = 0\\n', origin="bad.toml")
Traceback (most recent call last):
...
exact_khk.errors.InputError: bad.toml: system.n: the Lie–Poisson family needs n >= 2, got 1
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass, field
from decimal import Decimal
from fractions import Fraction
from pathlib import Path

from exact_khk.errors import InputError
from exact_khk.parsing import MAX_STEPS, _short, read_text_file
from exact_khk.sweep.tasks import TASKS, checked_timeout

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

#: the only spec format so far
SPEC_FORMAT = 1
#: the largest sweep a spec may describe
MAX_TASKS = 5_000_000
#: default per-task time limit in seconds (``timeout = 0`` in the spec: none)
DEFAULT_TIMEOUT = 600.0
MAX_SPEC_BYTES = 1_000_000

KEYS = {
    "": ("format", "name", "title", "task", "timeout", "system", "points", "grid", "options"),
    "system": ("family", "n", "seeds", "bound", "default", "catalogue", "file"),
    "points": ("seeds", "x0", "default"),
    "grid": ("eps", "arith", "steps"),
}


@dataclass(frozen=True)
class Task:
    """One task: its key, canonical parameters (JSON), the system file's spec to ship
    to the worker (or None) and its coordinates on the sweep's axes."""

    key: str
    params: dict
    system_spec: dict | None = None
    axes: dict = field(default_factory=dict)

    def payload(self, timeout=None, engine="local") -> dict:
        """What is sent to a worker (plain JSON data)."""
        out = {"key": self.key, "params": self.params, "timeout": timeout, "engine": engine}
        if self.system_spec is not None:
            out["system_spec"] = self.system_spec
        return out


def task_key(params: dict) -> str:
    """The content address of a task: sha256 of its canonical JSON, 20 hex digits."""
    text = json.dumps(params, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


@dataclass(frozen=True)
class _SystemEntry:
    params: dict          # the task parameters' "system"
    axes: dict            # its coordinates: n and seed, or the system's name
    dim: int
    n: int | None
    default_eps: Fraction
    spec: dict | None     # an expression system's to_json (shipped to the worker)
    seed: int | None = None


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep spec (see the module docstring); :meth:`tasks` expands it."""

    name: str
    title: str
    task: str
    timeout: float | None
    systems: tuple
    points: tuple          # ("same",) | ("seeds", [..]) | ("x0", [..]) | ("default",)
    eps: tuple | None      # None: each system's default step size
    ariths: tuple
    steps: tuple
    options: dict
    origin: str = "<string>"
    text: str = ""

    @property
    def digest(self) -> str:
        return hashlib.sha256(self.text.encode()).hexdigest()

    def tasks(self) -> list:
        """Every task, in a fixed order: system, point, ε, arithmetic, steps."""
        out, seen = [], set()
        eps_values = self.eps if self.eps is not None else {str(s.default_eps) for s in self.systems}
        vary = {"eps": len(eps_values) > 1, "arith": len(self.ariths) > 1,
                "steps": len(self.steps) > 1}
        for s in self.systems:
            for point, paxis in self._points(s):
                for eps in (self.eps if self.eps is not None else (str(s.default_eps),)):
                    for arith in self.ariths:
                        for steps in self.steps:
                            params = {"task": self.task, "system": s.params, "point": point, "eps": eps,
                                      "arith": arith, "steps": steps, "options": self.options}
                            key = task_key(params)
                            if key in seen:  # e.g. the same point listed twice
                                continue
                            seen.add(key)
                            axes = dict(s.axes)
                            if paxis is not None:
                                axes["point"] = paxis
                            axes.update({k: v for k, v in (("eps", eps), ("arith", arith), ("steps", steps))
                                         if vary[k]})
                            out.append(Task(key, params, s.spec, axes))
        return out

    def _points(self, s):
        kind = self.points[0]
        if kind == "same":
            return [({"seed": s.seed}, None)]
        if kind == "seeds":
            return [({"seed": k}, k) for k in self.points[1]]
        if kind == "x0":
            many = len(self.points[1]) > 1
            return [({"x0": x}, ("(" + ", ".join(x) + ")") if many else None) for x in self.points[1]]
        return [({"default": True}, None)]

    def count(self) -> int:
        per_system = {"same": 1, "default": 1}.get(self.points[0]) or len(self.points[1])
        return (len(self.systems) * per_system * (len(self.eps) if self.eps is not None else 1)
                * len(self.ariths) * len(self.steps))


# --- reading ---------------------------------------------------------------------------


def load_spec(path) -> SweepSpec:
    """Read a spec file; every problem is an InputError naming the file and the field."""
    p = Path(path)
    text = read_text_file(p, "sweep spec file", MAX_SPEC_BYTES)
    return parse_spec(text, origin=str(path), base=p.parent, default_name=p.stem)


def parse_spec(text: str, origin: str = "<string>", base=None, default_name: str = "sweep") -> SweepSpec:
    """A spec from its TOML text; ``base`` is the folder system files are relative to."""
    err = _Err(origin)
    try:
        t = tomllib.loads(text, parse_float=Decimal)
    except (tomllib.TOMLDecodeError, ValueError) as exc:
        raise InputError(f"{origin}: not valid TOML: {exc}") from None
    except RecursionError:  # tomllib reads nested arrays and tables recursively
        raise InputError(f"{origin}: arrays or tables nested too deeply for a sweep spec") from None
    _known(t, "", err)
    fmt = t.get("format", SPEC_FORMAT)
    if fmt != SPEC_FORMAT:
        raise err("format", f"this reader knows format {SPEC_FORMAT}, got {fmt!r}")
    name = t.get("name", default_name)
    title = t.get("title", "")
    for key, v in (("name", name), ("title", title)):
        if not isinstance(v, str):
            raise err(key, f"expected a string, got {v!r}")
    if "task" not in t:
        raise err("task", f"missing; one of {', '.join(sorted(TASKS))}")
    task = t["task"]
    if not isinstance(task, str) or task not in TASKS:
        raise err("task", f"unknown task {task!r}; available: {', '.join(sorted(TASKS))}")
    kind = TASKS[task]
    try:
        timeout = checked_timeout(t.get("timeout", DEFAULT_TIMEOUT))
    except InputError as exc:
        raise err("", str(exc)) from None

    if "system" not in t:
        raise err("system", "missing table [system]: family = \"lie-poisson\" (with n and seeds), "
                            "catalogue = NAME or file = PATH")
    systems = _systems(_table(t["system"], "system", err), err, Path(base) if base is not None else Path("."))
    points = _points(_table(t.get("points", {}), "points", err), systems, err)
    grid = _table(t.get("grid", {}), "grid", err)
    _known(grid, "grid", err)
    eps = None if "eps" not in grid else tuple(_eps_values(grid["eps"], err))
    ariths = tuple(_ariths(grid.get("arith"), kind, err))
    steps = tuple(_steps(grid.get("steps", kind.default_steps), kind, err))
    options = _options(_table(t.get("options", {}), "options", err), kind, systems, err)
    spec = SweepSpec(name, title, task, timeout, tuple(systems), points, eps, ariths, steps, options,
                     origin, text)
    total = spec.count()
    if total > MAX_TASKS:
        raise err("", f"the sweep has {total} tasks, more than the limit of {MAX_TASKS}")
    if total == 0:
        raise err("", "the sweep has no task")
    return spec


class _Err:
    """``err(where, message)``: the InputError ``ORIGIN: where: message``."""

    def __init__(self, origin: str):
        self.origin = origin

    def __call__(self, where, msg) -> InputError:
        return InputError(f"{self.origin}: {where}: {msg}" if where else f"{self.origin}: {msg}")


def _table(value, where, err) -> dict:
    if not isinstance(value, dict):
        raise err(where, f"expected a table [{where}], got {value!r}")
    return value


def _known(t, where, err):
    unknown = [k for k in t if k not in KEYS[where]]
    if unknown:
        at = f"{where}.{unknown[0]}" if where else unknown[0]
        raise err(at, f"unknown key; known keys{' in [' + where + ']' if where else ''}: {', '.join(KEYS[where])}")


def int_range(value, where, err, minimum=0, limit=1_000_000, maximum=None) -> list:
    """Integers from ``3``, ``[2, 3, 5]`` or ``"0-199"`` / ``"2-4,7"`` (in that order,
    without repeats); at most ``limit`` of them, each in [minimum, maximum]."""
    if isinstance(value, bool):
        raise err(where, f"expected an integer, a list of integers or a range such as '0-9', got {value!r}")
    if isinstance(value, int):
        out = [value]
    elif isinstance(value, list):
        if not value or not all(isinstance(v, int) and not isinstance(v, bool) for v in value):
            raise err(where, f"expected a non-empty list of integers, got {value!r}")
        out = list(value)
    elif isinstance(value, str):
        out = []
        for part in value.replace(" ", "").split(","):
            lo, dash, hi = part.partition("-")
            try:
                a, b = int(lo), int(hi) if dash else int(lo)
            except ValueError:
                raise err(where, f"{value!r} is not a range such as '0-9' or '2-4,7'") from None
            if b < a:
                raise err(where, f"{part!r}: the range is empty ({b} < {a})")
            if b - a + 1 + len(out) > limit:
                raise err(where, f"more than {limit} values")
            out.extend(range(a, b + 1))
    else:
        raise err(where, f"expected an integer, a list of integers or a range such as '0-9', got {value!r}")
    if len(out) > limit:
        raise err(where, f"more than {limit} values")
    low = [v for v in out if v < minimum]
    if low:
        raise err(where, f"values must be >= {minimum}, got {low[0]}")
    high = [v for v in out if maximum is not None and v > maximum]
    if high:
        raise err(where, f"values must be <= {maximum:,}, got {_short(high[0])}")
    return list(dict.fromkeys(out))


def _systems(s, err, base: Path) -> list:
    _known(s, "system", err)
    chosen = [k for k in ("family", "catalogue", "file") if k in s]
    if len(chosen) != 1:
        raise err("system", "give exactly one of family = \"lie-poisson\", catalogue = NAME(S) or file = PATH(S)"
                  + (f" (got {', '.join(chosen)})" if chosen else ""))
    if chosen[0] == "family":
        if s["family"] != "lie-poisson":
            raise err("system.family", f"unknown family {s['family']!r}; the only family is 'lie-poisson'")
        return _family(s, err)
    for key in ("n", "seeds", "bound", "default"):
        if key in s:
            raise err(f"system.{key}", "applies to family = \"lie-poisson\" only")
    names = s[chosen[0]]
    names = [names] if isinstance(names, str) else names
    if not isinstance(names, list) or not names or not all(isinstance(v, str) for v in names):
        raise err(f"system.{chosen[0]}", f"expected a name or a list of names, got {s[chosen[0]]!r}")
    out = []
    for i, name in enumerate(names):
        where = f"system.{chosen[0]}" + (f"[{i}]" if len(names) > 1 else "")
        try:
            if chosen[0] == "catalogue":
                from exact_khk.systems.catalogue import load

                system = load(name)
            else:
                from exact_khk.systems.expressions import load_system

                path = Path(name) if os.path.isabs(name) else base / name
                system = load_system(path)
        except InputError as exc:
            raise err(where, str(exc)) from None
        spec = system.to_json()
        digest = hashlib.sha256(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:16]
        out.append(_SystemEntry({"name": system.name, "digest": digest}, {"system": system.name}, system.dim,
                                None, Fraction(system.default_eps), spec))
    if len(out) == 1:
        out = [_SystemEntry(e.params, {}, e.dim, e.n, e.default_eps, e.spec) for e in out]
    return out


def _family(s, err) -> list:
    from exact_khk.systems.lie_poisson.system import DEFAULT_EPS

    if s.get("default", False) is True:
        for key in ("n", "seeds", "bound"):
            if key in s:
                raise err(f"system.{key}", "cannot be combined with default = true (the built-in n = 3 system)")
        return [_SystemEntry({"family": "lie-poisson", "default": True}, {}, 6, 3, DEFAULT_EPS, None)]
    if "default" in s and s["default"] is not False:
        raise err("system.default", f"expected true or false, got {s['default']!r}")
    for key in ("n", "seeds"):
        if key not in s:
            raise err(f"system.{key}", "missing (the family needs n and seeds, or default = true)")
    ns = int_range(s["n"], "system.n", err, minimum=-10**9, limit=4096)
    small = [n for n in ns if n < 2]
    if small:
        raise err("system.n", f"the Lie–Poisson family needs n >= 2, got {small[0]}")
    seeds = int_range(s["seeds"], "system.seeds", err)
    bound = s.get("bound", 3)
    if isinstance(bound, bool) or not isinstance(bound, int) or bound < 1:
        raise err("system.bound", f"expected a positive integer (coefficients in [-bound, bound]), got {bound!r}")
    extra = {} if bound == 3 else {"bound": bound}
    vary_n, vary_seed = len(ns) > 1, len(seeds) > 1
    out = []
    for n in ns:
        for seed in seeds:
            axes = ({"n": n} if vary_n else {}) | ({"seed": seed} if vary_seed else {})
            out.append(_SystemEntry({"family": "lie-poisson", "n": n, "seed": seed, **extra}, axes, 2 * n, n,
                                    DEFAULT_EPS, None, seed))
    return out


def _points(p, systems, err) -> tuple:
    _known(p, "points", err)
    family = systems[0].n is not None and systems[0].spec is None and "default" not in systems[0].params
    chosen = [k for k in ("seeds", "x0", "default") if k in p]
    if len(chosen) > 1:
        raise err("points", f"give one of seeds, x0 or default (got {', '.join(chosen)})")
    if not chosen:
        return ("same",) if family else ("default",)
    key = chosen[0]
    if key == "default":
        if p["default"] is not True:
            raise err("points.default", f"expected true, got {p['default']!r}")
        return ("default",)
    if key == "seeds":
        if p["seeds"] == "same":
            if not family:
                raise err("points.seeds", "'same' means the system's seed; only the random Lie–Poisson "
                                          "family has one")
            return ("same",)
        return ("seeds", int_range(p["seeds"], "points.seeds", err))
    x0 = p["x0"]
    if isinstance(x0, list) and x0 and not any(isinstance(v, list) for v in x0):
        x0 = [x0]  # one point
    if not isinstance(x0, list) or not x0 or not all(isinstance(v, list) for v in x0):
        raise err("points.x0", f"expected a point (a list of rationals) or a list of points, got {p['x0']!r}")
    dims = sorted({s.dim for s in systems})
    out = []
    for i, pt in enumerate(x0):
        where = f"points.x0[{i}]" if len(x0) > 1 else "points.x0"
        if len(dims) > 1:
            raise err(where, f"explicit points need systems of one dimension; the sweep has dimensions "
                             f"{', '.join(map(str, dims))}")
        if len(pt) != dims[0]:
            raise err(where, f"expected {dims[0]} coordinates, got {len(pt)}")
        out.append([str(_rational(v, f"{where}[{j}]", err)) for j, v in enumerate(pt)])
    return ("x0", out)


def _rational(value, where, err) -> Fraction:
    from exact_khk.parsing import parse_rational

    if isinstance(value, Decimal):
        value = str(value)
    try:
        return parse_rational(value, where)
    except InputError as exc:
        msg = str(exc)
        raise err(where, msg[len(where) + 2:] if msg.startswith(where + ": ") else msg) from None


def _eps_values(value, err) -> list:
    """A list of rationals, one rational, or {start, stop, count} (evenly spaced, exact)."""
    where = "grid.eps"
    if isinstance(value, dict):
        unknown = [k for k in value if k not in ("start", "stop", "count")]
        if unknown or not all(k in value for k in ("start", "stop", "count")):
            raise err(where, "a range of step sizes is {start = \"1/100\", stop = \"1/2\", count = 10}")
        a, b = _rational(value["start"], f"{where}.start", err), _rational(value["stop"], f"{where}.stop", err)
        count = value["count"]
        if isinstance(count, bool) or not isinstance(count, int) or count < 1 or count > 1_000_000:
            raise err(f"{where}.count", f"expected an integer from 1 to 1,000,000, got {count!r}")
        vals = [a] if count == 1 else [a + (b - a) * Fraction(i, count - 1) for i in range(count)]
    else:
        items = value if isinstance(value, list) else [value]
        if not items:
            raise err(where, "expected at least one step size")
        vals = [_rational(v, f"{where}[{i}]" if isinstance(value, list) else where, err)
                for i, v in enumerate(items)]
    for i, v in enumerate(vals):
        if v == 0:
            raise err(f"{where}[{i}]" if len(vals) > 1 else where, "the step size must be nonzero")
    return list(dict.fromkeys(str(v) for v in vals))


def _ariths(value, kind, err) -> list:
    from exact_khk.arith import default_arith, get_arith

    if value is None:
        value = ["float"] if kind.arith == "floating" else [default_arith().name]
    items = value if isinstance(value, list) else [value]
    if not items or not all(isinstance(v, str) for v in items):
        raise err("grid.arith", f"expected an arithmetic name or a list of names, got {value!r}")
    out = []
    for i, name in enumerate(items):
        where = f"grid.arith[{i}]" if isinstance(value, list) else "grid.arith"
        try:
            ar = get_arith(name)
        except InputError as exc:
            raise err(where, str(exc)) from None
        if kind.arith == "floating" and ar.exact:
            raise err(where, f"{kind.name} compares a floating or ball arithmetic with the exact orbit; "
                             f"{ar.name!r} is exact")
        if kind.arith == "exact" and not ar.exact:
            raise err(where, f"{kind.name} needs an exact arithmetic; {ar.name!r} is not")
        out.append(ar.name)
    return list(dict.fromkeys(out))


def _steps(value, kind, err) -> list:
    vals = int_range(value, "grid.steps", err, minimum=kind.min_steps, limit=100_000, maximum=MAX_STEPS)
    return vals


def _options(o, kind, systems, err) -> dict:
    family = systems[0].spec is None
    ctx = {"ns": sorted({s.n for s in systems if s.n is not None})}
    out = {}
    for key, value in o.items():
        where = f"options.{key}"
        opt = kind.options.get(key)
        if opt is None:
            known = ", ".join(sorted(kind.options)) or "none"
            raise err(where, f"unknown option of task {kind.name!r}; its options: {known}")
        if opt.applies == "lie-poisson" and not family:
            raise err(where, "applies to the Lie–Poisson family only")
        if opt.applies == "expressions" and family:
            raise err(where, "applies to catalogue systems and system files only")
        try:
            out[key] = opt.check(value, where, ctx)
        except InputError as exc:  # the checkers name the field themselves
            raise InputError(f"{err.origin}: {exc}") from None
    return dict(sorted(out.items()))
