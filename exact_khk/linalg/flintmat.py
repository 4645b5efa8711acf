"""Exact dense matrices in python-flint (``fmpq_mat``) for the ``flint`` arithmetic.

The generic code (:mod:`exact_khk.linalg.dense`) works on lists of rows over any
arithmetic context, one Python operation per scalar; when the arithmetic's
elements *are* python-flint ``fmpq`` (the ``flint`` arithmetic), products and
solves of whole matrices can run in C instead.  The results are the same
rational numbers (FLINT is exact); callers keep their list-of-rows interface
by converting at the boundary with :func:`mat` and :func:`rows`.

>>> from exact_khk.arith import get_arith
>>> ar = get_arith("flint")
>>> uses_flint(ar), uses_flint(get_arith("fraction"))
(True, False)
>>> A = mat([[ar(1), ar("1/2")], [ar(0), ar(3)]])
>>> rows(A * A)
[[1, 2], [0, 9]]
>>> rows(signed_rows(A, [1, 0], [1, -1]))
[[0, 3], [-1, -1/2]]
"""

from __future__ import annotations

import flint

fmpq_mat, fmpz_mat = flint.fmpq_mat, flint.fmpz_mat


def uses_flint(ar) -> bool:
    """Whether the elements of the arithmetic ``ar`` are python-flint ``fmpq``
    (exact rationals), so that :class:`flint.fmpq_mat` can hold them as they are."""
    return bool(getattr(ar, "rational", False)) and type(ar.zero) is flint.fmpq


def fmpq(t):
    """``t`` (fmpq, int, Fraction, or anything with numerator/denominator) as an ``fmpq``."""
    if type(t) is flint.fmpq:
        return t
    if isinstance(t, int):
        return flint.fmpq(t)
    return flint.fmpq(int(t.numerator), int(t.denominator))


def mat(rows_, ncols=None):
    """An ``fmpq_mat`` from a list of rows (elements as :func:`fmpq` reads them)."""
    m = len(rows_)
    c = len(rows_[0]) if ncols is None else ncols
    return fmpq_mat(m, c, [fmpq(t) for r in rows_ for t in r])


def column(v):
    """An m×1 ``fmpq_mat`` from a sequence."""
    return fmpq_mat(len(v), 1, list(v))


def rows(M):
    """The rows of an ``fmpq_mat`` as lists of ``fmpq``."""
    c, flat = M.ncols(), M.entries()
    return [flat[i * c:(i + 1) * c] for i in range(M.nrows())]


def signed_rows(M, source, sign):
    """The matrix whose row i is ``sign[i]`` · row ``source[i]`` of ``M`` (a signed
    permutation applied on the left, without a product; ``fmpq_mat`` or ``fmpz_mat``)."""
    c, flat = M.ncols(), M.entries()
    out = []
    for s, g in zip(source, sign):
        r = flat[s * c:(s + 1) * c]
        out.extend(r if g == 1 else [-t for t in r])
    return type(M)(len(source), c, out)


def signed_columns(M, source, sign):
    """The matrix whose column j is ``sign[j]`` · column ``source[j]`` of ``M``."""
    c, flat = M.ncols(), M.entries()
    out = []
    for i in range(M.nrows()):
        r = flat[i * c:(i + 1) * c]
        out.extend(r[s] if g == 1 else -r[s] for s, g in zip(source, sign))
    return type(M)(M.nrows(), len(source), out)


def is_zero(M) -> bool:
    """Whether every entry of ``M`` is 0."""
    return not any(M.entries())


#: the prime of :func:`rank` (a 62-bit prime: python-flint's ``nmod_mat`` takes word-size moduli)
RANK_PRIME = 4611686018427387847


def rank(rows_):
    """The exact rank over Q of a list of rows of rationals, certified cheaply:

    * r = the rank modulo :data:`RANK_PRIME` of the rows with denominators cleared, and r
      rows independent modulo p — hence over Q (a nonzero r-minor mod p is nonzero);
    * every other row is verified, exactly over Q, to be a combination of those r rows
      (coefficients from an r×r solve, then the whole row compared), so the rank is
      not above r.

    If a row is not in their span (p divides a minor: not seen in practice), the rank
    comes from ``fmpq_mat.rank()``.  The answer is always the exact rank.

    >>> rank([[1, 2, 3], [2, 4, 6], [0, 1, 1]]), rank([[1, 2], [3, 4]]), rank([[0, 0]])
    (2, 2, 0)
    """
    M = mat(rows_)
    m, N = M.nrows(), M.ncols()
    Z, _ = M.numer_denom()
    # independent rows mod p: the pivot columns of the transpose's echelon form
    R, r = flint.nmod_mat(N, m, Z.transpose().entries(), RANK_PRIME).rref()
    if r == m:
        return r
    E = R.entries()
    pivots, col = [], 0
    for i in range(r):
        while E[i * m + col] == 0:
            col += 1
        pivots.append(col)
        col += 1
    if r == 0:
        return 0 if Z.is_zero() else M.rank()
    rows_q = [M.entries()[i * N:(i + 1) * N] for i in range(m)]
    P = fmpq_mat(r, N, [t for i in pivots for t in rows_q[i]])
    # r columns where the pivot rows are independent (mod p, hence over Q)
    Rc, rc = flint.nmod_mat(r, N, P.numer_denom()[0].entries(), RANK_PRIME).rref()  # rc = r
    Ec, cols, col = Rc.entries(), [], 0
    for i in range(rc):
        while Ec[i * N + col] == 0:
            col += 1
        cols.append(col)
        col += 1
    S = fmpq_mat(r, r, [P.entries()[i * N + c] for c in cols for i in range(r)])  # Sᵀ: S[c][i] = P[i][c]
    others = [i for i in range(m) if i not in set(pivots)]
    rhs = fmpq_mat(r, len(others), [rows_q[i][c] for c in cols for i in others])
    coeffs = S.solve(rhs)  # column k: the coefficients of row others[k]
    if coeffs.transpose() * P != fmpq_mat(len(others), N, [t for i in others for t in rows_q[i]]):
        return M.rank()
    return r
