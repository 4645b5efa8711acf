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

Exact step: every product in R is one at each n-th root of unity, so the step is
one 2×2 step over each factor of tⁿ − 1; :func:`exact_step` splits it along
tⁿ − 1 = (t^(n/2) − 1)(t^(n/2) + 1) while n is even, with the point's part over
each factor in lowest terms (along Kahan orbits that part's denominator is about a
share deg/n of the point's; a point of a few bits is solved over R unsplit).  Over each
factor, with denominators cleared, the 2×2 system lives in Z[t]/(tᵏ ∓ 1) and is solved by
Cramer's rule in closed form (:func:`kahan_cramer`: four products of point-sized
polynomials); the one division, by the determinant D, is Cramer's rule again where its
answer is small (down the tower tᵏ ∓ 1 → t^(k/2) ∓ 1 by D(t)·D(−t),
:meth:`CirculantRing.norm`) and otherwise approximates the quotients in fixed point by
Newton's iteration, recovers the common denominator by rational reconstruction and checks
the candidate exactly (:meth:`CirculantRing.solve`).  D is a
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
from math import gcd, lcm

from exact_khk.arith import _as_fraction
from exact_khk.linalg.dense import SingularMatrix
from exact_khk.linalg.numtheory import ramanujan_sum
from exact_khk.systems.lie_poisson.paths import DIVISION_BY_NORM_MAX_BITS, DIVISION_BY_NORM_MAX_WORK

try:  # python-flint is optional: without it the dense path is used
    import flint
except ImportError:  # pragma: no cover
    flint = None

_MINUS_T = flint.fmpz_poly([0, -1]) if flint is not None else None

#: guard bits added to the arithmetic's precision in the DFT (ball) step
GUARD_BITS = 20


#: the first rows of the blocks f11, f12, f21, f22 of f'(x) (docs/conventions.md) as combinations
#: of p[2b + c] = X(m_b) times u (c = 0) or v (c = 1), b = 11, 12, 21, 22:
#: 2 p[4] + p[7], p[6], −2 p[0] − p[3], −p[2]  (f11 = 2 X(m21)u + X(m22)v, …)
JACOBIAN_FIRST_ROWS = ((0, 0, 0, 0, 2, 0, 0, 1), (0, 0, 0, 0, 0, 0, 1, 0), (-2, 0, 0, -1, 0, 0, 0, 0),
                       (0, 0, -1, 0, 0, 0, 0, 0))


@dataclass(frozen=True)
class CirculantStructure:
    """The Hankel first rows m11, m12, m21, m22 of a field's Hessian M: Fractions, or
    (from ``circulant_structure(field, cyclotomic=True)`` only) elements of Q(ζ_n)."""

    n: int
    m: tuple  # ((m11, m12), (m21, m22)), each a tuple of n Fractions
    #: :data:`JACOBIAN_FIRST_ROWS`, for the numpy builder of I − εf'(x)
    #: (:func:`exact_khk.linalg.floating.system_matrix`), which asks the structure
    jacobian_first_rows = JACOBIAN_FIRST_ROWS

    def __hash__(self):  # computed once: every step looks the structure up in caches
        h = self.__dict__.get("_hash")
        if h is None:
            h = hash((self.n, self.m))
            object.__setattr__(self, "_hash", h)
        return h


def hankel_first_row(block, cyclotomic=False):
    """w (as Fractions) if ``block[i][j] == w[(i + j) % n]`` for all i, j (a cyclic
    Hankel matrix with rational entries), else None; with ``cyclotomic``, entries in
    Q(ζ) (:class:`~exact_khk.arith.cyclotomic.CycloNumber`) too, kept as they are."""
    n = len(block)
    if cyclotomic:
        from exact_khk.arith.cyclotomic import CycloNumber  # needs python-flint, as Q(ζ) does

        w = tuple(block[0])
        if not all(isinstance(t, (int, Fraction, CycloNumber)) for t in w):
            return None  # e.g. balls, whose == is no identity
    else:
        try:
            w = tuple(_as_fraction(t) for t in block[0])
        except (TypeError, ValueError, ArithmeticError):  # e.g. cyclotomic entries
            return None
    if all(block[i][j] == w[(i + j) % n] for i in range(n) for j in range(n)):
        return w
    return None


def circulant_structure(field, cyclotomic=False):
    """The :class:`CirculantStructure` of a Lie–Poisson field, or None.

    None for fields without a system and Hessian (a generic
    :class:`~exact_khk.systems.quadratic.QuadraticField`), non-homogeneous fields, or a
    Hessian with a block that is not cyclic Hankel.  With ``cyclotomic``, also the
    structure of a field over Q(ω) (an associated field of a non-rational involution),
    for the exact DFT step (:mod:`exact_khk.systems.lie_poisson.circulant_dft`).  Cached on the field.
    """
    key = "circulant over Q(zeta)" if cyclotomic else "circulant"
    cache = getattr(field, "_cache", None)
    if cache is not None and key in cache:
        return cache[key]
    out = circulant_structure(field) if cyclotomic else None
    system, M = getattr(field, "system", None), getattr(field, "hessian", None)
    if out is None and system is not None and M and field.homogeneous and len(M) == 2 * system.n:
        n = system.n
        rows = [[hankel_first_row([r[bj * n:(bj + 1) * n] for r in M[bi * n:(bi + 1) * n]], cyclotomic)
                 for bj in range(2)] for bi in range(2)]
        if all(w is not None for r in rows for w in r):
            out = CirculantStructure(n, tuple(tuple(r) for r in rows))
    if cache is not None:
        cache[key] = out
    return out




def structure_rows(st, p, q):
    """``(first, R)``: the rows over [x_0, …, x_{2n−1}, D] of the first row of each
    block of D·(I − εf'(x)), ``first[bi][bj][m]`` for entry (bi·n, bj·n + m), and of
    the right-hand side D·x (``R``, 2n rows), at ε = p/q, for a homogeneous field
    with the declared :class:`~exact_khk.systems.lie_poisson.circulant.CirculantStructure` ``st``
    — what :meth:`~exact_khk.systems.quadratic.QuadraticField.integer_rows` gives for
    those entries up to one common factor, in O(n²) integer operations instead of the
    O(n³) rational Jacobian.  The first rows of the blocks of f'(x) are
    :data:`JACOBIAN_FIRST_ROWS` of the X(m_b)u and X(m_b)v, X(w)u having the entry
    Σ_j w[(k + j) mod n] u_j at k; the m_b are scaled by den, their common denominator.
    """
    n = st.n
    den = lcm(*(t.denominator for row in st.m for w in row for t in w))
    m = [[int(t * den) for t in w] for row in st.m for w in row]  # m11, m12, m21, m22
    first = [[[], []], [[], []]]
    for r, F in enumerate(JACOBIAN_FIRST_ROWS):
        bi, bj = divmod(r, 2)
        # the combination of the m_b that multiplies u (c = 0) and v (c = 1) in this block
        w = [[sum(F[2 * b + c] * m[b][i] for b in range(4)) for i in range(n)] for c in range(2)]
        for k in range(n):
            first[bi][bj].append([-p * w[c][(k + j) % n] for c in range(2) for j in range(n)]
                                 + [den * q if bi == bj and k == 0 else 0])
    R = [[den * q if i == j else 0 for j in range(2 * n)] + [0] for i in range(2 * n)]
    return first, R


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


def kahan_cramer(m, mu, uh, vh, p, S, mul):
    """Cramer's rule for :func:`kahan_system` with ``eps`` = p, ``one`` = S and
    right-hand side (uh, vh), in closed form: ``(det, (adj·x̂)_u, (adj·x̂)_v)``
    from four products of point-sized polynomials (the generic rule takes six,
    plus eight by the m_kl).  With f11 = 2m21û + m22v̂, f12 = m22û,
    f21 = −(2m11û + m12v̂), f22 = −m12û (:func:`kahan_system`),
    f11f22 − f12f21 = 2μû² with μ = m11m22 − m12m21 (given: it depends on the
    field only), so

        det = S² − pS(f11 + f22) + 2p²û·μû,
        (adj·x̂)_u = Sû + pû(m12û + m22v̂),
        (adj·x̂)_v = Sv̂ − p(v̂ f11 + û(2m11û + m12v̂)).
    """
    (m11, m12), (m21, m22) = m
    a, b, c = mul(m11, uh), mul(m12, uh), mul(m22, vh)
    f11 = 2 * mul(m21, uh) + c
    g = a * 2 + mul(m12, vh)
    mu_u = mul(mu, uh)
    det = mul(uh, mu_u) * (2 * p * p) - (f11 - b) * (p * S) + S * S
    ru = uh * S + mul(uh, b + c) * p
    rv = vh * S - (mul(vh, f11) + mul(uh, g)) * p
    return det, (ru, rv)


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


# --- exact: R = Q[t]/(tⁿ − 1), solved over Z[t]/(tⁿ − 1) ---

#: the prime of the exact unit test of a determinant d (a unit mod p is a unit over Q;
#: otherwise gcd(d, tⁿ − 1) over Z decides)
UNIT_PRIME = 4611686018427387847
#: least bits of the floating approximation of d⁻¹ (an acb DFT) that Newton's iteration refines
#: (:func:`_newton_start` picks from START_BITS to 2·START_BITS − 1)
START_BITS = 128
#: Newton's steps are planned for log ‖d̂⁻¹‖ up to this many bits (a larger one costs one
#: more, short, step)
NEWTON_SLACK_BITS = 4
#: the last answer's height relative to its d sets the next division's first precision when
#: it is at most this (Kahan steps along orbits ~1.1, the certificates' J((x + x̃)/2) solves
#: ~1.33); a larger one comes from a first step off a small point (~n) and is no guide ...
HINT_TRUSTED_RATIO = 2.0
#: ... and then, or without a last answer, the first precision is set for this ratio
HINT_MAX_RATIO = 1.25
#: the approximate quotients are trusted to within 2^TOLERANCE_BITS units (a heuristic:
#: every answer is checked exactly)
TOLERANCE_BITS = 12


def _shift(p, s):
    """⌊p·2^s⌋ coefficientwise for an fmpz_poly p (s < 0: a floor shift right)."""
    if s >= 0:
        return p * (flint.fmpz(1) << s) if s else p
    return flint.fmpz_poly([c >> -s for c in p.coeffs()])


def _arb_int(x, s):
    """⌊mid(x)·2^s⌋ for an arb x, as an int."""
    man, e = x.mid().man_exp()
    e = int(e) + s
    return int(man) << e if e >= 0 else int(man) >> -e


class CirculantRing:
    """Q[t]/(tⁿ − s), s = 1 (circulants; ``sign``) or −1 (the factor tⁿ + 1 of t²ⁿ − 1 in
    :func:`exact_step`): ``fmpq_poly`` elements for the public helpers, ``fmpz_poly``
    (denominators cleared) inside the exact step.

    :meth:`solve` divides by a unit d without forming d⁻¹ over Q (whose
    coefficients are far larger than the quotient's along Kahan orbits): the
    quotients r/d are approximated in fixed point — d⁻¹ from an acb DFT at
    :data:`START_BITS` to twice as many bits (chosen so that the doublings end on the
    precision needed), refined by Newton's iteration V ← V(2 − dV), every
    step two ``fmpz_poly`` products and shifts — to 2^−Q; the common
    denominator δ comes from rational reconstruction of one approximate
    coefficient (2×2 lattice reduction), and the candidate W = round(δ·r/d) is
    accepted only if d·W = δ·r holds exactly.  So the numerics decide the
    speed, never the answer.  Q starts from a hint (the last answer's height
    relative to d), doubles after a first miss and then grows fourfold until
    the check passes, up to twice a bound on the answer's height read off d's
    values at the roots of unity (δ divides Π_ω d(ω)); if the attempt at that
    bound fails, Cramer's rule down the tower answers (:meth:`norm`), as it does
    when Cramer's bound is small (:func:`by_norm`).  A division costs a few polynomial
    products at the size of the answer, all in FLINT (no p-adic reductions:
    a reduction modulo a big p^k costs about two products, a shift nearly
    nothing).
    """

    def __init__(self, n, sign=1):
        if flint is None:  # pragma: no cover
            raise ImportError("the structured exact step needs python-flint")
        self.n, self.sign, self._hankel = n, sign, {}
        self.modulus = flint.fmpq_poly([-sign] + [0] * (n - 1) + [1])
        self._zmodulus = flint.fmpz_poly([-sign] + [0] * (n - 1) + [1])
        #: sign −1: ζ^−i at the precisions of the DFT start (the roots of tⁿ + 1 are ζ·ωʲ,
        #: ζ = e^{iπ/n}, so d's values there are the DFT of the twisted d_i ζ^i)
        self._twists = {}
        #: answer height / height of d at the last division: where the next division
        #: starts its precision search (a hint only; results are checked); None: no hint
        self.height_ratio = None

    def mul(self, a, b):
        """a·b mod tⁿ − s (fmpq_poly or fmpz_poly)."""
        return self.fold(a * b)

    def fold(self, c):
        """c mod tⁿ − s for c of degree < 2n."""
        if c.degree() < self.n:
            return c
        low, high = c.truncate(self.n), c.right_shift(self.n)
        return low + high if self.sign == 1 else low - high

    def twist(self, prec):
        """[e^{−iπi/n} for i < n] as acb at ``prec`` bits (sign −1), cached."""
        if prec not in self._twists:
            with flint.ctx.workprec(prec):
                self._twists[prec] = [flint.acb(flint.fmpq(-i, self.n)).exp_pi_i() for i in range(self.n)]
        return self._twists[prec]

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

    def parts(self, st, reflected=False):
        """``{ring: (m, μ)}`` for this ring and each factor of tⁿ − 1 (:meth:`factors`),
        cached: the integer Hankel polynomials m_kl of ``st`` (or their reflections) and
        μ = m11m22 − m12m21, reduced mod the ring's modulus."""
        key = (st, reflected, "parts")
        if key not in self._hankel:
            m = self.integer_hankel(st, reflected)[0]
            hankel = {self: m}
            for ring in self.factors():
                if ring.sign == 1:
                    hankel[ring] = m
                else:
                    halves = [[_halves(w, ring.n) for w in row] for row in m]
                    hankel[ring] = tuple(tuple(h[1] for h in row) for row in halves)
                    m = tuple(tuple(h[0] for h in row) for row in halves)
            self._hankel[key] = {ring: (m, ring.mul(m[0][0], m[1][1]) - ring.mul(m[0][1], m[1][0]))
                                 for ring, m in hankel.items()}
        return self._hankel[key]

    def factors(self):
        """Rings of this ring's own (each keeps the hint of its own divisions) for the
        factors t^(n/2) + 1, t^(n/4) + 1, …, t^b + 1 and t^b − 1 of tⁿ − 1 (n = 2^a·b, b odd;
        just this ring for odd n), cached."""
        if "factors" not in self._hankel:
            out, k = [], self.n
            while k % 2 == 0:
                k //= 2
                out.append(CirculantRing(k, -1))
            self._hankel["factors"] = out + [self if k == self.n else CirculantRing(k)]
        return self._hankel["factors"]

    def solve(self, d, rhs):
        """``(W, δ)``: fmpz_polys W_i and an integer δ > 0 with d·W_i = δ·r_i in
        Z[t]/(tⁿ − s), i.e. W_i/δ = r_i/d, for fmpz_poly d and r_i.

        Raises :class:`SingularMatrix` exactly when d is not a unit of
        Q[t]/(tⁿ − s) (gcd(d, tⁿ − s) ≠ 1, i.e. d vanishes at a root of tⁿ − s).
        """
        n, hd = self.n, max(d.height_bits(), 1)
        hr = max(max(r.height_bits() for r in rhs), 1)
        if by_norm(n, _hadamard_bits(n, hd, hr)):
            return self._remember(self._solve_norm(d, rhs), hd)
        self._check_unit(d)
        inverse = _Reciprocal(self, d, hd)
        last = self.height_ratio
        ratio = HINT_MAX_RATIO if last is None or last > HINT_TRUSTED_RATIO else max(last, 0.25)
        Q, missed = int(2 * ratio * hd * 1.05) + 64 + 2 * TOLERANCE_BITS, False
        while True:
            found = self._attempt(d, rhs, inverse, hr, Q)
            if found is not None:
                return self._remember(found, hd)
            # the hint was too low: a sharper bound than Cramer's from d's values at the
            # roots of unity (det C(d) = Π_ω d(ω)), needed only now
            cap = 2 * inverse.answer_bits(hr) + 64 + 2 * TOLERANCE_BITS
            if Q >= cap:  # numerics out of reach (d far too ill-conditioned for the floating start)
                return self._solve_norm(d, rhs)  # pragma: no cover
            # a first miss is mostly narrow (the answer a little above the hint): twice the
            # precision; after that a few fourfold steps, then the bound
            Q = min(cap, 2 * Q) if not missed else cap if 8 * Q >= cap else 4 * Q
            missed = True

    def _attempt(self, d, rhs, inverse, hr, Q):
        """(W, δ) from quotients approximated to 2^−Q, checked exactly, or None."""
        hd = inverse.hd
        V, b = inverse.refine(Q + max(0, hr - hd) + 2 * self.n.bit_length() + 2 * TOLERANCE_BITS)
        if V is None:
            return None
        Z = [_shift(self.mul(r, V), Q - hd - b) for r in rhs]  # ≈ 2^Q·r/d
        m, mask = 1 << Q, (1 << Q) - 1
        half = m >> 1
        delta, scaled = flint.fmpz(1), Z
        for _ in range(2 * self.n + 2):  # each round finds one more factor of δ
            tol = int(delta) << TOLERANCE_BITS
            big = next((c for z in scaled for c in map(int, z.coeffs())
                        if abs(((c + half) & mask) - half) > tol), None)
            if big is None:
                break
            den = _small_denominator(big & mask, m, tol) or rational_reconstruction(
                flint.fmpz(big & mask), flint.fmpz(m))[1]
            delta *= den
            if den <= 1 or delta.bit_length() > Q // 2:
                return None
            scaled = [z * delta for z in Z]
        else:
            return None
        halves = flint.fmpz_poly([half] * self.n)  # round to nearest
        W = [_shift(z + halves, -Q) for z in scaled]
        if any(self.mul(d, w) != r * delta for w, r in zip(W, rhs)):
            return None
        return W, delta

    def _check_unit(self, d):
        """Raise :class:`SingularMatrix` unless d is a unit of Q[t]/(tⁿ − s): a unit mod
        :data:`UNIT_PRIME` is one over Q (its resultant with tⁿ − s is nonzero mod p);
        otherwise gcd(d, tⁿ − s) over Z decides (a root of tⁿ − s is one of t²ⁿ − 1)."""
        p = UNIT_PRIME
        if flint.nmod_poly(d.coeffs(), p).gcd(flint.nmod_poly(self._zmodulus.coeffs(), p)).degree() == 0:
            return
        if d.gcd(self._zmodulus).degree() != 0:
            raise SingularMatrix("the 2x2 determinant vanishes at a root of t^n - 1")

    def _remember(self, found, hd):
        W, delta = found
        self.height_ratio = max(delta.bit_length(), *(w.height_bits() for w in W)) / hd
        return found

    def _solve_norm(self, d, rhs):
        """(W, δ) by Cramer's rule, W_i = A·r_i and δ = N from :meth:`norm`, in lowest terms:
        for small answers, where it beats the fixed-point division's set-up, and as the
        fallback when the numerics are out of reach."""
        N, A = self.norm(d)
        if N == 0:
            raise SingularMatrix("the 2x2 determinant vanishes at a root of t^n - 1")
        W = [self.fold(A * r) for r in rhs] if A is not None else list(rhs)
        g = N
        for w in W:
            g = g.gcd(w.content())
        if N < 0:
            g = -g
        return [w // g for w in W], N // g

    def norm(self, d):
        """``(N, A)``: an integer N and an fmpz_poly A (None for 1) with d·A = N in
        Z[t]/(tⁿ − s); N is 0 exactly when d is not a unit, and ± Π d(ω) over the roots of
        tⁿ − s when n is a power of 2 (else it may carry other factors: lowest terms are the
        caller's).

        Down the tower: for even n, d(t)·d(−t) is even, e(t²), so (N, A) = (N', d(−t)·A'(t²))
        with (N', A') those of e in Z[s]/(s^(n/2) − s); at n = 1, N = d; at odd n > 1 by the
        Galois conjugates (:meth:`_galois_norm`; tⁿ + 1 is tⁿ − 1 at −t).  Every step is a few
        ``fmpz_poly`` products; d⁻¹ over Q (``fmpq_poly.xgcd``, FLINT's multimodular gcd,
        which does not know the tower) is 5–11× slower at 200–2000 bits, n = 4..32, and
        1.3–10× at 100–4000 bits, odd n = 9..21 (faster only for d of a few dozen bits)."""
        n = self.n
        if n == 1:
            return d[0], None
        if n % 2:
            if self.sign == -1:  # t → −t maps Z[t]/(tⁿ + 1) onto Z[t]/(tⁿ − 1)
                N, A = circulant_ring(n).norm(d(_MINUS_T))
                return N, None if A is None else A(_MINUS_T)
            return self._galois_norm(d)
        conjugate = d(_MINUS_T)
        N, A = circulant_ring(n // 2, self.sign).norm(self.fold(d * conjugate).deflate(2))
        if N == 0:
            return N, None
        return _lower_terms(N, conjugate if A is None else self.fold(conjugate * A.inflate(2)))

    def _galois_norm(self, d):
        """:meth:`norm` for odd n > 1 (sign 1), by the conjugates σ_k: t → tᵏ (k a unit mod n),
        ring automorphisms that permute coefficients.  Up a chain of subgroups of (Z/n)^×,
        each of prime index p over the last, e ← e·C with C the product of e's p − 1
        conjugates by the new cosets' representatives (the first: σ_−1, the reflection), so
        that at the end P = d·A is fixed by every σ_k: at a primitive q-th root of unity (q | n)
        its value v_q is an integer, (Σ_i P_i c_q(i))/φ(q) (Ramanujan sums).  With
        E_q = Σ_i c_q(i) tⁱ (n times the idempotents: Σ_q E_q = n), d⁻¹ = Σ_q A·E_q/(n·v_q);
        at q = 1 it is E_1/(n·d(1)) instead (v_1 = d(1)^φ(n) would carry the extra factor
        A(1) = d(1)^(φ(n) − 1)), and the last A·E_n is n·A less the others, so for prime n no
        product is left.  N = n·L, L the lcm of d(1) and the v_q; N = 0 if one of them is."""
        n = self.n
        tower, components = _galois_data(n)
        e, A = d, None
        for perms in tower:
            c = self.coeffs(e)
            C = [flint.fmpz_poly([c[i] for i in perm]) for perm in perms]
            while len(C) > 1:  # their product as a balanced tree (p − 1 may be large: n = 1019)
                C = [self.fold(a * b) for a, b in zip(C[::2], C[1::2])] + C[len(C) & ~1:]
            A = C[0] if A is None else self.fold(A * C[0])
            e = self.fold(e * C[0])
        c = self.coeffs(e)
        values = [d(1)]  # d(1), then v_q for q > 1
        values += [sum(c[i] * w for i, w in weights) // phi for phi, weights, _ in components[1:]]
        if any(v == 0 for v in values):
            return flint.fmpz(0), None
        parts = [components[0][2]] + [self.fold(A * E) for _, _, E in components[1:-1]]
        parts.append(A * n - sum(parts[1:], flint.fmpz_poly()) - A(1) * components[0][2])
        L = values[0].lcm(values[-1])  # v_n = N_n(d): its lowest terms are _lower_terms's
        for i in range(1, len(parts) - 1):  # A·E_q/v_q in lower terms (v_q = N_q(d)^(φ(n)/φ(q)))
            g = parts[i].content().gcd(values[i])
            parts[i], values[i] = parts[i] // g, values[i] // g
            L = L.lcm(values[i])
        return _lower_terms(n * L, sum(((L // v) * B for v, B in zip(values, parts)), flint.fmpz_poly()))


class _Reciprocal:
    """Fixed-point approximations V ≈ 2^b·d̂⁻¹ of the inverse of d̂ = 2^−hd·d (a unit of
    R ⊗ R), refined on demand.  ``refine(bits)`` returns (V, b) with b ≥ bits and
    V accurate to about 2^(b − bits) units, or (None, b) when the iteration does
    not converge (d far too ill-conditioned for the floating start: a wider start
    is tried first)."""

    def __init__(self, ring, d, hd):
        self.ring, self.d, self.hd = ring, d, hd
        self.V, self.b, self.start = None, 0, START_BITS
        self.values = None  # (2^(b0 − hd)·d(ω) as acb balls, b0) from the first start at b0 bits
        self.logs = None  # (log2 |det C(d)|, log2 max 1/|d(ω)|), from those values

    def _widen(self, limit):
        """Drop V and start again from a 4× wider floating start; False once the start
        would exceed ``limit`` bits."""
        self.V, self.start = None, self.start * 4
        return self.start <= limit

    def _begin(self):
        """V at b = start bits from the DFT: d̂(ω) at every n-th root of unity, inverted."""
        n, b0 = self.ring.n, self.start
        top = [int(c) for c in _shift(self.d, b0 - self.hd).coeffs()] + [0] * n
        with flint.ctx.workprec(b0 + 64):
            if self.ring.sign == 1:
                vals = flint.acb.dft([flint.acb(c) for c in top[:n]])  # 2^(b0 − hd)·d(ω)
            else:  # at the roots of tⁿ + 1
                twist = self.ring.twist(b0 + 64)
                vals = flint.acb.dft([c * w for c, w in zip(top[:n], twist)])
            if any(0 in v for v in vals):
                return False
            inv = flint.acb.dft([1 / v for v in vals], inverse=True)
            if self.ring.sign != 1:
                inv = [c / w for c, w in zip(inv, twist)]
            self.V = flint.fmpz_poly([_arb_int(c.real, 2 * b0) for c in inv])
        self.b = b0
        if self.values is None:
            self.values = (vals, b0)
        return True

    def answer_bits(self, hr):
        """An upper estimate of the bits of δ and W for right-hand sides of height hr:
        δ ≤ |det C(d)| and |W_i| ≤ δ·n·2^hr·max 1/|d(ω)| (from the floating start;
        Hadamard's bound when d is too ill-conditioned for it)."""
        n = self.ring.n
        while self.values is None and not self._begin():
            if not self._widen(64 * START_BITS):
                return _hadamard_bits(n, self.hd, hr)
        if self.logs is None:  # |d(ω)| within n (truncation) of the DFT's balls
            vals, b0 = self.values
            shift = b0 - self.hd
            with flint.ctx.workprec(b0 + 64):
                absv = [abs(v) for v in vals]
                self.logs = (sum(_log2(a.upper() + n) for a in absv) - n * shift,
                             shift - min(_log2(max(a.lower() - n, flint.arb(2) ** -b0)) for a in absv))
        det_bits, inv_bits = self.logs
        return int(max(det_bits, det_bits + hr + n.bit_length() + inv_bits)) + 2

    def refine(self, bits):
        R, d, hd = self.ring, self.d, self.hd
        if self.b == 0:  # not started yet: start where the doublings end on the target
            guard = R.n.bit_length() + 8 + NEWTON_SLACK_BITS
            self.start = _newton_start(bits + guard, guard)
        while True:
            if self.V is None and not self._begin():
                if not self._widen(4 * bits):
                    return None, self.b
                continue
            excess = max(self.V.height_bits() - self.b, 0) + R.n.bit_length() + 8  # log ‖V‖ + guard
            if self.b >= bits + excess:
                return self.V, self.b
            b, V = self.b, self.V
            b2 = min(2 * b - excess, bits + excess)
            if b2 <= b:  # ‖V‖ too large for the start's precision
                if not self._widen(4 * bits):
                    return None, self.b
                continue
            h = min(hd, b2)  # d to at most b2 bits (its own hd bits cost less than zeros)
            P = R.fold(_shift(d, h - hd) * V)  # ≈ 2^(b + h)·(1 − E)
            E = _shift(flint.fmpz_poly([flint.fmpz(1) << (b + h)]) - P, b2 - h - b)  # ≈ 2^b2·E
            if E.height_bits() > b2 - b // 2:  # |E| > 2^−b/2: no convergence, start wider
                if not self._widen(4 * bits):
                    return None, self.b
                continue
            self.V, self.b = _shift(V, b2 - b) + _shift(R.fold(V * E), -b), b2


def _newton_start(target, guard) -> int:
    """The start precision b in [START_BITS, 2·START_BITS) from which Newton's steps
    b → 2b − guard reach ``target`` without a last short step (the DFT start costs about
    the same anywhere in that range: 57–59 µs at n = 16, 117–121 µs at n = 32)."""
    b = target
    while b >= 2 * START_BITS:
        b = (b + guard + 1) // 2
    return max(b, START_BITS)


def _lower_terms(N, A):
    """(N/g, A/g) for g = gcd(N, content of A), N ≠ 0: d·A = N stays true, and along orbits g is
    most of N (6 234 of its 7 149 bits over t¹⁶ + 1 at n = 32, 434 bits), so the products
    above, A·r, and the last gcds work on far smaller numbers."""
    g = N.gcd(A.content())
    return (N // g, A // g) if g != 1 else (N, A)


@lru_cache(maxsize=None)
def _galois_data(n):
    """``(tower, components)`` of :meth:`CirculantRing._galois_norm` for odd n > 1.  tower:
    per subgroup step, one index list per conjugate σ_k (σ_k(e)_j = e_i for i = j·k⁻¹ mod n);
    components: per divisor q of n, (φ(q), [(i, Σ c_q over the class of i)] over one index i
    per class {i: gcd(i, n) = g}, the Ramanujan sums c_q(i) for i < n as an fmpz_poly)."""
    units = [k for k in range(1, n) if gcd(k, n) == 1]
    group, tower = {1}, []
    while len(group) < len(units):
        g = next(k for k in [n - 1] + units if k not in group)
        order, x = 1, g
        while x not in group:
            x, order = x * g % n, order + 1
        p = next(p for p in range(2, order + 1) if order % p == 0)  # a step of prime index
        g = pow(g, order // p, n)
        tower.append([[j * pow(k, -1, n) % n for j in range(n)] for k in (pow(g, i, n) for i in range(1, p))])
        group = {h * pow(g, i, n) % n for h in group for i in range(p)}
    divisors = [q for q in range(1, n + 1) if n % q == 0]
    components = []
    for q in divisors:
        c = [ramanujan_sum(q, i) for i in range(n)]
        weights = [(g % n, sum(c[i] for i in range(n) if gcd(i, n) == g)) for g in divisors]
        components.append((c[0], weights, flint.fmpz_poly(c)))  # c_q(0) = φ(q)
    return tuple(tower), tuple(components)


def by_norm(n, bound) -> bool:
    """Whether a division over Z[t]/(tⁿ ∓ 1) whose answer has at most ``bound`` bits
    (Cramer's) is Cramer's rule down the tower (the rule of ``systems.lie_poisson.paths``: b·bound bounded,
    b the odd part of n, where the tower ends in the Galois conjugates)."""
    b = n >> ((n & -n).bit_length() - 1)
    return n == 1 or (bound <= DIVISION_BY_NORM_MAX_BITS and b * bound <= DIVISION_BY_NORM_MAX_WORK)


def _hadamard_bits(n, hd, hr) -> int:
    """Bits of Cramer's rule's answer to d·W = δ·r (heights hd, hr) by Hadamard: δ ≤ |det C(d)|
    ≤ ‖d‖₂ⁿ and |adj(C(d))·r| ≤ ‖d‖₂ⁿ⁻¹‖r‖₂ (C(d) the n×n circulant of d, ‖d‖₂ ≤ √n·2^hd)."""
    return int(n * (hd + n.bit_length() / 2 + 1) + hr) + 1


def _log2(x) -> float:
    """log2 of a positive arb, as a float (arbs far beyond the float range included)."""
    return float(x.log() / flint.arb(2).log())


def _small_denominator(a, m, tol, steps=48):
    """A small q ≥ 1 with |q·a mod± m| ≤ q·tol from the first ``steps`` steps of
    Euclid's algorithm on (m, a) (the remainders are ±(q·a mod m) for the
    cofactors q), or None: the cheap case of :func:`rational_reconstruction`
    (after the first factor of δ, the others are usually tiny)."""
    r0, r1, t0, t1 = m, a, 0, 1
    for _ in range(steps):
        if abs(r1) <= abs(t1) * tol:
            return flint.fmpz(abs(t1))
        if not r1:
            return None
        q = r0 // r1
        r0, r1, t0, t1 = r1, r0 - q * r1, t1, t0 - q * t1
    return None


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


@lru_cache(maxsize=128)
def circulant_ring(n: int, sign: int = 1) -> CirculantRing:
    """The (cached) ring Q[t]/(tⁿ − s): the exact step's, and those of
    :meth:`CirculantRing.norm`'s tower (which uses their products only, not their hints)."""
    return CirculantRing(n, sign)


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


def _halves(p, k):
    """(p mod tᵏ − 1, p mod tᵏ + 1) for an fmpz_poly p of degree < 2k."""
    low, high = p.truncate(k), p.right_shift(k)
    return low + high, low - high


def point_polys(vals, reflected=False):
    """``(u, v, dx)``: the halves of a point of 2n fmpq values as fmpz_polys over their
    common denominator dx (with ``reflected``, û and v̂: :func:`reflect`), cleared in C
    (``fmpq_mat.numer_denom``: 0.5–1.0× a Python lcm loop; an ``fmpq_poly`` would also
    take its numerators' content, 5–20× slower from a few thousand bits)."""
    n = len(vals) // 2
    fix = reflect if reflected else list
    Z, dx = flint.fmpq_mat(2 * n, 1, fix(vals[:n]) + fix(vals[n:])).numer_denom()
    z = Z.entries()
    return flint.fmpz_poly(z[:n]), flint.fmpz_poly(z[n:]), dx


def split_solve(R, u, v, dx, solve_part):
    """``(W, δ)``: a 2×2 solve over R for the point with integer polynomials (u, v) and
    denominator dx, one solve over each factor of tⁿ − 1 (:meth:`CirculantRing.factors`;
    the caller's per-factor data: :meth:`CirculantRing.parts`), joined.

    Every product in R is one at each n-th root of unity, so a system whose entries are
    products of the point's polynomials with fixed ones is one system over each factor,
    on the point's part there.  Along Kahan orbits each part has a denominator of its own,
    about a share deg/n of dx's bits (dx is about their product), so the factor
    t^(n/2) + 1 works on half the coefficients at half the height.  ``solve_part(ring, pu,
    pv, s)`` solves over ``ring`` for the part (pu, pv)/s in lowest terms and
    returns ``(W_part, δ_part)``; the parts join by W = (a + b + tᵏ(a − b))/2 from
    W ≡ a mod tᵏ − 1 and W ≡ b mod tᵏ + 1.
    """
    def reduced(ring, parts):
        pu, pv = parts
        g = pu.content().gcd(pv.content()).gcd(dx)  # the part's own denominator is dx/g
        pu, pv, s = (pu // g, pv // g, dx // g) if g != 1 else (pu, pv, dx)
        return solve_part(ring, pu, pv, s)

    return _over_factors(R, [u, v], reduced)


def _over_factors(R, polys, solve_part):
    """``(W, δ)`` joined from ``solve_part(ring, parts)`` → (W_part, δ_part) over each
    factor of tⁿ − 1 (:meth:`CirculantRing.factors`), ``parts`` the polynomials ``polys``
    mod the factor (p mod tᵏ ∓ 1 is low ± high); the parts join by
    W = (a + b + tᵏ(a − b))/2 from W ≡ a mod tᵏ − 1 and W ≡ b mod tᵏ + 1."""
    factors, solved = R.factors(), []
    for ring in factors:
        if ring.sign == 1:
            parts = polys
        else:
            halves = [_halves(p, ring.n) for p in polys]
            polys, parts = [h[0] for h in halves], [h[1] for h in halves]
        solved.append(solve_part(ring, parts))
    W, delta = solved.pop()
    for ring, (B, beta) in zip(factors[-2::-1], solved[::-1]):
        join = delta.lcm(beta)
        fa, fb = join // delta, join // beta
        W = [(a * fa + b * fb) + (a * fa - b * fb).left_shift(ring.n) for a, b in zip(W, B)]
        delta = 2 * join
    return W, delta


def split_divide(R, d, rhs):
    """``(W, δ)`` as :meth:`CirculantRing.solve` (d·W_i = δ·r_i in Z[t]/(tⁿ − 1)), one
    division over each factor of tⁿ − 1 with d's part and the r_i's parts each divided by
    its content first (along orbits, as in :func:`split_solve`, a part of a point has far
    fewer bits than the point).  Raises :class:`SingularMatrix` when d is not a unit."""
    def divide(ring, parts):
        dp, rp = parts[0], parts[1:]
        gd = dp.content() or flint.fmpz(1)  # d's part 0: not a unit, ring.solve says so
        gr = flint.fmpz(0)
        for r in rp:
            gr = gr.gcd(r.content())
        gr = gr or flint.fmpz(1)
        W, delta = ring.solve(dp // gd, [r // gr for r in rp])
        return [w * gr for w in W], delta * gd

    return _over_factors(R, [d] + list(rhs), divide)


def exact_step(st: CirculantStructure, x, eps, ar=None):
    """Φ_f(x, ε) by 2×2 solves over the factors of R (:func:`split_solve`; exact: ``x``,
    ``eps`` in a rational arithmetic).

    Over each factor, with the point's part X/dx in lowest terms, ε = e/q and Hankel
    polynomials m/dm, s·(I − εf'(x)) with s = q·dm·dx has integer entries and
    right-hand side q·dm·X̂; Cramer's rule in closed form (:func:`kahan_cramer`) leaves
    one division by the determinant (:meth:`CirculantRing.solve`).  Raises
    :class:`SingularMatrix` exactly when det(I − εf'(x)) = 0 (a factor's determinant
    is not a unit).
    """
    from exact_khk.arith import get_arith

    ar = get_arith(ar or "flint")
    R = circulant_ring(st.n)
    dm = R.integer_hankel(st)[1]
    u, v, dx = point_polys([_fmpq(ar, t) for t in x], reflected=True)
    e = _fmpq(ar, eps)
    parts = R.parts(st)

    def solve_part(ring, pu, pv, s):
        det, rhs = kahan_cramer(*parts[ring], pu, pv, e.p, e.q * dm * s, ring.mul)
        return ring.solve(det, [r * (e.q * dm) for r in rhs])

    (wu, wv), delta = split_solve(R, u, v, dx, solve_part)
    return _from_fmpq(ar, [flint.fmpq(c, delta) for c in reflect(R.coeffs(wu)) + reflect(R.coeffs(wv))])


def htilde_solve(R, st, rhs_structures, u, v, dx, e):
    """``(W, δ)``: R_st z_i = M_i x (R_st = I − ε²(M J(x))², M the Hessian of ``st``, M_i that
    of ``rhs_structures[i]``) for x = (u, v)/dx (:func:`point_polys`) and ε = e (fmpq), by
    Cramer's rule over each factor of tⁿ − 1 (:func:`split_solve`): z_i has the reflected
    halves W[2i]/(δ·dm_i), W[2i + 1]/(δ·dm_i) (dm_i the denominator of M_i's Hankel
    polynomials).  Over each factor, with the point's part X'/s in lowest terms and
    M = m̂/dm (reflected Hankel polynomials m̂), the matrix is a = (q·dm·s)² R_st, so
    a z_i = q²·dm²·s·(m̂_i X')/dm_i.  Raises :class:`SingularMatrix` at a pole of H̃."""
    dm = R.integer_hankel(st, reflected=True)[1]
    parts = [R.parts(sti, reflected=True) for sti in [st] + list(rhs_structures)]

    def solve_part(ring, u, v, s):
        (a11, a12, a21, a22), _ = htilde_system(parts[0][ring][0], u, v, e.p, ring.mul, one=(e.q * dm * s) ** 2)
        scale = e.q ** 2 * dm ** 2 * s
        adj = []
        for structure in parts[1:]:
            (m11, m12), (m21, m22) = structure[ring][0]
            r0 = (ring.mul(m11, u) + ring.mul(m12, v)) * scale
            r1 = (ring.mul(m21, u) + ring.mul(m22, v)) * scale
            adj += [ring.mul(a22, r0) - ring.mul(a12, r1), ring.mul(a11, r1) - ring.mul(a21, r0)]
        return ring.solve(ring.mul(a11, a22) - ring.mul(a12, a21), adj)

    return split_solve(R, u, v, dx, solve_part)


def exact_htilde(st: CirculantStructure, x, eps, ar=None):
    """H̃(x, ε) = xᵀ (I − ε²(M J(x))²)^{-1} M x by 2×2 solves over the factors of R
    (:func:`htilde_solve`; exact).

    Equal (``==``) to :func:`exact_khk.systems.lie_poisson.invariants.Htilde`; raises
    :class:`SingularMatrix` where H̃ has a pole.  xᵀz is the constant coefficient of
    u(t) ẑ_u(t) + v(t) ẑ_v(t) (z's reflected halves ẑ).
    """
    from exact_khk.arith import get_arith

    ar = get_arith(ar or "flint")
    R = circulant_ring(st.n)
    u, v, dx = point_polys([_fmpq(ar, t) for t in x])
    (wu, wv), delta = htilde_solve(R, st, [st], u, v, dx, _fmpq(ar, eps))
    dm = R.integer_hankel(st, reflected=True)[1]
    return _from_fmpq(ar, [flint.fmpq((R.mul(u, wu) + R.mul(v, wv))[0], dx * delta * dm)])[0]


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
