"""Start-up stays cheap: structural checks (which modules a command imports), never timings.

Timings are measured by scripts/bench_startup.py (docs/benchmarks.md, "Start-up and set-up").
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import exact_khk
from exact_khk.cli import main as cli_main

#: libraries that no command line start-up needs (each costs 30 ms to 1 s to import)
HEAVY = ("sympy", "mpmath", "numpy", "matplotlib", "distributed", "dask", "gmpy2", "tqdm")


def _imported_after(code: str) -> list[str]:
    """The heavy modules (and exact_khk modules) in sys.modules after running ``code`` in a fresh interpreter."""
    probe = (f"import sys\n{code}\n"
             "import json\n"
             "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in "
             f"{HEAVY!r} + ('flint',) or m.startswith('exact_khk'))))")
    root = str(Path(exact_khk.__file__).resolve().parent.parent)  # the tree under test, not an installed copy
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([root] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    res = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, env=env,
                         cwd=root)
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout.strip().splitlines()[-1])


def _heavy(mods):
    return sorted({m.split(".")[0] for m in mods} & set(HEAVY))


def test_import_cli_main_imports_no_heavy_library():
    mods = _imported_after("import exact_khk.cli.main")
    assert _heavy(mods) == [], mods
    assert not any(m.startswith("exact_khk.certification") or m.startswith("exact_khk.studies") for m in mods), mods


def test_import_exact_khk_is_lazy():
    mods = _imported_after("import exact_khk")
    assert mods == ["exact_khk"], mods


def test_help_imports_no_command_module():
    mods = _imported_after("from exact_khk.cli.main import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n"
                           "    pass")
    assert _heavy(mods) == [] and "flint" not in mods, mods
    assert not any(m in mods for m, _ in cli_main.COMMANDS.values()), mods


@pytest.mark.parametrize("argv, needs", [(["orbit", "--steps", "1"], []), (["certify", "--steps", "1"], []),
                                         (["integrals"], []),
                                         (["orbit", "--steps", "1", "--arith", "float"], ["numpy"])])
def test_commands_import_only_what_they_use(argv, needs):
    """Exact commands import no heavy library; the float step is numpy's LAPACK solve."""
    mods = _imported_after(f"from exact_khk.cli.main import main\nassert main({argv!r}) == 0")
    assert _heavy(mods) == needs, mods
    assert "exact_khk.cli.study" not in mods and "exact_khk.cli.sweep" not in mods, mods


def test_catalogue_systems_and_their_kahan_maps_import_no_sympy():
    """Reading a system file (the safe parser's exact arithmetic is flint's fmpq_mpoly) and
    stepping its Kahan map import no heavy library: every command that takes --system NAME."""
    mods = _imported_after("from exact_khk.systems.catalogue import names, resolve\n"
                           "from exact_khk.kahan.map import KahanMap\n"
                           "for name in names():\n"
                           "    s = resolve(name)\n"
                           "    KahanMap(s.field('f'), '1/10', 'flint').step(s.default_x0)\n"
                           "import exact_khk.systems.real_expressions")
    assert "exact_khk.systems.expressions" in mods and "exact_khk.systems.real_expressions" in mods, mods
    assert _heavy(mods) == [], mods


def test_mp_imports_mpmath_when_asked():
    mods = _imported_after("from exact_khk.arith import get_arith\nget_arith('mp:64')")
    assert "mpmath" in mods


def test_deferred_arithmetics_are_known_by_name():
    """ball:P, cyclo:N and gf:P are registered without importing their modules."""
    code = ("from exact_khk.arith import arith_names, get_arith\n"
            "assert arith_names() == ['flint', 'float', 'fraction', 'gmpy2', 'ball:P', 'cyclo:N', 'gf:P', 'mp:P']\n"
            "assert [get_arith(n).name for n in ('ball:64', 'cyclo:3', 'gf:1000003')] == "
            "['ball:64', 'cyclo:3', 'gf:1000003']")
    assert "exact_khk.arith.cyclotomic" in _imported_after(code)


def test_every_public_name_imports():
    for name in exact_khk.__all__:
        assert getattr(exact_khk, name) is not None, name
    assert set(exact_khk.__all__) - {"__version__"} == set(exact_khk._WHERE)
    assert set(exact_khk.__all__) <= set(dir(exact_khk))
    ns = {}
    exec("from exact_khk import *", ns)
    assert set(exact_khk.__all__) <= set(ns)
    with pytest.raises(AttributeError):
        exact_khk.no_such_name  # noqa: B018


def test_stub_help_matches_the_commands():
    """The one-line help of each command in cli.main.COMMANDS is the one its module registers,
    in the same order, and the stub parser of ``--help`` lists the same commands."""
    def listing(parser):
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        return [(a.dest, a.help) for a in sub._choices_actions]

    full = listing(cli_main.build_parser())
    assert full == [(name, help) for name, (_, help) in cli_main.COMMANDS.items()]
    assert listing(cli_main.build_parser([])) == full
    assert cli_main.build_parser([]).format_help() == cli_main.build_parser().format_help()


def test_one_command_parser_is_the_full_one():
    """The parser built for one command parses its options as the full parser does."""
    for name in cli_main.COMMANDS:
        one = cli_main.build_parser([name])
        full = cli_main.build_parser()
        sub_one = next(a for a in one._actions if isinstance(a, argparse._SubParsersAction)).choices[name]
        sub_full = next(a for a in full._actions if isinstance(a, argparse._SubParsersAction)).choices[name]
        assert sub_one.format_help() == sub_full.format_help(), name
