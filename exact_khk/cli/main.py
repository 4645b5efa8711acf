"""Command-line interface: ``exact-khk <command> [options]``.

Exit status: 0 success; 1 a certification failed (``certify``); 2 malformed
input or a request beyond a documented limit (one-line message naming the
argument and the limit); 3 a singular Kahan step (one-line message naming the
step, x and eps), an integral evaluated at its pole, or a floating evaluation
with no trustworthy bit (overflow, condition estimate κ·2^-p ≥ 1); 4
inconclusive; 5 an output that cannot be written, a resource exhausted or a
required library not installed; 70 an internal error (a bug: please report); 130 interrupted (Ctrl-C).

Each command lives in a module with ``register(subparsers)``; :data:`COMMANDS`
names the module and one-line help of each.  A run imports only the module of
its command (``exact-khk --help`` none): the others get a stub parser with
their one-line help, so that start-up does not pay for SymPy, mpmath, numpy,
matplotlib or the certification code of commands that do not run.
"""

from __future__ import annotations

import argparse
import importlib
import re
import sys
import warnings

from exact_khk import __version__
from exact_khk.cli.options import Parser
from exact_khk.errors import (InputError, NumericalError, OutputError, PoleError, SingularStepError,
                              UndecidedError)

#: command name → (module that registers it, its one-line help as the module gives it;
#: tests/test_startup.py checks that the two agree), in the order of ``--help``
COMMANDS = {
    "orbit": ("exact_khk.cli.orbit", "iterate a Kahan map and print the orbit"),
    "certify": ("exact_khk.cli.certify", "certify integrals, commutation, reversibility, Poisson structure, "
                "involution and rank on an orbit, with negative controls"),
    "integrals": ("exact_khk.cli.certify", "print H~ and every K~ at a point"),
    "verify": ("exact_khk.cli.verify", "re-derive every record of a saved certificate (orbit, claims, controls, "
               "status) by a separate minimal exact code path"),
    "systems": ("exact_khk.cli.systems", "list the catalogue of classic KHK systems (use one with --system NAME)"),
    "degrees": ("exact_khk.cli.diagnostics", "degree growth of the iterates of a Kahan map, its recurrence and "
                "dynamical degree"),
    "find-integrals": ("exact_khk.cli.diagnostics", "discover conserved rational functions from orbits (HK bases)"),
    "find-measure": ("exact_khk.cli.discover", "discover invariant measures of a Kahan map (discrete Darboux polynomials and their cofactors)"),
    "find-poisson": ("exact_khk.cli.discover", "discover Poisson tensors preserved by a Kahan map, with their Casimirs"),
    "classify": ("exact_khk.cli.classify", "integrable, non-integrable or undetermined: a verdict on a Kahan map "
                 "with its evidence"),
    "atlas": ("exact_khk.cli.atlas", "classify every catalogue system (and a folder's system files) as a sweep; write docs/atlas.md"),
    "sweep": ("exact_khk.cli.sweep", "run one task over many systems, points and step sizes (locally or on Dask)"),
    "scale": ("exact_khk.cli.study", "compare floating and ball orbits with the exact orbit, step by step"),
    "enclose": ("exact_khk.cli.study", "certified enclosure of an orbit (naive balls and Lohner), real inputs"),
    "hard": ("exact_khk.cli.study", "run the catalogue of hard cases (near-singular steps, ...)"),
    "liouville": ("exact_khk.cli.liouville", "certify complete integrability (all involutions)"),
    "prove": ("exact_khk.cli.liouville", "symbolic proofs of every claim for n = 2 (seconds)"),
}
COMMAND_MODULES = list(dict.fromkeys(module for module, _ in COMMANDS.values()))


# --- entry point --------------------------------------------------------------


def build_parser(commands=None):
    """The command-line parser.  ``commands``: the command names whose modules are
    imported and registered in full (default: all); every other command gets a
    stub with its one-line help (enough for ``exact-khk --help``)."""
    parser = Parser(prog="exact-khk", description="Exact certification of Kahan–Hirota–Kimura maps "
                    "of quadratic vector fields (system files, a catalogue of classic systems, and the "
                    "Lie–Poisson family of Petrera & Suris).")
    parser.add_argument("--version", action="version", version=f"exact-khk {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for module in COMMAND_MODULES:
        names = [name for name, (m, _) in COMMANDS.items() if m == module]
        if commands is None or any(name in commands for name in names):
            importlib.import_module(module).register(sub)
        else:
            for name in names:
                sub.add_parser(name, help=COMMANDS[name][1])
    return parser


def _command(argv):
    """The command named in ``argv`` (its first word not starting with '-'; the
    top-level parser has no option that takes a value), or None."""
    return next((tok for tok in argv if not tok.startswith("-")), None)


#: a value made of signs and commas only (sign patterns such as '--+' or '--+,-++'): never an option
_SIGNS = re.compile(r"[+\-,]+")


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
        nxt = argv[i + 1] if i + 1 < len(argv) else ""
        if tok in takes_value and nxt.startswith("-") and nxt not in takes_value \
                and (not nxt.startswith("--") or _SIGNS.fullmatch(nxt) and nxt != "--"):
            out.append(f"{tok}={argv[i + 1]}")
            i += 2
        else:
            out.append(tok)
            i += 1
    return out


#: exit status by kind of failure (documented in the README)
EXIT = {"ok": 0, "invalid": 1, "input": 2, "singular": 3, "inconclusive": 4, "output": 5,
        "internal": 70, "interrupted": 130}


def main(argv=None) -> int:
    """Run one command; every failure becomes one line on stderr and an exit status
    (:data:`EXIT`), never a traceback.  Warnings (e.g. ``NearSingularWarning``)
    are gathered and, if the command succeeds, summarised in one line on stderr
    (the first, and how many more)."""
    if hasattr(sys, "set_int_max_str_digits"):
        sys.set_int_max_str_digits(0)  # exact orbits print and parse integers of any size
    for stream in (sys.stdout, sys.stderr):  # an ASCII-only terminal gets escapes, not a crash
        if hasattr(stream, "reconfigure"):
            try:
                stream.reconfigure(errors="backslashreplace")
            except (ValueError, OSError):  # a stream that cannot be reconfigured (closed, detached)
                pass
    seen = []
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = lambda message, category, *rest, **kw: seen.append((category, message))
        code = _run(argv)
    output = sys.modules.get("exact_khk.studies.output")  # imported by the commands that create folders
    if output is not None:  # an error or Ctrl-C before anything was written there: no empty folder left
        output.settle_new_folders(failed=code not in (EXIT["ok"], EXIT["invalid"], EXIT["inconclusive"]))
    if seen and code in (EXIT["ok"], EXIT["invalid"], EXIT["inconclusive"]):
        category, message = seen[0]
        more = f" (and {len(seen) - 1} more warning(s))" if len(seen) > 1 else ""
        text = " ".join(str(message).split())
        try:
            print(f"exact-khk: warning: {category.__name__}: {text[:1000]}{more}", file=sys.stderr)
        except Exception:  # noqa: BLE001 - stderr itself may be gone
            pass
    return code


#: the import names of the required libraries (pyproject.toml's dependencies) and their pip names:
#: one missing (a source checkout run without installing) is a resource problem, not a bug
REQUIRED = {"flint": "python-flint", "gmpy2": "gmpy2", "mpmath": "mpmath", "sympy": "sympy", "numpy": "numpy",
            "matplotlib": "matplotlib", "tqdm": "tqdm"}


def _run(argv) -> int:
    args = None
    try:
        argv = list(sys.argv[1:] if argv is None else argv)
        parser = build_parser([_command(argv)])
        args = parser.parse_args(_join_values(argv, parser))
        args.argv = ["exact-khk", *argv]  # as typed (a certificate records it: options.invocation)
        if args.command is None:
            parser.print_help()
            return EXIT["input"]
        return args.func(args)
    except InputError as exc:
        return _fail("error", exc, "input")
    except NumericalError as exc:
        return _fail("numerically undefined", exc, "singular")
    except (SingularStepError, PoleError) as exc:
        kind, seed = "singular step" if isinstance(exc, SingularStepError) else "undefined", getattr(args, "seed", None)
        if seed is not None and getattr(args, "x0", None) is None:  # the point was drawn, not given
            exc = f"{exc} (x0 is the point drawn for --seed {seed}: another --seed, or --x0, starts another orbit)"
        return _fail(kind, exc, "singular")
    except UndecidedError as exc:
        return _fail("undecided", exc, "inconclusive")
    except BrokenPipeError:
        return EXIT["ok"]
    except (OutputError, OSError) as exc:
        return _fail("output", exc, "output")
    except MemoryError:
        return _fail("resource", "out of memory (choose fewer steps, a smaller n or a lower precision)", "output")
    except KeyboardInterrupt:
        return _fail("interrupted", "stopped by the user (Ctrl-C)", "interrupted")
    except RecursionError as exc:
        return _fail("resource", exc, "output")
    except ModuleNotFoundError as exc:
        missing = (exc.name or "").split(".")[0]
        if missing not in REQUIRED:
            return _fail("internal error", f"{type(exc).__name__}: {exc} (please report this)", "internal")
        return _fail("resource", f"the required library {REQUIRED[missing]} is not installed in this Python "
                                 f"({sys.executable}); install exact_khk with its dependencies: pip install .", "output")
    except SystemExit as exc:  # argparse --help/--version, or a library calling sys.exit
        return exc.code if isinstance(exc.code, int) else (EXIT["ok"] if exc.code is None else EXIT["input"])
    except Exception as exc:  # noqa: BLE001 - the one error boundary of the command line
        return _fail("internal error", f"{type(exc).__name__}: {exc} (please report this)", "internal")


def _fail(kind, exc, status) -> int:
    text = " ".join(str(exc).split()) or type(exc).__name__
    try:
        print(f"exact-khk: {kind}: {text[:2000]}", file=sys.stderr)
    except Exception:  # noqa: BLE001 - stderr itself may be gone
        pass
    return EXIT[status]


def entry_point():  # console script
    try:
        code = main()
        if sys.stdout is not None:  # None when the shell closed it (>&-): print() wrote nothing
            sys.stdout.flush()
    except KeyboardInterrupt:  # Ctrl-C between the boundary and the exit
        code = EXIT["interrupted"]
    except BrokenPipeError:
        code = EXIT["ok"]
    except OSError as exc:  # the last buffered output cannot be written (e.g. a full disk)
        code = _fail("output", exc, "output")
    sys.exit(code)


if __name__ == "__main__":
    entry_point()
