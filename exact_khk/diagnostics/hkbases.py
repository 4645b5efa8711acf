"""Integrals from Hirota–Kimura bases: a ratio of two entries of a sparse kernel vector, fitted whole.

A *Hirota–Kimura basis* (Petrera, Pfadler, Suris, Experimental Math. 18 (2009), arXiv:0808.3345) is a
set S of candidate monomials whose orbit kernel K_S(x_0) is one-dimensional for a generic x_0: a
circuit of the orbit kernel (:func:`.fitting.circuits`).  Its vector c(x_0), unique up to a factor,
depends only on the orbit, so every ratio c_i/c_j of two of its entries is an integral.
:mod:`.fitting` fits one entry per circuit, c_i/c_free, at degree ≤ ``fit_degree`` over all
monomials; this route takes the ratio the kernel makes simplest and fits it at its own degree:

* **Which ratio.**  For each circuit (one :func:`.fitting.entry_jacobian` call: the gradients of
  e_i = c_i/c_last mod p) and each pair (i, j), the gradient of c_i/c_j = e_i/e_j says whether it
  raises the rank of the integrals kept.  Of those that do, the degrees (d_N, d_D) of numerator
  and denominator are read along a random line x_0 = a + t·b (the restriction of a rational
  function to a generic line keeps its total degrees): values at t = 1, 2, … from one orbit per t
  (all circuits read the same orbits), univariate rational reconstruction over F_p.  The pair with
  the fewest fit unknowns is fitted.
* **Fit.**  With c_j moved last in the circuit, r = c_i/c_j is an entry of its canonical kernel vector,
  fitted by :meth:`.fitting.EntryFitter.solve` with N and D over the monomials of degree ≤ d_N and
  ≤ d_D: one vector at the measured degrees (N/D reduced), lifted to Q over several primes.
  Coordinate sign changes σ under which r is invariant (single and paired flips, tested mod p on one
  orbit each) shrink the fit: r = N/D reduced and r∘σ = r give N∘σ = χ(σ)N and D∘σ = χ(σ)D with
  χ = ±1, and the invariant monomials (χ = 1) are tried first, then all monomials when within
  MAX_HK_UNKNOWNS.
* The caller verifies each integral exactly on a fresh orbit and keeps it only if it raises the
  exact rank of the Jacobian (``_Job.complete``).

Measured on the Clebsch system (ω = (1, 2, 5), ε = 1/10, degree 2; scripts/check_clebsch_integrals.py
recomputes it with SymPy): the orbit kernel (dimension 4) lives on 1, p_k², m_k p_k, m_k²; the circuit
{1, p1², p2², p3²} gives one integral (its three ratios have Jacobian rank 1), the circuits inside
{1, p_k², m_k p_k} two more (entries of degree 8); every ratio that raises the rank to 4 involves an
m_k² and has degree ≥ (10, 8): c_1/c_{m1p1} on {1, p1², m1p1, m2p2, m3p3, m2², m3²}.  Invariant under
the flips of (m_k, p_k), its fit has 1372 + 553 unknowns (8008 + 3003 over all monomials); two
primes lift it.  On the Lagrange top (catalogue, degree 2), after m3 and the two level-set pencils, the
ratio c_{m1²}/c_{p3²} of {1, p3, m1², m2², p3²} has degree (8, 6) and is invariant under the flips of
(m1, p1) and of (m2, p2): 847 + 276 unknowns, whose nullspace shrinks slowly as orbits are added (by
7 an orbit of 41 points, 158 left after 30 orbits); the pool grows from 26 orbits to 59 before it is one
vector.
"""

from __future__ import annotations

import itertools
import math
import random

import flint

from exact_khk.diagnostics.fitting import (EntryFitter, FitTooLarge, circuits, entry_jacobian, orbit_with_tangents,
                                           rank_mod)
from exact_khk.diagnostics.kernels import (_Evaluator, _point, canonical_nullspace, monomial_text, monomials,
                                           orbit_mod_or_none)
from exact_khk.errors import InputError, SingularStepError

#: the highest degree of a fitted numerator or denominator read along the line
MAX_HK_DEGREE = 12
#: unknowns of one fit at most (Clebsch: 1925; the nullspace of its 2009 x 1925 matrix mod p, about 4 s)
MAX_HK_UNKNOWNS = 2500
#: circuits whose ratios are examined, at most
MAX_HK_CIRCUITS = 200
#: fits tried in one search, at most: the first candidate's two shapes (sign-invariant, then all
#: monomials).  The fourth integral of the Clebsch system and that of the Lagrange top are each the
#: first fit (Lagrange: degree 8/6, 1123 unknowns, the pool grown to 59 orbits until its nullspace is
#: one vector; 11 s with the choice of the ratio)
MAX_HK_FITS = 2


def _vector(rows, cols, p):
    """The kernel vector of the evaluation ``rows`` restricted to ``cols`` (a list of column
    indices), normalised to 1 at the last column; None unless the kernel is that one line."""
    pivots, free, basis = canonical_nullspace([[r[c] for c in cols] for r in rows], len(cols), p)
    if len(basis) != 1 or free[0] != len(cols) - 1:
        return None
    return basis[0]


def _degrees(ts, values, p, top):
    """(deg N, deg D) of the univariate rational function with the given values mod p, both ≤ ``top``,
    or None.  At the bound d the pairs (N, D) matching the values are the multiples of the reduced
    pair by polynomials of degree ≤ d − d0 (d0 = its larger degree), given enough points: one solve at
    ``top`` gives d0, one at d0 the pair."""
    def solve(d):
        M = flint.nmod_mat(len(ts), 2 * d + 2, [w for t, g in zip(ts, values) for w in
                                                [pow(t, k, p) for k in range(d + 1)]
                                                + [(-g * pow(t, k, p)) % p for k in range(d + 1)]], p)
        return M.nullspace()

    if 2 * top + 4 > len(ts):
        return None
    d0 = top + 1 - solve(top)[1]
    if d0 < 0:
        return None
    X, nul = solve(d0)
    if nul != 1:
        return None
    v = [int(X[i, 0]) for i in range(2 * d0 + 2)]
    return (max((k for k in range(d0 + 1) if v[k]), default=0),
            max((k for k in range(d0 + 1) if v[d0 + 1 + k]), default=0))


def _candidates(job, ref, mod_rows, p, seed):
    """[(unknowns, (dN, dD), circuit columns, i, j)] for the ratios c_i/c_j of circuits that raise the
    rank of ``mod_rows`` mod p, fewest fit unknowns first."""
    N, m = job.fld.dim, len(job.exps)
    base = rank_mod(mod_rows, N, p)
    raising = []
    try:  # the orbit and its tangents, shared by every circuit (most of entry_jacobian's work)
        orbit = orbit_with_tangents(job.fld, job.eps, ref.x0, job.steps, p)
    except (SingularStepError, ZeroDivisionError, InputError):
        return []
    for S in circuits(ref.basis, m, p, seed)[:MAX_HK_CIRCUITS]:
        data = entry_jacobian(job.fld, job.eps, ref.x0, [job.exps[c] for c in S], job.steps, p, seed, orbit)
        if data is None or len(data[1]) != 1:
            continue
        last = data[1][0]
        val = {c: v for (c, _), v in data[2].items()}
        grad = {c: g for (c, _), g in data[3].items()}
        val[last], grad[last] = 1, [0] * N
        pairs = []
        for i, j in itertools.permutations(range(len(S)), 2):
            if not val.get(i) or not val.get(j) or (j, i) in pairs:
                continue
            inv = pow(val[j], -2, p)
            g = [((gi * val[j] - val[i] * gj) * inv) % p for gi, gj in zip(grad[i], grad[j])]
            if rank_mod(mod_rows + [g], N, p) > base:
                pairs.append((i, j))
        if pairs:
            raising.append((S, pairs))
    if not raising:
        return []
    rng = random.Random(f"hk-line-{seed}")
    a, b = _point(rng, N), _point(rng, N)
    ts = list(range(1, 2 * MAX_HK_DEGREE + 6))
    support = sorted({c for S, _ in raising for c in S})
    ev = _Evaluator([job.exps[c] for c in support])
    col = {c: k for k, c in enumerate(support)}
    lines = []
    for t in ts:
        pts = orbit_mod_or_none(job.fld, job.eps, [x + t * y for x, y in zip(a, b)], job.steps, p)
        lines.append(None if pts is None else [ev(q, 1, p) for q in pts])
    out = []
    for S, pairs in raising:
        vecs = [None if rows is None else _vector(rows, [col[c] for c in S], p) for rows in lines]
        good = [(t, v) for t, v in zip(ts, vecs) if v is not None]
        for i, j in pairs:
            pts = [(t, v[i] * pow(v[j], -1, p) % p) for t, v in good if v[j]]
            deg = _degrees([t for t, _ in pts], [g for _, g in pts], p, MAX_HK_DEGREE)
            if deg is not None:
                size = math.comb(N + deg[0], N) + math.comb(N + deg[1], N)
                out.append((size, deg, S, i, j))
    return sorted(out, key=lambda r: (r[0], r[1], r[2], r[3], r[4]))


def _symmetries(job, cols, i, j, p, seed):
    """The coordinate sign changes (single and paired flips, as tuples of ±1) that leave the ratio
    c_i/c_j of the circuit ``cols`` invariant, tested mod p on one orbit each."""
    N = job.fld.dim
    ev = _Evaluator([job.exps[c] for c in cols])
    x = _point(random.Random(f"hk-sym-{seed}"), N)

    def ratio(y):
        pts = orbit_mod_or_none(job.fld, job.eps, y, job.steps, p)
        v = None if pts is None else _vector([ev(q, 1, p) for q in pts], list(range(len(cols))), p)
        return None if v is None or not v[j] else v[i] * pow(v[j], -1, p) % p

    r0 = ratio(x)
    if r0 is None:
        return []
    flips = [tuple(-1 if k in ks else 1 for k in range(N))
             for n in (1, 2) for ks in itertools.combinations(range(N), n)]
    return [s for s in flips if ratio([t * c for t, c in zip(x, s)]) == r0]


def _invariant(exps, flips):
    return [e for e in exps if all(sum(k for k, s in zip(e, f) if s < 0) % 2 == 0 for f in flips)]


def hk_basis_integrals(job, ref, mod_rows, primes, seed, wanted):
    """Yield (num, den, note) for integrals from the ratios of HK bases (module docstring) while
    ``wanted()`` > 0 (re-read after each: the caller's acceptance updates ``mod_rows``); at most
    MAX_HK_FITS fits in all."""
    p, N = primes[0], job.fld.dim
    tried, budget = set(), MAX_HK_FITS
    while wanted() > 0 and budget > 0:
        cands = [c for c in _candidates(job, ref, mod_rows, p, seed) if (c[2], c[3], c[4]) not in tried]
        pair = None
        for _, (dn, dd), S, i, j in cands:
            tried.add((S, i, j))
            flips = _symmetries(job, S, i, j, p, seed)
            # c_j last: c_i/c_j is the entry (i, last) of the circuit's canonical kernel vector
            sub = [c for c in S if c != S[j]] + [S[j]]
            fitter = EntryFitter(job.fld, job.eps, [job.exps[c] for c in sub], job.steps, range(len(sub) - 1),
                                 seed, job.margin, (), job.progress, job.max_bytes)
            shapes = [(_invariant(monomials(N, dn), flips), _invariant(monomials(N, dd), flips))] if flips else []
            for nb, db in shapes + [(monomials(N, dn), monomials(N, dd))]:
                if len(nb) + len(db) <= MAX_HK_UNKNOWNS and budget > 0:
                    budget -= 1
                    try:
                        pair = fitter.solve((sub.index(S[i]), len(sub) - 1), nb, db, primes)
                    except FitTooLarge as exc:
                        job.warnings.append(f"HK basis: {exc}: not tried")
                        continue
                    if pair is not None:
                        break
            if pair is not None or budget <= 0:
                break
        if pair is None:
            return
        text = lambda c: monomial_text(job.exps[c], job.variables)  # noqa: E731
        yield pair[0], pair[1], (f"fitted (degree {dn}/{dd}, {len(nb) + len(db)} unknowns) as the ratio c_{text(S[i])}"
                                 f"/c_{text(S[j])} of the HK basis {', '.join(map(text, S))} (one kernel vector "
                                 f"on it)")
