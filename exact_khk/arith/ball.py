"""Ball arithmetic ``ball:P``: certified enclosures with python-flint's ``arb``.

An element is a ball [m ± r] (an ``arb``) that is guaranteed to contain the
exact value of the quantity it stands for.  Every operation is performed at
the precision of the context, **P bits**: python-flint has one global working
precision, so each :class:`BallArith` enters ``flint.ctx.workprec(P)`` in
:meth:`BallArith.local`.  ``KahanMap.step``/``jacobian`` and ``Htilde`` enter
it themselves; wrap your *own* arithmetic on balls in ``with ar.local():``,
otherwise it runs at flint's global precision (53 bits by default).

Predicates are honest: :meth:`BallArith.is_zero` answers ``True`` (exactly 0),
``False`` (0 is not in the ball) or ``None`` (undecided); a linear solve whose
pivots arb cannot certify nonzero raises
:class:`~exact_khk.errors.UndecidedError` — never a wrong answer.

>>> from exact_khk import get_arith, KahanMap
>>> from exact_khk.systems.lie_poisson import default_system, DEFAULT_X0
>>> ar = get_arith("ball:128")
>>> y = KahanMap(default_system().field("f"), "1/10", ar).step(DEFAULT_X0)
>>> ar.format(y[0], digits=20)
'[2.9605020302694721299 +/- 3.73e-20]'
>>> contains_exact(y[0], KahanMap(default_system().field("f"), "1/10").step(DEFAULT_X0)[0])
True
"""

from __future__ import annotations

from fractions import Fraction

import flint

from exact_khk.arith import Arith, _as_fraction, check_precision, register_arith
from exact_khk.errors import UndecidedError


def arb_to_fmpq(x) -> flint.fmpq:
    """The exact rational value of a (finite) arb with zero radius, e.g. a midpoint."""
    man, exp = x.man_exp()
    man, exp = int(man), int(exp)
    return flint.fmpq(man << exp) if exp >= 0 else flint.fmpq(man, 1 << -exp)


def ball_mid(x) -> flint.fmpq:
    """The midpoint of a ball as an exact rational."""
    return arb_to_fmpq(x.mid())


def ball_rad(x) -> flint.fmpq:
    """The radius of a ball as an exact rational."""
    return arb_to_fmpq(x.rad())


def contains_exact(x, q) -> bool:
    """Whether the ball ``x`` contains the exact rational ``q`` (decided exactly).

    ``arb.contains(fmpq)`` would first round ``q`` to a ball at flint's global
    precision; here |q − mid| ≤ rad is tested in exact rational arithmetic.
    """
    if not x.is_finite():
        return True  # an infinite ball contains everything (and certifies nothing)
    q = q if isinstance(q, flint.fmpq) else flint.fmpq(*_pq(q))
    return abs(q - ball_mid(x)) <= ball_rad(x)


def _pq(q):
    f = _as_fraction(q)
    return f.numerator, f.denominator


class BallArith(Arith):
    """python-flint ``arb`` balls at ``prec`` bits (``ball:P``).

    ``exact`` is False (results are enclosures, not values); ``to_float`` and
    ``to_fraction`` give the midpoint.
    """

    exact = False
    #: is_zero is rigorous (False only when 0 is outside the ball), so checks
    #: may decide "differs" from it; equality stays undecided unless exactly 0.
    decides = True

    def __init__(self, prec: int):
        self.prec = check_precision("ball", prec)
        self.name = f"ball:{prec}"
        self.evidence = f"certified enclosure (arb balls at {prec} bits)"
        self.zero, self.one = flint.arb(0), flint.arb(1)

    def local(self):
        """``flint.ctx.workprec(P)``: every arb operation inside runs at P bits."""
        return flint.ctx.workprec(self.prec)

    def convert(self, value):
        if isinstance(value, flint.arb):
            return value
        if isinstance(value, float):
            return flint.arb(value)  # a double is a dyadic rational: exact
        p, q = _pq(value)
        with self.local():
            return flint.arb(flint.fmpq(p, q))

    def is_zero(self, e):
        """True if exactly 0, False if 0 is outside the ball, None if undecided."""
        if e.is_zero():
            return True
        return None if e.contains(0) else False

    def magnitude(self, e) -> float:
        return float(abs(e).mid())

    def is_finite(self, e) -> bool:
        return bool(e.is_finite())

    def to_float(self, e) -> float:
        return float(e.mid())

    def to_fraction(self, e) -> Fraction:
        """The midpoint, exactly (the ball's centre, not a certified value)."""
        q = ball_mid(e)
        return Fraction(int(q.p), int(q.q))

    def format(self, e, digits: int | None = None) -> str:
        """``'[m +/- r]'``: the midpoint to ``digits`` (default: about P bits) and a radius.

        The printed ball still encloses the value: when the midpoint is cut to
        ``digits``, the radius is enlarged accordingly (arb's ``str``)."""
        if not e.is_finite():
            return "[+/- inf]"
        d = digits if digits is not None else max(1, int(self.prec * 0.30103))
        return e.str(d, radius=True) if not e.is_zero() else "0"

    def native_solve(self, M, B):
        """Certified enclosure of M⁻¹B (arb's LU with interval pivots).

        Raises :class:`UndecidedError` when arb cannot certify the pivots nonzero
        at this precision (the matrix may or may not be singular).
        """
        with self.local():
            try:
                X = flint.arb_mat(M).solve(flint.arb_mat(B))
            except ZeroDivisionError:
                raise UndecidedError(
                    f"{self.name}: no pivot of the {len(M)}x{len(M)} linear system is certainly "
                    f"nonzero at {self.prec} bits (singular or too ill-conditioned for this "
                    f"precision; raise P)") from None
        m = X.ncols()
        flat = X.entries()
        return [flat[i * m:(i + 1) * m] for i in range(X.nrows())]


register_arith("ball", BallArith, replace=True)  # the deferred factory of exact_khk.arith
