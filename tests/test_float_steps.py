"""The floating dense steps (``float`` by LAPACK through numpy, ``mp:P`` by the generic
elimination) against the exact step, with an error bound from the condition number.

One step from a point x whose coordinates are exactly representable (so x itself
carries no error).  Standard backward error analysis (Higham, *Accuracy and
Stability of Numerical Algorithms*, Thm 9.4 and §7.1), first order in u = 2^-p:

* every entry of M̂ = fl(I − εf'(x)) is a sum of at most 2n + 3 rounded terms
  (two dot products of length n from the circulant first rows, the factor ε and
  the 1 on the diagonal; the generic Jacobian terms have fewer), so
  ‖M̂ − M‖∞ ≤ (2n + 3) u ‖M‖∞ when the sums do not cancel heavily (small
  integer data, ε = 1/(10n), as here);
* Gaussian elimination with partial pivoting solves (M̂ + E) ẑ = b with
  ‖E‖∞ ≤ 3N ρ u ‖M̂‖∞ (ρ the growth factor, measured on the same matrix);

hence ‖ẑ − z‖∞ ≤ c κ∞(M) u ‖z‖∞ with c = 3Nρ + 2n + 4 (κ∞ computed exactly),
and for non-homogeneous f the step x + 2εX adds |2ε| times that for X plus
2 u ‖z‖∞.  We assert error ≤ 2 × bound (the 2 absorbs the O(u²) terms).  The
bound is never loosened to pass.
"""

import math
import warnings
from fractions import Fraction

import numpy
import pytest

from exact_khk import KahanMap, LiePoissonSystem, NearSingularWarning, SingularStepError, get_arith
from exact_khk.linalg import floating
from exact_khk.linalg.dense import inverse_norm1_estimate, lu_factor, solve
from exact_khk.systems.lie_poisson.system import random_point
from exact_khk.systems.quadratic import QuadraticField

F = Fraction


def _lv_field():
    """A non-homogeneous generic field (Lotka–Volterra-like, with linear and constant parts)."""
    return QuadraticField.from_tensor(
        [[[0, F(1, 2), 0], [F(1, 2), 0, 0], [0, 0, 0]],
         [[0, F(-1, 2), 0], [F(-1, 2), 0, F(1, 3)], [0, F(1, 3), 0]],
         [[1, 0, 0], [0, 0, 0], [0, 0, F(-1, 5)]]],
        linear=[[0, 0, 1], [0, 1, 0], [F(1, 7), 0, 0]], const=[F(1, 3), 0, -1])


def _exact_data(field, eps, x):
    """(exact step z, exact M, κ∞(M), growth factor ρ of binary64 partial pivoting on M)."""
    fr = get_arith("fraction")
    phi = KahanMap(field, eps, fr, method="dense")
    z = phi.step(x)
    M = phi.system_matrix([fr(t) for t in x])
    N = len(M)
    Minv, _ = solve(fr, M, [[F(int(i == j)) for j in range(N)] for i in range(N)])
    norm = lambda A: max(sum(abs(t) for t in row) for row in A)  # noqa: E731
    Mf = [[float(t) for t in row] for row in M]
    LU, _ = lu_factor(get_arith("float"), Mf)
    rho = max(abs(LU[i][j]) for i in range(N) for j in range(i, N)) / max(abs(t) for r in Mf for t in r)
    return z, M, float(norm(M) * norm(Minv)), max(rho, 1.0)


CASES = [(LiePoissonSystem.random(n, seed=s).field("f"), n, s) for n, s in ((2, 1), (3, 2), (5, 3), (8, 4), (16, 5))]


@pytest.mark.parametrize("name", ["float", "mp:64", "mp:200"])
@pytest.mark.parametrize("field, n, seed", CASES, ids=[f"lp{n}" for _, n, _ in CASES])
def test_step_within_condition_bound(name, field, n, seed):
    ar = get_arith(name)
    eps = F(1, 10 * n)
    x = random_point(n, seed)
    z, M, kappa, rho = _exact_data(field, eps, x)
    N = 2 * n
    c = 3 * N * rho + 2 * n + 4
    bound = c * kappa * ar.unit_roundoff * max(abs(t) for t in z)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # well conditioned: no warning either
        got = KahanMap(field, eps, ar).step(x)
    err = max(abs(ar.to_fraction(g) - t) for g, t in zip(got, z))
    assert float(err) <= 2 * bound, (name, n, float(err), bound)
    assert bound < 2.0 ** -20  # the bound says something
    if name == "float":
        assert all(type(t) is float for t in got)


@pytest.mark.parametrize("name", ["float", "mp:64"])
def test_non_homogeneous_generic_field_within_condition_bound(name):
    ar, field, eps = get_arith(name), _lv_field(), F(1, 10)
    x = ["1/2", "-3/4", "5/4"]
    z, M, kappa, rho = _exact_data(field, eps, x)
    X = [(t - F(s)) / (2 * eps) for t, s in zip(z, x)]  # the solved vector
    c = 3 * 3 * rho + 2 + 4
    bound = 2 * abs(eps) * c * kappa * ar.unit_roundoff * max(abs(t) for t in X) \
        + 2 * ar.unit_roundoff * max(abs(t) for t in z)
    got = KahanMap(field, eps, ar).step(x)
    err = max(abs(ar.to_fraction(g) - t) for g, t in zip(got, z))
    assert float(err) <= 2 * bound, (float(err), bound)


@pytest.mark.parametrize("name", ["float", "mp:80"])
def test_numpy_system_matrix_is_the_rounded_exact_one(name):
    ar, fr = get_arith(name), get_arith("fraction")
    for field, n, seed in CASES[:4]:
        x = random_point(n, seed)
        eps = F(1, 10 * n)
        exact = KahanMap(field, eps, fr, method="dense").system_matrix([fr(t) for t in x])
        got = floating.system_matrix(field, ar, [ar(t) for t in x], ar(eps))
        tol = (2 * n + 3) * ar.unit_roundoff * max(sum(abs(t) for t in row) for row in exact)
        assert max(abs(ar.to_fraction(g) - t) for grow, row in zip(got.tolist(), exact)
                   for g, t in zip(grow, row)) <= 2 * tol
    lv = _lv_field()
    if ar.lapack:  # the generic Jacobian terms (binary64 only)
        M = floating.system_matrix(lv, ar, [0.5, -0.75, 1.25], 0.1)
        E = KahanMap(lv, 0.1, ar, method="dense").system_matrix([0.5, -0.75, 1.25])
        assert numpy.allclose(M, numpy.array(E), rtol=0, atol=1e-15)


def test_condition_numbers_reported():
    """float: κ₁ from the inverse (equal to the exact one to rounding); mp: the p-bit
    estimate is a lower bound on κ₁, within LAPACK's usual factor 3 here, and κ₁ from
    binary64 (what an mp:P step reports where that is accurate) is within 2^-20 of it."""
    fr = get_arith("fraction")
    for field, n, seed in CASES:
        x, eps = random_point(n, seed), F(1, 10 * n)
        M = KahanMap(field, eps, fr, method="dense").system_matrix([fr(t) for t in x])
        N = len(M)
        Minv, _ = solve(fr, M, [[F(int(i == j)) for j in range(N)] for i in range(N)])
        norm1 = lambda A: max(sum(abs(A[i][j]) for i in range(N)) for j in range(N))  # noqa: E731
        exact = norm1(M) * norm1(Minv)
        kappa = float(exact)
        got = floating.binary64_condition([[get_arith("mp:200")(t) for t in row] for row in M])
        assert got is not None and abs(F(got) / exact - 1) < F(1, 2 ** 20)
        Mf = numpy.array([[float(t) for t in row] for row in M])
        _, cond = floating.float_solve(Mf, numpy.ones((N, 1)))
        assert abs(cond / kappa - 1) < 1e-10
        mp = get_arith("mp:100")
        LU, perm = lu_factor(mp, [[mp(t) for t in row] for row in M])
        est = inverse_norm1_estimate(mp, LU, perm) * float(norm1(M))
        assert kappa / 3 <= est <= kappa * (1 + 1e-20)


def test_mp_condition_where_binary64_cannot_hold_it():
    """Where binary64 cannot hold κ₁ of an mp:P system — an entry beyond the double range,
    a nonzero that underflows, N·κ > 2^32 — it is computed in p-bit arithmetic."""
    mp = get_arith("mp:200")
    big, tiny, one = mp("1e400"), mp("1e-400"), mp(1)
    t = F(1, 2 ** 40)  # [[1, 1], [1, 1 + t]]: κ₁ = (2 + t)²/t > 2^32
    close = [[one, one], [one, mp(1 + t)]]
    for M in ([[big, one], [one, one]], [[tiny, one], [one, one]], close):
        assert floating.binary64_condition(M) is None
    _, cond = solve(mp, close, [[one], [one]], condition=floating.binary64_condition)  # p-bit κ₁
    assert abs(F(cond) / ((2 + t) ** 2 / t) - 1) < F(1, 2 ** 40)


@pytest.mark.parametrize("name", ["float", "mp:64"])
def test_singular_and_near_singular_steps(name):
    """An exactly singular step raises; ε a hair off a root of det(I − εf'(x)) warns
    with κ ≥ 2^(p/2) (or raises when κ·2^-p ≥ 1), as the KahanMap docstring says."""
    import sympy as sp

    s = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3")
    x = ["1", "0", "2", "1"]
    fr = get_arith("fraction")
    Jf = sp.Matrix(s.field("f").jacobian(fr, [F(t) for t in x]))
    lam = sp.Symbol("lam")
    root = next(r for r in sp.roots(Jf.charpoly(lam).as_expr(), lam, filter="Q") if r != 0)
    eps0 = F(int(sp.numer(1 / root)), int(sp.denom(1 / root)))
    with pytest.raises(SingularStepError):
        KahanMap(s.field("f"), eps0, name).step(x)
    ar = get_arith(name)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        try:
            KahanMap(s.field("f"), eps0 * (1 + F(1, 10 ** 10)), name).step(x)
        except SingularStepError as exc:
            assert exc.condition * ar.unit_roundoff >= 1
        else:
            near = [w for w in rec if issubclass(w.category, NearSingularWarning)]
            assert near and near[0].message.condition >= 2.0 ** (ar.prec / 2)


def test_overflow_is_a_singular_step_not_nan():
    """Entries of I − εf'(x) that overflow binary64 never come back as NaN/inf data."""
    f = LiePoissonSystem.random(3, seed=1).field("f")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no raw RuntimeWarning from numpy either
        with pytest.raises(SingularStepError):
            KahanMap(f, "1/10", "float").step([1.5e308, -1.7e308, 1.6e308, 1.7e308, 1e308, -1.7e308])
        with pytest.raises(SingularStepError):  # non-homogeneous: x + 2εX overflows
            KahanMap(_lv_field(), "1/10", "float").step([1e200, 1e200, 1e200])


def test_numpy_inputs_accepted():
    f = LiePoissonSystem.random(4, seed=2).field("f")
    x = numpy.array([float(t) for t in random_point(4, 2)])
    y = KahanMap(f, "1/40", "float").step(x)
    assert all(type(t) is float for t in y)
    assert KahanMap(f, numpy.float64(1 / 40), "float").step(list(x)) == y
    assert KahanMap(f, "1/40", "float").step(x.astype(numpy.float32)) == y
    assert KahanMap(f, "1/40", "float").step(tuple(numpy.float64(t) for t in x)) == y
    z = KahanMap(f, "1/40", "mp:60").step(list(x))
    assert max(abs(float(a) - b) for a, b in zip(z, y)) < 1e-12
    D = KahanMap(f, "1/40", "float").jacobian(x)
    assert len(D) == 8 and all(type(t) is float for row in D for t in row)


def test_exact_zero_pivot_is_a_singular_step_without_warnings():
    """The float step runs LAPACK quietly: an exactly zero pivot (NaN from the gufuncs) is
    the same SingularStepError (κ = ∞) as before, with no RuntimeWarning from numpy.  The
    case: ε = −1/2 is 1/λ for an eigenvalue λ = −2 of f'(x) (SymPy), so I − εf'(x) is
    exactly singular in binary64 (dyadic entries), and numpy's public solve meets the zero
    pivot too (an independent route); ε = −1/3 is the negative control."""
    import sympy as sp

    s = LiePoissonSystem.from_vectors("-2,1", "0,2", "-1,-1")
    x = [1, 2, 2, 1]
    J = sp.Matrix(s.field("f").jacobian(get_arith("fraction"), [F(t) for t in x]))
    assert (sp.eye(4) + J / 2).det() == 0
    M = numpy.eye(4) + numpy.array(J.tolist(), dtype=float) / 2
    with pytest.raises(numpy.linalg.LinAlgError):
        numpy.linalg.solve(M, numpy.ones(4))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(SingularStepError) as err:
            KahanMap(s.field("f"), -0.5, "float").step(x)
        assert err.value.condition == math.inf
        y = KahanMap(s.field("f"), F(-1, 3), "float").step(x)
    assert all(map(math.isfinite, y))



@pytest.mark.parametrize("q, size", [(Fraction(10) ** 400, 1328), (Fraction(-(10 ** 5000), 3), 16608)])
def test_a_number_beyond_float64_is_refused_by_its_size(q, size):
    """float64 refuses |q| ≥ 2^1024 with InputError naming its size, also where Python refuses
    to print an int of more than 4300 digits (the message used to print q, and failed with
    ValueError there)."""
    import sys

    from exact_khk.errors import InputError

    old = sys.get_int_max_str_digits() if hasattr(sys, "get_int_max_str_digits") else None
    if old is not None:
        sys.set_int_max_str_digits(4300)  # Python's default (the command line lifts it)
    try:
        with pytest.raises(InputError, match=rf"arith float: a number of about 2\^{size} is too large"):
            get_arith("float").convert(q)
    finally:
        if old is not None:
            sys.set_int_max_str_digits(old)
