"""Exact arithmetic beyond Q: cyclotomic fields ``cyclo:N`` and prime fields ``gf:P``.

``cyclo:N`` is Q(ζ_N), ζ_N = e^{2πi/N}: elements are rational polynomials in
``z`` = ζ_N reduced modulo the N-th cyclotomic polynomial Φ_N (python-flint
``fmpq_poly``), wrapped in :class:`CycloNumber` so that they work with the
generic algorithms (``+ - * /``, ``==``, ``hash``).  The involutions of the
Lie–Poisson family that are not rational have entries in Q(ω), ω = ζ_n
(:func:`exact_khk.systems.involution_circulant_cyclotomic`); ``cyclo:N``
converts them for every N that is a multiple of n (ζ_n = z^{N/n}).

``gf:P`` is the prime field F_P (python-flint ``nmod``, P prime, checked:
:data:`MIN_PRIME` ≤ P < 2⁶⁴).  ``cyclo:N`` takes N ≤ :data:`MAX_CYCLOTOMIC_N`.
It converts a rational p/q only when P does not divide q (otherwise a
:class:`BadReductionError`), and an element of Q(ζ_m) only when
P ≡ 1 (mod m), through the fixed embedding ζ_m ↦ g^{(P-1)/m} with g the
least primitive root mod P (compatible for all m: it is the reduction of
``cyclo:N`` modulo a prime above P).

>>> from fractions import Fraction
>>> from exact_khk import get_arith
>>> K = get_arith("cyclo:3")
>>> z = K.gen
>>> K.format(z * z)                     # ζ² = −1 − ζ
'-1 - z'
>>> K.format(K(Fraction(1, 3)) - 2 * z / 3)
'1/3 - 2/3*z'
>>> (1 / (1 - z)) * (1 - z) == 1
True
>>> F = get_arith("gf:7")
>>> F.format(F(Fraction(1, 3)))          # 3 * 5 = 15 = 1 (mod 7)
'5'
>>> F.format(F(z))                       # ζ_3 ↦ 3^{(7-1)/3} = 2 (mod 7)
'2'
>>> get_arith("gf:5")(z)
Traceback (most recent call last):
...
exact_khk.errors.InputError: arith gf:5: ζ_3 (needed by an involution over Q(ω), ω = e^(2πi/3)) does not exist mod 5: choose a prime P ≡ 1 (mod 3)
"""

from __future__ import annotations

import cmath
from fractions import Fraction
from functools import lru_cache

import flint

from exact_khk.arith import Arith, _as_fraction, register_arith
from exact_khk.errors import InputError, NotRationalError
from exact_khk.parsing import poly_text

__all__ = ["CyclotomicField", "CycloNumber", "CycloArith", "GFArith", "BadReductionError",
           "cyclotomic_field", "DEFAULT_PRIME"]


#: a prime P ≡ 1 (mod 720720) below 2^62: ω = e^{2πi/n} exists in F_P for every n ≤ 16
DEFAULT_PRIME = 4611686018420360881

#: the largest n·φ of ``dft`` (φ = 1 in gf:P): its transform holds (n·φ)² integers, built once
#: (a memory bound: 4 million entries; the structured steps stay below 1024,
#: ``systems.lie_poisson.paths.exact_dft_fits``)
DFT_MAX_SIZE = 2048

#: the largest N of ``cyclo:N``: an element is a polynomial of degree < φ(N) ≤ N − 1,
#: so one product costs about N² coefficient operations and a 2n×2n solve
#: (2n)³ of them; at N = 10⁴ a single Kahan step already takes minutes
MAX_CYCLOTOMIC_N = 10_000
#: the smallest P of ``gf:P``: 2 and 3 divide the denominators of the formulas
#: themselves (the 1/2 of H0 and of (2ε)⁻¹, the 2/n of the involution B_0 for
#: n = 3), so every computation over F_2 or F_3 would be a bad reduction
MIN_PRIME = 5


class BadReductionError(InputError):
    """A rational whose denominator is divisible by P was sent to ``gf:P``."""


def _fmpq(value) -> flint.fmpq:
    q = _as_fraction(value)
    return flint.fmpq(q.numerator, q.denominator)


class CyclotomicField:
    """Q(ζ_N) as fmpq_poly modulo Φ_N; use :func:`cyclotomic_field` (cached)."""

    def __init__(self, N: int):
        self.N = N
        self.modulus = flint.fmpq_poly(flint.fmpz_poly.cyclotomic(N).coeffs())
        self.degree = self.modulus.degree()
        self._companion = self._regular = None
        self.gen = self.element(flint.fmpq_poly([0, 1]))
        self.zero = self.element(flint.fmpq_poly([0]))

    def element(self, poly) -> "CycloNumber":
        return CycloNumber(self, poly % self.modulus)

    def companion_powers(self) -> list:
        """Cᵏ for k < φ(N) as lists of integer rows, cached: C is the matrix of
        multiplication by ζ_N on the basis 1, ζ, …, ζ^(φ−1) (column c: ζ^(c+k) mod Φ_N)."""
        if self._companion is None:
            phi, z = self.degree, flint.fmpq_poly([0, 1])
            cols = [[flint.fmpq_poly([0] * c + [1]) for c in range(phi)]]  # cols[k][c] = ζ^(c+k)
            for _ in range(1, phi):
                cols.append([(p * z) % self.modulus for p in cols[-1]])
            self._companion = [[[int(cols[k][c][r]) for c in range(phi)] for r in range(phi)]
                               for k in range(phi)]
        return self._companion

    def regular_map(self):
        """The fmpz_mat G (φ × φ²) with G[k, r·φ + c] = (Cᵏ)_rc, cached: a row of
        ζᵏ-coefficients times G lists the entries of Σ_k aₖ Cᵏ, the matrix of
        multiplication by Σ_k aₖ ζᵏ."""
        if self._regular is None:
            phi = self.degree
            self._regular = flint.fmpz_mat(phi, phi * phi, [v for Ck in self.companion_powers()
                                                            for row in Ck for v in row])
        return self._regular

    def zeta_power(self, k: int) -> "CycloNumber":
        """ζ_N^k (k any integer)."""
        return self.element(flint.fmpq_poly([0] * (k % self.N) + [1]))

    def embed(self, e: "CycloNumber") -> "CycloNumber":
        """``e`` ∈ Q(ζ_m), m | N, as an element of this field (ζ_m = ζ_N^{N/m})."""
        m = e.K.N
        if self.N % m:
            raise InputError(f"arith cyclo:{self.N}: cannot represent ζ_{m} "
                             f"(an element of Q(ζ_{m})): use cyclo:N with N a multiple of {m}")
        if m == self.N:
            return e
        step = self.N // m
        coeffs = [0] * (step * e.p.degree() + 1) if not e.p.is_zero() else []
        for k, c in enumerate(e.p.coeffs()):
            coeffs[k * step] = c
        return self.element(flint.fmpq_poly(coeffs))

    def __repr__(self):
        return f"Q(ζ_{self.N})"


@lru_cache(maxsize=None)
def cyclotomic_field(N: int) -> CyclotomicField:
    """The field Q(ζ_N) (one object per N)."""
    if isinstance(N, bool) or not isinstance(N, int) or N < 1:
        raise InputError(f"arith: cyclo:N needs an integer N >= 1, got {N!r}")
    if N > MAX_CYCLOTOMIC_N:
        raise InputError(f"arith: cyclo:{N}: N is beyond the limit of {MAX_CYCLOTOMIC_N} (MAX_CYCLOTOMIC_N; "
                         f"an element of Q(zeta_N) is a polynomial of degree up to N - 1, one product about "
                         f"N^2 = {N * N:.2g} coefficient operations); the involutions of size n need only "
                         f"N = n")
    return CyclotomicField(N)


class CycloNumber:
    """An element of Q(ζ_N): ``p`` (fmpq_poly, degree < φ(N)) evaluated at ζ_N.

    Mixes with int, Fraction and fmpq.  It is rational exactly when ``p`` is
    constant; then ``numerator``/``denominator`` exist, otherwise reading them
    raises :class:`NotRationalError` (so the rational arithmetics refuse it).
    """

    __slots__ = ("K", "p")

    def __init__(self, K: CyclotomicField, p):
        self.K, self.p = K, p

    def _pair(self, other):
        """(K, a, b): this element and ``other`` as polynomials in a common field K
        (the larger of two fields when one contains the other), or None."""
        if type(other) is CycloNumber:
            if other.K is self.K:
                return self.K, self.p, other.p
            if self.K.N % other.K.N == 0:
                return self.K, self.p, self.K.embed(other).p
            if other.K.N % self.K.N == 0:
                return other.K, other.K.embed(self).p, other.p
            raise TypeError(f"cannot mix elements of Q(ζ_{self.K.N}) and Q(ζ_{other.K.N})")
        if isinstance(other, (int, Fraction, flint.fmpq, flint.fmpz)):
            return self.K, self.p, flint.fmpq_poly([_fmpq(other)])
        return None

    def __add__(self, other):
        t = self._pair(other)
        return NotImplemented if t is None else CycloNumber(t[0], t[1] + t[2])

    __radd__ = __add__

    def __sub__(self, other):
        t = self._pair(other)
        return NotImplemented if t is None else CycloNumber(t[0], t[1] - t[2])

    def __rsub__(self, other):
        t = self._pair(other)
        return NotImplemented if t is None else CycloNumber(t[0], t[2] - t[1])

    def __mul__(self, other):
        t = self._pair(other)
        if t is None:
            return NotImplemented
        K, a, b = t
        if a.degree() <= 0 or b.degree() <= 0:
            return CycloNumber(K, a * b)
        return CycloNumber(K, (a * b) % K.modulus)

    __rmul__ = __mul__

    def __neg__(self):
        return CycloNumber(self.K, -self.p)

    def __pos__(self):
        return self

    @staticmethod
    def _inv(K, p):
        if p.is_zero():
            raise ZeroDivisionError(f"division by zero in Q(ζ_{K.N})")
        if p.degree() == 0:
            return flint.fmpq_poly([1 / p.coeffs()[0]])
        g, s, _ = p.xgcd(K.modulus)  # g = s p + t Φ_N, g a nonzero constant
        return s / g

    @classmethod
    def _div(cls, K, a, b):
        return cls(K, a) * cls(K, cls._inv(K, b))

    def __truediv__(self, other):
        t = self._pair(other)
        return NotImplemented if t is None else self._div(t[0], t[1], t[2])

    def __rtruediv__(self, other):
        t = self._pair(other)
        return NotImplemented if t is None else self._div(t[0], t[2], t[1])

    def __pow__(self, k: int):
        if not isinstance(k, int):
            return NotImplemented
        base = self if k >= 0 else 1 / self
        out = CycloNumber(self.K, flint.fmpq_poly([1]))
        for _ in range(abs(k)):
            out = out * base
        return out

    def __eq__(self, other):
        t = self._pair(other)
        return NotImplemented if t is None else t[1] == t[2]

    def __ne__(self, other):
        eq = self.__eq__(other)
        return eq if eq is NotImplemented else not eq

    def __hash__(self):
        if self.p.degree() <= 0:
            return hash(self.to_fraction())  # equal to an equal Fraction/int
        return hash((self.K.N, tuple(str(c) for c in self.p.coeffs())))

    def __bool__(self):
        return not self.p.is_zero()

    def is_rational(self) -> bool:
        return self.p.degree() <= 0

    def to_fraction(self) -> Fraction:
        """The rational value; :class:`NotRationalError` if not rational."""
        if not self.is_rational():
            raise NotRationalError(f"{self} is an element of Q(ζ_{self.K.N}) that is not rational: "
                                   f"this needs cyclotomic arithmetic (cyclo:N) or gf:P")
        if self.p.is_zero():
            return Fraction(0)
        c = self.p.coeffs()[0]
        return Fraction(int(c.p), int(c.q))

    @property
    def numerator(self):
        return self.to_fraction().numerator

    @property
    def denominator(self):
        return self.to_fraction().denominator

    def __str__(self):
        return format_poly(self.p)

    def __repr__(self):
        return f"CycloNumber({self.K.N}, '{self}')"


def format_poly(p, var: str = "z") -> str:
    """'1/3 - 2/3*z + z^2' (constant term first)."""
    return poly_text(p.coeffs(), var)


class CycloArith(Arith):
    """Exact arithmetic in Q(ζ_N) (name ``cyclo:N``); ``gen`` is ζ_N, printed ``z``.

    Division by zero raises ZeroDivisionError; no ``to_fraction`` (TypeError)."""

    exact = True

    def __init__(self, N: int):
        self.K = cyclotomic_field(N)
        self.N = N
        self.name = f"cyclo:{N}"
        self.zero, self.one = self.K.zero, self.K.zeta_power(0)
        self.gen = self.K.gen
        self.evidence = f"exact in Q(zeta_{N})"
        #: rational coefficients per element (φ(N)): the size of its linear algebra over Q
        self.coefficient_degree = self.K.degree
        #: ζ_N: the n-th roots of unity for every n | N (the exact DFT, :meth:`dft`)
        self.roots_of_unity = N

    def owns(self, e) -> bool:
        """Whether ``e`` is an element of this field (not of another Q(ζ_M))."""
        return e.K is self.K

    def convert(self, value):
        if isinstance(value, CycloNumber):
            return self.K.embed(value)
        return CycloNumber(self.K, flint.fmpq_poly([_fmpq(value)]))

    def is_zero(self, e):
        return e.p.is_zero()

    def format(self, e) -> str:
        return format_poly(e.p)

    def magnitude(self, e) -> float:
        """|e| as a float, with ζ_N = e^{2πi/N} (display only; pivoting is exact)."""
        return abs(sum(float(c) * cmath.exp(2j * cmath.pi * k / self.N) for k, c in enumerate(e.p.coeffs())))

    def _coefficient_rows(self, values, zero=flint.fmpq(0)):
        """The ζᵏ-coefficients (k < φ) of each value, as one flat list, row by row."""
        phi, K, out = self.K.degree, self.K, []
        for v in values:
            c = (v if type(v) is CycloNumber and v.K is K else self.convert(v)).p.coeffs()
            out += c
            if len(c) < phi:
                out += [zero] * (phi - len(c))
        return out

    def linear_forms(self, rows, consts, dim):
        """The forms c_r + Σ_k a_rk x_k for :meth:`apply_forms`, over Z: for each power ζᵃ
        that occurs, D_H times the matrix of the ζᵃ-coefficients of the a_rk (fmpz_mat,
        R × dim; D_H their common denominator), with (Cᵃ)ᵀ; the constants' coefficients
        (R × φ) as (integer matrix, denominator)."""
        q, phi, R = flint.fmpq_mat, self.K.degree, len(rows)
        H = [[flint.fmpq(0)] * (R * dim) for _ in range(phi)]
        for r, row in enumerate(rows):
            for k, a in row:
                for e, c in enumerate(self.convert(a).p.coeffs()):
                    H[e][r * dim + k] += c
        used = [e for e in range(phi) if any(H[e])]
        powers = self.K.companion_powers() if any(used) else None  # rational forms: none needed
        Hz = [q(R, dim, H[e]).numer_denom() for e in used]
        DH = flint.fmpz(1)
        for _, d in Hz:
            DH = DH.lcm(d)
        terms = [(Z * (DH // d), flint.fmpz_mat(phi, phi, [powers[e][c][r] for r in range(phi) for c in range(phi)])
                  if e else None) for (Z, d), e in zip(Hz, used)]
        return terms, DH, q(R, phi, self._coefficient_rows(consts)).numer_denom(), dim

    def apply_forms(self, prepared, x):
        """[c_r + Σ_k a_rk x_k] for forms from :meth:`linear_forms`: a few fmpz_mat
        products, (Σ_a H_a X (Cᵃ)ᵀ) with X the coefficients of x, over one denominator
        (rational matrices with many denominators multiply 10× slower)."""
        terms, DH, (P, dP), dim = prepared
        phi, K = self.K.degree, self.K
        X, dX = flint.fmpq_mat(dim, phi, self._coefficient_rows(x)).numer_denom()
        S = P * (DH * dX)
        for H, CT in terms:
            S = S + (H * X if CT is None else H * X * CT) * dP
        E, D = S.entries(), DH * dX * dP
        return [CycloNumber(K, flint.fmpq_poly(E[r * phi:(r + 1) * phi]) / D) for r in range(S.nrows())]

    def dft(self, rows, n, sign=1):
        """[Σ_i w_i ω^(sign·i·j) for j < n] for each list w of n elements in ``rows``,
        ω = ζ_N^(N/n) (n | N): one fmpz_mat product of the rows' coefficients (over one
        denominator) with the integer matrix of the transform on coefficients.

        >>> ar = CycloArith(3)
        >>> [str(t) for t in ar.dft([[1, 1, 0]], 3)[0]]   # 1 + ω^j
        ['2', '1 + z', '-z']
        """
        rows = _dft_rows(self, rows, n, sign)
        phi, K = self.K.degree, self.K
        W, den = flint.fmpq_mat(len(rows), n * phi, self._coefficient_rows([e for w in rows for e in w])
                                ).numer_denom()
        E = (W * self._transform(n, sign)).entries()
        return [[CycloNumber(K, flint.fmpq_poly(E[(r * n + j) * phi:(r * n + j + 1) * phi]) / den) for j in range(n)]
                for r in range(len(rows))]

    @lru_cache(maxsize=16)
    def _transform(self, n, sign):
        """The fmpz_mat T (nφ × nφ) of :meth:`dft` on coefficients: row i·φ + a, column
        j·φ + r holds the ζʳ-coefficient of ζ^(a + sign·(N/n)·i·j) reduced modulo Φ_N."""
        N, phi = self.N, self.K.degree
        powers = [[int(c) for c in self.K.zeta_power(e).p.coeffs()] for e in range(N)]
        T = [[0] * (n * phi) for _ in range(n * phi)]
        for i in range(n):
            for a in range(phi):
                row = T[i * phi + a]
                for j in range(n):
                    for r, c in enumerate(powers[(a + sign * (N // n) * i * j) % N]):
                        row[j * phi + r] = c
        return flint.fmpz_mat(T)

    def native_matmul(self, A, B):
        """A B over Q(ζ_N) from the rational matrices of the coefficients: T_s = Σ_(a+b=s)
        A_a B_b (fmpq_mat products), then ζ^s reduced modulo Φ_N."""
        q, z, phi, K = flint.fmpq_mat, flint.fmpz_mat, self.K.degree, self.K
        n, m, p = len(A), len(B), len(B[0]) if B else 0
        # over Z: A = Az/dA, B = Bz/dB (rational matrices with many denominators multiply slowly)
        Ac, dA = q(n * m, phi, self._coefficient_rows([e for row in A for e in row])).numer_denom()
        Bc, dB = q(m * p, phi, self._coefficient_rows([e for row in B for e in row])).numer_denom()
        Ac, Bc = Ac.entries(), Bc.entries()
        As = [z(n, m, Ac[k::phi]) for k in range(phi)]
        Bs = [z(m, p, Bc[k::phi]) for k in range(phi)]
        R = [z(n, p) for _ in range(phi)]
        for s in range(2 * phi - 1):
            T = None
            for a in range(max(0, s - phi + 1), min(s, phi - 1) + 1):
                t = As[a] * Bs[s - a]
                T = t if T is None else T + t
            for r, c in enumerate(K.zeta_power(s).p.coeffs()):  # ζ^s = Σ_r c_r ζ^r (integers)
                if c:
                    R[r] = R[r] + T * int(c)
        E, D = [Rr.entries() for Rr in R], dA * dB
        return [[CycloNumber(K, flint.fmpq_poly([E[r][i * p + j] for r in range(phi)]) / D) for j in range(p)]
                for i in range(n)]

    def native_solve(self, M, B):
        """M X = B over Q(ζ_N) as one rational system φ(N) times larger, solved by FLINT
        (``fmpq_mat.solve``).  With the unknowns ordered by power of ζ, block (r, c) of
        that system is Σ_k (Cᵏ)_rc A_k: A_k the matrix of the ζᵏ-coefficients of M's
        entries, C the companion matrix of Φ_N (multiplication by ζ).  Its determinant
        is the norm of det M, so it is singular exactly when M is (ZeroDivisionError).
        A rational M is solved over Q directly.  (``linalg.dense.solve`` calls this only
        for sizes within ``linalg.dense.coefficients_native``.)"""
        K, phi, n, m = self.K, self.K.degree, len(M), len(B[0]) if B else 0
        q = flint.fmpq_mat
        Mc = self._coefficient_rows([e for row in M for e in row])  # entry (i, j), power k: [(i n + j) φ + k]
        Bc = self._coefficient_rows([e for row in B for e in row])
        if not any(c for k in range(1, phi) for c in Mc[k::phi]):  # rational M: M X_k = B_k for each power k
            X = q(n, n, Mc[::phi]).solve(q(n, m * phi, Bc))
            return [[CycloNumber(K, flint.fmpq_poly([X[i, j * phi + k] for k in range(phi)])) for j in range(m)]
                    for i in range(n)]
        # over Z (M = Mz/d, B = Bz/dB): the entries Σ_k (Cᵏ)_rc (A_k)_ij of every block, by one
        # product, at [(i n + j) φ² + r φ + c]; then (big/d) X = Bz/dB
        Mz, d = q(n * n, phi, Mc).numer_denom()
        E = (Mz * K.regular_map()).entries()
        big = flint.fmpz_mat(n * phi, n * phi, [E[t] for t in _regular_layout(n, phi)])
        Bz, dB = q(n * phi, m, [Bc[(i * m + j) * phi + k] for k in range(phi) for i in range(n)
                                for j in range(m)]).numer_denom()
        X = big.solve(Bz) * (flint.fmpq(d) / dB)
        return [[K.element(flint.fmpq_poly([X[k * n + i, j] for k in range(phi)])) for j in range(m)]
                for i in range(n)]


def _dft_rows(ar, rows, n, sign):
    """``rows`` as lists of n elements for ``ar.dft``, after checking n (a positive
    integer dividing ``ar.roots_of_unity``), the sign (±1) and every row's length
    (InputError)."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise InputError(f"dft: n must be a positive integer, got {n!r}")
    if sign not in (1, -1) or isinstance(sign, bool):
        raise InputError(f"dft: sign must be 1 or -1, got {sign!r}")
    if ar.roots_of_unity % n:
        raise InputError(f"arith {ar.name} holds no primitive {n}-th root of unity "
                         f"(n must divide {ar.roots_of_unity})")
    size = n * (getattr(ar, "coefficient_degree", None) or 1)
    if size > DFT_MAX_SIZE:
        raise InputError(f"dft: n·φ = {size} coefficients in {ar.name}, beyond the limit of {DFT_MAX_SIZE} "
                         f"(DFT_MAX_SIZE; the transform would hold {size * size:.2g} integers)")
    rows = [list(w) for w in rows]
    if any(len(w) != n for w in rows):
        raise InputError(f"dft: every row needs n = {n} elements, got lengths {sorted({len(w) for w in rows})}")
    return rows


@lru_cache(maxsize=8)
def _regular_layout(n: int, phi: int) -> tuple:
    """Where entry ((r, i), (c, j)) of the rational system of :meth:`CycloArith.native_solve`
    (row-major, rows r φ… by power then row) sits in the product of its coefficient rows
    with :meth:`CyclotomicField.regular_map`."""
    return tuple((i * n + j) * phi * phi + r * phi + c for r in range(phi) for i in range(n)
                 for c in range(phi) for j in range(n))


# --- prime fields -------------------------------------------------------------


@lru_cache(maxsize=None)
def _primitive_root(P: int) -> int:
    """The least generator of (Z/P)^*."""
    if P == 2:
        return 1
    qs = [int(q) for q, _ in flint.fmpz(P - 1).factor()]
    g = 2
    while any(pow(g, (P - 1) // q, P) == 1 for q in qs):
        g += 1
    return g


class GFArith(Arith):
    """The prime field F_P (name ``gf:P``), elements ``flint.nmod``.

    Exact: singular steps mod P are detected exactly (native ``nmod_mat`` solve)."""

    exact = True

    def __init__(self, P: int):
        if P < MIN_PRIME or P >= 2 ** 64 or not flint.fmpz(P).is_prime():
            why = ("too small: 2 and 3 divide the denominators of the formulas (bad reduction everywhere)"
                   if P in (2, 3) else "P >= 2^64" if P >= 2 ** 64 else "P < 2" if P < 2 else "not a prime")
            raise InputError(f"arith: gf:{P}: P must be a prime with {MIN_PRIME} <= P < 2^64 ({why})")
        self.P = P
        self.name = f"gf:{P}"
        self.zero, self.one = flint.nmod(0, P), flint.nmod(1, P)
        #: F_P holds the n-th roots of unity for every n | P − 1 (the exact DFT, :meth:`dft`)
        self.roots_of_unity = P - 1
        # A nonzero residual mod P refutes a claim at a point; zero residuals
        # mod P do not prove the rational claim (P may divide the residual).
        self.evidence = f"modular: exact in F_{P} (zero mod P is evidence, not proof)"

    def owns(self, e) -> bool:
        """Whether ``e`` is a residue mod this P."""
        return e.modulus() == self.P

    def root_of_unity(self, m: int):
        """ζ_m in F_P under the fixed embedding; InputError unless P ≡ 1 (mod m)."""
        if (self.P - 1) % m:
            raise InputError(f"arith {self.name}: ζ_{m} (needed by an involution over Q(ω), "
                             f"ω = e^(2πi/{m})) does not exist mod {self.P}: "
                             f"choose a prime P ≡ 1 (mod {m})")
        return flint.nmod(pow(_primitive_root(self.P), (self.P - 1) // m, self.P), self.P)

    def convert(self, value):
        if isinstance(value, flint.nmod) and value.modulus() == self.P:
            return value
        if isinstance(value, CycloNumber):
            r, out = self.root_of_unity(value.K.N), self.zero
            for c in reversed(value.p.coeffs()):
                out = out * r + self.convert(c)
            return out
        q = _as_fraction(value)
        if q.denominator % self.P == 0:
            what = (f"{q} has a denominator" if q.denominator.bit_length() + abs(q.numerator).bit_length() <= 400
                    else f"a denominator of {q.denominator.bit_length()} bits is")  # (a number, not pages of digits)
            raise BadReductionError(f"arith {self.name}: {what} divisible by {self.P} (bad reduction); "
                                    f"choose another prime")
        return flint.nmod(q.numerator, self.P) / q.denominator

    def format(self, e) -> str:
        return str(int(e))

    def magnitude(self, e) -> float:  # no order on F_P; never used for exact pivoting
        return float(int(e) != 0)

    def dft(self, rows, n, sign=1):
        """[Σ_i w_i ω^(sign·i·j) for j < n] for each list w of n elements in ``rows``, ω =
        :meth:`root_of_unity` (n) (n | P − 1): one ``nmod_mat`` product with the Vandermonde
        matrix of the powers of ω.

        >>> ar = GFArith(7)
        >>> [int(t) for t in ar.dft([[1, 1, 0]], 3)[0]]   # 1 + ω^j, ω = 3^2 = 2
        [2, 3, 5]
        """
        rows = _dft_rows(self, rows, n, sign)
        if not rows:
            return []
        V = self._vandermonde(n, sign)
        X = flint.nmod_mat([[self.convert(t) for t in w] for w in rows], self.P) * V
        return [[X[r, j] for j in range(n)] for r in range(len(rows))]

    @lru_cache(maxsize=16)
    def _vandermonde(self, n, sign):
        omega = self.root_of_unity(n) ** (1 if sign > 0 else n - 1)
        powers = [self.one]
        for _ in range(1, n):
            powers.append(powers[-1] * omega)
        return flint.nmod_mat([[powers[i * j % n] for j in range(n)] for i in range(n)], self.P)

    def native_solve(self, M, B):
        X = flint.nmod_mat(M, self.P).solve(flint.nmod_mat(B, self.P))
        return [[X[i, j] for j in range(X.ncols())] for i in range(X.nrows())]


register_arith("cyclo", CycloArith, letter="N", replace=True)  # the deferred factories of exact_khk.arith
register_arith("gf", GFArith, replace=True)
