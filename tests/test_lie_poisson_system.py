"""The Lie–Poisson family answers the System interface like any other system: integrals
(H~ and K~ of every rational involution), the Poisson tensor Pi, the commuting fields and a
control; the generic certificate of what it declares is VALID."""

from __future__ import annotations

from fractions import Fraction

import sympy as sp

from exact_khk.arith import get_arith
from exact_khk.certification.engine import certify_system
from exact_khk.systems.lie_poisson import DEFAULT_X0, default_system
from exact_khk.systems.lie_poisson.system import hankel


def _htilde_sympy(M, n, x, eps):
    """x^T (I - eps^2 (M J(x))^2)^-1 M x from the formula, J(x) = [[0, X(u)], [-X(u), 0]]."""
    u = x[:n]
    Xu = sp.Matrix(hankel([Fraction(t) for t in u]))
    J = sp.zeros(2 * n)
    J[:n, n:], J[n:, :n] = Xu, -Xu
    X = sp.Matrix(x)
    S = M * J
    return (X.T * (sp.eye(2 * n) - sp.Rational(eps) ** 2 * S * S).inv() * M * X)[0]


def test_the_family_declares_its_integrals_fields_tensor_and_control():
    s = default_system()
    assert s.field_names() == ("f", "g[+--]", "g[-++]")
    assert list(s.integrals()) == ["H~", "K~[+--]", "K~[-++]"]
    assert s.poisson() is not None and s.controls() == {}
    assert [c.name for c in s.negative_controls(DEFAULT_X0, Fraction(1, 10))] == [
        "control: commutation with non-associated field", "control: integral H~ conserved by Phi_control",
        "control: integral H~ conserved for a non-admissible Hessian", "control: integral H~ at a perturbed point"]
    ar, x, eps = get_arith("fraction"), [Fraction(t) for t in DEFAULT_X0], Fraction(1, 10)
    Hs = sp.Matrix(s.hessian)
    for name, fn in s.integrals().items():  # values against SymPy from the formula
        M = Hs if name == "H~" else sp.Matrix(s.involution(name[3:-1])) * Hs
        assert fn(ar, x, eps) == _htilde_sympy(M, s.n, DEFAULT_X0, eps)
    assert s.poisson().jacobiator(ar, x, eps) == [0] * 20
    assert s.field("g[-++]") is s.field("g", "-++")


def test_the_engine_runs_the_papers_certificate_of_the_family():
    """The one engine on the family is the paper's certificate: same records, same order."""
    from exact_khk.certification.lie_poisson import certify

    cert = certify_system(default_system(), DEFAULT_X0, "1/10", 4)
    assert cert.status == "VALID"
    names = [c.name for c in cert.checks]
    assert "integral K~[-++] conserved by Phi_g[+--]" in names and "commutation Phi_f o Phi_g[-++]" in names
    assert "Poisson map Phi_f" in names and "involution {H~,K~[-++]}_Pi" in names
    assert all(c.holds is False for c in cert.checks if not c.expected)
    paper = certify(default_system(), DEFAULT_X0, "1/10", 4)
    key = lambda c: [(k.name, k.claim, k.holds, k.residual, k.applicable, k.detail) for k in c.checks]  # noqa: E731
    assert key(cert) == key(paper) and cert.values == paper.values and cert.orbit == paper.orbit


def test_the_fast_paths_agree_with_the_interface_exactly():
    """The paper's certificate evaluates H~, K~ and Pi by flint closed forms; the System interface
    by the plain formulas in Fractions: the same rationals (==) at every orbit point."""
    from exact_khk.certification.lie_poisson import certify
    from exact_khk.systems.lie_poisson.flint_forms import FlintForms
    from exact_khk.linalg.flintmat import rows

    s, fr, fl = default_system(), get_arith("fraction"), get_arith("flint")
    cert = certify(s, DEFAULT_X0, "1/10", 6, "flint")
    pts = [[Fraction(t) for t in p] for p in cert.orbit]
    for name, fn in s.integrals().items():
        assert [Fraction(v) for v in cert.values[name]] == [fn(fr, x, Fraction(1, 10)) for x in pts]
    fast, P = FlintForms(s, fl("1/10")), s.poisson()
    for x in pts:
        xf = [fl(t) for t in x]
        assert [[Fraction(str(t)) for t in r] for r in rows(fast.Pi(xf))] == P.matrix(fr, x, Fraction(1, 10))
        assert [Fraction(str(t)) for t in fast.jacobiator(xf)] == P.jacobiator(fr, x, Fraction(1, 10))
