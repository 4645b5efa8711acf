"""Rough edges met by a new user (issue 43, item 5): each row failed on the old code."""

from __future__ import annotations

import json
import math
import types
from fractions import Fraction

import pytest

import exact_khk
from exact_khk import InputError, LiePoissonSystem, System, get_arith, register_arith
from exact_khk.cli.main import main


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


# --- degrees ---------------------------------------------------------------------------


def test_degrees_exact_json_is_serializable_and_agrees(capsys):
    """``--exact K --json`` exited 70 (fmpz is not JSON serializable)."""
    code, out, err = run(capsys, "degrees", "--system", "euler-top", "--steps", "6", "--exact", "3",
                         "--no-heights", "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert len(doc["exact_degrees"]) == 4 and all(type(d) is int for d in doc["exact_degrees"])
    assert doc["exact_degrees"] == doc["degrees"][:4]  # the composition over Q, a route apart from F_p


@pytest.mark.parametrize("confirm", ["1", "2"])
def test_degrees_refuses_too_few_confirmations(capsys, confirm):
    """With one confirmation the integrable cmoq-cubic's first 7 degrees were classified
    exponential, with no caveat: fewer than 3 confirmations are refused."""
    code, out, err = run(capsys, "degrees", "--system", "cmoq-cubic", "--steps", "6", "--confirm", confirm)
    assert code == 2 and not out and err.count("\n") == 1 and "--confirm" in err and "at least 3" in err


def test_the_refused_classification_was_wrong():
    """The reason for the refusal: the same 7 degrees with 1 confirmation fit a recurrence of
    exponential growth, while 21 degrees (the order-6 recurrence confirmed on as many terms as its
    order) give polynomial growth."""
    from exact_khk.diagnostics import degree_sequence
    from exact_khk.diagnostics.degrees import MIN_CONFIRM
    from exact_khk.diagnostics.recurrence import fit_recurrence

    long = degree_sequence("cmoq-cubic", steps=20, confirm=MIN_CONFIRM)
    assert long.fit.growth == "polynomial"
    short = fit_recurrence(long.degrees[:7], confirm=1)  # what --confirm 1 would have believed ...
    assert short.characteristic != long.fit.characteristic  # ... is not the recurrence of the sequence
    assert short.growth == "undetermined"  # and the order rule (as many confirmations as the order) refuses it
    assert degree_sequence("cmoq-cubic", steps=6).fit.growth == "undetermined"  # the default: no guess
    with pytest.raises(InputError, match="confirm"):
        degree_sequence("cmoq-cubic", steps=6, confirm=1)


# --- orbit with a huge step size --------------------------------------------------------


def test_orbit_abbreviates_a_huge_eps(capsys):
    """ε of 20 000 digits was printed in full (and the table's rounding cost seconds)."""
    eps = "1" + "0" * 20_000 + "/3"
    code, out, _ = run(capsys, "orbit", "--eps", eps, "--steps", "1")
    assert code == 0
    header = next(line for line in out.splitlines() if line.startswith("field"))
    assert len(header) < 300 and "3.3333333e+19999" in header and "20,001/1 digits" in header
    row = out.splitlines()[-1].split()
    assert row[0] == "1" and all(len(t) <= 20 for t in row)
    # the leading digits are those of the exact value (a Fraction recomputation)
    from exact_khk.cli.orbit import _leading

    q = Fraction(-10 ** 500 - 7, 3 * 10 ** 900)
    assert _leading(q.numerator, q.denominator) == "-3.3333333e-401"


# --- hard shows progress ---------------------------------------------------------------


def test_hard_shows_progress_on_a_terminal(capsys, monkeypatch):
    from exact_khk.cli import options

    monkeypatch.setattr(options, "_is_terminal", lambda stream: True)
    monkeypatch.setattr(options.Progress, "DELAY", 0.0)
    code, out, err = run(capsys, "hard", "--only", "long", "--long-steps", "5", "--no-precision", "--ariths", "float")
    assert code == 0 and "long" in out
    # a bar from the start (while the cases are built), then over the stages: 1 case x (exact + float)
    assert "hard: building the cases" in err and "0/2" in err and "stage" in err
    code, out, err = run(capsys, "hard", "--only", "long", "--long-steps", "5", "--no-precision", "--ariths",
                         "float", "--quiet")
    assert code == 0 and err == ""


# --- a certificate records its command line --------------------------------------------


def test_certificate_records_its_invocation(capsys, tmp_path):
    path = tmp_path / "cert.json"
    argv = ["certify", "--steps", "1", "--signs", "-++", "--eps", "1/7", "--json", str(path)]
    assert run(capsys, *argv)[0] == 0
    inv = json.loads(path.read_text())["invocation"]
    assert inv["argv"] == ["exact-khk", *argv]
    assert inv["options"]["steps"] == 1 and inv["options"]["signs"] == ["-++"] and inv["options"]["eps"] == "1/7"
    assert inv["resolved"] == {"arith": "flint", "x0": ["1", "2", "-1", "1/2", "0", "1"], "eps": "1/7", "steps": 1}
    code, out, _ = run(capsys, "verify", str(path))
    assert code == 0 and "VERIFIED" in out  # the verifier is not disturbed by the informational key


# --- API: typed errors -----------------------------------------------------------------

ARITHS = ["fraction", "gmpy2", "flint", "float", "mp:64", "ball:64", "cyclo:5", "gf:101"]


@pytest.mark.parametrize("name", ARITHS)
@pytest.mark.parametrize("value", [None, "abc", [1], object()], ids=["None", "abc", "list", "object"])
def test_convert_refuses_what_it_cannot_read(name, value):
    with pytest.raises(InputError):
        get_arith(name).convert(value)


@pytest.mark.parametrize("name", [n for n in ARITHS if get_arith(n).exact])
def test_exact_convert_refuses_nan_and_floats(name):
    for value in (float("nan"), 0.5):
        with pytest.raises(InputError):
            get_arith(name).convert(value)
    with pytest.raises(InputError, match="x0"):  # the public reading names the argument
        exact_khk.arith.to_element(get_arith(name), None, "x0")


def test_random_point_bound_is_checked():
    s = System.load("euler-top")
    for bound in (-5, 0, 1.5, True):  # 0 used to loop for ever (only the zero point)
        with pytest.raises(InputError, match="bound"):
            s.random_point(-1, bound)
    x = s.random_point(-1, 1)
    assert len(x) == s.dim and any(x) and all(abs(t) <= 1 for t in x)


def test_evaluate_refuses_a_point_of_the_wrong_length():
    f = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1").field("f")
    ar = get_arith("fraction")
    for x in ([ar.one] * 5, [ar.one] * 7, 3):
        with pytest.raises(InputError, match="6 coordinates"):
            f.evaluate(ar, x)
    assert len(f.evaluate(ar, [ar.one] * 6)) == 6


def test_register_arith_refuses_to_replace_a_known_name():
    before = get_arith("flint")
    for name in ("flint", "mp", "ball", "gf", "cyclo", "float"):
        with pytest.raises(InputError, match="already"):
            register_arith(name, lambda *a: before, parametrized=name in ("mp", "ball", "gf", "cyclo"))
    assert get_arith("flint") is before and get_arith("flint").convert(Fraction(1, 3)) == before.one / 3
    from exact_khk import arith

    try:  # a new name, then replaced on request
        register_arith("testq", arith._fraction_arith, parametrized=False)
        assert get_arith("testq").name == "fraction"
        register_arith("testq", arith.FloatArith, parametrized=False, replace=True)
        assert get_arith("testq").name == "float"  # the cached instance of the old factory is gone
    finally:
        arith._FIXED.pop("testq", None)
        arith._CACHE.pop("testq", None)
    with pytest.raises(InputError):
        register_arith("Bad Name", arith.FloatArith)


def test_package_namespace_holds_only_public_names():
    public = {n for n in vars(exact_khk) if not n.startswith("_")
              and not isinstance(vars(exact_khk)[n], types.ModuleType)}  # submodules appear once imported
    assert not {"TYPE_CHECKING", "annotations", "importlib"} & set(vars(exact_khk))
    assert public <= set(exact_khk.__all__), public - set(exact_khk.__all__)
    assert "TYPE_CHECKING" not in dir(exact_khk) and "KahanMap" in dir(exact_khk)
    assert math.isfinite(float(exact_khk.to_fraction(get_arith("flint"), "1/3")))


def test_a_missing_required_library_is_one_line_exit_5_and_another_missing_module_a_bug():
    """A source checkout run without its dependencies: one line naming the pip package (exit 5),
    not "internal error"; a missing module that is not a dependency stays an internal error (70)."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    script = ("import sys; sys.modules[{mod!r}] = None\n"
              "from exact_khk.cli.main import main\n"
              "sys.exit(main(['certify', '--steps', '2']))")
    for mod, code, text in (("flint", 5, "python-flint is not installed"),
                            ("exact_khk.certification.engine", 70, "internal error")):
        out = subprocess.run([sys.executable, "-c", script.format(mod=mod)], capture_output=True, text=True,
                             cwd=root, env={"PYTHONPATH": str(root), "PATH": ""})
        assert out.returncode == code, (mod, out.returncode, out.stderr)
        assert text in out.stderr and len(out.stderr.strip().splitlines()) == 1, out.stderr
