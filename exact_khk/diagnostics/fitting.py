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
  orbit s of a pool, one linear system [R_s | −e(x_s)·R_s] over F_p (R_s the echelon rows
  of the orbit's evaluation matrix: one row per condition, not per point) filled straight
  into an ``nmod_mat``, whose nullspace at the lowest δ is one vector, lifted to Q by
  Chinese remaindering and rational reconstruction over several word-size primes
  (:func:`.kernels.lift`) — :meth:`EntryFitter.fit`.  The caller checks each fitted
  N/D exactly on a fresh orbit and keeps it only if it raises the exact rank of the
  Jacobian of the integrals found (so never a power or product of found ones).
* **Which fits.**  N and D are sought in the variables e depends on (its gradient mod p):
  the KQV chain's entries of three-term kernel vectors depend on 4 of N variables, and their
  degree-3 fits have 70 unknowns whatever N.  A fit is tried only if it can equal e on a
  random line over F_p (:func:`entry_line`, :meth:`EntryLine.admits`): the restriction of e
  there, by Cauchy interpolation, has degree at most e's, so a fit that cannot reach it (or
  whose restriction has no solution beyond the vanishing ones) cannot succeed over Q.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass
from fractions import Fraction

import flint

from exact_khk.diagnostics.kernels import (PROGRESS_ENTRIES, _Evaluator, _point, _rref_pivots,
                                           _size, canonical_nullspace, evaluation_matrix, evaluator, lift, monomials,
                                           orbit_mod_or_none, to_mpoly)
from exact_khk.errors import InputError, SingularStepError

#: the fit of one entry at degree δ solves a system with 2·C(n + δ, n)·C(k + J, J) unknowns (n the variables
#: of the entry and of the k integrals used, J the degree in them): not beyond this.  1300 admits degree 4 in
#: 6 variables with J = 2, which the Clebsch system's second integral needs: 2·210·3 = 1260 unknowns, a
#: 1305 × 1260 nmod_mat (33 MB by fit_bytes), 1.0-1.5 s CPU per fit on the loaded shared 2-core machine.  The
#: KQV chain's integrals are fitted in their 4 variables at degree 3 (70 unknowns) whatever N.
MAX_FIT_UNKNOWNS = 1300
#: the same for a fit without the integrals found (J = 0), tried only when the entry's degree on a random line
#: is at most δ, so that it succeeds unless that line lowered the degree: 3 600 admits degree 3 in 20 variables
#: (KQV N = 20: an entry depending on all 20 variables, 3 542 unknowns, a 3 567 × 3 542 system: fitted in
#: 305 s CPU and 2 161 MB peak RSS over two primes on the loaded shared machine)
MAX_PLAIN_FIT_UNKNOWNS = 3600
#: the tangent route evaluates (orbit length) × candidates × N monomial derivatives in Python: not beyond this
MAX_TANGENT_WORK = 4_000_000
#: a fit is accepted when its nullspace kept its dimension while this many more orbits were added
STABLE_ORBITS = 3
#: random column orders tried for sparse kernel vectors (:func:`circuits`)
CIRCUIT_ORDERS = 200


def orbit_with_tangents(fld, eps, x0, steps, p):
    """(points, tangents) of the orbit of ``x0`` over F_p: the points x_k and T_k = dx_k/dx_0 (``nmod_mat``).
    Raises SingularStepError / ZeroDivisionError / InputError where a step is singular mod p."""
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
    out = [0] * (len(exps) * N)
    for r, e in enumerate(exps):
        used = [(i, k) for i, k in enumerate(e) if k]
        for t, k in used:
            v = k
            for i, kk in used:
                if kk - (i == t):
                    v = v * pow(x[i], kk - (i == t), p) % p
            out[r * N + t] = v % p
    return flint.nmod_mat(len(exps), N, out, p)


def entry_jacobian(fld, eps, x0, exps, steps, p, seed=0, orbit=None):
    """(pivots, free, {(pivot, free): value}, {(pivot, free): gradient row}) of the canonical
    kernel of the orbit of ``x0`` over F_p (module docstring), or None where the orbit is
    singular mod p or the work would exceed MAX_TANGENT_WORK.  ``orbit``: :func:`orbit_with_tangents`
    of the same x0, steps and p, computed once for all the supports of a search (it is most of the work)."""
    m, N = len(exps), fld.dim
    if (steps + 1) * m * N > MAX_TANGENT_WORK:
        return None
    try:
        pts, tangents = orbit or orbit_with_tangents(fld, eps, x0, steps, p)
    except (SingularStepError, ZeroDivisionError, InputError):
        return None
    ev = _Evaluator(exps)
    rows = [ev(q, 1, p) for q in pts]
    pivots, free, basis = canonical_nullspace(rows, m, p)
    if not free or not pivots:
        return pivots, free, {}, {}
    A = flint.nmod_mat(len(rows), m, [v for r in rows for v in r], p)
    AP = flint.nmod_mat(len(rows), len(pivots), [A[k, c] for k in range(len(rows)) for c in pivots], p)
    rng = random.Random(f"tangent-{seed}-{p}")
    for _ in range(4):  # a random left factor G makes the consistent system A_π c' = b square
        G = flint.nmod_mat(len(pivots), len(rows), [rng.randrange(p) for _ in range(len(pivots) * len(rows))], p)
        M = G * AP
        if M.rank() == len(pivots):
            break
    else:
        return None
    # row k of the derivative of A·v_f in x_0 is v_f^T (dφ(x_k)/dx_0): one (free × N) product per point
    F = len(free)
    VT = flint.nmod_mat(F, m, [basis[j][c] for j in range(F) for c in range(m)], p)
    W = [VT * _gradients(exps, q, p) * T for q, T in zip(pts, tangents)]
    B = flint.nmod_mat(len(rows), F * N, [-int(Wk[j, l]) % p for Wk in W for j in range(F) for l in range(N)], p)
    X = M.solve(G * B)  # column j·N + l: the derivatives of the entries of v_{free j} in the direction e_l
    values = {(c, f): basis[j][c] for j, f in enumerate(free) for c in pivots}
    grads = {(c, f): [int(X[i, j * N + l]) for l in range(N)] for i, c in enumerate(pivots) for j, f in enumerate(free)}
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
        for row in R.tolist()[:r]:
            found.add(frozenset(c for c, v in zip(order, row) if v))
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


@dataclass
class EntryLine:
    """An entry restricted to the line x = a + t·b over F_p: A/B in lowest terms (``nmod_poly``), or
    A = B = None when its degree there exceeds the bound it was computed to."""

    p: int
    a: list
    b: list
    A: object = None
    B: object = None

    @property
    def degree(self):
        return None if self.A is None else max(self.A.degree(), self.B.degree())

    def restrict(self, poly: dict):
        """A polynomial {exponents: Fraction} on the line, as an ``nmod_poly`` in t."""
        p = self.p
        lines = [flint.nmod_poly([u, w], p) for u, w in zip(self.a, self.b)]
        out = flint.nmod_poly([], p)
        for e, c in poly.items():
            term = flint.nmod_poly([c.numerator * pow(c.denominator, -1, p) % p], p)
            for L, k in zip(lines, e):
                if k:
                    term *= L ** k
            out += term
        return out

    def admits(self, known, delta, J) -> bool:
        """False when no N/D of degree ≤ δ with coefficients of degree ≤ J in the ``known`` integrals (pairs
        of ``nmod_poly`` on the line, :meth:`restrict`) equals the entry on the line: the pairs
        (n_b, d_b) of polynomials in t of degree ≤ δ with Σ n_b P_b · B = Σ d_b P_b · A (P_b the
        composed products of :meth:`EntryFitter._compose` on the line) are then only those with
        Σ n_b P_b = Σ d_b P_b = 0.  A fit's N/D, restricted to the line, would be another one unless its
        denominator vanishes on the whole line: probability ≤ (its degree)/p for a random line."""
        p = self.p
        cmons = monomials(len(known), J) if known else [()]
        P = []
        for b in cmons:
            f = flint.nmod_poly([1], p)
            for (A, B), k in zip(known, b):
                f *= A ** k * B ** (J - k)
            P.append(f)
        cols = [f * flint.nmod_poly([0] * k + [1], p) for f in P for k in range(delta + 1)]

        def nullity(polys):
            rows = 1 + max(f.degree() for f in polys)
            M = flint.nmod_mat(rows, len(polys), [int(f[r]) if r <= f.degree() else 0 for r in range(rows)
                                                 for f in polys], p)
            return len(polys) - M.rank()

        return nullity([f * self.B for f in cols] + [-f * self.A for f in cols]) > 2 * nullity(cols)


def entry_line(fld, eps, exps, steps, pivots, key, p, rng, max_degree):
    """The kernel entry ``key`` (:func:`entry_jacobian`'s keys) restricted to a random line x = a + t·b over
    F_p (:class:`EntryLine`): from its values at points of the line (an orbit kernel of ``exps`` each, kept
    where its pivots are ``pivots``), by Cauchy interpolation at 2D + 1 of them
    (:func:`.degrees.cauchy_degree`), D doubled up to ``max_degree`` until CHECK_POINTS more confirm it.
    Its degree max(deg A, deg B) is never above that of the entry over Q (a restriction and a reduction
    mod p only lower it).  A and B are None when no fraction of degree ≤ ``max_degree`` has these values;
    the result is None when too few points of the line were usable."""
    from exact_khk.diagnostics.degrees import CHECK_POINTS, cauchy_degree
    from exact_khk.kahan.map import KahanMap
    phi = KahanMap(fld, eps, f"gf:{p}")
    N = fld.dim
    line = EntryLine(p, [rng.randrange(p) for _ in range(N)], [rng.randrange(p) for _ in range(N)])
    ev = _Evaluator(exps)
    ts, vs, tried = [], [], set()

    def more(count):
        while len(ts) < count:
            if len(tried) > 4 * count + 20:
                return False  # the line meets the bad points too often: no conclusion
            t = rng.randrange(p)
            if t in tried:
                continue
            tried.add(t)
            try:
                pts = phi.orbit([(u + t * w) % p for u, w in zip(line.a, line.b)], steps)
            except (SingularStepError, ZeroDivisionError, InputError):
                continue
            piv, free, basis = canonical_nullspace([ev([int(u) for u in q], 1, p) for q in pts], len(exps), p)
            if tuple(piv) != tuple(pivots):
                continue
            ts.append(t)
            vs.append(basis[free.index(key[1])][key[0]])
        return True

    D = 1
    while True:
        if not more(2 * D + 1 + CHECK_POINTS):
            return None
        got = cauchy_degree(ts[:2 * D + 1], vs[:2 * D + 1], p, D)
        if got is not None and all(got[1](t) == v * got[2](t) for t, v in zip(ts[2 * D + 1:], vs[2 * D + 1:])):
            line.A, line.B = got[1], got[2]
            return line
        if D >= max_degree:
            return line
        D = min(2 * D, max_degree)


def rank_mod(rows, N, p) -> int:
    return flint.nmod_mat(len(rows), N, [v % p for r in rows for v in r], p).rank() if rows else 0


class FitTooLarge(InputError):
    """A fit whose linear system would need more memory than allowed (planned before it is built)."""


#: bytes per entry of a fit's system (:func:`fit_bytes`): measured peak RSS 2 161 MB for the 3 567 × 3 542
#: system of KQV N = 20 (from 283 MB before it: 149 bytes per entry), against 20 for an orbit kernel's
#: matrix and its echelon form (MATRIX_BYTES_PER_ENTRY); where the rest goes was not found
FIT_BYTES_PER_ENTRY = 160


def fit_bytes(width, rows) -> int:
    """The planned memory of one fit (:meth:`EntryFitter.fit`) of ``rows`` × ``width``, FIT_BYTES_PER_ENTRY
    an entry (the ``nmod_mat``, its echelon form and what else the measured peak held)."""
    return FIT_BYTES_PER_ENTRY * rows * width


class EntryFitter:
    """Fits entries of a kernel vector as N/D (module docstring) from a pool of orbits.

    With ``known`` integrals I_i = A_i/B_i (dict polynomials), N and D may have coefficients
    polynomial in the I_i (total degree ≤ J): the columns φ(x)·c^b with c the values of the I_i
    on the orbit ("modulo functions of those already found").  Then every vector
    μ·c^b·(A_i − c_i B_i) vanishes on every orbit; these *junk* vectors are spanned explicitly and
    the fit is the nullspace modulo them; the reported integral is N(x, I(x))/D(x, I(x)) with the
    denominators of the I_i cleared.

    One orbit's conditions on a polynomial P of degree ≤ δ (P = 0 at its points) are the rows of the
    reduced echelon form of its evaluation matrix (as many as its rank, against one per point); the
    fit's system stacks, for each orbit s of the pool, those rows R_s as [R_s ⊗ c_s^b | −e_s R_s ⊗ c_s^b],
    filled straight into one ``nmod_mat`` (its memory planned first, :func:`fit_bytes`).  N and D may
    range over different monomials (:meth:`solve`; the HK-basis route, :mod:`.hkbases`): R_s is then
    the echelon form of the evaluation of their union, its columns of each taken into its half."""

    def __init__(self, fld, eps, exps, steps, pivots, seed, margin, known=(), progress=None, max_bytes=None,
                 cache=None):
        self.fld, self.eps, self.exps, self.steps, self.pivots = fld, eps, exps, steps, tuple(pivots)
        self.margin, self.known = margin, list(known)
        self.cache = FitCache() if cache is None else cache  # shared by the fitters of a search
        self.say, self.max_bytes = progress or (lambda text: None), max_bytes
        self.rng = random.Random(f"fit-{seed}")
        self.starts = []          # pool starting points (rational) and the known integrals' values there
        self.data = {}            # p -> list of (points mod p, entry values, known values) per pool orbit

    def _orbit(self, start, p):
        x0, cvals = start
        if any(c.denominator % p == 0 for c in cvals):
            return None
        if (tuple(x0), p) not in self.cache.orbits:
            self.cache.orbits[tuple(x0), p] = orbit_mod_or_none(self.fld, self.eps, x0, self.steps, p)
        pts = self.cache.orbits[tuple(x0), p]
        if pts is None:
            return None
        ev = evaluator(tuple(self.exps))
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

    def _block(self, p, mons, i):
        """(R, rank): the reduced echelon form of the evaluation of ``mons`` (a tuple) on pool orbit i (its
        first ``rank`` rows are the orbit's conditions); None when the pool is unusable mod p."""
        data = self.pool(p, i + 1)
        if data is None:
            return None
        return self.cache.block((self.starts[i][0], p, mons), lambda: evaluation_matrix(mons, data[i][0], p).rref())

    def _orbits_for(self, p, mons, rows):
        """The number of pool orbits whose echelon rows first reach ``rows`` (None: pool unusable)."""
        total, count = 0, 0
        while total < rows:
            block = self._block(p, mons, count)
            if block is None:
                return None
            total += block[1]
            count += 1
            if count > rows + STABLE_ORBITS + 2:  # orbits of rank 0: nothing to fit against
                return None
        return count

    def _system(self, p, shape, key, start, stop):
        """The ``nmod_mat`` of the conditions [R_s ⊗ c^b | −e_s·R_s ⊗ c^b] of pool orbits start..stop-1
        (class docstring; R_s over ``shape.union``, its columns of N's and of D's monomials in each
        half), or None when the pool is unusable mod p."""
        blocks = [self._block(p, shape.union, i) for i in range(start, stop)]
        if any(b is None for b in blocks):
            return None
        data = self.data[p]
        mu, nn, nd = len(shape.union), len(shape.num), len(shape.den)
        A = flint.nmod_mat(sum(rank for _, rank in blocks), shape.width, p)
        i = 0
        for (_, values, cv), (R, rank) in zip(data[start:stop], blocks):
            e = values[key]
            ws = [math.prod(pow(c, k, p) for c, k in zip(cv, b)) % p for b in shape.cmons]
            left = [(k * nn, w) for k, w in enumerate(ws)]
            right = [(shape.half + k * nd, (-e * w) % p) for k, w in enumerate(ws)]
            flat = [int(t) for t in R.entries()[:rank * mu]]
            for r in range(rank):
                row = flat[r * mu:(r + 1) * mu]
                nz = [(j, v) for j, v in enumerate(row[:nn]) if v]  # N's monomials lead the union
                for off, w in left:
                    for j, v in nz:
                        A[i, off + j] = v * w % p if w != 1 else v
                if not shape.same:
                    nz = [(j, v) for j, v in enumerate([row[c] for c in shape.dcols]) if v]
                for off, w in right:
                    for j, v in nz:
                        A[i, off + j] = v * w % p
                i += 1
        return A

    def _junk(self, shape, J, p):
        """Reduced echelon rows (mod p) of the span of the vectors μ·c^b·(A_i − c_i·B_i) in each half."""
        if not self.known or J == 0:
            return []
        cpos = {b: i for i, b in enumerate(shape.cmons)}
        vecs = []
        for mons, start in ((shape.num, 0), (shape.den, shape.half)):
            md, pos = len(mons), {e: i for i, e in enumerate(mons)}
            for i, (num, den) in enumerate(self.known):
                for mu in mons:
                    shifted = [(tuple(x + y for x, y in zip(e, mu)), c, bb) for poly, bb in ((num, 0), (den, 1))
                               for e, c in poly.items()]
                    if any(t not in pos for t, _, _ in shifted):
                        continue
                    for b in shape.cmons:
                        b1 = tuple(k + (j == i) for j, k in enumerate(b))
                        if b1 not in cpos:
                            continue
                        v = [0] * shape.width
                        for t, c, bb in shifted:
                            col = start + cpos[b1 if bb else b] * md + pos[t]
                            v[col] = (v[col] + (-1 if bb else 1) * c.numerator * pow(c.denominator, -1, p)) % p
                        vecs.append(v)
        if not vecs:
            return []
        R, rank = flint.nmod_mat(len(vecs), shape.width, [t for v in vecs for t in v], p).rref()
        return [[int(R[i, j]) for j in range(shape.width)] for i in range(rank)]

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

    def _nullspace(self, A, width, p):
        """The nullspace of A as a width × nul ``nmod_mat`` (canonical basis from the echelon form), or None if 0."""
        R, rank = A.rref()
        pivots = _rref_pivots(R, rank, width)
        piv = set(pivots)
        free = [c for c in range(width) if c not in piv]
        if not free:
            return None
        B = flint.nmod_mat(width, len(free), p)
        for j, f in enumerate(free):
            B[f, j] = 1
            for i, c in enumerate(pivots):
                t = int(R[i, f])
                if t:
                    B[c, j] = p - t
        return B

    def _grown(self, p, shape, key, count):
        """(nullspace basis as an nmod_mat, orbits used): the pool grows one orbit at a time until the
        nullspace has kept its dimension for STABLE_ORBITS orbits (a relation between the entry and
        the other integrals' values on few orbits loses a dimension per orbit), or is zero."""
        width = shape.width
        A = self._system(p, shape, key, 0, count)
        if A is None:
            return None, count
        if A.nrows() * width > PROGRESS_ENTRIES:
            self.say(f"fit of a kernel entry: echelon form {A.nrows()} x {width} mod p")
        B = self._nullspace(A, width, p)
        del A
        stable = 0
        while B is not None and stable < STABLE_ORBITS and count < width + STABLE_ORBITS + 2:
            block = self._system(p, shape, key, count, count + 1)
            if block is None:
                return None, count
            count += 1
            if not block.nrows():
                continue
            X, nul = (block * B).nullspace()
            if nul == 0:
                return None, count
            stable = stable + 1 if nul == B.ncols() else 0
            if nul < B.ncols():
                B = B * flint.nmod_mat(X.nrows(), nul, [X[i, j] for i in range(X.nrows()) for j in range(nul)], p)
        return B, count

    def fit(self, key, delta, primes, J=0, variables=None):
        """(N, D) dicts over Q with N/D equal to the entry ``key`` on the pool's orbits, of degree ≤ δ
        in the ``variables`` (indices; default all) with coefficients of degree ≤ J in the known
        integrals, or None (no such pair, not unique, or the lift not confirmed).  Raises
        :class:`FitTooLarge` before any work when the system's planned memory exceeds ``max_bytes``."""
        N = self.fld.dim
        variables = tuple(range(N)) if variables is None else tuple(variables)
        mons = [_embedded(e, variables, N) for e in monomials(len(variables), delta)]
        if 2 * len(mons) * (math.comb(len(self.known) + J, J) if self.known else 1) \
                > (MAX_PLAIN_FIT_UNKNOWNS if J == 0 else MAX_FIT_UNKNOWNS):
            return None
        return self.solve(key, mons, mons, primes, J)

    def solve(self, key, num, den, primes, J=0):
        """(N, D) dicts over Q, N over the monomials ``num`` and D over ``den`` (each with coefficients
        of degree ≤ J in the known integrals), with N/D equal to the entry ``key`` on the pool's orbits,
        reduced; or None (no such pair, not unique, or the lift not confirmed).  Raises
        :class:`FitTooLarge` before any work when the system's planned memory exceeds ``max_bytes``."""
        shape = _Shape(num, den, monomials(len(self.known), J) if self.known else [()])
        width = shape.width
        need = width + self.margin
        if self.max_bytes is not None and fit_bytes(width, need) > self.max_bytes:
            raise FitTooLarge(f"a fit with {width} unknowns needs about {_size(fit_bytes(width, need))}, beyond "
                              f"the memory limit of {_size(self.max_bytes)} (EXACT_KHK_MAX_MEMORY)")
        count = self._orbits_for(primes[0], shape.union, need)
        if count is None:
            return None
        count = max(count, max(map(sum, shape.union)) + J + 2)
        B, count = self._grown(primes[0], shape, key, count)
        if B is None:
            return None
        vec = self._representative([[int(B[i, j]) for i in range(width)] for j in range(B.ncols())],
                                   self._junk(shape, J, primes[0]), primes[0])
        if vec is None:
            return None  # no pair of this degree, or not unique: the caller raises δ
        per = [(primes[0], [vec])]
        for p in primes[1:]:
            A = self._system(p, shape, key, 0, count)
            if A is None:
                continue
            B = self._nullspace(A, width, p)
            del A
            if B is None:
                continue
            vec = self._representative([[int(B[i, j]) for i in range(width)] for j in range(B.ncols())],
                                       self._junk(shape, J, p), p)
            if vec is None:
                continue
            per.append((p, [vec]))
            out = lift(per)
            if out is not None:
                return self._compose(out[0], shape, J)
        return None

    def _compose(self, vec, shape, J):
        """N(x, I(x))/D(x, I(x)) with the known integrals' denominators cleared, reduced, as dicts over Q."""
        N = self.fld.dim
        parts = []
        for mons, start in ((shape.num, 0), (shape.den, shape.half)):
            md = len(mons)
            total = to_mpoly({}, N)
            for k, b in enumerate(shape.cmons):
                coeffs = {e: c for e, c in zip(mons, vec[start + k * md: start + (k + 1) * md]) if c}
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


#: entries of the echelon forms kept by a search (:class:`FitCache`, 8 bytes each: 34 MB); the Lagrange top's
#: 200 fits evaluate the monomials of degree <= 1..4 in its 6 variables on the same pool orbits
BLOCK_ENTRIES = 2 ** 22


class FitCache:
    """What the fitters of a search share (their pools start from the same points): ``orbits``, (x0, p) ->
    the orbit mod p (None where singular), and the echelon forms of monomial evaluations on them,
    (x0, p, monomials) -> (R, rank) (:meth:`block`); beyond BLOCK_ENTRIES entries the oldest of other
    monomials or primes are dropped (those of the fit at work are all needed again when its system is
    built, after :meth:`EntryFitter._orbits_for` has counted their ranks)."""

    def __init__(self):
        self.orbits, self.kept, self.entries = {}, {}, 0

    def block(self, key, make):
        if key not in self.kept:
            R, rank = make()
            self.kept[key] = (R, rank)
            self.entries += R.nrows() * R.ncols()
            for old in [k for k in self.kept if k[1:] != key[1:]]:
                if self.entries <= BLOCK_ENTRIES:
                    break
                R0, _ = self.kept.pop(old)
                self.entries -= R0.nrows() * R0.ncols()
        return self.kept[key]


class _Shape:
    """The unknowns of one fit: the coefficients of N over the monomials ``num`` and of D over ``den``,
    each times every product c^b in ``cmons`` of the known integrals' values, as columns [N | D] (c^b
    blocks in each half); ``union`` (``num``, then the rest of ``den``) is evaluated on each pool orbit."""

    def __init__(self, num, den, cmons):
        self.num, self.den, self.cmons = list(num), list(den), list(cmons)
        have = set(self.num)
        self.union = tuple(self.num + [e for e in self.den if e not in have])
        pos = {e: i for i, e in enumerate(self.union)}
        self.dcols = [pos[e] for e in self.den]
        self.same = self.num == self.den
        self.half = len(self.num) * len(self.cmons)
        self.width = self.half + len(self.den) * len(self.cmons)


def _embedded(e, variables, N) -> tuple:
    """The exponent tuple in all N variables of a monomial ``e`` in the ``variables`` (indices)."""
    out = [0] * N
    for i, k in zip(variables, e):
        out[i] = k
    return tuple(out)


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
