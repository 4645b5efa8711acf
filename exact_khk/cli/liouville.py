"""``exact-khk liouville`` and ``exact-khk prove``: complete integrability checks.

Both run the claim registry (:mod:`~exact_khk.certification.claims`) through the engine on the
family's system with the involutions chosen (:mod:`~exact_khk.certification.engine`).
``liouville`` checks the claims ``integrals`` (H~ and the n integrals K~_j conserved by Φ_f and every
Φ_g), ``commutation`` (every pair of maps, option ``pairs``), ``involution`` (∇K~ = B∇H~ and
{I, I'} = 0 for J and Π for every pair of integrals, option ``brackets``) and ``rank``, with the
family's negative controls: exactly at orbit points for an exact arithmetic (``--arith cyclo:3``),
or as identities by Schwartz–Zippel for ``--arith gf:P`` (the engine's identity mode).  ``prove``
proves every claim of the registry symbolically (the engine's symbolic mode; n = 2).

Both end as ``certify`` does (exit 0 VALID, 1 INVALID, 4 INCONCLUSIVE): at a degenerate x0
(J(x0) singular, or an equilibrium) a control that held is *inapplicable* and a rank below n
undecided, by certify's rule, never a failure.  ``liouville``'s work (:func:`_check_work`) is
estimated and refused up front beyond :data:`MAX_WORK_SECONDS`.
"""

from __future__ import annotations

from exact_khk.arith import get_arith
from exact_khk.cli.options import (Progress, add_json_option, add_system_options, check_output, check_resources,
                                   system_from_args, write_json)
from exact_khk.certification.records import library_versions, status_of
from exact_khk.arith.cyclotomic import GFArith
from exact_khk.errors import InputError
from exact_khk.parsing import format_signs, parse_signs
from exact_khk.certification.identities import integral_patterns, involution_patterns
from exact_khk.systems.lie_poisson.system import check_signs_arith

def register(sub):
    p = sub.add_parser("liouville", help="certify complete integrability (all involutions)",
                       description="Check the n integrals, conservation by Φ_f and every Φ_g, "
                       "commutation, involutivity and rank n: exactly at orbit points "
                       "(--arith cyclo:N, flint, ...; default cyclo:n for n >= 3, where the involutions "
                       "need Q(omega), and flint for n = 2) or as identities over gf:P (Schwartz–Zippel).")
    add_system_options(p, steps_default=2, lie_poisson_only=True)
    p.add_argument("--involutions", default="all",
                   help="'all' (2^n - 2 sign patterns), 'basis' (B_0..B_{n-1}) or a comma list "
                        "such as '+-+,++-'")
    p.add_argument("--pairs", choices=["all", "f"], default="all",
                   help="commutation of all pairs of maps, or of Φ_f with each Φ_g")
    p.add_argument("--trials", type=int, default=3, help="random points for gf:P (default 3)")
    p.add_argument("--draw-seed", type=int, default=0, help="seed of the random points for gf:P")
    add_json_option(p, "the records")
    p.set_defaults(func=cmd_liouville)

    q = sub.add_parser("prove", help="symbolic proofs of every claim for n = 2 (seconds)",
                       description="Prove every claim of the certificate (closed forms, conservation, "
                       "commutation, reversibility, Poisson structure, involution, rank) with its negative "
                       "controls as identities of rational functions in x and eps, for n = 2 (seconds) (with no "
                       "system options: the n = 2 system a = %s, b = %s, c = %s of docs/evidence.md)."
                       % PROVE_DEFAULT_VECTORS)
    add_system_options(q, steps_default=0, lie_poisson_only=True, arith=False)
    add_json_option(q, "the records")
    q.set_defaults(func=cmd_prove)


#: the n = 2 system ``prove`` takes when no system option is given (the built-in default has
#: n = 3, beyond the symbolic proofs' reach)
PROVE_DEFAULT_VECTORS = ("1,2", "0,1", "3,1")
#: the most involutions ``--involutions all`` may check (2^n − 2 of them: n ≤ 12)
MAX_PATTERNS = 4096
#: the most random points ``--trials`` may draw for gf:P
MAX_TRIALS = 1000
#: the most work ``liouville`` may plan, in estimated seconds (10 minutes: n = 7 takes about
#: two, n = 8 with all pairs in cyclo:8 about four; n = 9 with all pairs about forty)
MAX_WORK_SECONDS = 600
#: seconds per solve (one Kahan step or one integral) per n and per degree of the arithmetic
#: over Q (cyclo:N: phi(N); flint: 1), and per n in gf:P: measured 50-80 us (n = 4..10, cyclo:n)
#: and 14-17 us (n = 6..8, gf:P) on a 2-core machine
SOLVE_SECONDS = {"exact": 70e-6, "gf": 16e-6}


def _patterns(n, spec):
    if spec == "all":
        if 2 ** n - 2 > MAX_PATTERNS:
            raise InputError(f"--involutions all: n = {n} has 2^{n} - 2 involutions, beyond the limit of "
                             f"{MAX_PATTERNS} (MAX_PATTERNS); use --involutions basis or a comma list")
        return involution_patterns(n)
    if spec == "basis":
        return [s for s in integral_patterns(n) if s != "+" * n]
    out = [format_signs(parse_signs(s.strip(), n)) for s in spec.split(",")]
    if any(s in ("+" * n, "-" * n) for s in out):
        raise InputError("--involutions: +I and -I are not involutions of interest; leave them out")
    return out


def _solves(n, patterns, pairs):
    """An estimate of the solves (Kahan steps and integrals) at one point: every map's image and
    the n integrals there, the pairs of maps composed both ways, the gradients, the controls."""
    maps = 1 + patterns
    composed = maps * (maps - 1) if pairs == "all" else 2 * (maps - 1)
    return maps + n + maps * n + composed + 2 * (n + 1) + 5


def _check_work(args, n, patterns, ar):
    """Refuse up front a run whose estimated time (solves x :data:`SOLVE_SECONDS`) is beyond
    :data:`MAX_WORK_SECONDS`, naming the options that set it."""
    gf = isinstance(ar, GFArith)
    points, option = (args.trials, "--trials") if gf else (args.steps + 1, "--steps")
    solves = points * _solves(n, patterns, args.pairs)
    degree = getattr(getattr(ar, "K", None), "degree", 1)
    per_solve = n * (SOLVE_SECONDS["gf"] if gf else SOLVE_SECONDS["exact"] * degree)
    if solves * per_solve > MAX_WORK_SECONDS:
        ways = ["--pairs f", "--involutions basis", f"fewer {option}", "a smaller --n"]
        ways += [] if gf else ["--arith gf:P"]
        raise InputError(f"--n {n}, --involutions {args.involutions} ({patterns} involutions), --pairs {args.pairs}, "
                         f"{option} {args.trials if gf else args.steps}: about {solves:,} solves (Kahan steps and "
                         f"integrals) at {points} point(s), about {_duration(solves * per_solve)} in {ar.name} "
                         f"(estimate: {per_solve * 1e3:.2g} ms per solve), beyond the budget of "
                         f"{_duration(MAX_WORK_SECONDS)} (MAX_WORK_SECONDS); choose {', '.join(ways[:-1])} "
                         f"or {ways[-1]}")


def _duration(seconds) -> str:
    for unit, size in (("days", 86400), ("hours", 3600), ("minutes", 60)):
        if seconds >= 2 * size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.3g} s"


#: the mark of a record by its status (:attr:`~exact_khk.certification.records.Check.status`)
MARKS = {"ok": "ok  ", "inapplicable": "n/a ", "UNDECIDED": "??  "}


def _report(args, system, recs, extra, status=None):
    """Print or write the records; the exit status: by ``status`` (VALID, INVALID, INCONCLUSIVE)
    when given, else 0 when every record is as expected and 1 otherwise."""
    ok = status == "VALID" if status else all(r.passed for r in recs)
    if args.json is not None:
        write_json({"system": system.to_json(), **extra, "records": [r.to_json() for r in recs],
                    "ok": ok, **({"status": status} if status else {}), "versions": library_versions()}, args.json)
    if args.json != "-":
        print(system.describe())
        for r in recs:
            print(f"{MARKS.get(r.status, 'FAIL')} {r.name:<26} holds={str(r.holds):<5} {r.evidence}")
            if r.residual != "0":
                print(f"     residual: {r.residual[:200]}")
            if r.detail:
                print(f"     {r.detail[:300]}")
        if status:
            print(status)
    from exact_khk.cli.main import EXIT

    if status:
        return EXIT[{"VALID": "ok", "INVALID": "invalid", "INCONCLUSIVE": "inconclusive"}[status]]
    return EXIT["ok"] if ok else EXIT["invalid"]


def cmd_liouville(args):
    from exact_khk.certification.lie_poisson import liouville
    from exact_khk.kahan.map import KahanMap

    check_output(args.json)
    system, x0, eps = system_from_args(args)
    # default: all involutions need Q(omega), omega = exp(2 pi i / n), from n = 3 on
    ar = get_arith(args.arith if args.arith is not None or system.n <= 2 else f"cyclo:{system.n}")
    if not 1 <= args.trials <= MAX_TRIALS:
        raise InputError(f"--trials: expected an integer from 1 to {MAX_TRIALS} (MAX_TRIALS; the failure bound "
                         f"shrinks geometrically, a handful is enough), got {args.trials}")
    pats = _patterns(system.n, args.involutions)
    check_resources("liouville", system, KahanMap(system.field("f"), eps, ar), x0, args.steps, dense=True,
                    orbits=1 + len(pats), per_point=1 + system.dim, cube_numbers=2)
    if not isinstance(ar, GFArith) and not ar.exact:
        raise InputError(f"--arith: liouville needs an exact arithmetic (cyclo:N, gf:P, flint, ...), got {ar.name}")
    check_signs_arith(system.n, pats + integral_patterns(system.n), ar, "--involutions")
    _check_work(args, system.n, len(pats), ar)
    if not isinstance(ar, GFArith) and args.steps < 1:
        raise InputError(f"--steps: liouville at orbit points needs at least 1 step, got {args.steps}")
    with Progress(args, None, "liouville", unit="check") as progress:
        recs = liouville(system, x0, eps, ar, args.steps, pats, args.pairs, args.trials, args.draw_seed, progress)
    extra = {"arith": ar.name, "trials": args.trials} if isinstance(ar, GFArith) else \
        {"arith": ar.name, "x0": [str(t) for t in x0], "eps": str(eps), "steps": args.steps}
    return _report(args, system, recs, {**extra, "involutions": pats}, status_of(recs))


def cmd_prove(args):
    from exact_khk.certification.engine import symbolic_checks
    from exact_khk.certification.lie_poisson import default_signs, prove_limits

    check_output(args.json)
    if args.steps:
        raise InputError("--steps: prove works with rational functions of x and eps, not along an orbit")
    for option in ("x0", "eps"):
        if getattr(args, option, None) is not None:
            raise InputError(f"--{option}: prove works with rational functions of x and eps (symbols), "
                             f"not at a point or step size")
    if all(getattr(args, k, None) is None for k in ("system", "n", "a", "b", "c", "seed")):
        from exact_khk.systems.lie_poisson.system import LiePoissonSystem

        system = LiePoissonSystem.from_vectors(*PROVE_DEFAULT_VECTORS)
    else:
        system, _, _ = system_from_args(args, point=False)
    prove_limits(system)
    with Progress(args, None, "prove", unit="check") as progress:
        recs = symbolic_checks(system.with_involutions(default_signs(system.n)), progress=progress)
    return _report(args, system, recs, {}, status_of(recs))
