"""Integrals, q_l, Π and exact gradients against an independent SymPy model.

The SymPy model below is built from the definitions in docs/conventions.md only (cyclic
Hankel blocks, J(x), A, the Kahan step as a linear solve, H̃ by (tH 4) and by
its definition); it uses none of the library's matrices or solvers.
"""

import random
from fractions import Fraction as F

import pytest
import sympy as sp

from exact_khk import InputError, LiePoissonSystem, get_arith
from exact_khk.linalg.dual import Dual, DualArith, gradient, jacobian, seed
from exact_khk.certification.lie_poisson import htilde_definition
from exact_khk.systems.lie_poisson.invariants import (Htilde, Pi, Pi_from_q, grad_Htilde,
                                  q_coefficients)
from exact_khk.linalg.dense import solve
from exact_khk.systems.lie_poisson.system import default_system, random_point

from .conftest import EXACT


def Q(v):
    return sp.Rational(v.numerator, v.denominator)


class SymModel:
    """The family for one (a, b, c), in SymPy, from the definitions in docs/conventions.md."""

    def __init__(self, a, b, c):
        self.n = n = len(a)
        X = lambda w: sp.Matrix(n, n, lambda i, j: w[(i + j) % n])  # noqa: E731
        self.X = X
        self.Hs = sp.BlockMatrix([[X(a), X(b)], [X(b), X(c)]]).as_explicit()
        P = sp.Matrix(n, n, lambda i, j: 1 if j == (i + 1) % n else 0)
        self.A = sp.diag(P, P)
        self.B0 = sp.eye(2 * n) - sp.Rational(2, n) * sp.diag(sp.ones(n), sp.ones(n))

    @classmethod
    def of(cls, system):
        return cls(*([Q(t) for t in v] for v in (system.a, system.b, system.c)))

    def J(self, x):
        n = self.n
        Xu = self.X(list(x[:n]))
        return sp.BlockMatrix([[sp.zeros(n), Xu], [-Xu, sp.zeros(n)]]).as_explicit()

    def step(self, M, x, eps):
        """Kahan step of f(x) = J(x) M x: (I - eps f'(x)) y = x, f' by symbolic differentiation."""
        xs = sp.symbols(f"y0:{2 * self.n}")
        f = self.J(xs) * M * sp.Matrix(xs)
        Jf = f.jacobian(xs).subs(dict(zip(xs, x)))
        return (sp.eye(2 * self.n) - eps * Jf).LUsolve(sp.Matrix(x))

    def htilde(self, M, x, eps):
        x = sp.Matrix(x)
        R = sp.eye(2 * self.n) - eps ** 2 * (M * self.J(x)) ** 2
        return (x.T * R.LUsolve(M * x))[0]

    def h_definition(self, M, x, eps):
        x = sp.Matrix(x)
        y = self.step(M, x, eps)
        return (x.T * self.J((x + y) / 2).LUsolve(y))[0] / (2 * eps)

    def Pi(self, x, eps):
        J = self.J(x)
        return J - eps ** 2 * J * self.Hs * J * self.Hs * J


def _case(n, seed):
    s = LiePoissonSystem.random(n, seed)
    return s, SymModel.of(s), [Q(t) for t in random_point(n, seed)]


def _fr(ar, v):
    return ar.to_fraction(v)


@pytest.mark.parametrize("arith", EXACT)
@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_htilde_closed_form_and_definition_match_sympy(n, arith):
    ar = get_arith(arith)
    s, m, x = _case(n, seed=10 + n)
    eps = F(1, 7)
    xa = [ar(F(int(t.p), int(t.q))) for t in x]
    expected_H = m.htilde(m.Hs, x, sp.Rational(1, 7))
    assert expected_H == m.h_definition(m.Hs, x, sp.Rational(1, 7))  # the model agrees with itself
    assert Q(_fr(ar, Htilde(s.field("f"), xa, eps, ar))) == expected_H
    assert Q(_fr(ar, htilde_definition(s.field("f"), xa, eps, ar))) == expected_H
    # K~ for B_0 = I - (2/n)(1 ⊕ 1), signs '-+…+'
    expected_K = m.htilde(m.B0 * m.Hs, x, sp.Rational(1, 7))
    g = s.field("g", "-" + "+" * (n - 1))
    assert Q(_fr(ar, Htilde(g, xa, eps, ar))) == expected_K
    assert Q(_fr(ar, htilde_definition(g, xa, eps, ar))) == expected_K


def test_htilde_is_even_in_eps_and_perturbs_2H0():
    s, m, x = _case(3, seed=4)
    ar = get_arith("fraction")
    xa = [F(int(t.p), int(t.q)) for t in x]
    assert Htilde(s.field("f"), xa, "1/9", ar) == Htilde(s.field("f"), xa, "-1/9", ar)
    e = sp.Symbol("e")
    H = m.htilde(m.Hs, x, e)
    assert sp.series(H, e, 0, 2).removeO() == (sp.Matrix(x).T * m.Hs * sp.Matrix(x))[0]  # 2 H0


def test_4d_q0_q1_paper_formulas():
    """Paper, Examples 2n = 4: q0 = α(x1²+x2²) + 2βx1x2, q1 = β(x1²+x2²) + 2αx1x2 (1-based h, x)."""
    h = sp.symbols("h1:7")
    x = sp.symbols("x1:5")
    m = SymModel(h[0:2], h[2:4], h[4:6])
    assert m.Hs == sp.Matrix([[h[0], h[1], h[2], h[3]], [h[1], h[0], h[3], h[2]],
                              [h[2], h[3], h[4], h[5]], [h[3], h[2], h[5], h[4]]])  # the paper's Hesse matrix
    S = (m.J(x) * m.Hs) ** 2
    alpha = h[2] ** 2 + h[3] ** 2 - h[0] * h[4] - h[1] * h[5]
    beta = 2 * h[2] * h[3] - h[0] * h[5] - h[1] * h[4]
    q0 = alpha * (x[0] ** 2 + x[1] ** 2) + 2 * beta * x[0] * x[1]
    q1 = beta * (x[0] ** 2 + x[1] ** 2) + 2 * alpha * x[0] * x[1]
    assert sp.expand(S - q0 * sp.eye(4) - q1 * m.A) == sp.zeros(4)
    assert sp.expand(S.trace() / 4 - q0) == 0 and sp.expand((m.A * S).trace() / 4 - q1) == 0
    # the library at rational points, in every exact arithmetic
    rng = random.Random(5)
    for _ in range(5):
        hv = [F(rng.randint(-9, 9), rng.randint(1, 5)) for _ in range(6)]
        xv = [F(rng.randint(-9, 9), rng.randint(1, 5)) for _ in range(4)]
        sub = dict(zip(h + x, [Q(t) for t in hv + xv]))
        sys2 = LiePoissonSystem(hv[0:2], hv[2:4], hv[4:6])
        for name in EXACT:
            ar = get_arith(name)
            got = [Q(_fr(ar, t)) for t in q_coefficients(sys2, [ar(t) for t in xv], ar)]
            assert got == [q0.subs(sub), q1.subs(sub)]


@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_matrix_polynomial_and_q_gradients(n):
    """(J Hs)² = Σ q_l A^l (docs/conventions.md) and ∇q_l = A^l ∇q_0, from the library's q_l and dual gradients."""
    s, m, x = _case(n, seed=20 + n)
    ar = get_arith("flint")
    xa = [ar(F(int(t.p), int(t.q))) for t in x]
    q, grads = jacobian(ar, lambda d, xd: q_coefficients(s, xd, d), xa)
    S = (m.J(x) * m.Hs) ** 2
    assert S == sum((Q(_fr(ar, ql)) * m.A ** l for l, ql in enumerate(q)), sp.zeros(2 * n))
    g0 = sp.Matrix([Q(_fr(ar, t)) for t in grads[0]])
    for l in range(1, n):
        assert sp.Matrix([Q(_fr(ar, t)) for t in grads[l]]) == m.A ** l * g0


def test_6d_bracket_table_of_J():
    """Paper, Examples 2n = 6 (1-based): the non-vanishing brackets {x_i, x_j} of J."""
    x = sp.symbols("x1:7")
    J = sp.Matrix(default_system().J(list(x)))
    table = {(1, 4): x[0], (2, 6): x[0], (3, 5): x[0],
             (1, 5): x[1], (2, 4): x[1], (3, 6): x[1],
             (1, 6): x[2], (2, 5): x[2], (3, 4): x[2]}
    for i in range(6):
        for j in range(6):
            want = table.get((i + 1, j + 1), 0) - table.get((j + 1, i + 1), 0)
            assert J[i, j] == want, (i + 1, j + 1)


@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_Pi_definition_formula_and_sympy(n):
    s, m, x = _case(n, seed=30 + n)
    for name in EXACT:
        ar = get_arith(name)
        xa = [ar(F(int(t.p), int(t.q))) for t in x]
        P = Pi(s, xa, "1/5", ar)
        assert P == Pi_from_q(s, xa, "1/5", ar)
        assert sp.Matrix([[Q(_fr(ar, t)) for t in row] for row in P]) == m.Pi(x, sp.Rational(1, 5))


@pytest.mark.parametrize("n", [2, 3])
def test_grad_htilde_matches_sympy_derivative(n):
    """Exact dual-number gradient = SymPy's derivative of the rational function t -> H~(x + t e_i)."""
    s, m, x = _case(n, seed=40 + n)
    ar = get_arith("fraction")
    xa = [F(int(t.p), int(t.q)) for t in x]
    g = grad_Htilde(s.field("f"), xa, "1/10", ar)
    t = sp.Symbol("t")
    for i in range(2 * n):
        xt = [xi + (t if j == i else 0) for j, xi in enumerate(x)]
        d = sp.diff(m.htilde(m.Hs, xt, sp.Rational(1, 10)), t).subs(t, 0)
        assert Q(g[i]) == sp.nsimplify(d)


@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_grad_K_is_B_grad_H_and_involution(n):
    s = LiePoissonSystem.random(n, 50 + n)
    ar = get_arith("flint")
    x = [ar(t) for t in random_point(n, 50 + n)]
    gH = grad_Htilde(s.field("f"), x, "1/6", ar)
    J, P = s.J(x), Pi(s, x, "1/6", ar)
    for signs in ("-" + "+" * (n - 1), "+" + "-" * (n - 1)):
        B = [[ar(t) for t in row] for row in s.involution(signs)]
        gK = grad_Htilde(s.field("g", signs), x, "1/6", ar)
        assert gK == [sum((b * h for b, h in zip(row, gH)), ar.zero) for row in B]
        for T in (J, P):
            assert sum(gH[i] * T[i][j] * gK[j] for i in range(2 * n) for j in range(2 * n)) == 0
    # a control: the control field's H~ is not in involution with H~ (so the test can fail)
    gC = grad_Htilde(s.field("control"), x, "1/6", ar)
    assert sum(gH[i] * J[i][j] * gC[j] for i in range(2 * n) for j in range(2 * n)) != 0


def test_htilde_input_errors():
    s = default_system()
    with pytest.raises(InputError, match="eps"):
        Htilde(s.field("f"), [F(1)] * 6, 0.1, get_arith("fraction"))
    with pytest.raises(InputError, match="field"):
        Htilde(object(), [F(1)] * 6, "1/10", get_arith("fraction"))


# --- dual numbers ---------------------------------------------------------------


def test_dual_arithmetic_rules():
    ar = get_arith("fraction")
    d, (u, v) = seed(ar, [F(2), F(3)])
    w = (u * v - 1) / (u + v) + 2 * u - v / 3
    # d/du = (v(u+v) - (uv-1))/(u+v)^2 + 2 ; d/dv = (u(u+v) - (uv-1))/(u+v)^2 - 1/3
    assert w.val == F(5, 5) + 4 - 1
    assert w.tan == (F(3 * 5 - 5, 25) + 2, F(2 * 5 - 5, 25) - F(1, 3))
    assert (1 - u).tan == (-1, 0) and (1 / u).tan == (F(-1, 4), 0)
    with pytest.raises(ZeroDivisionError):
        u / (u - 2)


@pytest.mark.parametrize("arith", ["flint", "fraction", "mp:100"])
def test_dual_native_solve(arith):
    """Solving M(x) z = b(x) with duals gives dz = M^-1 (db - dM z), checked against Cramer's rule."""
    ar = get_arith(arith)

    def z0(d, x):
        M = [[x[0], d.one], [x[1], x[0] * x[1]]]
        Z, _ = solve(d, M, [[d.one], [x[0]]])
        return Z[0][0]

    x = [ar(F(3)), ar(F(2))]
    g = gradient(ar, z0, x)
    # by Cramer's rule z0 = (x0 x1 - x0) / (x0^2 x1 - x1); its partial derivatives by the quotient rule
    a, b = F(3), F(2)
    num, den = a * b - a, a * a * b - b
    dnum, dden = (b - 1, a), (2 * a * b, a * a - 1)
    want = [(dn * den - num * dd) / den ** 2 for dn, dd in zip(dnum, dden)]
    if ar.exact:
        assert [ar.to_fraction(t) for t in g] == want
    else:  # 100-bit floats: a handful of roundings of O(1) quantities, 2^-90 is ample
        assert all(abs(ar.to_fraction(t) - w) < F(1, 2 ** 90) for t, w in zip(g, want))


def test_dual_arith_context():
    ar = get_arith("gmpy2")
    d = DualArith(ar, 2)
    e = Dual(ar(F(1)), (ar(F(0)), ar(F(0))))
    assert d.is_zero(e - d.one) is True and d.is_zero(Dual(ar(F(0)), (ar(F(1)), ar(F(0))))) is False
    assert d.format(Dual(ar(F(1, 2)), None)) == "1/2 + d(0, 0)"
    assert d.convert(ar(F(1, 3))).val == ar(F(1, 3))
