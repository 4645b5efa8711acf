"""Kahan steps and H̃ as 2×2 systems over circulants (MATH.md, "Structure worth exploiting").

For a Lie–Poisson field f(x) = J(x) M x whose Hessian M has four cyclic Hankel
n×n blocks (f, every associated field g and the control field do), all four
blocks of f'(x) are circulant.  Circulants form the commutative ring
R = Q[t]/(tⁿ − 1) (P ↔ t), so I − εf'(x) is a 2×2 matrix over R and a Kahan
step is a few products in R and one inversion in R.

Dictionary (0-based, as in MATH.md):

* a vector w ∈ Qⁿ ↔ its *reflected* polynomial ŵ(t) = Σ_i w_i t^{−i}; then
  P w ↔ t ŵ, so a circulant Σ_m c_m P^m acts as multiplication by c(t);
* a Hankel block X(w) (first row w) times X(u) is the circulant of
  w(t)·û(t); the Jacobian blocks are (y = Mx, y_u ↔ Y_u = m11 û + m12 v̂, …)

      f'(x) = [[ û m21 + Y_v,   û m22 ],
               [ −û m11 − Y_u,  −û m12 ]]

  with m_kl(t) the polynomial of the first row of the Hankel block M_kl.

Exact step: the 2×2 system is solved by Cramer's rule in R; division by the
determinant D ∈ R is one n×n circulant solve over Z (D is a unit of R ⟺
D(ω) ≠ 0 at every n-th root of unity ω ⟺ det(I − εf'(x)) = Π_ω D(ω) ≠ 0 ⟺
the step is defined).
Floating step: the DFT splits R ⊗ C into n copies of C, so the step is n
independent 2×2 complex systems, solved in python-flint ball arithmetic at
the arithmetic's precision plus guard bits; the ball radius bounds the error.

>>> from exact_khk import LiePoissonSystem, get_arith
>>> s = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")
>>> st = circulant_structure(s.field("g"))
>>> st.n
3
>>> ar = get_arith("flint")
>>> x = [ar(t) for t in (1, 0, 0, 0, 1, 0)]
>>> z = exact_step(st, x, ar(Fraction(1, 10)))
>>> [str(t) for t in z[:2]]
['88225/158249', '-18465/158249']
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache

from .arith import _as_fraction
from .errors import InputError
from .linalg import SingularMatrix

try:  # python-flint is optional: without it the dense path is used
    import flint
except ImportError:  # pragma: no cover
    flint = None

#: guard bits added to the arithmetic's precision in the DFT (ball) step
GUARD_BITS = 20


@dataclass(frozen=True)
class CirculantStructure:
    """The Hankel first rows m11, m12, m21, m22 (Fractions) of a field's Hessian M."""

    n: int
    m: tuple  # ((m11, m12), (m21, m22)), each a tuple of n Fractions


def hankel_first_row(block):
    """w (as Fractions) if ``block[i][j] == w[(i + j) % n]`` for all i, j (a cyclic
    Hankel matrix with rational entries), else None."""
    n = len(block)
    try:
        w = tuple(_as_fraction(t) for t in block[0])
    except (TypeError, ValueError, ArithmeticError):  # e.g. cyclotomic entries
        return None
    if all(block[i][j] == w[(i + j) % n] for i in range(n) for j in range(n)):
        return w
    return None


def circulant_structure(field):
    """The :class:`CirculantStructure` of a Lie–Poisson field, or None.

    None for fields without a system and Hessian (a generic
    :class:`~exact_khk.quadratic.QuadraticField`), non-homogeneous fields, or a
    Hessian with a block that is not cyclic Hankel.  Cached on the field.
    """
    cache = getattr(field, "_cache", None)
    if cache is not None and "circulant" in cache:
        return cache["circulant"]
    out = None
    system, M = getattr(field, "system", None), getattr(field, "hessian", None)
    if system is not None and M and field.homogeneous and len(M) == 2 * system.n:
        n = system.n
        rows = [[hankel_first_row([r[bj * n:(bj + 1) * n] for r in M[bi * n:(bi + 1) * n]])
                 for bj in range(2)] for bi in range(2)]
        if all(w is not None for r in rows for w in r):
            out = CirculantStructure(n, tuple(tuple(r) for r in rows))
    if cache is not None:
        cache["circulant"] = out
    return out


def structure_from_system(system, kind="f", signs=None, power=0) -> CirculantStructure:
    """The structure of ``system.field(kind, signs, power)`` computed from the vectors a, b, c
    alone, in O(n²) (building the field itself costs O((2n)³) memory).

    First rows: A^p X(w) = X(w shifted by p); B X(w) = X(Σ_k α_k w shifted by k).
    """
    from .systems import b0_signs, involution_circulant

    n = system.n

    def left(coeffs, w):  # first row of (Σ_k coeffs[k] P^k) X(w)
        return tuple(sum((c * w[(j + k) % n] for k, c in enumerate(coeffs) if c), Fraction(0))
                     for j in range(n))

    unit = lambda k: [Fraction(int(i == k % n)) for i in range(n)]  # noqa: E731
    if kind == "f":
        coeffs = unit(power)
    elif kind == "g":
        coeffs = involution_circulant(n, signs if signs is not None else b0_signs(n))
    elif kind == "control":
        coeffs = unit(1) if n >= 3 else [2 * a + b for a, b in zip(unit(0), unit(1))]
    else:
        raise InputError(f"field: unknown kind {kind!r}; expected 'f', 'g' or 'control'")
    a, b, c = system.a, system.b, system.c
    return CirculantStructure(n, ((left(coeffs, a), left(coeffs, b)), (left(coeffs, b), left(coeffs, c))))


def reflect(w):
    """Coefficients of ŵ(t) = Σ w_i t^{−i} mod tⁿ − 1 (an involution)."""
    n = len(w)
    return [w[-i % n] for i in range(n)]


def kahan_system(m, uh, vh, eps, mul):
    """The 2×2 matrix I − εf'(x) and right-hand side x̂ over a commutative ring.

    ``m`` the Hankel polynomials, ``uh, vh`` the reflected u, v, ``mul`` the
    ring product (reducing mod tⁿ − 1, or plain products at one frequency).
    """
    (m11, m12), (m21, m22) = m
    yu, yv = mul(m11, uh) + mul(m12, vh), mul(m21, uh) + mul(m22, vh)
    f11, f12 = mul(uh, m21) + yv, mul(uh, m22)
    f21, f22 = -mul(uh, m11) - yu, -mul(uh, m12)
    return (1 - eps * f11, -eps * f12, -eps * f21, 1 - eps * f22), (uh, vh)


def htilde_system(m, u, v, eps, mul):
    """The 2×2 matrix I − ε²(M J(x))² and right-hand side (M x)^ over a ring.

    M J(x) = [[−M12 X(u), M11 X(u)], [−M22 X(u), M21 X(u)]] and
    X(w) X(u) ↔ ŵ(t) u(t), so with reflected Hankel polynomials m̂_kl and the
    *plain* polynomials u, v everything is a circulant.
    """
    (m11, m12), (m21, m22) = m
    s11, s12, s21, s22 = -mul(m12, u), mul(m11, u), -mul(m22, u), mul(m21, u)
    e2 = eps * eps
    q11 = mul(s11, s11) + mul(s12, s21)
    q12 = mul(s11, s12) + mul(s12, s22)
    q21 = mul(s21, s11) + mul(s22, s21)
    q22 = mul(s21, s12) + mul(s22, s22)
    rhs = (mul(m11, u) + mul(m12, v), mul(m21, u) + mul(m22, v))
    return (1 - e2 * q11, -e2 * q12, -e2 * q21, 1 - e2 * q22), rhs


def cramer(a, r, mul, divide):
    """Solve [[a11, a12], [a21, a22]] z = r over a commutative ring by Cramer's rule;
    ``divide(det, (r0, r1))`` → (r0/det, r1/det), raising
    :class:`~exact_khk.linalg.SingularMatrix` when det is not a unit."""
    a11, a12, a21, a22 = a
    det = mul(a11, a22) - mul(a12, a21)
    return divide(det, (mul(a22, r[0]) - mul(a12, r[1]), mul(a11, r[1]) - mul(a21, r[0])))


# --- exact: R = Q[t]/(tⁿ − 1) with python-flint fmpq_poly -------------------


class CirculantRing:
    """Q[t]/(tⁿ − 1) with elements ``fmpq_poly`` of degree < n.

    Division by a unit D solves the n×n circulant system C(D) w = r over Z
    with python-flint's ``fmpz_mat.solve`` (p-adic lifting, whose cost follows
    the size of the *answer*: along Kahan orbits D⁻¹ itself is far larger
    than D⁻¹ r, so inverting D by an extended gcd is much slower).
    """

    def __init__(self, n):
        if flint is None:  # pragma: no cover
            raise ImportError("the structured exact step needs python-flint")
        self.n, self._hankel = n, {}
        self.modulus = flint.fmpq_poly([-1] + [0] * (n - 1) + [1])

    def mul(self, a, b):
        return (a * b) % self.modulus

    def divide(self, d, rhs):
        """(r/d for r in rhs); :class:`SingularMatrix` if d is not a unit (d(ω) = 0 for
        some n-th root of unity ω, i.e. gcd(d, tⁿ − 1) ≠ 1)."""
        n = self.n
        num, den = d.numer(), d.denom()
        C = flint.fmpz_mat(n, n, [num[(i - j) % n] for i in range(n) for j in range(n)])
        parts = [(r * den).numer() for r in rhs], [(r * den).denom() for r in rhs]
        common = parts[1][0]
        for q in parts[1][1:]:
            common = common * q // common.gcd(q)
        B = flint.fmpz_mat(n, len(rhs), [p[i] * (common // q) for i in range(n)
                                         for p, q in zip(*parts)])
        try:
            X = C.solve(B)
        except ZeroDivisionError:
            raise SingularMatrix("the 2x2 determinant vanishes at a root of t^n - 1") from None
        cols = X.transpose().entries()
        return tuple(flint.fmpq_poly(cols[k * n:(k + 1) * n]) / common for k in range(len(rhs)))

    def poly(self, coeffs):
        return flint.fmpq_poly(list(coeffs))

    def hankel_polys(self, st, reflected=False):
        """The four Hankel polynomials m_kl (or their reflections) of ``st``, cached."""
        key = (st, reflected)
        if key not in self._hankel:
            fix = reflect if reflected else tuple
            self._hankel[key] = tuple(tuple(self.poly(fix([flint.fmpq(q.numerator, q.denominator) for q in w]))
                                            for w in row) for row in st.m)
        return self._hankel[key]

    def coeffs(self, p):
        return [p[i] for i in range(self.n)]


@lru_cache(maxsize=64)
def circulant_ring(n: int) -> CirculantRing:
    """The (cached) ring Q[t]/(tⁿ − 1)."""
    return CirculantRing(n)


def _fmpq(ar, t):
    if isinstance(t, flint.fmpq):
        return t
    if ar.integers is not None:
        return flint.fmpq(int(ar.integers.num(t)), int(ar.integers.den(t)))
    q = ar.to_fraction(t)
    return flint.fmpq(q.numerator, q.denominator)


def _from_fmpq(ar, vals):
    if isinstance(ar.zero, flint.fmpq):
        return tuple(vals)
    if ar.integers is not None:
        return tuple(ar.integers.make(int(t.p), int(t.q)) for t in vals)
    return tuple(ar.convert(Fraction(int(t.p), int(t.q))) for t in vals)


def exact_step(st: CirculantStructure, x, eps, ar=None):
    """Φ_f(x, ε) by the 2×2 solve over R (exact; ``x``, ``eps`` in a rational arithmetic).

    Raises :class:`SingularMatrix` exactly when det(I − εf'(x)) = 0.
    """
    from .arith import get_arith

    ar = get_arith(ar or "flint")
    R, n = circulant_ring(st.n), st.n
    m = R.hankel_polys(st)
    x = [_fmpq(ar, t) for t in x]
    a, r = kahan_system(m, R.poly(reflect(x[:n])), R.poly(reflect(x[n:])), _fmpq(ar, eps), R.mul)
    zu, zv = cramer(a, r, R.mul, R.divide)
    return _from_fmpq(ar, reflect(R.coeffs(zu)) + reflect(R.coeffs(zv)))


def exact_htilde(st: CirculantStructure, x, eps, ar=None):
    """H̃(x, ε) = xᵀ (I − ε²(M J(x))²)^{-1} M x by a 2×2 solve over R (exact).

    Equal (``==``) to :func:`exact_khk.invariants.Htilde`; raises
    :class:`SingularMatrix` where H̃ has a pole.  xᵀz is the constant
    coefficient of u(t) ẑ_u(t) + v(t) ẑ_v(t).
    """
    from .arith import get_arith

    ar = get_arith(ar or "flint")
    R, n = circulant_ring(st.n), st.n
    mh = R.hankel_polys(st, reflected=True)
    x = [_fmpq(ar, t) for t in x]
    u, v = R.poly(x[:n]), R.poly(x[n:])
    a, r = htilde_system(mh, u, v, _fmpq(ar, eps), R.mul)
    zu, zv = cramer(a, r, R.mul, R.divide)
    return _from_fmpq(ar, [R.mul(u, zu)[0] + R.mul(v, zv)[0]])[0]


# --- floating: the DFT splits R ⊗ C into n copies of C -----------------------


def _dft_hankel(st, prec):
    """DFTs of the Hankel polynomials at working precision ``prec`` (cached)."""
    hit = _DFT_CACHE.get((st, prec))
    if hit is None:
        hit = tuple(tuple(flint.acb.dft([flint.fmpq(q.numerator, q.denominator) for q in w])
                          for w in row) for row in st.m)
        _DFT_CACHE[(st, prec)] = hit
    return hit


_DFT_CACHE: dict = {}


def numeric_step(st: CirculantStructure, x, eps, ar):
    """Φ_f(x, ε) for a floating arithmetic ``ar`` (``float``, ``mp:P``) via the DFT.

    Returns ``(z, condition, radius)``: the step rounded into ``ar``; the
    condition estimate κ = max_j ‖M_j‖₁ · max_j ‖M_j^{-1}‖₁ of the n 2×2 blocks
    M_j of I − εf'(x) in the Fourier basis (I − εf'(x) is unitarily similar to
    their direct sum, so κ is within a factor 2 of its 2-norm condition
    number; ``inf`` when a block is numerically singular); and a rigorous
    bound on |z_i − Φ_f(x, ε)_i| before the final rounding into ``ar`` (the
    ball radius; ``x`` and ``eps`` are taken as the exact binary values, ε as
    the exact rational when ``eps`` is a Fraction).
    """
    n, prec = st.n, ar.prec + GUARD_BITS + 2 * st.n.bit_length()
    with flint.ctx.workprec(prec):
        m = _dft_hankel(st, prec)
        e = flint.arb(flint.fmpq(eps.numerator, eps.denominator)) if isinstance(eps, Fraction) \
            else flint.arb(eps)
        uh = flint.acb.dft([flint.arb(t) for t in reflect(x[:n])])
        vh = flint.acb.dft([flint.arb(t) for t in reflect(x[n:])])
        zu, zv = [None] * n, [None] * n
        big, small = 0.0, 0.0
        for j in range(n):
            mj = ((m[0][0][j], m[0][1][j]), (m[1][0][j], m[1][1][j]))
            a, r = kahan_system(mj, uh[j], vh[j], e, _mul)
            a11, a12, a21, a22 = a
            det = a11 * a22 - a12 * a21
            if 0 in det:  # the ball contains 0: numerically singular
                return None, float("inf"), float("inf")
            norm = max(_abs(a11) + _abs(a21), _abs(a12) + _abs(a22))
            big = max(big, norm)
            small = max(small, max(_abs(a22) + _abs(a21), _abs(a12) + _abs(a11)) / _abs(det))
            zu[j], zv[j] = cramer(a, r, _mul, _divide)
        zu, zv = flint.acb.dft(zu, inverse=True), flint.acb.dft(zv, inverse=True)
        coords = [c.real for c in reflect(zu) + reflect(zv)]
        radius = max(float(c.rad()) for c in coords)
        z = tuple(ar.from_man_exp(*c.mid().man_exp()) for c in coords)
    return z, big * small, radius


def _mul(a, b):
    return a * b


def _divide(d, rhs):
    inv = 1 / d
    return tuple(inv * r for r in rhs)


def _abs(z) -> float:
    return float(abs(z).mid())
