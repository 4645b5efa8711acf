"""The division in Z[t]/(tⁿ ∓ 1) behind the structured exact step
(:meth:`exact_khk.systems.lie_poisson.circulant.CirculantRing.solve`), against python-flint's dense
``fmpz_mat.solve`` of the n×n circulant (or negacirculant) system (an independent algorithm)."""

import random

import pytest

flint = pytest.importorskip("flint")

from exact_khk.systems.lie_poisson.circulant import UNIT_PRIME, CirculantRing, rational_reconstruction  # noqa: E402
from exact_khk.linalg.dense import SingularMatrix  # noqa: E402


def _poly(rng, n, bits):
    return flint.fmpz_poly([rng.randint(-2 ** bits, 2 ** bits) for _ in range(n)])


def _as_rational(W, delta):
    return [flint.fmpq_poly(w) / delta for w in W]


def _dense_reference(R, d, rhs):
    """(W, δ) from python-flint's ``fmpz_mat.solve`` of the n×n system C(d) W = δ r of
    multiplication by d mod tⁿ − s (tʲ·tᵏ = s·t^{j+k−n} past tⁿ): an algorithm independent
    of the ring's division."""
    n = R.n
    c = d.coeffs() + [0] * (n - d.length())
    C = flint.fmpz_mat(n, n, [c[(i - j) % n] * (R.sign if j > i else 1) for i in range(n) for j in range(n)])
    X = C.solve(flint.fmpz_mat(n, len(rhs), [r[i] for i in range(n) for r in rhs]))
    num, delta = X.numer_denom()
    cols = num.transpose().entries()
    return [flint.fmpz_poly(cols[k * n:(k + 1) * n]) for k in range(len(rhs))], delta


@pytest.fixture(params=["norm", "fixed point"])
def route(request, monkeypatch):
    """Every division of the test by Cramer's rule down the tower, or (but at n = 1) by the
    fixed-point division."""
    from exact_khk.systems.lie_poisson import circulant as C

    bits = 0 if request.param == "fixed point" else 10 ** 9
    for name in ("DIVISION_BY_NORM_MAX_BITS", "DIVISION_BY_NORM_MAX_WORK"):
        monkeypatch.setattr(C, name, bits)
    return request.param


def _check(R, d, rhs):
    W, delta = R.solve(d, rhs)
    assert delta > 0
    for w, r in zip(W, rhs):
        assert R.mul(d, w) == r * delta  # the defining equation, exactly
    ref_W, ref_delta = _dense_reference(R, d, rhs)
    assert _as_rational(W, delta) == _as_rational(ref_W, ref_delta)
    return W, delta


@pytest.mark.parametrize("sign", [1, -1])
@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 8, 12, 17])
def test_solve_equals_dense_circulant_solve(n, sign, route):
    rng = random.Random(n)
    R = CirculantRing(n, sign)
    checked = 0
    for bits in (1, 8, 64, 300):
        for _ in range(3):
            d = _poly(rng, n, bits)
            if d.gcd(R._zmodulus).degree() != 0:
                continue  # not a unit: covered below
            _check(R, d, [_poly(rng, n, bits), _poly(rng, n, rng.randint(1, 2 * bits))])
            checked += 1
    assert checked >= 8


@pytest.mark.parametrize("sign", [1, -1])
@pytest.mark.parametrize("n", [1, 2, 3, 4, 6, 8, 9, 11, 12, 15, 16, 17, 21, 23, 30, 32, 45, 47])
def test_norm_is_the_resultant(n, sign):
    """d·A = N in Z[t]/(tⁿ − s); N is 0 exactly when Res(d, tⁿ − s) is (FLINT's resultant,
    another algorithm), i.e. for the non-units, and divides it for n a power of 2 (the tower
    keeps N and A in lowest terms).  Where the tower ends at an odd b > 1 (the Galois
    conjugates), N divides b times an lcm of powers of the norms there, not Res in general."""
    rng = random.Random(100 + n)
    R = CirculantRing(n, sign)
    # a multiple of each irreducible factor of tⁿ − s (a cyclotomic one: d vanishes at its roots)
    factors = [f for f, _ in R._zmodulus.factor()[1]]
    units = [_poly(rng, n, bits) for bits in (1, 5, 60, 200)]
    non_units = [flint.fmpz_poly([0])] + [R.mul(f, _poly(rng, n, 30)) for f in factors]
    for d in units + non_units:
        N, A = R.norm(d)
        res = d.resultant(R._zmodulus)
        assert (N == 0) == (res == 0)
        if N:
            assert res % N == 0 or n & (n - 1)
            assert (A if A is not None else flint.fmpz_poly([1])).content().gcd(N) == 1  # lowest terms
            assert R.mul(d, A if A is not None else flint.fmpz_poly([1])) == N
    assert all(R.norm(d)[0] == 0 for d in non_units) and sum(R.norm(d)[0] != 0 for d in units) >= 3


def test_fixed_point_division_over_the_negacyclic_ring(monkeypatch):
    """Over Z[t]/(tⁿ + 1) (the factor the exact step splits off) the fixed-point division
    starts from d's values at the roots of tⁿ + 1 (a twisted DFT): it answers without the
    fallback, whatever the hint, and equals the dense negacirculant solve; the DFT of the
    cyclic ring in its place does not converge to d⁻¹ (the negative control)."""
    from exact_khk.systems.lie_poisson import circulant as C

    rng = random.Random(12)
    n = 16
    d = _poly(rng, n, 4600) + flint.fmpz_poly([2 ** 4610])  # a unit: |d(ζ)| ≈ 2^4610 everywhere
    rhs = [_poly(rng, n, 2300), _poly(rng, n, 1500)]
    assert not C.by_norm(n, C._hadamard_bits(n, d.height_bits(), 2300))
    monkeypatch.setattr(C.CirculantRing, "_solve_norm", None)  # the fallback is not taken
    answers = []
    for ratio in (0.0, 1.0, 1e9, None):
        R = CirculantRing(n, -1)
        R.height_ratio = ratio
        answers.append(_as_rational(*_check(R, d, rhs)))
    assert answers[0] == answers[1] == answers[2] == answers[3]
    # control: without the twist the start approximates the inverse mod tⁿ − 1, and Newton's
    # iteration mod tⁿ + 1 does not converge from it
    class FellBack(Exception):
        pass

    def fallback(self, d, rhs):
        raise FellBack

    monkeypatch.setattr(C.CirculantRing, "_solve_norm", fallback)
    R = CirculantRing(n, -1)
    R.twist = lambda prec: [flint.acb(1)] * n
    with pytest.raises(FellBack):
        R.solve(d, rhs)


def test_precision_search_does_not_depend_on_the_hint(route):
    """The starting precision is a hint (the last answer's height); a hint far too
    small or too large changes the work, not the answer."""
    rng = random.Random(7)
    n = 6
    d, rhs = _poly(rng, n, 40), [_poly(rng, n, 40), _poly(rng, n, 5)]
    answers = []
    for ratio in (None, 0.0, 1.0, 1e9):
        R = CirculantRing(n)
        R.height_ratio = ratio
        answers.append(_as_rational(*_check(R, d, rhs)))
    assert answers[0] == answers[1] == answers[2] == answers[3]


def test_fixed_point_division_with_hints_far_off(monkeypatch):
    """The same on the fixed-point path (Cramer's bound above the rule of ``by_norm``).
    A hint that is too small fails its first attempt, which then asks d's values at the
    roots of unity for a bound (``answer_bits``) and tries again.  Along an orbit the hint
    holds and the bound is never asked for."""
    from fractions import Fraction

    from exact_khk import KahanMap, LiePoissonSystem
    from exact_khk.systems.lie_poisson import circulant as C
    from exact_khk.systems.lie_poisson.system import random_point

    rng = random.Random(11)
    n = 16
    d = _poly(rng, n, 4600) + flint.fmpz_poly([2 ** 4610])  # a unit: d(ω) ≈ 2^4610 everywhere
    rhs = [_poly(rng, n, 2300), _poly(rng, n, 1500)]
    assert not C.by_norm(n, C._hadamard_bits(n, d.height_bits(), 2300))
    bounds = []
    answer_bits = C._Reciprocal.answer_bits
    monkeypatch.setattr(C._Reciprocal, "answer_bits", lambda self, hr: bounds.append(hr) or answer_bits(self, hr))
    inverse = C.CirculantRing._solve_norm
    monkeypatch.setattr(C.CirculantRing, "_solve_norm", None)  # the fallback is not taken
    answers = []
    for ratio in (0.0, 1.0, 1e9, None):
        bounds.clear()
        R = CirculantRing(n)
        R.height_ratio = ratio
        answers.append(_as_rational(*_check(R, d, rhs)))
        assert bounds or ratio != 0.0
    assert answers[0] == answers[1] == answers[2] == answers[3]

    monkeypatch.setattr(C.CirculantRing, "_solve_norm", inverse)  # for the first step's small answer
    phi = KahanMap(LiePoissonSystem.random(n, seed=1).field("f"), Fraction(1, 10), "flint", method="structured")
    dense = KahanMap(phi.field, phi.eps, "flint", method="dense")
    x = phi.step(random_point(n, 1))
    bounds.clear()
    for _ in range(2):
        y = phi.step(x)
        assert y == dense.step(x)
        x = y
    assert bounds == []


@pytest.mark.parametrize("n", [2, 3, 4, 6])
def test_non_units_raise(n, route):
    R = CirculantRing(n)
    t = flint.fmpz_poly([0, 1])
    rhs = [flint.fmpz_poly([1, 2]), flint.fmpz_poly([3])]
    singular = [flint.fmpz_poly([0]), R.mul(t - 1, flint.fmpz_poly([5, -2, 7]))]  # d(1) = 0
    if n % 2 == 0:
        singular.append(t + 1)  # d(−1) = 0
    for d in singular:
        with pytest.raises(SingularMatrix):
            R.solve(d, rhs)
        with pytest.raises(ZeroDivisionError):  # control: the dense solve agrees it is singular
            _dense_reference(R, d, rhs)


def test_units_that_are_not_units_mod_the_test_prime():
    """d = t − 1 + c is a unit of Q[t]/(tⁿ − 1) (d(ω) = ω − 1 + c ≠ 0) but not mod a
    prime dividing c: the gcd over Z decides, and the division goes on."""
    n = 5
    R = CirculantRing(n)
    t = flint.fmpz_poly([0, 1])
    rhs = [flint.fmpz_poly([1, -4, 2, 0, 9])]
    for c in (UNIT_PRIME, 3 * UNIT_PRIME):
        _check(R, t - 1 + c, rhs)


@pytest.mark.parametrize("n", [2, 4, 7, 16])
def test_ill_conditioned_units(n, route):
    """d with |d(ω)| tiny at a root of unity against its size (the floating start of
    the Newton iteration then fails until it is widened): still the exact answer."""
    rng = random.Random(n)
    R = CirculantRing(n)
    t = flint.fmpz_poly([0, 1])
    for k in (100, 400, 2000):
        # d(1) = 1 while the coefficients have k bits: |d⁻¹| ≈ 2^k
        d = R.mul(t - 1, _poly(rng, n, k)) + 1
        _check(R, d, [_poly(rng, n, 50), _poly(rng, n, k)])


def test_rational_reconstruction():
    rng = random.Random(5)
    m = flint.fmpz(UNIT_PRIME) ** 3
    limit = int((m // 2).isqrt())
    for _ in range(200):
        num, den = rng.randint(-limit, limit), rng.randint(1, limit)
        g = flint.fmpz(num).gcd(den)
        num, den = num // int(g), den // int(g)
        a = num * pow(den, -1, int(m)) % int(m)
        assert rational_reconstruction(flint.fmpz(a), m) == (num, den)


@pytest.mark.parametrize("n", [256, 320])
def test_orbit_steps_need_no_dense_fallback(n, monkeypatch):
    """Along an orbit the fixed-point division answers on its own: Cramer's rule down the
    tower is a fallback for numerics out of reach (and the route of small Cramer bounds,
    :func:`~exact_khk.systems.lie_poisson.circulant.by_norm`: here the first step, whose small point
    is solved unsplit, and the small factors of tⁿ − 1 the later steps split off), and a precision search that gives up early (as a first step with
    answers of ~n·hd bits once did for n ≥ 32) would send every first step there.  The
    first answer is checked against the fallback's."""
    from fractions import Fraction

    from exact_khk import get_arith
    from exact_khk.systems.lie_poisson import circulant as C
    from exact_khk.systems.lie_poisson.system import LiePoissonSystem, random_point

    st = C.circulant_structure(LiePoissonSystem.random(n, seed=3).field("f"))
    ar = get_arith("flint")
    x, eps = [ar(t) for t in random_point(n, 3)], ar(Fraction(1, 10))
    fallback = C.CirculantRing._solve_norm
    calls = []

    def refuse(self, d, rhs):
        hr = max(r.height_bits() for r in rhs)
        if not C.by_norm(self.n, C._hadamard_bits(self.n, d.height_bits(), hr)):
            calls.append((self.n, self.sign))  # a fallback, not the route of small bounds
        return fallback(self, d, rhs)

    monkeypatch.setattr(C.CirculantRing, "_solve_norm", refuse)
    C.circulant_ring.cache_clear()
    first = x = C.exact_step(st, x, eps, ar)
    for _ in range(2):
        x = C.exact_step(st, x, eps, ar)
    assert calls == []
    # control: the first step again with every division sent to the fixed-point one
    # (no route of small bounds) and made to miss, so that it falls back
    for name in ("DIVISION_BY_NORM_MAX_BITS", "DIVISION_BY_NORM_MAX_WORK"):
        monkeypatch.setattr(C, name, 0)
    monkeypatch.setattr(C.CirculantRing, "_attempt", lambda *args: None)
    C.circulant_ring.cache_clear()
    x0 = [ar(t) for t in random_point(n, 3)]
    assert C.exact_step(st, x0, eps, ar) == first and calls


def test_certificate_divisions_need_no_bound(monkeypatch):
    """The divisions of a certificate (Kahan steps, H̃, the J((x + x̃)/2) solves of the
    definition checks) start from a precision their last answer justifies and never miss
    it: the bound read off d's values is not asked for.  With the hint capped at 1.25 the
    definition solves (answers ≈ 1.33× d's height) missed 19 times here, each miss then
    costing an attempt at the bound's 6× precision (5edf94a to e329474)."""
    from exact_khk import LiePoissonSystem, certify
    from exact_khk.systems.lie_poisson import circulant as C
    from exact_khk.systems.lie_poisson.system import random_point

    asked = []
    answer_bits = C._Reciprocal.answer_bits
    monkeypatch.setattr(C._Reciprocal, "answer_bits", lambda self, hr: asked.append(hr) or answer_bits(self, hr))
    system = LiePoissonSystem.random(8, 1)
    cert = certify(system, random_point(8, 1, system=system), steps=14)
    assert cert.status == "VALID" and asked == []


@pytest.mark.parametrize("n", [2, 6, 8, 12, 16])
def test_split_divide_equals_dense_circulant_solve(n):
    """``split_divide`` (the division over each factor of tⁿ − 1, each part divided by its
    content first) gives the quotients of python-flint's dense circulant solve, for d
    and right-hand sides with common factors and a zero right-hand side; a d that
    vanishes at a root of unity is refused like ``CirculantRing.solve`` refuses it."""
    from exact_khk.systems.lie_poisson.circulant import split_divide

    rng = random.Random(50 + n)
    R = CirculantRing(n)
    checked = 0
    for bits in (1, 30, 200):
        for _ in range(3):
            d = _poly(rng, n, bits) * rng.randint(1, 50)
            if d.gcd(R._zmodulus).degree() != 0:
                continue
            rhs = [_poly(rng, n, bits) * 6, _poly(rng, n, 2 * bits), flint.fmpz_poly([])]
            W, delta = split_divide(R, d, rhs)
            ref_W, ref_delta = _dense_reference(R, d, rhs)
            assert _as_rational(W, delta) == _as_rational(ref_W, ref_delta)
            checked += 1
    assert checked >= 6
    # control: a non-unit (d(1) = 0 for d = t − 1) is refused, by the part over t − 1
    with pytest.raises(SingularMatrix):
        split_divide(R, flint.fmpz_poly([-1, 1]), [flint.fmpz_poly([1])])


def test_division_rule_as_documented():
    """``by_norm`` is the rule of the table in ``systems.lie_poisson.paths``: the tower while
    H ≤ DIVISION_BY_NORM_MAX_BITS and b·H ≤ DIVISION_BY_NORM_MAX_WORK, b the odd part of m,
    always at m = 1."""
    from exact_khk.systems.lie_poisson.circulant import by_norm
    from exact_khk.systems.lie_poisson.paths import DIVISION_BY_NORM_MAX_BITS as BITS, DIVISION_BY_NORM_MAX_WORK as WORK

    assert by_norm(1, 10 ** 9) and by_norm(256, BITS) and not by_norm(256, BITS + 1)
    assert by_norm(2, BITS) and not by_norm(8, BITS + 1) and WORK >= BITS
    assert by_norm(12, WORK // 3) and not by_norm(12, WORK // 3 + 1) and by_norm(3, WORK // 3)
    assert by_norm(11, WORK // 11) and not by_norm(88, WORK // 11 + 1) and not by_norm(15, WORK // 15 + 1)
