"""Symbolic proofs: identities in the field of rational functions.

:class:`RationalFunctionArith` is an exact arithmetic whose elements are
rational functions p/q of symbols (python-flint ``fmpq_mpoly``, reduced by a
gcd, denominator monic), so the *same* generic algorithms (Kahan step, integrals,
the claims of the registry) run over Q(x_0, …, x_{N−1}, ε): comparing the results
with ``==`` proves an identity of rational functions, for all x and ε where both
sides are defined (the engine's symbolic mode,
:func:`~exact_khk.certification.engine.symbolic_checks`).

:func:`prove_jacobi` proves the Jacobi identity of the family's Π(x) = J − ε² J Hs J Hs J
as a polynomial identity, with ``symbolic_hessian=True`` for every admissible Hessian at once
(a theorem about the family, beyond one system's claims).

>>> from exact_khk import LiePoissonSystem
>>> s = LiePoissonSystem.from_vectors("1,2", "0,1", "3,1")
>>> prove_jacobi(s, symbolic_hessian=True).holds
True
"""

from __future__ import annotations

import time
from fractions import Fraction

import flint

from exact_khk.arith import Arith, _as_fraction
from exact_khk.certification.records import Check
from exact_khk.linalg.dense import matmul
from exact_khk.systems.lie_poisson.system import hankel


class RatFunc:
    """p/q with p, q ``fmpq_mpoly`` in one context, gcd(p, q) = 1, q monic."""

    __slots__ = ("num", "den")

    def __init__(self, num, den, reduce=True):
        if reduce:
            if den.is_zero():
                raise ZeroDivisionError("rational function with zero denominator")
            if not den.is_constant():
                g = num.gcd(den)
                if not g.is_one():
                    num, den = num / g, den / g
            lc = den.leading_coefficient()
            if lc != 1:
                num, den = num / lc, den / lc
        self.num, self.den = num, den

    def _lift(self, other):
        if isinstance(other, RatFunc):
            return other
        if isinstance(other, (int, Fraction, flint.fmpq, flint.fmpz)):
            ctx = self.num.context()
            q = _as_fraction(other)
            return RatFunc(ctx.from_dict({}) + flint.fmpq(q.numerator, q.denominator), ctx.from_dict({}) + 1,
                           reduce=False)
        return None

    def __add__(self, other):
        # Henrici's addition: gcds of the denominators' parts, never of the sum's
        # numerator with the product of the denominators
        o = self._lift(other)
        if o is None:
            return NotImplemented
        a, b, c, d = self.num, self.den, o.num, o.den
        if b == d:
            return RatFunc(a + c, b)
        g = _gcd(b, d)
        if g is None or g.is_one():  # (ad + cb)/(bd) is in lowest terms, bd monic
            return _canonical(a * d + c * b, b * d)
        b1, d1 = b / g, d / g
        t = a * d1 + c * b1
        g2 = t.gcd(g)
        return _canonical(t / g2, b1 * (d / g2))

    __radd__ = __add__

    def __neg__(self):
        return RatFunc(-self.num, self.den, reduce=False)

    def __sub__(self, other):
        o = self._lift(other)
        return NotImplemented if o is None else self + (-o)

    def __rsub__(self, other):
        o = self._lift(other)
        return NotImplemented if o is None else o + (-self)

    def __mul__(self, other):
        o = self._lift(other)
        if o is None:
            return NotImplemented
        return _product(self.num, self.den, o.num, o.den)

    __rmul__ = __mul__

    def __truediv__(self, other):
        o = self._lift(other)
        if o is None:
            return NotImplemented
        if o.num.is_zero():
            raise ZeroDivisionError("division by the zero rational function")
        lc = o.num.leading_coefficient()  # d/c with c made monic
        return _product(self.num, self.den, o.den / lc, o.num / lc)

    def __rtruediv__(self, other):
        o = self._lift(other)
        return NotImplemented if o is None else o / self

    def __eq__(self, other):
        o = self._lift(other)
        return NotImplemented if o is None else (self.num == o.num and self.den == o.den)

    def __ne__(self, other):
        eq = self.__eq__(other)
        return eq if eq is NotImplemented else not eq

    def __hash__(self):
        return hash((str(self.num), str(self.den)))

    def __str__(self):
        return str(self.num) if self.den.is_one() else f"({self.num})/({self.den})"

    __repr__ = __str__


def _canonical(num, den):
    """num/den already in lowest terms with den monic; 0 as 0/1."""
    return RatFunc(num, den if not num.is_zero() else den.context().from_dict({}) + 1, reduce=False)


def _gcd(p, q):
    """gcd(p, q), monic (1 when either is a nonzero constant)."""
    return p.gcd(q) if not (p.is_constant() or q.is_constant()) else None


def _product(a, b, c, d):
    """(a/b)·(c/d) for fractions in lowest terms with monic denominators (Henrici:
    the cross gcds gcd(a, d), gcd(c, b) only)."""
    g1, g2 = _gcd(a, d), _gcd(c, b)
    if g1 is not None and not g1.is_one():
        a, d = a / g1, d / g1
    if g2 is not None and not g2.is_one():
        c, b = c / g2, b / g2
    return _canonical(a * c, b * d)


class RationalFunctionArith(Arith):
    """Exact arithmetic in Q(symbols) (elements :class:`RatFunc`)."""

    exact = True

    def __init__(self, symbols):
        self.symbols = tuple(symbols)
        self.name = "qfunc[" + ",".join(self.symbols) + "]"
        self.ctx = flint.fmpq_mpoly_ctx.get(self.symbols, "degrevlex")
        one = self.ctx.from_dict({}) + 1
        self.zero = RatFunc(self.ctx.from_dict({}), one, reduce=False)
        self.one = RatFunc(one, one, reduce=False)

    def gens(self):
        return [RatFunc(g, self.one.den, reduce=False) for g in self.ctx.gens()]

    def convert(self, value):
        if isinstance(value, RatFunc):
            return value
        return self.zero + _as_fraction(value)

    def is_zero(self, e):
        return e.num.is_zero()

    def format(self, e) -> str:
        return str(e)

    def evaluate(self, e, point) -> Fraction:
        """The value of ``e`` at ``point`` (one rational per symbol, in order);
        ZeroDivisionError where the denominator vanishes."""
        vals = {name: flint.fmpq(q.numerator, q.denominator)
                for name, q in zip(self.symbols, map(_as_fraction, point))}
        num, den = e.num.subs(vals), e.den.subs(vals)
        c = (num.leading_coefficient() if not num.is_zero() else flint.fmpq(0)) / den.leading_coefficient()
        return Fraction(int(c.p), int(c.q))


def _block_hessian(abc):
    """[[X(a), X(b)], [X(b), X(c)]] from the 3n symbols a, b, c (in this order)."""
    n = len(abc) // 3
    Xa, Xb, Xc = hankel(abc[:n]), hankel(abc[n:2 * n]), hankel(abc[2 * n:])
    return [ra + rb for ra, rb in zip(Xa, Xb)] + [rb + rc for rb, rc in zip(Xb, Xc)]


def jacobi_residual(system, symbolic_hessian=False, eps_zero=False, perturb=False):
    """(holds, residual) of the Jacobi identity
    Σ_l Π_il ∂_l Π_jk + Π_jl ∂_l Π_ki + Π_kl ∂_l Π_ij = 0 (all i < j < k) for
    Π = J − ε² J Hs J Hs J (J if ``eps_zero``), polynomials in x, ε (and a, b, c
    if ``symbolic_hessian``).  ``perturb`` adds ε² x_0 (E_01 − E_10), a negative
    control that is not Poisson.  Also returns the symbol names."""
    n, N = system.n, 2 * system.n
    names = [f"x{i}" for i in range(N)] + ["eps"]
    if symbolic_hessian:
        names += [f"{v}{i}" for v in "abc" for i in range(n)]
    ctx = flint.fmpq_mpoly_ctx.get(names, "degrevlex")
    g = ctx.gens()
    x, eps = g[:N], g[N]
    zero = ctx.from_dict({})
    if symbolic_hessian:
        Hs = _block_hessian(g[N + 1:])
    else:
        Hs = [[zero + flint.fmpq(int(t.numerator), int(t.denominator)) for t in row]
              for row in system.hessian]
    J = system.J(x)
    JH = matmul(J, Hs)
    T = matmul(matmul(JH, JH), J)
    Pm = [list(r) for r in J] if eps_zero else [[p - eps * eps * q for p, q in zip(rp, rq)]
                                                for rp, rq in zip(J, T)]
    if perturb:
        Pm[0][1] += eps * eps * x[0]
        Pm[1][0] -= eps * eps * x[0]
    D = [[[Pm[i][j].derivative(names[l]) for l in range(N)] for j in range(N)] for i in range(N)]
    for i in range(N):
        for j in range(i + 1, N):
            for k in range(j + 1, N):
                s = zero
                for l in range(N):
                    s += Pm[i][l] * D[j][k][l] + Pm[j][l] * D[k][i][l] + Pm[k][l] * D[i][j][l]
                if not s.is_zero():
                    return False, f"({i},{j},{k}): {s}", names
    return True, "0", names


def prove_jacobi(system, symbolic_hessian=False, eps_zero=False, perturb=False):
    """Prove the Jacobi identity of Π(x) = J − ε² J Hs J Hs J (of J if ``eps_zero``)
    as a polynomial identity (see :func:`jacobi_residual`); ``perturb``: the negative
    control, a perturbed Π that is not Poisson (``expected`` False)."""
    t0 = time.perf_counter()
    holds, res, names = jacobi_residual(system, symbolic_hessian, eps_zero, perturb)
    scope = "for every admissible Hessian (a, b, c symbolic)" if symbolic_hessian else "for this system"
    tensor = ("J(x)" if eps_zero else "Pi(x)") + (" + eps^2 x0 (E01 - E10)" if perturb else "")
    ring = f"Q[{', '.join(names)}]"
    evidence = (f"symbolic proof: polynomial identity in {ring} {scope}" if holds
                else f"symbolic disproof: a nonzero difference in {ring} {scope}")
    return Check("proof:jacobi" + (":control" if perturb else ""), f"Jacobi identity of {tensor}, n = {system.n}",
                 not perturb, holds, res, "qmpoly[" + ",".join(names) + "]", time.perf_counter() - t0, evidence)
