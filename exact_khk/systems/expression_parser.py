"""The safe expression parser behind system files (:mod:`exact_khk.systems.expressions`).

SymPy's ``parse_expr`` calls Python's ``eval``; this parser never does.  An
expression may contain only the names it is given (variables, parameters,
``eps``), integer and decimal literals (exact: 0.1 = 1/10, 1e-5 = 1/100000), ``+ - * / **`` and
parentheses, with Python's precedence (``^`` is read as ``**``, as SymPy reads it); an exponent is an integer literal with
|e| <= 64, and towers such as ``x**10**9`` are refused.  The value is computed
exactly as a quotient num/den of two polynomials in python-flint's sparse
polynomial ring Q[x_0, ..., x_{N-1}, eps] (``flint.fmpq_mpoly``, lex order; see
:func:`ring`) and reduced to lowest terms with flint's gcd (:func:`cancel`; SymPy
is not imported).  The work spent expanding and the size of the numbers are
budgeted as it goes (:data:`MAX_WORK`, :data:`MAX_BITS`), so a huge power of a
long sum is refused in seconds instead of hanging.  Every refusal is an
:class:`~exact_khk.errors.InputError` naming the field and the offending token.

>>> R = ring(["x", "eps"])
>>> x, eps = R.gens()
>>> Parser("(x**2 - 1)/(x - 1) + 0.5*eps", "demo", R, {"x": x, "eps": eps}, {}, "x, eps").value
(2*x + eps + 2, 2)
>>> Parser("x**10**9", "demo", R, {"x": x}, {}, "x").value
Traceback (most recent call last):
...
exact_khk.errors.InputError: demo: unexpected '**' at position 5 (chained ** is not allowed; use parentheses)
"""

from __future__ import annotations

import re
from fractions import Fraction

import flint

from ..errors import InputError
from ..parsing import MAX_EXPONENT as MAX_DECIMAL_EXPONENT
from .functions import Polynomial

MAX_LENGTH = 100_000      # characters in one expression
MAX_EXPONENT = 64         # |e| in x**e
MAX_DEPTH = 100           # nested parentheses
MAX_WORK = 3_000_000      # term products (weighted by number size) spent on one expression
MAX_BITS = 2_000_000      # size of the numbers
_TOKEN = re.compile(r"\s*(?:((?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)|([A-Za-z_][A-Za-z0-9_]*)|(\*\*|\^|[-+*/()]))")


def ring(names):
    """The polynomial ring Q[names] (a ``flint.fmpq_mpoly_ctx``, lex order in the order of
    ``names``: the order in which terms are printed and leading coefficients are taken)."""
    return flint.fmpq_mpoly_ctx.get(tuple(names), "lex")


#: the ring of constants, for parameter values
CONSTANTS = ring(())


# --- numbers and printing without Python's 4300-digit int <-> str limit ------------


def to_int(digits: str) -> int:
    """int(digits), also beyond Python's 4300-digit limit (through flint)."""
    return int(digits) if len(digits) < 4000 else int(flint.fmpz(digits))


def frac(c) -> Fraction:
    """A Fraction from a ring coefficient (a ``flint.fmpq``; ``int(fmpz)`` has no digit limit)."""
    return Fraction(int(c.p), int(c.q))


def number_text(q) -> str:
    """'p' or 'p/q' for an exact rational."""
    q = Fraction(q)
    return str(flint.fmpz(q.numerator)) if q.denominator == 1 else str(flint.fmpq(q.numerator, q.denominator))


def short_number(q: Fraction) -> str:
    """The rational q for a message: in full, or '<a 5001-digit number>' when huge."""
    n = max(abs(q.numerator), q.denominator)
    if n.bit_length() <= 1000:
        return number_text(q)
    d = int((n.bit_length() - 1) * 0.30102999)
    while n >= 10 ** d:
        d += 1
    return f"<a {d}-digit number>"


def short(text: str) -> str:
    """text on one line, cut to 80 characters."""
    text = " ".join(text.split())
    return text if len(text) <= 80 else text[:77] + "..."


def text_of(p) -> str:
    """A ring polynomial for a message, with ``**`` for powers as in the file syntax
    (e.g. 'x1**2 - 2*x2'; never fails on huge coefficients)."""
    try:
        return short(str(p).replace("^", "**"))
    except ValueError:  # a coefficient beyond the int -> str limit
        return "<a polynomial with very large coefficients>"


def term_text(c, m, names) -> str:
    """c·x^m, e.g. '-2*x2**2*x3'."""
    mono = "*".join(n if k == 1 else f"{n}**{k}" for n, k in zip(names, m) if k)
    c = frac(c)
    if mono and c in (1, -1):
        return ("-" if c < 0 else "") + mono
    return f"{short_number(c)}*{mono}" if mono else short_number(c)


def bits_of(p) -> int:
    """The size in bits of the largest coefficient of a ring polynomial."""
    return max((c.p.bit_length() + c.q.bit_length() for c in p.coeffs()), default=0)


# --- ring polynomials ------------------------------------------------------------------


def terms(p) -> list:
    """The terms of a ring polynomial as [(exponent tuple of ints, fmpq coefficient)], leading
    term first (flint's exponents are fmpz)."""
    return [(tuple(map(int, m)), c) for m, c in zip(p.monoms(), p.coeffs())]


def lc(p):
    """The leading coefficient (lex order) of a ring polynomial, 0 for the zero polynomial."""
    return p.leading_coefficient()


def cancel(num, den) -> tuple:
    """num/den in lowest terms, in the canonical form SymPy's ``cancel`` gives over Q:
    num and den coprime, with integer coefficients whose common gcd is 1, and den's
    leading coefficient positive; (0, 1) if num = 0.

    >>> R = ring(["x", "y"])
    >>> x, y = R.gens()
    >>> cancel((x**2 - y**2) / 6, (2*y - 2*x) / 9)
    (-3*x - 3*y, 4)
    """
    R = num.context()
    if not num:
        return num, R.constant(1)
    g = num.gcd(den)
    if not g.is_one():
        num, den = num / g, den / g  # exact divisions
    cs = num.coeffs() + den.coeffs()
    q, p = flint.fmpz(1), flint.fmpz(0)
    for c in cs:
        q, p = q.lcm(c.q), p.gcd(c.p)
    scale = flint.fmpq(q, p) if lc(den) > 0 else -flint.fmpq(q, p)
    return (num, den) if scale == 1 else (num * scale, den * scale)


# --- the safe parser ---------------------------------------------------------------


class Parser:
    """Recursive descent over whitelisted tokens; every value is a pair (num, den) of
    elements of the polynomial ring ``R`` (a ``flint.fmpq_mpoly_ctx``, see :func:`ring`).

    ``names`` maps each allowed name to a ring element (a generator, or a
    parameter's value); ``refused`` maps names declared but not allowed here to
    the reason.  After :meth:`parse`, ``value`` is (num, den) in lowest terms and
    ``summands`` lists the top-level terms as (source text, (num, den)).
    """

    def __init__(self, text: str, where: str, R, names: dict, refused: dict, allowed: str):
        self.where, self.text, self.R, self.names, self.work = where, text, R, names, 0
        self.one = R.constant(1)
        if not isinstance(text, str):
            self.fail(f"expected a string, got {text!r}")
        if len(text) > MAX_LENGTH:
            self.fail(f"the expression has {len(text)} characters (limit {MAX_LENGTH})")
        self.tokens, pos = [], 0
        while (m := _TOKEN.match(text, pos)) and m.end() > pos:
            num, name, op = m.groups()
            at = m.start(m.lastindex)
            if name is not None and name not in names:
                self.fail(refused[name] if name in refused else
                          f"unknown name {name!r} at position {at} ({allowed})")
            op = "**" if op == "^" else op  # x^2 reads as x**2, as SymPy's parse_expr reads it
            self.tokens.append(("num" if num else "name" if name else "op", num or name or op, at))
            pos = m.end()
        if text[pos:].strip():
            pos += len(text[pos:]) - len(text[pos:].lstrip())
            self.fail(f"character {text[pos]!r} at position {pos} is not allowed; expressions "
                      f"use names, numbers, + - * / ** (or ^) and parentheses only")
        self.i, self.summands = 0, []
        self.value = self.parse()

    def fail(self, message):
        raise InputError(f"{self.where}: {message}")

    def peek(self):
        return self.tokens[self.i][1] if self.i < len(self.tokens) else None

    def take(self):
        if self.i >= len(self.tokens):
            self.fail("the expression ends too early" if self.tokens else "empty expression")
        self.i += 1
        return self.tokens[self.i - 1]

    def parse(self):
        num, den = self.sum(0)
        if self.i < len(self.tokens):
            _, tok, pos = self.tokens[self.i]
            self.fail(f"unexpected {tok!r} at position {pos}" + (
                " (chained ** is not allowed; use parentheses)" if tok == "**" else ""))
        return cancel(num, den)

    # --- grammar: sum := product (('+'|'-') product)*, product := unary (('*'|'/') unary)*,
    #     unary := ('+'|'-')* power, power := atom ('**' integer)?, atom := number | name | '(' sum ')'

    def sum(self, depth):
        start = self.i
        value = self.product(depth)
        terms = [(start, value)]
        while self.peek() in ("+", "-"):
            sign = self.take()[1]
            start = self.i
            rhs = self.product(depth)
            terms.append((start, rhs))
            value = self.add(value, rhs if sign == "+" else (-rhs[0], rhs[1]))
        if depth == 0:
            ends = [self.tokens[s][2] for s, _ in terms[1:]] + [len(self.text)]
            self.summands = [(self.text[self.tokens[s][2]:e].rstrip(" +-"), v) for (s, v), e in zip(terms, ends)]
        return value

    def product(self, depth):
        value = self.unary(depth)
        while self.peek() in ("*", "/"):
            op, rhs = self.take()[1], self.unary(depth)
            value = self.times(value, rhs) if op == "*" else self.times(value, self.inverse(rhs))
        return value

    def unary(self, depth):
        sign = 1
        while self.peek() in ("+", "-"):
            sign = -sign if self.take()[1] == "-" else sign
        num, den = self.power(depth)
        return (num, den) if sign > 0 else (-num, den)

    def power(self, depth):
        value = self.atom(depth)
        if self.peek() != "**":
            return value
        self.take()
        paren = self.peek() == "("
        if paren:
            self.take()
        sign = -1 if self.peek() in ("+", "-") and self.take()[1] == "-" else 1
        kind, tok, pos = self.take()
        if kind != "num" or not tok.isdigit():
            self.fail(f"exponent {tok!r} at position {pos} is not an integer literal")
        if len(tok) > 3 or int(tok) > MAX_EXPONENT:
            self.fail(f"exponent {tok[:20]} at position {pos} is too large (|exponent| <= {MAX_EXPONENT})")
        if paren and self.take()[1] != ")":
            self.fail(f"the exponent at position {pos} must be an integer literal")
        e = int(tok)
        value = self.inverse(value) if sign < 0 else value
        result = (self.one, self.one)
        while e:  # binary powering, every product budgeted
            if e & 1:
                result = self.times(result, value)
            e >>= 1
            if e:
                value = self.times(value, value)
        return result

    def atom(self, depth):
        kind, tok, pos = self.take()
        if kind == "num":
            mantissa, _, exp = tok.lower().partition("e")
            if exp and (len(exp) > 6 or abs(int(exp)) > MAX_DECIMAL_EXPONENT):
                self.fail(f"the exponent of {tok[:30]} at position {pos} is beyond the limit of "
                          f"{MAX_DECIMAL_EXPONENT}")
            whole, _, frac = mantissa.partition(".")
            shift = int(exp or 0) - len(frac)
            num, den = to_int(whole + frac) * 10 ** max(shift, 0), 10 ** max(-shift, 0)
            return self.R.constant(flint.fmpq(num, den)), self.one
        if kind == "name":
            return self.names[tok], self.one
        if tok != "(":
            self.fail(f"unexpected {tok!r} at position {pos}")
        if depth >= MAX_DEPTH:
            self.fail(f"parentheses nested deeper than {MAX_DEPTH}")
        value = self.sum(depth + 1)
        if self.peek() != ")":
            self.fail(f"missing ')' for the '(' at position {pos}")
        self.take()
        return value

    # --- exact arithmetic on (num, den), within the budget ------------------------

    def spend(self, work):
        self.work += work
        if self.work > MAX_WORK:
            self.fail(f"the expression is too large to expand (over {MAX_WORK} term operations)")

    def cost(self, p, q):
        """Spend the work of a product (or division) of p and q: term pairs, weighted by
        the size of the numbers."""
        bits = bits_of(p) + bits_of(q)
        if bits > MAX_BITS:
            self.fail(f"the numbers in this expression are too large (over {MAX_BITS} bits)")
        self.spend(len(p) + len(q) + len(p) * len(q) * (1 + bits // 1024))

    def mul(self, p, q):
        self.cost(p, q)
        return p * q

    def add(self, a, b):
        """a + b over a common denominator: the larger one if the other divides it."""
        self.spend(len(a[0]) + len(b[0]) + len(a[1]))
        if a[1] == b[1]:
            return a[0] + b[0], a[1]
        for (p, P), (q, Q) in ((a, b), (b, a)):
            if len(Q) <= len(P):
                self.cost(P, Q)
                quo, rem = divmod(P, Q)
                if not rem:  # p/P + q/Q = (p + q·(P/Q))/P
                    return p + self.mul(q, quo), P
        return self.mul(a[0], b[1]) + self.mul(b[0], a[1]), self.mul(a[1], b[1])

    def times(self, a, b):
        return self.mul(a[0], b[0]), self.mul(a[1], b[1])

    def inverse(self, a):
        if not a[0]:
            self.fail("division by zero")
        return a[1], a[0]


# --- exact objects from parsed expressions --------------------------------------------


def to_polynomial(p, nx: int) -> Polynomial:
    """A ring polynomial in (x_0, ..., x_{nx-1}, eps) as an exact :class:`Polynomial`."""
    return Polynomial(nx, {m: frac(c) for m, c in terms(p)})


def checked_polynomial(parsed: Parser, names, max_degree: int, where: str, why: str):
    """The value of ``parsed`` as one ring polynomial; InputError naming the first term that
    is not a polynomial, or has degree > max_degree in the variables ``names``."""
    num, den = parsed.value
    if not den.is_constant():
        bad = next((t for t, (n, d) in parsed.summands if not cancel(n, d)[1].is_constant()), parsed.text)
        raise InputError(f"{where}: term {short(bad)} is not a polynomial in the variables; {why}")
    p = num / lc(den)
    for m, c in sorted(terms(p), reverse=True):
        if sum(m[:len(names)]) > max_degree:
            raise InputError(f"{where}: term {term_text(c, m, names)} has degree {sum(m[:len(names)])}; {why}")
    return p
