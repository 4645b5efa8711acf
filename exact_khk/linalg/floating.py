"""The system I − εf'(x) as a numpy array, and the binary64 dense solve by LAPACK.

:func:`system_matrix` builds I − εf'(x) for a floating arithmetic in one of two
ways, both plain p-bit arithmetic (every entry a sum of rounded products, in
some order):

* a field whose Jacobian blocks are circulant (``field.circulant_structure()``
  is not None) from the Hankel first rows m_kl of its Hessian and the structure's
  ``jacobian_first_rows`` F: with y = Mx the blocks of f'(x) are the circulants
  with first rows F applied to the X(m_kl)u, X(m_kl)v, e.g. (docs/conventions.md)

      f11: 2 X(m21)u + X(m22)v   f12: X(m22)u
      f21: −2 X(m11)u − X(m12)v  f22: −X(m12)u

  (X(w) the cyclic Hankel matrix of w; X(m)u is one dot product per entry),
  in O(n²) for any element type numpy holds — binary64, or mpmath numbers in
  an object array, so that ``mp:P`` builds its system the same way;
* any other :class:`~exact_khk.systems.quadratic.QuadraticField` (binary64
  only) from its Jacobian terms, ∂f_i/∂x_j = Σ_k c_ijk x_k + L_ij, summed by
  ``numpy.bincount``.

:func:`float_solve` is the ``float`` arithmetic's dense solve:
``numpy.linalg.solve`` (LAPACK ``gesv``: partially pivoted LU in binary64,
i.e. p = 53 dense arithmetic) and the 1-norm condition number
κ = ‖M‖₁‖M⁻¹‖₁ with M⁻¹ = ``numpy.linalg.inv(M)`` — exactly
``numpy.linalg.cond(M, 1)``, not an estimate.  Both are called as the gufuncs
behind ``numpy.linalg.solve`` and ``inv`` (as ``numpy.linalg.cond`` itself does),
which skips their Python wrappers, a tenth of a step for N ≤ 32, and gives the
same bits.  numpy exposes no LU factors for LAPACK's O(N²) estimator ``gecon``,
so κ costs a second factorisation.  One ``gesv`` of M [X | Y] = [B | I] would
save it (0.8–0.9× the two calls for N = 32..512, but 1.3× for N ≤ 8; OpenBLAS
0.3.31) at the price of X's bits: LAPACK solves one right-hand side with a
different kernel (OpenBLAS: ``trsv``, not ``trsm``), so X would no longer be
``numpy.linalg.solve(M, B)``.  An exactly zero pivot raises
:class:`~exact_khk.linalg.dense.SingularMatrix`.

>>> from exact_khk import LiePoissonSystem, get_arith
>>> f = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1").field("f")
>>> M = system_matrix(f, get_arith("float"), [1.0, 0, 0, 0, 1, 0], 0.1)
>>> ar = get_arith("fraction")
>>> J = f.jacobian(ar, [ar(t) for t in (1, 0, 0, 0, 1, 0)])
>>> all(abs(M[i, j] - float((i == j) - ar("1/10") * J[i][j])) < 1e-15 for i in range(6) for j in range(6))
True
>>> X, cond = float_solve(numpy.array([[2.0, 1], [1, 3]]), numpy.array([[1.0], [2]]))
>>> [round(t, 12) for t in X[:, 0].tolist()], cond
([0.2, 0.6], 3.2)
"""

from __future__ import annotations

import functools
import operator
import threading

import numpy
from numpy.lib.stride_tricks import as_strided

from exact_khk.linalg.dense import SingularMatrix

#: ``mp:P`` dense steps: κ from binary64 (M rounded, LAPACK's inverse) when N·κ ≤ this, where
#: rounding and the inverse move κ by less than 2^-20 (an accuracy rule, not a tuned one;
#: :func:`binary64_condition`); 0.6–0.7× mpmath.lu_solve's time
#: at n = 2, 3 against 0.94–0.99× with κ in p bits; whole commands without / with it:
#: ``orbit --n 16 --seed 1 --arith mp:100 --steps 100`` 1.45×, ``--n 8 ... --steps 200`` 1.42×,
#: ``scale --n 3 --seed 39 --steps 200 --digits 20`` 1.42×
BINARY64_CONDITION_MAX = 2.0 ** 32


def _data(field, ar):
    """The field's coefficients as numpy data for ``ar`` (cached on the field):
    ``('circulant', X, F)`` with X the (4, n, n) cyclic Hankel matrices X(m11),
    X(m12), X(m21), X(m22) (views of one (4, 2n) array) and F the structure's ``jacobian_first_rows``, or ``('terms', rows, ks, coefs, L)`` (binary64 only)."""
    key = ("numpy system", ar.name)
    hit = field._cache.get(key)
    if hit is not None:
        return hit
    st = field.circulant_structure()
    dtype = float if ar.lapack else object
    if st is not None:
        rows = [ar.convert(q) for row in st.m for w in row for q in w]
        m = numpy.array(rows, dtype=dtype).reshape(4, st.n)
        # the four cyclic Hankel matrices X(m_kl) as views (row k: m_kl[k], …, m_kl[k+n−1])
        hit = ("circulant", _viewer(dtype, 0, (4, st.n, st.n), (2 * st.n, 1, 1))(numpy.concatenate([m, m], axis=1)),
               numpy.array([[ar.convert(t) for t in row] for row in st.jacobian_first_rows], dtype=dtype))
    elif ar.lapack:
        N = field.dim
        _, jterms, lin, _ = field._converted(ar)  # ∂f_i/∂x_j = Σ_k c x_k, in the arithmetic
        jac = [(i * N + j, k, c) for i in range(N) for j in range(N) for k, c in jterms[i][j]]
        L = numpy.zeros(N * N)
        for i, row in enumerate(lin):
            for j, c in row:
                L[i * N + j] += c
        hit = ("terms", numpy.array([t[0] for t in jac], dtype=numpy.intp),
               numpy.array([t[1] for t in jac], dtype=numpy.intp), numpy.array([t[2] for t in jac], dtype=float), L)
    else:
        hit = (None,)
    field._cache[key] = hit
    return hit


def _viewer(dtype, offset, shape, strides):
    """``a ↦`` the view of a contiguous array ``a`` of ``dtype`` from element ``offset``
    with ``strides`` in elements (no copy; numpy's constructor for binary64,
    ``as_strided`` for objects)."""
    size = numpy.dtype(dtype).itemsize
    strides = tuple(size * t for t in strides)
    if dtype is object:
        return lambda a: as_strided(a.reshape(-1)[offset:], shape, strides, writeable=False)
    return lambda a: numpy.ndarray(shape, dtype, a, size * offset, strides)


def has_system_matrix(field, ar) -> bool:
    """Whether :func:`system_matrix` applies (binary64: every field; other
    floating arithmetics: fields with circulant blocks)."""
    return _data(field, ar)[0] is not None


def system_matrix(field, ar, x, eps):
    """I − ε f'(x) as an N×N numpy array (binary64 for ``float``, else an object
    array of ``ar``'s elements); ``x`` a sequence of ``ar``'s elements."""
    data = _data(field, ar)
    x = numpy.asarray(x, dtype=float if ar.lapack else object)
    with numpy.errstate(all="ignore"):  # overflow gives inf, found by the caller's finiteness check
        return _matrix_builder(data, field.dim, ar, eps)(x)


def _matrix_builder(data, N, ar, eps):
    """``(x, out=None) ↦`` I − ε f'(x) for a numpy vector x of ``ar``'s elements, with what
    depends on ε only computed once; written into ``out`` (an N×N binary64 array) if given."""
    one = ar.one
    if data[0] == "circulant":
        hankel, n, F = data[1], N // 2, data[2]
        # block (a, c), entry (i, k) = w_ac[(k − i) mod n] = [w | w][2a + c, n − i + k]
        blocks = _viewer(float if ar.lapack else object, n, (2, n, 2, n), (4 * n, -1, 2 * n, 1))
        # X(m) is symmetric: row 2b + c of p is X(m_b) u (c = 0) or X(m_b) v (c = 1); w = −ε × the
        # first rows of f11, f12, f21, f22 = (−ε F) p, F = the structure's jacobian_first_rows
        if ar.lapack:
            eF = F * -eps
            first_rows = lambda x: eF @ (x.reshape(2, n) @ hankel).reshape(8, n)  # noqa: E731
        else:  # objects: only the products that F's zeros do not cancel (p: 6 of 8 rows, F: 6 of 32
            # entries), summed in the same order: the same values
            terms = [[(k, F[r, k] * -eps) for k in range(8) if F[r, k] != 0] for r in range(4)]

            def first_rows(x):
                p = {k: x[n * (k % 2):][:n] @ hankel[k // 2] for k in (0, 2, 3, 4, 6, 7)}
                return numpy.array([functools.reduce(operator.add, [p[k] * c for k, c in t]) for t in terms])

        def build(x, out=None):
            w = first_rows(x)
            w[0, 0] += one  # the diagonals of the circulants f11, f22: w[., 0]
            w[3, 0] += one
            view = blocks(numpy.concatenate([w, w], axis=1))
            if out is None:
                return view.reshape(N, N)  # one copy
            numpy.copyto(out.reshape(2, n, 2, n), view)
            return out
        return build
    _, rows, ks, coefs, L = data

    def build(x, out=None):
        # float64 also when f has no quadratic term (bincount of no weights is int64)
        M = numpy.bincount(rows, weights=coefs * x[ks], minlength=N * N).astype(float, copy=False)
        M += L
        M *= -eps
        M = M.reshape(N, N)
        M.flat[::N + 1] += one
        if out is None:
            return M
        numpy.copyto(out, M)
        return out
    return build


def _values_data(field, ar):
    """f's terms as numpy data for :func:`float_step` (cached; ``()`` for homogeneous f)."""
    data = field._cache.get("numpy values")
    if data is None:
        data = ()
        if not field.homogeneous:
            fterms, _, lin, const = field._converted(ar)
            fl = [(i, j, k, c) for i, terms in enumerate(fterms) for j, k, c in terms]
            L = numpy.zeros((field.dim, field.dim))
            for i, row in enumerate(lin):
                for j, c in row:
                    L[i, j] += c
            data = (*(numpy.array([t[s] for t in fl], dtype=numpy.intp) for s in range(3)),
                    numpy.array([t[3] for t in fl], dtype=float), L, numpy.array(const, dtype=float))
        field._cache["numpy values"] = data
    return data


def float_step(field, ar, x, eps):
    """``(z, κ)``: the dense Kahan step z = Φ_f(x, ε) in binary64 (a list of Python
    floats) and κ as in :func:`float_solve`; ``ar`` the ``float`` arithmetic.

    Homogeneous f: (I − εf'(x)) z = x; otherwise z = x + 2ε (I − εf'(x))⁻¹ f(x)
    (the same formulas as the generic dense step).  Quiet: an exactly zero pivot
    gives NaN in z and κ, an overflow inf or NaN, and the caller checks z and κ
    (for ``float`` both mean a singular step; one error state for the whole step
    instead of :func:`float_solve`'s second one is a tenth of a step at N ≤ 8).
    """
    return float_stepper(field, ar, eps)(x)


def float_stepper(field, ar, eps):
    """``x ↦`` :func:`float_step` ``(field, ar, x, eps)``, with what depends on ε only
    computed once (a :class:`~exact_khk.kahan.map.KahanMap` keeps one)."""
    N = field.dim
    build = _matrix_builder(_data(field, ar), N, ar, eps)
    data, two_eps = _values_data(field, ar), eps + eps
    # M and M⁻¹ of a step are written into one array of each thread, overwritten by its next
    # step: both norms of κ are then three ufunc calls in place (a tenth of a step at N ≤ 8,
    # and no N×N temporaries), and LAPACK does not run on freshly allocated memory (up to
    # 1.4× slower for 0.5–2 MB, N = 256..512: glibc maps new pages for it)
    local = threading.local()

    def step(x):
        xv = numpy.array(x, dtype=float)
        both = getattr(local, "both", None)
        if both is None:
            both = local.both = numpy.empty((2, N, N))
        with numpy.errstate(all="ignore"):  # a zero pivot: NaN (see float_step)
            M = build(xv, both[0])
            if data:
                i, j, k, c, lin, const = data
                fx = numpy.bincount(i, weights=c * xv[j] * xv[k], minlength=N) + lin @ xv + const
            try:
                X, _ = _gufuncs(M, (fx if data else xv)[:, None], both[1])
            except numpy.linalg.LinAlgError:  # pragma: no cover  (the public functions: a zero pivot)
                return None, float("inf")
            z = xv + two_eps * X[:, 0] if data else X[:, 0]
            # ‖M‖₁, ‖M⁻¹‖₁ (inf·0 is nan without a warning); both are scratch by now
            norms = _max(_add(numpy.abs(both, out=both), 1), 1)
            return z.tolist(), float(norms[0]) * float(norms[1])
    return step


def float_solve(M, B):
    """``(X, κ)`` for M X = B in binary64: ``numpy.linalg.solve`` and κ₁ from
    ``numpy.linalg.inv`` (see the module docstring); ``M`` N×N, ``B`` N×m (numpy).  Raises
    :class:`~exact_khk.linalg.dense.SingularMatrix` on an exactly zero pivot;
    non-finite data give non-finite X or κ."""
    X, Y = _lapack(M, B)
    return X, _norm1(M) * _norm1(Y)


def binary64_condition(M):
    """κ₁(M) = ‖M‖₁‖M⁻¹‖₁ of a matrix of ``mp:P`` numbers, computed in binary64 (M
    rounded to doubles, M⁻¹ by LAPACK), or None where binary64 cannot be trusted with
    it: an entry that is not a normal double (out of range, or a nonzero that
    underflows), an exactly zero pivot, or N·κ > :data:`BINARY64_CONDITION_MAX`.

    Why that suffices: rounding perturbs each entry by a relative 2^-53, so
    ‖ΔM‖₁ ≤ 2^-53‖M‖₁ and ‖M⁻¹‖₁ moves by a relative ≲ κ·2^-53; LAPACK's inverse
    adds about N·κ·2^-53 (backward stable LU with small growth).  With N·κ ≤ 2^32 both
    stay below 2^-20: κ to five digits, for a quantity that is compared with 2^(p/2)
    and 2^p.  Otherwise the caller computes κ in p-bit arithmetic
    (:func:`~exact_khk.linalg.dense.solve`).  For N = 4..6 this is a third of an
    ``mp:128`` step less (the p-bit inverse takes N column solves).
    """
    A = numpy.array(M, dtype=object)
    try:
        F = A.astype(float)
    except (OverflowError, TypeError, ValueError):
        return None
    mag = numpy.abs(F)
    nonzero = mag != 0
    if not numpy.isfinite(mag).all() or (mag[nonzero] < 2.0 ** -1022).any() \
            or numpy.count_nonzero(nonzero) != numpy.count_nonzero(A):
        return None
    try:
        _, Y = _lapack(F)
    except SingularMatrix:
        return None
    kappa = _norm1(F) * _norm1(Y)  # an overflowing inverse: inf (or nan), refused below
    return kappa if kappa * len(F) <= BINARY64_CONDITION_MAX else None


def _lapack(M, B=None):
    """:func:`_gufuncs` in their error state: an exactly zero pivot sets the invalid flag
    (and nothing else in them does) and raises
    :class:`~exact_khk.linalg.dense.SingularMatrix`."""
    try:
        with numpy.errstate(invalid="raise", over="ignore", divide="ignore", under="ignore"):
            return _gufuncs(M, B)
    except (FloatingPointError, numpy.linalg.LinAlgError):
        raise SingularMatrix("Singular matrix") from None


def _gufuncs(M, B=None, inverse=None):
    """``(X, M⁻¹)`` in binary64 by the gufuncs of ``numpy.linalg.solve`` and ``inv`` (X None
    without ``B``; M⁻¹ written into ``inverse`` if given).  An exactly zero pivot gives NaN
    and sets the invalid flag: what that does is the caller's error state.  Without numpy's
    private module, the public functions, which raise ``LinAlgError`` there instead."""
    if _gesv is None:  # pragma: no cover
        Y = numpy.linalg.inv(M)
        if inverse is not None:
            inverse[...], Y = Y, inverse
        return None if B is None else numpy.linalg.solve(M, B), Y
    Y = _inv(M, signature="d->d") if inverse is None else _inv(M, signature="d->d", out=inverse)
    return None if B is None else _gesv(M, B, signature="dd->d"), Y


def _norm1(A) -> float:
    """‖A‖₁ by ufunc reductions, as a Python float (inf·0 is then nan without a warning)."""
    return float(_max(_add(numpy.abs(A), 0)))


_add, _max = numpy.add.reduce, numpy.maximum.reduce
try:  # numpy's private module (numpy 1.x and 2.x); without it, the public functions
    from numpy.linalg import _umath_linalg

    _gesv, _inv = _umath_linalg.solve, _umath_linalg.inv
except ImportError:  # pragma: no cover
    _gesv = _inv = None
