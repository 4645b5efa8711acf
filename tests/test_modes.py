"""The engine's other modes of the claim registry: identities over F_P (Schwartz–Zippel, with the
degree bounds each claim states) and symbolic proofs over Q(x, eps)."""

import re

import pytest
import sympy

from exact_khk import InputError
from exact_khk.arith.cyclotomic import DEFAULT_PRIME
from exact_khk.certification.claims import X, at, function_deg, minus, step_deg
from exact_khk.certification.engine import identity_checks, symbolic_checks
from exact_khk.systems.catalogue import resolve

P = DEFAULT_PRIME

TOP = """name = "top-file"
variables = ["x", "y", "z"]
claims = ["reversibility", "integrals", "jacobian"]

[field]
x = "y*z"
y = "-2*z*x"
z = "x*y"

[integrals]
H12 = "{integral}"

[defaults]
x0 = ["1", "2", "3"]
eps = "1/10"
"""
#: the Hirota–Kimura integral (a2 x1^2 - a1 x2^2)/(1 - eps^2 a1 a2 x3^2) for a = (1, -2, 1), and a wrong one
RIGHT, WRONG = "(-2*x**2 - y**2)/(1 + 2*eps**2*z**2)", "(-2*x**2 - y**2)/(1 + 3*eps**2*z**2)"


def _file(tmp_path, integral):
    path = tmp_path / "top.toml"
    path.write_text(TOP.format(integral=integral))
    return resolve(str(path))


def _bound_of(evidence):
    """(stated failure bound, d, S, D1, k) parsed from an identity record's evidence."""
    m = re.search(r"failure bound <= ([0-9.e+-]+); (\d+) random points .* degree <= (\d+) in \(x, eps\).*"
                  r"S = (\d+) checks, D1 = (\d+)", evidence)
    return float(m.group(1)), int(m.group(3)), int(m.group(4)), int(m.group(5)), int(m.group(2))


@pytest.mark.parametrize("system", ["euler-top", "file"])
def test_identity_mode_is_valid_with_its_bound_stated(system, tmp_path):
    s = resolve(system) if system != "file" else _file(tmp_path, RIGHT)
    recs = identity_checks(s, trials=2, seed=3)
    assert recs and all(r.passed for r in recs) and all(r.name.startswith("identity: ") for r in recs)
    claims = [r for r in recs if r.expected]
    assert any(not r.expected and r.applicable for r in recs)
    for r in claims:
        bound, d, S, D1, k = _bound_of(r.evidence)
        assert k == 2 and d > 0 and S == len(claims)
        assert f"{bound:.4g}" == f"{(d / (P - S * D1 - 1)) ** k:.4g}" and bound < 1e-30
    for r in recs:
        if not r.expected:
            assert r.holds is False and r.evidence.startswith(f"exact refutation over F_{P}")


def test_a_wrong_integral_is_refuted_in_both_modes(tmp_path):
    s = _file(tmp_path, WRONG)
    bad = {r.name: r for r in identity_checks(s, trials=2)}["identity: integral H12 conserved by Phi_f"]
    assert bad.holds is False and bad.residual != "0" and bad.evidence.startswith("exact refutation over F_")
    bad = {r.name: r for r in symbolic_checks(s)}["proof: integral H12 conserved by Phi_f"]
    assert bad.holds is False and "eps" in bad.residual and bad.evidence.startswith("symbolic disproof")
    good = {r.name: r for r in symbolic_checks(_file(tmp_path, RIGHT))}["proof: integral H12 conserved by Phi_f"]
    assert good.holds is True and good.evidence == "symbolic proof: identity in Q(x0, x1, x2, eps)"


def test_symbolic_mode_proves_the_euler_top():
    recs = symbolic_checks(resolve("euler-top"))
    assert all(r.passed for r in recs)
    names = [r.name for r in recs]
    assert "proof: Poisson map Phi_f" in names and "proof: integral H31 conserved by Phi_f" in names
    assert all(r.evidence.startswith("symbolic disproof") for r in recs if not r.expected)


def test_symbolic_mode_is_refused_beyond_its_dimension_at_once():
    with pytest.raises(InputError, match="dimension 4"):
        symbolic_checks(resolve("lagrange-top"), progress=lambda name: pytest.fail(f"a check started: {name}"))


def test_identity_mode_needs_a_prime_field_and_regular_draws():
    with pytest.raises(InputError, match="gf:P"):
        identity_checks(resolve("euler-top"), "cyclo:3")
    with pytest.raises(InputError, match="trials"):
        identity_checks(resolve("euler-top"), "gf:5", trials=50, max_draws=5)


def test_a_check_with_no_degree_bound_is_not_available_never_holding(monkeypatch):
    """A claim that states no bound is listed as not available (undecided), not dropped."""
    from exact_khk.certification import claims

    monkeypatch.setattr(claims, "tensor_deg", lambda P: None)
    recs = {r.name: r for r in identity_checks(resolve("euler-top"), trials=1)}
    r = recs["identity: Poisson map Phi_f"]
    assert r.holds is None and r.evidence.startswith("not available in the identity mode")


def _sympy_step(f, xs, eps):
    """The Kahan step x~ = x + 2 eps (I - eps f'(x))^-1 f(x) in SymPy, from the field's formulas."""
    J = sympy.Matrix(f).jacobian(xs)
    A = sympy.eye(len(xs)) - eps * J
    return [sympy.cancel(t) for t in sympy.Matrix(xs) + 2 * eps * A.LUsolve(sympy.Matrix(f))]


def _degrees(expr, gens):
    num, den = sympy.fraction(sympy.cancel(sympy.together(expr)))
    return sympy.Poly(num, *gens).total_degree(), sympy.Poly(den, *gens).total_degree()


def test_degree_bounds_are_at_least_sympys_actual_degrees():
    """For the Euler top (N = 3): the step and the residual I(Phi(x)) - I(x) of a function that is
    not conserved (I = x^2 + y^2), computed by SymPy from the formulas, have degrees at most the
    stated bounds (the step's checked against the project's at a point)."""
    x, y, z, e = gens = sympy.symbols("x y z eps")
    f = [y * z, -2 * z * x, x * y]
    step = _sympy_step(f, [x, y, z], e)
    assert [t.subs({x: 1, y: 2, z: 3, e: sympy.Rational(1, 10)}) for t in step] == _exact_step()
    bound = step_deg(3)
    for t in step:
        a, b = _degrees(t, gens)
        assert a <= bound.num and b <= bound.den
    I = x ** 2 + y ** 2  # not conserved: a nonzero residual whose degree the bound must cover
    residual = I.subs({x: step[0], y: step[1], z: step[2]}, simultaneous=True) - I
    a, _ = _degrees(residual, gens)
    d = minus(at(function_deg(_poly_function("x**2 + y**2")), bound), function_deg(_poly_function("x**2 + y**2")))
    assert 0 < a <= d.num, (a, d)


def _exact_step():
    from exact_khk import KahanMap

    return [sympy.Rational(str(t)) for t in KahanMap(_top_field(), "1/10", "fraction").step([1, 2, 3])]


def _top_field():
    from exact_khk.systems.expressions import ExpressionSystem

    return ExpressionSystem.from_expressions(["x", "y", "z"], field={"x": "y*z", "y": "-2*z*x", "z": "x*y"},
                                             x0=["1", "2", "3"], eps="1/10").field("f")


def _poly_function(text):
    from exact_khk.systems.expressions import ExpressionSystem

    s = ExpressionSystem.from_expressions(["x", "y", "z"], field={"x": "y*z", "y": "-2*z*x", "z": "x*y"},
                                          x0=["1", "2", "3"], eps="1/10", integrals={"I": text})
    return s.integrals()["I"]


def test_the_degree_rules_at_a_point():
    """A step at x is (2N + 1, 2N) (Cramer), and a function evaluated at x is itself."""
    assert step_deg(3)[:2] == (7, 6) and at(function_deg(_poly_function("x*y")), X)[:2] == (2, 0)


def test_cli_certify_identities_and_prove_for_a_catalogue_system(capsys):
    from exact_khk.cli.main import main

    assert main(["certify", "--system", "euler-top", "--steps", "3", "--identities"]) == 0
    out = capsys.readouterr().out
    assert "identity: integral H12 conserved by Phi_f" in out and "VALID" in out
    assert main(["certify", "--system", "euler-top", "--steps", "3", "--prove"]) == 0
    out = capsys.readouterr().out
    assert "proof: Poisson map Phi_f" in out and "symbolic proof" in out and "VALID" in out


def test_a_prime_too_small_for_a_bound_below_one_leaves_the_claims_undecided():
    """Over F_101 the Euler top's bounds exceed 1: zero residuals prove nothing, so the claims are
    undecided (None), never holding; the controls still fail exactly (a nonzero residual refutes)."""
    recs = identity_checks(resolve("euler-top"), "gf:101", trials=2, max_draws=200)
    claims = [r for r in recs if r.expected and not r.name.startswith("identity: rank")]
    assert claims and all(r.holds is None for r in claims)
    assert all("bound <= 1;" in r.evidence or "not available" in r.evidence for r in claims)
    assert any(r.holds is False for r in recs if not r.expected)
    big = identity_checks(resolve("euler-top"), trials=2)
    assert all(r.holds is True for r in big if r.expected)
