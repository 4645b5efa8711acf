"""Forward-mode dual numbers over an arithmetic context: exact gradients.

A :class:`Dual` is ``val + Σ_d tan[d] δ_d`` with ``δ_d δ_e = 0``; its parts are
elements of a *base* arithmetic (exact rationals, a cyclotomic field, floats…).
:class:`DualArith` is itself an arithmetic context, so any algorithm written
over a context (H̃, Π, q_l) evaluated at a dual point returns its value *and*
its exact gradient — no finite differences.  Linear solves go through
:meth:`DualArith.native_solve`, which solves twice with the base arithmetic
(value, then all tangents: ``M0 X_d = B_d - M_d X0``), so a pivot never has to
be a dual number.

>>> from fractions import Fraction as F
>>> from exact_khk.arith import get_arith
>>> ar = get_arith("fraction")
>>> gradient(ar, lambda d, x: x[0] * x[0] * x[1] / (x[1] + d.one), [F(3), F(1)])
[Fraction(3, 1), Fraction(9, 4)]
"""

from __future__ import annotations

from exact_khk.arith import Arith
from exact_khk.linalg.dense import SingularMatrix, solve


class Dual:
    """A value with a tuple of tangents (``None`` when all tangents are zero)."""

    __slots__ = ("val", "tan")

    def __init__(self, val, tan=None):
        self.val, self.tan = val, tan

    @staticmethod
    def _lift(o):
        return o if isinstance(o, Dual) else Dual(o)

    def __add__(self, o):
        o = Dual._lift(o)
        if o.tan is None or self.tan is None:
            return Dual(self.val + o.val, self.tan if o.tan is None else o.tan)
        return Dual(self.val + o.val, tuple(a + b for a, b in zip(self.tan, o.tan)))

    __radd__ = __add__

    def __neg__(self):
        return Dual(-self.val, None if self.tan is None else tuple(-a for a in self.tan))

    def __pos__(self):
        return self

    def __sub__(self, o):
        return self + (-Dual._lift(o))

    def __rsub__(self, o):
        return Dual._lift(o) + (-self)

    def __mul__(self, o):
        if not isinstance(o, Dual):  # a scalar of the base (or an int)
            return Dual(self.val * o, None if self.tan is None else tuple(a * o for a in self.tan))
        if o.tan is None:
            return self * o.val
        if self.tan is None:
            return o * self.val
        return Dual(self.val * o.val, tuple(self.val * b + o.val * a for a, b in zip(self.tan, o.tan)))

    __rmul__ = __mul__

    def __truediv__(self, o):
        o = Dual._lift(o)
        q = self.val / o.val  # ZeroDivisionError when the value is zero
        if o.tan is None:
            return Dual(q, None if self.tan is None else tuple(a / o.val for a in self.tan))
        st = self.tan if self.tan is not None else (0 * q,) * len(o.tan)
        return Dual(q, tuple((a - q * b) / o.val for a, b in zip(st, o.tan)))

    def __rtruediv__(self, o):
        return Dual._lift(o) / self

    def __eq__(self, o):
        o = Dual._lift(o)
        return self.val == o.val and all(a == 0 for a in _diff(self.tan, o.tan))

    __hash__ = None

    def __repr__(self):
        return f"Dual({self.val!r}, {self.tan!r})"


def _diff(t1, t2):
    if t1 is None and t2 is None:
        return ()
    if t1 is None:
        return tuple(-b for b in t2)
    if t2 is None:
        return t1
    return tuple(a - b for a, b in zip(t1, t2))


class DualArith(Arith):
    """The arithmetic of :class:`Dual` numbers with ``ndir`` tangent directions over ``base``."""

    def __init__(self, base: Arith, ndir: int):
        self.base, self.ndir = base, ndir
        self.name = f"dual{ndir}({base.name})"
        self.exact, self.prec = base.exact, base.prec
        self.zero, self.one = Dual(base.zero), Dual(base.one)

    def convert(self, value):
        if isinstance(value, Dual):
            return value
        if type(value) is type(self.base.zero) and not isinstance(value, (int, str)):
            return Dual(value)
        return Dual(self.base.convert(value))

    def tangents(self, e):
        """The full tangent tuple of ``e`` (zeros filled in)."""
        return e.tan if e.tan is not None else (self.base.zero,) * self.ndir

    def is_zero(self, e):
        parts = [self.base.is_zero(e.val)] + [self.base.is_zero(t) for t in e.tan or ()]
        return False if False in parts else (None if None in parts else True)

    def format(self, e) -> str:
        return f"{self.base.format(e.val)} + d({', '.join(self.base.format(t) for t in self.tangents(e))})"

    def magnitude(self, e) -> float:
        return self.base.magnitude(e.val)

    def local(self):
        return self.base.local()

    def native_solve(self, M, B):
        """Solve ``M X = B`` for dual matrices with two base solves (see module doc)."""
        base, N, m = self.base, len(M), len(B[0])
        M0 = [[e.val for e in row] for row in M]
        try:
            X0, _ = solve(base, M0, [[e.val for e in row] for row in B])
            rhs = []
            for i in range(N):
                Bt = [self.tangents(e) for e in B[i]]
                Mt = [self.tangents(e) for e in M[i]]
                rhs.append([Bt[c][d] - sum((Mt[j][d] * X0[j][c] for j in range(N)), base.zero)
                            for c in range(m) for d in range(self.ndir)])
            Xt, _ = solve(base, M0, rhs)
        except SingularMatrix as exc:
            raise ZeroDivisionError(str(exc)) from None
        nd = self.ndir
        return [[Dual(X0[i][c], tuple(Xt[i][c * nd:(c + 1) * nd])) for c in range(m)] for i in range(N)]


def seed(ar, x):
    """``(DualArith, point)``: ``x`` (elements of ``ar``) with tangents the unit vectors."""
    d = DualArith(ar, len(x))
    units = [tuple(ar.one if i == j else ar.zero for j in range(len(x))) for i in range(len(x))]
    return d, [Dual(xi, u) for xi, u in zip(x, units)]


def jacobian(ar, fn, x):
    """Values and exact gradients of ``fn(dual_arith, point)`` (a list of scalars) at ``x``:
    returns ``(values, rows)`` with ``rows[i]`` the gradient of the i-th output."""
    d, xd = seed(ar, x)
    out = [d.convert(e) for e in fn(d, xd)]
    return [e.val for e in out], [list(d.tangents(e)) for e in out]


def gradient(ar, fn, x):
    """The exact gradient of ``fn(dual_arith, point)`` (a scalar) at ``x``."""
    return jacobian(ar, lambda d, xd: [fn(d, xd)], x)[1][0]


def jacobiator(ar, matrix, x):
    """All cyclic sums Σ_m (Π_im ∂_mΠ_jk + Π_jm ∂_mΠ_ki + Π_km ∂_mΠ_ij), i < j < k, of the
    bivector ``matrix(context, point)`` at x, its derivatives exact by dual numbers."""
    N = len(x)
    vals, grads = jacobian(ar, lambda d, xd: [t for row in matrix(d, xd) for t in row], list(x))
    P = [vals[i * N:(i + 1) * N] for i in range(N)]
    dP = lambda j, k: grads[j * N + k]  # noqa: E731  (∂_m Π_jk for m = 0..N-1)
    out = []
    for i in range(N):
        for j in range(i + 1, N):
            for k in range(j + 1, N):
                out.append(sum((P[i][m] * dP(j, k)[m] + P[j][m] * dP(k, i)[m] + P[k][m] * dP(i, j)[m]
                                for m in range(N)), ar.zero))
    return out
