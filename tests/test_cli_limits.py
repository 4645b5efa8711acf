"""Refusals up front: sizes and costs estimated before the work, bad paths and files.

A command that would run for minutes or exhaust the memory is refused at once (exit 2,
one line naming the option or file and a way out).  The commands that used to run on
are started in a subprocess with a timeout, so that the test fails instead of hanging.
"""

import json
import subprocess
import sys
from argparse import Namespace

import pytest

from exact_khk.cli.main import EXIT, main

#: seconds after which a command that was not refused is stopped and the test fails (a refusal
#: takes about a second with the interpreter's start-up; the commands it guards ran for minutes;
#: no speed is asserted)
STOP = 15


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def run_process(*argv):
    """(exit status, stderr) of ``exact-khk ARGV`` in a fresh interpreter."""
    try:
        proc = subprocess.run([sys.executable, "-m", "exact_khk", *argv], capture_output=True, text=True,
                              timeout=STOP)
    except subprocess.TimeoutExpired:
        pytest.fail(f"exact-khk {' '.join(argv)} was still running after {STOP} s: not refused up front")
    return proc.returncode, proc.stderr


def system_file(path, n, x0=False):
    """A system file of ``n`` variables whose field is 0 (with ``x0``: a [defaults] x0)."""
    names = [f"x{i}" for i in range(n)]
    text = (f'name = "big"\nvariables = [{", ".join(json.dumps(v) for v in names)}]\n'
            f'field = [{", ".join(chr(34) + "0" + chr(34) for _ in names)}]\n')
    if x0:
        text += f'[defaults]\nx0 = [{", ".join(chr(34) + "1" + chr(34) for _ in names)}]\n'
    path.write_text(text)
    return str(path)


# --- system files: the size before the default point ----------------------------------------


@pytest.mark.parametrize("command", ["orbit", "certify", "scale", "hard", "degrees"])
def test_a_large_system_file_without_x0_is_refused_before_its_default_point(tmp_path, command):
    """3000 variables and no [defaults] x0: the default point (a determinant of size N per draw)
    was searched for while the file was read, before any limit: minutes, or out of memory."""
    code, err = run_process(command, "--system", system_file(tmp_path / "big.toml", 3000))
    assert code == EXIT["input"], err
    assert "3000 variables" in err and len(err.strip().splitlines()) == 1


def test_a_system_file_beyond_max_variables_is_refused_while_read(tmp_path):
    """100 000 variables: the polynomial ring alone exhausted FLINT's memory (an abort, no message)."""
    from exact_khk.systems.expressions import MAX_VARIABLES

    code, err = run_process("orbit", "--system", system_file(tmp_path / "big.toml", MAX_VARIABLES + 1))
    assert code == EXIT["input"], err
    assert "MAX_VARIABLES" in err and "big.toml" in err


def test_the_size_refusal_of_a_system_file_names_its_variables_not_n(capsys, tmp_path):
    """A system file has no --n and no structured path: the refusal names its variables."""
    code, _, err = run(capsys, "orbit", "--system", system_file(tmp_path / "big.toml", 1001, x0=True))
    assert code == EXIT["input"]
    assert err.startswith("exact-khk: error: --system:") and "1001 variables" in err, err
    assert "--n" not in err and "--method" not in err and "n = 500" not in err, err
    code, _, err = run(capsys, "orbit", "--n", "600", "--seed", "1", "--method", "dense")  # the family: --n
    assert code == EXIT["input"] and "--n: orbit at n = 600" in err


# --- the exact reference orbit of scale and enclose --------------------------------------------


@pytest.mark.parametrize("argv", [
    ["scale", "--steps", "100000"],
    ["scale", "--steps", "100000", "--ariths", "float"],
    ["scale", "--steps", "10000000", "--ariths", "float"],
    ["enclose", "--steps", "100000", "--check-exact"],
], ids=" ".join)
def test_the_exact_reference_orbit_is_estimated_up_front(argv):
    code, err = run_process(*argv)
    assert code == EXIT["input"], err
    assert err.startswith("exact-khk: error: --steps:") and "exact reference orbit" in err and "in flint" in err


# --- liouville: the work, and a degenerate point --------------------------------------------------


@pytest.mark.parametrize("argv", [
    ["--n", "12", "--seed", "1", "--steps", "1"],
    ["--n", "9", "--seed", "1"],
    ["--n", "11", "--seed", "1", "--arith", "gf:4611686018420360881"],
], ids=" ".join)
def test_liouville_refuses_work_far_beyond_its_budget(argv):
    code, err = run_process("liouville", *argv)
    assert code == EXIT["input"], err
    assert "MAX_WORK_SECONDS" in err and "--pairs f" in err and "a smaller --n" in err, err


def test_liouville_budget_admits_the_documented_runs():
    """README: `liouville --n 7` takes about two minutes; docs/benchmarks.md: n = 8 in cyclo:8
    about four, in gf:P 23 s."""
    from exact_khk.arith import get_arith
    from exact_khk.cli.liouville import _check_work

    def check(n, arith, **kw):
        args = Namespace(**{"steps": 2, "trials": 3, "pairs": "all", "involutions": "all", **kw})
        _check_work(args, n, 2 ** n - 2, get_arith(arith))

    for n in range(2, 9):
        check(n, f"cyclo:{n}" if n > 2 else "flint")
    check(8, "gf:4611686018420360881")
    check(10, "cyclo:10", pairs="f", steps=1)


@pytest.mark.parametrize("argv", [
    ["--x0", "0,0,0,0,0,0"],
    ["--a", "0,0,0", "--b", "0,0,0", "--c", "0,0,0", "--x0", "1,2,3,4,5,6"],
], ids=" ".join)
def test_liouville_at_a_degenerate_point_is_inconclusive_as_certify(capsys, argv):
    """The controls cannot fail where J(x0) is singular or x0 is an equilibrium: inapplicable,
    not FAILED; the rank is undecided there; exit 4, as certify on the same input."""
    code, out, _ = run(capsys, "liouville", *argv, "--json")
    doc = json.loads(out)
    records = {r["name"]: r for r in doc["records"]}
    assert code == EXIT["inconclusive"] and doc["status"] == "INCONCLUSIVE" and not doc["ok"]
    controls = [r for r in doc["records"] if not r["expected"]]
    assert len(controls) == 4
    for r in controls:
        assert r["applicable"] is False and r["detail"].startswith("inapplicable:")
    assert records["rank of integral gradients A^i grad H~ (i < n)"]["holds"] is None
    assert run(capsys, "certify", *argv)[0] == code


def test_liouville_is_still_valid_on_the_built_in_system(capsys):
    code, out, _ = run(capsys, "liouville", "--steps", "1")
    assert code == EXIT["ok"] and out.rstrip().endswith("VALID")


# --- paths and files ------------------------------------------------------------------------------


@pytest.mark.parametrize("argv", [
    ["scale", "--steps", "1", "--ariths", "float", "--out", ""],
    ["enclose", "--steps", "2", "--out", ""],
    ["hard", "--only", "long", "--long-steps", "2", "--no-precision", "--out", ""],
    ["degrees", "--steps", "3", "--plot", ""],
    ["certify", "--steps", "1", "--json", ""],
    ["liouville", "--steps", "0", "--json", ""],
], ids=" ".join)
def test_an_empty_output_path_is_refused(capsys, argv):
    code, out, err = run(capsys, *argv)
    assert code == EXIT["input"] and out == "", err
    assert f"argument {argv[-2]}: expected a file or folder name, got an empty string" in err


def test_a_deeply_nested_system_file_is_refused_naming_it(capsys, tmp_path):
    path = tmp_path / "deep.toml"
    path.write_text('name = "d"\nvariables = ["x"]\nfield = ["x"]\nclaims = ' + "[" * 10000 + "]" * 10000 + "\n")
    code, _, err = run(capsys, "orbit", "--system", str(path))
    assert code == EXIT["input"] and str(path) in err and "nested too deeply" in err, err
