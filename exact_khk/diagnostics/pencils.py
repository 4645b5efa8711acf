"""From orbit kernels over Q to integrals: common denominators and pencils.

Let K_i = K(x_i) be the kernels of a few generic orbits (canonical bases over Q,
:mod:`.kernels`), d = dim K_i and W = Σ K_i, w = dim W.

* **w = d + 1** (one common denominator): the evaluation vector of an echelon
  basis W_1..W_w of W is proportional to a fixed vector along every orbit, so
  W_j/W_w are integrals (:func:`ratio_integrals`).
* **w = 2d** (d independent pencils N_a − h_a D_a with distinct denominators):
  W = K_1 ⊕ K_2, and K_3, K_4 are graphs of linear maps T, T': K_1 → K_2.  A pencil
  meets K_1 in u_a and K_2 in v_a with T u_a ∝ v_a and T' u_a ∝ v_a, so the u_a are
  the left eigenvectors of S = T'T^{-1}, and u_a/(T u_a) =
  (N_a − h_a(x_1)D_a)/(N_a − h_a(x_2)D_a) is an integral.  For an irreducible
  factor f of degree e > 1 of det(λ − S) the pencils are defined over the number
  field K = Q[y]/f only; with the eigenvector over K, P = Σ_k y^k P_k and
  Q = Σ_k y^k Q_k (first put in reduced echelon form over K), the product
  Π_σ (Z·σ(Q) − σ(P)) = det(Z·Q(C) − P(C)) (C the companion matrix of f) has rational coefficients c_0..c_e in x, and the
  elementary symmetric functions c_j/c_e of the e conjugate integrals are
  rational integrals of degree 2·e·deg (:func:`pencil_integrals`).

Polynomials are dicts {exponent tuple: Fraction}.

>>> canonical_pair({(0, 0): Fraction(2), (2, 0): Fraction(1)}, {(0, 0): Fraction(4), (0, 2): Fraction(6)})
({(0, 0): Fraction(2, 1), (2, 0): Fraction(1, 1)}, {(0, 2): Fraction(3, 1), (2, 0): Fraction(-1, 1)})
"""

from __future__ import annotations

import math
from fractions import Fraction

import flint

MAX_FIELD_DEGREE = 6
#: the symmetric functions of e conjugate pencils are not expanded when a polynomial of degree
#: e·D in N variables may have more terms than this (C(N + e·D, N); the Laplace expansion holds
#: many polynomials of that size: n = 8, D = 2, e = 4 has 735 471 terms: 3.5 min, 4.7 GB; n = 10 grew
#: past 17 GB and was stopped)
MAX_SYMMETRIC_TERMS = 200_000


def _q(x):
    return flint.fmpq(x.numerator, x.denominator)


def _f(x):
    return Fraction(int(x.p), int(x.q))


def _qmat(rows):
    return flint.fmpq_mat(len(rows), len(rows[0]), [_q(v) for r in rows for v in r])


def _rows(M):
    return [[_f(M[i, j]) for j in range(M.ncols())] for i in range(M.nrows())]


def as_dict(vec, exps):
    return {e: Fraction(c) for e, c in zip(exps, vec) if c}


def primitive(poly: dict) -> dict:
    """The integer polynomial with coprime coefficients proportional to ``poly``
    (first coefficient positive)."""
    if not poly:
        return {}
    den = math.lcm(*(c.denominator for c in poly.values()))
    ints = {e: int(c * den) for e, c in poly.items()}
    g = math.gcd(*ints.values())
    sign = -1 if ints[min(ints)] < 0 else 1
    return {e: Fraction(sign * v // g) for e, v in sorted(ints.items())}


def canonical_pair(P: dict, Q: dict):
    """The integral P/Q written with the echelon basis (R_1, R_2) of span(P, Q):
    R_1/R_2 is a Möbius function of P/Q, hence an integral too; both made
    integer-primitive."""
    exps = sorted(set(P) | set(Q))
    R, rank = _qmat([[P.get(e, 0) for e in exps], [Q.get(e, 0) for e in exps]]).rref()
    rows = _rows(R)
    if rank < 2:
        return primitive(P), primitive(Q)
    return primitive(as_dict(rows[0], exps)), primitive(as_dict(rows[1], exps))


def ratio_integrals(K, exps):
    """w = d + 1: the integrals W_j / W_w of the echelon basis of K_1 + K_2."""
    R, w = _qmat(K[0] + K[1]).rref()
    W = _rows(R)[:w]
    return [canonical_pair(as_dict(W[j], exps), as_dict(W[-1], exps)) for j in range(w - 1)]


def _graphs(K, notes):
    d = len(K[0])
    B12 = _qmat(K[0] + K[1])
    R, rank = B12.rref()
    if rank != 2 * d:
        notes.append("two orbit kernels intersect: pencils not separated")
        return None
    piv = [next(j for j in range(R.ncols()) if R[i, j] != 0) for i in range(rank)]
    sub = lambda M: flint.fmpq_mat(M.nrows(), rank, [M[i, j] for i in range(M.nrows()) for j in piv])  # noqa: E731
    inv = sub(B12).inv()
    out = []
    for Ki in K[2:4]:
        X = sub(_qmat(Ki)) * inv  # coordinates of K_i's basis in (K_1, K_2)
        if X * B12 != _qmat(Ki):
            notes.append("an orbit kernel leaves K_1 + K_2: pencils not separated")
            return None
        A, C = (flint.fmpq_mat(d, d, [X[i, j + off] for i in range(d) for j in range(d)]) for off in (0, d))
        if A.rank() < d:
            notes.append("an orbit kernel meets K_2: pencils not separated")
            return None
        out.append(A.inv() * C)
    return out


def pencil_integrals(K, exps, notes):
    """w = 2d: integrals from the pencils (module docstring); ``K`` four kernels over Q."""
    graphs = _graphs(K, notes)
    if graphs is None:
        return []
    T, T2 = graphs
    S = T2 * T.inv()
    B1, TB2 = _qmat(K[0]), T * _qmat(K[1])
    _, factors = S.charpoly().factor()
    out = []
    for f, mult in factors:
        e = f.degree()
        if mult > 1:
            notes.append(f"{mult * e} pencils share cross-ratios (repeated factor of degree {e}): not separated")
            continue
        if e > MAX_FIELD_DEGREE:
            notes.append(f"{e} pencils are conjugate over a number field of degree {e} > {MAX_FIELD_DEGREE}: "
                         f"not extracted")
            continue
        terms = symmetric_terms_bound(e, exps)
        if e > 1 and terms > MAX_SYMMETRIC_TERMS:
            notes.append(f"{e} pencils are conjugate over a number field of degree {e}: their symmetric "
                         f"functions (degree {e * max(map(sum, exps))} in {len(exps[0])} variables) may have up to "
                         f"{terms:,} terms, beyond the limit of {MAX_SYMMETRIC_TERMS:,} (MAX_SYMMETRIC_TERMS): "
                         f"not extracted")
            continue
        f = f / f.coeffs()[-1]
        alpha = _eigenvector(S, f)      # entries: fmpq_poly in y, reduced mod f
        P = _combine(alpha, B1, f)      # per monomial: fmpq_poly in y
        Q = _combine(alpha, TB2, f)
        if e == 1:
            out.append(canonical_pair(as_dict([_f(c.coeffs()[0]) if not c.is_zero() else 0 for c in P], exps),
                                      as_dict([_f(c.coeffs()[0]) if not c.is_zero() else 0 for c in Q], exps)))
        else:
            notes.append(f"{e} pencils are conjugate over a number field of degree {e}: the elementary "
                         f"symmetric functions of their integrals are given (degree {e} in the pencil polynomials)")
            out += _symmetric(*_echelon_pair(P, Q, f), f, exps)
    return out


def symmetric_terms_bound(e, exps) -> int:
    """An upper bound on the terms of each symmetric function of e conjugate pencils whose
    polynomials have the monomials ``exps``: they have degree ≤ e·D (D the largest degree
    in ``exps``) in N variables, so at most C(N + e·D, N) terms.

    >>> symmetric_terms_bound(4, [(0, 0), (1, 0), (0, 2)])  # C(2 + 8, 2)
    45
    """
    return math.comb(len(exps[0]) + e * max(map(sum, exps)), len(exps[0]))


def _mod(a, f):
    return a % f if a.degree() >= f.degree() else a


def _inv(a, f):
    g, s, _ = a.xgcd(f)
    return _mod(s / g, f)


def _eigenvector(S, f):
    """A left eigenvector α (α S = y α) of S over K = Q[y]/f, by elimination over K."""
    d = S.nrows()
    y = flint.fmpq_poly([0, 1])
    # rows of (S^T − y I): α^T is its kernel vector
    A = [[_mod(flint.fmpq_poly([S[j, i]]) - (y if i == j else 0), f) for j in range(d)] for i in range(d)]
    pivots, r = [], 0
    for c in range(d):
        p = next((i for i in range(r, d) if not A[i][c].is_zero()), None)
        if p is None:
            continue
        A[r], A[p] = A[p], A[r]
        inv = _inv(A[r][c], f)
        A[r] = [_mod(v * inv, f) for v in A[r]]
        for i in range(d):
            if i != r and not A[i][c].is_zero():
                k = A[i][c]
                A[i] = [_mod(v - k * w, f) for v, w in zip(A[i], A[r])]
        pivots.append(c)
        r += 1
    free = next(c for c in range(d) if c not in pivots)
    v = [flint.fmpq_poly([0])] * d
    v[free] = flint.fmpq_poly([1])
    for i, c in enumerate(pivots):
        v[c] = -A[i][free]
    return v


def _echelon_pair(P, Q, f):
    """The reduced echelon basis (R_1, R_2) over K of span_K(P, Q): canonical, so the
    conjugate integrals R_1/R_2 (Möbius functions of P/Q) have simple coefficients."""
    P, Q = list(P), list(Q)
    c = next(j for j, v in enumerate(P) if not v.is_zero())
    inv = _inv(P[c], f)
    P = [_mod(v * inv, f) for v in P]
    k = Q[c]
    Q = [_mod(q - k * v, f) for q, v in zip(Q, P)]
    c2 = next((j for j, v in enumerate(Q) if not v.is_zero()), None)
    if c2 is None:
        return P, Q
    inv = _inv(Q[c2], f)
    Q = [_mod(v * inv, f) for v in Q]
    k = P[c2]
    return [_mod(p - k * v, f) for p, v in zip(P, Q)], Q


def _combine(alpha, B, f):
    """α·B for α over K and B rational (d × m): one element of K per column."""
    d, m = B.nrows(), B.ncols()
    return [_mod(sum((alpha[i] * B[i, j] for i in range(d) if B[i, j] != 0), flint.fmpq_poly([0])), f)
            for j in range(m)]


def _det(A, zero):
    """Determinant by Laplace expansion along the first row with the minors of the
    lower rows cached (Σ_k C(e, k) minors instead of e! products)."""
    e = len(A)
    minors = {(): None}

    def minor(cols, row):  # det of rows row..e-1 and columns cols
        if row == e:
            return None
        key = cols
        if key in minors:
            return minors[key]
        total = zero
        for i, c in enumerate(cols):
            rest = cols[:i] + cols[i + 1:]
            sub = minor(rest, row + 1)
            term = A[row][c] if sub is None else A[row][c] * sub
            total = total + term if i % 2 == 0 else total - term
        minors[key] = total
        return total

    return minor(tuple(range(e)), 0)


def _symmetric(P, Q, f, exps):
    """The rational integrals c_j/c_e from det(Z·Q(C) − P(C)) (module docstring)."""
    e = f.degree()
    N = len(exps[0])
    ctx = flint.fmpq_mpoly_ctx.get(tuple(f"x{i}" for i in range(N)) + ("Z",), "degrevlex")
    gens = ctx.gens()
    Z = gens[-1]
    C = flint.fmpq_mat(e, e, [(1 if i == j + 1 else 0) if j < e - 1 else -f.coeffs()[i] for i in range(e)
                              for j in range(e)]).transpose()
    powers = [flint.fmpq_mat(e, e, [int(i == j) for i in range(e) for j in range(e)])]
    for _ in range(e - 1):
        powers.append(powers[-1] * C)
    mono = [ctx.from_dict({tuple(ex) + (0,): 1}) for ex in exps]

    def matrix(coeffs):  # Σ_i φ_i(x) c_i(C), as an e×e matrix of polynomials
        M = [[ctx.from_dict({}) for _ in range(e)] for _ in range(e)]
        for phi, c in zip(mono, coeffs):
            if c.is_zero():
                continue
            cm = sum((powers[k] * c.coeffs()[k] for k in range(len(c.coeffs()))),
                     flint.fmpq_mat(e, e, [0] * (e * e)))
            for r in range(e):
                for s in range(e):
                    if cm[r, s] != 0:
                        M[r][s] = M[r][s] + phi * cm[r, s]
        return M

    MP, MQ = matrix(P), matrix(Q)
    A = [[Z * MQ[r][s] - MP[r][s] for s in range(e)] for r in range(e)]
    det = _det(A, ctx.from_dict({}))
    coeffs = [{} for _ in range(e + 1)]
    for ex, c in det.to_dict().items():
        coeffs[int(ex[-1])][tuple(int(k) for k in ex[:-1])] = _f(c)
    return [(primitive(coeffs[j]), primitive(coeffs[e])) for j in range(e) if coeffs[j]]


# --- pencils on the level sets of a linear integral, interpolated in its value ---------


def rational_in(values: dict):
    """(a, b) fmpq_poly with a(c)/b(c) = values[c] at every c given, of the lowest degree n = deg a
    = deg b with two values beyond the 2n + 1 that determine it, or None.

    >>> a, b = rational_in({Fraction(c): Fraction(c, c + 1) for c in range(1, 8)})
    >>> a * flint.fmpq_poly([1, 1]) == b * flint.fmpq_poly([0, 1])
    True
    """
    cs = sorted(values)
    for n in range(0, (len(cs) - 4) // 2 + 1):
        rows = [[_q(c) ** k for k in range(n + 1)] + [-_q(values[c]) * _q(c) ** k for k in range(n + 1)]
                for c in cs]
        R, rank = flint.fmpq_mat(len(rows), 2 * n + 2, [v for r in rows for v in r]).rref()
        nul = 2 * n + 2 - rank
        if nul == 1:
            piv = [next(j for j in range(2 * n + 2) if R[i, j] != 0) for i in range(rank)]
            free = next(j for j in range(2 * n + 2) if j not in piv)
            v = [flint.fmpq(0)] * (2 * n + 2)
            v[free] = flint.fmpq(1)
            for i, c in enumerate(piv):
                v[c] = -R[i, free]
            a, b = flint.fmpq_poly(v[:n + 1]), flint.fmpq_poly(v[n + 1:])
            if not b.is_zero():
                return a, b
        if nul:
            return None
    return None


def echelon_pencil(P: dict, Q: dict, exps):
    """(pivot columns, (R_1, R_2) as coefficient lists over ``exps``): the reduced echelon basis of
    span(P, Q), whose coefficients are rational functions of whatever P/Q depends on rationally."""
    R, rank = _qmat([[P.get(e, 0) for e in exps], [Q.get(e, 0) for e in exps]]).rref()
    if rank < 2:
        return None
    rows = _rows(R)[:2]
    return tuple(next(j for j, v in enumerate(r) if v) for r in rows), rows


def interpolated_pencils(by_level: dict, exps, linear: dict, N: int) -> list:
    """Integrals (N, D) from pencils found on the level sets L = c of a linear integral L:
    ``by_level`` maps c to {key: (R_1, R_2)} (:func:`echelon_pencil` rows, the key naming the same
    pencil at every level); each coefficient is reconstructed as a rational function of c
    (:func:`rational_in`), the denominators cleared and c replaced by L(x)."""
    seen = [k for v in by_level.values() for k in v]
    keys = {k for k in seen if seen.count(k) >= 6}
    ctx = flint.fmpq_mpoly_ctx.get(tuple(f"x{i}" for i in range(N)), "degrevlex")
    L = ctx.from_dict({e: _q(c) for e, c in linear.items()})
    out = []
    for key in sorted(keys):
        fits = []
        for half in (0, 1):
            for j in range(len(exps)):
                vals = {c: v[key][half][j] for c, v in by_level.items() if key in v}
                if not any(vals.values()):
                    fits.append(None)
                    continue
                ab = rational_in(vals)
                if ab is None:
                    break
                fits.append(ab)
            else:
                continue
            break
        else:
            den = flint.fmpq_poly([1])
            for ab in fits:
                if ab is not None:
                    den = den * ab[1] / den.gcd(ab[1])
            polys = []
            for half in (0, 1):
                total = ctx.from_dict({})
                for j, ab in enumerate(fits[half * len(exps):(half + 1) * len(exps)]):
                    if ab is None:
                        continue
                    coeff = ab[0] * den / ab[1]
                    value = ctx.from_dict({})
                    for k, c in enumerate(coeff.coeffs()):
                        value = value + L ** k * c
                    total = total + value * ctx.from_dict({exps[j]: 1})
                polys.append(total)
            num, den_poly = polys
            if num.is_zero() or den_poly.is_zero():
                continue
            g = num.gcd(den_poly)
            num, den_poly = num / g, den_poly / g
            out.append(tuple({tuple(int(t) for t in e): _f(c) for e, c in p.to_dict().items()}
                             for p in (num, den_poly)))
    return out
