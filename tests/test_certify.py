"""Certificates: every claim holds, every negative control fails, exact residuals, JSON schema."""

import dataclasses
import json
from fractions import Fraction as F

import pytest
import sympy as sp

from exact_khk import (Arith, Certificate, Check, InputError, KahanMap, LiePoissonSystem,
                       SingularStepError, certify, get_arith)
from exact_khk.certification.checks import compare
from exact_khk.systems.lie_poisson.controls import non_admissible_hessian
from exact_khk.certification.lie_poisson import default_signs
from exact_khk.systems.lie_poisson.invariants import Pi
from exact_khk.systems.lie_poisson.system import DEFAULT_EPS, DEFAULT_X0, default_system, random_point
from exact_khk.testing import (assert_certificate_valid, assert_commute, assert_conserved,
                               assert_poisson_map, assert_reversible)

from .conftest import EXACT
from .test_invariants import SymModel

CONTROLS = ["control: commutation with non-associated field",
            "control: integral H~ conserved by Phi_control",
            "control: integral H~ conserved for a non-admissible Hessian",
            "control: integral H~ at a perturbed point"]


@pytest.fixture(scope="module")
def default_cert():
    return certify()


def test_default_certificate_is_valid(default_cert):
    c = default_cert
    assert isinstance(c, Certificate) and all(isinstance(k, Check) for k in c.checks)
    assert c.valid and c.verdict().startswith("VALID")
    assert (c.system.n, c.x0, c.eps, c.steps, c.arith) == (3, tuple(F(t) for t in DEFAULT_X0), DEFAULT_EPS, 20, "flint")
    assert c.signs == ("+--", "-++")
    names = [k.name for k in c.checks]
    assert len(names) == len(set(names))
    for word in ("integral", "commutation", "reversibility", "Poisson", "involution", "rank"):
        assert any(word in name for name in names), word
    for name in ["integral H~ (closed form = definition)", "integral H~ conserved by Phi_f",
                 "integral K~[-++] conserved by Phi_g[-++]", "commutation Phi_f o Phi_g[-++]",
                 "reversibility Phi_f", "Poisson map Phi_f", "Poisson tensor Pi formula",
                 "involution {H~,K~[-++]}_J", "involution {H~,K~[-++]}_Pi"]:
        assert c.check(name).holds is True and c.check(name).residual == "0"
    assert [k.name for k in c.checks if not k.expected] == CONTROLS
    for k in c.checks:
        assert k.evidence == "exact in Q" and k.arith == "flint" and k.seconds >= 0
        assert k.holds is k.expected
        assert (k.residual == "0") == k.expected or k.name.startswith("rank")
    assert c.check("rank of integral gradients (H~, K~[+--], K~[-++])").residual == "rank 2"
    assert c.check("rank of integral gradients A^i grad H~ (i < n)").residual == "rank 3"
    assert c.height_bits > 100  # heights grow along the orbit
    assert_certificate_valid(c)


def test_control_residuals_equal_independent_sympy_values():
    """The exact residuals of the four controls, recomputed with the SymPy model."""
    s = default_system()
    m = SymModel.of(s)
    x0 = sp.Matrix([sp.Rational(t) for t in DEFAULT_X0])
    e = sp.Rational(1, 10)
    c = certify(steps=3, signs=["-++"])
    C = m.A * m.Hs  # control Hessian for n = 3
    diff = m.step(m.Hs, m.step(C, x0, e), e) - m.step(C, m.step(m.Hs, x0, e), e)
    first = next(d for d in diff if d != 0)
    assert sp.Rational(c.check(CONTROLS[0]).residual) == first
    assert sp.Rational(c.check(CONTROLS[1]).residual) == m.htilde(m.Hs, m.step(C, x0, e), e) - m.htilde(m.Hs, x0, e)
    M = sp.Matrix([[sp.Rational(t.numerator, t.denominator) for t in r] for r in non_admissible_hessian(s)])
    assert M - m.Hs == sp.Matrix(6, 6, lambda i, j: int(i == j == 0))
    assert sp.Rational(c.check(CONTROLS[2]).residual) == m.htilde(M, m.step(M, x0, e), e) - m.htilde(M, x0, e)
    xp = x0.copy()
    xp[5] = x0[5] * (1 + sp.Rational(1, 2 ** 60))
    assert sp.Rational(c.check(CONTROLS[3]).residual) == m.htilde(m.Hs, xp, e) - m.htilde(m.Hs, x0, e)


@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_certificates_n2_to_5(n):
    s = LiePoissonSystem.random(n, seed=n)
    c = certify(s, random_point(n, n), "1/9", steps=4)
    assert_certificate_valid(c)
    assert c.signs == tuple(default_signs(n))
    assert all(k.holds is False for k in c.checks if not k.expected)
    divisors = sum(1 for d in range(1, n + 1) if n % d == 0)
    assert c.checks[-6].name.startswith("rank") and c.checks[-6].residual == f"rank {divisors}"
    assert c.checks[-5].residual == f"rank {n}"
    if n == 2:  # B_1 = A ('+-') and B_0 = -A ('-+')
        assert c.signs == ("+-", "-+")
        assert s.involution("+-") == s.shift


def test_exact_arithmetics_give_identical_certificates():
    certs = [certify(steps=3, arith=name) for name in EXACT]
    assert len(certs) == 3
    for c in certs:
        assert c.valid
        assert [(k.name, k.holds, k.residual) for k in c.checks] == \
            [(k.name, k.holds, k.residual) for k in certs[0].checks]


@pytest.mark.parametrize("arith", ["cyclo:3", "gf:1000003"])
def test_all_involutions_in_an_arithmetic_with_omega(arith):
    """With ω = e^{2πi/3} available, all 6 involutions ≠ ±I are certified and the
    integrals' gradients reach the full rank n = 3 (over Q only 2)."""
    c = certify(steps=2, arith=arith)
    assert_certificate_valid(c)
    assert c.signs == ("++-", "+-+", "+--", "-++", "-+-", "--+")
    assert c.check("rank of integral gradients (H~, " + ", ".join(f"K~[{s}]" for s in c.signs) + ")").residual \
        == "rank 3"
    assert c.check("commutation Phi_f o Phi_g[+-+]").holds is True
    with pytest.raises(InputError, match="cyclo:3"):
        certify(steps=2, signs=["+-+"])  # not expressible over Q


class QEl:
    """A rational wrapped so that it has no to_fraction path: stands for a Q(ζ) element."""

    __slots__ = ("v",)

    def __init__(self, v):
        self.v = v

    def _o(self, o):
        return o.v if isinstance(o, QEl) else o

    def __add__(self, o): return QEl(self.v + self._o(o))
    __radd__ = __add__
    def __sub__(self, o): return QEl(self.v - self._o(o))
    def __rsub__(self, o): return QEl(self._o(o) - self.v)
    def __mul__(self, o): return QEl(self.v * self._o(o))
    __rmul__ = __mul__
    def __truediv__(self, o): return QEl(self.v / self._o(o))
    def __rtruediv__(self, o): return QEl(self._o(o) / self.v)
    def __neg__(self): return QEl(-self.v)
    def __eq__(self, o): return self.v == self._o(o)
    __hash__ = None


class OpaqueExact(Arith):
    name, exact = "opaque-exact", True
    zero, one = QEl(F(0)), QEl(F(1))

    def convert(self, value):
        return QEl(F(value))

    def format(self, e):
        return f"<{e.v}>"


def test_certify_needs_no_to_fraction():
    """A new exact context with only + - * / == (like Q(zeta)) works unchanged."""
    ar = OpaqueExact()
    with pytest.raises(TypeError):
        ar.to_fraction(ar.one)
    c = certify(steps=3, arith=ar, signs=["-++"])
    assert_certificate_valid(c)
    assert c.height_bits is None and c.arith == "opaque-exact"
    assert c.check(CONTROLS[0]).residual.startswith("<")


def test_validity_needs_controls_to_fail(default_cert):
    checks = list(default_cert.checks)
    i = next(i for i, k in enumerate(checks) if not k.expected)
    broken = dataclasses.replace(default_cert, checks=tuple(
        checks[:i] + [dataclasses.replace(checks[i], holds=True, residual="0")] + checks[i + 1:]))
    # a control that did not fail says nothing about the system: inconclusive, never INVALID
    assert not broken.valid and broken.status == "INCONCLUSIVE" and checks[i].name in broken.verdict()
    false_claim = dataclasses.replace(default_cert, checks=tuple(
        [dataclasses.replace(checks[0], holds=False, residual="1")] + checks[1:]))
    assert false_claim.status == "INVALID" and checks[0].name in false_claim.verdict()
    undecided = dataclasses.replace(default_cert, checks=tuple(
        [dataclasses.replace(checks[0], holds=None)] + checks[1:]))
    assert not undecided.valid and undecided.verdict().startswith("INCONCLUSIVE")
    inapplicable = dataclasses.replace(default_cert, checks=tuple(
        checks[:i] + [dataclasses.replace(checks[i], holds=True, applicable=False)] + checks[i + 1:]))
    assert inapplicable.valid and "1 inapplicable" in inapplicable.verdict()
    # no applicable control at all (an equilibrium): nothing shows the checks can fail there
    idle = dataclasses.replace(default_cert, checks=tuple(
        k if k.expected else dataclasses.replace(k, holds=True, applicable=False) for k in checks))
    assert not idle.valid and idle.status == "INCONCLUSIVE"
    assert idle.verdict().startswith("INCONCLUSIVE: all 31 claims hold, but no negative control can fail at "
                                     "this point (4 inapplicable)")
    with pytest.raises(AssertionError, match="INCONCLUSIVE"):
        assert_certificate_valid(broken)
    with pytest.raises(AssertionError, match="INVALID"):
        assert_certificate_valid(false_claim)
    empty = dataclasses.replace(default_cert, checks=())
    assert not empty.valid and empty.verdict().startswith("INCONCLUSIVE: the certificate has no checks")


def test_certificate_json_schema(default_cert):
    data = json.loads(json.dumps(default_cert.to_json()))
    assert set(data) >= {"system", "x0", "eps", "steps", "arith", "versions", "checks", "valid", "signs"}
    assert data["system"] == {"family": "lie-poisson", "n": 3, "a": ["1", "0", "2"], "b": ["0", "1", "0"],
                              "c": ["3", "1", "1"]}
    assert data["x0"] == list(DEFAULT_X0) and data["eps"] == "1/10" and data["steps"] == 20
    assert data["valid"] is True and data["versions"]["exact_khk"]
    for k in data["checks"]:
        assert set(k) == {"name", "claim", "expected", "holds", "residual", "arith", "seconds", "evidence", "detail",
                          "applicable"}
        assert isinstance(k["expected"], bool) and k["holds"] in (True, False, None)
        assert isinstance(k["residual"], str) and isinstance(k["seconds"], float)
    assert sum(not k["expected"] for k in data["checks"]) == 4


def test_floating_certificate_is_measured_not_decided():
    c = certify(steps=3, arith="mp:120", signs=["-++"])
    assert not c.valid and c.verdict().startswith("INCONCLUSIVE")
    assert all(k.holds is None and k.evidence == "numeric (measured error)" for k in c.checks)
    claims = [float(k.residual) for k in c.checks if k.expected and not k.name.startswith("rank")]
    # the structural controls differ by O(1); the claims only by rounding (120 bits, a few dozen
    # operations on O(10) quantities: far below 2^-100)
    assert max(claims) < 2.0 ** -100
    assert min(float(c.check(name).residual) for name in CONTROLS[:3]) > 1e-3


def test_poisson_subset_is_stated():
    c = certify(steps=6, signs=["-++"], poisson_points=2)
    assert c.valid
    assert "2 of the 6 points (k = [0, 5])" in c.check("Poisson map Phi_f").claim
    assert c.check("Poisson map Phi_f").detail == "checked at 2 orbit points"


def test_certify_input_errors():
    with pytest.raises(InputError, match="signs"):
        certify(steps=2, signs=["+++"])
    with pytest.raises(InputError, match="steps"):
        certify(steps=0)
    with pytest.raises(InputError, match="eps"):
        certify(eps=0)
    with pytest.raises(InputError, match="x0"):
        certify(x0=["1", "2"])
    with pytest.raises(InputError, match="poisson_points"):
        certify(steps=2, poisson_points=0)


def test_singular_step_raises_with_step():
    # for this n = 2 system det(I - eps f'(x0)) = (2e-1)(2e+1)(3e+1)(5e-1): eps = 1/5 is singular
    s = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3")
    with pytest.raises(SingularStepError, match="step 1"):
        certify(s, ["1", "0", "2", "1"], "1/5", steps=3)


def test_compare_reports_first_nonzero_exactly_and_skips_undefined_points():
    ar = get_arith("fraction")
    ok = [(0, lambda: ([F(1), F(2)], [F(1), F(2)])), (1, lambda: (F(3), F(3)))]
    assert compare(ar, ok) == (True, "0", "checked at 2 orbit points")
    bad = [(0, lambda: (F(1), F(1))), (1, lambda: ([F(1), F(5, 2)], [F(1), F(2)]))]
    assert compare(ar, bad) == (False, "1/2", "first nonzero residual at x_1")

    def undefined():
        raise SingularStepError(["0"], "1")

    holds, _, detail = compare(ar, [(0, undefined), (1, lambda: (F(3), F(3)))])
    assert holds is True and "skipped k = [0]" in detail
    assert compare(ar, [(0, undefined)])[0] is None
    with pytest.raises(SingularStepError):
        compare(ar, [(0, undefined)], skip_undefined=False)


def test_orbit_on_singular_hyperplane_is_not_certified():
    """On sum(u) = 0 (invariant), J is singular: the definition h(x, x~) is undefined everywhere."""
    s = LiePoissonSystem.random(5, 2)
    x0 = ("2", "2", "-3", "-1", "0", "1", "-2", "0", "3", "1")  # random_point avoids this hyperplane
    assert sum(F(t) for t in x0[:5]) == 0
    c = certify(s, x0, "1/7", steps=3)
    assert not c.valid and c.verdict().startswith("INCONCLUSIVE")
    undecided = [k for k in c.checks if k.holds is None]
    assert [k.name for k in undecided] == [f"integral {i} (closed form = definition)"
                                           for i in ("H~", "K~[+----]", "K~[-++++]")]
    assert all("J((x+x~)/2) is singular" in k.detail for k in undecided)
    assert all(k.passed for k in c.checks if k.holds is not None)


# --- exact_khk.testing ---------------------------------------------------------


def test_testing_helpers_pass_and_fail_with_exact_residual():
    s = default_system()
    phi = KahanMap(s.field("f"), DEFAULT_EPS, "flint")
    g = KahanMap(s.field("g", "-++"), DEFAULT_EPS, "flint")
    assert_commute(phi, g, DEFAULT_X0, 5)
    assert_reversible(g, DEFAULT_X0, 5)
    assert_poisson_map(phi, lambda x: Pi(s, x, DEFAULT_EPS, phi.arith), DEFAULT_X0, 3)
    # controls: Φ_g at another step size does not commute with Φ_f; J itself is not invariant
    g2 = KahanMap(s.field("g", "-++"), 2 * DEFAULT_EPS, "flint")
    with pytest.raises(AssertionError, match=r"do not commute: first nonzero residual at x_0: -?\d+/\d+"):
        assert_commute(phi, g2, DEFAULT_X0, 5)
    with pytest.raises(AssertionError, match="not a Poisson map"):
        assert_poisson_map(phi, lambda x: s.J(list(x)), DEFAULT_X0, 3)


def test_testing_helpers_floating_need_tol():
    s = default_system()
    phi = KahanMap(s.field("f"), DEFAULT_EPS, "float")
    from exact_khk.systems.lie_poisson.invariants import Htilde

    H = lambda x: Htilde(s.field("f"), x, DEFAULT_EPS, phi.arith)  # noqa: E731
    with pytest.raises(InputError, match="tol"):
        assert_conserved(phi, H, DEFAULT_X0, 3)
    # H~ ~ 1.6 here; 3 steps of float64 solves and one H~ each: errors ~1e-14, 1e-9 is generous
    assert_conserved(phi, H, DEFAULT_X0, 3, tol=1e-9)
    with pytest.raises(AssertionError, match="measured error"):
        assert_conserved(phi, lambda x: x[0], DEFAULT_X0, 3, tol=1e-9)


def test_docs_examples():
    import doctest
    import pathlib

    doc = pathlib.Path(__file__).resolve().parent.parent / "docs" / "certify.md"
    result = doctest.testfile(str(doc), module_relative=False)
    assert result.attempted >= 3 and result.failed == 0
