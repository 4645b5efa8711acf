"""Re-check a saved certificate by a separate, minimal code path: ``verify(data)``.

A certificate (:meth:`~exact_khk.certification.records.Certificate.to_json`,
schema version 2) records the orbit x_0, …, x_K of the Kahan map Φ_f and the
values of the integrals at its points.  :func:`verify` re-checks that record
with plain exact arithmetic written out here from the formulas — its own
Gaussian elimination over :class:`fractions.Fraction` — and never calls the
library's Kahan map, linear algebra, circulant or split solvers or arithmetic
contexts.  From the library it takes only the reading of the input: the
certificate's structure (:meth:`Certificate.from_json`, which raises
:class:`~exact_khk.errors.InputError` naming the key at fault), rationals
(:func:`~exact_khk.parsing.parse_rational`, any size) and, for a system given by
expressions, the coefficients of its field (``ExpressionSystem.from_json(d).field("f")``).
The Lie–Poisson field f(x) = J(x) Hs x is built here from the vectors a, b, c.

The named results, in order:

* ``schema version`` — the version is 2 (nothing else is read otherwise);
* ``exact arithmetic`` — the certificate was computed in an exact arithmetic the
  verifier can redo: Q (``fraction``, ``gmpy2``, ``flint``), Q(ζ_N) (``cyclo:N``,
  polynomials in z modulo Φ_N) or F_P (``gf:P``).  A floating or ball certificate
  holds approximations: it is reported **not checkable** (``checkable=False``,
  ``ok=False``, this result failing) and only the status and verdict are checked; a
  name that is no arithmetic of the library (``cyclo:0``, ``gf:4``) is malformed
  input (:class:`~exact_khk.errors.InputError`);
* ``orbit length`` — K + 1 points; ``orbit starts at x0`` — x_0 = x0;
* ``Kahan step equations`` — (I − εf'(x_k)) x_{k+1} = (I + εL) x_k + 2εc for every
  k, verified by substitution, without solving (for homogeneous f: = x_k);
* ``Kahan steps nonsingular`` — det(I − εf'(x_k)) ≠ 0, so each step is the unique one;
* ``integrals recorded`` — the integrals recorded are those of the system
  (H~ and K~[s] for each involution s of a Lie–Poisson certificate);
* ``values of I`` — each recorded value equals I recomputed at its point: for the
  Lie–Poisson family by the closed form H~_M(x) = xᵀ(I − ε²(M J(x))²)⁻¹ M x
  (M = Hs for H~, B Hs for K~[s]), for expression systems by evaluating the
  integral's text from the system JSON with the small evaluator below (an
  integral recorded as undefined must have a pole on the orbit);
* ``I conserved`` — the values agree along the orbit exactly when the recorded
  check ``integral I conserved by Phi_f`` says so (a VALID certificate: they all agree);
* ``H~ closed form = definition`` (Lie–Poisson) — H~(x_k) = (2ε)⁻¹ x_kᵀ J(m)⁻¹ x_{k+1},
  m = (x_k + x_{k+1})/2, along the recorded orbit, where J(m) is invertible;
* ``status`` — the status recomputed from the checks' ``expected``, ``holds`` and
  ``applicable`` fields (VALID iff every claim holds, every applicable control
  fails and some control is applicable; INVALID iff a claim is false; else
  INCONCLUSIVE) is the recorded one, and so is ``valid``; ``verdict`` — the
  verdict line starts with that status and, for VALID and INVALID, with the
  counts of the recorded checks (claims and applicable controls; false claims).

``ok`` is True iff every result holds.  The other checks of a certificate
(commutation, Poisson structure, ranks, controls) are not recomputed: they are
taken as recorded, and only their consistency with the status is checked.

>>> from exact_khk.certification.lie_poisson import certify
>>> data = certify(steps=3, signs=["-++"]).to_json()
>>> report = verify(data)
>>> report.ok, report.summary().splitlines()[-1][:40]
(True, 'VERIFIED: the record of this VALID certi')
>>> data["orbit"][2][0] = "1/3"                     # tamper with one coordinate
>>> bad = verify(data)
>>> bad.ok, bad.failures()[0][0]
(False, 'Kahan step equations')
"""

from __future__ import annotations

import re
import unicodedata
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache

from exact_khk.errors import InputError
from exact_khk.parsing import parse_rational

#: the certificate schema versions this verifier reads
SCHEMA_VERSIONS = (2,)
#: arithmetics whose elements are exact rationals printed 'p' or 'p/q'
RATIONAL_ARITHS = ("fraction", "gmpy2", "flint")
#: longest detail shown for one number (longer ones are abbreviated)
_SHOW_BITS = 2000


class _Undefined(Exception):
    """A quantity that does not exist at a point (division by zero, a pole)."""


# --- the report ---------------------------------------------------------------------


@dataclass(frozen=True)
class VerifyReport:
    """The outcome of :func:`verify`: ``results`` is a tuple of ``(name, ok, detail)``;
    ``ok`` is True iff there is at least one result and all hold; ``checkable`` is
    False for a certificate computed in an inexact arithmetic (then ``ok`` is False)."""

    ok: bool
    results: tuple
    checkable: bool = True

    def failures(self) -> list:
        """The results that do not hold, in order."""
        return [r for r in self.results if not r[1]]

    def verdict(self) -> str:
        """One line: ``VERIFIED: ...`` or ``NOT VERIFIED: <first failing check>: ...``."""
        if self.ok:
            return f"VERIFIED: {self._what}"
        name, _, detail = self.failures()[0] if self.failures() else ("no results", False, "")
        more = len(self.failures()) - 1
        tail = f" (and {more} more failing check{'s' * (more != 1)})" if more > 0 else ""
        return f"NOT VERIFIED: {name}: {detail}{tail}"

    @property
    def _what(self) -> str:
        status = next((d for n, _, d in self.results if n == "status"), "")
        word = status.split()[1] if status.startswith("recomputed") else "?"
        return (f"the record of this {word} certificate is correct: all {len(self.results)} checks "
                f"re-checked exactly and independently")

    def summary(self) -> str:
        """The results, one per line, then the verdict line."""
        lines = [f"  {'ok  ' if ok else 'FAIL'}  {name}: {detail}" for name, ok, detail in self.results]
        return "\n".join(lines + [self.verdict()])

    def to_json(self) -> dict:
        return {"ok": self.ok, "checkable": self.checkable, "verdict": self.verdict(),
                "results": [{"name": n, "ok": ok, "detail": d} for n, ok, d in self.results]}


# --- exact fields: Q, Q(zeta_N), F_P --------------------------------------------------


def _show(e) -> str:
    """A field element for a message (huge numbers abbreviated, never str() of a huge int)."""
    if isinstance(e, Fraction):
        bits = max(abs(e.numerator).bit_length(), e.denominator.bit_length())
        if bits > _SHOW_BITS:
            return f"<a rational of about {int(bits * 0.30103) + 1} digits>"
        return str(e)
    return str(e)


class _Rationals:
    """Q: elements are Fractions."""

    name = "Q"
    one, zero = Fraction(1), Fraction(0)

    def of(self, q: Fraction):
        return Fraction(q)

    def parse(self, text: str, where: str):
        return parse_rational(text, where)

    def root_of_unity(self, n: int):
        if n <= 2:
            return Fraction(-1) if n == 2 else Fraction(1)
        raise _Undefined(f"Q has no primitive {n}-th root of unity")


def _trim(c) -> tuple:
    c = list(c)
    while c and c[-1] == 0:
        c.pop()
    return tuple(c)


def _pmul(a, b) -> list:
    if not a or not b:
        return []
    out = [Fraction(0)] * (len(a) + len(b) - 1)
    for i, s in enumerate(a):
        if s:
            for j, t in enumerate(b):
                out[i + j] += s * t
    return out


def _pdivmod(a, b):
    """(q, r) with a = q b + r, deg r < deg b (coefficient lists, constant term first)."""
    a, q = list(a), [Fraction(0)] * max(len(a) - len(b) + 1, 0)
    for i in range(len(a) - len(b), -1, -1):
        c = Fraction(a[i + len(b) - 1]) / b[-1]
        q[i] = c
        if c:
            for j, t in enumerate(b):
                a[i + j] -= c * t
    return _trim(q), _trim(a[:len(b) - 1])


@lru_cache(maxsize=None)
def cyclotomic_polynomial(N: int) -> tuple:
    """Φ_N as integer coefficients, constant term first: (z^N − 1) / Π_{d | N, d < N} Φ_d.

    >>> cyclotomic_polynomial(3), cyclotomic_polynomial(4)
    ((1, 1, 1), (1, 0, 1))
    """
    p = [Fraction(-1)] + [Fraction(0)] * (N - 1) + [Fraction(1)]
    for d in range(1, N):
        if N % d == 0:
            p, r = _pdivmod(p, [Fraction(t) for t in cyclotomic_polynomial(d)])
            assert not r
    return tuple(int(t) for t in p)


class _Cyclotomic:
    """Q(ζ_N): polynomials in z = ζ_N of degree < φ(N) with Fraction coefficients,
    reduced modulo Φ_N (the printing of ``cyclo:N``: '1/3 - 2/3*z + z^2')."""

    _TERM = re.compile(r"\s*([+-]?)\s*(?:(\d+(?:/\d+)?)(\*z(?:\^(\d+))?)?|z(?:\^(\d+))?)\s*")

    def __init__(self, N: int):
        self.N = N
        self.name = f"Q(zeta_{N})"
        self.modulus = tuple(Fraction(t) for t in cyclotomic_polynomial(N))
        self.one, self.zero = _Cyc(self, (Fraction(1),)), _Cyc(self, ())

    def reduce(self, c) -> tuple:
        c, m, d = list(c), self.modulus, len(self.modulus) - 1
        for i in range(len(c) - 1, d - 1, -1):
            t = c[i]
            if t:
                for j in range(d + 1):
                    c[i - d + j] -= t * m[j]
        return _trim(c[:d])

    def inverse(self, c) -> tuple:
        """c⁻¹ mod Φ_N by the extended Euclidean algorithm (Φ_N is irreducible)."""
        if not c:
            raise ZeroDivisionError(f"division by zero in {self.name}")
        r0, r1, s0, s1 = _trim(self.modulus), _trim(c), (), (Fraction(1),)
        while r1:
            q, r = _pdivmod(r0, r1)
            qs = _pmul(q, s1)
            n = max(len(s0), len(qs))
            s0, s1 = s1, _trim([(s0[i] if i < len(s0) else 0) - (qs[i] if i < len(qs) else 0) for i in range(n)])
            r0, r1 = r1, r
        return self.reduce([t / r0[0] for t in s0])  # r0 is a nonzero constant

    def of(self, q: Fraction):
        return _Cyc(self, (Fraction(q),))

    def parse(self, text: str, where: str):
        if not isinstance(text, str) or not text.strip():
            raise InputError(f"{where}: expected an element of {self.name} such as '1/3 - 2/3*z', got {text!r}")
        coeffs, pos, first = {}, 0, True
        while pos < len(text):
            m = self._TERM.match(text, pos)
            if m is None or m.end() == pos or (not first and not m.group(1)):
                raise InputError(f"{where}: {text[:60]!r} is not an element of {self.name} "
                                 f"(expected terms such as '1/3', '- 2/3*z', '+ z^2')")
            sign, num, zpart, e1, e2 = m.groups()
            if num is not None:
                c = parse_rational(num, where)
                k = 0 if zpart is None else int(e1 or 1)
            else:
                c, k = Fraction(1), int(e2 or 1)
            coeffs[k] = coeffs.get(k, 0) + (-c if sign == "-" else c)
            pos, first = m.end(), False
        top = max(coeffs)
        return _Cyc(self, self.reduce([coeffs.get(k, Fraction(0)) for k in range(top + 1)]))

    def root_of_unity(self, n: int):
        if self.N % n:
            raise _Undefined(f"{self.name} contains no primitive {n}-th root of unity")
        return _Cyc(self, self.reduce([Fraction(0)] * (self.N // n) + [Fraction(1)]))


class _Cyc:
    """An element of Q(ζ_N) (coefficients, constant term first)."""

    __slots__ = ("K", "c")

    def __init__(self, K, c):
        self.K, self.c = K, _trim(c)

    def _co(self, o):
        if isinstance(o, _Cyc):
            return o.c
        if isinstance(o, (int, Fraction)):
            return _trim([Fraction(o)])
        return None

    def _add(self, a, b, sign=1):
        n = max(len(a), len(b))
        return _Cyc(self.K, [(a[i] if i < len(a) else 0) + sign * (b[i] if i < len(b) else 0) for i in range(n)])

    def __add__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else self._add(self.c, b)

    __radd__ = __add__

    def __sub__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else self._add(self.c, b, -1)

    def __rsub__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else self._add(b, self.c, -1)

    def __neg__(self):
        return _Cyc(self.K, [-t for t in self.c])

    def __mul__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else _Cyc(self.K, self.K.reduce(_pmul(self.c, b)))

    __rmul__ = __mul__

    def __truediv__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else _Cyc(self.K, self.K.reduce(_pmul(self.c, self.K.inverse(b))))

    def __rtruediv__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else _Cyc(self.K, self.K.reduce(_pmul(b, self.K.inverse(self.c))))

    def __eq__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else self.c == b

    __hash__ = None

    def __bool__(self):
        return bool(self.c)

    def __str__(self):
        parts = [(("-" if t < 0 else "+"), (_show(abs(t)) if k == 0 else
                  ("" if abs(t) == 1 else _show(abs(t)) + "*") + ("z" if k == 1 else f"z^{k}")))
                 for k, t in enumerate(self.c) if t]
        if not parts:
            return "0"
        return ("-" if parts[0][0] == "-" else "") + parts[0][1] + "".join(f" {s} {b}" for s, b in parts[1:])


class _PrimeField:
    """F_P, P a prime (checked by :func:`exact_field`): elements are :class:`_Mod` (printed as
    the residue in [0, P))."""

    def __init__(self, P: int):
        self.P, self.name = P, f"F_{P}"
        self.one, self.zero = _Mod(P, 1), _Mod(P, 0)

    def of(self, q: Fraction):
        q = Fraction(q)
        if q.denominator % self.P == 0:
            raise _Undefined(f"{_show(q)} has no value mod {self.P} (its denominator is divisible by P)")
        return _Mod(self.P, q.numerator * pow(q.denominator, -1, self.P))

    def parse(self, text: str, where: str):
        if not isinstance(text, str) or not re.fullmatch(r"\d{1,40}", text.strip()) or int(text) >= self.P:
            raise InputError(f"{where}: {str(text)[:60]!r} is not a residue mod {self.P} (an integer in [0, P))")
        return _Mod(self.P, int(text))

    def root_of_unity(self, n: int):
        """g^((P-1)/n), g the least primitive root mod P (the embedding of ``gf:P``)."""
        if (self.P - 1) % n:
            raise _Undefined(f"F_{self.P} contains no primitive {n}-th root of unity (P != 1 mod {n})")
        return _Mod(self.P, pow(_least_primitive_root(self.P), (self.P - 1) // n, self.P))


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


class _Mod:
    """An element of F_P."""

    __slots__ = ("P", "v")

    def __init__(self, P, v):
        self.P, self.v = P, v % P

    def _co(self, o):
        if isinstance(o, _Mod):
            return o.v
        if isinstance(o, int):
            return o % self.P
        if isinstance(o, Fraction):
            if o.denominator % self.P == 0:
                raise ZeroDivisionError(f"{_show(o)} has no value mod {self.P}")
            return o.numerator * pow(o.denominator, -1, self.P) % self.P
        return None

    def __add__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else _Mod(self.P, self.v + b)

    __radd__ = __add__

    def __sub__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else _Mod(self.P, self.v - b)

    def __rsub__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else _Mod(self.P, b - self.v)

    def __neg__(self):
        return _Mod(self.P, -self.v)

    def __mul__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else _Mod(self.P, self.v * b)

    __rmul__ = __mul__

    def __truediv__(self, o):
        b = self._co(o)
        if b is None:
            return NotImplemented
        if b == 0:
            raise ZeroDivisionError(f"division by zero mod {self.P}")
        return _Mod(self.P, self.v * pow(b, -1, self.P))

    def __rtruediv__(self, o):
        b = self._co(o)
        if b is None:
            return NotImplemented
        if self.v == 0:
            raise ZeroDivisionError(f"division by zero mod {self.P}")
        return _Mod(self.P, b * pow(self.v, -1, self.P))

    def __eq__(self, o):
        b = self._co(o)
        return NotImplemented if b is None else self.v == b

    __hash__ = None

    def __bool__(self):
        return self.v != 0

    def __str__(self):
        return str(self.v)


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
        return _Rationals()
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
        raise _Undefined(f"cyclo:{param[:40]}: N is above {MAX_CYCLOTOMIC_N}, the largest cyclo:N this "
                         "library computes in (not checkable)")
    return _Cyclotomic(value)


def _invalid_name(arith: str, why: str) -> InputError:
    return InputError(f"arith: {arith[:60]!r} is not a valid arithmetic name ({why})")


# --- linear algebra: plain Gaussian elimination over a field ------------------------


def _eliminate(A, B=None):
    """Gaussian elimination on the square matrix A (with right-hand side columns B):
    returns (det A, the solution X of A X = B or None).  Pivots: the first nonzero entry."""
    N = len(A)
    M = [list(row) + (list(B[i]) if B is not None else []) for i, row in enumerate(A)]
    det = 1
    for col in range(N):
        piv = next((i for i in range(col, N) if M[i][col] != 0), None)
        if piv is None:
            return 0 * M[0][0], None
        if piv != col:
            M[col], M[piv] = M[piv], M[col]
            det = -det
        p = M[col][col]
        det = det * p
        for i in range(col + 1, N):
            if M[i][col] != 0:
                m = M[i][col] / p
                M[i] = [a - m * b for a, b in zip(M[i], M[col])]
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


# --- the field f(x) = Q(x) + L x + c --------------------------------------------------


class _Quadratic:
    """f_i(x) = Σ q x_j x_k + Σ l x_j + c_i with coefficients in the field."""

    def __init__(self, dim, quad, linear, const):
        self.dim, self.quad, self.linear, self.const = dim, quad, linear, const

    def jacobian(self, x):
        """f'(x): ∂(q x_j x_k)/∂x_j = q x_k (and symmetrically), plus L."""
        N = self.dim
        J = [[0] * N for _ in range(N)]
        for i in range(N):
            for j, k, q in self.quad[i]:
                J[i][j] = J[i][j] + q * x[k]
                J[i][k] = J[i][k] + q * x[j]
            for j, l in self.linear[i]:
                J[i][j] = J[i][j] + l
        return J

    @property
    def homogeneous(self):
        return not any(self.linear) and all(c == 0 for c in self.const)


def _expression_field(system, F) -> _Quadratic:
    """The quadratic terms of an ExpressionSystem's field f (its coefficient tuples)."""
    fld = system.field("f")
    quad = [[(j, k, F.of(Fraction(c))) for (j, k), c in terms] for terms in fld.quad]
    lin = [[(j, F.of(Fraction(c))) for j, c in row] for row in fld.linear]
    return _Quadratic(fld.dim, quad, lin, [F.of(Fraction(c)) for c in fld.const])


def _hankel(w):
    n = len(w)
    return [[w[(i + j) % n] for j in range(n)] for i in range(n)]


def _lp_hessian(a, b, c):
    """Hs = [[X(a), X(b)], [X(b), X(c)]], X(w)[i][j] = w[(i+j) mod n]."""
    Xa, Xb, Xc = _hankel(a), _hankel(b), _hankel(c)
    return [ra + rb for ra, rb in zip(Xa, Xb)] + [rb + rc for rb, rc in zip(Xb, Xc)]


def _lp_J(x, n):
    """J(x) = [[0, X(u)], [−X(u), 0]], u = x[:n]."""
    Xu = _hankel(list(x[:n]))
    zero = 0 * x[0]
    return [[zero] * n + list(r) for r in Xu] + [[-t for t in r] + [zero] * n for r in Xu]


def _lp_field(n, Hs) -> _Quadratic:
    """f(x) = J(x) Hs x written out: for i < n, f_i = Σ_l u_{(i+l) mod n} (Hs x)_{n+l};
    for i = n + i', f_i = −Σ_l u_{(i'+l) mod n} (Hs x)_l."""
    N = 2 * n
    quad = []
    for i in range(N):
        row, sign, ii = (n, 1, i) if i < n else (0, -1, i - n)
        acc = {}
        for l in range(n):
            j = (ii + l) % n  # the u-coordinate multiplying (Hs x)_{row + l}
            for m in range(N):
                h = Hs[row + l][m]
                if h != 0:
                    key = (min(j, m), max(j, m))
                    acc[key] = acc.get(key, 0) + sign * h
        quad.append([(j, k, q) for (j, k), q in sorted(acc.items()) if q != 0])
    return _Quadratic(N, quad, [[] for _ in range(N)], [0] * N)


def _involution(n, signs, F):
    """B = Bc ⊕ Bc, Bc[i][j] = α_{(j−i) mod n}, α_k = (1/n) Σ_j s_j ω^{−jk}, ω = ζ_n,
    computed in Q(ζ_n) and mapped into F (ζ_n to F's primitive n-th root of unity)."""
    s = [1 if ch == "+" else -1 for ch in signs]
    K = _Cyclotomic(n)
    alpha = []
    for k in range(n):
        coeffs = [Fraction(0)] * n
        for j in range(n):
            coeffs[(-j * k) % n] += Fraction(s[j], n)
        alpha.append(K.reduce(coeffs))
    if isinstance(F, _Rationals) and any(len(a) > 1 for a in alpha):
        raise _Undefined(f"the involution {signs!r} is not rational")
    if all(len(a) <= 1 for a in alpha):
        vals = [F.of(a[0] if a else Fraction(0)) for a in alpha]
    else:
        w = F.root_of_unity(n)
        vals = []
        for a in alpha:
            v, p = F.zero, F.one
            for t in a:
                v, p = v + p * t, p * w
            vals.append(v)
    Bc = [[vals[(j - i) % n] for j in range(n)] for i in range(n)]
    Z = [F.zero] * n
    return [list(r) + Z for r in Bc] + [Z + list(r) for r in Bc]


def _htilde(M, x, e, n):
    """H~_M(x, ε) = xᵀ (I − ε²(M J(x))²)⁻¹ M x; _Undefined at a pole."""
    N = 2 * n
    MJ = _matmul(M, _lp_J(x, n))
    MJ2 = _matmul(MJ, MJ)
    e2 = e * e
    S = [[(1 if i == j else 0) - e2 * MJ2[i][j] for j in range(N)] for i in range(N)]
    det, z = _eliminate(S, [[t] for t in _matvec(M, x)])
    if z is None:
        raise _Undefined("I - eps^2 (M J(x))^2 is singular")
    return _dot(x, [r[0] for r in z])


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


# --- verify -------------------------------------------------------------------------


def verify(data) -> VerifyReport:
    """Re-check the certificate ``data`` (the JSON dict of ``Certificate.to_json``);
    see the module docstring for what is checked.  Malformed structures raise
    :class:`~exact_khk.errors.InputError` naming the field."""
    from exact_khk.certification.records import Certificate

    if not isinstance(data, dict):
        raise InputError(f"certificate: expected a JSON object, got {type(data).__name__}")
    if "schema_version" not in data:
        raise InputError("schema_version: missing key 'schema_version'")
    version = data["schema_version"]
    if type(version) is not int or version not in SCHEMA_VERSIONS:
        return VerifyReport(False, (("schema version", False, f"unknown schema version {version!r} "
                                     f"(this verifier reads {', '.join(map(str, SCHEMA_VERSIONS))})"),))
    results = [("schema version", True, str(version))]
    cert = Certificate.from_json(data)  # the structure: InputError naming the field
    for key, types in (("status", str), ("valid", bool), ("verdict", str)):
        if key not in data:
            raise InputError(f"{key}: missing key {key!r}")
        if not isinstance(data[key], types):
            raise InputError(f"{key}: expected {'a string' if types is str else 'true or false'}")
    try:
        F = exact_field(cert.arith)
    except _Undefined as exc:
        F, why = None, str(exc)
    else:
        why = (f"the certificate was computed in the inexact arithmetic {cert.arith!r}: its orbit and values "
               f"are approximations and cannot be re-checked exactly (not checkable)")
    if F is None:
        results.append(("exact arithmetic", False, why))
        results += _status_results(data)
        return VerifyReport(False, tuple(results), checkable=False)
    results.append(("exact arithmetic", True, f"{cert.arith}: re-checked in {F.name}"))
    results += _Recheck(cert, data, F).run()
    results += _status_results(data)
    return VerifyReport(bool(results) and all(ok for _, ok, _ in results), tuple(results))


class _Recheck:
    """The orbit and the integrals of one certificate, re-checked in the field F."""

    def __init__(self, cert, data, F):
        self.cert, self.data, self.F = cert, data, F
        self.system = cert.system
        self.lp = getattr(self.system, "kind", "") == "lie-poisson"
        self.pts = [[F.parse(t, f"orbit[{k}][{i}]") for i, t in enumerate(p)] for k, p in enumerate(cert.orbit)]
        self.e = F.of(cert.eps)
        if self.lp:
            n = self.system.n
            self.n = n
            self.Hs = [[F.of(t) for t in row] for row in _lp_hessian(self.system.a, self.system.b, self.system.c)]
            self.f = _lp_field(n, self.Hs)
        else:
            self.f = _expression_field(self.system, F)

    def run(self) -> list:
        out = [self.orbit_length(), self.starts_at_x0()]
        out += self.steps()
        out += self.integrals()
        return out

    def orbit_length(self):
        K, got = self.cert.steps, len(self.pts)
        if got != K + 1:
            return ("orbit length", False, f"{got} points recorded; {_show(Fraction(K))} steps need {_show(Fraction(K + 1))}")
        return ("orbit length", True, f"{K + 1} points")

    def starts_at_x0(self):
        if not self.pts:
            return ("orbit starts at x0", False, "no orbit recorded")
        try:
            x0 = [self.F.of(t) for t in self.cert.x0]
        except _Undefined as exc:
            return ("orbit starts at x0", False, str(exc))
        bad = [i for i, (a, b) in enumerate(zip(self.pts[0], x0)) if a != b]
        if bad:
            i = bad[0]
            return ("orbit starts at x0", False, f"x_0[{i}] = {_show(self.pts[0][i])} but x0[{i}] = {_show(x0[i])}")
        return ("orbit starts at x0", True, "x_0 = x0")

    def steps(self):
        f, e, N, pts = self.f, self.e, self.f.dim, self.pts
        homogeneous = f.homogeneous
        eq_bad = det_bad = None
        for k in range(len(pts) - 1):
            x, y = pts[k], pts[k + 1]
            D = f.jacobian(x)
            A = [[(1 if i == j else 0) - e * D[i][j] for j in range(N)] for i in range(N)]
            lhs = _matvec(A, y)
            if homogeneous:
                rhs = x
            else:
                rhs = [x[i] + e * _dot([l for _, l in f.linear[i]], [x[j] for j, _ in f.linear[i]])
                       + 2 * e * f.const[i] for i in range(N)]
            diff = [a - b for a, b in zip(lhs, rhs)]
            i = next((i for i, d in enumerate(diff) if d != 0), None)
            if i is not None and eq_bad is None:
                eq_bad = (k, i, diff[i])
            det, _ = _eliminate(A)
            if det == 0 and det_bad is None:
                det_bad = k
        K = len(pts) - 1
        form = ("(I - eps f'(x_k)) x_{k+1} = x_k" if homogeneous else
                "(I - eps f'(x_k)) x_{k+1} = (I + eps L) x_k + 2 eps c")
        if eq_bad is not None:
            k, i, d = eq_bad
            first = ("Kahan step equations", False, f"{form} fails at k = {k}, row {i}: residual {_show(d)}")
        else:
            first = ("Kahan step equations", True, f"{form} holds exactly for k = 0..{K - 1}")
        if det_bad is not None:
            second = ("Kahan steps nonsingular", False, f"det(I - eps f'(x_k)) = 0 at k = {det_bad}: the step "
                      f"from x_{det_bad} is not unique")
        else:
            second = ("Kahan steps nonsingular", True, f"det(I - eps f'(x_k)) != 0 for k = 0..{K - 1}")
        return [first, second]

    # --- integrals -------------------------------------------------------------

    def integral_functions(self) -> dict:
        """name -> fn(x) (a field element; ZeroDivisionError or _Undefined at a pole)."""
        F, e = self.F, self.e
        if self.lp:
            n = self.n
            fns = {"H~": lambda x: _htilde(self.Hs, x, e, n)}
            for s in self.cert.signs:
                try:
                    M = _matmul(_involution(n, s, F), self.Hs)
                except _Undefined as exc:
                    fns[f"K~[{s}]"] = exc
                    continue
                fns[f"K~[{s}]"] = lambda x, M=M: _htilde(M, x, e, n)
            return fns
        spec = self.data["system"]
        params = {p: _Evaluate(t, {}, F, f"system.parameters.{p}").value
                  for p, t in (spec.get("parameters") or {}).items()}
        variables = list(spec["variables"])
        fns = {}
        for name, text in (spec.get("integrals") or {}).items():
            def fn(x, text=text, name=name):
                names = dict(params, eps=e, **dict(zip(variables, x)))
                return _Evaluate(text, names, F, f"system.integrals.{name}").value
            fns[name] = fn
        return fns

    def _value(self, name, fn, k):
        """(value, how) of integral ``name`` at x_k; raises _Undefined at a pole."""
        x = self.pts[k]
        try:
            return fn(x), ""
        except ZeroDivisionError:
            pass
        except _Undefined:
            raise
        if self.lp or not isinstance(self.F, _Rationals):
            raise _Undefined("division by zero")
        # the expression as written divides by zero at x_k; its value there is that of the
        # reduced rational function, if it is finite (the library reduces it to lowest terms)
        from exact_khk.arith import get_arith
        from exact_khk.errors import PoleError

        try:
            return self.system.integrals()[name](get_arith("fraction"), x, self.cert.eps), " (reduced form)"
        except PoleError:
            raise _Undefined("pole") from None

    def integrals(self) -> list:
        fns = self.integral_functions()
        recorded = self.cert.values
        out = []
        missing = [n for n in fns if n not in recorded]
        extra = [n for n in recorded if n not in fns]
        if missing or extra:
            out.append(("integrals recorded", False, "; ".join(
                ([f"no values recorded for {', '.join(missing)}"] if missing else []) +
                ([f"values recorded for {', '.join(extra)}, which the system does not declare"] if extra else []))))
        else:
            out.append(("integrals recorded", True, f"{', '.join(fns) or 'none declared'}"))
        checks = {c.name: c for c in self.cert.checks}
        for name, fn in fns.items():
            if name not in recorded:
                continue
            out += self._one_integral(name, fn, recorded[name], checks.get(f"integral {name} conserved by Phi_f"))
        if self.lp and "H~" in recorded and isinstance(recorded["H~"], list):
            out.append(self._definition(recorded["H~"]))
        return out

    def _one_integral(self, name, fn, recorded, check):
        label = f"values of {name}"
        if isinstance(fn, _Undefined):
            return [(label, False, f"cannot be recomputed: {fn}")]
        if recorded is None:  # recorded as undefined: there must be a pole on the orbit
            for k in range(len(self.pts)):
                try:
                    self._value(name, fn, k)
                except _Undefined:
                    return [(label, True, f"recorded as undefined; {name} has a pole at x_{k}")]
            return [(label, False, f"recorded as undefined, but {name} is finite at every orbit point")]
        if len(recorded) != len(self.pts):
            return [(label, False, f"{len(recorded)} values recorded for {len(self.pts)} orbit points")]
        values, notes = [], set()
        for k, text in enumerate(recorded):
            r = self.F.parse(text, f"values.{name}[{k}]")
            try:
                v, how = self._value(name, fn, k)
            except _Undefined as exc:
                return [(label, False, f"recorded {_show(r)} at x_{k}, where {name} is undefined ({exc})")]
            if v != r:
                return [(label, False, f"at x_{k}: recorded {_show(r)}, recomputed {_show(v)}")]
            values.append(v)
            notes.add(how)
        result = [(label, True, f"all {len(values)} recorded values recomputed exactly{''.join(sorted(notes))}")]
        conserved = all(v == values[0] for v in values)
        k = next((k for k, v in enumerate(values) if v != values[0]), None)
        state = "equal along the orbit" if conserved else f"not equal along the orbit (x_{k} differs from x_0)"
        if check is None:
            result.append((f"{name} conserved", True, f"values {state}; no conservation check recorded"))
        elif check.holds is None:
            result.append((f"{name} conserved", False, f"values {state}, but the recorded check "
                           f"{check.name!r} is undecided"))
        elif check.holds != conserved:
            result.append((f"{name} conserved", False, f"values {state}, but the recorded check "
                           f"{check.name!r} says holds = {str(check.holds).lower()}"))
        else:
            result.append((f"{name} conserved", True, f"values {state}, as the recorded check says"))
        return result

    def _definition(self, recorded):
        """H~(x_k) = (2 eps)^-1 x_k^T J(m)^-1 x_{k+1}, m = (x_k + x_{k+1})/2 (skipped where J(m) is singular)."""
        label = "H~ closed form = definition"
        n, e, pts, F = self.n, self.e, self.pts, self.F
        if len(recorded) != len(pts):
            return (label, False, "the values of H~ do not match the orbit")
        done, skipped = 0, []
        for k in range(len(pts) - 1):
            x, y = pts[k], pts[k + 1]
            m = [(a + b) / 2 for a, b in zip(x, y)]
            _, z = _eliminate(_lp_J(m, n), [[t] for t in y])
            if z is None:
                skipped.append(k)
                continue
            h = _dot(x, [r[0] for r in z]) / (2 * e)
            r = F.parse(recorded[k], f"values.H~[{k}]")
            if h != r:
                return (label, False, f"at x_{k}: recorded H~ = {_show(r)}, definition gives {_show(h)}")
            done += 1
        note = f"; skipped k = {skipped[:5]}{'...' if len(skipped) > 5 else ''} (J(m) singular)" if skipped else ""
        return (label, True, f"h(x_k, x_(k+1)) = H~(x_k) at {done} orbit points{note}")


def _status_results(data) -> list:
    """The status recomputed from the checks, and the verdict line's consistency."""
    checks = data["checks"]
    passed = [(not c.get("applicable", True)) or (c["holds"] is not None and c["holds"] == c["expected"])
              for c in checks]
    wrong = [c["expected"] and c["holds"] is False for c in checks]
    controls = sum(1 for c in checks if not c["expected"] and c.get("applicable", True))
    valid = bool(checks) and all(passed) and controls > 0
    status = "VALID" if valid else "INVALID" if any(wrong) else "INCONCLUSIVE"
    out = []
    if data["status"] != status or data["valid"] != valid:
        bad = next((c["name"] for c, p in zip(checks, passed) if not p), None)
        why = (f" (check {bad!r} is {'wrong' if wrong[passed.index(False)] else 'not passed'})" if bad else
               " (no negative control is applicable)" if checks and not controls else "")
        out.append(("status", False, f"recorded status {str(data['status'])[:20]!r} (valid = "
                    f"{str(data['valid']).lower()}), but the checks give {status}{why}"))
    else:
        out.append(("status", True, f"recomputed {status} from {len(checks)} checks, as recorded"))
    # the verdict line's status, and for VALID / INVALID its counts (a certificate cut short keeps
    # the verdict of the whole one)
    claims = sum(1 for c in checks if c["expected"])
    head = {"VALID": f"VALID: all {claims} claims hold and all {controls} negative controls fail",
            "INVALID": f"INVALID: {sum(wrong)} claim(s) are false"}.get(status, f"{status}:")
    if data["verdict"].startswith(head):
        out.append(("verdict", True, f"the verdict line states {status}"
                    + (f" with the counts of the {len(checks)} checks" if status != "INCONCLUSIVE" else "")))
    else:
        out.append(("verdict", False, f"the verdict line {data['verdict'][:60]!r} does not state {head!r}"))
    return out
