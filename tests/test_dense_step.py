"""The dense exact step over Z (QuadraticField.integer_system + kernel columns):
equal (==) to the plain Fraction elimination, for steps, orbits kept as kernel
columns, non-homogeneous fields, and singular steps inside an orbit."""

import random
from fractions import Fraction as F

import pytest
import sympy as sp

from exact_khk import InputError, KahanMap, LiePoissonSystem, SingularStepError, get_arith
from exact_khk.kahan import map as kahan
from exact_khk.kahan.map import SMALL_ANSWER_MIN_BITS
from exact_khk.systems.quadratic import QuadraticField
from exact_khk.systems.lie_poisson.system import random_point

from .conftest import EXACT

FAST = [a for a in EXACT if a != "fraction"]  # the arithmetics with an integer kernel
FR = get_arith("fraction")


def _affine_field():
    """A non-homogeneous field with fractional quadratic, linear and constant parts."""
    T = [[[F(1, 3), F(-2, 5), 0], [0, 0, F(7, 2)], [1, 0, 0]],
         [[0, F(1, 2), 0], [F(-1, 7), 0, F(2, 3)], [0, 0, -1]],
         [[F(5, 4), 0, 0], [0, F(-3, 2), 0], [0, F(1, 9), F(1, 6)]]]
    return QuadraticField.from_tensor(T, linear=[[0, F(1, 2), 0], [-1, 0, F(3, 4)], [0, 0, F(-2, 3)]],
                                      const=[F(1, 5), 0, F(-7, 3)], label="affine")


def _fields():
    out = [_affine_field()]
    for n in range(2, 9):
        s = LiePoissonSystem.random(n, seed=10 + n)
        out += [s.field("f"), s.field("g")]
    return out


def _point(rng, dim, height=30):
    return [F(rng.getrandbits(height) - 2 ** (height - 1), rng.getrandbits(height) | 1) for _ in range(dim)]


def _as_fractions(ar, pts):
    return [[ar.to_fraction(t) for t in p] for p in pts]


def test_affine_field_is_not_homogeneous():
    assert not _affine_field().homogeneous


@pytest.mark.parametrize("arith", FAST)
def test_square_tensor_keeps_each_distinct_row_once(arith):
    """The system's N² rows are stored once per distinct row: a Lie–Poisson field's
    four circulant blocks leave at most 4n (n per block), and the count agrees
    with the distinct rows of the Hessian itself."""
    K = get_arith(arith).integers
    for n in (2, 3, 5):
        fld = LiePoissonSystem.random(n, seed=n).field("f")
        H, L, _, _ = fld._rational_jacobian()
        rows = {tuple(H[i][j]) + (int(i == j),) for i in range(2 * n) for j in range(2 * n)}
        (_, index, N) = fld.integer_system(K, 1, 10)[0]
        assert N == 2 * n and len(index) == N * N
        assert max(index) + 1 == len(rows) <= 4 * n


@pytest.mark.parametrize("arith", FAST)
def test_integer_system_is_the_scaled_kahan_system(arith):
    """V·v = vec(D(I − εf'(x))) and R·v = D((I + εL)x + 2εc), D = q·den·dx, entry by entry
    against the Fraction system matrix and f(x) (for the affine field and a Lie–Poisson one)."""
    K = get_arith(arith).integers
    for fld in (_affine_field(), LiePoissonSystem.random(3, seed=1).field("g")):
        x = _point(random.Random(1), fld.dim)
        eps = F(-3, 7)
        V, R = fld.integer_system(K, -3, 7)
        v = K.clear(K.column([get_arith(arith)(t) for t in x]))
        M, b = K.square(V, v), K.product(R, v)
        xi, dx = K.split([get_arith(arith)(t) for t in x])
        M_ref = KahanMap(fld, eps, "fraction").system_matrix(x)
        # D·(I − εf'(x)) x + 2εD·f(x) = D((I + εL)x + 2εc): the right-hand side from f itself
        fx = fld.evaluate(FR, x)
        rhs = [sum(M_ref[i][j] * x[j] for j in range(fld.dim)) + 2 * eps * fx[i] for i in range(fld.dim)]
        rows = [[F(int(t)) for t in row] for row in (M.tolist() if hasattr(M, "tolist") else M)]
        b = [F(int(t[0])) for t in (b.tolist() if hasattr(b, "tolist") else b)]
        scales = {rows[i][j] / M_ref[i][j] for i in range(fld.dim) for j in range(fld.dim) if M_ref[i][j]}
        assert len(scales) == 1  # one common integer factor D
        D = scales.pop()
        assert D.denominator == 1 and D % (7 * int(dx)) == 0  # D = q·den·dx
        assert rows == [[D * t for t in r] for r in M_ref]
        assert b == [D * t for t in rhs]


@pytest.mark.parametrize("arith", FAST)
def test_dense_steps_equal_fraction_elimination(arith):
    """n = 2..8 (fields f and g) and the affine field: step and inverse, == the Fraction reference."""
    ar, rng = get_arith(arith), random.Random(5)
    for fld in _fields():
        x = _point(rng, fld.dim)
        ref = KahanMap(fld, "2/11", "fraction").step(x)
        phi = KahanMap(fld, "2/11", arith, method="dense")
        y = phi.step(x)
        assert [ar.to_fraction(t) for t in y] == list(ref)
        assert phi.step([str(t) for t in x]) == y  # parsed and ready-made points agree
        assert phi.inverse(y) == phi.point(x)


@pytest.mark.parametrize("arith", FAST)
def test_dense_orbits_equal_fraction_elimination(arith):
    """20-step orbits (n = 2, 3), 4-step orbits up to n = 8 and 5 steps of the affine field
    (its heights triple per step): the state kept as a kernel column between steps gives
    exactly the Fraction orbit."""
    ar, rng = get_arith(arith), random.Random(6)
    for fld in _fields():
        steps = 5 if not fld.homogeneous else 20 if fld.dim <= 6 else 4
        x = _point(rng, fld.dim, height=8)
        ref = KahanMap(fld, "1/7", "fraction").orbit(x, steps)
        got = KahanMap(fld, "1/7", arith, method="dense").orbit(x, steps)
        assert _as_fractions(ar, got) == [list(p) for p in ref]


def test_flint_and_bareiss_agree_on_long_orbit():
    """python-flint fmpz_mat.solve and gmpy2 Bareiss along 20 steps at n = 8."""
    if not {"flint", "gmpy2"} <= set(EXACT):
        pytest.skip("needs python-flint and gmpy2")
    fld = LiePoissonSystem.random(8, seed=3).field("f")
    x = _point(random.Random(7), fld.dim, height=4)
    a = KahanMap(fld, "1/10", "flint", method="dense").orbit(x, 20)
    b = KahanMap(fld, "1/10", "gmpy2", method="dense").orbit(x, 20)
    assert _as_fractions(get_arith("flint"), a) == _as_fractions(get_arith("gmpy2"), b)


def _singular_orbit(fld, candidates):
    """(x0, y, ε): det(I − εf'(y)) = 0 for a rational ε ≠ 0 (SymPy's rational eigenvalues
    of f'(y), checked again with a SymPy determinant) and x0 = Φ^{-2}(y), whose first two
    (Fraction) steps are defined and reach y."""
    lam = sp.Symbol("lam")
    for y in candidates:
        Jf = sp.Matrix(fld.jacobian(FR, y)).applyfunc(sp.Rational)
        for root in sp.roots(Jf.charpoly(lam).as_expr(), lam, filter="Q"):
            if root == 0:
                continue
            eps = F(int(sp.numer(1 / root)), int(sp.denom(1 / root)))
            assert (sp.eye(fld.dim) - sp.Rational(eps.numerator, eps.denominator) * Jf).det() == 0
            phi = KahanMap(fld, eps, "fraction")
            try:
                x0 = phi.inverse(phi.inverse(y))
                if phi.orbit(x0, 2)[-1] == tuple(y):
                    return x0, y, eps
            except SingularStepError:
                continue
    raise AssertionError("no singular orbit from these points")


@pytest.mark.parametrize("arith", EXACT)
@pytest.mark.parametrize("which", ["lie-poisson", "affine"])
def test_singular_step_inside_orbit(arith, which):
    """x0 = Φ^{-2}(y) with the step at y singular: the orbit fails at step 3 with the point
    y and ε; the first two steps are fine and reach y (negative control)."""
    rng = random.Random(2)
    if which == "affine":
        fld = _affine_field()
    else:
        fld = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3").field("f")
    cands = [[F(rng.randint(-3, 3)) for _ in range(fld.dim)] for _ in range(200)]
    x0, y, eps = _singular_orbit(fld, cands)
    phi = KahanMap(fld, eps, arith, method="dense")
    ar = phi.arith
    assert _as_fractions(ar, phi.orbit(x0, 2))[-1] == y
    with pytest.raises(SingularStepError) as info:
        phi.orbit(x0, 5)
    err = info.value
    assert err.step == 3 and err.x == [str(t) for t in y] and err.eps == str(eps)
    assert "step 3" in str(err)
    with pytest.raises(SingularStepError) as info:
        phi.step(y)
    assert info.value.step is None and info.value.x == [str(t) for t in y]


@pytest.mark.parametrize("arith", EXACT)
def test_ready_made_point_of_wrong_dimension_is_refused(arith):
    ar = get_arith(arith)
    phi = KahanMap(LiePoissonSystem.random(2, seed=1).field("f"), "1/10", arith)
    with pytest.raises(InputError, match="expected 4 coordinates"):
        phi.step((ar(1), ar(2), ar(3)))


def test_orbit_solves_small_answers_output_sensitively(monkeypatch):
    """Along an orbit at n = 5 (N = 10) the dense flint step tells the solver that
    the answer is small once the height passes SMALL_ANSWER_MIN_BITS (python-flint
    then runs Dixon's solve); the first step, with no history, never does.  The
    orbit equals the gmpy2 Bareiss orbit (an independent solver) with ==."""
    if not {"flint", "gmpy2"} <= set(EXACT):
        pytest.skip("needs python-flint and gmpy2")
    K = get_arith("flint").integers
    flags, solve = [], K.solve_column

    def spy(M, b, small=False):
        flags.append(small)
        return solve(M, b, small)

    monkeypatch.setattr(K, "solve_column", spy)
    fld = LiePoissonSystem.random(5, seed=1).field("f")
    x = random_point(5, 1)
    phi = KahanMap(fld, "1/10", "flint", method="dense")
    a = phi.orbit(x, 16)
    b = KahanMap(fld, "1/10", "gmpy2", method="dense").orbit(x, 16)
    assert _as_fractions(get_arith("flint"), a) == _as_fractions(get_arith("gmpy2"), b)
    assert len(flags) == 16 and not flags[0] and sum(flags) >= 8
    heights = [max(max(abs(t.p).bit_length(), t.q.bit_length()) for t in p) for p in a]
    assert all(small == (SMALL_ANSWER_MIN_BITS <= heights[k] < 2 * heights[k - 1])
               for k, small in enumerate(flags) if k > 0)  # heights far below DIXON_BITS·(N − 6)
    gm = KahanMap(fld, "1/10", "gmpy2", method="dense")
    same = lambda p, q: _as_fractions(get_arith("flint"), [p]) == _as_fractions(get_arith("gmpy2"), [q])  # noqa: E731
    # the map remembers: a single step at an orbit point is solved as small ...
    assert same(phi.step(a[-1]), gm.step(b[-1])) and flags[-1] is True
    # ... until an answer of Cramer's size (a random 200-bit point) switches it off
    tall = _point(random.Random(5), fld.dim, height=200)
    y, z = phi.step(tall), phi.step(tall)
    assert y == z and same(y, gm.step(tall))
    assert flags[-2:] == [True, False]


def test_output_sensitive_solve_refuses_singular_systems():
    """The Dixon branch raises the ZeroDivisionError the orbit turns into a
    SingularStepError, like fmpz_mat.solve (negative control: a regular system)."""
    K = get_arith("flint").integers
    flint = pytest.importorskip("flint")
    N = 8
    M = flint.fmpz_mat([[i * N + j + 1 for j in range(N)] for i in range(N)])  # rank 2
    b = flint.fmpz_mat(N, 1, list(range(N)))
    for small in (False, True):
        with pytest.raises(ZeroDivisionError):
            K.solve_column(M, b, small)
    A = M + flint.fmpz_mat([[int(i == j) * (i + 1) ** 3 for j in range(N)] for i in range(N)])
    assert A * K.solve_column(A, b, True) == b


def test_dense_orbit_stops_dixon_above_its_crossover(monkeypatch):
    """Above DIXON_BITS·(N − 6) bits the dense flint orbit step goes back to
    ``fmpz_mat.solve`` (Dixon loses there); here the threshold is lowered so that
    a short orbit at n = 5 (N = 10) crosses it.  The orbit is unchanged."""
    K = get_arith("flint").integers
    flags, solve = [], K.solve_column
    monkeypatch.setattr(K, "solve_column", lambda M, b, small=False: flags.append(small) or solve(M, b, small))
    monkeypatch.setattr(kahan, "DIXON_BITS", 100)  # N = 10: Dixon from 128 to 400 bits
    fld, x = LiePoissonSystem.random(5, seed=1).field("f"), random_point(5, 1)
    a = KahanMap(fld, "1/10", "flint", method="dense").orbit(x, 16)
    assert a == KahanMap(fld, "1/10", "flint", method="split").orbit(x, 16)
    heights = [max(max(abs(t.p).bit_length(), t.q.bit_length()) for t in p) for p in a]
    assert flags[1:] == [SMALL_ANSWER_MIN_BITS <= heights[k] < 400 and heights[k] < 2 * heights[k - 1]
                         for k in range(1, 16)]
    assert any(flags) and heights[15] >= 400 and not flags[-1]
