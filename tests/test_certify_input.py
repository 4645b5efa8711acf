"""Bad and unusual input to ``certify``, ``prove`` and ``verify``: typed errors, documented
exit statuses, inapplicable controls, and certificates that ``verify`` reads back."""

import json
import pathlib

import pytest

from exact_khk import certify
from exact_khk.certification.engine import symbolic_checks
from exact_khk.certification.verify import verify
from exact_khk.cli.main import EXIT, main
from exact_khk.errors import InputError
from exact_khk.systems.lie_poisson.system import LiePoissonSystem

CUBIC = str(pathlib.Path(__file__).parent.parent / "docs" / "examples" / "cubic.toml")


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


# --- 1. the CMOQ determinants in ball arithmetic: undecided, never SingularMatrix -------


@pytest.mark.parametrize("system, arith", [(CUBIC, "ball:2"), (CUBIC, "ball:3"), ("cmoq-cubic", "ball:3")])
def test_cmoq_check_in_low_precision_balls_is_undecided(system, arith):
    cert = certify(system, steps=3, arith=arith)
    assert cert.status == "INCONCLUSIVE"
    measure = cert.check("CMOQ invariant measure")
    assert measure.holds is None and "not evaluable" in measure.detail


def test_cmoq_check_in_low_precision_balls_exits_inconclusive(capsys):
    code, _, err = run(capsys, "certify", "--system", CUBIC, "--steps", "3", "--arith", "ball:2")
    assert code == EXIT["inconclusive"], err
    assert "internal error" not in err and "SingularMatrix" not in err


# --- 2. prove at a degenerate system: the controls are inapplicable, not failures -------


def _prove(*vectors):
    return symbolic_checks(LiePoissonSystem.from_vectors(*vectors).with_involutions(["+-", "-+"]))


def test_prove_controls_at_zero_hessian_are_inapplicable():
    """Hs = 0: every map is the identity, every point an equilibrium: each control held and is
    inapplicable, the rank of the (zero) gradients undecided, never a failure."""
    recs = {r.name: r for r in _prove("0,0", "0,0", "0,0")}
    controls = [r for r in recs.values() if not r.expected]
    assert len(controls) == 4
    for r in controls:
        assert r.holds is True and not r.applicable and r.status == "inapplicable", r
        assert r.detail.startswith("inapplicable: ") and "inapplicable" not in r.evidence
    assert recs["proof: control: commutation with non-associated field"].detail.startswith(
        "inapplicable: Hs = 0: every point is an equilibrium")
    assert all(r.passed or r.name.startswith("proof: rank") for r in recs.values())
    assert not any(r.wrong for r in recs.values())


def test_prove_at_zero_hessian_exit_status(capsys):
    code, out, err = run(capsys, "prove", "--n", "2", "--a", "0,0", "--b", "0,0", "--c", "0,0")
    assert "FAIL" not in out and out.count("\nn/a ") == 4, out
    assert code == EXIT["inconclusive"], (out, err)  # no control can fail: INCONCLUSIVE, never INVALID


# --- 3. verify reads every number syntax of system files --------------------------------


SYSTEM = """name = "numbers"
variables = ["x", "y"]
field = ["x*y - x**2", "x**2 - x*y"]
[integrals]
I = "{integral}"
[defaults]
x0 = ["1", "2"]
eps = "1/10"
"""


@pytest.mark.parametrize("integral", ["1e5*(x+y)", "2.5E3*(x+y)", "(x+y)/1e-3", "1.e+2*(x+y)",
                                      "\u0663*(x+y)", "(x+y)*\u0661\u0662.5e\u0661"])
def test_verify_reads_the_numbers_of_system_files(tmp_path, capsys, integral):
    path = tmp_path / "numbers.toml"
    path.write_text(SYSTEM.format(integral=integral), encoding="utf-8")
    cert = tmp_path / "c.json"
    code, _, err = run(capsys, "certify", "--system", str(path), "--steps", "3", "--json", str(cert), "--quiet")
    assert code == EXIT["ok"], err
    code, out, err = run(capsys, "verify", str(cert))
    assert code == EXIT["ok"] and "VERIFIED" in out, (out, err)


def test_verify_rejects_a_value_recomputed_with_a_wrong_exponent(tmp_path):
    data = certify(_system("1e5*(x+y)"), steps=2).to_json()
    assert verify(data).ok
    data["system"]["integrals"]["I"] = "1e4*(x+y)"  # the recorded values are those of 1e5*(x+y)
    assert not verify(data).ok


def test_verify_evaluator_reads_numbers_as_the_system_file_parser():
    """Exactly, with the parser's exponent limit (|e| <= 10000, at most 6 characters)."""
    from fractions import Fraction

    from exact_khk.certification.verify import _Evaluate, _Rationals

    value = lambda text: _Evaluate(text, {}, _Rationals(), "w").value  # noqa: E731
    assert value("2.5E-3") == Fraction(1, 400) and value(".5e1") == 5 and value("1e+00005") == 10 ** 5
    assert value("\u0661\u0662.5") == Fraction(25, 2)  # Arabic-Indic digits, as the parser reads them
    for text in ("1e10001", "1e0000005"):
        with pytest.raises(InputError, match="limit"):
            value(text)


def _system(integral):
    from exact_khk.systems.expressions import ExpressionSystem

    return ExpressionSystem.from_toml(SYSTEM.format(integral=integral))


# --- 4. verify: an invalid arithmetic name is malformed input, not an inexact arithmetic --


@pytest.mark.parametrize("arith, why", [("cyclo:0", "N >= 1"), ("gf:" + "1" * 50, "P"), ("gf:4", "prime"),
                                        ("cyclo:\u0663", "ASCII"), ("quad", "unknown")])
def test_verify_names_an_invalid_arithmetic(arith, why):
    data = certify(steps=1).to_json()
    with pytest.raises(InputError, match="not a valid arithmetic name") as exc:
        verify(dict(data, arith=arith))
    assert why in str(exc.value) and "inexact" not in str(exc.value)


def test_verify_cli_invalid_arithmetic_exits_2(tmp_path, capsys):
    path = tmp_path / "c.json"
    path.write_text(json.dumps(dict(certify(steps=1).to_json(), arith="cyclo:0")))
    code, _, err = run(capsys, "verify", str(path))
    assert code == EXIT["input"] and "not a valid arithmetic name" in err and "inexact" not in err, err


def test_verify_inexact_arithmetic_still_not_checkable():
    data = certify(steps=1, arith="mp:64").to_json()
    report = verify(data)
    assert not report.ok and not report.checkable and "inexact" in report.verdict()


def test_integrals_with_an_irrational_involution_names_the_option_and_the_way_out(capsys):
    """K~ of '-+-' (n = 3) lies in Q(omega): refused at once, as certify refuses it (it ended in
    a conversion error naming neither --signs nor cyclo:3), and computed in cyclo:3."""
    assert main(["integrals", "--signs", "-+-"]) == 2
    assert capsys.readouterr().err.strip() == (
        "exact-khk: error: --signs: '-+-' is not a rational involution; it needs an arithmetic containing "
        "omega = e^(2 pi i/3), e.g. --arith cyclo:3")
    assert main(["integrals", "--signs", "-+-", "--arith", "cyclo:3"]) == 0
    assert "K~[-+-] = " in capsys.readouterr().out
