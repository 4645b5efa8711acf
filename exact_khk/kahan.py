"""The Kahan (Kahan–Hirota–Kimura) map of a quadratic vector field.

For f(x) = Q(x) + L x + c and step size ε (one step approximates the time-2ε
flow):

* homogeneous f:  Φ_f(x, ε) = (I − ε f'(x))^{-1} x
* general f:      Φ_f(x, ε) = x + 2ε (I − ε f'(x))^{-1} f(x)
* inverse:        Φ_f(·, ε)^{-1} = Φ_f(·, −ε)
* Jacobian:       dΦ_f(x) = (I − ε f'(x))^{-1} (I + ε f'(Φ_f(x)))

The step is undefined where det(I − ε f'(x)) = 0.  Exact arithmetics detect
this exactly and raise :class:`~exact_khk.errors.SingularStepError`.
Floating arithmetics (``float``, ``mp:P``) compute a 1-norm condition estimate
κ of I − ε f'(x) at every step and

* raise :class:`SingularStepError` (with κ) when a pivot is exactly zero, a
  result is not finite, or κ·2^-p ≥ 1 (no correct bit can be guaranteed);
* warn with :class:`~exact_khk.errors.NearSingularWarning` (carrying κ) when
  κ ≥ 2^(p/2), i.e. conditioning alone may cost more than half the bits.

>>> from exact_khk import LiePoissonSystem, KahanMap
>>> sys3 = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")
>>> phi = KahanMap(sys3.field("f"), eps="1/10", arith="fraction")
>>> y = phi.step(["1", "0", "0", "0", "1", "0"])
>>> [str(t) for t in y]
['72745/57239', '34155/57239', '27780/57239', '-34910/57239', '19745/57239', '-18505/57239']
>>> [str(t) for t in phi.inverse(y)]
['1', '0', '0', '0', '1', '0']
"""

from __future__ import annotations

import math
import warnings

from .arith import get_arith
from .errors import InputError, NearSingularWarning, SingularStepError
from .linalg import SingularMatrix, solve
from .parsing import parse_rational


def as_point(ar, x, dim: int, name: str = "x"):
    """Convert a point (strings, ints, Fractions, backend rationals, or elements
    of ``ar``) into a tuple of elements of ``ar``; checks the dimension."""
    try:
        coords = list(x)
    except TypeError:
        raise InputError(f"{name}: expected a sequence of {dim} numbers, got {x!r}") from None
    if len(coords) != dim:
        raise InputError(f"{name}: expected {dim} coordinates, got {len(coords)}")
    out = []
    for i, t in enumerate(coords):
        if not ar.exact and isinstance(t, float):
            out.append(ar.convert(t))
        elif _is_element(ar, t):
            out.append(t)
        else:
            out.append(ar.convert(parse_rational(t, f"{name}[{i}]")))
    return tuple(out)


def _is_element(ar, t) -> bool:
    return type(t) is type(ar.zero) and not isinstance(t, (int, str))


class KahanMap:
    """Φ_f(·, ε) for a :class:`~exact_khk.quadratic.QuadraticField` in one arithmetic.

    ``eps`` is an exact rational (``'1/10'``, Fraction, int) or an element of
    the arithmetic; ``arith`` a name (see :func:`exact_khk.arith.get_arith`) or
    context, default the fastest exact one.
    """

    def __init__(self, field, eps, arith=None):
        self.field = field
        self.arith = ar = get_arith(arith)
        if _is_element(ar, eps):
            self.eps = eps
            self.eps_exact = ar.to_fraction(eps) if ar.exact else None
        else:
            self.eps_exact = parse_rational(eps, "eps")
            self.eps = ar.convert(self.eps_exact)
        if ar.is_zero(self.eps) is True:
            raise InputError("eps: the step size must be nonzero")

    def __repr__(self):
        return f"KahanMap({self.field.label}, eps={self.arith.format(self.eps)}, arith={self.arith.name})"

    def point(self, x, name="x"):
        """``x`` as a tuple of elements of this map's arithmetic."""
        return as_point(self.arith, x, self.field.dim, name)

    def with_eps(self, eps):
        """The same map with another step size (e.g. ``-eps`` for the inverse)."""
        out = KahanMap.__new__(KahanMap)
        out.field, out.arith, out.eps = self.field, self.arith, eps
        out.eps_exact = self.arith.to_fraction(eps) if self.arith.exact else None
        return out

    def system_matrix(self, x, sign=1):
        """I − sign·ε f'(x)."""
        ar, e = self.arith, self.eps if sign == 1 else -self.eps
        Jf = self.field.jacobian(ar, x)
        return [[(ar.one if i == j else ar.zero) - e * Jf[i][j] for j in range(len(x))]
                for i in range(len(x))]

    def _solve(self, M, B, x, eps):
        """Solve M X = B, turning singularity and ill-conditioning into our errors."""
        ar = self.arith
        with ar.local():
            try:
                X, cond = solve(ar, M, B)
            except SingularMatrix:
                raise SingularStepError([ar.format(t) for t in x], ar.format(eps)) from None
        if not ar.exact:
            # cond is None when the context's solver gives no estimate (balls
            # carry their own error bounds instead).
            bad = any(not ar.is_finite(t) for row in X for t in row)
            if bad or (cond is not None and (cond != cond or cond * ar.unit_roundoff >= 1)):
                raise SingularStepError([ar.format(t) for t in x], ar.format(eps),
                                        condition=float("inf") if bad or cond != cond else cond)
            if cond is not None and cond >= 2.0 ** (ar.prec / 2):
                warnings.warn(NearSingularWarning(
                    f"Kahan step at eps = {ar.format(eps)} is ill-conditioned: "
                    f"condition estimate {cond:.3g} of I - eps*f'(x) in {ar.name} "
                    f"(about {math.log2(cond):.0f} of {ar.prec} bits at risk)", cond), stacklevel=3)
        return X

    def step(self, x):
        """Φ_f(x, ε)."""
        x = self.point(x)
        ar, eps = self.arith, self.eps
        M = self.system_matrix(x)
        if self.field.homogeneous:
            X = self._solve(M, [[t] for t in x], x, eps)
            return tuple(row[0] for row in X)
        fx = self.field.evaluate(ar, x)
        X = self._solve(M, [[t] for t in fx], x, eps)
        two_eps = eps + eps
        return tuple(xi + two_eps * row[0] for xi, row in zip(x, X))

    def inverse(self, x):
        """Φ_f(x, −ε) = Φ_f^{-1}(x, ε)."""
        return self.with_eps(-self.eps).step(x)

    def orbit(self, x0, steps: int, progress=None):
        """[x0, Φ(x0), …, Φ^steps(x0)]; a singular step raises with its step number.

        ``progress``, if given, is called as ``progress(k)`` after step k.
        """
        if not isinstance(steps, int) or steps < 0:
            raise InputError(f"steps: expected a non-negative integer, got {steps!r}")
        pts = [self.point(x0, "x0")]
        for k in range(1, steps + 1):
            try:
                pts.append(self.step(pts[-1]))
            except SingularStepError as exc:
                raise exc.at_step(k) from None
            if progress is not None:
                progress(k)
        return pts

    def jacobian(self, x):
        """dΦ_f(x) = (I − ε f'(x))^{-1} (I + ε f'(Φ_f(x)))."""
        x = self.point(x)
        y = self.step(x)
        return self._solve(self.system_matrix(x), self.system_matrix(y, sign=-1), x, self.eps)


def kahan_step(field, x, eps, arith=None):
    """Φ_f(x, ε) (functional form of :meth:`KahanMap.step`)."""
    return KahanMap(field, eps, arith).step(x)


def orbit(field, x0, eps, steps, arith=None, progress=None):
    """The orbit of K = ``steps`` Kahan steps (functional form of :meth:`KahanMap.orbit`)."""
    return KahanMap(field, eps, arith).orbit(x0, steps, progress=progress)


def map_jacobian(field, x, eps, arith=None):
    """dΦ_f(x) (functional form of :meth:`KahanMap.jacobian`)."""
    return KahanMap(field, eps, arith).jacobian(x)


