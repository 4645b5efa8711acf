"""Dense linear algebra written once over an arithmetic context.

``solve(ar, M, B)`` solves ``M X = B`` (``M`` square, ``B`` a list of rows).
Exact contexts pivot on the first nonzero entry and report singularity
exactly; inexact ones use partial pivoting and return a 1-norm condition
estimate of ``M`` so that callers can warn about or refuse ill-conditioned
steps.  A context with a native solver (python-flint's ``fmpq_mat.solve``)
uses it instead of the generic elimination.

>>> from fractions import Fraction as F
>>> from exact_khk.arith import get_arith
>>> X, cond = solve(get_arith("fraction"), [[F(2), F(1)], [F(1), F(3)]], [[F(1)], [F(2)]])
>>> X, cond
([[Fraction(1, 5)], [Fraction(3, 5)]], None)
"""

from __future__ import annotations


class SingularMatrix(ArithmeticError):
    """``M`` is singular (exactly, or a floating pivot is exactly zero)."""


def identity(ar, n):
    return [[ar.one if i == j else ar.zero for j in range(n)] for i in range(n)]


def matmul(A, B):
    """Product of two matrices given as lists of rows (any ring elements)."""
    cols = list(zip(*B))
    return [[sum((a * b for a, b in zip(row, col)), start=row[0] * 0) for col in cols] for row in A]


def matvec(A, x):
    return [sum((a * b for a, b in zip(row, x)), start=row[0] * 0) for row in A]


def transpose(A):
    return [list(r) for r in zip(*A)]


def norm1(ar, A) -> float:
    """Max column sum of magnitudes (as a float)."""
    return max(sum(ar.magnitude(A[i][j]) for i in range(len(A))) for j in range(len(A[0])))


def lu_factor(ar, M):
    """LU factorisation with row pivoting: returns (LU, perm), L unit lower.

    Raises :class:`SingularMatrix` when no usable pivot exists.
    """
    n = len(M)
    LU = [list(row) for row in M]
    perm = list(range(n))
    for k in range(n):
        if ar.exact:
            p = next((i for i in range(k, n) if not ar.is_zero(LU[i][k])), None)
        else:
            p = max(range(k, n), key=lambda i: ar.magnitude(LU[i][k]))
            if ar.is_zero(LU[p][k]) is not False:
                p = None
        if p is None:
            raise SingularMatrix(f"no nonzero pivot in column {k}")
        if p != k:
            LU[k], LU[p] = LU[p], LU[k]
            perm[k], perm[p] = perm[p], perm[k]
        piv = LU[k][k]
        for i in range(k + 1, n):
            if ar.is_zero(LU[i][k]) is True:
                continue
            m = LU[i][k] / piv
            LU[i][k] = m
            rowk, rowi = LU[k], LU[i]
            for j in range(k + 1, n):
                rowi[j] = rowi[j] - m * rowk[j]
    return LU, perm


def determinant(ar, M):
    """det M by the elimination of :func:`lu_factor` (0 when it finds no pivot).

    >>> from fractions import Fraction as F
    >>> from exact_khk.arith import get_arith
    >>> determinant(get_arith("fraction"), [[F(2), F(1)], [F(1), F(3)]])
    Fraction(5, 1)
    """
    try:
        LU, perm = lu_factor(ar, M)
    except SingularMatrix:
        if ar.exact:
            return ar.zero
        raise
    det, seen = ar.one, [False] * len(perm)
    for i in range(len(perm)):  # the sign of the permutation, by its cycles
        j, length = i, 0
        while not seen[j]:
            seen[j], j, length = True, perm[j], length + 1
        if length and length % 2 == 0:
            det = -det
    for i in range(len(M)):
        det = det * LU[i][i]
    return det


def lu_solve(LU, perm, B):
    """Solve with a factorisation from :func:`lu_factor`; ``B`` is a list of rows."""
    n = len(LU)
    X = [list(B[perm[i]]) for i in range(n)]
    m = len(X[0])
    for i in range(n):
        for k in range(i):
            l = LU[i][k]
            for j in range(m):
                X[i][j] = X[i][j] - l * X[k][j]
    for i in reversed(range(n)):
        for k in range(i + 1, n):
            u = LU[i][k]
            for j in range(m):
                X[i][j] = X[i][j] - u * X[k][j]
        for j in range(m):
            X[i][j] = X[i][j] / LU[i][i]
    return X


def bareiss_solve(M, B):
    """Fraction-free (Bareiss) elimination over the integers (int, gmpy2 mpz, ...).

    Returns ``(Y, d)`` with ``M Y = d B`` and ``d = ±det M`` (nonzero): every
    intermediate entry is a minor of ``[M | B]`` and each division is exact, so
    integers never grow beyond Hadamard's bound.  Back substitution is
    fraction-free too: ``d M^{-1} B`` is integral.  Raises :class:`SingularMatrix`.

    >>> bareiss_solve([[2, 1], [1, 3]], [[1], [2]])
    ([[1], [3]], 5)
    """
    n, m = len(M), len(B[0])
    R = [list(M[i]) + list(B[i]) for i in range(n)]
    prev = 1
    for k in range(n):
        p = next((i for i in range(k, n) if R[i][k] != 0), None)
        if p is None:
            raise SingularMatrix(f"no nonzero pivot in column {k}")
        R[k], R[p] = R[p], R[k]
        rk, piv = R[k], R[k][k]
        for i in range(k + 1, n):
            ri = R[i]
            rik = ri[k]
            for j in range(k + 1, n + m):
                ri[j] = (piv * ri[j] - rik * rk[j]) // prev
        prev = piv
    d = prev
    Y = [[0] * m for _ in range(n)]
    for i in reversed(range(n)):
        ri = R[i]
        for c in range(m):
            acc = d * ri[n + c]
            for j in range(i + 1, n):
                acc -= ri[j] * Y[j][c]
            Y[i][c] = acc // ri[i]
    return Y, d


def solve(ar, M, B):
    """Solve ``M X = B``; returns ``(X, condition)``.

    ``condition`` is ``None`` for exact contexts, else the 1-norm condition
    estimate ``|M|_1 |M^-1|_1`` (computed from the same factorisation).
    Raises :class:`SingularMatrix` if ``M`` is (exactly) singular.
    """
    if ar.native_solve is not None:
        try:
            return ar.native_solve(M, B), None
        except ZeroDivisionError as exc:
            raise SingularMatrix(str(exc)) from None
    if ar.exact and getattr(ar, "integers", None) is not None:
        # clear denominators row by row, then one fraction-free elimination
        Mi, Bi = [], []
        for row, rhs in zip(M, B):
            ints, _ = ar.integers.split(list(row) + list(rhs))
            Mi.append(ints[:len(row)])
            Bi.append(ints[len(row):])
        return ar.integers.solve(Mi, Bi), None
    LU, perm = lu_factor(ar, M)
    X = lu_solve(LU, perm, B)
    if ar.exact:
        return X, None
    inv = lu_solve(LU, perm, identity(ar, len(M)))
    return X, norm1(ar, M) * norm1(ar, inv)
