"""The exact fields of the verifier — Q (python-flint ``fmpq``, or Fractions), Q(ζ_N)
(``fmpq_poly`` modulo Φ_N), F_P (``nmod``) — with no arithmetic context of the library,
plain Gaussian elimination over them, dual numbers for exact derivatives, and a tiny
evaluator of the system's expression text.

Elements support ``+ - * /`` and ``==``; a quantity that does not exist at a point
(division by zero, a pole, a singular step) raises :class:`Undefined`.
"""

from __future__ import annotations

import re
import unicodedata

import flint
from fractions import Fraction
from functools import lru_cache

from exact_khk.errors import InputError
from exact_khk.parsing import parse_rational

#: arithmetics whose elements are exact rationals printed 'p' or 'p/q'
RATIONAL_ARITHS = ("fraction", "gmpy2", "flint")
#: longest detail shown for one number (longer ones are abbreviated)
_SHOW_BITS = 2000


class Undefined(Exception):
    """A quantity that does not exist at a point (division by zero, a pole, a singular step)."""


# --- exact fields: Q, Q(zeta_N), F_P --------------------------------------------------


def _show(e) -> str:
    """A field element for a message (huge numbers abbreviated, never str() of a huge int)."""
    if isinstance(e, (Fraction, flint.fmpq)):
        num, den = (e.numerator, e.denominator) if isinstance(e, Fraction) else (e.p, e.q)
        bits = max(abs(num).bit_length(), den.bit_length())
        if bits > _SHOW_BITS:
            return f"<a rational of about {int(bits * 0.30103) + 1} digits>"
    return str(e)


def to_fraction(t) -> Fraction:
    """An element of Q (python-flint ``fmpq``) as a Fraction."""
    return Fraction(int(t.p), int(t.q)) if isinstance(t, flint.fmpq) else Fraction(t)


class _Rationals:
    """Q: elements are Fractions."""

    name = "Q"
    evidence = "exact in Q"
    one, zero = Fraction(1), Fraction(0)

    def of(self, q):
        return to_fraction(q)

    def parse(self, text: str, where: str):
        return self.of(parse_rational(text, where))

    def root_of_unity(self, n: int):
        if n <= 2:
            return self.of(-1 if n == 2 else 1)
        raise Undefined(f"{self.name} has no primitive {n}-th root of unity")


class _FlintRationals(_Rationals):
    """Q with python-flint ``fmpq`` elements (exact rationals in GMP: Fractions are ten times
    slower on the numbers of long orbits); the field of the rational certificates."""

    one, zero = flint.fmpq(1), flint.fmpq(0)

    def of(self, q):
        if isinstance(q, flint.fmpq):
            return q
        q = Fraction(q)
        return flint.fmpq(q.numerator, q.denominator)


@lru_cache(maxsize=None)
def cyclotomic_polynomial(N: int) -> tuple:
    """Φ_N as integer coefficients, constant term first (python-flint's ``fmpz_poly.cyclotomic``).

    >>> cyclotomic_polynomial(3), cyclotomic_polynomial(4)
    ((1, 1, 1), (1, 0, 1))
    """
    return tuple(int(t) for t in flint.fmpz_poly.cyclotomic(N).coeffs())


class _Cyclotomic:
    """Q(ζ_N): elements are :class:`_Cyc`, polynomials in z = ζ_N reduced modulo Φ_N (the printing
    of ``cyclo:N``: '1/3 - 2/3*z + z^2')."""

    _TERM = re.compile(r"\s*([+-]?)\s*(?:(\d+(?:/\d+)?)(\*z(?:\^(\d+))?)?|z(?:\^(\d+))?)\s*")

    def __init__(self, N: int):
        self.N, self.name = N, f"Q(zeta_{N})"
        self.evidence = f"exact in Q(zeta_{N})"
        self.poly = flint.fmpq_poly(list(cyclotomic_polynomial(N)))
        self.one, self.zero = self.of(1), self.of(0)

    def of(self, q, k: int = 0):
        """q z^k."""
        q = Fraction(q)
        return _Cyc(self, flint.fmpq_poly([0] * k + [flint.fmpq(q.numerator, q.denominator)]) % self.poly)

    def parse(self, text: str, where: str):
        if not isinstance(text, str) or not text.strip():
            raise InputError(f"{where}: expected an element of {self.name} such as '1/3 - 2/3*z', got {text!r}")
        out, pos = self.zero, 0
        while pos < len(text):
            m = self._TERM.match(text, pos)
            if m is None or m.end() == pos or (pos and not m.group(1)):
                raise InputError(f"{where}: {text[:60]!r} is not an element of {self.name} "
                                 f"(expected terms such as '1/3', '- 2/3*z', '+ z^2')")
            sign, num, zpart, e1, e2 = m.groups()
            if num is not None:
                c, k = parse_rational(num, where), 0 if zpart is None else int(e1 or 1)
            else:
                c, k = Fraction(1), int(e2 or 1)
            out, pos = out + self.of(-c if sign == "-" else c, k), m.end()
        return out

    def root_of_unity(self, n: int):
        if self.N % n:
            raise Undefined(f"{self.name} contains no primitive {n}-th root of unity")
        return self.of(1, self.N // n)


def _cyc_op(fn):
    """A binary operation of :class:`_Cyc` on python-flint polynomials: ``fn(self, other, the field)``."""
    def op(self, o):
        b = _poly(o)
        return NotImplemented if b is None else _Cyc(self.K, fn(self.p, b, self.K))
    return op


def _poly(o):
    """An element of Q(ζ_N), an int or a Fraction as a python-flint polynomial (None for another type)."""
    return o.p if isinstance(o, _Cyc) else flint.fmpq_poly([o]) if isinstance(o, int) else \
        flint.fmpq_poly([flint.fmpq(o.numerator, o.denominator)]) if isinstance(o, Fraction) else None


def _inverse(b, K):
    if b.is_zero():
        raise ZeroDivisionError(f"division by zero in {K.name}")
    g, s, _ = b.xgcd(K.poly)  # Φ_N is irreducible: g is a nonzero constant
    return s / g.coeffs()[0]


class _Cyc:
    """An element of Q(ζ_N): a python-flint ``fmpq_poly`` ``p`` in z of degree < φ(N), reduced modulo Φ_N."""

    __slots__ = ("K", "p")

    def __init__(self, K, p):
        self.K, self.p = K, p

    @property
    def c(self) -> tuple:
        """The coefficients as Fractions, constant term first."""
        return tuple(Fraction(int(t.p), int(t.q)) for t in self.p.coeffs())

    __add__ = __radd__ = _cyc_op(lambda a, b, K: a + b)
    __sub__ = _cyc_op(lambda a, b, K: a - b)
    __rsub__ = _cyc_op(lambda a, b, K: b - a)
    __mul__ = __rmul__ = _cyc_op(lambda a, b, K: a * b % K.poly)
    __truediv__ = _cyc_op(lambda a, b, K: a * _inverse(b, K) % K.poly)
    __rtruediv__ = _cyc_op(lambda a, b, K: b * _inverse(a, K) % K.poly)
    __hash__ = None

    def __eq__(self, o):
        b = _poly(o)
        return NotImplemented if b is None else self.p == b

    def __neg__(self):
        return _Cyc(self.K, -self.p)

    def __bool__(self):
        return not self.p.is_zero()

    def __str__(self):
        parts = [(("-" if t < 0 else "+"), (_show(abs(t)) if k == 0 else
                  ("" if abs(t) == 1 else _show(abs(t)) + "*") + ("z" if k == 1 else f"z^{k}")))
                 for k, t in enumerate(self.c) if t]
        if not parts:
            return "0"
        return ("-" if parts[0][0] == "-" else "") + parts[0][1] + "".join(f" {s} {b}" for s, b in parts[1:])


class _PrimeField:
    """F_P, P a prime (checked by :func:`exact_field`): elements are python-flint ``nmod`` (printed
    as the residue in [0, P))."""

    def __init__(self, P: int):
        self.P, self.name = P, f"F_{P}"
        self.evidence = f"modular: exact in F_{P} (zero mod P is evidence, not proof)"
        self.one, self.zero = flint.nmod(1, P), flint.nmod(0, P)

    def of(self, q):
        q = Fraction(q)
        if q.denominator % self.P == 0:
            raise Undefined(f"{_show(q)} has no value mod {self.P} (its denominator is divisible by P)")
        return flint.nmod(q.numerator, self.P) / q.denominator

    def parse(self, text: str, where: str):
        if not isinstance(text, str) or not re.fullmatch(r"\d{1,40}", text.strip()) or int(text) >= self.P:
            raise InputError(f"{where}: {str(text)[:60]!r} is not a residue mod {self.P} (an integer in [0, P))")
        return flint.nmod(int(text), self.P)

    def root_of_unity(self, n: int):
        """g^((P-1)/n), g the least primitive root mod P (the embedding of ``gf:P``)."""
        if (self.P - 1) % n:
            raise Undefined(f"F_{self.P} contains no primitive {n}-th root of unity (P != 1 mod {n})")
        return flint.nmod(pow(_least_primitive_root(self.P), (self.P - 1) // n, self.P), self.P)


@lru_cache(maxsize=None)
def _least_primitive_root(P: int) -> int:
    import sympy

    if P == 2:
        return 1
    qs = list(sympy.factorint(P - 1))
    g = 2
    while any(pow(g, (P - 1) // q, P) == 1 for q in qs):
        g += 1
    return g


#: the largest N of a ``cyclo:N`` certificate re-checked: the library's own limit
#: (:data:`exact_khk.arith.cyclotomic.MAX_CYCLOTOMIC_N`, not imported: this module stands alone)
MAX_CYCLOTOMIC_N = 10_000
#: the library's limits of ``gf:P`` (a prime 5 <= P < 2^64) and of ``mp:P``, ``ball:P`` (2 to 10^6 bits)
GF_PRIMES, PRECISION_BITS = (5, 2 ** 64), (2, 1_000_000)
#: the names of the library's arithmetics
ARITH_NAMES = "fraction, gmpy2, flint, cyclo:N, gf:P, float, mp:P, ball:P"


def exact_field(arith: str):
    """The field in which a certificate computed in ``arith`` is re-checked, or None
    for an inexact arithmetic (floating point, balls); InputError for a name that is
    no arithmetic of the library."""
    if arith in RATIONAL_ARITHS:
        return _FlintRationals()
    if arith == "float":
        return None
    prefix, _, param = arith.partition(":")
    if prefix not in ("cyclo", "gf", "mp", "ball"):
        raise _invalid_name(arith, f"unknown; known: {ARITH_NAMES}")
    if not re.fullmatch(r"[0-9]+", param, re.ASCII):
        raise _invalid_name(arith, f"{prefix}: must be followed by an integer in ASCII digits")
    value = int(param) if len(param) <= 30 else 10 ** 30  # a longer one is beyond every limit below
    if prefix in ("mp", "ball"):
        low, high = PRECISION_BITS
        if not low <= value <= high:
            raise _invalid_name(arith, f"the precision P of {prefix}:P is from {low} to {high} bits")
        return None
    if prefix == "gf":
        import sympy

        low, high = GF_PRIMES
        if not (low <= value < high and sympy.isprime(value)):
            raise _invalid_name(arith, f"gf:P needs a prime P with {low} <= P < 2^64")
        return _PrimeField(value)
    if value < 1:
        raise _invalid_name(arith, "cyclo:N needs N >= 1")
    if value > MAX_CYCLOTOMIC_N:  # as get_arith: Φ_N has degree φ(N)
        raise Undefined(f"cyclo:{param[:40]}: N is above {MAX_CYCLOTOMIC_N}, the largest cyclo:N this "
                         "library computes in (not checkable)")
    return _Cyclotomic(value)


def _invalid_name(arith: str, why: str) -> InputError:
    return InputError(f"arith: {arith[:60]!r} is not a valid arithmetic name ({why})")


# --- linear algebra: plain Gaussian elimination over a field ------------------------


def _forward(M, width):
    """Gaussian elimination on the rows of M, in place, over its first ``width`` columns (pivot:
    the first nonzero entry): (the number of pivots, their product times the swaps' sign)."""
    r, det = 0, 1
    for col in range(width):
        piv = next((i for i in range(r, len(M)) if nonzero(M[i][col])), None)
        if piv is None:
            continue
        if piv != r:
            M[r], M[piv] = M[piv], M[r]
            det = -det
        p = M[r][col]
        det = det * p
        for i in range(r + 1, len(M)):
            if M[i][col] != 0:
                m = M[i][col] / p
                M[i] = [a - m * b for a, b in zip(M[i], M[r])]
        r += 1
    return r, det


def rank(rows) -> int:
    return _forward([list(r) for r in rows], len(rows[0]) if rows else 0)[0]


def _eliminate(A, B=None):
    """Gaussian elimination on the square matrix A (with right-hand side columns B):
    returns (det A, the solution X of A X = B or None)."""
    N = len(A)
    M = [list(row) + (list(B[i]) if B is not None else []) for i, row in enumerate(A)]
    r, det = _forward(M, N)
    if r < N:
        return 0 * M[0][0], None
    if B is None:
        return det, None
    width = len(B[0])
    X = [[None] * width for _ in range(N)]
    for i in range(N - 1, -1, -1):
        for j in range(width):
            s = M[i][N + j]
            for k in range(i + 1, N):
                s = s - M[i][k] * X[k][j]
            X[i][j] = s / M[i][i]
    return det, X


def solve(A, b, singular: str):
    """The solution x of A x = b (a vector); :class:`Undefined` ``singular`` if A is singular."""
    _, X = _eliminate(A, [[t] for t in b])
    if X is None:
        raise Undefined(singular)
    return [r[0] for r in X]


def nonzero(t) -> bool:
    """t != 0; for a dual number, its value (a pivot must be invertible)."""
    return (t.v if isinstance(t, Dual) else t) != 0


def _matmul(A, B):
    cols = list(zip(*B))
    return [[_dot(r, c) for c in cols] for r in A]


def _dot(u, v):
    s = 0
    for a, b in zip(u, v):
        if a != 0 and b != 0:
            s = s + a * b
    return s


def _matvec(A, x):
    return [_dot(r, x) for r in A]


def transpose(M):
    return [list(r) for r in zip(*M)]


# --- a tiny evaluator of the integrals' expression text -------------------------------

#: the numbers of system files: digits (any script's decimal digits, as Python's \d and int()
#: read them), an optional point and exponent: 12, 1.5, .5, 1., 1e5, 2.5E-3
_TOKEN = re.compile(r"\s*(?:((?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)|([A-Za-z_][A-Za-z0-9_]*)|(\*\*|[-+*/()]))")
#: the largest |exponent| of a number such as 1e-300 (the system-file parser's limit)
MAX_DECIMAL_EXPONENT = 10_000


class _Evaluate:
    """The value of an expression (names, numbers, + - * / **, parentheses, Python's
    precedence; exponents integer literals) at a point, in the field of ``one``.
    Division by zero raises ZeroDivisionError."""

    def __init__(self, text, names, F, where):
        self.names, self.F, self.where, self.tokens, pos = names, F, where, [], 0
        if not isinstance(text, str):
            raise InputError(f"{where}: expected an expression (a string)")
        while (m := _TOKEN.match(text, pos)) and m.end() > pos:
            self.tokens.append(m.group(m.lastindex) if m.lastindex != 1 else ("num", m.group(1)))
            pos = m.end()
        if text[pos:].strip():
            raise InputError(f"{where}: unexpected character {text[pos:].strip()[0]!r}")
        self.i = 0
        self.value = self.sum(0)
        if self.i != len(self.tokens):
            raise InputError(f"{where}: unexpected {self.tokens[self.i]!r}")

    def peek(self):
        return self.tokens[self.i] if self.i < len(self.tokens) else None

    def take(self):
        if self.i >= len(self.tokens):
            raise InputError(f"{self.where}: the expression ends too early")
        self.i += 1
        return self.tokens[self.i - 1]

    def sum(self, depth):
        v = self.product(depth)
        while self.peek() in ("+", "-"):
            v = v + self.product(depth) if self.take() == "+" else v - self.product(depth)
        return v

    def product(self, depth):
        v = self.unary(depth)
        while self.peek() in ("*", "/"):
            v = v * self.unary(depth) if self.take() == "*" else v / self.unary(depth)
        return v

    def unary(self, depth):
        sign = 1
        while self.peek() in ("+", "-"):
            sign = -sign if self.take() == "-" else sign
        v = self.power(depth)
        return v if sign > 0 else -v

    def power(self, depth):
        v = self.atom(depth)
        if self.peek() != "**":
            return v
        self.take()
        paren = self.peek() == "("
        if paren:
            self.take()
        neg = self.peek() in ("+", "-") and self.take() == "-"
        tok = self.take()
        if not (isinstance(tok, tuple) and tok[1].isdigit() and len(tok[1]) <= 3 and int(tok[1]) <= 64):
            raise InputError(f"{self.where}: an exponent must be an integer literal of at most 64")
        if paren and self.take() != ")":
            raise InputError(f"{self.where}: missing ')' after the exponent")
        if neg:
            v = self.F.one / v
        out = self.F.one
        for _ in range(int(tok[1])):
            out = out * v
        return out

    def atom(self, depth):
        tok = self.take()
        if isinstance(tok, tuple):  # digits[.digits][e±digits], exactly: 2.5e3 = 25 * 10^2
            mantissa, _, exp = tok[1].lower().partition("e")
            if exp and (len(exp) > 6 or abs(int(exp)) > MAX_DECIMAL_EXPONENT):
                raise InputError(f"{self.where}: the exponent of {tok[1][:30]} is beyond the limit of "
                                 f"{MAX_DECIMAL_EXPONENT}")
            whole, _, frac = mantissa.partition(".")
            digits = "".join(str(unicodedata.decimal(ch)) for ch in whole + frac).lstrip("0") or "0"
            return self.F.of(parse_rational(digits, self.where) * Fraction(10) ** (int(exp or 0) - len(frac)))
        if tok == "(":
            if depth > 200:
                raise InputError(f"{self.where}: parentheses nested too deeply")
            v = self.sum(depth + 1)
            if self.take() != ")":
                raise InputError(f"{self.where}: missing ')'")
            return v
        if tok in self.names:
            return self.names[tok]
        raise InputError(f"{self.where}: unknown name {tok!r}")



# --- dual numbers: exact first derivatives ----------------------------------------------


class Dual:
    """v + Σ_m d_m δ_m: a value and its partial derivatives (δ_m² = δ_m δ_l = 0), over a field."""

    __slots__ = ("v", "d")

    def __init__(self, v, d):
        self.v, self.d = v, d

    @staticmethod
    def variables(x):
        """The point x as dual numbers, x_m with derivative e_m."""
        N = len(x)
        zero = 0 * x[0]
        return [Dual(t, [zero + (1 if m == i else 0) for m in range(N)]) for i, t in enumerate(x)]

    @staticmethod
    def parts(t, N, zero):
        """(value, gradient) of a dual number in N variables, or of a constant (gradient 0)."""
        return (t.v, t.d) if isinstance(t, Dual) else (t, [zero] * N)

    def _split(self, o):
        if isinstance(o, Dual):
            return o.v, o.d
        return o, None

    def __add__(self, o):
        v, d = self._split(o)
        return Dual(self.v + v, self.d if d is None else [a + b for a, b in zip(self.d, d)])

    __radd__ = __add__

    def __neg__(self):
        return Dual(-self.v, [-a for a in self.d])

    def __sub__(self, o):
        return self + (-o)

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        v, d = self._split(o)
        if d is None:
            return Dual(self.v * v, [a * v for a in self.d])
        return Dual(self.v * v, [a * v + self.v * b for a, b in zip(self.d, d)])

    __rmul__ = __mul__

    def __truediv__(self, o):
        v, d = self._split(o)
        if v == 0:
            raise ZeroDivisionError("division by zero")
        if d is None:
            return Dual(self.v / v, [a / v for a in self.d])
        q = self.v / v
        return Dual(q, [(a - q * b) / v for a, b in zip(self.d, d)])

    def __rtruediv__(self, o):
        if self.v == 0:
            raise ZeroDivisionError("division by zero")
        q = o / self.v
        return Dual(q, [-(q / self.v) * a for a in self.d])

    def __eq__(self, o):
        v, d = self._split(o)
        return self.v == v and all(a == (0 if d is None else b) for a, b in zip(self.d, d or self.d))

    __hash__ = None
