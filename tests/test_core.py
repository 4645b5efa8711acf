"""Core: systems, fields, Kahan steps and orbits over every arithmetic."""

import pathlib
import subprocess
import sys
from fractions import Fraction

import numpy as np
import pytest
import sympy as sp

from exact_khk import (InputError, KahanMap, LiePoissonSystem, NotRationalError,
                       SingularStepError, get_arith, involution_circulant, rational_sign_patterns)
from exact_khk.linalg.dense import matmul
from exact_khk.systems.lie_poisson.system import default_system, DEFAULT_X0, DEFAULT_EPS

from .conftest import EXACT


def _case_map(case, arith):
    system = LiePoissonSystem.from_vectors(case["a"], case["b"], case["c"])
    return KahanMap(system.field(case["field"], signs=case["signs"]), case["eps"], arith)


ROOT = pathlib.Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("script", [
    "generate_golden.py", pytest.param("generate_degree_golden.py", marks=pytest.mark.slow)])
def test_golden_files_are_what_the_independent_route_gives(script, tmp_path):
    """The committed golden data (tests/data) is what its SymPy-only generator gives now
    (``--check``), and the check can fail: a tampered copy is reported (exit status 1)."""
    run = [sys.executable, str(ROOT / "scripts" / script), "--check"]
    res = subprocess.run(run, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0 and "agree" in res.stdout, res.stdout + res.stderr[-800:]
    if script == "generate_golden.py":  # the negative control (the quick one)
        bad = tmp_path / "golden.json"
        bad.write_text((ROOT / "tests" / "data" / "golden_orbits.json").read_text().replace('"1/7"', '"1/8"', 1))
        res = subprocess.run(run + ["--out", str(bad)], capture_output=True, text=True, timeout=600)
        assert res.returncode == 1 and "DIFFER" in res.stdout, res.stdout + res.stderr[-800:]


@pytest.mark.parametrize("arith", EXACT)
def test_golden_orbits_exact(golden, arith):
    """Every exact arithmetic reproduces the SymPy-generated orbits, entry by entry."""
    assert len(golden) >= 10
    for case in golden:
        phi = _case_map(case, arith)
        pts = phi.orbit(case["x0"], case["steps"])
        got = [[phi.arith.format(t) for t in p] for p in pts]
        assert got == case["orbit"], (case["n"], case["field"], case["signs"])


def test_exact_arithmetics_agree_with_eq():
    s = default_system()
    results = []
    for name in EXACT:
        phi = KahanMap(s.field("g", "-++"), DEFAULT_EPS, name)
        results.append([tuple(phi.arith.to_fraction(t) for t in p) for p in phi.orbit(DEFAULT_X0, 15)])
    assert len(results) == 3
    assert all(r == results[0] for r in results[1:])


@pytest.mark.parametrize("arith", EXACT)
def test_reversibility_along_orbit(arith):
    s = LiePoissonSystem.random(4, seed=7)
    for kind, signs in (("f", None), ("g", "-+++"), ("control", None)):
        phi = KahanMap(s.field(kind, signs), "2/9", arith)
        pts = phi.orbit(["1", "0", "2", "-1", "0", "1", "1", "1/2"], 8)
        for p, q in zip(pts, pts[1:]):
            assert phi.inverse(q) == p


def test_involutions_match_eigen_definition():
    """B from Ramanujan sums equals Σ s_j Π_j built numerically from the DFT."""
    for n in range(2, 9):
        w = np.exp(2j * np.pi / n)
        P = np.roll(np.eye(n), 1, axis=1)  # P[i][(i+1)%n] = 1
        assert P[0, 1 % n] == 1
        for signs in rational_sign_patterns(n):
            s = [1 if ch == "+" else -1 for ch in signs]
            B = sum(s[j] * sum(w ** (-j * k) * np.linalg.matrix_power(P, k) for k in range(n)) / n
                    for j in range(n))
            alpha = involution_circulant(n, signs)
            Bq = np.array([[float(alpha[(j - i) % n]) for j in range(n)] for i in range(n)])
            assert np.abs(B - Bq).max() < 1e-12
            # eigenvalue s_j on the ω^j eigenvector
            for j in range(n):
                v = w ** (j * np.arange(n))
                assert np.allclose(Bq @ v, s[j] * v)
    assert len(rational_sign_patterns(6)) == 16 and len(rational_sign_patterns(7)) == 4


def test_b0_and_half_shift_examples():
    assert involution_circulant(3, "-++") == (Fraction(1, 3), Fraction(-2, 3), Fraction(-2, 3))
    n = 4  # B_{n/2}: α_k = δ_k0 − (2/n)(−1)^k
    assert involution_circulant(n, "++-+") == tuple(int(k == 0) - Fraction(2, n) * (-1) ** k for k in range(n))


def test_non_rational_signs_name_the_class():
    with pytest.raises(NotRationalError, match=r"gcd\(j, 5\) = 1\} = \{1, 2, 3, 4\}"):
        LiePoissonSystem.random(5, 1).field("g", "-+-++")


def test_system_matrices_follow_conventions():
    s = LiePoissonSystem.from_vectors("1,2,3", "4,5,6", "7,8,9")
    x = [Fraction(v) for v in (1, 2, 3, 4, 5, 6)]
    J = s.J(x)
    assert J[0][3:] == [1, 2, 3] and J[1][3:] == [2, 3, 1] and J[3][:3] == [-1, -2, -3]
    A = s.shift
    # Aᵀ J(x) = J(x) A
    At = [list(r) for r in zip(*A)]
    assert matmul(At, J) == matmul(J, A)
    # H_1 has Hessian A Hs, and A Hs is again admissible: A (A Hs) = (A Hs) Aᵀ
    M = s.hamiltonian_hessian(1)
    assert matmul(A, M) == matmul(M, At)
    # f(x) = J(x) Hs x and its Jacobian from the formula in docs/conventions.md
    ar = get_arith("fraction")
    fld = s.field("f")
    y = [sum(h * t for h, t in zip(row, x)) for row in s.hessian]
    assert fld.evaluate(ar, x) == [sum(j * t for j, t in zip(row, y)) for row in J]
    E = lambda k: [Fraction(int(i == k)) for i in range(6)]  # noqa: E731
    cols = [[sum(j * t for j, t in zip(row, y)) for row in s.J(E(k))] for k in range(3)]
    expected = [[sum(J[i][l] * s.hessian[l][j] for l in range(6)) + (cols[j][i] if j < 3 else 0)
                 for j in range(6)] for i in range(6)]
    assert fld.jacobian(ar, x) == expected


def test_map_jacobian_against_sympy_derivative():
    """dΦ from the closed form equals SymPy's derivative of the rational map (n = 2)."""
    s = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3")
    eps = Fraction(1, 7)
    xs = sp.symbols("x0:4")
    fld = s.field("f")
    ar = get_arith("fraction")
    # symbolic f'(x): linear in x, read off from the library's field at unit vectors
    Jf = sp.zeros(4, 4)
    for k in range(4):
        ek = [Fraction(int(i == k)) for i in range(4)]
        Jf += sp.Matrix(fld.jacobian(ar, ek)).applyfunc(sp.Rational) * xs[k]
    phi_sym = (sp.eye(4) - sp.Rational(eps) * Jf).LUsolve(sp.Matrix(xs))
    D = phi_sym.jacobian(xs)
    pt = {xs[0]: 1, xs[1]: 0, xs[2]: 2, xs[3]: 1}
    expected = [[sp.Rational(sp.simplify(D[i, j].subs(pt))) for j in range(4)] for i in range(4)]
    got = KahanMap(fld, eps, "fraction").jacobian(["1", "0", "2", "1"])
    assert [[sp.Rational(t.numerator, t.denominator) for t in r] for r in got] == expected


def test_map_jacobian_inverse_identity():
    """dΦ_{-ε}(Φ(x)) dΦ_ε(x) = I exactly (from reversibility)."""
    s = LiePoissonSystem.random(3, seed=2)
    phi = KahanMap(s.field("f"), "1/6", "flint")
    x = phi.point(["1", "1", "0", "2", "-1", "1/3"])
    D1 = phi.jacobian(x)
    D2 = phi.with_eps(-phi.eps).jacobian(phi.step(x))
    prod = matmul(D2, D1)
    assert prod == [[int(i == j) for j in range(6)] for i in range(6)]


def test_general_quadratic_field_step():
    """Non-homogeneous field: Kahan's defining equation holds exactly and the map is reversible."""
    from exact_khk import QuadraticField

    F = Fraction
    # Lotka–Volterra: x' = x(1 - y), y' = y(x - 1)
    T = [[[0, F(-1, 2)], [F(-1, 2), 0]], [[0, F(1, 2)], [F(1, 2), 0]]]
    fld = QuadraticField.from_tensor(T, linear=[[1, 0], [0, -1]])
    assert not fld.homogeneous
    phi = KahanMap(fld, "1/5", "fraction")
    x = (F(1, 2), F(3, 2))
    y = phi.step(x)
    e = F(1, 5)
    # (x̃ - x)/(2ε) = Q(x, x̃) + ½ L (x + x̃)
    lhs = [(b - a) / (2 * e) for a, b in zip(x, y)]
    rhs = [-(x[0] * y[1] + x[1] * y[0]) / 2 + (x[0] + y[0]) / 2,
           (x[0] * y[1] + x[1] * y[0]) / 2 - (x[1] + y[1]) / 2]
    assert lhs == rhs
    assert phi.inverse(y) == x


def _rational_singular_eps(system, x):
    """A rational ε with det(I − ε f'(x)) = 0, found independently with SymPy."""
    ar = get_arith("fraction")
    Jf = sp.Matrix(system.field("f").jacobian(ar, [Fraction(t) for t in x])).applyfunc(sp.Rational)
    lam = sp.Symbol("lam")
    for root in sp.roots(Jf.charpoly(lam).as_expr(), lam, filter="Q"):
        if root != 0:
            return Fraction(int(sp.numer(1 / root)), int(sp.denom(1 / root)))
    raise AssertionError("no rational singular step at this point")


@pytest.mark.parametrize("arith", EXACT)
def test_singular_step_is_reported(arith):
    s = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3")
    x = ["1", "0", "2", "1"]
    eps = _rational_singular_eps(s, x)
    phi = KahanMap(s.field("f"), eps, arith)
    with pytest.raises(SingularStepError) as info:
        phi.orbit(x, 3)
    err = info.value
    assert err.step == 1 and err.x == ["1", "0", "2", "1"] and err.eps == str(eps)
    assert "step 1" in str(err) and str(eps) in str(err)


def test_singular_step_float_raises_not_garbage():
    s = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3")
    x = ["1", "0", "2", "1"]
    eps = _rational_singular_eps(s, x)
    with pytest.raises(SingularStepError) as info:
        KahanMap(s.field("f"), eps, "float").step(x)
    assert info.value.condition is not None


@pytest.mark.parametrize("bad, match", [
    (dict(a="1,2", b="1", c="1,1"), "a, b, c need one length n: a has 2 entries, b 1, c 2"),
    (dict(a="1,0", b="0,1,0", c="3,1,1"), "a has 2 entries, b 3, c 3"),  # a short a is a's fault too
    (dict(a="1", b="1", c="1"), "n >= 2"),
    (dict(a="1,x", b="1,1", c="1,1"), r"a\[1\]"),
])
def test_bad_system_input(bad, match):
    with pytest.raises(InputError, match=match):
        LiePoissonSystem.from_vectors(**bad)


def test_bad_map_input():
    fld = default_system().field("f")
    with pytest.raises(InputError, match="eps"):
        KahanMap(fld, 0)
    with pytest.raises(InputError, match="eps"):
        KahanMap(fld, 0.1)  # a binary float is not an exact rational
    with pytest.raises(InputError, match="x0: expected 6"):
        KahanMap(fld, "1/10").orbit([1, 2], 2)
    with pytest.raises(InputError, match="unknown arithmetic"):
        KahanMap(fld, "1/10", "quad")
    with pytest.raises(InputError, match="signs"):
        default_system().field("g", "-+")


def test_mpmath_contexts_are_private():
    import mpmath

    before = mpmath.mp.prec
    a, b = get_arith("mp:300"), get_arith("mp:40")
    assert a.ctx.prec == 300 and b.ctx.prec == 40 and mpmath.mp.prec == before
    assert a.format(a(Fraction(1, 3))) != b.format(b(Fraction(1, 3)))
