"""Degree growth of the iterates Φ^k of a Kahan map, by restriction to random lines over F_p.

**What is reported.**  For ε a fixed rational, one Kahan step
Φ(x) = x + 2ε(I − εf'(x))^{-1} f(x) is a birational map of affine N-space.  Its
iterate Φ^k is written with a common denominator in lowest terms,
Φ^k = (P_1, …, P_N)/Q with gcd(P_1, …, P_N, Q) = 1, and

    d_k = deg Φ^k = max(deg P_1, …, deg P_N, deg Q)

is the degree of the *projective* map [x_0 : x] ↦ [x_0^{d} Q(x/x_0) : x_0^{d} P(x/x_0)]
of P^N (the homogenisation by an extra coordinate x_0).  This is the degree the
literature on degree growth uses; it is the same for homogeneous and
non-homogeneous fields (a homogeneous quadratic field does *not* make Φ
homogeneous: Φ(λx, ε) = λΦ(x, λε)).  d_0 = 1 (the identity).

**How.**  With (Q, P) the homogeneous coordinates of a point, one step is the
integer-coefficient linear system M(Q, P) y = r(Q, P) of
:meth:`~exact_khk.systems.quadratic.QuadraticField.integer_rows` (M, r linear in
(Q, P)); Cramer's rule gives the degree-N homogeneous polynomial map
C(Q, P) = (det M, adj(M) r) whose projective class is Φ.  Along a line
ℓ(t) = a + t b (a, b random in F_p^N) the point (1, a + t b) is iterated in
F_p[t]^{N+1}: fraction-free elimination (Bareiss, exact divisions in
``nmod_poly``) gives C of the current point, and the gcd of its N + 1
coordinates is divided out at every step.  The degree of the reduced vector is
the degree of the curve Φ^k(ℓ).  From dimension 8 (:func:`line_route`) the same
degree is read off values instead: the orbits of points ℓ(s) of the line, one
``nmod_mat`` solve per point and step, give the values of L₁(G)/L₂(G) for two
random linear forms, whose degree Cauchy interpolation finds
(:func:`valued_line_degrees`): 2d_k + 5 solves per step instead of O(N³)
products of polynomials of degree ~N·d_k (for the Lie–Poisson family at n = 8, 28–34×
per run and 22× for ``exact-khk degrees``, docs/benchmarks.md).

**Never an overcount.**  Let G = (G_0, …, G_N) be the coprime integral forms of
degree d_k representing Φ^k.  The k-fold formal composite C^{∘k} equals H·G
over Z (Gauss's lemma), and reduction mod p commutes with composition, so
whenever the computation never meets the zero vector the computed point is
proportional to G_p(ℓ(s, t)) (ℓ homogenised); its reduced degree is d_k minus
the degree of the common factor of those N + 1 binary forms: ≤ d_k.

**Undercount bound (Schwartz–Zippel).**  Call p *good* for k when G mod p has
coprime components (all but finitely many p: those dividing the content of
the resultant below).  For random u, w the resultant of the binary forms
Σ u_i G_i(ℓ) and Σ w_i G_i(ℓ) is a polynomial of total degree ≤ 2 d(d + 1) in
(a, b, u, w), not identically zero mod a good p, and it vanishes whenever the
restriction has a common factor.  Hence for one random line

    Pr[undercount of d_k] ≤ 2 d_k (d_k + 1) / p,

and the reported degree, the maximum over independent (prime, line) runs, is
too small only if every run undercounts: probability ≤ Π_runs 2 d(d+1)/p for
the good primes among them (the bound is stated at the reported d_k; a bad
prime undercounts at every line, which is why several primes are used and
runs that disagree with the maximum are reported).  The route from values adds
(4d/p)^4 per fit that could pass its check falsely (:func:`run_bound`); it never
overcounts either.

>>> from exact_khk.systems.expressions import ExpressionSystem
>>> euler = ExpressionSystem.from_expressions(["x", "y", "z"], field=["y*z", "-2*x*z", "x*y"])
>>> r = degree_sequence(euler, steps=10, eps="1/10")
>>> r.degrees
(1, 3, 9, 19, 33, 51, 73, 99, 129, 163, 201)
>>> r.fit.growth, r.fit.polynomial
('polynomial', '2*k^2 + 1')
"""

from __future__ import annotations

import math
import random
import time
from dataclasses import dataclass, field as dc_field
from fractions import Fraction

import flint

from exact_khk.errors import InputError
from exact_khk.parsing import any_int_digits, _short, check_count, parse_rational
from exact_khk.systems.quadratic import QuadraticField

MAX_STEPS = 100_000
MAX_DIM = 64
DEFAULT_PRIME_BITS = 62


# --- shared helpers (also used by integrals.py) ---------------------------------------


def check_primes(primes, name="primes", count_default=2, seed=0) -> tuple:
    """A tuple of primes: ``primes`` an int (that many random primes in [2^61, 2^62),
    reproducible from ``seed``) or a list of primes (each checked, 2 < p < 2^63)."""
    if primes is None:
        primes = count_default
    if isinstance(primes, bool):
        raise InputError(f"{name}: expected a count or a list of primes, got {primes!r}")
    if isinstance(primes, str):
        primes = [t for t in primes.replace(" ", "").split(",") if t]
    if isinstance(primes, int):
        if not 1 <= primes <= 64:
            raise InputError(f"{name}: expected between 1 and 64 primes, got {_short(primes)}")
        return random_primes(primes, seed)
    try:
        out = tuple(int(p) for p in primes)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a count or a list of primes, got {primes!r}") from None
    if not out:
        raise InputError(f"{name}: the list of primes is empty")
    for p in out:
        if not 2 < p < 2 ** 63 or not flint.fmpz(p).is_prime():
            raise InputError(f"{name}: {_short(p)} is not an odd prime below 2^63")
    return out


def random_primes(count: int, seed=0, bits: int = DEFAULT_PRIME_BITS) -> tuple:
    """``count`` distinct random primes in [2^(bits-1), 2^bits), reproducible from ``seed``."""
    rng = random.Random(f"primes-{seed}-{bits}")
    out = []
    while len(out) < count:
        p = rng.randrange(2 ** (bits - 1), 2 ** bits) | 1
        if flint.fmpz(p).is_prime() and p not in out:
            out.append(p)
    return tuple(out)


def resolve_field(system, field="f") -> tuple:
    """(system or None, QuadraticField) from a System (and a field name for
    :meth:`~exact_khk.systems.base.System.named_field`, such as ``'f'``, ``'g'``,
    ``'g[-++]'``, ``'-++'``, ``'control'``), a catalogue name / system file, or a
    QuadraticField."""
    if isinstance(system, QuadraticField):
        return None, system
    from exact_khk.systems.catalogue import resolve

    system = resolve(system)
    if isinstance(field, QuadraticField):
        return system, field
    return system, system.named_field(field)


def eps_of(system, eps):
    eps = (system.default_eps if system is not None else Fraction(1, 10)) if eps is None \
        else parse_rational(eps, "eps")
    if eps == 0:
        raise InputError("eps: the step size must be nonzero")
    return Fraction(eps)


# --- one step in a polynomial ring ----------------------------------------------------


class _Degenerate(ArithmeticError):
    """The iterated point became zero, or the step matrix is singular along the curve."""


def bareiss(M, r, exact_div):
    """(det M, [det·y_i]) for M y = r over an integral domain of polynomials, by
    fraction-free elimination (Bareiss) and back substitution.

    >>> P = flint.fmpz_poly
    >>> det, ys = bareiss([[P([2]), P([0, 1])], [P([1]), P([3])]], [P([1]), P([0, 0, 1])], lambda a, b: a // b)
    >>> det, ys
    ((-1)*x + 6, [(-1)*x^3 + 3, 2*x^2 + (-1)])
    """
    N = len(M)
    A = [list(M[i]) + [r[i]] for i in range(N)]
    prev = None
    for k in range(N):
        cands = [i for i in range(k, N) if not A[i][k].is_zero()]
        if not cands:
            raise _Degenerate("singular step matrix")
        piv = min(cands, key=lambda i: _deg(A[i][k]))
        A[k], A[piv] = A[piv], A[k]
        rk, akk = A[k], A[k][k]
        for i in range(k + 1, N):
            row, aik = A[i], A[i][k]
            for j in range(k + 1, N + 1):
                v = akk * row[j] if aik.is_zero() else akk * row[j] - aik * rk[j]
                row[j] = v if prev is None else exact_div(v, prev)
        prev = akk
    det = A[N - 1][N - 1]
    ys = [None] * N
    ys[N - 1] = A[N - 1][N]
    for i in range(N - 2, -1, -1):
        s = A[i][N] * det
        for j in range(i + 1, N):
            s = s - A[i][j] * ys[j]
        ys[i] = exact_div(s, A[i][i])
    return det, ys


def _deg(p):
    return p.degree() if hasattr(p, "degree") else p.total_degree()


def kahan_rows(fld: QuadraticField, eps: Fraction):
    """Integer (V, R): M = (Σ_l V[i·N+j][l] w_l), r = (Σ_l R[i][l] w_l) for w = (P, Q)."""
    return fld.integer_rows(eps.numerator, eps.denominator)


def step_polys(w, V, R, zero, exact_div, gcd_of):
    """One Kahan step on the homogeneous point w = (P_1..P_N, Q) of polynomials,
    reduced by the gcd of its coordinates (``gcd_of``)."""
    N = len(w) - 1
    def comb(coeffs):
        s = zero
        for l, c in enumerate(coeffs):
            if c:
                s = s + w[l] * c
        return s
    M = [[comb(V[i * N + j]) for j in range(N)] for i in range(N)]
    r = [comb(R[i]) for i in range(N)]
    det, ys = bareiss(M, r, exact_div)
    out = ys + [det]
    if all(c.is_zero() for c in out):
        raise _Degenerate("zero point")
    return gcd_of(out)


def _nmod_gcd_reduce(rng, p):
    def reduce(vec):
        nz = [c for c in vec if not c.is_zero()]
        comb = nz[0]
        for c in nz[1:]:
            comb = comb + c * rng.randrange(1, p)
        g = nz[0].gcd(comb) if len(nz) > 1 else nz[0]
        out = []
        for c in vec:
            q, rem = divmod(c, g)
            if not rem.is_zero():  # the random combination's gcd was too large: exact gcd
                g = nz[0]
                for c2 in nz[1:]:
                    g = g.gcd(c2)
                return [c2 // g for c2 in vec]
            out.append(q)
        return out
    return reduce


def line_degrees(fld, eps, p, steps, rng, max_degree=None, progress=None):
    """d_0..d_steps of Φ restricted to one random line over F_p (see the module docstring);
    stops early at a degree past ``max_degree`` (reported by polynomial arithmetic, not
    from values); ``progress(k)`` after step k.

    By polynomial arithmetic (:func:`polynomial_line_degrees`) below dimension
    :data:`~exact_khk.systems.lie_poisson.paths.DEGREES_BY_VALUES_MIN_DIM` or for p below
    :data:`VALUES_MIN_PRIME`, else from values at points of the line
    (:func:`valued_line_degrees`) unless the degrees grow geometrically
    (:func:`line_run`)."""
    return line_run(fld, eps, p, steps, rng, max_degree, progress)[0]


def line_route(dim: int, p: int) -> str:
    """Where :func:`line_run` starts for dimension ``dim`` over F_p: ``'values'`` or
    ``'polynomials'`` (the rule of :mod:`exact_khk.systems.lie_poisson.paths`)."""
    from exact_khk.systems.lie_poisson.paths import DEGREES_BY_VALUES_MIN_DIM

    return "values" if dim >= DEGREES_BY_VALUES_MIN_DIM and p >= VALUES_MIN_PRIME else "polynomials"


def line_run(fld, eps, p, steps, rng, max_degree=None, progress=None) -> tuple:
    """``(degrees, route)`` of :func:`line_degrees`: from values where :func:`line_route`
    says so, handing over to polynomial arithmetic on a new line from the start once the
    degrees grow geometrically (:func:`_geometric`) below dimension
    :data:`~exact_khk.systems.lie_poisson.paths.DEGREES_HAND_OVER_BELOW_DIM` (there the values' new
    points, each iterated from the line, and a last step that must fail at
    D = ``max_degree`` make that route about 1.6× slower, docs/benchmarks.md)."""
    from exact_khk.systems.lie_poisson.paths import DEGREES_HAND_OVER_BELOW_DIM

    if line_route(fld.dim, p) == "values":
        degs = valued_line_degrees(fld, eps, p, steps, rng, max_degree, progress,
                                   hand_over=fld.dim < DEGREES_HAND_OVER_BELOW_DIM)
        if degs is not None:
            return degs, "values"
    return polynomial_line_degrees(fld, eps, p, steps, rng, max_degree, progress), "polynomials"


def _geometric(degs) -> bool:
    """The last three degrees grew geometrically by a factor of at least 2:
    d_k ≥ 2d_(k−1), d_k d_(k−2) ≥ d_(k−1)² and d_(k−1) d_(k−3) ≥ d_(k−2)² (never
    for polynomial growth past its first terms: 1, 3, 9, 19 and 1, 6, 12, 18 fail it).

    >>> _geometric([1, 8, 64, 512]), _geometric([1, 3, 9, 19]), _geometric([1, 16, 32, 48])
    (True, False, False)
    """
    if len(degs) < 4:
        return False
    d3, d2, d1, d0 = degs[-4:]
    return d0 >= 2 * d1 and d0 * d2 >= d1 * d1 and d1 * d3 >= d2 * d2


def run_bound(d: int, p: int, route: str) -> float:
    """The probability bound of an undercount of d on one random line over a good prime p:
    2d(d + 1)/p (module docstring), plus, for the route from values
    (:func:`valued_line_degrees`), (4d/p)^CHECK_POINTS for each fit tried at a degree
    below d that could pass its check falsely (D doubles: at most bit_length(d) + 1
    of them); at most 1."""
    extra = (d.bit_length() + 1) * (4 * d / p) ** CHECK_POINTS if route == "values" else 0.0
    return min(1.0, 2 * d * (d + 1) / p + extra)


def polynomial_line_degrees(fld, eps, p, steps, rng, max_degree=None, progress=None):
    """:func:`line_degrees` by iterating the point (1, a + t b) in F_p[t]^(N+1) (Bareiss
    over ``nmod_poly``, the coordinates' gcd removed every step); the step that passes
    ``max_degree`` is the last one reported."""
    V, R = kahan_rows(fld, eps)
    V = [[c % p for c in row] for row in V]
    R = [[c % p for c in row] for row in R]
    N = fld.dim
    P = lambda cs: flint.nmod_poly(cs, p)  # noqa: E731
    w = [P([rng.randrange(p), rng.randrange(p)]) for _ in range(N)] + [P([1])]
    zero, reduce = P([]), _nmod_gcd_reduce(rng, p)
    degs = [1]
    for k in range(1, steps + 1):
        w = step_polys(w, V, R, zero, lambda a, b: a // b, reduce)
        degs.append(max(_deg(c) for c in w))
        if progress is not None:
            progress(k)
        if max_degree is not None and degs[-1] > max_degree:
            break
    return degs


# --- degrees from values at points of the line -----------------------------------------

#: the evaluation needs 2d + 1 + CHECK_POINTS distinct points of F_p per degree d and
#: bounds a false check by (4d/p)^CHECK_POINTS: used only for p from here (smaller
#: primes, as in the tests of the undercount frequency, take the polynomial route)
VALUES_MIN_PRIME = 2 ** 31
#: points of the line not used by the fit that must confirm it
CHECK_POINTS = 4


def interpolate(xs, vs, p):
    """``(f, m)``: the polynomial f of degree < len(xs) over F_p with f(x_j) = v_j, and
    m = Π (t − x_j) (distinct x_j), by a subproduct tree (O(len(xs)) ``nmod_poly`` calls).

    >>> f, m = interpolate([1, 2, 3], [2, 5, 10], 101)
    >>> f, m
    (x^2 + 1, x^3 + 95*x^2 + 11*x + 95)
    """
    levels = [[flint.nmod_poly([-x % p, 1], p) for x in xs]]
    while len(levels[-1]) > 1:
        lv = levels[-1]
        levels.append([lv[i] * lv[i + 1] if i + 1 < len(lv) else lv[i] for i in range(0, len(lv), 2)])
    m = levels[-1][0]
    rems = [m.derivative()]
    for lv in reversed(levels[:-1]):  # m'(x_j) by a remainder tree
        rems = [rems[i // 2] % lv[i] for i in range(len(lv))]
    ws = [flint.nmod_poly([int(v) * pow(int(r[0]), -1, p)], p) for v, r in zip(vs, rems)]
    for lv in levels[:-1]:  # Lagrange's sum, combined up the tree
        ws = [ws[i] * lv[i + 1] + ws[i + 1] * lv[i] if i + 1 < len(ws) else ws[i] for i in range(0, len(ws), 2)]
    return ws[0], m


def cauchy_degree(xs, vs, p, D):
    """max(deg A, deg B) of the reduced A/B with deg A, deg B ≤ D and A(x_j) = v_j B(x_j)
    at the 2D + 1 points (x_j, v_j), or None when there is none (the values are not those
    of such a fraction).  The first remainder of degree ≤ D in Euclid's algorithm on
    (Π (t − x_j), f), f interpolating the values, with its cofactor (Cauchy interpolation:
    von zur Gathen & Gerhard, *Modern Computer Algebra*, 5.7); with A and B, B monic.

    >>> d, A, B = cauchy_degree([1, 2, 3, 4, 5], [51, 41, 68, 44, 26], 101, 2)  # (t + 1)/(t + 3) mod 101
    >>> d, A, B
    (1, x + 1, x + 3)
    """
    f, m = interpolate(xs, vs, p)
    r0, r1 = m, f
    t0, t1 = flint.nmod_poly([], p), flint.nmod_poly([1], p)
    while r1.degree() > D:
        q, r = divmod(r0, r1)
        r0, r1, t0, t1 = r1, r, t1, t0 - q * t1
    if t1.is_zero() or t1.degree() > D or any(t1(x) == 0 for x in xs):
        return None
    g = r1.gcd(t1)
    A, B = r1 // g, t1 // g
    c = B.leading_coefficient() ** -1  # B monic
    return max(A.degree(), B.degree()), A * c, B * c


def valued_line_degrees(fld, eps, p, steps, rng, max_degree=None, progress=None, hand_over=False):
    """:func:`line_degrees` from values: the orbits of points ℓ(s) = a + s b of the line,
    for random distinct s in F_p, one ``nmod_mat`` solve per step, give the values at s of
    R_k = L₁(G)/L₂(G) for two random forms L₁, L₂ of the homogeneous point G = Φ^k(ℓ).
    R_k has degree d_k unless L₁(G), L₂(G) share a factor — the event the module
    docstring's Schwartz–Zippel bound already counts — and Cauchy interpolation
    (:func:`cauchy_degree`) at 2D + 1 points finds it exactly whenever D ≥ d_k; D is
    doubled until the fit passes :data:`CHECK_POINTS` further points.  So it never
    overcounts; it undercounts besides that event only if a fit at D < d_k passes the
    check (probability ≤ (4d_k/p)^CHECK_POINTS per fit: the check points are random among
    at least p/2 unused ones, and the difference of two fractions of degree ≤ d_k vanishes
    at most at 2d_k of them).  Points whose orbit meets a singular step or a pole of R_k
    are dropped (finitely many: they are roots of nonzero polynomials unless the line
    is degenerate, which raises :class:`_Degenerate`).  It stops before a step whose
    degree passes ``max_degree`` (no fit at D = ``max_degree``); that step is not
    reported.  ``hand_over``: return None once the growth is geometric
    (:func:`_geometric`).  Cost: about 2d_k + 5 solves at step k, and k for each new
    point, against O(N³) products of polynomials of degree ~N·d_k by
    :func:`polynomial_line_degrees`.
    """
    V, R = kahan_rows(fld, eps)
    N = fld.dim
    # M(x) = Σ_l w_l A_l and r(x) = Σ_l w_l r_l for w = (x, 1): N + 1 matrices
    A = [flint.nmod_mat(N, N, [V[i * N + j][l] % p for i in range(N) for j in range(N)], p) for l in range(N + 1)]
    r = [flint.nmod_mat(N, 1, [R[i][l] % p for i in range(N)], p) for l in range(N + 1)]
    a, b = [rng.randrange(p) for _ in range(N)], [rng.randrange(p) for _ in range(N)]
    u, w = [rng.randrange(p) for _ in range(N + 1)], [rng.randrange(p) for _ in range(N + 1)]
    one = flint.nmod(1, p)

    def step(x):  # ZeroDivisionError when the step matrix is singular there
        M, rhs = A[N], r[N]
        for l, t in enumerate(x):
            if t:
                M, rhs = M + A[l] * t, rhs + r[l] * t
        return M.solve(rhs).entries()

    def value(x):  # R_k at the point, None at a pole
        num = sum((c * t for c, t in zip(u, x)), one * u[N])
        den = sum((c * t for c, t in zip(w, x)), one * w[N])
        return None if den == 0 else num / den

    used, lost = set(), [0]
    points = []  # [s, Φ^k(ℓ(s))]

    def grow(count, k):  # more points, their orbits taken to step k
        while len(points) < count:
            if lost[0] > 64 + 2 * count:
                raise _Degenerate("singular step matrix along the line")
            s = rng.randrange(p)
            if s in used:
                continue
            used.add(s)
            x = [flint.nmod(ai + s * bi, p) for ai, bi in zip(a, b)]
            try:
                for _ in range(k):
                    x = step(x)
            except ZeroDivisionError:
                lost[0] += 1
                continue
            points.append([s, x])

    degs, D = [1], 1
    for k in range(1, steps + 1):
        kept = []
        for pt in points:
            try:
                pt[1] = step(pt[1])
                kept.append(pt)
            except ZeroDivisionError:
                lost[0] += 1
        points[:] = kept
        while True:
            need = 2 * D + 1 + CHECK_POINTS
            grow(need, k)
            vals = [(s, v) for s, v in ((s, value(x)) for s, x in points) if v is not None]
            if len(vals) < need:  # poles: more points
                lost[0] += need - len(vals)
                grow(len(points) + need - len(vals), k)
                continue
            fit = cauchy_degree([s for s, _ in vals[:2 * D + 1]], [v for _, v in vals[:2 * D + 1]], p, D)
            if fit is not None:
                d, F, G = fit
                if all(F(s) == v * G(s) for s, v in vals[2 * D + 1:need]):
                    break
            if max_degree is not None and D >= max_degree:
                return degs  # d_k > max_degree
            D = 2 * D if max_degree is None else min(2 * D, max_degree)
        degs.append(d)
        if hand_over and _geometric(degs):
            return None
        if progress is not None:
            progress(k)
        # the next degree, extrapolated linearly, or geometrically where the growth is at
        # least geometric (d_k d_(k-2) ≥ d_(k-1)²); doubled while short
        D = max(1, 2 * d - degs[-2] + 1)
        if k >= 2 and d * degs[-3] >= degs[-2] ** 2:
            D = max(D, d * d // degs[-2] + 1)
        if max_degree is not None:
            D = min(D, max_degree)
    return degs


def exact_degrees(fld, eps, steps, max_terms=200_000):
    """d_1..d_steps exactly, by composing Φ with itself as a rational map over Q
    (python-flint ``fmpz_mpoly``, gcds and contents removed every step); stops
    before a step whose Cramer output could have more than ``max_terms`` terms
    (C(N·d + N, N) for the current degree d).  No line, no prime: these
    are the degrees themselves."""
    N = fld.dim
    ctx = flint.fmpz_mpoly_ctx.get(tuple(f"x{i}" for i in range(N)), "degrevlex")
    V, R = kahan_rows(fld, eps)
    w = list(ctx.gens()) + [ctx.from_dict({(0,) * N: 1})]
    zero = ctx.from_dict({})

    def reduce(vec):
        g = zero
        for c in vec:
            g = c if g.is_zero() else g.gcd(c)
            if g.is_constant():  # the integer content is removed below
                break
        out = vec if g.is_constant() else [c / g for c in vec]
        cont = math.gcd(*(int(k) for c in out for k in c.coeffs()))
        return [c / cont for c in out] if cont > 1 else out

    degs = [1]
    for _ in range(steps):
        if math.comb(N * degs[-1] + N, N) > max_terms:  # the dense size of the Cramer output
            break
        w = step_polys(w, V, R, zero, lambda a, b: a / b, reduce)
        degs.append(max(c.total_degree() for c in w))
    return degs


# --- the result ------------------------------------------------------------------------

#: the fewest later terms that must confirm the fitted recurrence before the growth is
#: classified: with one, the integrable cmoq-cubic's d_0..d_6 = 1, 3, 5, 9, 13, 21, 29 fit an
#: order-3 recurrence with a root > 1 ("exponential"; its degrees grow quadratically, the
#: order-6 recurrence of 13 terms says so); a classifier that a short run fools is refused
MIN_CONFIRM = 3


@dataclass(frozen=True)
class DegreeSequence:
    """Degrees d_0..d_K of Φ^k (the maximum over all runs), the runs, the exact
    degrees if asked, the undercount bound and the recurrence fit
    (:class:`~exact_khk.diagnostics.recurrence.RecurrenceFit`)."""

    label: str
    dim: int
    eps: Fraction
    degrees: tuple
    runs: tuple            # ((prime, line index, (d_0, ...)), ...)
    exact: tuple           # exact d_0.. over Q (may be shorter), () if not asked
    failed_runs: int
    undercount_bound: float
    fit: object
    seconds: float
    heights: object = None
    notes: tuple = dc_field(default=())
    routes: tuple = ()     # the route of each run ('values' or 'polynomials', line_run)

    @property
    def disagreeing(self) -> tuple:
        """(prime, line) of the runs that undercount somewhere (bad prime or line)."""
        return tuple((p, i) for p, i, d in self.runs if tuple(d) != self.degrees[:len(d)])

    @any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
    def to_json(self) -> dict:
        return {"field": self.label, "dim": self.dim, "eps": str(self.eps), "degrees": list(self.degrees),
                "degree_kind": "projective degree of Phi^k (max degree of numerators and common denominator)",
                "runs": [{"prime": p, "line": i, "degrees": list(d),
                          "route": self.routes[j] if j < len(self.routes) else None}
                         for j, (p, i, d) in enumerate(self.runs)],
                "disagreeing_runs": [list(t) for t in self.disagreeing], "failed_runs": self.failed_runs,
                "exact_degrees": [int(d) for d in self.exact], "undercount_bound": self.undercount_bound,
                "fit": self.fit.to_json(), "seconds": self.seconds,
                "heights": self.heights.to_json() if self.heights is not None else None,
                "notes": list(self.notes)}

    @any_int_digits()
    def summary(self) -> str:
        lines = [f"degrees of Phi^k for {self.label} (dimension {self.dim}, eps = {self.eps}), k = 0..{len(self.degrees) - 1}:",
                 "  " + ", ".join(map(str, self.degrees)),
                 f"  {len(self.runs)} run(s) over F_p on random lines (primes "
                 f"{', '.join(str(p) for p in sorted({p for p, _, _ in self.runs}))}); "
                 f"P(undercount) <= {self.undercount_bound:.3g} at good primes (Schwartz–Zippel, 2d(d+1)/p per run"
                 + (f"; + (bits(d) + 1)(4d/p)^{CHECK_POINTS} for runs from values at points of the line)"
                    if "values" in self.routes else ")")]
        if self.disagreeing:
            lines.append("  runs undercounting (bad prime or line): " + ", ".join(f"p={p} line {i}" for p, i in self.disagreeing))
        if self.exact:
            ok = tuple(self.exact) == self.degrees[:len(self.exact)]
            lines.append(f"  exact over Q (composition): {', '.join(map(str, self.exact))} "
                         f"({'agrees' if ok else 'DISAGREES'})")
        lines.append("  " + self.fit.summary().replace("\n", "\n  "))
        if self.heights is not None:
            lines.append("  " + self.heights.summary().replace("\n", "\n  "))
        lines += [f"  note: {n}" for n in self.notes]
        lines.append(f"  time {self.seconds:.2f} s")
        return "\n".join(lines)


@any_int_digits()
def degree_sequence(system, steps=20, eps=None, field="f", primes=2, lines=1, seed=0, exact=0,
                    exact_terms=10_000, confirm=3, heights=False, x0=None, max_bits=200_000, max_degree=20_000,
                    progress=None):
    """Degrees d_0..d_steps of the iterates of the Kahan map of ``field`` (module docstring).

    ``system`` a System, catalogue name, system file or QuadraticField; ``primes``
    a count or list of primes; ``lines`` random lines per prime; ``exact`` the
    number of iterates also composed exactly over Q (while the Cramer output stays
    below ``exact_terms`` terms); the iteration stops once a degree exceeds
    ``max_degree`` (exponential growth); ``heights=True`` adds
    :func:`~exact_khk.diagnostics.heights.height_growth` of the orbit of ``x0``.
    ``progress(k)``: called with the steps over F_p made so far, of ``steps`` per line
    (a line that stops early counts as finished).
    """
    from exact_khk.diagnostics.recurrence import fit_recurrence, too_short

    t0 = time.perf_counter()
    sysobj, fld = resolve_field(system, field)
    eps = eps_of(sysobj, eps)
    check_count(steps, "steps", 1, MAX_STEPS)
    check_count(lines, "lines", 1, 64)
    check_count(exact, "exact", 0, 50)
    check_count(max_degree, "max_degree", 1, 10 ** 7)
    if isinstance(confirm, int) and not isinstance(confirm, bool) and 1 <= confirm < MIN_CONFIRM:
        raise InputError(f"confirm: at least {MIN_CONFIRM} later terms must confirm the recurrence (MIN_CONFIRM), "
                         f"got {confirm}: with fewer, short runs of integrable maps fit recurrences of "
                         f"exponential growth; raise steps instead")
    check_count(confirm, "confirm", MIN_CONFIRM, 1000)
    check_count(exact_terms, "exact_terms", 0, 10 ** 8)
    seed = check_count(seed, "seed", -2 ** 63, 2 ** 63)
    if fld.dim > MAX_DIM:
        raise InputError(f"system: dimension {fld.dim} exceeds {MAX_DIM}")
    primes = check_primes(primes, seed=seed)
    runs, routes, failed, reported = [], [], 0, [0]

    def report(k):  # increasing only: the steps of a degenerate line, taken again, count once
        if progress is not None and k > reported[0]:
            reported[0] = k
            progress(k)
    for line, (p, i) in enumerate((p, i) for p in primes for i in range(lines)):
        if i == 0:
            rng = random.Random(f"line-{seed}-{p}")
        for _attempt in range(5):
            try:
                degs, route = line_run(fld, eps, p, steps, rng, max_degree,
                                       lambda k, base=line * steps: report(base + k))
                runs.append((p, i, tuple(degs)))
                routes.append(route)
                break
            except _Degenerate:
                failed += 1
        report((line + 1) * steps)  # a line that stopped early (or degenerated every time) is done
    if not runs:
        raise InputError("primes: every run degenerated (the step matrix is singular along every line "
                         "tried: choose other primes)")
    length = min(len(r[2]) for r in runs)
    degs = tuple(max(r[2][k] for r in runs) for k in range(length))
    bound = max((math.prod(run_bound(d, p, route) for (p, _, _), route in zip(runs, routes)) for d in degs),
                default=0.0)
    ex = tuple(exact_degrees(fld, eps, exact, exact_terms)) if exact else ()
    notes = []
    if length < steps + 1:
        notes.append(f"stopped after k = {length - 1}: the degree passed max_degree = {max_degree}")
    if any(a > b for a, b in zip(degs, ex)):
        notes.append("exact degrees below the modular ones: this is impossible; please report it")
    bad = [p for p in primes if eps.numerator % p == 0 or eps.denominator % p == 0]
    if bad:
        notes.append(f"prime(s) {', '.join(map(str, bad))} divide eps = {eps}: the map degenerates there (bad primes)")
    hts = None
    if heights:
        from exact_khk.diagnostics.heights import height_growth
        hts = height_growth(fld, x0 if x0 is not None else (sysobj.default_x0 if sysobj is not None else None),
                            eps, steps=max(4, min(steps, 60)), max_bits=max_bits)
    label = f"{sysobj.name if sysobj is not None else 'field'} {fld.label}"
    try:
        fit = fit_recurrence(degs, confirm=confirm)
    except InputError as exc:
        fit = too_short(degs, str(exc))
    return DegreeSequence(label, fld.dim, eps, degs, tuple(runs), ex, failed, bound,
                          fit, time.perf_counter() - t0, hts, tuple(notes), tuple(routes))
