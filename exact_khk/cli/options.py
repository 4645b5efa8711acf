"""Options shared by the commands: the system, x0, ε, steps, arithmetic, output.

``--system NAME|FILE`` selects a catalogue system or a system file; otherwise
the Lie–Poisson family (``--n``, ``--a/--b/--c``, ``--seed``; default the
built-in n = 3 system).

Limits, checked before any work (:func:`check_resources`), each refused with
an :class:`~exact_khk.errors.InputError` that names it and states the estimate:

* ``--steps`` ≤ :data:`MAX_STEPS`;
* the planned memory ≤ :data:`MAX_MEMORY_BYTES` (4 GiB; the environment
  variable ``EXACT_KHK_MAX_MEMORY``, e.g. ``16G``, changes it): the dense
  2n×2n path costs about :data:`DENSE_BYTES_PER_CUBE` · (2n)³ bytes (its
  integer and coefficient tensors; measured 130 B exact and 230 B float at
  n = 60), the certificate's exact gradients and Jacobi sums (2n)³ numbers
  more, and the stored orbit (steps + 1)·2n numbers, whose size grows along
  exact orbits (measured on two probe steps when 2n ≤ 64, else about
  n·(2·log2 n + 5) bits per step); the structured path (``--method
  structured``, or ``auto`` for exact flint steps at n ≥ 16) needs O(n) numbers
  per point, and an exact structured step about
  :data:`STRUCTURED_STEP_BYTES_PER_BIT` · n · (h + 2h₀) bytes from a point of
  height h₀ to an output of height h bits (so one exact step at n = 20 000, about
  670 000 bits per coordinate, is refused: about 67 GB, and its output alone is
  about 3 GB; the float and mp:P structured steps are O(n)); a system file has
  only the dense N×N path (:func:`check_dense`, checked as soon as the file is read,
  before its default point is searched for), and the refusal names its N variables;
* an empty path for ``--out``, ``--plot`` or ``--json`` (:data:`OUTPUT_OPTIONS`);
* precisions, ``cyclo:N`` and ``gf:P`` are bounded in :mod:`exact_khk.arith`.

A run that lasts more than about 2 s shows progress on stderr (a tqdm bar,
only when stderr is a terminal; ``--quiet`` turns it off).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from functools import lru_cache

from exact_khk.errors import InputError, SingularStepError
from exact_khk.parsing import MAX_N, MAX_STEPS, _short, parse_rational, parse_vector  # noqa: F401 (limits: the CLI's too)

# The rest of the library is imported inside the functions that use it: ``exact-khk
# --help`` imports this module (for :class:`Parser`) and nothing else of the library.


#: the options that name an output file or folder, in every command (an empty one is refused:
#: it would be silently ignored, or fail only when the results are written)
OUTPUT_OPTIONS = ("--out", "--plot", "--json", "--toml", "--markdown", "--figure")


class Parser(argparse.ArgumentParser):
    """argparse with a one-line error message and exit status 2; an option defined
    twice (a command's own ``--quiet`` after the shared one) replaces the first; an
    empty path for one of :data:`OUTPUT_OPTIONS` is refused."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("conflict_handler", "resolve")
        super().__init__(*args, **kwargs)

    def parse_known_args(self, args=None, namespace=None):
        namespace, rest = super().parse_known_args(args, namespace)
        for action in self._actions:
            for option in set(action.option_strings) & set(OUTPUT_OPTIONS):
                if getattr(namespace, action.dest, None) == "":
                    self.error(f"argument {option}: expected a file or folder name, got an empty string")
        return namespace, rest

    def error(self, message):
        where = self.prog.removeprefix("exact-khk").strip()
        raise InputError(f"{where}: {message}" if where else message)


# --- shared options -----------------------------------------------------------


def add_system_options(p, steps_default=20, lie_poisson_only=False, arith=True):
    """The options that choose the system, x0, ε, steps and arithmetic (``lie_poisson_only``:
    no ``--system``, for commands about the Lie–Poisson family's theorems; ``arith=False``: no
    ``--arith``, for commands that choose their own arithmetic)."""
    from exact_khk.systems.lie_poisson.system import DEFAULT_EPS

    g = p.add_argument_group("system (default: the built-in n = 3 Lie–Poisson system of the README, unless the "
                             "description above names another)")
    if lie_poisson_only:
        p.set_defaults(system=None)
    else:
        g.add_argument("--system", metavar="NAME|FILE",
                       help="a catalogue system (see 'exact-khk systems') or a system file (.toml, see "
                            "docs/system-files.md) instead of the Lie–Poisson family")
    g.add_argument("--n", type=int, help="half the phase-space dimension (n >= 2)")
    g.add_argument("--a", help="first Hessian block vector, e.g. '1/2,-3,0' (enclose: also reals such as "
                               "'sqrt(2),[1.9,2.1],0')")
    g.add_argument("--b", help="second Hessian block vector")
    g.add_argument("--c", help="third Hessian block vector")
    g.add_argument("--seed", type=int, help="draw a, b, c (and x0 if not given) as small random integers")
    g.add_argument("--x0", help="initial point: comma-separated rationals (2n for the Lie–Poisson family)")
    g.add_argument("--eps", default=None, help=f"step size eps, a nonzero rational: one Kahan step approximates the "
                   f"flow over time 2*eps (Kahan's step h = 2 eps) (default {DEFAULT_EPS}; with --system: the "
                   f"system's)")
    g.add_argument("--steps", type=int, default=steps_default,
                   help=f"number of steps K (default {steps_default})" if steps_default is not None else
                   "number of steps K (default 20, or the system file's [defaults] steps)")
    if arith:
        g.add_argument("--arith", default=None, help=arith_help())
    else:
        p.set_defaults(arith=None)
    p.add_argument("--quiet", action="store_true",
                   help="no progress display on stderr (shown only for runs longer than about 2 s, and only "
                        "when stderr is a terminal)")


@lru_cache(maxsize=None)
def arith_help() -> str:
    """The ``--arith`` help: every arithmetic, with its bounds (made when a command's
    parser is built: it imports :mod:`exact_khk.arith.cyclotomic` for the bounds)."""
    from exact_khk.arith import MAX_PRECISION_BITS, arith_names
    from exact_khk.arith.cyclotomic import MAX_CYCLOTOMIC_N, MIN_PRIME

    names = arith_names()
    return ("arithmetic: " + ", ".join(names) + " (default: flint, the fastest exact one, unless the description "
            "above names another). flint, gmpy2, fraction: exact "
            "rationals; float: IEEE float64; mp:P: mpmath at P bits; ball:P: certified arb balls at P bits "
            f"(2 <= P <= {MAX_PRECISION_BITS}); cyclo:N: exact Q(zeta_N), N <= {MAX_CYCLOTOMIC_N}; gf:P: the "
            f"prime field F_P, P prime, {MIN_PRIME} <= P < 2^64")


def add_field_options(p):
    """``--field`` and ``--signs`` (read by :func:`field_name`)."""
    p.add_argument("--field", default="f",
                   help="Lie–Poisson family: f (Hessian Hs), g (B Hs, see --signs; also g[SIGNS]) or control (A Hs; "
                        "(2I+A) Hs for n = 2); --system: f or a field named in the system file")
    p.add_argument("--signs", help="sign pattern of the involution for --field g (default B_0 = '-+...+')")


def field_name(system, args) -> str:
    """The name of the field chosen by ``--field`` and ``--signs`` (``g[SIGNS]``), for
    :meth:`~exact_khk.systems.base.System.named_field`; ``--signs`` goes only with ``--field g``
    of the Lie–Poisson family."""
    if args.signs is None:
        return args.field
    if "signs" not in system.certificate_options or args.field != "g":
        raise InputError("--signs applies only to --field g of the Lie–Poisson family")
    return f"g[{args.signs}]"


def system_from_args(args, reals=None, point=True):
    """(system, x0, eps) from parsed options, with typed errors naming the option.
    ``point=False`` (a command without a point or step size, ``prove``): the system
    only, (system, None, None).

    ``reals``: a precision P, for a command that reads ``--x0`` and ``--eps`` as reals
    itself (``enclose``): a given ``--x0``/``--eps`` is then not read here (it comes back
    as None), and ``--a/--b/--c`` with an entry that is not a plain rational give a
    :class:`~exact_khk.systems.lie_poisson.real.RealLiePoissonSystem` with arb blocks at
    P bits."""
    from exact_khk.systems.lie_poisson.system import (DEFAULT_EPS, DEFAULT_VECTORS, DEFAULT_X0, LiePoissonSystem,
                                                      random_point)

    if getattr(args, "system", None) is not None:
        return _named_system(args, reals)
    given = [v is not None for v in (args.a, args.b, args.c)]
    if any(given) and not all(given):
        raise InputError("--a, --b and --c must be given together")
    if all(given) and args.seed is not None:
        raise InputError("give either --a/--b/--c or --seed, not both")
    if args.n is not None and args.n < 2:
        raise InputError(f"--n: the family needs n >= 2, got {args.n}")
    check_n(args.n)
    if all(given) and reals is not None and not all(map(_rational_vector, (args.a, args.b, args.c))):
        from exact_khk.systems.lie_poisson.real import RealLiePoissonSystem

        system = RealLiePoissonSystem.from_reals(args.a, args.b, args.c, reals, ("--a", "--b", "--c"), args.n)
        check_n(system.n, "--a")
        if args.x0 is None:
            raise InputError("--x0 is required with --a/--b/--c")
    elif all(given):
        a = parse_vector(args.a, "--a", args.n)
        check_n(len(a), "--a")
        system = LiePoissonSystem(a, parse_vector(args.b, "--b", len(a)), parse_vector(args.c, "--c", len(a)))
        if args.x0 is None and point:
            raise InputError("--x0 is required with --a/--b/--c")
    elif args.seed is not None:
        if args.n is None:
            raise InputError("--seed needs --n")
        system = LiePoissonSystem.random(args.n, args.seed)
    else:
        if args.n not in (None, 3):
            raise InputError("--n other than 3 needs --a/--b/--c or --seed")
        system = LiePoissonSystem.from_vectors(*DEFAULT_VECTORS)
    if not point:
        return system, None, None
    # a seeded point is off the degenerate sets (random_point), also those of this system and eps
    return _point_and_eps(args, system, reals, DEFAULT_EPS, lambda: DEFAULT_X0,
                          lambda eps: random_point(system.n, args.seed, system=system, eps=eps))


def _point_and_eps(args, system, reals, default_eps, default_x0, seeded):
    """(system, x0, eps) from ``--eps``, ``--x0``/``--seed`` (``seeded(eps)``: the seed's
    point; ``default_x0()``: the point without either) and ``--steps``; ``--x0``/``--eps``
    come back as None when ``reals`` is given (the command reads them as reals itself)."""
    eps = default_eps if args.eps is None else None if reals is not None else parse_rational(args.eps, "--eps")
    if eps == 0:
        raise InputError("--eps: the step size must be nonzero")
    if args.x0 is not None:
        x0 = None if reals is not None else parse_vector(args.x0, "--x0", system.dim)
    elif args.seed is not None:
        x0 = seeded(eps)
    else:
        x0 = parse_vector(list(default_x0()), "--x0", system.dim)
    if args.steps is not None:
        if args.steps < 0:
            raise InputError(f"--steps: expected a non-negative integer, got {args.steps}")
        check_steps(args.steps)
    return system, x0, eps


def add_json_option(p, what="the result"):
    """The one output option of every command: ``--json [PATH]``, ``what`` as JSON to PATH
    (written atomically, :func:`write_json`), or to stdout with no PATH or ``-``."""
    p.add_argument("--json", nargs="?", const="-", default=None, metavar="PATH",
                   help=f"write {what} as JSON to PATH (atomically), or to stdout with no PATH or '-' "
                        f"(then instead of the table)")


def write_json(obj, target):
    """Write ``obj`` to a path (atomically), or to stdout for ``-`` (or None)."""
    text = json.dumps(obj, indent=1)
    if target in (None, "-"):
        print(text)
    else:
        from exact_khk.studies.output import write_atomic

        write_atomic(target, text + "\n", "--json")


def report(system, res, target, **extra) -> bool:
    """A result's JSON (``{"system": ..., **extra, **res.to_json()}``) to ``target`` when asked
    (``--json``), and the system's description and ``res.summary()`` unless that JSON went to
    stdout; True when the text was printed (the caller may add lines)."""
    if target is not None:
        write_json({"system": system.to_json(), **extra, **res.to_json()}, target)
    if target == "-":
        return False
    print(system.describe())
    print(res.summary())
    return True


def invocation(args, **resolved) -> dict:
    """The command line (``argv``) and its options after defaults (``options``), with what the
    command resolved from them (``resolved``: the arithmetic, ε, x0, ...): an informational
    record for a document the command writes (a certificate's ``invocation``)."""
    plain = (str, int, float, bool, type(None))
    options = {k: v for k, v in sorted(vars(args).items())
               if k not in ("func", "argv") and (isinstance(v, plain) or
                                                 isinstance(v, list) and all(isinstance(t, plain) for t in v))}
    return {"argv": list(getattr(args, "argv", [])), "options": options,
            "resolved": {k: v if isinstance(v, plain) else [str(t) for t in v] if isinstance(v, (list, tuple))
                         else str(v) for k, v in resolved.items()}}


def json_command(run):
    """A command ``run(args) -> JSON document`` with ``--json [PATH]``: its printed tables are
    dropped when the document goes to stdout; the document is then written (:func:`write_json`)."""
    def cmd(args):
        import contextlib
        import io

        check_output(args.json)
        with contextlib.redirect_stdout(io.StringIO()) if args.json == "-" else contextlib.nullcontext():
            doc = run(args)
        if args.json is not None:
            write_json(doc, args.json)
        return 0

    cmd.__doc__ = run.__doc__
    return cmd


def check_output(target, what="--json"):
    """Check an output path (not ``-``) before the work starts."""
    if target not in (None, "-"):
        from exact_khk.studies.output import check_writable

        check_writable(target, what)


def _rational_vector(text) -> bool:
    """Whether every entry of a comma-separated vector is a plain rational."""
    from exact_khk.arith.reals import is_rational_text

    return all(is_rational_text(t.strip()) for t in text.split(","))


def _named_system(args, reals=None):
    """(system, x0, eps) for ``--system NAME|FILE``."""
    from exact_khk.systems.catalogue import resolve

    clash = [o for o, v in (("--n", args.n), ("--a", args.a), ("--b", args.b), ("--c", args.c)) if v is not None]
    if clash:
        raise InputError(f"--system: {clash[0]} describes the Lie–Poisson family; it cannot be combined with --system")
    system = resolve(args.system)
    # every command steps the system's Kahan map by dense N x N solves: refused before a file's
    # default point is searched for (N^3 work)
    check_dense(getattr(args, "command", None) or "this command", system)
    return _point_and_eps(args, system, reals, system.default_eps, lambda: system.default_x0,
                          lambda eps: system.seeded_point(args.seed, eps))


# --- limits, estimated before the work ------------------------------------------

#: the memory a command may plan to use, in bytes (``EXACT_KHK_MAX_MEMORY`` overrides)
MAX_MEMORY_BYTES = 4 * 2 ** 30
#: bytes per (2n)³ of the dense 2n×2n path (its coefficient and integer tensors)
DENSE_BYTES_PER_CUBE = 250
#: bits per step by which exact orbit heights grow when not measured: about
#: n·(2·log2 n + GROWTH_BITS_PER_N) (measured from small integers at n = 16, 32, 64:
#: about 13·n, 16·n, 17·n per step; the first step at n = 256, 512, 1024, 2048:
#: 19.4·n, 21.0·n, 23.2·n, 25.2·n bits)
GROWTH_BITS_PER_N = 5
#: the exact structured step's working memory, in bytes per n per bit of h + 2h₀ (h the
#: output's height, h₀ the input's: the divisor d has about 2h₀ bits, Newton's iteration
#: and r·d⁻¹ hold polynomials of n coefficients at about twice h; FLINT's products need a
#: few times their operands): peak RSS growth over the process's base measured
#: 4.0–4.7 · n · (h + 2h₀) for one to four steps from random_point(n, 1), n = 256..2048
#: (7.2 for one step at n = 256, where the 9 MB are mostly fixed costs)
STRUCTURED_STEP_BYTES_PER_BIT = 5


def max_memory() -> int:
    """:data:`MAX_MEMORY_BYTES`, or ``EXACT_KHK_MAX_MEMORY`` (bytes, or with a K/M/G/T suffix)."""
    text = os.environ.get("EXACT_KHK_MAX_MEMORY", "").strip().upper().removesuffix("B")
    if not text:
        return MAX_MEMORY_BYTES
    scale = {"K": 2 ** 10, "M": 2 ** 20, "G": 2 ** 30, "T": 2 ** 40}.get(text[-1:], 1)
    try:
        value = float(text[:-1] if scale != 1 else text) * scale
    except ValueError:
        raise InputError(f"EXACT_KHK_MAX_MEMORY: expected a size such as '16G', got "
                         f"{os.environ['EXACT_KHK_MAX_MEMORY']!r}") from None
    if not value > 0 or not math.isfinite(value):
        raise InputError("EXACT_KHK_MAX_MEMORY: expected a positive size")
    return int(value)


def check_n(n, option="--n"):
    if n is not None and n > MAX_N:
        raise InputError(f"{option}: n = {n} is beyond the limit of {MAX_N:,} (MAX_N; even the O(n) set-up of the "
                         f"system would take minutes, one exact step hours)")


def check_steps(steps):
    if steps > MAX_STEPS:
        raise InputError(f"--steps: {_short(steps)} is beyond the limit of {MAX_STEPS:,} steps (MAX_STEPS; the orbit "
                         f"alone would hold more than 10^7 points)")


def human_bytes(b) -> str:
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if b < 1000 or unit == "PB":
            return f"{b:.3g} {unit}"
        b /= 1000
    return f"{b:.3g} PB"  # pragma: no cover


def _number_bytes(ar, bits) -> float:
    """About the bytes of one number of ``ar`` whose numerator and denominator have ``bits`` bits."""
    if not ar.exact:
        if ar.name == "float":
            return 32
        return 120 + (2 if ar.name.startswith("ball") else 1) * ar.prec / 8
    if ar.name.startswith("gf:"):
        return 40
    degree = getattr(getattr(ar, "K", None), "degree", 1)
    return degree * (100 + bits / 4)


def _growth(phi, x0, steps, ar):
    """(height of x0 in bits, bits per step): measured on two steps when cheap, else a model."""
    from exact_khk.arith import point_height

    if not ar.rational:
        return 64, 0
    h0 = point_height(ar, phi.point(x0, "x0"))
    n = phi.field.dim // 2
    if phi.field.dim <= 64 and steps:
        try:
            pts = phi.orbit(x0, min(steps, 2))
        except SingularStepError:
            return h0, 0
        hs = [point_height(ar, p) for p in pts]
        return h0, max(1, max(b - a for a, b in zip(hs, hs[1:])))
    return h0, int(n * (2 * math.log2(n) + GROWTH_BITS_PER_N)) + 2 * h0


def check_dense(what, system, ar=None, dense=True, cube_numbers=0):
    """Refuse at once (:class:`InputError`) a run of ``what`` whose dense N×N path (``dense``) and
    ``cube_numbers``·N³ further numbers of ``ar`` need more than :func:`max_memory`, naming what
    sets N: ``--n`` for the Lie–Poisson family, the number of variables of a system file."""
    N, limit = system.dim, max_memory()
    per_cube = (DENSE_BYTES_PER_CUBE if dense else 0) + (cube_numbers * _number_bytes(ar, 64) if cube_numbers else 0)
    need = per_cube * N ** 3
    if need <= limit:
        return
    cube = "N^3" if system.size_option is None else "(2n)^3"
    about = (f"which need about {human_bytes(need)} (estimate: {DENSE_BYTES_PER_CUBE} bytes x {cube}"
             + (f" + {cube_numbers} x {cube} numbers" if cube_numbers else "")
             + f"), beyond the limit of {human_bytes(limit)} (EXACT_KHK_MAX_MEMORY)")
    if system.size_option is None:
        fits = int((limit / per_cube) ** (1 / 3))
        raise InputError(f"--system: {system.name} has {N} variables, and {what} solves dense {N}x{N} systems, "
                         f"{about}; within that limit a system has at most about {fits} variables")
    hint = (" (the structured path, --method structured, needs O(n) memory with --arith float or mp:P; "
            f"an exact structured step about {STRUCTURED_STEP_BYTES_PER_BIT} bytes x n x (its output's + "
            f"twice its input's height in bits))" if what == "orbit" else "")
    raise InputError(f"{system.size_option}: {what} at n = {N // 2} solves dense {N}x{N} systems, {about}{hint}")


def check_resources(what, system, phi, x0, steps, dense=False, orbits=1, per_point=1, cube_numbers=0,
                    final_solve=False):
    """Refuse at once (:class:`InputError`, with the estimate and the limit) a run whose
    planned memory is beyond :func:`max_memory`: the dense 2n×2n path (``dense``),
    ``cube_numbers``·(2n)³ further numbers (the certificate's exact gradients and
    Jacobi sums), ``orbits`` stored orbits of ``steps`` + 1 points with
    ``per_point`` numbers each (2n for an orbit), and on the structured path the last
    exact division: the last step's, or with ``final_solve`` one more at the orbit's
    last point (H̃ and K̃ there cost about a step from it)."""
    check_steps(steps)
    ar, N, limit = phi.arith, system.dim, max_memory()
    n = N // 2
    check_dense(what, system, ar, dense, cube_numbers)
    solves = steps + 1 if final_solve else steps
    h0, g = _growth(phi, x0, solves, ar)
    if phi.structure is not None and ar.exact and solves:  # the last structured division
        step = STRUCTURED_STEP_BYTES_PER_BIT * n * (h0 + g * solves + 2 * (h0 + g * (solves - 1)))
        if step > limit:
            kind = "step" if solves == steps else "solve (H~ or K~ at a point, like a step from it)"
            raise InputError(f"--n: one exact structured {kind} at n = {n} needs about {human_bytes(step)} of "
                             f"working memory (estimate: {STRUCTURED_STEP_BYTES_PER_BIT} bytes x n x (the output's "
                             f"height + twice the input's), heights growing from {h0} by about {g} bits per step), beyond the limit of "
                             f"{human_bytes(limit)} (EXACT_KHK_MAX_MEMORY); exact heights grow like n log n bits "
                             f"per step" + (": use --arith float or mp:P with --method structured for large n"
                                            if what == "orbit" else ""))
    mean_bits = h0 + g * steps / 2
    need = orbits * (steps + 1) * N * per_point * _number_bytes(ar, mean_bits)
    if need > limit:
        grow = f", heights growing from {h0} by about {g} bits per step" if g else ""
        raise InputError(f"--steps: {what} would hold {orbits * (steps + 1) * per_point * N:,} numbers "
                         f"({orbits} orbit(s) of {steps + 1} points of dimension {N}"
                         + (f", {per_point} vectors per point" if per_point > 1 else "")
                         + f"; about {human_bytes(need)} in {ar.name}{grow}), beyond the memory limit of "
                         f"{human_bytes(limit)} (EXACT_KHK_MAX_MEMORY); choose fewer steps")


# --- progress on stderr ---------------------------------------------------------


def shows_progress(args) -> bool:
    """Whether a long run shows a progress bar: stderr is a terminal and ``--quiet``
    was not given (the rule of :class:`Progress`, for the studies' own bars)."""
    return not getattr(args, "quiet", False) and _is_terminal(sys.stderr)


class Progress:
    """A progress display on stderr for long runs: a tqdm bar shown after 2 s, only
    when stderr is a terminal and ``--quiet`` is not given.  Call it with a step
    number (``k``, of ``total``) or a stage name.  A daemon thread redraws the bar
    every second from then on, so a run whose first step (or any one step) takes
    minutes shows the bar and its elapsed time instead of nothing."""

    #: seconds before the bar appears, and between redraws while nothing is reported
    DELAY, TICK = 2.0, 1.0

    def __init__(self, args, total=None, desc="", unit="step"):
        self.bar, self._stop = None, None
        if shows_progress(args):
            import threading

            from tqdm import tqdm

            self.bar = tqdm(total=total, desc=desc, unit=unit, delay=self.DELAY, file=sys.stderr, leave=False,
                            dynamic_ncols=True)
            self._stop = threading.Event()
            threading.Thread(target=self._tick, daemon=True).start()

    def _tick(self):
        if self._stop.wait(self.DELAY):
            return
        while True:
            self.bar.refresh()
            if self._stop.wait(self.TICK):
                return

    def __call__(self, where):
        if self.bar is None:
            return
        if isinstance(where, int):
            self.bar.update(where - self.bar.n)
        else:
            self.bar.set_description_str(str(where)[:48], refresh=False)
            self.bar.update(1)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.bar is not None:
            self._stop.set()
            self.bar.close()
        return False


def _is_terminal(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError, OSError):
        return False
