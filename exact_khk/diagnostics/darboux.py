"""The shared core of measure and Poisson discovery: the Kahan map as rational functions,
its values at random points over F_p, modular kernels lifted to Q, exact checks.

**The map.**  For a quadratic field f with Jacobian f'(x) = J(x) + L (J linear in x,
L constant) and M(x) = I − εf'(x), A(x) = det M(x) (degree ≤ N):

    x̃ = Φ(x) = x + 2ε M(x)⁻¹ f(x) = Ñ(x) / A(x),      Ñ_i = A x_i + 2ε (adj M · f)_i,
    dΦ(x) = M(x)⁻¹ (I + εf'(x̃)),                      det dΦ(x) = det M₂(x) / A(x)^(N+1),

with M₂ = A(I + εL) + εJ(Ñ) (J is linear, so A·J(x̃) = J(Ñ)).  :func:`symbolic_map`
computes these over Q (python-flint ``fmpq_mpoly``, fraction-free Bareiss elimination),
reduces det dΦ to lowest terms and factors numerator, denominator and A over Q.

**Discrete Darboux polynomials** (Celledoni, Evripidou, McLaren, Owren, Quispel, Tapley,
J. Phys. A 52 (2019), arXiv:1902.04685): P with P(x̃) = C(x)·P(x).  The cofactor of a
polynomial P is P(x̃)/P(x) = P^h(Ñ, A) / (A^deg P · P) with P^h the homogenisation
(:func:`cofactor`); its numerator and denominator are written over the factors of A
and det dΦ where they are products of them.

**Kernels over F_p.**  A linear condition Σ_j c_j row_j(x) = 0 on coefficients c,
evaluated at random points x of F_p^N (points where A(x) = 0 are skipped), is a
matrix whose nullspace (canonical basis from the reduced echelon form,
``nmod_mat``) is computed modulo several 62-bit primes and lifted to Q by Chinese
remaindering and rational reconstruction, confirmed by a prime not used for the
lift (:func:`lifted_kernel`).
"""

from __future__ import annotations

import random
from dataclasses import dataclass
from fractions import Fraction

import flint

from exact_khk.diagnostics.degrees import bareiss, random_primes
from exact_khk.diagnostics.kernels import _Evaluator, lift, poly_text
from exact_khk.errors import InputError, UndecidedError

#: the largest dimension whose det dΦ is expanded and factored over Q (degree ≤ N(N+1)
#: in N variables: N = 4 takes about a second)
MAX_SYMBOLIC_DIM = 4
#: the most unknowns of one linear problem (an m × m nmod_mat per prime)
MAX_UNKNOWNS = 3000
#: extra random points beyond the number of unknowns (the nullspace is then the true
#: kernel unless a nonzero polynomial of bounded degree vanishes at all of them)
MARGIN = 12


# --- the map over Q ----------------------------------------------------------------------


def _q(c):
    c = Fraction(c)
    return flint.fmpq(c.numerator, c.denominator)


def mpoly_ctx(N):
    return flint.fmpq_mpoly_ctx.get(tuple(f"x{i}" for i in range(N)), "degrevlex")


def field_mpolys(fld, ctx):
    """(f_i, J, L): f as fmpq_mpoly, J(x) its linear Jacobian part (matrix of polys), L its constant part."""
    N = fld.dim
    x = ctx.gens()
    zero = ctx.from_dict({})
    f = [zero + _q(c) for c in fld.const]
    J = [[zero for _ in range(N)] for _ in range(N)]
    L = [[Fraction(0)] * N for _ in range(N)]
    for i, terms in enumerate(fld.terms()):
        for (j, k), c in terms:
            f[i] = f[i] + _q(c) * x[j] * x[k]
            J[i][j] = J[i][j] + _q(c) * x[k]
            J[i][k] = J[i][k] + _q(c) * x[j]
    for i, row in enumerate(fld.linear):
        for j, c in row:
            f[i] = f[i] + _q(c) * x[j]
            L[i][j] += Fraction(c)
    return f, J, L


@dataclass
class SymbolicMap:
    """Φ = Ñ/A and det dΦ = num/den (lowest terms) over Q, with factors (module docstring)."""

    ctx: object
    numerators: list       # Ñ_i
    A: object              # det(I − εf'(x))
    det_num: object
    det_den: object
    factors: list          # distinct irreducible factors of A, det_num, det_den (primitive, fmpq_mpoly)

    def express(self, num, den):
        """(constant, {factor index: exponent}) with num/den = constant · Π factor^exponent, or None
        when a factor of num or den is not among :attr:`factors`."""
        const, exps = flint.fmpq(1), {}
        for poly, sign in ((num, 1), (den, -1)):
            c, facs = poly.factor()
            const = const * c if sign == 1 else const / c
            for g, e in facs:
                k = _index(self.factors, g)
                if k is None:
                    return None
                g0 = self.factors[k]
                ratio = (g / g0).leading_coefficient()  # a constant: the same irreducible up to scaling
                const = const * ratio ** e if sign == 1 else const / ratio ** e
                exps[k] = exps.get(k, 0) + sign * e
        return const, {k: e for k, e in exps.items() if e}


def _index(factors, g):
    for k, h in enumerate(factors):
        if g.total_degree() == h.total_degree():
            q, r = divmod(g, h)
            if r.is_zero() and q.is_constant():
                return k
    return None


def _exact_div(a, b):
    q, r = divmod(a, b)
    if not r.is_zero():
        raise ArithmeticError("inexact division in Bareiss elimination")
    return q


def symbolic_map(fld, eps) -> SymbolicMap | None:
    """The map, det dΦ and their factors over Q (module docstring), or None beyond
    :data:`MAX_SYMBOLIC_DIM`."""
    N = fld.dim
    if N > MAX_SYMBOLIC_DIM:
        return None
    ctx = mpoly_ctx(N)
    x = ctx.gens()
    e = _q(eps)
    one = ctx.from_dict({(0,) * N: 1})
    f, J, L = field_mpolys(fld, ctx)
    M = [[(one if i == j else 0 * one) - e * (J[i][j] + _q(L[i][j])) for j in range(N)] for i in range(N)]
    A, adjf = bareiss(M, f, _exact_div)
    Nt = [A * x[i] + 2 * e * adjf[i] for i in range(N)]
    Jt = [[sum((_lin_coef(J[i][j], k, N) * Nt[k] for k in range(N)), 0 * one) for j in range(N)] for i in range(N)]
    M2 = [[A * ((1 if i == j else 0) + e * _q(L[i][j])) + e * Jt[i][j] for j in range(N)] for i in range(N)]
    D2, _ = bareiss(M2, [0 * one] * N, _exact_div)
    den = A ** (N + 1)
    g = D2.gcd(den)
    num, den = D2 / g, den / g
    c = den.leading_coefficient()
    num, den = num / c, den / c
    factors = []
    for poly in (A, num, den):
        if poly.is_constant():
            continue
        for h, _ in poly.factor()[1]:
            if _index(factors, h) is None:
                factors.append(h)
    return SymbolicMap(ctx, Nt, A, num, den, factors)


def _lin_coef(poly, k, N):
    """The coefficient of x_k in a linear polynomial."""
    e = [0] * N
    e[k] = 1
    return poly.to_dict().get(tuple(e), flint.fmpq(0))


def homogenised_at(poly, numerators, A, degree):
    """P^h(Ñ, A) = A^degree · P(Ñ/A) for P of total degree ≤ ``degree``."""
    total = 0 * A
    for e, c in poly.to_dict().items():
        term = A ** (degree - sum(e)) * c
        for Ni, k in zip(numerators, e):
            if k:
                term = term * Ni ** k
        total = total + term
    return total


def cofactor(sym: SymbolicMap, poly):
    """(num, den) of P(x̃)/P(x) in lowest terms (a polynomial ratio when P is Darboux)."""
    d = poly.total_degree()
    num, den = homogenised_at(poly, sym.numerators, sym.A, d), sym.A ** d * poly
    g = num.gcd(den)
    num, den = num / g, den / g
    c = den.leading_coefficient()
    return num / c, den / c


def mpoly_dict(poly) -> dict:
    return {tuple(e): Fraction(int(c.p), int(c.q)) for e, c in poly.to_dict().items()}


def mpoly_text(poly, variables) -> str:
    return poly_text(mpoly_dict(poly), variables)


def primitive(poly: dict) -> dict:
    """``poly`` scaled to coprime integer coefficients with a positive first coefficient (by degree)."""
    from math import gcd, lcm

    if not poly:
        return {}
    den = lcm(*(c.denominator for c in poly.values()))
    ints = {e: int(c * den) for e, c in poly.items() if c}
    g = 0
    for v in ints.values():
        g = gcd(g, v)
    first = min(ints, key=lambda e: (sum(e), [-k for k in e]))
    s = -1 if ints[first] < 0 else 1
    return {e: Fraction(s * v // g) for e, v in ints.items()}


# --- the map over F_p ------------------------------------------------------------------


class ModMap:
    """Φ, f' and dΦ at points of F_p^N (nmod_mat solves)."""

    def __init__(self, fld, eps, p):
        from exact_khk.arith import get_arith

        self.fld, self.p, self.N = fld, p, fld.dim
        self.ar = get_arith(f"gf:{p}")
        self.e = flint.nmod(Fraction(eps).numerator, p) / Fraction(eps).denominator

    def _mat(self, x, sign):
        N, ar = self.N, self.ar
        J = self.fld.jacobian(ar, [ar.convert(t) for t in x])
        return flint.nmod_mat(N, N, [int((1 if i == j else 0) + sign * self.e * J[i][j])
                                     for i in range(N) for j in range(N)], self.p)

    def at(self, x):
        """(x, x̃, dΦ(x), A(x), det(I + εf'(x̃))) as ints / nmod_mat, or None where A(x) = 0."""
        ar, p = self.ar, self.p
        M = self._mat(x, -1)
        A = M.det()
        if int(A) == 0:
            return None
        fx = self.fld.evaluate(ar, [ar.convert(t) for t in x])
        y = M.solve(flint.nmod_mat(self.N, 1, [int(2 * self.e * t) for t in fx], p))
        xt = [(int(t) + int(y[i, 0])) % p for i, t in enumerate(x)]
        M2 = self._mat(xt, 1)
        return list(x), xt, M.solve(M2), int(A), int(M2.det())


def random_point_mod(rng, N, p):
    return [rng.randrange(p) for _ in range(N)]


# --- kernels -------------------------------------------------------------------------


def kernel_mod(rows, m, p) -> list:
    """The canonical basis of the nullspace of ``rows`` (ints mod p), from the reduced echelon form."""
    R, rank = flint.nmod_mat(len(rows), m, [v for r in rows for v in r], p).rref()
    pivots, row = [], 0
    for c in range(m):
        if row < rank and int(R[row, c]) != 0:
            pivots.append(c)
            row += 1
    basis = []
    piv = set(pivots)
    for fcol in (c for c in range(m) if c not in piv):
        v = [0] * m
        v[fcol] = 1
        for i, c in enumerate(pivots):
            v[c] = (-int(R[i, fcol])) % p
        basis.append(v)
    return basis


def lifted_kernel(make_rows, m, seed, max_primes=12, progress=None):
    """(basis over Q as lists of Fractions, primes used, notes): the nullspace of the
    rows ``make_rows(p, rng)`` over F_p, for random primes until the lift is confirmed.
    A prime whose kernel dimension exceeds the smallest seen is unlucky and skipped."""
    if m > MAX_UNKNOWNS:
        raise InputError(f"degree: {m} unknowns exceed the limit of {MAX_UNKNOWNS} (MAX_UNKNOWNS); "
                         f"choose a smaller degree")
    per, used, best = [], [], None
    for p in random_primes(max_primes, seed):
        if progress:
            progress(f"kernel mod p ({m} unknowns)")
        basis = kernel_mod(make_rows(p, random.Random(f"rows-{seed}-{p}")), m, p)
        if best is not None and len(basis) > best:
            continue
        if best is None or len(basis) < best:
            per, best = [], len(basis)
        used.append(p)
        if not basis:
            return [], tuple(used)
        per.append((p, basis))
        out = lift(per)
        if out is not None:
            return out, tuple(used)
    raise UndecidedError(f"the rational reconstruction of the kernel was not confirmed with {len(used)} primes "
                         "(coefficients too large: try a smaller degree)")


def rows_of_points(N, count, mod_map, row_at, rng):
    """At least ``count`` rows, ``row_at(point data)`` (a list of rows) at random points."""
    rows, tries = [], 0
    while len(rows) < count:
        tries += 1
        if tries > 20 * count + 100:
            raise InputError("the Kahan step is singular at almost every random point over F_p")
        at = mod_map.at(random_point_mod(rng, N, mod_map.p))
        if at is not None:
            rows += row_at(at)
    return rows


#: the highest point (bits of numerators and denominators) of the exact orbit checks of
#: find-measure and find-poisson: heights grow about 3x a step (a start of 10^4 digits reaches
#: 1.2 million bits after 4 steps, about 10 s); beyond, an InputError naming x0 and the steps
MAX_ORBIT_BITS = 1 << 21

#: the last exact orbit computed: find_measure and find_poisson check several candidates on the same one
_LAST_ORBIT: list = [None, None, None]


def exact_orbit(fld, eps, x0, steps):
    """The exact orbit and A(x_k), det(I + εf'(x_{k+1})), dΦ(x_k) along it, in python-flint ``fmpq``
    (Python's Fraction spends nearly all its time in gcds: 3x slower at a 1500-digit start;
    :func:`eval_poly` takes Fraction coefficients at these points); InputError past
    :data:`MAX_ORBIT_BITS`."""
    from exact_khk.arith import get_arith
    from exact_khk.kahan.map import KahanMap

    key = (Fraction(eps), tuple(Fraction(t) for t in x0), steps)
    if _LAST_ORBIT[0] is fld and _LAST_ORBIT[1] == key:
        return _LAST_ORBIT[2]
    ar = get_arith("flint")
    e = flint.fmpq(key[0].numerator, key[0].denominator)
    phi = KahanMap(fld, key[0], "flint")
    pts = [phi.point(key[1], "x0")]
    for k in range(1, steps + 1):
        bits = max(int(t.p).bit_length() + int(t.q).bit_length() for t in pts[-1])
        if bits > MAX_ORBIT_BITS:
            raise InputError(f"x0: the exact orbit check's point {k - 1} has {bits} bits, beyond the limit of "
                             f"{MAX_ORBIT_BITS} (MAX_ORBIT_BITS): give a smaller x0 or fewer steps")
        pts.append(phi.step(pts[-1]))

    def mat(x, sign):
        J = fld.jacobian(ar, x)
        return flint.fmpq_mat([[(1 if i == j else 0) + sign * e * J[i][j] for j in range(fld.dim)]
                               for i in range(fld.dim)])

    out = []
    for k in range(steps):
        x, xt = pts[k], pts[k + 1]
        M, M2 = mat(x, -1), mat(xt, 1)
        D = M.solve(M2)
        out.append((tuple(x), tuple(xt), M.det(), M2.det(),
                    [[D[i, j] for j in range(fld.dim)] for i in range(fld.dim)]))
    _LAST_ORBIT[:] = [fld, key, out]
    return out


def eval_poly(poly: dict, x):
    """A dict polynomial at a point (any ring elements; Fraction coefficients are read as ``fmpq``
    at a point of ``fmpq``, which does not mix with Fraction)."""
    to_fmpq = bool(x) and isinstance(x[0], flint.fmpq)
    total = 0
    for e, c in poly.items():
        term = flint.fmpq(c.numerator, c.denominator) if to_fmpq and isinstance(c, Fraction) else c
        for xi, k in zip(x, e):
            if k:
                term = term * xi ** k
        total = total + term
    return total


def fresh_point(seed, N, bound=5):
    rng = random.Random(f"verify-{seed}")
    return tuple(Fraction(rng.choice([i for i in range(-bound, bound + 1) if i]), rng.randint(2, 5))
                 for _ in range(N))


__all__ = ["SymbolicMap", "symbolic_map", "cofactor", "ModMap", "lifted_kernel", "rows_of_points", "exact_orbit",
           "eval_poly", "_Evaluator", "MARGIN"]
