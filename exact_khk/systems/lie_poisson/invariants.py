"""Integrals of the Kahan maps of the Lie–Poisson family (MATH.md, (tH 4)).

For a Lie–Poisson field f(x) = J(x) M x (M = Hs for f, B Hs for an associated
field g):

    H̃_M(x, ε) = xᵀ (I − ε² (M J(x))²)^{-1} M x

(= 2 H_M(x) + O(ε²), even in ε).  K̃ is the same with M = B Hs.

>>> from exact_khk import LiePoissonSystem, get_arith
>>> from exact_khk.systems.lie_poisson import default_system, DEFAULT_X0
>>> s = default_system(); ar = get_arith("fraction")
>>> x = [ar(t) for t in (1, 0, 0, 0, 1, 0)]
>>> Htilde(s.field("f"), x, "1/10", ar)
Fraction(229600, 64011)
"""

from __future__ import annotations

from fractions import Fraction

from exact_khk.linalg import circulant
from exact_khk.arith import get_arith
from exact_khk.errors import InputError, PoleError
from exact_khk.linalg.dense import SingularMatrix, matmul, matvec, solve, transpose
from exact_khk.linalg.paths import HTILDE_STRUCTURED_MIN_N
from exact_khk.parsing import parse_rational


def _eps(ar, eps):
    """ε as an element of ``ar``: from a rational (string, int, Fraction) or an element
    (of ``ar``, or of its base for a dual context)."""
    if type(eps) is type(ar.zero) and not isinstance(eps, (int, str)):
        return eps
    if isinstance(eps, (str, int, Fraction)) or (isinstance(eps, float) and ar.exact):
        return ar.convert(parse_rational(eps, "eps"))
    return ar.convert(eps)


def hessian_in(ar, field):
    """The field's constant matrix M converted into ``ar`` (cached on the field)."""
    key = ("hessian", ar.name)
    hit = field._cache.get(key)
    if hit is None:
        hit = [[ar.convert(t) for t in row] for row in field.hessian]
        field._cache[key] = hit
    return hit


def Htilde(field, x, eps, arith=None, method="auto"):
    """H̃(x, ε) = xᵀ (I − ε²(M J(x))²)^{-1} M x for a :class:`LiePoissonField`.

    Raises :class:`~exact_khk.errors.PoleError` where I − ε²(M J(x))² is
    singular (there the integral has a pole).

    Exact rational arithmetics with python-flint solve the 2n×2n system as a
    2×2 system over circulants (:func:`exact_khk.linalg.circulant.exact_htilde`) when
    the Hessian blocks are cyclic Hankel and n ≥ :data:`~exact_khk.linalg.paths.HTILDE_STRUCTURED_MIN_N`
    (measured at orbit points, docs/benchmarks.md: n = 3, 8, 16 about 3×,
    40×, 160× faster than the dense solve); the result is the same rational
    number.  ``method='dense'`` forces the 2n×2n solve.
    """
    ar = get_arith(arith)
    if not hasattr(field, "system") or field.system is None:
        raise InputError("field: H̃ is defined for Lie–Poisson fields f(x) = J(x) M x")
    if method not in ("auto", "dense"):
        raise InputError(f"method: expected 'auto' or 'dense', got {method!r}")
    e = _eps(ar, eps)
    if method == "auto" and ar.rational and circulant.flint is not None and field.system.n >= HTILDE_STRUCTURED_MIN_N:
        st = circulant.circulant_structure(field)
        if st is not None:
            try:
                return circulant.exact_htilde(st, x, e, ar)
            except SingularMatrix:
                raise _pole(ar, x, e) from None
    with ar.local():  # e.g. the working precision of ball:P
        return _htilde(ar, field, x, e)


def _pole(ar, x, e):
    return PoleError("H~ has a pole at x = (" + ", ".join(ar.format(t) for t in x)
                     + f"), eps = {ar.format(e)}: I - eps^2 (M J(x))^2 is singular")


def _htilde(ar, field, x, e):
    M = hessian_in(ar, field)
    x = list(x)
    S = matmul(M, field.system.J(x))
    S2 = matmul(S, S)
    e2 = e * e
    N = len(x)
    R = [[(ar.one if i == j else ar.zero) - e2 * S2[i][j] for j in range(N)] for i in range(N)]
    Mx = [[sum((M[i][j] * x[j] for j in range(N)), ar.zero)] for i in range(N)]
    try:
        z, _ = solve(ar, R, Mx)
    except SingularMatrix:
        raise _pole(ar, x, e) from None
    return sum((x[i] * z[i][0] for i in range(N)), ar.zero)


def shift_index(n: int, l: int) -> list[int]:
    """σ with (A^l)[j][σ(j)] = 1, so (A^l v)[j] = v[σ(j)] and (A^l M)[j] = M[σ(j)]."""
    return [(j + l) % n if j < n else n + (j - n + l) % n for j in range(2 * n)]


def q_coefficients(system, x, arith=None):
    """[q_0, …, q_{n-1}] at x: q_l = tr((Aᵀ)^l (J(x) Hs)²)/(2n), so that
    (J(x) Hs)² = Σ_l q_l A^l (MATH.md)."""
    ar = get_arith(arith)
    n = system.n
    S = matmul(system.J(list(x)), hessian_in(ar, system.field("f")))
    S2 = matmul(S, S)
    two_n = ar.convert(2 * n)
    return [sum((S2[i][s] for i, s in enumerate(shift_index(n, l))), ar.zero) / two_n for l in range(n)]


def Pi(system, x, eps, arith=None):
    """The invariant Poisson tensor by its definition Π(x) = J − ε² J Hs J Hs J (J = J(x))."""
    ar = get_arith(arith)
    e = _eps(ar, eps)
    J = system.J(list(x))
    JH = matmul(J, hessian_in(ar, system.field("f")))
    T = matmul(matmul(JH, JH), J)
    e2 = e * e
    return [[a - e2 * b for a, b in zip(ra, rb)] for ra, rb in zip(J, T)]


def Pi_from_q(system, x, eps, arith=None):
    """Π(x) = (1 − ε² q_0) J − ε² Σ_{l≥1} q_l A^l J (the paper's formula, sum from l = 1)."""
    ar = get_arith(arith)
    e = _eps(ar, eps)
    e2 = e * e
    J = system.J(list(x))
    q = q_coefficients(system, x, ar)
    out = [[(ar.one - e2 * q[0]) * t for t in row] for row in J]
    for l in range(1, system.n):
        c = e2 * q[l]
        for j, s in enumerate(shift_index(system.n, l)):
            out[j] = [a - c * t for a, t in zip(out[j], J[s])]
    return out


def _J_form(n, u, v, k):
    """uᵀ J(e_k) v = Σ_{(i+j) ≡ k} (u_i v_{n+j} − u_{n+i} v_j)."""
    s = u[0] * 0
    for i in range(n):
        j = (k - i) % n
        s = s + u[i] * v[n + j] - u[n + i] * v[j]
    return s


def grad_Htilde(field, x, eps, arith=None):
    """The exact gradient of :func:`Htilde` at x, by a closed form (two solves).

    With R = I − ε²S², S = M J(x), z = R^{-1} M x and w = R^{-T} x:
    ∂_k H̃ = z_k + (Mᵀw)_k + ε² [ (Mᵀw)ᵀ J(e_k) S z + (Mᵀ Sᵀ w)ᵀ J(e_k) z ] for k < n
    (J is linear in u = x[:n]), and without the bracket for k ≥ n.  Tests compare
    it with :func:`grad_Htilde_dual` and with SymPy's derivative.

    >>> from exact_khk import LiePoissonSystem, get_arith
    >>> s = LiePoissonSystem.from_vectors("1,0", "0,1", "2,1"); ar = get_arith("fraction")
    >>> [str(t) for t in grad_Htilde(s.field("f"), [ar(t) for t in (1, 0, 0, 1)], "1/3", ar)]
    ['332/121', '-152/121', '14/11', '58/11']
    """
    ar = get_arith(arith)
    e = _eps(ar, eps)
    M = hessian_in(ar, field)
    n, N = field.system.n, len(M)
    x = list(x)
    S = matmul(M, field.system.J(x))
    S2 = matmul(S, S)
    e2 = e * e
    R = [[(ar.one if i == j else ar.zero) - e2 * S2[i][j] for j in range(N)] for i in range(N)]
    with ar.local():
        try:
            zw, _ = solve(ar, R, [[t] for t in matvec(M, x)])
            ww, _ = solve(ar, transpose(R), [[t] for t in x])
        except SingularMatrix:
            raise PoleError("H~ has a pole at x = (" + ", ".join(ar.format(t) for t in x)
                            + f"), eps = {ar.format(e)}: I - eps^2 (M J(x))^2 is singular") from None
    z, w = [r[0] for r in zw], [r[0] for r in ww]
    Mt = transpose(M)
    a = matvec(Mt, w)
    b = matvec(S, z)
    c = matvec(Mt, matvec(transpose(S), w))
    return [z[k] + a[k] + (e2 * (_J_form(n, a, b, k) + _J_form(n, c, z, k)) if k < n else ar.zero)
            for k in range(N)]


def grad_Htilde_dual(field, x, eps, arith=None):
    """The exact gradient of :func:`Htilde` by forward-mode dual numbers (an
    independent route to :func:`grad_Htilde`; no differences)."""
    from exact_khk.arith.dual import gradient

    ar = get_arith(arith)
    e = _eps(ar, eps)
    return gradient(ar, lambda d, xd: Htilde(field, xd, e, d), list(x))
