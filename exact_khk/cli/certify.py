"""``exact-khk certify`` and ``exact-khk integrals`` (thin views of :mod:`exact_khk.certify`).

Exit status of ``certify``: 0 VALID (every claim holds and every applicable
negative control fails), 1 INVALID (a claim is false), 4 INCONCLUSIVE (no claim
is false, but a check is undecided or a control did not fail); 2 bad input;
3 singular step.
"""

from __future__ import annotations

from exact_khk.arith import get_arith
from exact_khk.certification.generic import CLAIMS, certify_system
from exact_khk.certification.lie_poisson import certify, default_signs
from exact_khk.cli.options import add_system_options, check_output, system_from_args, write_json
from exact_khk.certification.records import library_versions
from exact_khk.errors import InputError
from exact_khk.arith.cyclotomic import DEFAULT_PRIME
from exact_khk.systems.lie_poisson.invariants import Htilde
from exact_khk.kahan.map import KahanMap
from exact_khk.parsing import format_signs, parse_signs


#: exit status by certificate status
EXIT_STATUS = {"VALID": 0, "INVALID": 1, "INCONCLUSIVE": 4}


def _signs(args, n, ar):
    if not args.signs:
        return default_signs(n, ar)
    return [format_signs(parse_signs(s, n)) for s in args.signs]


def register(sub):
    p = sub.add_parser("certify", help="certify integrals, commutation, reversibility, Poisson "
                       "structure, involution and rank on an orbit, with negative controls",
                       description="Certify the theorems of Petrera & Suris on the orbit of x0 (with no "
                       "options: the built-in n = 3 system, x0 and eps = 1/10, 20 steps), or with --system what "
                       "a catalogue system or a system file declares. Exit status 0 VALID, 1 INVALID (a claim "
                       "is false), 4 INCONCLUSIVE.")
    add_system_options(p, steps_default=20)
    p.add_argument("--signs", action="append", metavar="SIGNS",
                   help="involution of an associated field, e.g. '-++' (repeatable; default: every "
                   "involution other than ±I that the arithmetic can express: the rational ones, "
                   "all of them in cyclo:N with n | N or gf:P with P = 1 mod n)")
    p.add_argument("--poisson-points", type=int, metavar="K",
                   help="run the Poisson-map and Jacobi checks at K evenly spread orbit points (default: all)")
    p.add_argument("--identities", nargs="?", const=f"gf:{DEFAULT_PRIME}", metavar="gf:P",
                   help="also check every claim as an identity in (x, eps) by Schwartz–Zippel over F_P "
                   f"(probabilistic evidence with a stated failure bound; default P = {DEFAULT_PRIME})")
    p.add_argument("--prove", action="store_true",
                   help="also prove conservation, commutation and the Jacobi identity symbolically (n = 2)")
    p.add_argument("--claims", metavar="LIST",
                   help="with --system: comma-separated claims to certify, some of " + ", ".join(CLAIMS)
                   + " (default: the system file's list, else everything it declares)")
    p.add_argument("--json", metavar="FILE", help="write the certificate as JSON to FILE ('-': stdout, no table)")
    p.set_defaults(func=cmd_certify)

    q = sub.add_parser("integrals", help="print H~ and every K~ at a point",
                       description="Print the integrals H~(x, eps) and K~[signs](x, eps) (closed form "
                       "(tH 4)) at x0, or at the point after --steps steps of Phi_f.")
    add_system_options(q, steps_default=0)
    q.add_argument("--signs", action="append", metavar="SIGNS",
                   help="involution for K~ (repeatable; default as for certify)")
    q.add_argument("--json", action="store_true",
                   help='print {"Htilde": "p/q", "Ktilde": {"<signs>": "p/q", ...}, ...}')
    q.set_defaults(func=cmd_integrals)


def cmd_certify(args):
    check_output(args.json)
    system, x0, eps = system_from_args(args)
    if args.steps < 1:
        raise InputError(f"--steps: certify needs at least 1 step, got {args.steps}")
    if system.kind != "lie-poisson":
        return _certify_system(args, system, x0, eps)
    if args.claims is not None:
        raise InputError("--claims applies to --system; the Lie–Poisson certificate checks every theorem")
    if args.poisson_points is not None and args.poisson_points < 1:
        raise InputError(f"--poisson-points: expected a positive integer, got {args.poisson_points}")
    ar = get_arith(args.arith)
    cert = certify(system, x0, eps, args.steps, ar, _signs(args, system.n, ar),
                   poisson_points=args.poisson_points, identities=args.identities, prove=args.prove)
    if args.json != "-":
        print(system.describe())
        print(f"x0 = ({', '.join(str(t) for t in x0)}), eps = {eps}, {args.steps} steps, "
              f"arithmetic {cert.arith}, associated fields g[{'], g['.join(cert.signs)}]")
        print(cert.table())
        print(cert.verdict())
    if args.json is not None:
        write_json(cert.to_json(), args.json)
    return EXIT_STATUS[cert.status]


def _certify_system(args, system, x0, eps):
    """``certify --system``: the generic certificate of what the system declares."""
    for opt, given in (("--signs", args.signs), ("--poisson-points", args.poisson_points),
                       ("--identities", args.identities), ("--prove", args.prove)):
        if given:
            raise InputError(f"{opt} applies only to the Lie–Poisson family, not to --system")
    claims = None if args.claims is None else [c.strip() for c in args.claims.split(",") if c.strip()]
    cert = certify_system(system, x0, eps, args.steps, get_arith(args.arith), claims=claims)
    if args.json != "-":
        print(cert.summary().rsplit("\n", 1)[0])
        print(cert.table())
        print(cert.verdict())
    if args.json is not None:
        write_json(cert.to_json(), args.json)
    return EXIT_STATUS[cert.status]


def cmd_integrals(args):
    system, x0, eps = system_from_args(args)
    ar = get_arith(args.arith)
    if system.kind != "lie-poisson":
        return _system_integrals(args, system, x0, eps, ar)
    x = KahanMap(system.field("f"), eps, ar).orbit(x0, args.steps)[-1]
    signs = _signs(args, system.n, ar)
    H = ar.format(Htilde(system.field("f"), x, eps, ar))
    K = {s: ar.format(Htilde(system.field("g", s, cyclotomic=True), x, eps, ar)) for s in signs}
    if args.json:
        write_json({"Htilde": H, "Ktilde": K, "system": system.to_json(), "x": [ar.format(t) for t in x],
                    "step": args.steps, "eps": str(eps), "arith": ar.name, "exact": ar.exact,
                    "versions": library_versions()}, "-")
        return 0
    print(system.describe())
    at = "x0" if args.steps == 0 else f"x_{args.steps} = Phi_f^{args.steps}(x0)"
    print(f"at {at} = ({', '.join(ar.format(t) for t in x)}), eps = {eps}, arithmetic {ar.name}")
    print(f"H~ = {H}")
    for s, v in K.items():
        print(f"K~[{s}] = {v}")
    return 0


def _system_integrals(args, system, x0, eps, ar):
    """``integrals --system``: the declared integrals at x0 or after --steps steps."""
    if args.signs:
        raise InputError("--signs applies only to the Lie–Poisson family, not to --system")
    x = KahanMap(system.field("f"), eps, ar).orbit(x0, args.steps)[-1]
    e = ar.convert(eps)
    values = {name: ar.format(fn(ar, x, e)) for name, fn in system.integrals().items()}
    if args.json:
        write_json({"integrals": values, "system": system.to_json(), "x": [ar.format(t) for t in x],
                    "step": args.steps, "eps": str(eps), "arith": ar.name, "exact": ar.exact,
                    "versions": library_versions()}, "-")
        return 0
    print(system.describe())
    at = "x0" if args.steps == 0 else f"x_{args.steps} = Phi_f^{args.steps}(x0)"
    print(f"at {at} = ({', '.join(ar.format(t) for t in x)}), eps = {eps}, arithmetic {ar.name}")
    if not values:
        print(f"{system.name} declares no integrals")
    for name, v in values.items():
        print(f"{name} = {v}")
    return 0
