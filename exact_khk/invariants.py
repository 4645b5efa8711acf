"""Integrals of the Kahan maps of the Lie–Poisson family (MATH.md, (tH 4)).

For a Lie–Poisson field f(x) = J(x) M x (M = Hs for f, B Hs for an associated
field g):

    H̃_M(x, ε) = xᵀ (I − ε² (M J(x))²)^{-1} M x

(= 2 H_M(x) + O(ε²), even in ε).  K̃ is the same with M = B Hs.

>>> from exact_khk import LiePoissonSystem, get_arith
>>> from exact_khk.systems import default_system, DEFAULT_X0
>>> s = default_system(); ar = get_arith("fraction")
>>> x = [ar(t) for t in (1, 0, 0, 0, 1, 0)]
>>> Htilde(s.field("f"), x, "1/10", ar)
Fraction(229600, 64011)
"""

from __future__ import annotations

from .arith import get_arith
from .errors import InputError, SingularStepError
from .linalg import SingularMatrix, matmul, solve
from .parsing import parse_rational


def _eps(ar, eps):
    if type(eps) is type(ar.zero) and not isinstance(eps, (int, str)):
        return eps
    return ar.convert(parse_rational(eps, "eps"))


def hessian_in(ar, field):
    """The field's constant matrix M converted into ``ar`` (cached on the field)."""
    key = ("hessian", ar.name)
    hit = field._cache.get(key)
    if hit is None:
        hit = [[ar.convert(t) for t in row] for row in field.hessian]
        field._cache[key] = hit
    return hit


def Htilde(field, x, eps, arith=None):
    """H̃(x, ε) = xᵀ (I − ε²(M J(x))²)^{-1} M x for a :class:`LiePoissonField`.

    Raises :class:`SingularStepError` where I − ε²(M J(x))² is singular (there
    the integral has a pole).
    """
    ar = get_arith(arith)
    if not hasattr(field, "system") or field.system is None:
        raise InputError("field: H̃ is defined for Lie–Poisson fields f(x) = J(x) M x")
    e = _eps(ar, eps)
    M = hessian_in(ar, field)
    x = list(x)
    S = matmul(M, field.system.J(x))
    S2 = matmul(S, S)
    e2 = e * e
    N = len(x)
    R = [[(ar.one if i == j else ar.zero) - e2 * S2[i][j] for j in range(N)] for i in range(N)]
    Mx = [[sum((M[i][j] * x[j] for j in range(N)), ar.zero)] for i in range(N)]
    with ar.local():
        try:
            z, _ = solve(ar, R, Mx)
        except SingularMatrix:
            raise SingularStepError([ar.format(t) for t in x], ar.format(e),
                                    detail="H̃ has a pole here: I - eps^2 (M J(x))^2 is singular") from None
    return sum((x[i] * z[i][0] for i in range(N)), ar.zero)
