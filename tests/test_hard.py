"""Hard cases: certified singular step sizes, warnings near them, the catalogue."""

import warnings
from fractions import Fraction

import pytest
import sympy

from exact_khk import KahanMap, NearSingularWarning, SingularStepError
from exact_khk.cli.main import main
from exact_khk.studies.hard import (HardCase, catalogue, cell, classify, det_polynomial, markdown_table, run_case,
                            run_catalogue, singular_step_sizes)
from exact_khk.studies.scaling import ArithRun, StepRow
from exact_khk.systems.lie_poisson.system import LiePoissonSystem

S2 = LiePoissonSystem.from_vectors("1,2", "0,1", "3,1")
X2 = ["1", "2", "-1", "1/2"]
E = sympy.Symbol("eps")


def independent_det(system, x):
    """det(I - eps f'(x)) from the formula of docs/conventions.md, f'(x) = J(x) Hs + [J(e_0) y, ..., J(e_{n-1}) y, 0...],
    y = Hs x, in SymPy matrices (not the library's Jacobian)."""
    n, N = system.n, system.dim
    x = sympy.Matrix([sympy.Rational(t) for t in x])
    Hs = sympy.Matrix(system.hessian).applyfunc(lambda q: sympy.Rational(q.numerator, q.denominator))

    def J(v):
        X = sympy.Matrix(n, n, lambda i, j: v[(i + j) % n])
        return sympy.BlockMatrix([[sympy.zeros(n), X], [-X, sympy.zeros(n)]]).as_explicit()

    y = Hs * x
    cols = [J(sympy.Matrix([int(i == k) for i in range(N)])) * y for k in range(n)]
    D = sympy.Matrix.hstack(*cols, sympy.zeros(N, N - n))
    return sympy.Poly((sympy.eye(N) - E * (J(x) * Hs + D)).det(), E)


def test_det_polynomial_matches_independent_route():
    assert det_polynomial(S2.field("f"), X2).as_expr().equals(independent_det(S2, X2).as_expr())


def test_singular_step_sizes_are_certified():
    p = independent_det(S2, X2)
    roots = singular_step_sizes(S2.field("f"), X2, width=Fraction(1, 10 ** 40))
    assert len(roots) == 2
    for r in roots:
        assert 0 < r.hi - r.lo <= Fraction(1, 10 ** 40)
        lo, hi = sympy.Rational(r.lo.numerator, r.lo.denominator), sympy.Rational(r.hi.numerator, r.hi.denominator)
        assert p.eval(lo) * p.eval(hi) < 0                   # a sign change: a root inside
    # by hand: 6 eps^2 - 2 eps - 1 divides p; its roots are (1 ± sqrt 7)/6
    assert sympy.rem(p, sympy.Poly(6 * E ** 2 - 2 * E - 1, E)).is_zero
    big = roots[-1]
    assert (6 * big.lo - 1) ** 2 < 7 < (6 * big.hi - 1) ** 2


def test_rational_root_is_exactly_singular():
    x0 = ["-2", "-2", "-2", "1"]
    assert independent_det(S2, x0).eval(sympy.Rational(-1, 6)) == 0
    roots = singular_step_sizes(S2.field("f"), x0)
    assert any(r.exact and r.lo == Fraction(-1, 6) for r in roots)
    with pytest.raises(SingularStepError):
        KahanMap(S2.field("f"), "-1/6", "flint").step(x0)


def _near(d):
    root = singular_step_sizes(S2.field("f"), X2)[-1]
    return root.mid + Fraction(1, 10 ** d)


def test_float_warns_near_root_with_condition():
    with pytest.warns(NearSingularWarning) as rec:
        KahanMap(S2.field("f"), _near(10), "float").step(X2)
    cond = rec[0].message.condition
    assert cond >= 2.0 ** 26.5                               # the policy's threshold for 53 bits
    # negative control: far from the root the same step is silent (warnings are errors here)
    KahanMap(S2.field("f"), _near(3), "float").step(X2)
    # even closer: float cannot resolve eps, and refuses with a condition estimate
    with pytest.raises(SingularStepError) as exc:
        KahanMap(S2.field("f"), _near(20), "float").step(X2)
    assert exc.value.condition is not None and exc.value.condition * 2.0 ** -53 >= 1


def test_run_case_near_root():
    case = next(c for c in catalogue(long_steps=5) if c.name == "near-root 1e-20")
    r = run_case(case, ["float", "mp:113", "mp:256", "ball:512"], digits=10)
    out = {o.arith: o for o in r.outcomes}
    assert r.exact_status == "ok"
    assert out["float"].status == "singular" and out["float"].flagged
    assert out["mp:113"].status == "warned" and out["mp:113"].condition > 1e20
    assert out["mp:256"].status == "ok" and out["mp:256"].error_log10 < -40
    assert out["ball:512"].encloses is True
    assert not any(o.silent_failure for o in r.outcomes)
    # 10 digits need more than float's 53 bits here, and mp:256 sufficed
    assert 53 < r.bits_needed <= 256


def test_a_point_beyond_an_arithmetic_is_its_cell_not_the_end_of_the_run():
    """x0 beyond float64 (2^3321): the float column says OUT OF RANGE with the reason, flagged,
    and the other arithmetics still run (the run used to stop with the float error)."""
    s = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3")
    case = HardCase("huge", "a coordinate of 10^1000", s, (Fraction(10) ** 1000, 1, 2, -1), Fraction(1, 10), 2)
    r = run_case(case, ["float", "mp:113", "ball:128"], precision=False)
    out = {o.arith: o for o in r.outcomes}
    assert out["float"].status == "unrepresentable" and out["float"].flagged and not out["float"].silent_failure
    assert "too large for float64" in out["float"].message and "2^3321" in out["float"].message
    assert cell(out["float"]) == "OUT OF RANGE"
    assert out["mp:113"].status != "unrepresentable" and out["ball:128"].status != "unrepresentable"


def test_a_point_too_high_for_the_root_isolation_is_refused_at_once():
    from exact_khk.errors import InputError
    from exact_khk.studies.hard import HARD_MAX_X0_BITS, system_cases

    s = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3")
    with pytest.raises(InputError, match=rf"x0: a point of {HARD_MAX_X0_BITS + 1} bits is beyond"):
        system_cases(s, x0=(2 ** HARD_MAX_X0_BITS, 1, 2, -1), long_steps=2)
    assert system_cases(s, x0=(2 ** 100, 1, 2, -1), long_steps=2, distances=(3,))  # below it: built


def test_classify_detects_silent_failure():
    row = StepRow("float", 1, -3.0)
    run = ArithRun("float", 53, "ok", 1, None, "", 1e-5, -3.0, 10.0, None, None, None, None, None, (row,))
    assert classify(run) == (False, True)                    # 3 digits, no flag: silent
    good = ArithRun("float", 53, "ok", 1, None, "", 1e-5, -15.0, 50.0, None, None, None, None, None,
                    (StepRow("float", 1, -15.0),))
    assert classify(good) == (False, False)
    assert classify(good, exact_failed_step=1) == (False, True)   # a number where det = 0
    warned = ArithRun("float", 53, "warned", 1, None, "", 1e-5, -3.0, 10.0, None, None, None, None, 1e12, (row,))
    assert classify(warned) == (True, False)


def test_near_undefined_case_reaches_the_singular_set():
    case = next(c for c in catalogue(long_steps=5) if c.name == "near undefined point")
    phi = KahanMap(case.system.field("f"), case.eps, "flint")
    x3 = phi.orbit(case.x0, 3)[-1]
    p = det_polynomial(case.system.field("f"), [Fraction(int(t.p), int(t.q)) for t in x3])
    val = abs(p.eval(sympy.Rational(case.eps.numerator, case.eps.denominator)))
    assert 0 < val < sympy.Rational(1, 10 ** 9)               # close to det = 0, not on it


def test_quick_catalogue_no_silent_failures(capsys):
    cases = catalogue(long_steps=20, distances=(3, 15))
    with warnings.catch_warnings():
        warnings.simplefilter("error")                       # the runner must catch its warnings
        results = run_catalogue(cases, ["float", "mp:113", "ball:128"], precision=False, progress=False)
    assert [r.case.name for r in results] == [c.name for c in cases]
    for r in results:
        assert not any(o.silent_failure for o in r.outcomes), r.case.name
        if r.exact_status == "singular":                     # nobody returns a number there
            assert all(o.status in ("singular", "undecided") for o in r.outcomes)
    table = markdown_table(results)
    assert table.count("\n") == len(results) + 1 and "UNFLAGGED" not in table


def test_cli_hard(tmp_path, capsys):
    rc = main(["hard", "--only", "singular", "--markdown", "--quiet", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 0 and out.count("SINGULAR (det = 0)") == 2
    assert (tmp_path / "hard_cases.json").exists() and (tmp_path / "hard_cases.md").exists()
    assert main(["hard", "--only", "no-such-case", "--quiet"]) == 2
    assert main(["hard", "--ariths", "fraction", "--quiet"]) == 2


@pytest.mark.slow
def test_full_catalogue():
    results = run_catalogue(progress=False)
    assert not any(o.silent_failure for r in results for o in r.outcomes)
