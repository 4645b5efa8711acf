"""Exact fit of a degree sequence: the shortest linear recurrence, the dynamical
degree as an algebraic number, and the growth class.

**The fit.**  Berlekamp–Massey over Q gives the shortest recurrence
s_k = c_1 s_{k-1} + … + c_L s_{k-L} (k ≥ L) satisfied by *all* given terms,
i.e. the generating function Σ s_k z^k = N(z)/C(z) with
C(z) = 1 − c_1 z − … − c_L z^L of least order.  If the infinite integer sequence
has a rational generating function, its reduced denominator has integer
coefficients and C(0) = 1 (Fatou's lemma), so a fit with a non-integer c_i is
not the sequence's recurrence: it is refused.  The recurrence is determined by
the first F = max(2L, j + 1) terms (j: the last term at which Berlekamp–Massey
changed it; a recurrence of order L is unique once 2L terms are known); the
remaining terms were *predicted*, not fitted.  A growth class needs at least
max(``confirm``, L) such terms: a recurrence of order L must predict as many terms as
its order before it is believed.  The rule is measured on the degrees of Sage's
doctest map [Z², XY, Y²] (not linearly recurrent: d_k = 2^k − Σ_j min_i (A^k)_ij
for its exponent matrix A, λ = √2): Berlekamp–Massey finds an order-14 recurrence
on its first 28 terms that predicts the next 7 and gives λ ≈ 1.41457 — wrong, and
unconfirmed under this rule (tests/test_classify.py).

**Growth.**  χ(x) = x^L C(1/x) is monic in Z[x]; since the recurrence is minimal,
every nonzero root of χ occurs in s_k.  Factor χ over Z: an irreducible factor
other than x that is not cyclotomic has a root of modulus > 1 (Kronecker:
a monic integer polynomial with all roots in the closed unit disc and nonzero
constant term has only roots of unity), so the growth is **exponential**, and
the dynamical degree λ = lim d_k^{1/k} is the largest modulus of a root, which
is a positive real root (Pringsheim: the generating function has nonnegative
coefficients).  Otherwise all nonzero roots are roots of unity, λ = 1 and the
growth is **polynomial** of degree e − 1 (e the largest multiplicity of a root
of unity), **bounded** when e = 1.

λ is reported by its minimal polynomial (the irreducible factor of χ having
it as a root) and a certified decimal enclosure: SymPy's exact real-root
isolation (rational intervals, refined), rounded outwards.

>>> fit = fit_recurrence([1, 2, 4, 8, 16, 32, 64])
>>> fit.coefficients, fit.growth, fit.dynamical_degree.minimal_polynomial
((2,), 'exponential', 'x - 2')
>>> fib = fit_recurrence([1, 1, 2, 3, 5, 8, 13, 21, 34])
>>> fib.dynamical_degree.enclosure
('1.6180339887', '1.6180339888')
>>> fit_recurrence([1, 3, 9, 19, 33, 51, 73, 99, 129]).polynomial
'2*k^2 + 1'
>>> short = fit_recurrence([1, 3, 9, 19, 33])
>>> short.growth, short.confirmed_on
('undetermined', 0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import flint

from exact_khk.errors import InputError
from exact_khk.parsing import any_int_digits, poly_text as _poly_text

DIGITS = 10


def berlekamp_massey(seq):
    """(C, L, j): connection polynomial C = [1, C_1, …, C_L] over Q (Σ C_i s_{n-i} = 0
    for n ≥ L), the order L, and the index j of the last term that changed C (−1 if none).

    >>> berlekamp_massey([1, 1, 2, 3, 5, 8])
    ([Fraction(1, 1), Fraction(-1, 1), Fraction(-1, 1)], 2, 2)
    """
    s = [Fraction(v) for v in seq]
    C, B = [Fraction(1)], [Fraction(1)]
    L, m, b, last = 0, 1, Fraction(1), -1
    for n in range(len(s)):
        d = s[n] + sum((C[i] * s[n - i] for i in range(1, min(L, len(C) - 1) + 1)), Fraction(0))
        if d == 0:
            m += 1
            continue
        T = list(C)
        coef = d / b
        C = C + [Fraction(0)] * max(0, len(B) + m - len(C))
        for i, bi in enumerate(B):
            C[i + m] -= coef * bi
        last = n
        if 2 * L <= n:
            L, B, b, m = n + 1 - L, T, d, 1
        else:
            m += 1
    C = (C + [Fraction(0)] * (L + 1))[:L + 1]
    return C, L, last


@dataclass(frozen=True)
class DynamicalDegree:
    """λ as an algebraic number: minimal polynomial, certified enclosure [lo, hi]
    (decimal strings, rounded outwards), and a float."""

    minimal_polynomial: str
    coefficients: tuple   # of the minimal polynomial, highest degree first
    enclosure: tuple
    value: float

    @any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
    def to_json(self) -> dict:
        return {"minimal_polynomial": self.minimal_polynomial, "coefficients": list(self.coefficients),
                "enclosure": list(self.enclosure), "value": self.value}


@dataclass(frozen=True)
class RecurrenceFit:
    """The shortest recurrence of a sequence and what it says (module docstring).

    ``growth`` is 'bounded', 'polynomial', 'exponential' or 'undetermined' (then
    ``reason`` says why); ``polynomial_degree`` the degree of polynomial growth;
    ``polynomial`` a closed form such as '2*k^2 + 1' when the roots of unity are
    all 1."""

    sequence: tuple
    order: int
    coefficients: tuple
    characteristic: tuple       # χ, highest degree first
    fitted_on: int
    confirmed_on: int
    growth: str
    polynomial_degree: int | None
    polynomial: str | None
    dynamical_degree: DynamicalDegree | None
    reason: str

    @property
    def confirmed(self) -> bool:
        return self.growth != "undetermined"

    @property
    def determined(self) -> bool:
        """Whether the terms determine the fitted recurrence (a recurrence of order L is
        unique once 2L terms are known; :func:`too_short` fits nothing)."""
        return self.fitted_on <= len(self.sequence) and (self.order > 0 or not any(self.sequence))

    def characteristic_text(self) -> str:
        return poly_text(self.characteristic)

    @any_int_digits()
    def to_json(self) -> dict:
        return {"order": self.order, "coefficients": [str(c) for c in self.coefficients],
                "characteristic_polynomial": self.characteristic_text(), "fitted_on": self.fitted_on,
                "confirmed_on": self.confirmed_on, "growth": self.growth,
                "polynomial_degree": self.polynomial_degree, "polynomial": self.polynomial,
                "dynamical_degree": self.dynamical_degree.to_json() if self.dynamical_degree else None,
                "reason": self.reason}

    @any_int_digits()
    def summary(self) -> str:
        if not self.determined:  # no recurrence is stated that the terms do not determine
            return f"recurrence: not determined\ngrowth: not classified ({self.reason})"
        terms = [(c, f"d[k-{i}]") for i, c in enumerate(self.coefficients, 1) if c]
        rec = _linear_text(terms)
        out = [f"recurrence d[k] = {rec} (order {self.order}; chi(x) = {self.characteristic_text()}), "
               f"fitted on {self.fitted_on} terms, confirmed on {self.confirmed_on} more"]
        if self.growth == "undetermined":
            out.append(f"growth: not classified ({self.reason})")
            return "\n".join(out)
        g = self.growth
        if g == "polynomial":
            g += f" of degree {self.polynomial_degree}" + (f": d_k = {self.polynomial}" if self.polynomial else "")
        dd = self.dynamical_degree
        out.append(f"growth: {g}; dynamical degree {dd.minimal_polynomial} = 0, "
                   f"lambda in [{dd.enclosure[0]}, {dd.enclosure[1]}]")
        return "\n".join(out)


def poly_text(coeffs, var="x") -> str:
    """'x^2 - x - 1' from integer coefficients, highest degree first.

    >>> poly_text([1, 0, -3, 2])
    'x^3 - 3*x + 2'
    """
    return _poly_text([Fraction(c) for c in coeffs], var, ascending=False)


def _linear_text(terms) -> str:
    """'3*d[k-1] - 3*d[k-2] + d[k-3]' from (coefficient, name) pairs."""
    out = ""
    for c, name in terms:
        c = Fraction(c)
        body = name if abs(c) == 1 else f"{_frac_text(abs(c))}*{name}"
        out += (("-" if c < 0 else "") + body) if not out else (f" - {body}" if c < 0 else f" + {body}")
    return out or "0"


def _frac_text(q: Fraction) -> str:
    return str(q) if q.denominator == 1 else f"({q})"


def _enclosure(coeffs, digits=DIGITS):
    """(lo, hi, value) of the largest real root of the integer polynomial, certified."""
    import sympy

    x = sympy.Symbol("x")
    poly = sympy.Poly([int(c) for c in coeffs], x)
    ivs = poly.intervals(eps=Fraction(1, 10 ** (digits + 2)))
    (a, b), _ = max(ivs, key=lambda iv: iv[0][1])
    a, b = Fraction(int(a.p), int(a.q)), Fraction(int(b.p), int(b.q))
    scale = 10 ** digits
    lo, hi = math.floor(a * scale), math.ceil(b * scale)
    fmt = lambda n: f"{'-' if n < 0 else ''}{abs(n) // scale}.{abs(n) % scale:0{digits}d}"  # noqa: E731
    return fmt(lo), fmt(hi), float((a + b) / 2)


def _dd_from_factor(factor) -> DynamicalDegree:
    coeffs = tuple(int(c) for c in reversed(factor.coeffs()))
    lo, hi, val = _enclosure(coeffs)
    return DynamicalDegree(poly_text(coeffs), coeffs, (lo, hi), val)


def too_short(sequence, reason) -> RecurrenceFit:
    """An unclassified fit of a sequence too short to fit anything."""
    seq = tuple(int(v) for v in sequence)
    return RecurrenceFit(seq, 0, (), (1,), len(seq), 0, "undetermined", None, None, None, reason)


def fit_recurrence(sequence, confirm: int = 3) -> RecurrenceFit:
    """Fit, confirm and classify a sequence of nonnegative integers (module docstring).

    Raises :class:`InputError` when the sequence cannot even be confirmed by an
    order-1 recurrence (fewer than ``confirm`` + 2 terms) or is not made of
    nonnegative integers."""
    if isinstance(confirm, bool) or not isinstance(confirm, int) or confirm < 1:
        raise InputError(f"confirm: expected a positive integer, got {confirm!r}")
    try:
        seq = tuple(int(v) for v in sequence)
    except (TypeError, ValueError):
        raise InputError(f"sequence: expected integers, got {sequence!r}"[:200]) from None
    if any(v != w for v, w in zip(seq, sequence)) or any(v < 0 for v in seq):
        raise InputError("sequence: expected nonnegative integers (degrees)")
    if len(seq) < confirm + 2:
        raise InputError(f"sequence: {len(seq)} terms are too short to fit and confirm a recurrence "
                         f"(need at least {confirm + 2})")
    C, L, last = berlekamp_massey(seq)
    coefficients = tuple(-c for c in C[1:])
    fitted = max(2 * L, last + 1)
    confirmed_on = len(seq) - fitted
    chi = tuple(C)
    base = dict(sequence=seq, order=L, coefficients=tuple(int(c) if c.denominator == 1 else c for c in coefficients),
                characteristic=tuple(int(c) if c.denominator == 1 else c for c in chi), fitted_on=fitted,
                confirmed_on=max(confirmed_on, 0))
    undetermined = dict(growth="undetermined", polynomial_degree=None, polynomial=None, dynamical_degree=None)
    if fitted > len(seq):
        return RecurrenceFit(**base, **undetermined,
                             reason=f"sequence too short: the shortest recurrence of its {len(seq)} terms has "
                                    f"order {L}, which only {fitted} terms determine (need {fitted + confirm} "
                                    f"terms to fit and confirm it)")
    need = max(confirm, L)
    if confirmed_on < need:
        return RecurrenceFit(**base, **undetermined,
                             reason=f"sequence too short: the order-{L} recurrence is determined by the first "
                                    f"{fitted} terms and only {max(confirmed_on, 0)} later term(s) confirm it "
                                    f"(need {need}: max(confirm = {confirm}, the order))")
    if any(c.denominator != 1 for c in chi):
        return RecurrenceFit(**base, **undetermined,
                             reason="the shortest recurrence has non-integer coefficients, so it is not the "
                                    "recurrence of the whole sequence (Fatou's lemma): more terms are needed")
    if all(v == 0 for v in seq):
        return RecurrenceFit(**base, growth="bounded", polynomial_degree=0, polynomial="0",
                             dynamical_degree=None, reason="")
    _, factors = flint.fmpz_poly([int(c) for c in reversed(chi)]).factor()
    x = flint.fmpz_poly([0, 1])
    growing = [f for f, _ in factors if f != x and not f.is_cyclotomic()]
    if growing:
        dds = [_dd_from_factor(f) for f in growing]
        dd = max(dds, key=lambda d: d.value)
        return RecurrenceFit(**base, growth="exponential", polynomial_degree=None, polynomial=None,
                             dynamical_degree=dd, reason="")
    e = max(m for f, m in factors if f != x)
    zeros = sum(m for f, m in factors if f == x)
    only_one = all(f == x or f == x - 1 for f, _ in factors)
    formula = _polynomial(seq, zeros, e) if only_one else None
    one = DynamicalDegree("x - 1", (1, -1), ("1." + "0" * DIGITS, "1." + "0" * DIGITS), 1.0)
    return RecurrenceFit(**base, growth="bounded" if e == 1 else "polynomial", polynomial_degree=e - 1,
                         polynomial=formula, dynamical_degree=one, reason="")


def _polynomial(seq, start, e):
    """The polynomial of degree e − 1 in k through s_start..s_{start+e-1}, as text
    (valid for k ≥ start), by Lagrange interpolation over Q."""
    pts = list(range(start, start + e))
    coeffs = [Fraction(0)] * e   # coefficient of k^i
    for i, ki in enumerate(pts):
        basis = [Fraction(1)]
        den = Fraction(1)
        for kj in pts:
            if kj == ki:
                continue
            basis = [Fraction(0)] + basis
            for t in range(len(basis) - 1):
                basis[t] -= kj * basis[t + 1]
            den *= ki - kj
        for t, b in enumerate(basis):
            coeffs[t] += seq[ki] * b / den
    text = poly_text(list(reversed(coeffs)), "k")
    return text if start == 0 else f"{text} for k >= {start}"
