"""``exact-khk classify``: is the Kahan map of a system integrable?  One verdict and its evidence
(a thin view of :mod:`exact_khk.diagnostics.classify`; docs/diagnostics.md)."""

from __future__ import annotations

from exact_khk.cli.options import (Progress, add_field_options, add_system_options, check_output, field_name,
                                   report, system_from_args)
from exact_khk.errors import InputError

HELP = "integrable, non-integrable or undetermined: a verdict on a Kahan map with its evidence"


def register(sub):
    p = sub.add_parser("classify", help=HELP,
                       description="Degree growth over F_p (and exactly over Q for the first iterates), the fitted "
                       "recurrence and dynamical degree, integrals found and verified, invariant measure and "
                       "Poisson structure where found; one verdict by the rules in docs/diagnostics.md. Exit 0 "
                       "for integrable or non-integrable, 4 for undetermined.")
    p.add_argument("target", nargs="?", metavar="SYSTEM",
                   help="a catalogue name (see 'exact-khk systems') or a system file; same as --system")
    add_system_options(p, steps_default=20, arith=False)
    add_field_options(p)
    p.add_argument("--degree", type=int, default=None,
                   help="largest degree of the integral search (when not given: 4, or lower where the candidates "
                        "would exceed 70 monomials: 3 in dimension 5, 2 in 6)")
    p.add_argument("--fit-degree", type=int, default=None,
                   help="degree bound of the integrals fitted from kernel entries (when not given: twice --degree, "
                        "or --degree from dimension 6)")
    p.add_argument("--exact", type=int, default=6, metavar="K",
                   help="compose the first K iterates exactly over Q where affordable: exact degrees and the "
                        "proven bound lambda <= d_k^(1/k) (default 6)")
    p.add_argument("--line-seed", type=int, default=0, help="seed of the random primes, lines and orbits (default 0)")
    p.add_argument("--no-discover", action="store_true", help="skip the invariant-measure and Poisson searches")
    p.add_argument("--json", nargs="?", const="-", default=None, metavar="PATH",
                   help="write the classification as JSON to PATH (stdout without PATH or with '-')")
    p.set_defaults(func=cmd_classify)


def cmd_classify(args):
    from exact_khk.diagnostics.classify import classify

    if args.target is not None:
        if args.system is not None and args.system != args.target:
            raise InputError(f"classify: two systems given ({args.target!r} and --system {args.system!r})")
        args.system = args.target
    if args.x0 is not None:  # it was read and ignored: the evidence uses random lines and fresh orbits
        raise InputError("--x0: classify starts from no given point (degrees on random lines over F_p, integrals "
                         "and measures checked on fresh orbits); use find-measure/find-poisson --x0 for an orbit")
    if args.json not in (None, "-"):
        check_output(args.json)
    system, _x0, eps = system_from_args(args)
    try:
        with Progress(args, None, "classify", unit="stage") as progress:
            res = classify(system, eps=eps, steps=args.steps, degree=args.degree, field=field_name(system, args),
                           seed=args.line_seed, exact=args.exact,
                           discover=() if args.no_discover else ("measure", "poisson"), progress=progress,
                           fit_degree=args.fit_degree)
    except InputError as exc:
        msg = str(exc)
        for name in ("steps", "degree", "fit_degree", "exact", "discover", "seed"):
            if msg.startswith(name + ":"):
                msg = "--" + {"seed": "line-seed"}.get(name, name.replace("_", "-")) + msg[len(name):]
                break
        raise InputError(msg) from None
    if report(system, res, args.json):
        if args.json is not None:
            print(f"classification written to {args.json}")
    return 4 if res.verdict == "undetermined" else 0
