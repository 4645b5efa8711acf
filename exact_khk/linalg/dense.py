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

from exact_khk.errors import SingularMatrix

#: generic floating dense solve (``mp:P``): κ from the exact inverse up to this N, where
#: N column solves cost no more than the estimator's five triangular solves (an
#: operation count; at N = 4 the estimate would be ~50 % of the step)
EXACT_INVERSE_MAX_N = 5
#: ``cyclo:N`` linear algebra in FLINT on the coefficients (``CycloArith.native_solve``,
#: ``native_matmul``, ``linear_forms``) for φ(N) up to this degree, and a solve of size m as
#: one rational system of size m·φ(N) up to the next bound (1.2–9× faster than elimination
#: over Q(ζ_N) for m·φ ≤ 32, 13× at 160, 45× at 240, 84× at 400, random systems).  Memory
#: bounds, not tuned ones: that system has (m·φ)² entries and the companion powers φ³
#: (``orbit --arith cyclo:10000``: m·φ = 24 000, tens of GB); beyond them elimination over
#: Q(ζ_N), and a rational matrix is solved over Q at any N.  Whole commands without / with
#: FLINT: ``certify --n 3 --arith cyclo:3`` 2.75×, ``orbit --n 4 --seed 1 --arith cyclo:8`` 1.64×
CYCLO_REGULAR_MAX_DEGREE = 128
CYCLO_REGULAR_MAX_SIZE = 1024


def coefficients_native(ar, m: int = 0) -> bool:
    """Whether linear algebra of size m over ``ar`` runs in FLINT on its rational
    coefficients (the ``cyclo:N`` row of the table of rules,
    :mod:`exact_khk.systems.lie_poisson.paths`): always for arithmetics without a
    ``coefficient_degree``; else φ ≤ :data:`CYCLO_REGULAR_MAX_DEGREE` and
    m·φ ≤ :data:`CYCLO_REGULAR_MAX_SIZE`."""
    phi = getattr(ar, "coefficient_degree", None)
    return phi is None or (phi <= CYCLO_REGULAR_MAX_DEGREE and m * phi <= CYCLO_REGULAR_MAX_SIZE)


def identity(ar, n):
    return [[ar.one if i == j else ar.zero for j in range(n)] for i in range(n)]


def matmul(A, B, ar=None):
    """Product of two matrices given as lists of rows (any ring elements); by the
    arithmetic ``ar``'s ``native_matmul`` when it has one."""
    if ar is not None and ar.native_matmul is not None and A and B and B[0] and coefficients_native(ar):
        return ar.native_matmul(A, B)
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
        rowk = LU[k]
        piv, tail = rowk[k], rowk[k + 1:]
        for i in range(k + 1, n):
            rowi = LU[i]
            if ar.is_zero(rowi[k]) is True:
                continue
            m = rowi[k] = rowi[k] / piv
            rowi[k + 1:] = [a - m * b for a, b in zip(rowi[k + 1:], tail)]
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
    cols = [[B[perm[i]][c] for i in range(n)] for c in range(len(B[0]))]
    for y in cols:  # L y = P b, then U x = y, column by column
        for i in range(1, n):
            t, row = y[i], LU[i]
            for k in range(i):
                t = t - row[k] * y[k]
            y[i] = t
        for i in reversed(range(n)):
            t, row = y[i], LU[i]
            for k in range(i + 1, n):
                t = t - row[k] * y[k]
            y[i] = t / row[i]
    return [list(r) for r in zip(*cols)]


def lu_solve_transposed(LU, perm, c):
    """Solve Mᵀ z = c (``c`` a list) with a factorisation PM = LU from :func:`lu_factor`:
    Uᵀ w = c, Lᵀ v = w, z = Pᵀ v."""
    n = len(LU)
    w = list(c)
    for i in range(n):
        t = w[i]
        for k in range(i):
            t = t - LU[k][i] * w[k]
        w[i] = t / LU[i][i]
    for i in reversed(range(n)):
        t = w[i]
        for k in range(i + 1, n):
            t = t - LU[k][i] * w[k]
        w[i] = t
    z = [None] * n
    for i in range(n):
        z[perm[i]] = w[i]
    return z


def inverse_norm1_estimate(ar, LU, perm) -> float:
    """A lower bound on ‖M⁻¹‖₁ from a factorisation of :func:`lu_factor`, by
    Hager's method with Higham's refinements (LAPACK's ``xLACN2``, the estimator
    behind ``xGECON``): at most 5 solves with M and Mᵀ, O(N²) each, instead of
    the O(N³) inverse; in practice within a factor 3 of the true norm, often exact.

    >>> from exact_khk.arith import get_arith
    >>> ar = get_arith("mp:53")
    >>> LU, perm = lu_factor(ar, [[ar(2), ar(1)], [ar(1), ar(3)]])
    >>> inverse_norm1_estimate(ar, LU, perm)  # M⁻¹ = [[3, −1], [−1, 2]] / 5
    0.8
    """
    n = len(LU)
    col = lambda v: [row[0] for row in lu_solve(LU, perm, [[t] for t in v])]  # noqa: E731
    norm = lambda v: sum(ar.magnitude(t) for t in v)  # noqa: E731
    one, minus_one, zero = ar.one, -ar.one, ar.zero
    x = [one / ar.convert(n)] * n
    est, j = 0.0, None
    for it in range(5):
        y = col(x)
        new = norm(y)
        if it and new <= est:
            break
        est = new
        z = lu_solve_transposed(LU, perm, [one if not t < zero else minus_one for t in y])
        mags = [ar.magnitude(t) for t in z]
        k = max(range(n), key=mags.__getitem__)
        if it and (k == j or mags[k] <= mags[j]):  # x = e_j after the first round: zᵀx = z_j
            break
        j, x = k, [one if i == k else zero for i in range(n)]
    # Higham's alternating vector guards against the cases where the above stalls
    alt = [ar.convert((-1) ** i * (1 + i / max(n - 1, 1))) for i in range(n)]
    return max(est, 2 * norm(col(alt)) / (3 * n))


def solve(ar, M, B, condition=None):
    """Solve ``M X = B``; returns ``(X, condition)``.

    ``condition`` is ``None`` for exact contexts, else the 1-norm condition
    estimate ``|M|_1 |M^-1|_1``: what the ``condition`` argument (a callable
    ``M ↦ κ or None``, e.g. :func:`~exact_khk.linalg.floating.binary64_condition`)
    returns, if anything; else from the same factorisation, |M⁻¹|₁ of the
    inverse for N ≤ :data:`EXACT_INVERSE_MAX_N`, else
    estimated (:func:`inverse_norm1_estimate`, O(N²), LAPACK's method).
    Raises :class:`SingularMatrix` if ``M`` is (exactly) singular.
    """
    if ar.native_solve is not None and coefficients_native(ar, len(M)):
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
    kappa = condition(M) if condition is not None else None
    if kappa is not None:
        return X, kappa
    if len(M) <= EXACT_INVERSE_MAX_N:
        return X, norm1(ar, M) * norm1(ar, lu_solve(LU, perm, identity(ar, len(M))))
    return X, norm1(ar, M) * inverse_norm1_estimate(ar, LU, perm)
