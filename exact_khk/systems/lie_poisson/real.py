"""Lie–Poisson systems with real Hessian blocks: a, b, c as arb balls (``exact-khk enclose``).

The field f(x) = J(x) Hs x is linear in (a, b, c): every entry of
Hs = [[X(a), X(b)], [X(b), X(c)]] is one entry of a, b or c, and every coefficient
of f (and of the associated field g = J(x) B Hs x, B rational) is a sum of such
entries with rational weights.  :class:`RealLiePoissonSystem` keeps a, b, c as arb
balls at P bits, each enclosing every admissible value (an exact real such as
``sqrt(2)``, or every point of an interval ``[1.9,2.1]``), and builds its fields
from the same formulas as :class:`~.system.LiePoissonSystem` in ball arithmetic, so
that every coefficient ball contains the true coefficient for every parameter
value in the boxes.  A coefficient is dropped only when it is exactly 0 (a ball
that contains 0 stays a term: :func:`~exact_khk.systems.quadratic.certainly_zero`).

Ball evaluations of the field, its Jacobian and the integrals H̃, K̃
(:func:`~.invariants.Htilde` evaluates xᵀ(I − ε²(MJ(x))²)⁻¹Mx with the ball
Hessian M) then enclose their values for every (x, p) in the boxes.  These fields
serve ``ball:P`` only; the exact, structured and certificate paths need rational
a, b, c (:class:`~.system.LiePoissonSystem`).

>>> s = RealLiePoissonSystem.from_reals("sqrt(2),0,[1.9,2.1]", "0,1,0", "3,1,1", 128)
>>> f3 = dict(s.field("f").terms()[3])      # f_3 = -(X(u)(X(a) u + X(b) v))_0
>>> f3[(0, 0)].rad() < 2 ** -126, f3[(0, 2)]      # -a_0 = -sqrt(2), and -2 a_2 in [-4.2, -3.8]
(True, [-4e+0 +/- 0.201])
"""

from __future__ import annotations

from dataclasses import dataclass

import flint

from exact_khk.arith import check_precision
from exact_khk.errors import InputError
from exact_khk.parsing import format_signs, parse_signs

from .system import LiePoissonSystem, b0_signs, is_rational_pattern


def _times(C, M, prec):
    """C·M for a rational matrix C and a matrix M of arb balls, at ``prec`` bits (each
    row of C over its common denominator: integer multiples of M's entries, one division)."""
    from math import lcm

    out = []
    with flint.ctx.workprec(prec):
        for row in C:
            den = lcm(1, *(t.denominator for t in row))
            ints = [(k, int(t.numerator * (den // t.denominator))) for k, t in enumerate(row) if t]
            out.append(tuple(sum((w * M[k][j] for k, w in ints), flint.arb(0)) / den for j in range(len(M[0]))))
    return tuple(out)


@dataclass(frozen=True, eq=False)
class RealLiePoissonSystem(LiePoissonSystem):
    """A Lie–Poisson system whose blocks a, b, c are arb balls at ``prec`` bits (see the
    module docstring); build it with :meth:`from_reals`.  Its fields ``'f'`` (any power),
    ``'g'`` (rational sign patterns) and ``'control'`` have ball coefficients."""

    prec: int = 256

    def __post_init__(self):
        check_precision("ball", self.prec)
        n = len(self.a)
        if n < 2:
            raise InputError(f"n: the family needs n >= 2, got n = {n}")
        for name in ("a", "b", "c"):
            v = tuple(getattr(self, name))
            if len(v) != n:
                raise InputError(f"{name}: expected {n} coordinates, got {len(v)}")
            if not all(isinstance(t, flint.arb) and t.is_finite() for t in v):
                raise InputError(f"{name}: expected finite arb balls (use RealLiePoissonSystem.from_reals)")
            object.__setattr__(self, name, v)

    @classmethod
    def from_reals(cls, a, b, c, prec: int = 256, names=("a", "b", "c"), n: int | None = None):
        """From three vectors of reals (texts read by
        :func:`~exact_khk.arith.reals.parse_real_vector`: ``'sqrt(2),0,[1.9,2.1]'``, or
        sequences of texts, exact numbers or arb balls) at ``prec`` bits; ``names`` name
        them in errors, ``n`` is the expected length of a."""
        from exact_khk.arith.reals import parse_real_vector

        prec = check_precision("ball", prec)
        va = parse_real_vector(a, prec, names[0], n)
        if len(va) < 2:
            raise InputError(f"{names[0]}: the family needs n >= 2, got n = {len(va)}")
        return cls(va, parse_real_vector(b, prec, names[1], len(va)), parse_real_vector(c, prec, names[2], len(va)),
                   prec=prec)

    def describe(self) -> str:
        fmt = lambda v: "(" + ", ".join(t.str(10, radius=True) for t in v) + ")"  # noqa: E731
        return (f"Lie–Poisson system n={self.n} with real blocks (arb balls at {self.prec} bits): a={fmt(self.a)}, "
                f"b={fmt(self.b)}, c={fmt(self.c)}")

    def to_json(self) -> dict:
        return {"family": "lie-poisson", "n": self.n, "real": True, "prec": self.prec,
                **{k: [t.str(30, radius=True) for t in getattr(self, k)] for k in ("a", "b", "c")}}

    @property
    def hessian(self):
        with flint.ctx.workprec(self.prec):
            return tuple(tuple(r) for r in super().hessian)

    def _times(self, C, M):
        return _times(C, M, self.prec)

    def _structure(self, kind, signs=None, power=0):
        return None  # no structured (exact circulant) path for ball coefficients

    def field(self, kind: str = "f", signs=None, power: int = 0, cyclotomic: bool = False):
        """:meth:`LiePoissonSystem.field` with ball coefficients (summed at P bits); rational
        sign patterns only."""
        if kind == "g":
            s = format_signs(parse_signs(signs if signs is not None else b0_signs(self.n), self.n))
            if not is_rational_pattern(self.n, s):
                raise InputError(f"field: g[{s}] has an involution with entries in Q(zeta_{self.n}); real "
                                 f"blocks a, b, c are supported with rational involutions only")
        fld = super().field(kind, signs, power)
        with flint.ctx.workprec(self.prec):
            fld.terms()  # the coefficient sums, at P bits
        return fld

    def parameter_fields(self, kind: str = "f", signs=None, power: int = 0):
        """``field(kind, signs, power)`` as a :class:`~exact_khk.systems.quadratic.ParameterFields`
        in the block entries of nonzero radius (None when every entry is a point).

        The field is linear in (a, b, c) (every Hessian entry is one entry of a, b or c,
        and ``'g'``, ``'control'`` and the powers multiply the Hessian by rational
        matrices), so f(x; p) = f(x; m) + Σ_j (p_j − m_j) f_{e_j}(x): the midpoint field
        is the rational system at the balls' midpoints, and the unit field of entry j is
        the rational system with that entry 1 and every other entry 0."""
        from fractions import Fraction

        from exact_khk.arith.ball import ball_mid
        from exact_khk.systems.quadratic import ParameterFields

        blocks = {k: getattr(self, k) for k in ("a", "b", "c")}
        free = [(k, i) for k, v in blocks.items() for i, t in enumerate(v) if not t.rad().is_zero()]
        if not free:
            return None
        zero = (Fraction(0),) * self.n

        def rational(**vectors):
            return LiePoissonSystem(*(vectors.get(k, zero) for k in blocks)).field(kind, signs, power)

        mid = rational(**{k: tuple(Fraction(int(q.p), int(q.q)) for q in map(ball_mid, v))
                          for k, v in blocks.items()})
        units = [rational(**{k: tuple(Fraction(int(j == i)) for j in range(self.n))}) for k, i in free]
        radii = tuple(flint.arb(blocks[k][i].rad()) for k, i in free)
        return ParameterFields(mid, tuple(units), radii, tuple(f"{k}_{i}" for k, i in free))
