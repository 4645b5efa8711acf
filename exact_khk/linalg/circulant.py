"""Kahan steps and H̃ as 2×2 systems over circulants (docs/conventions.md, "Structure worth exploiting").

For a Lie–Poisson field f(x) = J(x) M x whose Hessian M has four cyclic Hankel
n×n blocks (f, every associated field g and the control field do), all four
blocks of f'(x) are circulant.  Circulants form the commutative ring
R = Q[t]/(tⁿ − 1) (P ↔ t), so I − εf'(x) is a 2×2 matrix over R and a Kahan
step is a few products in R and one inversion in R.

Dictionary (0-based, as in docs/conventions.md):

* a vector w ∈ Qⁿ ↔ its *reflected* polynomial ŵ(t) = Σ_i w_i t^{−i}; then
  P w ↔ t ŵ, so a circulant Σ_m c_m P^m acts as multiplication by c(t);
* a Hankel block X(w) (first row w) times X(u) is the circulant of
  w(t)·û(t); the Jacobian blocks are (y = Mx, y_u ↔ Y_u = m11 û + m12 v̂, …)

      f'(x) = [[ û m21 + Y_v,   û m22 ],
               [ −û m11 − Y_u,  −û m12 ]]

  with m_kl(t) the polynomial of the first row of the Hankel block M_kl.

Exact step: with denominators cleared the 2×2 system lives in Z[t]/(tⁿ − 1)
and is solved by Cramer's rule; the one division, by the determinant D, is a
p-adic lift with polynomial arithmetic (:meth:`CirculantRing.solve`).  D is a
unit of R ⟺ D(ω) ≠ 0 at every n-th root of unity ω ⟺ s^2n·det(I − εf'(x))
= Π_ω D(ω) ≠ 0 (s the cleared denominator) ⟺ the step is defined.
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

from exact_khk.arith import _as_fraction
from exact_khk.errors import InputError
from exact_khk.linalg.dense import SingularMatrix

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

    def __hash__(self):  # computed once: every step looks the structure up in caches
        h = self.__dict__.get("_hash")
        if h is None:
            h = hash((self.n, self.m))
            object.__setattr__(self, "_hash", h)
        return h


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
    :class:`~exact_khk.systems.quadratic.QuadraticField`), non-homogeneous fields, or a
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


def reflect(w):
    """Coefficients of ŵ(t) = Σ w_i t^{−i} mod tⁿ − 1 (an involution)."""
    n = len(w)
    return [w[-i % n] for i in range(n)]


def kahan_system(m, uh, vh, eps, mul, one=1):
    """The 2×2 matrix one·I − εf'(x) and right-hand side x̂ over a commutative ring.

    ``m`` the Hankel polynomials, ``uh, vh`` the reflected u, v, ``mul`` the
    ring product (reducing mod tⁿ − 1, or plain products at one frequency);
    ``one`` ≠ 1 when denominators are cleared (see :func:`exact_step`).
    """
    (m11, m12), (m21, m22) = m
    yu, yv = mul(m11, uh) + mul(m12, vh), mul(m21, uh) + mul(m22, vh)
    f11, f12 = mul(uh, m21) + yv, mul(uh, m22)
    f21, f22 = -mul(uh, m11) - yu, -mul(uh, m12)
    return (one - eps * f11, -eps * f12, -eps * f21, one - eps * f22), (uh, vh)


def htilde_system(m, u, v, eps, mul, one=1):
    """The 2×2 matrix one·I − ε²(M J(x))² and right-hand side (M x)^ over a ring.

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
    return (one - e2 * q11, -e2 * q12, -e2 * q21, one - e2 * q22), rhs


def cramer(a, r, mul, divide):
    """Solve [[a11, a12], [a21, a22]] z = r over a commutative ring by Cramer's rule:
    ``divide(det, (r0', r1'))`` on the adjugate's numerators, returning what
    ``divide`` returns (e.g. (r0'/det, r1'/det)) and raising
    :class:`~exact_khk.linalg.dense.SingularMatrix` when det is not a unit."""
    a11, a12, a21, a22 = a
    det = mul(a11, a22) - mul(a12, a21)
    return divide(det, (mul(a22, r[0]) - mul(a12, r[1]), mul(a11, r[1]) - mul(a21, r[0])))


# --- exact: R = Q[t]/(tⁿ − 1), solved over Z[t]/(tⁿ − 1) by p-adic lifting ---

#: primes p < 2^62 for the p-adic lift; D must be a unit mod p (else the next is tried)
LIFT_PRIMES = (4611686018427387847, 4611686018427387817, 4611686018427387787)


class CirculantRing:
    """Q[t]/(tⁿ − 1): ``fmpq_poly`` elements for the public helpers, ``fmpz_poly``
    (denominators cleared) inside the exact step.

    :meth:`solve` divides by a unit d without forming d⁻¹ over Q (whose
    coefficients are far larger than the quotient's along Kahan orbits):
    d⁻¹ mod (p, tⁿ − 1) by an extended gcd over F_p, Newton lifting to
    d⁻¹ mod p^k, the quotients mod p^k, rational reconstruction with one common
    denominator (2×2 lattice reduction), and an exact check d·W = δ·r that
    turns the reconstruction into a proof.  Precision is searched from a hint
    (the last answer's height relative to d); if two attempts fail, one more at
    the Hadamard bound uses δ = |Res(d, tⁿ − 1)| = |det C(d)| and needs no
    reconstruction.  Every step is a product of n-coefficient polynomials, so
    a division costs a few polynomial multiplications at the size of the
    answer, against O(n²) work per lifting step in a dense p-adic solve.
    """

    def __init__(self, n):
        if flint is None:  # pragma: no cover
            raise ImportError("the structured exact step needs python-flint")
        self.n, self._hankel, self._cyclotomic = n, {}, []
        self.modulus = flint.fmpq_poly([-1] + [0] * (n - 1) + [1])
        self._zmodulus = flint.fmpz_poly([-1] + [0] * (n - 1) + [1])
        #: answer height / height of D at the last division: where the next
        #: division starts its precision search (a hint only; results are checked)
        self.height_ratio = 1.0

    def mul(self, a, b):
        """a·b mod tⁿ − 1 (fmpq_poly or fmpz_poly)."""
        c = a * b
        return c.truncate(self.n) + c.right_shift(self.n) if c.degree() >= self.n else c

    def poly(self, coeffs):
        return flint.fmpq_poly(list(coeffs))

    def coeffs(self, p):
        return [p[i] for i in range(self.n)]

    def hankel_polys(self, st, reflected=False):
        """The four Hankel polynomials m_kl (or their reflections) of ``st`` as fmpq_poly, cached."""
        key = (st, reflected)
        if key not in self._hankel:
            fix = reflect if reflected else tuple
            self._hankel[key] = tuple(tuple(self.poly(fix([flint.fmpq(q.numerator, q.denominator) for q in w]))
                                            for w in row) for row in st.m)
        return self._hankel[key]

    def integer_hankel(self, st, reflected=False):
        """``(polys, den)``: den·m_kl as fmpz_poly with the least common denominator den, cached."""
        key = (st, reflected, "Z")
        if key not in self._hankel:
            m = self.hankel_polys(st, reflected)
            den = flint.fmpz(1)
            for row in m:
                for w in row:
                    den = den.lcm(w.denom())
            self._hankel[key] = tuple(tuple((w * den).numer() for w in row) for row in m), den
        return self._hankel[key]

    def solve(self, d, rhs):
        """``(W, δ)``: fmpz_polys W_i and an integer δ > 0 with d·W_i = δ·r_i in
        Z[t]/(tⁿ − 1), i.e. W_i/δ = r_i/d, for fmpz_poly d and r_i.

        Raises :class:`SingularMatrix` exactly when d is not a unit of
        Q[t]/(tⁿ − 1) (gcd(d, tⁿ − 1) ≠ 1, i.e. d(ω) = 0 at an n-th root of unity).
        """
        inverse = self._inverse_mod_prime(d)
        if inverse is None:  # d is a unit but not modulo any prime we tried
            return self._solve_dense(d, rhs)
        u, p = inverse
        n, hd = self.n, max(d.height_bits(), 1)
        # Hadamard: |det C(d)| ≤ ‖d‖₂ⁿ and |adj(C(d))·r| ≤ ‖d‖₂ⁿ⁻¹‖r‖₂ (C(d) the n×n
        # circulant of d); Kahan orbits need far smaller answers than these bounds
        norm_bits = n.bit_length() / 2 + 1  # ≥ log2 √n
        hr = max(r.height_bits() for r in rhs)
        adj_bits = int((n - 1) * (hd + norm_bits) + hr + norm_bits) + 1
        # two attempts with reconstruction, starting near the last answer's height
        # relative to d, then the Cramer bound, which needs no reconstruction.  The
        # hint is capped at 2 (one from an unrelated division must not cost much)
        # unless the bound is itself within 8·hd (small n): then an answer near the
        # bound, as at random points, sends the next division straight to it
        cap = max(2.0, adj_bits / hd) if adj_bits <= 8 * hd else 2.0
        bits = int(min(max(self.height_ratio, 0.5), cap) * hd * 1.05) + 64
        k = 1
        for attempt in (bits, bits * 3 // 2):
            if 2 * attempt >= adj_bits:
                break
            # m = p^j ≥ 2^(2·bits + 8): numerators and δ up to 2^bits are recovered
            j = -(-(2 * attempt + 8) // p.bit_length())
            u, k = self._lift(d, u, k, p, j)
            found = self._reconstruct(d, rhs, u % p ** j, p ** j)
            if found is not None:
                return self._remember(found, hd)
        j = -(-(adj_bits + 2) // p.bit_length())  # m > 2·|adj(C(d))·r|
        u, k = self._lift(d, u, k, p, j)
        m = p ** j
        delta = self.resultant(d)  # = |det C(d)|: δ·r/d is integral
        W = [self.symmetric_mod(self.mul(r, u % m) * delta, m) for r in rhs]
        if any(self.mul(d, w) != r * delta for w, r in zip(W, rhs)):  # pragma: no cover
            raise ArithmeticError("circulant solve: the Cramer-bound solution failed its check")
        g = delta
        for w in W:
            g = g.gcd(w.content())
        return self._remember(([w // g for w in W], delta // g), hd)

    def _lift(self, d, u, k, p, j):
        """(u', k') with u' = d⁻¹ mod (p^k', tⁿ − 1), k' = max(k, j), from u = d⁻¹ mod p^k,
        by Newton: d·u ≡ 1 + p^k·e  ⇒  d·u(1 − p^k·e) ≡ 1 (mod p^2k)."""
        while k < j:
            k2 = min(2 * k, j)
            pk, low = p ** k, p ** (k2 - k)
            e = (self.mul(d % p ** k2, u) - 1) // pk % low
            u, k = u - pk * (self.mul(u, e) % low), k2
        return u, k

    def resultant(self, d):
        """|Res(d, tⁿ − 1)| = |det C(d)| as the product of |Res(d mod Φ_k, Φ_k)| over the
        cyclotomic factors Φ_k of tⁿ − 1 (k | n): for tall d far faster than one
        resultant with tⁿ − 1 (measured 1.2 s against 14 ms at n = 4 and 200 000 bits)."""
        if not self._cyclotomic:
            self._cyclotomic = [flint.fmpz_poly.cyclotomic(k) for k in range(1, self.n + 1) if self.n % k == 0]
        out = flint.fmpz(1)
        for phi in self._cyclotomic:
            out *= (d % phi).resultant(phi)
        return abs(out)

    def _remember(self, found, hd):
        W, delta = found
        self.height_ratio = max(delta.bit_length(), *(w.height_bits() for w in W)) / hd
        return found

    def _inverse_mod_prime(self, d):
        """(d⁻¹ mod (p, tⁿ − 1) as fmpz_poly, p) for the first p in :data:`LIFT_PRIMES`
        with d a unit mod p; None if there is none; :class:`SingularMatrix` if d is
        not a unit over Q."""
        coeffs = d.coeffs()
        for p in LIFT_PRIMES:
            g, s, _ = flint.nmod_poly(coeffs, p).xgcd(flint.nmod_poly(self._zmodulus.coeffs(), p))
            if g.degree() == 0:  # xgcd returns the monic gcd: g == 1
                return flint.fmpz_poly([int(c) for c in s.coeffs()]), flint.fmpz(p)
            if d.gcd(self._zmodulus).degree() != 0:
                raise SingularMatrix("the 2x2 determinant vanishes at a root of t^n - 1")
        return None  # needs p | resultant(d, t^n - 1) for every listed p

    def _reconstruct(self, d, rhs, u, m):
        """W, δ from the quotients r_i·d⁻¹ mod m (one common denominator δ), or None
        if m is too small for them; a returned pair is checked exactly."""
        bound = (m // 2).isqrt()  # |numerator|, δ ≤ bound make the reconstruction unique
        images = [self.mul(r, u) for r in rhs]
        delta = flint.fmpz(1)
        while True:
            W = [self.symmetric_mod(image * delta, m) for image in images]
            big = next((c for w in W for c in w.coeffs() if abs(c) > bound), None)
            if big is None:
                break
            num, den = rational_reconstruction(big, m)  # big ≡ num/den: δ·den next
            delta *= den
            if den <= 1 or delta > bound or abs(num) > bound:  # den = 1: no progress
                return None
        if any(self.mul(d, w) != r * delta for w, r in zip(W, rhs)):
            return None
        return W, delta

    def symmetric_mod(self, p, m):
        """The coefficients of ``p`` reduced into [−⌊m/2⌋, m − ⌊m/2⌋) (``fmpz_poly % m``
        alone leaves them anywhere in (−m, m))."""
        half = m // 2
        shift = flint.fmpz_poly([m + half] * self.n)  # makes every coefficient positive
        return (p % m + shift) % m - flint.fmpz_poly([half] * self.n)

    def _solve_dense(self, d, rhs):
        """Fallback: the n×n circulant system C(d) W = δ r by ``fmpz_mat.solve``."""
        n = self.n
        C = flint.fmpz_mat(n, n, [d[(i - j) % n] for i in range(n) for j in range(n)])
        X = C.solve(flint.fmpz_mat(n, len(rhs), [r[i] for i in range(n) for r in rhs]))
        num, delta = X.numer_denom()
        cols = num.transpose().entries()
        return [flint.fmpz_poly(cols[k * n:(k + 1) * n]) for k in range(len(rhs))], delta


def rational_reconstruction(a, m):
    """(num, den), den ≥ 0, with num ≡ a·den (mod m): the first vector of an
    LLL-reduced basis (python-flint, δ = 0.99) of the lattice
    {(x, y): x ≡ a·y mod m}.  If a ≡ N/D (mod m) with |N|, D ≤ √m/4, then
    num/den = N/D: LLL's first vector is within a factor √1.36 of the
    shortest, and every vector independent of (N, D) is longer than m/|(N, D)|.

    >>> rational_reconstruction(5 * pow(7, -1, 1000003) % 1000003, 1000003)
    (5, 7)
    """
    num, den = flint.fmpz_mat([[m, 0], [a, 1]]).lll().tolist()[0]
    return (-num, -den) if den < 0 else (num, den)


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


def _cleared(vals):
    """(numerators, common denominator) of fmpq values."""
    den = flint.fmpz(1)
    for t in vals:
        den = den.lcm(t.q)
    return [t.p * (den // t.q) for t in vals], den


def exact_step(st: CirculantStructure, x, eps, ar=None):
    """Φ_f(x, ε) by the 2×2 solve over R (exact; ``x``, ``eps`` in a rational arithmetic).

    With x = X/dx, ε = e/q and Hankel polynomials m/dm, s·(I − εf'(x)) with
    s = q·dm·dx has integer entries in Z[t]/(tⁿ − 1) and right-hand side
    q·dm·X̂; Cramer's rule leaves one division by the determinant
    (:meth:`CirculantRing.solve`).  Raises :class:`SingularMatrix` exactly when
    det(I − εf'(x)) = 0.
    """
    from exact_khk.arith import get_arith

    ar = get_arith(ar or "flint")
    R, n = circulant_ring(st.n), st.n
    m, dm = R.integer_hankel(st)
    X, dx = _cleared([_fmpq(ar, t) for t in x])
    e = _fmpq(ar, eps)
    a, (xu, xv) = kahan_system(m, flint.fmpz_poly(reflect(X[:n])), flint.fmpz_poly(reflect(X[n:])),
                               e.p, R.mul, one=e.q * dm * dx)
    (wu, wv), delta = cramer(a, (xu * (e.q * dm), xv * (e.q * dm)), R.mul, R.solve)
    return _from_fmpq(ar, [flint.fmpq(c, delta) for c in reflect(R.coeffs(wu)) + reflect(R.coeffs(wv))])


def exact_htilde(st: CirculantStructure, x, eps, ar=None):
    """H̃(x, ε) = xᵀ (I − ε²(M J(x))²)^{-1} M x by a 2×2 solve over R (exact).

    Equal (``==``) to :func:`exact_khk.systems.lie_poisson.invariants.Htilde`; raises
    :class:`SingularMatrix` where H̃ has a pole.  xᵀz is the constant
    coefficient of u(t) ẑ_u(t) + v(t) ẑ_v(t).  Denominators are cleared as in
    :func:`exact_step`: S = (q·dm·dx)² times the matrix, q²·dm·dx times the
    right-hand side.
    """
    from exact_khk.arith import get_arith

    ar = get_arith(ar or "flint")
    R, n = circulant_ring(st.n), st.n
    mh, dm = R.integer_hankel(st, reflected=True)
    X, dx = _cleared([_fmpq(ar, t) for t in x])
    e = _fmpq(ar, eps)
    u, v = flint.fmpz_poly(X[:n]), flint.fmpz_poly(X[n:])
    a, (ru, rv) = htilde_system(mh, u, v, e.p, R.mul, one=(e.q * dm * dx) ** 2)
    scale = e.q ** 2 * dm * dx
    (wu, wv), delta = cramer(a, (ru * scale, rv * scale), R.mul, R.solve)
    return _from_fmpq(ar, [flint.fmpq((R.mul(u, wu) + R.mul(v, wv))[0], dx * delta)])[0]


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
