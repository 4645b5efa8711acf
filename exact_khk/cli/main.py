"""Command-line interface: ``exact-khk <command> [options]``.

Exit status: 0 success; 1 a certification failed (``certify``); 2 malformed
input (one-line message); 3 a singular Kahan step (one-line message naming the
step, x and eps) or an integral evaluated at its pole.

Each command lives in a module with ``register(subparsers)``; the module list
is :data:`COMMAND_MODULES`.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys

from exact_khk import __version__
from exact_khk.arith import arith_names, get_arith
from exact_khk.errors import InputError, PoleError, SingularStepError
from exact_khk.kahan.map import METHODS, KahanMap
from exact_khk.parsing import parse_rational, parse_vector
from exact_khk.systems.lie_poisson.system import (DEFAULT_EPS, DEFAULT_VECTORS, DEFAULT_X0, LiePoissonSystem, b0_signs,
                      random_point)

COMMAND_MODULES = ["exact_khk.cli.main", "exact_khk.cli.certify", "exact_khk.cli.study", "exact_khk.cli.liouville"]


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error message and exit status 2."""

    def error(self, message):
        where = self.prog.removeprefix("exact-khk").strip()
        raise InputError(f"{where}: {message}" if where else message)


# --- shared options -----------------------------------------------------------


def add_system_options(p, steps_default=20):
    g = p.add_argument_group("system (default: the built-in n = 3 system, see README)")
    g.add_argument("--n", type=int, help="half the phase-space dimension (n >= 2)")
    g.add_argument("--a", help="first Hessian block vector, e.g. '1/2,-3,0'")
    g.add_argument("--b", help="second Hessian block vector")
    g.add_argument("--c", help="third Hessian block vector")
    g.add_argument("--seed", type=int, help="draw a, b, c (and x0 if not given) as small random integers")
    g.add_argument("--x0", help="initial point: 2n comma-separated rationals")
    g.add_argument("--eps", default=None, help=f"step size, a nonzero rational (default {DEFAULT_EPS})")
    g.add_argument("--steps", type=int, default=steps_default, help=f"number of steps K (default {steps_default})")
    g.add_argument("--arith", default=None,
                   help="arithmetic: " + ", ".join(arith_names()) + " (default: fastest exact)")


def system_from_args(args):
    """(system, x0, eps) from parsed options, with typed errors naming the option."""
    given = [v is not None for v in (args.a, args.b, args.c)]
    if any(given) and not all(given):
        raise InputError("--a, --b and --c must be given together")
    if all(given) and args.seed is not None:
        raise InputError("give either --a/--b/--c or --seed, not both")
    if args.n is not None and args.n < 2:
        raise InputError(f"--n: the family needs n >= 2, got {args.n}")
    if all(given):
        a = parse_vector(args.a, "--a", args.n)
        system = LiePoissonSystem(a, parse_vector(args.b, "--b", len(a)), parse_vector(args.c, "--c", len(a)))
        if args.x0 is None:
            raise InputError("--x0 is required with --a/--b/--c")
    elif args.seed is not None:
        if args.n is None:
            raise InputError("--seed needs --n")
        system = LiePoissonSystem.random(args.n, args.seed)
    else:
        if args.n not in (None, 3):
            raise InputError("--n other than 3 needs --a/--b/--c or --seed")
        system = LiePoissonSystem.from_vectors(*DEFAULT_VECTORS)
    if args.x0 is not None:
        x0 = parse_vector(args.x0, "--x0", system.dim)
    elif args.seed is not None:
        x0 = random_point(system.n, args.seed)
    else:
        x0 = parse_vector(list(DEFAULT_X0), "--x0")
    eps = DEFAULT_EPS if args.eps is None else parse_rational(args.eps, "--eps")
    if eps == 0:
        raise InputError("--eps: the step size must be nonzero")
    if args.steps < 0:
        raise InputError(f"--steps: expected a non-negative integer, got {args.steps}")
    return system, x0, eps


def system_json(system):
    return {"family": "lie-poisson", "n": system.n,
            "a": [str(t) for t in system.a], "b": [str(t) for t in system.b],
            "c": [str(t) for t in system.c]}


def library_versions():
    import importlib.metadata as md

    out = {"exact_khk": __version__, "python": sys.version.split()[0]}
    for dist in ("python-flint", "gmpy2", "mpmath", "sympy"):
        try:
            out[dist] = md.version(dist)
        except md.PackageNotFoundError:
            out[dist] = None
    return out


def write_json(obj, target):
    """Write ``obj`` to a path, or to stdout for ``-``."""
    text = json.dumps(obj, indent=1)
    if target in (None, "-"):
        print(text)
    else:
        with open(target, "w") as fh:
            fh.write(text + "\n")


def height_bits(ar, v) -> int:
    """max(bit length of numerator, denominator) of an exact rational."""
    q = ar.to_fraction(v)
    return max(abs(q.numerator).bit_length(), q.denominator.bit_length())


# --- exact-khk orbit ----------------------------------------------------------


def register(sub):
    p = sub.add_parser("orbit", help="iterate a Kahan map and print the orbit",
                       description="Iterate the Kahan map of a Lie–Poisson field.")
    add_system_options(p)
    p.add_argument("--field", choices=["f", "g", "control"], default="f",
                   help="f (Hessian Hs), g (B Hs, see --signs) or control (A Hs; (2I+A) Hs for n = 2)")
    p.add_argument("--signs", help="sign pattern of the involution for --field g (default B_0 = '-+...+')")
    p.add_argument("--method", choices=METHODS, default="auto",
                   help="how each step is solved: dense (one 2n x 2n solve), structured (2x2 over "
                        "Q[t]/(t^n - 1), or the DFT for floating arithmetics), split (exact, n = 2, 3, 4, "
                        "6: 2x2 over each factor of t^n - 1); default auto: the fastest measured path")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    p.set_defaults(func=cmd_orbit)


def cmd_orbit(args):
    system, x0, eps = system_from_args(args)
    ar = get_arith(args.arith)
    if args.signs is not None and args.field != "g":
        raise InputError("--signs applies only to --field g")
    signs = args.signs if args.signs is not None else (b0_signs(system.n) if args.field == "g" else None)
    from exact_khk.certification.lie_poisson import expresses_omega  # a non-rational involution needs ω in the arithmetic

    fld = system.field(args.field, signs=signs, cyclotomic=args.field == "g" and expresses_omega(ar, system.n))
    phi = KahanMap(fld, eps, ar, method=args.method)
    pts = phi.orbit(x0, args.steps)
    if args.json:
        write_json({"system": system_json(system), "field": fld.label, "signs": fld.signs,
                    "eps": str(eps), "steps": args.steps, "arith": ar.name, "exact": ar.exact,
                    "method": args.method, "path": phi.path,
                    "x0": [str(t) for t in x0],
                    "orbit": [[ar.format(t) for t in p] for p in pts],
                    "versions": library_versions()}, "-")
        return 0
    print(system.describe())
    kind = "exact" if ar.exact else f"{ar.prec}-bit floating point"
    print(f"field {fld.label}, eps = {eps}, {args.steps} steps, arithmetic {ar.name} ({kind}), "
          f"method {args.method}: {phi.path}")
    if not (ar.rational or not ar.exact):  # Q(zeta), F_p: no real approximation to show
        for k, p in enumerate(pts):
            print(f"{k:>4}  (" + ", ".join(ar.format(t) for t in p) + ")")
        return 0
    if ar.exact:
        print("coordinates are the exact rationals rounded to 8 significant digits for display; "
              "'bits' is the largest numerator/denominator bit length (--json prints them exactly)")
    else:
        print(f"coordinates are the {ar.name} values rounded to 8 significant digits (--json prints all digits)")
    head = f"{'k':>4}  " + "  ".join(f"{'x' + str(i):>15}" for i in range(system.dim))
    print(head + ("   bits" if ar.exact else ""))
    for k, p in enumerate(pts):
        row = f"{k:>4}  " + "  ".join(f"{ar.to_float(t):>15.8g}" for t in p)
        if ar.exact:
            row += f"  {max(height_bits(ar, t) for t in p):>5}"
        print(row)
    return 0


# --- entry point --------------------------------------------------------------


def build_parser():
    parser = _Parser(prog="exact-khk", description="Exact certification of Kahan–Hirota–Kimura maps "
                     "(Lie–Poisson family of Petrera & Suris).")
    parser.add_argument("--version", action="version", version=f"exact-khk {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def _join_values(argv, parser):
    """Turn ``--opt -1/10`` into ``--opt=-1/10`` for options that take a value.

    argparse would read a value starting with '-' (a negative rational, a sign
    pattern such as '-++') as an option.
    """
    takes_value = set()
    subparsers = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    for sp in [parser] + [p for a in subparsers for p in a.choices.values()]:
        for a in sp._actions:
            if a.option_strings and a.nargs is None:  # a store/append option with one value
                takes_value.update(a.option_strings)
    out, i = [], 0
    while i < len(argv):
        tok = argv[i]
        if tok in takes_value and i + 1 < len(argv) and argv[i + 1].startswith("-") \
                and argv[i + 1] not in takes_value and not argv[i + 1].startswith("--"):
            out.append(f"{tok}={argv[i + 1]}")
            i += 2
        else:
            out.append(tok)
            i += 1
    return out


def main(argv=None) -> int:
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        args = parser.parse_args(_join_values(argv, parser))
        if args.command is None:
            parser.print_help()
            return 2
        return args.func(args)
    except InputError as exc:
        print(f"exact-khk: error: {exc}", file=sys.stderr)
        return 2
    except SingularStepError as exc:
        print(f"exact-khk: singular step: {exc}", file=sys.stderr)
        return 3
    except PoleError as exc:
        print(f"exact-khk: undefined: {exc}", file=sys.stderr)
        return 3
    except BrokenPipeError:
        return 0


def entry_point():  # console script
    sys.exit(main())


if __name__ == "__main__":
    entry_point()
