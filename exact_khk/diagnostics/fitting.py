"""Every integral an orbit kernel shows: the entries of its canonical basis, fitted.

Let K(x_0) be the orbit kernel of the candidates (:mod:`.kernels`) and
v_f = e_f + Σ_i c_{i,f} e_{π_i} its canonical basis (π the pivot columns of the
reduced echelon form of the evaluation matrix, f the free ones).  K(x_0) depends
only on the orbit, so each *entry* c_{i,f}(x_0) is a conserved function of x_0,
and every conserved function the kernel can see is a function of the entries.

* **How many.**  The rank of the Jacobian of the entries with respect to x_0 is the
  number of independent integrals the kernel shows ("visible").  It is computed
  over F_p along the orbit's tangent: T_{k+1} = dΦ(x_k) T_k, B_l = the derivative
  of the evaluation matrix A in the direction e_l, and A_π c' = −B_l v_f (A_π the
  pivot columns of A, of full column rank) gives the derivatives of the entries
  (:func:`entry_jacobian`).  A rank over F_p equals the rank over Q unless p
  divides a minor: a lower bound with high probability equal.
* **Which vectors.**  Any kernel vector of minimal support (a circuit) gives conserved
  entries in the same way, and sparse ones give simpler functions: :func:`circuits` finds
  them as echelon rows of the kernel basis under random column orders, taken in turn with
  the canonical basis vectors; the kernel of the candidates of one circuit is that vector.
* **Which formula.**  An entry e that is not a function of the integrals already
  found (its gradient mod p is independent of theirs) is written as N/D with N, D of
  degree ≤ δ, δ = 1, 2, … : N − e(x_s)·D vanishes on the orbit of x_s for every
  orbit s of a pool, one linear system [φ(x) | −e(x_s)·φ(x)] over F_p whose
  nullspace at the lowest δ is one vector, lifted to Q over several primes
  (:func:`.kernels.lift`) — :meth:`EntryFitter.fit`.  The caller checks each fitted
  N/D exactly on a fresh orbit and keeps it only if it raises the exact rank of the
  Jacobian of the integrals found (so never a power or product of found ones).
"""

from __future__ import annotations

import math
import random
from fractions import Fraction

import flint

from exact_khk.diagnostics.kernels import _Evaluator, _point, canonical_nullspace, lift, monomials, to_mpoly
from exact_khk.errors import InputError, SingularStepError

#: the fit of one entry at degree δ solves a system with 2·C(N + δ, N)·C(k + J, J) unknowns (k integrals
#: found, J the degree in them): not beyond this (1300 admits degree 4 in 6 variables with J = 2, which the
#: Clebsch system's second integral needs: 2·210·3 = 1260; a few seconds per fit on the shared 2-core machine)
MAX_FIT_UNKNOWNS = 1300
#: the tangent route evaluates (orbit length) × candidates × N monomial derivatives in Python: not beyond this
MAX_TANGENT_WORK = 4_000_000
#: a fit is accepted when its nullspace kept its dimension while this many more orbits were added
STABLE_ORBITS = 3
#: random column orders tried for sparse kernel vectors (:func:`circuits`)
CIRCUIT_ORDERS = 200


def _orbit_with_tangents(fld, eps, x0, steps, p):
    from exact_khk.kahan.map import KahanMap
    phi = KahanMap(fld, eps, f"gf:{p}")
    pts = phi.orbit(x0, steps)
    N = fld.dim
    T = flint.nmod_mat(N, N, [int(i == j) for i in range(N) for j in range(N)], p)
    tangents = [T]
    for q in pts[:-1]:
        J = phi.jacobian(q)
        T = flint.nmod_mat(N, N, [int(t) for r in J for t in r], p) * T
        tangents.append(T)
    return [[int(t) for t in q] for q in pts], tangents


def _gradients(exps, x, p):
    """The m × N matrix of ∂φ_j/∂x_t at x mod p."""
    N = len(x)
    out = []
    for e in exps:
        row = []
        for t in range(N):
            if not e[t]:
                row.append(0)
                continue
            v = e[t]
            for i, k in enumerate(e):
                kk = k - (i == t)
                if kk:
                    v = v * pow(x[i], kk, p) % p
            row.append(v % p)
        out += row
    return flint.nmod_mat(len(exps), N, out, p)


def entry_jacobian(fld, eps, x0, exps, steps, p, seed=0):
    """(pivots, free, {(pivot, free): value}, {(pivot, free): gradient row}) of the canonical
    kernel of the orbit of ``x0`` over F_p (module docstring), or None where the orbit is
    singular mod p or the work would exceed MAX_TANGENT_WORK."""
    m, N = len(exps), fld.dim
    if (steps + 1) * m * N > MAX_TANGENT_WORK:
        return None
    try:
        pts, tangents = _orbit_with_tangents(fld, eps, x0, steps, p)
    except (SingularStepError, ZeroDivisionError, InputError):
        return None
    ev = _Evaluator(exps)
    rows = [ev(q, 1, p) for q in pts]
    pivots, free, basis = canonical_nullspace(rows, m, p)
    if not free or not pivots:
        return pivots, free, {}, {}
    A = flint.nmod_mat(len(rows), m, [v for r in rows for v in r], p)
    AP = flint.nmod_mat(len(rows), len(pivots), [A[k, c] for k in range(len(rows)) for c in pivots], p)
    V = flint.nmod_mat(m, len(free), [basis[j][c] for c in range(m) for j in range(len(free))], p)
    rng = random.Random(f"tangent-{seed}-{p}")
    for _ in range(4):  # a random left factor G makes the consistent system A_π c' = b square
        G = flint.nmod_mat(len(pivots), len(rows), [rng.randrange(p) for _ in range(len(pivots) * len(rows))], p)
        M = G * AP
        if M.rank() == len(pivots):
            break
    else:
        return None
    D = [_gradients(exps, q, p) * T for q, T in zip(pts, tangents)]  # m × N each: d φ(x_k) / d x_0
    values = {(c, f): basis[j][c] for j, f in enumerate(free) for c in pivots}
    grads = {key: [0] * N for key in values}
    for l in range(N):
        B = flint.nmod_mat(len(rows), m, [Dk[j, l] for Dk in D for j in range(m)], p)
        X = M.solve(G * (-(B * V)))
        for i, c in enumerate(pivots):
            for j, f in enumerate(free):
                grads[(c, f)][l] = int(X[i, j])
    return pivots, free, values, grads


def circuits(basis, m, p, seed=0, orders=CIRCUIT_ORDERS) -> list:
    """Supports of sparse kernel vectors (circuits: no kernel vector has a smaller support inside),
    smallest first: the rows of the reduced echelon form of the kernel basis under random column
    orders (each row is the only kernel vector, up to a factor, supported on its pivot and the
    non-pivot columns).  Their entries are simpler integrals than those of the canonical basis
    (Clebsch: {1, p1², p2², p3²} against 7 of 10 columns)."""
    d = len(basis)
    if not d:
        return []
    support = [c for c in range(m) if any(v[c] for v in basis)]
    rng = random.Random(f"circuits-{seed}")
    found = set()
    for t in range(orders):
        order = support[:] if t == 0 else rng.sample(support, len(support))
        R, r = flint.nmod_mat(d, len(order), [v[c] for v in basis for c in order], p).rref()
        for i in range(r):
            found.add(frozenset(order[j] for j in range(len(order)) if int(R[i, j])))
    # each support found is minimal already: a kernel vector supported inside row i's support (its
    # pivot and non-pivot columns) is a multiple of row i, its coefficients being fixed by the pivots
    small = [tuple(sorted(S)) for S in sorted(found, key=lambda S: (len(S), sorted(S)))]
    # the canonical basis vectors are circuits too (support: pivots and one free column); they are
    # taken in turn with the smallest ones (the Lagrange top's modified energy is fitted from one)
    canonical = [tuple(c for c in range(m) if v[c]) for v in basis]
    out = []
    for pair in zip(small, canonical):
        out += [S for S in pair if S not in out]
    return out + [S for S in small[len(canonical):] + canonical[len(small):] if S not in out]


def rank_mod(rows, N, p) -> int:
    return flint.nmod_mat(len(rows), N, [v % p for r in rows for v in r], p).rank() if rows else 0


class EntryFitter:
    """Fits entries of a kernel vector as N/D (module docstring) from a pool of orbits.

    With ``known`` integrals I_i = A_i/B_i (dict polynomials), N and D may have coefficients
    polynomial in the I_i (total degree ≤ J): the columns φ(x)·c^b with c the values of the I_i
    on the orbit ("modulo functions of those already found").  Then every vector
    μ·c^b·(A_i − c_i B_i) vanishes on every orbit; these *junk* vectors are spanned explicitly and
    the fit is the nullspace modulo them; the reported integral is N(x, I(x))/D(x, I(x)) with the
    denominators of the I_i cleared."""

    def __init__(self, fld, eps, exps, steps, pivots, seed, margin, known=()):
        self.fld, self.eps, self.exps, self.steps, self.pivots = fld, eps, exps, steps, tuple(pivots)
        self.margin, self.known = margin, list(known)
        self.rng = random.Random(f"fit-{seed}")
        self.starts = []          # pool starting points (rational) and the known integrals' values there
        self.data = {}            # p -> list of (points mod p, entry values, known values) per pool orbit
        self.evals = {}           # (p, δ) -> list per pool orbit of rows of monomial values

    def _orbit(self, start, p):
        from exact_khk.kahan.map import KahanMap
        x0, cvals = start
        if any(c.denominator % p == 0 for c in cvals):
            return None
        try:
            pts = [[int(t) for t in q] for q in KahanMap(self.fld, self.eps, f"gf:{p}").orbit(x0, self.steps)]
        except (SingularStepError, ZeroDivisionError, InputError):
            return None
        ev = _Evaluator(self.exps)
        pivots, free, basis = canonical_nullspace([ev(q, 1, p) for q in pts], len(self.exps), p)
        if tuple(pivots) != self.pivots:
            return None  # a smaller invariant set or an unlucky prime: another pivot pattern
        return (pts, {(c, f): basis[j][c] for j, f in enumerate(free) for c in pivots},
                [c.numerator * pow(c.denominator, -1, p) % p for c in cvals])

    def _start(self):
        x = _point(self.rng, self.fld.dim)
        vals = []
        for num, den in self.known:
            d = _value(den, x)
            if d == 0:
                return None
            vals.append(_value(num, x) / d)
        return x, vals

    def pool(self, p, count):
        """``count`` pool orbits mod p (None when a pool orbit is unusable mod this prime)."""
        first = not self.data or p == next(iter(self.data))
        data = self.data.setdefault(p, [])
        while len(data) < count:
            if len(data) < len(self.starts):
                got = self._orbit(self.starts[len(data)], p)
                if got is None:
                    return None
                data.append(got)
                continue
            if not first:
                return None
            for _ in range(20):
                start = self._start()
                got = None if start is None else self._orbit(start, p)
                if got is not None:
                    self.starts.append(start)
                    data.append(got)
                    break
            else:
                return None
        return data[:count]

    def _rows(self, p, delta, J, key, start, stop):
        """The rows [φ(x)·c^b | −e(x_s)·φ(x)·c^b] of the pool orbits start..stop-1 mod p (None: pool unusable)."""
        data = self.pool(p, stop)
        if data is None:
            return None
        cache = self.evals.setdefault((p, delta), [])
        ev = _Evaluator(monomials(self.fld.dim, delta))
        while len(cache) < stop:
            cache.append([ev(q, 1, p) for q in data[len(cache)][0]])
        cmons = monomials(len(self.known), J) if self.known else [()]
        rows = []
        for (_, values, cv), block in zip(data[start:stop], cache[start:stop]):
            e = values[key]
            ws = [math.prod(pow(c, k, p) for c, k in zip(cv, b)) % p for b in cmons]
            for r in block:
                left = [v * w % p for w in ws for v in r]
                rows.append(left + [(-e * v) % p for v in left])
        return rows

    def _junk(self, delta, J, p):
        """Reduced echelon rows (mod p) of the span of the vectors μ·c^b·(A_i − c_i·B_i) in both halves."""
        if not self.known or J == 0:
            return []
        mons = monomials(self.fld.dim, delta)
        md, pos = len(mons), {e: i for i, e in enumerate(monomials(self.fld.dim, delta))}
        cmons = monomials(len(self.known), J)
        cpos = {b: i for i, b in enumerate(cmons)}
        width = 2 * md * len(cmons)
        vecs = []
        for i, (num, den) in enumerate(self.known):
            deg = max(sum(e) for e in list(num) + list(den))
            for mu in monomials(self.fld.dim, delta - deg) if deg <= delta else []:
                for b in cmons:
                    b1 = tuple(k + (j == i) for j, k in enumerate(b))
                    if b1 not in cpos:
                        continue
                    for half in (0, width // 2):
                        v = [0] * width
                        for poly, bb, sign in ((num, b, 1), (den, b1, -1)):
                            for e, c in poly.items():
                                col = half + cpos[bb] * md + pos[tuple(x + y for x, y in zip(e, mu))]
                                v[col] = (v[col] + sign * c.numerator * pow(c.denominator, -1, p)) % p
                        vecs.append(v)
        if not vecs:
            return []
        R, rank = flint.nmod_mat(len(vecs), width, [t for v in vecs for t in v], p).rref()
        return [[int(R[i, j]) for j in range(width)] for i in range(rank)]

    def _representative(self, vectors, junk, p):
        """The one vector of the nullspace modulo the junk span, reduced by the junk's echelon rows
        and scaled to a leading 1 (canonical, so its images mod several primes lift together); or None."""
        if len(vectors) != len(junk) + 1:
            return None
        piv = [(next(j for j, t in enumerate(r) if t), r) for r in junk]
        for v in vectors:
            v = list(v)
            for c, r in piv:
                if v[c]:
                    k = v[c]
                    v = [(a - k * b) % p for a, b in zip(v, r)]
            if any(v):
                return _normalised(v, p)
        return None

    def _grown(self, p, delta, J, key, count, width):
        """(nullspace basis as an nmod_mat, orbits used): the pool grows one orbit at a time until the
        nullspace has kept its dimension for STABLE_ORBITS orbits (a relation between the entry and
        the other integrals' values on few orbits loses a dimension per orbit), or is zero."""
        rows = self._rows(p, delta, J, key, 0, count)
        if rows is None:
            return None, count
        _, _, basis = canonical_nullspace(rows, width, p)
        if not basis:
            return None, count
        B = flint.nmod_mat(width, len(basis), [v[i] for i in range(width) for v in basis], p)
        stable = 0
        while stable < STABLE_ORBITS and count < width + STABLE_ORBITS + 2:
            block = self._rows(p, delta, J, key, count, count + 1)
            if block is None:
                return None, count
            count += 1
            X, nul = (flint.nmod_mat(len(block), width, [v for r in block for v in r], p) * B).nullspace()
            if nul == 0:
                return None, count
            stable = stable + 1 if nul == B.ncols() else 0
            if nul < B.ncols():
                B = B * flint.nmod_mat(X.nrows(), nul, [X[i, j] for i in range(X.nrows()) for j in range(nul)], p)
        return B, count

    def fit(self, key, delta, primes, J=0):
        """(N, D) dicts over Q with N/D equal to the entry ``key`` on the pool's orbits, of degree ≤ δ
        (coefficients of degree ≤ J in the known integrals), or None (no such pair, not unique, or
        the lift not confirmed)."""
        mons = monomials(self.fld.dim, delta)
        cmons = monomials(len(self.known), J) if self.known else [()]
        md = len(mons)
        width = 2 * md * len(cmons)
        if width > MAX_FIT_UNKNOWNS:
            return None
        start = max(delta + J + 2, math.ceil((width + 2 * self.margin) / (self.steps + 1)))
        B, count = self._grown(primes[0], delta, J, key, start, width)
        if B is None:
            return None
        vec = self._representative([[int(B[i, j]) for i in range(width)] for j in range(B.ncols())],
                                   self._junk(delta, J, primes[0]), primes[0])
        if vec is None:
            return None  # no pair of this degree, or not unique: the caller raises δ
        per = [(primes[0], [vec])]
        for p in primes[1:]:
            rows = self._rows(p, delta, J, key, 0, count)
            if rows is None:
                continue
            _, _, basis = canonical_nullspace(rows, width, p)
            vec = self._representative(basis, self._junk(delta, J, p), p)
            if vec is None:
                continue
            per.append((p, [vec]))
            out = lift(per)
            if out is not None:
                return self._compose(out[0], mons, cmons, J)
        return None

    def _compose(self, vec, mons, cmons, J):
        """N(x, I(x))/D(x, I(x)) with the known integrals' denominators cleared, as dicts over Q."""
        N = self.fld.dim
        md = len(mons)
        half = len(vec) // 2
        parts = []
        for off in (0, half):
            total = to_mpoly({}, N)
            for k, b in enumerate(cmons):
                coeffs = {e: c for e, c in zip(mons, vec[off + k * md: off + (k + 1) * md]) if c}
                if not coeffs:
                    continue
                term = to_mpoly(coeffs, N)
                for (num, den), bi in zip(self.known, b):
                    term = term * to_mpoly(num, N) ** bi * to_mpoly(den, N) ** (J - bi)
                total = total + term
            parts.append(total)
        num, den = parts
        if num.is_zero() or den.is_zero():
            return None
        g = num.gcd(den)
        num, den = num / g, den / g
        return ({tuple(int(t) for t in e): Fraction(int(c.p), int(c.q)) for e, c in num.to_dict().items()},
                {tuple(int(t) for t in e): Fraction(int(c.p), int(c.q)) for e, c in den.to_dict().items()})


def _value(poly, x):
    total = Fraction(0)
    for e, c in poly.items():
        term = c
        for t, k in zip(x, e):
            if k:
                term *= t ** k
        total += term
    return total


def _normalised(v, p):
    """v scaled so that its first nonzero entry is 1 (the canonical representative of its line)."""
    inv = pow(next(t for t in v if t), -1, p)
    return [t * inv % p for t in v]
