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
import sys

from exact_khk import __version__
from exact_khk.cli.options import Parser
from exact_khk.errors import InputError, PoleError, SingularStepError

COMMAND_MODULES = ["exact_khk.cli.orbit", "exact_khk.cli.certify", "exact_khk.cli.study",
                   "exact_khk.cli.liouville"]


# --- entry point --------------------------------------------------------------


def build_parser():
    parser = Parser(prog="exact-khk", description="Exact certification of Kahan–Hirota–Kimura maps "
                     "(Lie–Poisson family of Petrera & Suris).")
    parser.add_argument("--version", action="version", version=f"exact-khk {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
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
