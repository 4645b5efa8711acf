"""Floating arithmetics against the exact orbit, with a first-order error bound.

Bound used (standard forward error analysis, first order in the unit roundoff u):

    e_0     <= u |x_0|
    e_{k+1} <= |dΦ(x_k)| e_k + c_k κ(M_k) u |x_{k+1}|,   c_k = 3N ρ_k + n + 4

(∞-norms; M_k = I − ε f'(x_k) built with n+1 roundings per entry and solved by
Gaussian elimination with partial pivoting, whose backward error is at most
3N ρ_k u |M_k| with ρ_k the growth factor; κ = |M||M^-1|).  Everything on the
right is evaluated on the *exact* orbit.  We assert error <= 2 * bound, the 2
absorbing the neglected O(u²) terms, while the bound is below 2^-20.
"""

import warnings
from fractions import Fraction

import pytest

from exact_khk import KahanMap, LiePoissonSystem, get_arith
from exact_khk.linalg.dense import lu_factor, solve
from exact_khk.systems.lie_poisson.system import DEFAULT_EPS, DEFAULT_X0, default_system

STEPS = 15


def _norm_inf_vec(v):
    return max(abs(float(t)) for t in v)


def _norm_inf(M):
    return max(sum(abs(float(t)) for t in row) for row in M)


def _first_order_bound(phi_exact, pts, u):
    ar = phi_exact.arith
    N = len(pts[0])
    n = N // 2
    e = u * _norm_inf_vec(pts[0])
    bounds = [e]
    for k in range(len(pts) - 1):
        M = phi_exact.system_matrix(pts[k])
        Minv, _ = solve(ar, M, [[ar.one if i == j else ar.zero for j in range(N)] for i in range(N)])
        kappa = _norm_inf(M) * _norm_inf(Minv)
        fl = get_arith("float")
        Mf = [[float(t) for t in row] for row in M]
        LU, _ = lu_factor(fl, Mf)
        rho = max(abs(LU[i][j]) for i in range(N) for j in range(i, N)) / max(abs(t) for r in Mf for t in r)
        c = 3 * N * max(rho, 1.0) + n + 4
        D = phi_exact.jacobian(pts[k])
        e = _norm_inf(D) * e + c * kappa * u * _norm_inf_vec(pts[k + 1])
        bounds.append(e)
    return bounds


@pytest.mark.parametrize("name", ["float", "mp:64", "mp:128", "mp:256"])
def test_floating_orbit_within_first_order_bound(name):
    system = default_system()
    exact = KahanMap(system.field("f"), DEFAULT_EPS, "flint")
    pts = exact.orbit(DEFAULT_X0, STEPS)
    ar = get_arith(name)
    approx = KahanMap(system.field("f"), DEFAULT_EPS, ar).orbit(DEFAULT_X0, STEPS)
    bounds = _first_order_bound(exact, pts, ar.unit_roundoff)
    assert bounds[-1] < 2.0 ** -20
    for k, (p, q, b) in enumerate(zip(pts, approx, bounds)):
        err = max(abs(exact.arith.to_fraction(s) - ar.to_fraction(t)) for s, t in zip(p, q))
        assert float(err) <= 2 * b, (name, k, float(err), b)
    # the bound is not vacuous: the error is nonzero and within a few thousand ulps
    last = max(abs(exact.arith.to_fraction(s) - ar.to_fraction(t)) for s, t in zip(pts[-1], approx[-1]))
    assert last > 0


def test_errors_shrink_with_precision():
    system = default_system()
    exact = KahanMap(system.field("f"), DEFAULT_EPS, "flint").orbit(DEFAULT_X0, STEPS)
    errs = []
    for name in ["float", "mp:100", "mp:200", "mp:400"]:
        ar = get_arith(name)
        pts = KahanMap(system.field("f"), DEFAULT_EPS, ar).orbit(DEFAULT_X0, STEPS)
        errs.append(max(abs(Fraction(int(s.p), int(s.q)) - ar.to_fraction(t)) for s, t in zip(exact[-1], pts[-1])))
    assert errs[0] > errs[1] > errs[2] > errs[3] > 0


def test_near_singular_float_step_warns_with_condition():
    """ε a hair away from a root of det(I − ε f'(x)): a warning carrying κ, or a typed error."""
    from exact_khk import NearSingularWarning
    import sympy as sp

    s = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3")
    x = ["1", "0", "2", "1"]
    Jf = sp.Matrix(s.field("f").jacobian(get_arith("fraction"), [Fraction(t) for t in x]))
    lam = sp.Symbol("lam")
    root = next(r for r in sp.roots(Jf.charpoly(lam).as_expr(), lam, filter="Q") if r != 0)
    eps0 = Fraction(int(sp.numer(1 / root)), int(sp.denom(1 / root)))
    eps = eps0 * (1 + Fraction(1, 10 ** 10))
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        KahanMap(s.field("f"), eps, "float").step(x)
    near = [w for w in rec if issubclass(w.category, NearSingularWarning)]
    assert near and near[0].message.condition > 2.0 ** 26


@pytest.mark.parametrize("name", ["float", "mp:80"])
def test_non_finite_coordinates_are_refused(name):
    """NaN or ±inf in a point is bad input (named), not a 'singular step'."""
    from exact_khk import InputError

    ar = get_arith(name)
    phi = KahanMap(default_system().field("f"), DEFAULT_EPS, name)
    for bad in (float("nan"), float("inf"), -float("inf")):
        x = list(phi.point(DEFAULT_X0))
        x[2] = ar.convert(bad)
        with pytest.raises(InputError, match=r"x\[2\]: expected a finite number"):
            phi.step(tuple(x))
        with pytest.raises(InputError, match=r"x0\[2\]"):
            phi.orbit(x, 1)
    assert all(ar.is_finite(t) for t in phi.step(DEFAULT_X0))  # control: a finite point steps


def test_float_solve_gives_the_bits_of_numpys_public_functions(monkeypatch):
    """float_solve calls the gufuncs behind numpy.linalg.solve and inv (a private numpy
    module); without them it calls the public functions: the same bits, and the same
    SingularMatrix on an exactly zero pivot."""
    import numpy

    from exact_khk.linalg import floating
    from exact_khk.linalg.dense import SingularMatrix

    rng = numpy.random.default_rng(5)
    cases = [(rng.standard_normal((N, N)), rng.standard_normal((N, 1))) for N in (2, 3, 8, 33)]
    fast = [floating.float_solve(M, B) for M, B in cases]
    assert all(X.tolist() == numpy.linalg.solve(M, B).tolist() for (M, B), (X, _) in zip(cases, fast))
    monkeypatch.setattr(floating, "_gesv", None)
    public = [floating.float_solve(M, B) for M, B in cases]
    assert [(X.tolist(), k) for X, k in fast] == [(X.tolist(), k) for X, k in public]
    singular = numpy.array([[1.0, 2.0], [2.0, 4.0]])
    for gesv in (None, floating._umath_linalg.solve):
        monkeypatch.setattr(floating, "_gesv", gesv)
        with pytest.raises(SingularMatrix):
            floating.float_solve(singular, numpy.ones((2, 1)))


def test_float_steps_of_one_map_from_several_threads():
    """The float step writes I − εf'(x) and its inverse into one array per map and thread:
    steps of one map taken concurrently from threads (LAPACK releases the GIL) equal serial
    steps (one array shared by the threads fails this test)."""
    import threading

    from exact_khk.systems.lie_poisson.system import random_point

    n = 160
    phi = KahanMap(LiePoissonSystem.random(n, seed=2).field("f"), "1/1000", "float")
    points = [phi.point(random_point(n, seed)) for seed in range(8)]
    serial = [phi.orbit(p, 5) for p in points]
    results = [None] * len(points)

    def run(k):
        results[k] = phi.orbit(points[k], 5)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(len(points))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results == serial
    # control: the orbits differ from one another (a shared, overwritten M would mix them)
    assert len({tuple(r[-1]) for r in serial}) == len(points)
