"""``exact-khk degrees`` and ``exact-khk find-integrals``: integrability diagnostics
(a thin view of :mod:`exact_khk.diagnostics`; docs/diagnostics.md)."""

from __future__ import annotations

import re

from exact_khk.cli.options import (Progress, add_field_options, add_json_option, add_system_options, check_output,
                                   field_name, max_memory, report, system_from_args, write_json)
from exact_khk.errors import InputError


def register(sub):
    p = sub.add_parser("degrees", help="degree growth of the iterates of a Kahan map, its recurrence and "
                       "dynamical degree",
                       description="Degrees d_k of the iterates Phi^k (projective degree: numerators and common "
                       "denominator in lowest terms), computed on random lines over F_p; the shortest integer "
                       "recurrence, the dynamical degree and the growth class; heights of the exact orbit of x0.")
    add_system_options(p, steps_default=20, arith=False)
    add_field_options(p)
    p.add_argument("--primes", default="2", help="number of random 62-bit primes, or a comma-separated list (default 2)")
    p.add_argument("--lines", type=int, default=1, help="random lines per prime (default 1)")
    p.add_argument("--line-seed", type=int, default=0, help="seed of the random primes and lines (default 0)")
    p.add_argument("--exact", type=int, default=0, metavar="K",
                   help="also compose the first K iterates exactly over Q (where affordable) to confirm")
    p.add_argument("--confirm", type=int, default=3,
                   help="terms beyond the fit that must confirm the recurrence before growth is classified "
                        "(default 3, also the minimum)")
    p.add_argument("--no-heights", action="store_true", help="skip the heights of the exact orbit of x0")
    p.add_argument("--max-bits", type=int, default=100_000, help="stop the height orbit past this height (default 100000)")
    p.add_argument("--plot", metavar="FILE.png", help="plot degree and log-height against the step (needs matplotlib)")
    p.add_argument("--map", metavar="F0,F1,...",
                   help="instead of a Kahan map: the map of P^N given by homogeneous polynomials of one degree, "
                        "comma-separated, e.g. 'Z**2, X*Y, Y**2' (needs --variables; docs/diagnostics.md)")
    p.add_argument("--variables", metavar="X,Y,...", help="with --map: the homogeneous coordinates, in order")
    add_json_option(p, "the degrees, recurrence and heights")
    p.set_defaults(func=cmd_degrees)

    q = sub.add_parser("find-integrals", help="discover conserved rational functions from orbits (HK bases)",
                       description="Evaluate candidate monomials on orbits, compute the kernels modulo primes, "
                       "lift them to Q and report conserved ratios of kernel polynomials, each checked exactly on "
                       "a fresh orbit (docs/diagnostics.md).")
    q.add_argument("system_spec", nargs="?", metavar="SYSTEM",  # as find-measure, find-poisson, classify
                   help="a catalogue system or a system file (the same as --system)")
    add_system_options(q, steps_default=0, arith=False)
    add_field_options(q)
    g = q.add_mutually_exclusive_group()
    g.add_argument("--degree", type=int, help="candidates: all monomials of degree <= D (default 2)")
    g.add_argument("--monomials", help="candidates: a comma-separated list such as '1,x*y,z^2'")
    q.add_argument("--homogeneous", action="store_true", help="with --degree: monomials of degree exactly D")
    q.add_argument("--orbits", type=int, default=3, help="random orbits (default 3; 4 are used for pencils)")
    q.add_argument("--primes", default="2", help="initial number of random primes, or a list (default 2)")
    q.add_argument("--line-seed", type=int, default=0, help="seed of the random orbits and primes (default 0)")
    q.add_argument("--verify-steps", type=int, default=6, help="steps of the fresh exact orbit of the check (default 6)")
    q.add_argument("--fit-degree", type=int, default=None, metavar="D",
                   help="degree bound of integrals fitted from sparse kernel vectors (default twice the candidates' "
                   "degree; 0: no fit)")
    q.add_argument("--toml", metavar="FILE.toml", help="also write a system file with the found integrals in "
                   "[integrals] (and [defaults] eps), ready for `exact-khk certify --system FILE.toml`")
    q.add_argument("--symbolic", action="append", metavar="NAMES",
                   help="reconstruct the integrals as rational functions of eps and/or parameters of the system "
                   "(comma-separated or repeated: --symbolic eps,a1) from searches at random values, and prove "
                   "I(Phi(x)) = I(x) (exactly; over F_p with a stated bound beyond dimension 4); exit 4 if one is "
                   "not proven")
    q.add_argument("--symbolic-degree", type=int, default=None, metavar="T",
                   help="with --symbolic: the total degree bound of each coefficient's numerator and denominator "
                   "in the symbols (default and limit 12)")
    add_json_option(q, "the integrals found")
    q.set_defaults(func=cmd_find_integrals)


def _primes(text):
    text = str(text).strip()
    if text.isdigit() and "," not in text:
        return int(text)
    try:
        return [int(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise InputError(f"--primes: expected a count or a comma-separated list of primes, got {text!r}") from None


def _option(match) -> str:
    """The command-line option of a parameter name matched in an API error (``seed`` is ``--line-seed``)."""
    name = match.group(1)
    return "--" + {"seed": "line-seed"}.get(name, name.replace("_", "-")) + ":"


def cmd_map_degrees(args):
    """``degrees --map``: the degrees of a map of P^N and their recurrence fit."""
    from exact_khk.diagnostics.map_degrees import MapDegrees

    given = [o for o, v in (("--system", args.system), ("--n", args.n), ("--seed", args.seed), ("--x0", args.x0),
                            ("--eps", args.eps), ("--exact", args.exact or None), ("--plot", args.plot))
             if v is not None]
    if given:
        raise InputError(f"--map: {given[0]} does not apply to a map given by its components")
    if not args.variables:
        raise InputError("--map: give the homogeneous coordinates with --variables, e.g. --variables X,Y,Z")
    check_output(args.json)
    try:
        res = MapDegrees(args.map.split(","), args.variables.split(","), steps=args.steps,
                         primes=_primes(args.primes), seed=args.line_seed, confirm=args.confirm)
    except InputError as exc:
        raise InputError(re.sub(r"^(steps|primes|confirm|variables|map|seed):", _option, str(exc))) from None
    if args.json is not None:
        write_json(res.to_json(), args.json)
    if args.json != "-":
        print(res.summary())
    return 0


def cmd_degrees(args):
    from exact_khk.diagnostics import degree_sequence, plot_growth

    if args.map is not None:
        return cmd_map_degrees(args)

    if args.plot:
        from exact_khk.diagnostics.heights import plot_format

        plot_format(args.plot)
        check_output(args.plot, "--plot")
    check_output(args.json)
    system, x0, eps = system_from_args(args)
    primes = _primes(args.primes)
    try:
        total = (primes if isinstance(primes, int) else len(primes)) * args.lines * args.steps  # steps over F_p
        with Progress(args, total if 0 < total <= 10 ** 12 else None, "degrees") as progress:
            res = degree_sequence(system, steps=args.steps, eps=eps, field=field_name(system, args),
                                  primes=primes, lines=args.lines, seed=args.line_seed, exact=args.exact,
                                  confirm=args.confirm, heights=not args.no_heights, x0=x0, max_bits=args.max_bits,
                                  progress=progress)
    except InputError as exc:  # name the command-line options
        raise InputError(re.sub(r"(?<![-\w])(steps|primes|lines|exact|max_bits|confirm|seed):", _option,
                                str(exc))) from None
    if args.plot:
        plot_growth(args.plot, degrees=res, heights=res.heights,
                    title=f"{res.label}, ε = {eps}, x0 = ({', '.join(map(str, x0))})")
    if report(system, res, args.json):
        if args.plot:
            print(f"plot written to {args.plot}")
    return 0


def cmd_find_integrals(args):
    from exact_khk.diagnostics import find_integrals

    if args.system_spec is not None:
        if args.system is not None and args.system != args.system_spec:
            raise InputError(f"SYSTEM {args.system_spec!r} and --system {args.system!r} differ: give one")
        args.system = args.system_spec
    check_output(args.json)
    system, x0, eps = system_from_args(args)
    if args.toml == "-":  # check_output takes '-' for stdout; a file named '-' would surprise
        raise InputError("--toml: expected a file name ('-' for stdout is not supported: the table goes there)")
    if args.toml:
        check_output(args.toml, "--toml")
    kw = dict(field=field_name(system, args), eps=eps, homogeneous=args.homogeneous, orbits=args.orbits,
              steps=args.steps or None, primes=_primes(args.primes), seed=args.line_seed,
              x0=x0 if args.x0 is not None else None, verify_steps=args.verify_steps, fit_degree=args.fit_degree,
              max_bytes=max_memory())
    if args.monomials is not None:
        if args.homogeneous:
            raise InputError("--homogeneous applies only to --degree")
        kw["monomials_list"] = [t.strip() for t in args.monomials.split(",") if t.strip()]
    else:
        kw["degree"] = 2 if args.degree is None else args.degree
    try:
        with Progress(args, None, "find-integrals", unit="stage") as progress:
            if args.symbolic:
                return _symbolic(args, system, kw, progress)
            if args.symbolic_degree is not None:
                raise InputError("--symbolic-degree applies only with --symbolic")
            res = find_integrals(system, **kw, progress=progress)
    except InputError as exc:
        msg = str(exc)
        if msg.startswith("fit_degree:") and args.fit_degree is None:  # the default, twice the candidates' degree
            raise InputError(f"--fit-degree: not given, and its default (twice the candidates' degree) is beyond the "
                             f"limit ({msg.partition(': ')[2]}); give --fit-degree D (0: no fit)") from None
        for name in ("degree", "monomials", "orbits", "steps", "primes", "verify_steps", "x0", "fit_degree",
                     "symbolic", "max_degree", "toml", "seed"):
            if msg.startswith(name + ":"):
                msg = "--" + {"max_degree": "symbolic-degree", "seed": "line-seed"}.get(name, name.replace("_", "-")) \
                    + msg[len(name):]
                break
        raise InputError(msg) from None
    if args.toml:
        from exact_khk.diagnostics.integrals import system_file
        from exact_khk.studies.output import write_atomic

        write_atomic(args.toml, system_file(system, res, eps, kw["field"], x0 if args.x0 is not None else None),
                     "--toml")
    if report(system, res, args.json, eps=str(eps)):
        if args.toml:
            print(f"system file with the {len(res.integrals)} integral(s) written to {args.toml} "
                  f"(exact-khk certify --system {args.toml})")
    return 0


def _symbolic(args, system, kw, progress):
    """``--symbolic``: :func:`~exact_khk.diagnostics.parametric.symbolic_integrals`; exit 4 when an
    integral is not proven."""
    from exact_khk.diagnostics.parametric import MAX_DEGREE, symbolic_integrals, system_file

    names = [t for a in args.symbolic for t in a.split(",")]
    if args.toml and (getattr(system, "kind", None) != "expressions" or kw["field"] != "f"):
        raise InputError("--toml: with --symbolic, only for a system file or catalogue entry and the field f")
    res = symbolic_integrals(system, names, progress=progress, max_degree=MAX_DEGREE if args.symbolic_degree is None
                             else args.symbolic_degree, **kw)
    if args.toml:
        from exact_khk.studies.output import write_atomic

        write_atomic(args.toml, system_file(system, res), "--toml")
    if report(system, res, args.json):
        if args.toml:
            print(f"system file with the {sum(f.proven for f in res.integrals)} proven integral(s) written to "
                  f"{args.toml} (exact-khk certify --system {args.toml})")
    return 0 if all(f.proven for f in res.integrals) else 4
