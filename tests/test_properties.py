"""Hypothesis properties of the Kahan map, exact (python-flint)."""

from fractions import Fraction

import sympy as sp
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from exact_khk import KahanMap, LiePoissonSystem, SingularStepError, get_arith

rationals = st.fractions(min_value=-5, max_value=5, max_denominator=7)
nonzero = rationals.filter(lambda q: q != 0)


@st.composite
def setups(draw):
    n = draw(st.integers(2, 4))
    seed = draw(st.integers(0, 10_000))
    kind = draw(st.sampled_from(["f", "g", "control"]))
    x = [draw(rationals) for _ in range(2 * n)]
    return LiePoissonSystem.random(n, seed), kind, x


def _step(system, kind, x, eps):
    phi = KahanMap(system.field(kind), eps, "flint")
    try:
        return phi, phi.step(x)
    except SingularStepError:
        assume(False)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(setups(), nonzero, nonzero)
def test_homogeneity(setup, lam, eps):
    """Φ(λx, ε) = λ Φ(x, λε)."""
    system, kind, x = setup
    phi, y = _step(system, kind, [lam * t for t in x], eps)
    _, z = _step(system, kind, x, lam * eps)
    assert y == tuple(phi.arith(lam) * t for t in z)


def _critical(system, kind, y, eps):
    """det(I + εf'(y)) = 0 (SymPy): with y = Φ(x), det dΦ(x) = 0 (dΦ(x) =
    (I − εf'(x))⁻¹(I + εf'(y))), i.e. x lies on the hypersurface Φ contracts."""
    fld = system.field(kind)
    J = sp.Matrix(fld.jacobian(get_arith("fraction"), [Fraction(str(t)) for t in y])).applyfunc(sp.Rational)
    return (sp.eye(fld.dim) + sp.Rational(eps.numerator, eps.denominator) * J).det() == 0


# found by hypothesis: x on the critical set of Φ, so Φ⁻¹ is undefined at Φ(x)
@example(setup=(LiePoissonSystem.from_vectors("1,3", "-1,-3", "2,-3"), "f",
                [Fraction(-3, 2), Fraction(-8, 3), Fraction(-3), Fraction(-8, 3)]), eps=Fraction(-3, 2))
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(setups(), nonzero)
def test_reversibility(setup, eps):
    """Φ(Φ(x, ε), −ε) = x wherever the inverse step is defined, and it is undefined
    exactly where det(I + εf'(Φ(x))) = 0 (checked with SymPy both ways)."""
    system, kind, x = setup
    phi, y = _step(system, kind, x, eps)
    try:
        back = phi.inverse(y)
    except SingularStepError:
        assert _critical(system, kind, y, eps), f"inverse step singular at Φ({x}) for eps={eps}"
        return
    assert back == tuple(phi.arith(t) for t in x)
    assert not _critical(system, kind, y, eps)


@settings(max_examples=30, deadline=None)
@given(setups(), nonzero)
def test_fixed_point_form(setup, eps):
    """x̃ = (I + ε f'(x̃)) x (the equivalent form of the step, docs/conventions.md)."""
    system, kind, x = setup
    phi, y = _step(system, kind, x, eps)
    ar = phi.arith
    xs = [ar(t) for t in x]
    Jy = phi.field.jacobian(ar, y)
    e = ar(Fraction(eps))
    assert list(y) == [xs[i] + e * sum(Jy[i][j] * xs[j] for j in range(len(xs))) for i in range(len(xs))]


tall = st.fractions(min_value=-10 ** 30, max_value=10 ** 30, max_denominator=10 ** 30)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(setups(), st.lists(tall, min_size=8, max_size=8), nonzero)
def test_structured_step_equals_dense_step_at_tall_points(setup, coords, eps):
    """The structured step (precision hint, reconstruction, Cramer's rule down the tower for small answers) gives the
    dense step's rational point, also at points with 100-bit entries."""
    system, kind, _ = setup
    x = coords[:2 * system.n]
    fld = system.field(kind)
    dense = KahanMap(fld, eps, "flint", method="dense")
    fast = KahanMap(fld, eps, "flint", method="structured")
    try:
        y = dense.step(x)
    except SingularStepError:
        try:
            fast.step(x)
        except SingularStepError:
            return  # both agree the step is undefined
        raise AssertionError("structured step defined where the dense one is singular")
    assert fast.step(x) == y
