"""Exact sparse polynomials and rational functions of (x, ε), evaluated in any arithmetic.

A :class:`Polynomial` in the N + 1 variables x_0, …, x_{N-1}, ε is the finite sum

    p(x, ε) = Σ_α c_α x_0^{α_0} ⋯ x_{N-1}^{α_{N-1}} ε^{α_N},   c_α ∈ Q,

stored as a dict exponent tuple α -> Fraction c_α (no zero coefficients).  A
:class:`RationalFunction` is a quotient p/q of two of them; it is a
:class:`~exact_khk.systems.base.Function`: ``fn(ar, x, eps)`` evaluates it in
the arithmetic context ``ar`` (exact rationals, floats, mpmath, balls,
cyclotomic fields, prime fields) and raises :class:`~exact_khk.errors.PoleError`
where q vanishes.  Its gradient is the quotient rule
∂_i(p/q) = (q ∂_i p − p ∂_i q)/q², with the partials computed symbolically once.
A :class:`PolynomialTensor` is a skew matrix Π of rational functions.

>>> from fractions import Fraction as F
>>> from exact_khk.arith import get_arith
>>> x0, x1 = Polynomial.variable(2, 0), Polynomial.variable(2, 1)
>>> eps = Polynomial.variable(2, 2)
>>> I = RationalFunction(x0 * x0 + x1, Polynomial.constant(2, 1) - eps * x0, name="I")
>>> ar = get_arith("fraction")
>>> I(ar, [F(1), F(2)], F(1, 10))
Fraction(10, 3)
>>> I.gradient(ar, [F(1), F(2)], F(1, 10))
[Fraction(70, 27), Fraction(10, 9)]
>>> I.at_eps_zero().num == x0 * x0 + x1
True
>>> I(ar, [F(10), F(0)], F(1, 10))
Traceback (most recent call last):
...
exact_khk.errors.PoleError: I has a pole at x = (10, 0), eps = 1/10: its denominator vanishes (arithmetic fraction)
"""

from __future__ import annotations

from fractions import Fraction
from itertools import combinations
from math import lcm

import flint

from ..arith import _as_fraction
from ..errors import InputError, PoleError, UndecidedError
from .base import Function, Tensor


class Polynomial:
    """p(x_0, …, x_{nx-1}, ε) with exact rational coefficients (see the module doc).

    ``terms`` maps exponent tuples of length ``nx + 1`` (the last one is the
    exponent of ε) to nonzero Fractions.  Instances are treated as immutable.
    """

    __slots__ = ("nx", "terms", "_cache")

    def __init__(self, nx: int, terms=()):
        self.nx = nx
        self.terms = {}
        for exps, c in dict(terms).items():
            exps, c = tuple(int(e) for e in exps), _as_fraction(c)
            if len(exps) != nx + 1 or min(exps, default=0) < 0:
                raise InputError(f"polynomial: exponent {exps} is not a tuple of {nx + 1} naturals")
            c += self.terms.pop(exps, 0)
            if c:
                self.terms[exps] = c
        self._cache = {}

    @classmethod
    def constant(cls, nx: int, c) -> "Polynomial":
        return cls(nx, {(0,) * (nx + 1): c})

    @classmethod
    def variable(cls, nx: int, i: int) -> "Polynomial":
        """x_i, or ε for i = nx."""
        return cls(nx, {tuple(int(k == i) for k in range(nx + 1)): 1})

    # --- algebra (exact, on the coefficient dicts) ---------------------------

    def __add__(self, other):
        out = dict(self.terms)
        for e, c in other.terms.items():
            out[e] = out.get(e, 0) + c
        return Polynomial(self.nx, out)

    def __neg__(self):
        return Polynomial(self.nx, {e: -c for e, c in self.terms.items()})

    def __sub__(self, other):
        return self + (-other)

    def __mul__(self, other):
        out = {}
        for e1, c1 in self.terms.items():
            for e2, c2 in other.terms.items():
                e = tuple(a + b for a, b in zip(e1, e2))
                out[e] = out.get(e, 0) + c1 * c2
        return Polynomial(self.nx, out)

    def scale(self, c) -> "Polynomial":
        c = _as_fraction(c)
        return Polynomial(self.nx, {e: c * v for e, v in self.terms.items()})

    def __eq__(self, other):
        return isinstance(other, Polynomial) and (self.nx, self.terms) == (other.nx, other.terms)

    __hash__ = None

    def __repr__(self):
        return f"Polynomial({self.nx}, {len(self.terms)} terms)"

    def is_zero(self) -> bool:
        return not self.terms

    def constant_value(self):
        """The value as a Fraction if p is constant, else None."""
        if not self.terms:
            return Fraction(0)
        if len(self.terms) == 1:
            (e, c), = self.terms.items()
            return c if not any(e) else None
        return None

    # --- calculus and degrees ------------------------------------------------

    def derivative(self, i: int) -> "Polynomial":
        """∂p/∂x_i (∂p/∂ε for i = nx)."""
        out = {}
        for e, c in self.terms.items():
            if e[i]:
                out[e[:i] + (e[i] - 1,) + e[i + 1:]] = c * e[i]
        return Polynomial(self.nx, out)

    def degree_in_x(self) -> int:
        """Total degree in x (ε not counted); −1 for the zero polynomial."""
        return max((sum(e[:-1]) for e in self.terms), default=-1)

    @property
    def depends_on_eps(self) -> bool:
        return any(e[-1] for e in self.terms)

    def eps_valuation(self):
        """The largest k with ε^k | p (None for p = 0)."""
        return min((e[-1] for e in self.terms), default=None)

    def eps_shift(self, k: int) -> "Polynomial":
        """p / ε^k, then ε set to 0: the coefficient of ε^k when ε^k | p."""
        return Polynomial(self.nx, {e[:-1] + (0,): c for e, c in self.terms.items() if e[-1] == k})

    # --- evaluation --------------------------------------------------------------

    def _compiled(self, ar):
        """(terms, max exponents): coefficients converted into ``ar`` once, cached by name."""
        hit = self._cache.get(ar.name)
        if hit is None:
            terms = [(ar.convert(c), tuple((v, k) for v, k in enumerate(e) if k))
                     for e, c in self.terms.items()]
            top = {}
            for _, factors in terms:
                for v, k in factors:
                    top[v] = max(top.get(v, 0), k)
            hit = self._cache[ar.name] = (terms, top)
        return hit

    def evaluate(self, ar, x, eps):
        """p(x, ε) in ``ar`` (x a sequence of elements, ε an element); powers are
        computed once per variable, then each term is one product.  At a point of
        python-flint rationals the sum is taken over Z (:meth:`_evaluate_over_z`)."""
        values = list(x) + [eps]
        if len(self.terms) > 1 and all(type(v) is flint.fmpq for v in values):
            return self._evaluate_over_z(values)
        terms, top = self._compiled(ar)
        powers = _powers(top, values, ar.one)
        total = ar.zero
        for c, factors in terms:
            for v, k in factors:
                c = c * powers[v][k]
            total = total + c
        return total

    def _evaluate_over_z(self, values):
        """p at fmpq values over one denominator: with v_j = V_j/D and A the total degree,
        p = Σ C_α V^α D^(A − |α|) / (L D^A), C_α = L c_α integers (L the coefficients'
        common denominator): fmpz products and one reduction at the end, where the sum of
        rationals took a gcd per operation (18.8 → 8.2 ms for a degree-12 integral of
        lagrange-top with 58 terms at a 6000-bit point)."""
        hit = self._cache.get("over Z")
        if hit is None:
            L = lcm(*(c.denominator for c in self.terms.values()))
            A = max(sum(e) for e in self.terms)
            terms = [(flint.fmpz(c.numerator * (L // c.denominator)), tuple((v, k) for v, k in enumerate(e) if k),
                      A - sum(e)) for e, c in self.terms.items()]
            top = {}
            for _, factors, _ in terms:
                for v, k in factors:
                    top[v] = max(top.get(v, 0), k)
            hit = self._cache["over Z"] = (terms, top, A, flint.fmpz(L))
        terms, top, A, L = hit
        D = flint.fmpz(1)
        for v in values:
            D = D.lcm(v.q)
        V = [v.p * (D // v.q) for v in values]
        powers = _powers(top, V, flint.fmpz(1))
        dpow = _powers({0: A}, [D], flint.fmpz(1))[0]
        total = flint.fmpz(0)
        for C, factors, r in terms:
            t = C * dpow[r]
            for v, k in factors:
                t = t * powers[v][k]
            total += t
        return flint.fmpq(total, L * dpow[A])


def _powers(top, values, one) -> dict:
    """{v: [1, values[v], …, values[v]^m]} for each (v, m) in ``top``, by repeated products."""
    out = {}
    for v, m in top.items():
        row = [one, values[v]]  # the value itself, not one·value (a rounding in floating contexts)
        for _ in range(m - 1):
            row.append(row[-1] * values[v])
        out[v] = row
    return out


def _show(ar, e) -> str:
    """A short printable form of an element (never fails on huge numbers)."""
    try:
        text = ar.format(e)
    except (ValueError, TypeError):
        return "<number too large to print>"
    return text if len(text) <= 40 else text[:37] + "..."


def _point(ar, x, eps) -> str:
    return f"x = ({', '.join(_show(ar, t) for t in x)}), eps = {_show(ar, eps)}"


def _elements(ar, x, eps):
    """x and ε as elements of ``ar`` (exact Fractions/ints are converted)."""
    conv = (lambda t: ar.convert(t) if isinstance(t, (int, Fraction)) else t)
    return [conv(t) for t in x], conv(eps)


class RationalFunction(Function):
    """f = num/den, two :class:`Polynomial` in the same variables (x, ε).

    A constant denominator is folded into the numerator, so a polynomial has
    ``den == 1`` (``is_polynomial``).  ``name`` labels it in errors; ``text`` is
    the formula as the user wrote it.
    """

    def __init__(self, num: Polynomial, den: Polynomial | None = None, name: str = "?", text: str = ""):
        den = den if den is not None else Polynomial.constant(num.nx, 1)
        if den.nx != num.nx:
            raise InputError(f"{name}: numerator and denominator have different variables")
        c = den.constant_value()
        if c == 0:
            raise InputError(f"{name}: the denominator is identically zero")
        if c is not None and c != 1:
            num, den = num.scale(1 / c), Polynomial.constant(num.nx, 1)
        self.num, self.den, self.name, self.text = num, den, name, text
        self.is_polynomial = c is not None
        self.depends_on_eps = num.depends_on_eps or den.depends_on_eps
        self._partials = None

    @property
    def nx(self) -> int:
        return self.num.nx

    def _denominator(self, ar, x, eps):
        """den(x, ε), checked nonzero: PoleError if it is 0, UndecidedError if a ball contains 0."""
        d = self.den.evaluate(ar, x, eps)
        zero = ar.is_zero(d)
        if zero:
            raise PoleError(f"{self.name} has a pole at {_point(ar, x, eps)}: "
                            f"its denominator vanishes (arithmetic {ar.name})")
        if zero is None:
            raise UndecidedError(f"{ar.name}: cannot decide whether the denominator of {self.name} "
                                 f"vanishes at {_point(ar, x, eps)} (raise the precision)")
        return d

    def _finite(self, ar, values, x, eps):
        """``values``, unless one is not finite (float overflow, or a pole missed in rounding)."""
        if not ar.exact and not all(ar.is_finite(v) for v in values):
            raise PoleError(f"{self.name} is not finite at {_point(ar, x, eps)} in arithmetic "
                            f"{ar.name} (overflow or a pole; try an exact arithmetic or mp:P)")
        return values

    def __call__(self, ar, x, eps):
        """f(x, ε) as an element of ``ar``."""
        x, eps = _elements(ar, x, eps)
        with ar.local():
            n = self.num.evaluate(ar, x, eps)
            if not self.is_polynomial:
                n = n / self._denominator(ar, x, eps)
            return self._finite(ar, [n], x, eps)[0]

    def partials(self):
        """([∂num/∂x_i], [∂den/∂x_i]) as polynomials (computed once)."""
        if self._partials is None:
            self._partials = ([self.num.derivative(i) for i in range(self.nx)],
                              [self.den.derivative(i) for i in range(self.nx)])
        return self._partials

    def gradient(self, ar, x, eps):
        """[∂f/∂x_i] = [(den ∂_i num − num ∂_i den)/den²] in ``ar``."""
        x, eps = _elements(ar, x, eps)
        dnum, dden = self.partials()
        with ar.local():
            grad = [p.evaluate(ar, x, eps) for p in dnum]
            if not self.is_polynomial:
                d = self._denominator(ar, x, eps)
                n, d2 = self.num.evaluate(ar, x, eps), d * d
                grad = [(g * d - n * q.evaluate(ar, x, eps)) / d2 for g, q in zip(grad, dden)]
            return self._finite(ar, grad, x, eps)

    def at_eps_zero(self):
        """The limit ε → 0 as a RationalFunction of x, or None when it has a pole at
        ε = 0 identically.  With ε^k ∥ den and ε^m ∥ num: the limit is
        (num/ε^k)|_{ε=0} / (den/ε^k)|_{ε=0} if m ≥ k, and infinite if m < k."""
        k = self.den.eps_valuation()
        m = self.num.eps_valuation()
        if m is not None and m < k:
            return None
        return RationalFunction(self.num.eps_shift(k), self.den.eps_shift(k),
                                name=self.name, text=f"({self.text}) at eps = 0")

    def __neg__(self):
        return RationalFunction(-self.num, self.den, name=f"-{self.name}", text=f"-({self.text})")

    def equals(self, other) -> bool:
        """Exact equality as rational functions: num·den' = num'·den."""
        return (self.num * other.den - other.num * self.den).is_zero()


class PolynomialTensor(Tensor):
    """A skew N×N matrix Π(x, ε) of :class:`RationalFunction` entries.

    The constructor checks Π_ii = 0 and Π_ij + Π_ji = 0 exactly (as rational
    functions); :meth:`matrix` evaluates the upper triangle only.
    """

    def __init__(self, entries, name: str = "Pi", text: str = ""):
        self.entries = tuple(tuple(row) for row in entries)
        N = self.dim = len(self.entries)
        for i, row in enumerate(self.entries):
            if len(row) != N or any(not isinstance(e, RationalFunction) or e.nx != N for e in row):
                raise InputError(f"{name}: row {i} must hold {N} rational functions of {N} variables")
        for i in range(N):
            if not self.entries[i][i].num.is_zero():
                e = self.entries[i][i]
                raise InputError(f"{name}: diagonal entry [{i}][{i}] = {e.text or e.name} must be 0 "
                                 f"(a Poisson tensor is skew-symmetric)")
            for j in range(i + 1, N):
                a, b = self.entries[i][j], self.entries[j][i]
                if not a.equals(-b):
                    raise InputError(f"{name}: entry [{j}][{i}] = {b.text or b.name} is not minus "
                                     f"entry [{i}][{j}] = {a.text or a.name} (a Poisson tensor is "
                                     f"skew-symmetric)")
        self.name, self.text = name, text
        self.depends_on_eps = any(e.depends_on_eps for row in self.entries for e in row)
        self._upper = [(i, j) for i, j in combinations(range(N), 2) if not self.entries[i][j].num.is_zero()]

    def matrix(self, ar, x, eps):
        """Π(x, ε) as rows of elements of ``ar``."""
        x, eps = _elements(ar, x, eps)
        M = [[ar.zero] * self.dim for _ in range(self.dim)]
        for i, j in self._upper:
            v = self.entries[i][j](ar, x, eps)
            M[i][j], M[j][i] = v, -v
        return M

    def jacobiator(self, ar, x, eps):
        """[Σ_m (Π_im ∂_mΠ_jk + Π_jm ∂_mΠ_ki + Π_km ∂_mΠ_ij) for i < j < k]: all zero
        iff Π satisfies the Jacobi identity at (x, ε)."""
        x, eps = _elements(ar, x, eps)
        N = self.dim
        P = self.matrix(ar, x, eps)
        G = {}
        for i, j in self._upper:
            g = self.entries[i][j].gradient(ar, x, eps)
            G[i, j], G[j, i] = g, [-t for t in g]
        out = []
        with ar.local():
            for i, j, k in combinations(range(N), 3):
                s = ar.zero
                for a, b, c in ((i, j, k), (j, k, i), (k, i, j)):
                    g = G.get((b, c))
                    if g is not None:
                        for m in range(N):
                            s = s + P[a][m] * g[m]
                out.append(s)
        return out
