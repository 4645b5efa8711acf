"""``exact-khk certify`` and ``exact-khk integrals`` (thin views of :mod:`exact_khk.certify`).

Exit status of ``certify``: 0 VALID (every claim holds and every applicable
negative control fails), 1 INVALID (a claim is false), 4 INCONCLUSIVE (no claim
is false, but a check is undecided or a control did not fail); 2 bad input;
3 singular step.
"""

from __future__ import annotations

import sys

from exact_khk.arith import get_arith
from exact_khk.certification.claims import CLAIMS
from exact_khk.certification.controls import degenerate_point
from exact_khk.certification.engine import certify_system
from exact_khk.certification.lie_poisson import certify, default_signs
from exact_khk.cli.options import (Progress, add_json_option, add_system_options, check_output, check_resources,
                                   invocation, system_from_args, write_json)
from exact_khk.certification.records import library_versions
from exact_khk.errors import InputError, SingularStepError
from exact_khk.arith.cyclotomic import DEFAULT_PRIME
from exact_khk.systems.lie_poisson.invariants import Htilde
from exact_khk.systems.lie_poisson.system import check_signs_arith
from exact_khk.kahan.map import KahanMap
from exact_khk.parsing import format_signs, parse_signs


#: exit status by certificate status
EXIT_STATUS = {"VALID": 0, "INVALID": 1, "INCONCLUSIVE": 4}


#: the most involutions certified by default (2^(number of divisors of n) − 2
#: rational ones, 2^n − 2 with omega): beyond, --signs must name them
MAX_DEFAULT_SIGNS = 4096


def _signs(args, n, ar):
    if not args.signs:
        from exact_khk.systems.lie_poisson.system import divisor_classes, expresses_omega

        count = 2 ** (n if n >= 3 and expresses_omega(ar, n) else len(divisor_classes(n))) - 2
        if count > MAX_DEFAULT_SIGNS:
            raise InputError(f"--signs: n = {n} has {count:,} involutions to certify by default, beyond the "
                             f"limit of {MAX_DEFAULT_SIGNS} (MAX_DEFAULT_SIGNS); name some with --signs")
        return default_signs(n, ar)
    return [format_signs(parse_signs(s, n)) for s in args.signs]


def register(sub):
    p = sub.add_parser("certify", help="certify integrals, commutation, reversibility, Poisson "
                       "structure, involution and rank on an orbit, with negative controls",
                       description="Certify the theorems of Petrera & Suris on the orbit of x0 (with no "
                       "options: the built-in n = 3 system, x0 and eps = 1/10, 20 steps), or with --system what "
                       "a catalogue system or a system file declares. Exit status 0 VALID, 1 INVALID (a claim "
                       "is false), 2 malformed input or a run beyond a limit, 3 a singular step of Phi_f (or an "
                       "integral at its pole, or a floating result with no trustworthy bit), 4 INCONCLUSIVE (a "
                       "check undecided, or a control that did not fail or cannot fail), 5 an output that cannot "
                       "be written or memory exhausted, 70 an internal error, 130 interrupted.")
    add_system_options(p, steps_default=None)
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
                   help="also prove every claim symbolically, as an identity of rational functions in "
                        "(x, eps) (dimension <= 4: the Euler top, the family's n = 2; seconds)")
    p.add_argument("--claims", metavar="LIST",
                   help="with --system: comma-separated claims to certify, some of " + ", ".join(CLAIMS)
                   + " (default: the system file's list, else everything it declares)")
    add_json_option(p, "the certificate")
    p.set_defaults(func=cmd_certify)

    q = sub.add_parser("integrals", help="print H~ and every K~ at a point",
                       description="Print the integrals H~(x, eps) and K~[signs](x, eps) (closed form "
                       "(tH 4)) at x0, or at the point after --steps steps of Phi_f.")
    add_system_options(q, steps_default=0)
    q.add_argument("--signs", action="append", metavar="SIGNS",
                   help="involution for K~ (repeatable; default as for certify)")
    add_json_option(q, 'the values ({"Htilde": "p/q", "Ktilde": {"<signs>": "p/q", ...}, ...})')
    q.set_defaults(func=cmd_integrals)


def cmd_certify(args):
    check_output(args.json)
    system, x0, eps = system_from_args(args)
    if args.steps is None:
        args.steps = system.default_steps
    if args.steps < 1:
        raise InputError(f"--steps: certify needs at least 1 step, got {args.steps}")
    if not system.certificate_options:  # the certificate of what the system declares
        return _certify_system(args, system, x0, eps)
    if args.claims is not None:
        raise InputError("--claims applies to --system; the Lie–Poisson certificate checks every theorem")
    if args.poisson_points is not None and args.poisson_points < 1:
        raise InputError(f"--poisson-points: expected a positive integer, got {args.poisson_points}")
    ar = get_arith(args.arith)
    phi = KahanMap(system.field("f"), eps, ar)
    # the certificate solves dense 2n x 2n systems and takes exact gradients of Pi by dual
    # numbers ((2n)^3 numbers): checked first, before the involutions are even listed
    check_resources("certify", system, phi, x0, 0, dense=True, cube_numbers=2)
    signs = _signs(args, system.n, ar)
    # it keeps every orbit (Phi_f and each Phi_g) with Pi and the gradients at each point
    check_resources("certify", system, phi, x0, args.steps, orbits=1 + len(signs), per_point=1 + system.dim)
    with Progress(args, None, "certify", unit="check") as progress:
        cert, x0 = _drawn(args, system, x0, eps, lambda x: certify(
            system, x, eps, args.steps, ar, signs, poisson_points=args.poisson_points, progress=progress,
            identities=args.identities, prove=args.prove))
    if args.json != "-":
        print(system.describe())
        print(f"x0 = ({', '.join(str(t) for t in x0)}), eps = {eps}, {args.steps} steps, "
              f"arithmetic {cert.arith}, associated fields g[{'], g['.join(cert.signs)}]")
        print(cert.table())
        print(cert.verdict())
    _advise(cert)
    if args.json is not None:
        write_json(_with_invocation(cert, args, x0, eps), args.json)
    return EXIT_STATUS[cert.status]


#: points drawn for ``--seed`` before a singular step or a degenerate point is reported (exit 3 or 4): of 300
#: random Lie–Poisson certificates (n = 2, 3, 4, seeds 0-99), 21 first draws met a singular step at steps 2-5
#: and 2 lay on orbits where the integrals' gradients have rank 1
MAX_REDRAWS = 20


def _drawn(args, system, x0, eps, run):
    """(certificate, x0) of ``run(x0)``; a point the tool drew itself (``--seed`` without ``--x0``) whose
    orbit meets a singular step, or that is degenerate by :func:`degenerate_point` (the rule that advises a
    user to pick another point), is replaced by the seed's next draw, and stderr says so.  A certificate
    with a false claim is never redrawn."""
    drawn, seen = args.seed is not None and args.x0 is None, []
    for skip in range(1, MAX_REDRAWS + 1):
        try:
            cert = run(x0)
            if not drawn or skip == MAX_REDRAWS or degenerate_point(cert) is None:
                break
            seen.append("degenerate (INCONCLUSIVE)")
        except SingularStepError as exc:
            if not drawn or skip == MAX_REDRAWS:
                raise
            seen.append("a singular step" + (f" at step {exc.step}" if getattr(exc, "step", None) is not None else ""))
        x0 = system.seeded_point(args.seed, eps, skip=skip)
    if seen:
        last = ("; every draw is: the system itself may be degenerate (e.g. its integrals dependent everywhere)"
                if len(seen) == MAX_REDRAWS - 1 and degenerate_point(cert) is not None else "")
        print(f"x0 drawn for --seed {args.seed}: draw {len(seen) + 1} is used, x0 = ({', '.join(str(t) for t in x0)}); "
              f"draws 1..{len(seen)}: {', '.join(dict.fromkeys(seen))}{last}", file=sys.stderr)
    return cert, x0


def _with_invocation(cert, args, x0, eps) -> dict:
    """The certificate's JSON with the informational key ``invocation`` (the command line and
    its resolved options; the verifier does not read it)."""
    return {**cert.to_json(), "invocation": invocation(args, arith=cert.arith, x0=x0, eps=eps, steps=args.steps)}


def _advise(cert):
    """On stderr: why the point is degenerate and how to pick another, when it is."""
    advice = degenerate_point(cert)
    if advice:
        print(advice, file=sys.stderr)


def _certify_system(args, system, x0, eps):
    """``certify --system``: the generic certificate of what the system declares."""
    for opt, given in (("--signs", args.signs), ("--poisson-points", args.poisson_points)):
        if given:
            raise InputError(f"{opt} applies only to the Lie–Poisson family, not to --system")
    ar = get_arith(args.arith)
    check_resources("certify", system, KahanMap(system.field("f"), eps, ar), x0, args.steps, dense=True,
                    orbits=len(system.field_names()), per_point=1 + system.dim, cube_numbers=2)
    with Progress(args, None, "certify", unit="check") as progress:
        cert, x0 = _drawn(args, system, x0, eps, lambda x: certify_system(
            system, x, eps, args.steps, ar, claims=args.claims,  # a comma list
            identities=args.identities, prove=args.prove, progress=progress))
    if args.json != "-":
        print(cert.summary().rsplit("\n", 1)[0])
        print(cert.table())
        print(cert.verdict())
    _advise(cert)
    if args.json is not None:
        write_json(_with_invocation(cert, args, x0, eps), args.json)
    return EXIT_STATUS[cert.status]


def cmd_integrals(args):
    check_output(args.json)
    system, x0, eps = system_from_args(args)
    ar = get_arith(args.arith)
    if "signs" not in system.certificate_options:  # no involutions: the declared integrals
        return _system_integrals(args, system, x0, eps, ar)
    phi = KahanMap(system.field("f"), eps, ar)
    # H~ takes the structured solve for exact flint arithmetic and n >= 3, else the dense one
    structured_htilde = ar.rational and ar.integers is not None and ar.integers.name == "flint" and system.n >= 3
    check_resources("integrals", system, phi, x0, args.steps,
                    dense=not structured_htilde or (phi.structure is None and not phi.split), final_solve=True)
    signs = _signs(args, system.n, ar)
    check_signs_arith(system.n, signs, ar, "--signs")  # before the orbit: K~ of the others needs Q(omega)
    with Progress(args, args.steps, "orbit") as progress:
        x = phi.orbit(x0, args.steps, progress=progress)[-1]
    K = {}
    with Progress(args, 1 + len(signs), "integrals", unit="integral") as progress:
        H = ar.format(Htilde(system.field("f"), x, eps, ar))
        for k, s in enumerate(signs, 1):
            progress(k)
            K[s] = ar.format(Htilde(system.field("g", s, cyclotomic=True), x, eps, ar))
        progress(1 + len(signs))
    return _show_integrals(args, system, x, eps, ar, {"Htilde": H, "Ktilde": K},
                           {"H~": H} | {f"K~[{s}]": v for s, v in K.items()})


def _show_integrals(args, system, x, eps, ar, data, lines):
    """Print the integrals' values at x (``lines``: name -> value), or ``data`` as JSON."""
    if args.json is not None:
        write_json({**data, "system": system.to_json(), "x": [ar.format(t) for t in x], "step": args.steps,
                    "eps": str(eps), "arith": ar.name, "exact": ar.exact, "versions": library_versions()}, args.json)
        if args.json == "-":
            return 0
    print(system.describe())
    at = "x0" if args.steps == 0 else f"x_{args.steps} = Phi_f^{args.steps}(x0)"
    print(f"at {at} = ({', '.join(ar.format(t) for t in x)}), eps = {eps}, arithmetic {ar.name}")
    if not lines:
        print(f"{system.name} declares no integrals")
    for name, v in lines.items():
        print(f"{name} = {v}")
    return 0


def _system_integrals(args, system, x0, eps, ar):
    """``integrals --system``: the declared integrals at x0 or after --steps steps."""
    if args.signs:
        raise InputError("--signs applies only to the Lie–Poisson family, not to --system")
    phi = KahanMap(system.field("f"), eps, ar)
    check_resources("integrals", system, phi, x0, args.steps, dense=True)
    x = phi.orbit(x0, args.steps)[-1]
    e = ar.convert(eps)
    values = {name: ar.format(fn(ar, x, e)) for name, fn in system.integrals().items()}
    return _show_integrals(args, system, x, eps, ar, {"integrals": values}, values)
