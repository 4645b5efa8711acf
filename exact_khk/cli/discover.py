"""``exact-khk find-measure`` and ``exact-khk find-poisson``: invariant measures (discrete
Darboux polynomials) and preserved Poisson tensors of a Kahan map (a thin view of
:mod:`exact_khk.diagnostics.measures` and :mod:`exact_khk.diagnostics.poisson`;
docs/diagnostics.md)."""

from __future__ import annotations

from exact_khk.cli.options import (Progress, add_field_options, add_system_options, check_output, field_name,
                                   system_from_args, write_json)
from exact_khk.errors import InputError
from exact_khk.parsing import parse_vector

MEASURE_HELP = "discover invariant measures of a Kahan map (discrete Darboux polynomials and their cofactors)"
POISSON_HELP = "discover Poisson tensors preserved by a Kahan map, with their Casimirs"


def _common(p):
    p.add_argument("system_spec", nargs="?", metavar="SYSTEM",
                   help="a catalogue system or a system file (the same as --system)")
    add_system_options(p, steps_default=4, arith=False)  # --x0, --steps: the exact orbit check
    add_field_options(p)
    p.add_argument("--line-seed", type=int, default=0, help="seed of the random points and primes (default 0)")
    p.add_argument("--json", nargs="?", const="-", metavar="PATH",
                   help="write one JSON object to PATH (stdout without a path)")
    p.add_argument("--toml", action="store_true", help="print a ready system-file block ([measure] or [poisson])")


def register(sub):
    p = sub.add_parser("find-measure", help=MEASURE_HELP,
                       description="Darboux polynomials P(x~) = C(x) P(x) with cofactors built from the factors over "
                       "Q of det dPhi, and densities m with m(x~) det dPhi(x) = m(x), each verified exactly on a fresh "
                       "orbit, as an identity over F_p (Schwartz-Zippel bound) and against a perturbed density "
                       "(docs/diagnostics.md).")
    _common(p)
    p.add_argument("--degree", type=int, default=2, help="degree bound of the Darboux polynomials (default 2)")
    _symbolic_options(p, "the densities", "m(Phi) det dPhi = m")
    p.set_defaults(func=cmd_find_measure)
    q = sub.add_parser("find-poisson", help=POISSON_HELP,
                       description="Bivectors pi with polynomial entries with dPhi pi dPhi^T = pi o Phi, the Jacobi "
                       "identity solved on their span, Casimirs U/V (V = 1 or a Darboux polynomial), each verified "
                       "(docs/diagnostics.md).")
    _common(q)
    q.add_argument("--degree", type=int, default=2, help="degree bound of the entries (default 2)")
    q.add_argument("--casimir-degree", type=int, default=2,
                   help="degree bound of polynomial Casimirs, and of the Darboux denominators tried (default 2)")
    _symbolic_options(q, "the tensors", "dPhi pi dPhi^T = pi o Phi and the Jacobi identity")
    q.set_defaults(func=cmd_find_poisson)


def _symbolic_options(p, what, identity):
    p.add_argument("--symbolic", action="append", metavar="NAMES",
                   help=f"reconstruct {what} as rational functions of eps and/or parameters of the system "
                   f"(comma-separated or repeated) from searches at random values, and prove {identity} (exactly; over "
                   f"F_p with a stated bound beyond dimension 4); exit 4 if one is not proven")
    p.add_argument("--symbolic-degree", type=int, default=None, metavar="T",
                   help="with --symbolic: the total degree bound of each coefficient's numerator and denominator "
                   "in the symbols (default and limit 12)")


def _system(args):
    if args.system_spec is not None:
        if args.system is not None and args.system != args.system_spec:
            raise InputError(f"SYSTEM {args.system_spec!r} and --system {args.system!r} differ: give one")
        args.system = args.system_spec
    system, _, eps = system_from_args(args)
    if args.json not in (None, "-"):
        check_output(args.json)
    x0 = None if args.x0 is None else parse_vector(args.x0, "--x0", system.dim)
    return system, eps, x0


def _rename(exc):
    msg = str(exc)
    for name, option in (("degree", "--degree"), ("casimir_degree", "--casimir-degree"), ("verify_steps", "--steps"),
                         ("symbolic", "--symbolic"), ("max_degree", "--symbolic-degree"), ("x0", "--x0"),
                         ("seed", "--line-seed")):
        if msg.startswith(name + ":"):
            return InputError(option + msg[len(name):])
    return exc


def _show(args, system, eps, res):
    if args.json is not None:
        write_json({"system": system.to_json(), "eps": str(eps), **res.to_json()}, args.json)
        if args.json == "-":
            return 0
    if args.toml:
        print(res.toml(), end="")
    else:
        print(system.describe())
        print(res.summary())
    return 0


def cmd_find_measure(args):
    from exact_khk.diagnostics.measures import find_measure

    system, eps, x0 = _system(args)
    try:
        with Progress(args, None, "find-measure", unit="stage") as progress:
            if args.symbolic:
                return _symbolic(args, system, eps, x0, progress)
            if args.symbolic_degree is not None:
                raise InputError("--symbolic-degree applies only with --symbolic")
            res = find_measure(system, degree=args.degree, field=field_name(system, args), eps=eps,
                               seed=args.line_seed, verify_steps=args.steps, x0=x0, progress=progress)
    except InputError as exc:
        raise _rename(exc) from None
    return _show(args, system, eps, res)


def cmd_find_poisson(args):
    from exact_khk.diagnostics.poisson import find_poisson

    system, eps, x0 = _system(args)
    try:
        with Progress(args, None, "find-poisson", unit="stage") as progress:
            if args.symbolic:
                return _symbolic(args, system, eps, x0, progress, casimir_degree=args.casimir_degree,
                                 measure_degree=args.casimir_degree)
            if args.symbolic_degree is not None:
                raise InputError("--symbolic-degree applies only with --symbolic")
            res = find_poisson(system, degree=args.degree, field=field_name(system, args), eps=eps,
                               seed=args.line_seed, verify_steps=args.steps, x0=x0,
                               casimir_degree=args.casimir_degree, measure_degree=args.casimir_degree,
                               progress=progress)
    except InputError as exc:
        raise _rename(exc) from None
    return _show(args, system, eps, res)


def _symbolic(args, system, eps, x0, progress, **kw):
    """``--symbolic``: :func:`~exact_khk.diagnostics.parametric.symbolic_measures` (find-measure) or
    :func:`~exact_khk.diagnostics.parametric.symbolic_tensors` (find-poisson); exit 4 when one found
    is not proven."""
    from exact_khk.diagnostics.parametric import MAX_DEGREE, symbolic_measures, symbolic_tensors

    names = [t for a in args.symbolic for t in a.split(",")]
    run = symbolic_tensors if kw else symbolic_measures
    res = run(system, names, degree=args.degree, field=field_name(system, args), eps=eps, seed=args.line_seed,
              verify_steps=args.steps, x0=x0, progress=progress,
              max_degree=MAX_DEGREE if args.symbolic_degree is None else args.symbolic_degree, **kw)
    proven = [d for d in res.integrals if d.proven]
    status = 0 if len(proven) == len(res.integrals) else 4
    if args.json is not None:
        write_json({"system": system.to_json(), **res.to_json()}, args.json)
        if args.json == "-":
            return status
    if args.toml:
        head = f"# found by exact-khk {'find-poisson' if kw else 'find-measure'} --symbolic {','.join(res.symbols)}"
        if not proven:
            print("# nothing proven")
        elif kw:
            rows = ",\n          ".join("[" + ", ".join(f'"{e}"' for e in r) + "]" for r in proven[0].entries)
            print(f"[poisson]\n{head}\nmatrix = [{rows}]")
        else:
            print(f'[measure]\n{head}\ndensity = "({proven[0].numerator})/({proven[0].denominator})"')
    else:
        print(system.describe())
        print(res.summary())
    return status
