"""The tasks a sweep runs, and the one function every worker calls: :func:`run_task`.

A task is described by plain JSON-compatible data (its *payload*: rationals as
strings, seeds as integers) and returns plain JSON-compatible data (its
*record*), so that nothing unpicklable crosses a process or network boundary:
systems, points and python-flint/mpmath numbers are built inside the worker.

The registry :data:`TASKS` maps a task name to a :class:`TaskKind`: its
function, the options it accepts (each with a checker that names the option at
fault), the arithmetics it makes sense for and its default number of steps.
Adding a task is one entry::

    register(TaskKind("degrees", _degrees, "degree sequence of the iterates",
                      options={"field": Option(_text, "a field of the system")}))

with ``_degrees(inp)`` returning ``{"verdict": ..., "detail": ..., "figures": {...}}``
(``figures`` flat: name -> number, string, bool or None).

Verdicts.  A task function returns its own verdict (``certify``: VALID, INVALID,
INCONCLUSIVE; ``orbit``/``probe``: OK; ``scale``: OK, WARNED, SINGULAR,
UNDECIDED; ``degrees``: OK, or UNDETERMINED when the sequence is too short to
classify; ``find-integrals``: FOUND when an integral was found and verified
exactly, else NONE).  :func:`run_task` adds the verdicts of what was raised: SINGULAR
(a singular Kahan step, :class:`~exact_khk.errors.SingularStepError`: the
theorems say nothing there), UNDEFINED (an integral at its pole), UNDECIDED
(ball arithmetic cannot decide), TIMEOUT (the per-task time limit) and ERROR
(anything else that was raised, with its one-line message).  ERROR and TIMEOUT
are *failed* tasks (:data:`FAILED`).

Time limit inside the worker (:func:`time_limit`): in the main thread of a
POSIX process (the local process pool, ``--workers 0``) an interval timer
(``signal.setitimer``) raises :class:`TaskTimeout` in the task; in any other
thread (a Dask worker runs tasks in a thread pool) a watchdog thread raises it
asynchronously in the task's thread (``PyThreadState_SetAsyncExc``).  Either
way the exception arrives between two Python bytecodes: a single long call into
C (one huge python-flint solve) is interrupted only when it returns.  The
local engine therefore also enforces a hard limit from outside: it kills the
worker process and replaces it (see :mod:`exact_khk.sweep.run`).

>>> sorted(TASKS)
['certify', 'classify', 'degrees', 'find-integrals', 'orbit', 'probe', 'scale']
>>> rec = run_task({"key": "k", "params": {"task": "probe", "system": {"family": "lie-poisson", "n": 2, "seed": 1},
...                 "point": {"seed": 1}, "eps": "1/10", "arith": "flint", "steps": 1, "options": {}}})
>>> rec["verdict"], rec["figures"]["n"], rec["error"]
('OK', 2, None)
"""

from __future__ import annotations

import ctypes
import datetime
import functools
import json
import math
import os
import signal
import socket
import sys
import threading
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from decimal import Decimal
from fractions import Fraction
from typing import Callable

from exact_khk.errors import InputError, PoleError, SingularStepError, UndecidedError
from exact_khk.parsing import _short, any_int_digits

#: version of a result line (``results.jsonl``)
RECORD_FORMAT = 1
#: every verdict a result line can carry, from "as expected" to "failed" (the order of the
#: summaries); each task kind's ``verdicts`` (checked by :func:`register`) and
#: :data:`ENGINE_VERDICTS` are among them, and ``--only`` accepts no other
VERDICTS = ("VALID", "OK", "FOUND", "NONE", "INCONCLUSIVE", "WARNED", "UNDETERMINED", "INVALID", "SINGULAR",
            "UNDEFINED", "UNDECIDED", "TIMEOUT", "ERROR")
#: verdicts of failed tasks (rerun with ``--only failed``)
FAILED = ("ERROR", "TIMEOUT")
#: verdicts that :func:`run_task` gives from what was raised
ENGINE_VERDICTS = ("SINGULAR", "UNDEFINED", "UNDECIDED", "TIMEOUT", "ERROR")
#: longest error/detail message kept in a record (characters)
MAX_MESSAGE = 500
#: the longest time a sweep accepts, in seconds (a task's time limit, the probe's sleep): a
#: year, well within what ``signal.setitimer`` and ``threading.Timer`` take
MAX_SECONDS = 365 * 24 * 3600


class TaskTimeout(BaseException):
    """Raised inside a task that exceeds its time limit (a BaseException, so that
    no ``except Exception`` inside the libraries swallows it)."""


# --- options -----------------------------------------------------------------------


@dataclass(frozen=True)
class Option:
    """A task option: ``check(value, where, context) -> normalised value`` raises an
    InputError naming ``where``; ``applies`` is 'any', 'lie-poisson' or 'expressions'
    (the kind of system the option makes sense for)."""

    check: Callable
    help: str
    applies: str = "any"


def _positive_int(value, where, ctx=None):
    if not isinstance(value, int) or isinstance(value, bool) or value < 1:
        raise InputError(f"{where}: expected a positive integer, got {value!r}")
    return value


def _nonnegative_int(value, where, ctx=None):
    if not isinstance(value, int) or isinstance(value, bool) or value < 0:
        raise InputError(f"{where}: expected a non-negative integer, got {value!r}")
    return value


def _bool(value, where, ctx=None):
    if not isinstance(value, bool):
        raise InputError(f"{where}: expected true or false, got {value!r}")
    return value


def _text(value, where, ctx=None):
    if not isinstance(value, str) or not value.strip():
        raise InputError(f"{where}: expected a non-empty string, got {value!r}")
    return value.strip()


def _seconds(value, where, ctx=None):
    """A number of seconds from 0 to :data:`MAX_SECONDS` (a float; a TOML number is a Decimal)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, Decimal)):
        raise InputError(f"{where}: expected a number of seconds, got {_short(value)}")
    if isinstance(value, Decimal):
        value = float(value)  # inf beyond the float range; an int is compared exactly
    if not 0 <= value <= MAX_SECONDS:  # nan fails too
        raise InputError(f"{where}: expected a number of seconds from 0 to {MAX_SECONDS:,} (a year), "
                         f"got {_short(value)}")
    return float(value)


def checked_timeout(value, where="timeout"):
    """A per-task time limit in seconds (:func:`_seconds`), None for 0 or None (no limit)."""
    return None if value is None else _seconds(value, where) or None


def _int_list(value, where, ctx=None):
    if isinstance(value, int) and not isinstance(value, bool):
        value = [value]
    if not isinstance(value, list) or not all(isinstance(v, int) and not isinstance(v, bool) for v in value):
        raise InputError(f"{where}: expected a list of integers (system seeds), got {value!r}")
    return sorted(set(value))


def _signs(value, where, ctx=None):
    """'b0' (B_0 = '-+…+' for every n), 'default' (every rational involution but ±I)
    or a list of sign patterns (all of the same length n)."""
    from exact_khk.parsing import format_signs, parse_signs

    if value in ("b0", "default"):
        return value
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not value or not all(isinstance(s, str) for s in value):
        raise InputError(f"{where}: expected 'b0', 'default' or a list of sign patterns such as ['-++'], "
                         f"got {value!r}")
    out = []
    for i, s in enumerate(value):
        n = len(s.strip())
        try:
            out.append(format_signs(parse_signs(s, n)))
        except InputError as exc:
            raise InputError(f"{where}[{i}]: {exc}") from None
        if ctx is not None and ctx.get("ns") and any(m != n for m in ctx["ns"]):
            raise InputError(f"{where}[{i}]: {s!r} is a pattern for n = {n}, but the sweep has n = "
                             f"{', '.join(map(str, ctx['ns']))}; use 'b0' for B_0 at every n")
    return out


def _claims(value, where, ctx=None):
    from exact_khk.certification.claims import CLAIMS

    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not value or not all(isinstance(c, str) for c in value):
        raise InputError(f"{where}: expected a list of claims among {', '.join(CLAIMS)}, got {value!r}")
    for c in value:
        if c not in CLAIMS:
            raise InputError(f"{where}: unknown claim {c!r}; expected some of {', '.join(CLAIMS)}")
    return list(dict.fromkeys(value))


def _gf(value, where, ctx=None):
    """A ``gf:P`` arithmetic, read as the task reads it (:func:`~exact_khk.arith.get_arith`)."""
    from exact_khk.arith import get_arith
    from exact_khk.arith.cyclotomic import GFArith

    name = _text(value, where)
    try:
        ar = get_arith(name)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    if not isinstance(ar, GFArith):
        raise InputError(f"{where}: expected a gf:P arithmetic (P prime), got {ar.name!r}")
    return ar.name


def _method(value, where, ctx=None):
    from exact_khk.kahan.map import METHODS

    if value not in METHODS:
        raise InputError(f"{where}: expected one of {', '.join(METHODS)}, got {value!r}")
    return value


# --- the task kinds ---------------------------------------------------------------


@dataclass(frozen=True)
class TaskInput:
    """What a task function receives: the system, x0 (Fractions), ε (Fraction), the
    arithmetic's name, the number of steps and the (normalised) options."""

    system: object
    x0: tuple
    eps: Fraction
    arith: str
    steps: int
    options: dict
    params: dict = field(default_factory=dict)


@dataclass(frozen=True)
class TaskKind:
    """One kind of task (see the module docstring).

    ``run(inp: TaskInput) -> {"verdict", "detail", "figures"}``; ``arith``: 'any',
    'exact' or 'floating' (checked when the spec is read); ``verdicts``: those
    ``run`` returns; ``ok``: the verdict that means "as expected" (the summary's
    success share); ``min_steps``: the smallest number of steps accepted;
    ``figures``: the figures the summary shows first (all are recorded).
    """

    name: str
    run: Callable
    help: str
    options: dict = field(default_factory=dict)
    default_steps: int = 10
    min_steps: int = 1
    arith: str = "any"
    verdicts: tuple = ("OK",)
    ok: str = "OK"
    figures: tuple = ()


#: task name -> TaskKind
TASKS: dict = {}


def register(kind: TaskKind) -> TaskKind:
    """Add (or replace) a task kind in :data:`TASKS`; its verdicts must be in :data:`VERDICTS`."""
    unknown = [v for v in (*kind.verdicts, kind.ok) if v not in VERDICTS]
    if unknown:
        raise ValueError(f"task kind {kind.name!r}: verdicts {unknown} are not in VERDICTS")
    TASKS[kind.name] = kind
    return kind


def _names(checks) -> str:
    shown = [c.name for c in checks[:4]]
    more = f" and {len(checks) - 4} more" if len(checks) > 4 else ""
    return "; ".join(shown) + more


def _certify(inp: TaskInput) -> dict:
    from exact_khk.certification import certify
    from exact_khk.systems.lie_poisson.system import b0_signs

    opts = dict(inp.options)
    if opts.get("signs") == "b0":
        opts["signs"] = [b0_signs(inp.system.n)]
    elif opts.get("signs") == "default":
        opts.pop("signs")
    cert = certify(inp.system, inp.x0, inp.eps, inp.steps, inp.arith, **opts)
    checks = cert.checks
    wrong = [c for c in checks if c.wrong]
    open_ = [c for c in checks if not c.passed and not c.wrong]
    status = cert.status
    detail = ("" if status == "VALID" else f"false: {_names(wrong)}" if wrong
              else f"undecided or did not fail: {_names(open_)}" if open_
              else "no negative control can fail at this point (all inapplicable)")
    return {"verdict": status, "detail": detail, "figures": {
        "checks": len(checks), "claims": sum(c.expected for c in checks),
        "controls": sum((not c.expected) and c.applicable for c in checks),
        "inapplicable": sum(not c.applicable for c in checks),
        "false": len(wrong), "open": len(open_), "height_bits": cert.height_bits, "path": cert.path or None}}


def _orbit(inp: TaskInput) -> dict:
    from exact_khk.arith import get_arith, point_height
    from exact_khk.kahan.map import KahanMap

    from exact_khk.systems.lie_poisson.system import expresses_omega

    ar = get_arith(inp.arith)
    fld = inp.system.named_field(inp.options.get("field", "f"),  # ω asked for only when a pattern is named
                                 cyclotomic=lambda: expresses_omega(ar, inp.system.n))
    phi = KahanMap(fld, inp.eps, ar, method=inp.options.get("method", "auto"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pts = phi.orbit(inp.x0, inp.steps)
    figures = {"steps": inp.steps, "path": phi.path,
               "near_singular_warnings": sum(1 for w in caught if "condition" in str(w.message).lower())}
    if ar.rational:
        heights = [point_height(ar, p) for p in pts]
        figures.update(final_height_bits=heights[-1], max_height_bits=max(heights),
                       height_growth_exponent=_growth_exponent(heights), heights=heights)
    if ar.rational or not ar.exact:
        norm = max((abs(ar.to_float(t)) for t in pts[-1]), default=0.0)
        figures["final_abs_max"] = norm if math.isfinite(norm) else str(norm)
    return {"verdict": "OK", "detail": "", "figures": figures}


def _growth_exponent(heights) -> float | None:
    """Least-squares slope of log(height) against log(k) over the second half of the
    orbit (k ≥ K/2, k ≥ 1): the exponent p of a growth like k^p (1 linear, 2
    quadratic); for exponential growth it increases with K; None for fewer than 2
    points."""
    K = len(heights) - 1
    ks = [k for k in range(max(1, K // 2), K + 1) if heights[k] > 0]
    if len(ks) < 2:
        return None
    xs = [math.log(k) for k in ks]
    ys = [math.log(heights[k]) for k in ks]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    if sxx == 0:
        return None
    return round(sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx, 6)


def _scale(inp: TaskInput) -> dict:
    from exact_khk.studies.scaling import jsonable, run_orbit

    run = run_orbit(inp.system, inp.x0, inp.eps, inp.steps, inp.arith,
                    diagnostics=inp.options.get("diagnostics", True))
    summary = run.summary()
    for k in ("seconds_per_step", "message", "arith", "rows"):
        summary.pop(k, None)
    figures = dict(summary)
    last = {}
    for row in run.rows:  # the last value of each integral's drift
        last.update({k: v for k, v in (row.drift_log10 or {}).items()})
    for name, v in sorted(last.items()):
        figures[f"drift_log10[{name}]"] = v
    verdict = {"ok": "OK", "warned": "WARNED", "singular": "SINGULAR", "undecided": "UNDECIDED"}.get(
        run.status, run.status.upper())
    return {"verdict": verdict, "detail": _one_line(run.message), "figures": jsonable(figures)}


def _degrees(inp: TaskInput) -> dict:
    from exact_khk.diagnostics import degree_sequence

    res = degree_sequence(inp.system, steps=inp.steps, eps=inp.eps, field=inp.options.get("field", "f"),
                          primes=inp.options.get("primes", 2), seed=inp.options.get("line_seed", 0),
                          heights=inp.options.get("heights", False), x0=inp.x0)
    fit = res.fit
    dd = fit.dynamical_degree
    return {"verdict": "OK" if fit.growth != "undetermined" else "UNDETERMINED", "detail": _one_line(fit.reason),
            "figures": {"growth": fit.growth, "polynomial_degree": fit.polynomial_degree,
                        "dynamical_degree": dd.value if dd else None,
                        "minimal_polynomial": dd.minimal_polynomial if dd else None,
                        "recurrence": fit.characteristic_text(), "last_degree": res.degrees[-1],
                        "degrees": list(res.degrees), "disagreeing_runs": len(res.disagreeing),
                        "undercount_bound": res.undercount_bound, "routes": sorted(set(res.routes)),
                        "height_growth": res.heights.growth if res.heights is not None else None}}


def _find_integrals(inp: TaskInput) -> dict:
    from exact_khk.diagnostics import find_integrals

    res = find_integrals(inp.system, degree=inp.options.get("degree", 2), field=inp.options.get("field", "f"),
                         eps=inp.eps, steps=inp.steps or None, seed=inp.options.get("line_seed", 0))
    verified = sum(1 for f in res.integrals if f.verified)
    return {"verdict": "FOUND" if verified else "NONE", "detail": "",
            "figures": {"kernel_dim": res.kernel_dim, "trivial_dim": res.trivial_dim, "new_dim": res.new_dim,
                        "integrals": len(res.integrals), "verified": verified, "independent": res.independent}}


def _classify(inp: TaskInput) -> dict:
    from exact_khk.diagnostics.classify import classify

    o = inp.options
    res = classify(inp.system, eps=inp.eps, steps=inp.steps, degree=o.get("degree"), field=o.get("field", "f"),
                   seed=o.get("line_seed", 0), exact=o.get("exact", 6),
                   discover=() if o.get("no_discover", False) else ("measure", "poisson"))
    data = res.to_json()
    return {"verdict": {"integrable": "OK", "non-integrable": "OK"}.get(res.verdict, "UNDETERMINED"),
            "detail": _one_line(f"{res.verdict}: {res.reason}"),
            "figures": {"classification": res.verdict, "growth": data["growth"]["class"],
                        "independent_integrals": res.independent_integrals,
                        "json": json.dumps(data, sort_keys=True)}}


def _probe(inp: TaskInput) -> dict:
    """An engine probe: no mathematics.  Sleeps ``sleep`` seconds; raises at the
    system seeds in ``fail``; runs for an hour in Python (short sleeps, which
    the time limit interrupts) at the seeds in ``slow``; blocks in one long C
    call that the in-worker limit cannot interrupt at the seeds in ``hang``;
    kills its own process at the seeds in ``crash``.  For tests of the engine
    and for measuring its overhead."""
    seed = inp.params.get("system", {}).get("seed")
    opts = inp.options
    if seed in opts.get("fail", ()):
        raise RuntimeError(f"probe failure at seed {seed}")
    if seed in opts.get("crash", ()):  # the worker process dies (local engine only: inline, it is the command)
        os.kill(os.getpid(), signal.SIGKILL)
    if seed in opts.get("slow", ()):  # an hour of short sleeps: a long computation in Python
        end = time.monotonic() + 3600
        while time.monotonic() < end:
            time.sleep(0.01)
    if seed in opts.get("hang", ()):
        import hashlib

        hashlib.pbkdf2_hmac("sha256", b"probe", b"hang", 2 ** 31 - 1)  # one C call, many minutes
    if opts.get("sleep"):
        time.sleep(opts["sleep"])
    n = getattr(inp.system, "n", inp.system.dim)
    return {"verdict": "OK", "detail": "", "figures": {
        "n": n, "seed": seed, "value": (n * 7 + (seed or 0) * 3) % 11, "eps": float(inp.eps)}}


#: the field of a task (:meth:`~exact_khk.systems.base.System.named_field`)
_FIELD = Option(_text, "the field: f, control, g (= b0: B_0), a sign pattern or g[SIGNS] (Lie–Poisson), "
                       "or a field of the system file")

register(TaskKind(
    "certify", _certify, "certify the orbit (exact_khk.certify): VALID / INVALID / INCONCLUSIVE",
    options={"signs": Option(_signs, "involutions: 'b0', 'default' or a list of sign patterns", "lie-poisson"),
             "poisson_points": Option(_positive_int, "Poisson-map checks at this many orbit points",
                                      "lie-poisson"),
             "identities": Option(_gf, "a gf:P arithmetic for the Schwartz–Zippel identity checks"),
             "prove": Option(_bool, "add the symbolic proofs (dimension <= 4)"),
             "claims": Option(_claims, "the claims to certify (system files)", "expressions")},
    verdicts=("VALID", "INVALID", "INCONCLUSIVE"), ok="VALID", figures=("height_bits", "false", "open")))
register(TaskKind(
    "orbit", _orbit, "iterate the Kahan map: heights and their growth, the last point's size",
    options={"field": _FIELD,
             "method": Option(_method, "how each step is solved (auto, dense, structured, split)")},
    min_steps=0, figures=("final_height_bits", "height_growth_exponent", "final_abs_max")))
register(TaskKind(
    "scale", _scale, "a floating or ball orbit against the exact one: error, bits lost per step, drifts",
    options={"diagnostics": Option(_bool, "also the integrals' drifts and the residuals")},
    arith="floating", verdicts=("OK", "WARNED", "SINGULAR", "UNDECIDED"),
    figures=("final_error_log10", "bits_left", "loss_rate", "drift_log10[H~]")))
register(TaskKind(
    "degrees", _degrees, "degree growth of the iterates over F_p: recurrence, dynamical degree, growth class",
    options={"field": _FIELD,
             "primes": Option(_positive_int, "random 62-bit primes (default 2)"),
             "line_seed": Option(_nonnegative_int, "seed of the random primes and lines (default 0)"),
             "heights": Option(_bool, "also the height growth of the exact orbit of the point")},
    arith="exact", default_steps=20, min_steps=4, verdicts=("OK", "UNDETERMINED"),
    figures=("growth", "dynamical_degree", "last_degree")))
register(TaskKind(
    "find-integrals", _find_integrals, "conserved rational functions discovered from orbits (HK bases), "
    "each verified exactly",
    options={"field": _FIELD,
             "degree": Option(_positive_int, "candidates: all monomials of degree <= D (default 2)"),
             "line_seed": Option(_nonnegative_int, "seed of the random orbits and primes (default 0)")},
    arith="exact", default_steps=0, min_steps=0, verdicts=("FOUND", "NONE"), ok="FOUND",  # steps 0: automatic
    figures=("kernel_dim", "verified", "independent")))
register(TaskKind(
    "classify", _classify, "exact_khk.diagnostics.classify: integrable / non-integrable / undetermined with "
    "its evidence (figures.json: classify's JSON)",
    options={"field": _FIELD,
             "degree": Option(_positive_int, "largest degree of the integral search (default: classify's)"),
             "exact": Option(_nonnegative_int, "exact degrees over Q for the first K iterates (default 6)"),
             "line_seed": Option(_nonnegative_int, "seed of the random primes, lines and orbits (default 0)"),
             "no_discover": Option(_bool, "skip the invariant-measure and Poisson searches")},
    arith="exact", default_steps=20, min_steps=4, verdicts=("OK", "UNDETERMINED"),
    figures=("classification", "growth", "independent_integrals")))
register(TaskKind(
    "probe", _probe, "engine probe (no mathematics): sleeps, fails or hangs on request",
    options={"sleep": Option(_seconds, "seconds every probe sleeps"),
             "fail": Option(_int_list, "system seeds at which the probe raises"),
             "slow": Option(_int_list, "system seeds at which the probe sleeps an hour"),
             "hang": Option(_int_list, "system seeds at which the probe blocks in C"),
             "crash": Option(_int_list, "system seeds at which the probe kills its worker process "
                                        "(local engine only)")},
    min_steps=0, figures=("value",)))


# --- building the inputs inside the worker -----------------------------------------


_SYSTEMS: dict = {}


def build_system(params: dict, system_spec=None):
    """The system of a task: the Lie–Poisson family from (n, seed), or a system
    file's spec (``system_spec``, shipped with the payload; cached by digest)."""
    s = params["system"]
    if "family" in s:
        from exact_khk.systems.catalogue import from_spec

        return from_spec(s)
    digest = s.get("digest")
    if digest not in _SYSTEMS:
        from exact_khk.systems.expressions import ExpressionSystem

        if system_spec is None:  # a catalogue name alone (no spec shipped)
            from exact_khk.systems.catalogue import load

            system = load(s["name"])
        else:
            system = ExpressionSystem.from_json(system_spec)
        if len(_SYSTEMS) > 64:
            _SYSTEMS.clear()
        _SYSTEMS[digest] = system
    return _SYSTEMS[digest]


def build_point(params: dict, system) -> tuple:
    """x0 of a task: a seed (``random_point``), explicit coordinates, or the default."""
    from exact_khk.parsing import parse_vector

    p = params["point"]
    if "x0" in p:
        return parse_vector(p["x0"], "x0", system.dim)
    if "seed" in p:
        return system.random_point(p["seed"])
    return parse_vector(list(system.default_x0), "x0", system.dim)


# --- the time limit ------------------------------------------------------------------


@contextmanager
def time_limit(seconds):
    """Raise :class:`TaskTimeout` in the body after ``seconds`` (None or 0: no limit);
    see the module docstring for how."""
    if not seconds:
        yield
        return
    if hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread():
        with _alarm(seconds):
            yield
    else:
        with _watchdog(seconds):
            yield


@contextmanager
def _alarm(seconds):
    state = {"armed": True}

    def handler(signum, frame):
        if state["armed"]:
            state["armed"] = False
            raise TaskTimeout()

    old = signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        state["armed"] = False
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


@contextmanager
def _watchdog(seconds):
    tid = threading.get_ident()
    lock = threading.Lock()
    state = {"armed": True, "fired": False}
    set_exc = ctypes.pythonapi.PyThreadState_SetAsyncExc

    def fire():
        with lock:
            if state["armed"]:
                state["fired"] = True
                set_exc(ctypes.c_ulong(tid), ctypes.py_object(TaskTimeout))

    timer = threading.Timer(seconds, fire)
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        with lock:
            state["armed"] = False
            timer.cancel()
            if state["fired"]:
                set_exc(ctypes.c_ulong(tid), None)  # clear it if still pending


# --- running one task ----------------------------------------------------------------


@functools.lru_cache(maxsize=1)
def _versions() -> dict:
    from exact_khk.certification.records import library_versions

    return library_versions()


def _one_line(text, limit: int = MAX_MESSAGE) -> str:
    text = " ".join(str(text or "").split())
    return text if len(text) <= limit else text[:limit - 1] + "…"


def error_text(exc: BaseException) -> str:
    """``Type: message`` on one line (cut to :data:`MAX_MESSAGE` characters)."""
    msg = _one_line(exc)
    return _one_line(f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__)


def worker_info(engine: str = "local") -> dict:
    """Where a task ran: the engine, host, process id and (Dask) worker address."""
    info = {"engine": engine, "host": socket.gethostname(), "pid": os.getpid()}
    if "distributed" in sys.modules:
        try:
            from distributed import get_worker

            info["address"] = get_worker().address
            info["engine"] = "dask"
        except (ImportError, ValueError, AttributeError):
            pass
    return info


def now_iso() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="milliseconds")


def make_record(payload: dict, verdict: str, *, detail: str = "", figures=None, error=None,
                seconds: float = 0.0, cpu_seconds=None, worker=None, versions=None) -> dict:
    """One result line (see docs/sweeps.md for the fields)."""
    return {"format": RECORD_FORMAT, "key": payload["key"], "params": payload["params"],
            "verdict": verdict, "detail": detail, "figures": figures or {}, "error": error,
            "seconds": round(seconds, 6),
            "cpu_seconds": None if cpu_seconds is None else round(cpu_seconds, 6),
            "worker": worker or {}, "finished": now_iso(),
            "versions": versions if versions is not None else _versions()}


def run_task(payload: dict) -> dict:
    """Run one task (``payload``: ``key``, ``params``, optional ``timeout`` in seconds,
    ``engine``, ``system_spec``) and return its record; never raises (except
    KeyboardInterrupt): what a task raises becomes its verdict."""
    with any_int_digits():  # exact figures may be huge integers; the caller's limit is restored
        return _run_task(payload)


def _run_task(payload: dict) -> dict:
    params = payload["params"]
    timeout = payload.get("timeout")
    t0, c0 = time.perf_counter(), time.thread_time()
    detail, figures, error = "", {}, None
    try:
        with time_limit(timeout):
            kind = TASKS.get(params["task"])
            if kind is None:
                raise InputError(f"task: unknown task {params['task']!r} in this worker "
                                 f"(available: {', '.join(sorted(TASKS))})")
            system = build_system(params, payload.get("system_spec"))
            from exact_khk.parsing import parse_rational

            inp = TaskInput(system, build_point(params, system), parse_rational(params["eps"], "eps"),
                            params["arith"], params["steps"], dict(params.get("options", {})), params)
            out = kind.run(inp)
        verdict, detail, figures = out["verdict"], _one_line(out.get("detail", "")), out.get("figures", {})
    except TaskTimeout:
        verdict, error = "TIMEOUT", f"time limit of {timeout:g} s exceeded"
    except SingularStepError as exc:
        verdict, detail = "SINGULAR", _one_line(exc)
    except PoleError as exc:
        verdict, detail = "UNDEFINED", _one_line(exc)
    except UndecidedError as exc:
        verdict, detail = "UNDECIDED", _one_line(exc)
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # noqa: BLE001 - recorded (MemoryError, RecursionError too), never fatal
        verdict, error = "ERROR", error_text(exc)
    return make_record(payload, verdict, detail=detail, figures=figures, error=error,
                       seconds=time.perf_counter() - t0, cpu_seconds=time.thread_time() - c0,
                       worker=worker_info(payload.get("engine", "local")))
