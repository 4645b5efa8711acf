"""Options shared by the commands: the system, x0, ε, steps, arithmetic, output.

``--system NAME|FILE`` selects a catalogue system or a system file; otherwise
the Lie–Poisson family (``--n``, ``--a/--b/--c``, ``--seed``; default the
built-in n = 3 system).
"""

from __future__ import annotations

import argparse
import json

from exact_khk.arith import arith_names
from exact_khk.errors import InputError
from exact_khk.parsing import parse_rational, parse_vector
from exact_khk.studies.output import check_writable, write_atomic
from exact_khk.systems.lie_poisson.system import (DEFAULT_EPS, DEFAULT_VECTORS, DEFAULT_X0, LiePoissonSystem,
                                                  random_point)


class Parser(argparse.ArgumentParser):
    """argparse with a one-line error message and exit status 2."""

    def error(self, message):
        where = self.prog.removeprefix("exact-khk").strip()
        raise InputError(f"{where}: {message}" if where else message)


# --- shared options -----------------------------------------------------------


def add_system_options(p, steps_default=20):
    g = p.add_argument_group("system (default: the built-in n = 3 Lie–Poisson system, see README)")
    g.add_argument("--system", metavar="NAME|FILE",
                   help="a catalogue system (see 'exact-khk systems') or a system file (.toml, see "
                        "docs/system-files.md) instead of the Lie–Poisson family")
    g.add_argument("--n", type=int, help="half the phase-space dimension (n >= 2)")
    g.add_argument("--a", help="first Hessian block vector, e.g. '1/2,-3,0'")
    g.add_argument("--b", help="second Hessian block vector")
    g.add_argument("--c", help="third Hessian block vector")
    g.add_argument("--seed", type=int, help="draw a, b, c (and x0 if not given) as small random integers")
    g.add_argument("--x0", help="initial point: comma-separated rationals (2n for the Lie–Poisson family)")
    g.add_argument("--eps", default=None, help=f"step size, a nonzero rational (default {DEFAULT_EPS})")
    g.add_argument("--steps", type=int, default=steps_default, help=f"number of steps K (default {steps_default})")
    g.add_argument("--arith", default=None,
                   help="arithmetic: " + ", ".join(arith_names()) + " (default: fastest exact)")


def system_from_args(args):
    """(system, x0, eps) from parsed options, with typed errors naming the option."""
    if getattr(args, "system", None) is not None:
        return _named_system(args)
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


def write_json(obj, target):
    """Write ``obj`` to a path (atomically), or to stdout for ``-``."""
    text = json.dumps(obj, indent=1)
    if target in (None, "-"):
        print(text)
    else:
        write_atomic(target, text + "\n", "--json")


def check_output(target, what="--json"):
    """Check an output path (not ``-``) before the work starts."""
    if target not in (None, "-"):
        check_writable(target, what)




def _named_system(args):
    """(system, x0, eps) for ``--system NAME|FILE``."""
    from exact_khk.systems.catalogue import resolve

    clash = [o for o, v in (("--n", args.n), ("--a", args.a), ("--b", args.b), ("--c", args.c)) if v is not None]
    if clash:
        raise InputError(f"--system: {clash[0]} describes the Lie–Poisson family; it cannot be combined with --system")
    system = resolve(args.system)
    if args.x0 is not None:
        x0 = parse_vector(args.x0, "--x0", system.dim)
    elif args.seed is not None:
        x0 = system.random_point(args.seed)
    else:
        x0 = parse_vector(list(system.default_x0), "--x0", system.dim)
    eps = system.default_eps if args.eps is None else parse_rational(args.eps, "--eps")
    if eps == 0:
        raise InputError("--eps: the step size must be nonzero")
    if args.steps < 0:
        raise InputError(f"--steps: expected a non-negative integer, got {args.steps}")
    return system, x0, eps
