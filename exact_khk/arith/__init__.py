"""Arithmetic contexts: one algorithm, many number systems.

An *arithmetic* (a context, as in mpmath or SymPy's domains) is a small object
that converts exact rationals into its own raw elements and knows how to print,
test and solve with them.  Algorithms receive the context and touch numbers
only through ordinary operators and the context's methods, so the Kahan step
is written once for all of them.

Names understood by :func:`get_arith`:

========== ============================================================
``fraction``  :class:`fractions.Fraction` (pure Python, the slow reference)
``gmpy2``     ``gmpy2.mpq``
``flint``     ``flint.fmpq`` (python-flint; the fastest exact backend)
``mp:P``      mpmath binary floats at P bits, in a private ``MPContext``
``float``     IEEE float64 (Python floats)
``cyclo:N``   Q(ζ_N), exact (:mod:`exact_khk.arith.cyclotomic`)
``gf:P``      the prime field F_P (:mod:`exact_khk.arith.cyclotomic`)
``ball:P``    python-flint ``arb`` balls at P bits (:mod:`exact_khk.arith.ball`)
========== ============================================================

Limits, refused at once with an :class:`~exact_khk.errors.InputError` naming
them: P ≤ :data:`MAX_PRECISION_BITS` (10⁶ bits) for ``mp:P`` and ``ball:P``
(one number then takes 125 kB and one product milliseconds; beyond, a 2n×2n
solve no longer fits in memory and time); N ≤
:data:`~exact_khk.arith.cyclotomic.MAX_CYCLOTOMIC_N` for ``cyclo:N``; P a prime
with 5 ≤ P < 2⁶⁴ for ``gf:P``.

Values are converted into an arithmetic by :func:`to_element` (strings such as
``'1/3'``, int, Fraction, gmpy2/python-flint rationals, elements of the
arithmetic; binary floats only into floating arithmetics) and back into exact
rationals by :func:`to_fraction`:

>>> to_fraction(get_arith("flint"), get_arith("flint")("-3/4") * 2)
Fraction(-3, 2)
>>> to_fraction(get_arith("float"), 0.5)
Fraction(1, 2)
>>> to_element(get_arith("flint"), 0.1, "eps")
Traceback (most recent call last):
...
exact_khk.errors.InputError: eps: 0.1 is a binary float, not an exact rational; write it as a string such as '1/10' or as a Fraction

>>> ar = get_arith("flint")
>>> ar.format(ar(Fraction(-3, 4)) * 2)
'-3/2'
>>> get_arith("mp:100").format(get_arith("mp:100")(Fraction(1, 3)))
'0.33333333333333333333333333333346'
>>> get_arith("float").exact
False
"""

from __future__ import annotations

import contextlib
import importlib
import math
import numbers
import re
from fractions import Fraction

from exact_khk.errors import InputError, SingularMatrix
from exact_khk.parsing import _short, any_int_digits

#: the largest precision P (bits) of ``mp:P`` and ``ball:P``: one number of 10⁶ bits
#: takes 125 kB and one multiplication about a millisecond, so a 2n×2n solve
#: at this precision is already minutes; beyond it the run would not finish
MAX_PRECISION_BITS = 1_000_000
#: the longest parameter text after ``:`` in an arithmetic's name (digits)
_MAX_PARAM_DIGITS = 30


def check_precision(kind: str, prec) -> int:
    """``prec`` if 2 ≤ prec ≤ :data:`MAX_PRECISION_BITS`, else :class:`InputError` naming the limit."""
    if isinstance(prec, bool) or not isinstance(prec, int):
        raise InputError(f"arith: {kind}:P needs an integer precision P in bits, got {prec!r}")
    if prec < 2:
        raise InputError(f"arith: {kind}:{prec}: the {kind} precision must be at least 2 bits")
    if prec > MAX_PRECISION_BITS:
        raise InputError(f"arith: {kind}:{prec}: the precision is beyond the limit of {MAX_PRECISION_BITS} bits "
                         f"(MAX_PRECISION_BITS; one {kind} number would take {prec // 8:,} bytes)")
    return prec


class Arith:
    """Base arithmetic context.

    Subclasses set ``name``, ``exact`` (results are exact, compare with ``==``),
    ``zero``, ``one`` and implement :meth:`convert` and :meth:`format`.
    ``prec`` is the working precision in bits (``None`` for exact contexts).
    """

    name = "?"
    exact = True
    prec = None
    #: exact rationals (Q) with ``to_fraction``/``convert`` round trips
    rational = False
    #: an :class:`IntegerKernel` for fraction-free solves (rational contexts only)
    integers = None
    #: binary floating point with ``from_man_exp``: the DFT (structured) step applies
    fourier = False
    #: IEEE binary64: dense steps by LAPACK through numpy (:mod:`exact_khk.linalg.floating`)
    lapack = False

    def __call__(self, value):
        """``value`` as an element of this arithmetic, read as every public function
        reads numbers (:func:`to_element`: ``'1/3'``, int, Fraction, backend
        rationals; binary floats only in floating arithmetics)."""
        return to_element(self, value)

    def convert(self, value):  # pragma: no cover - abstract
        raise NotImplementedError

    def format(self, e) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    def is_zero(self, e):
        """True / False, or None when undecidable (e.g. a ball containing 0)."""
        return e == self.zero

    def magnitude(self, e) -> float:
        """A float measure of |e|, used for pivoting in inexact contexts."""
        return abs(float(e))

    def is_finite(self, e) -> bool:
        return True

    def to_fraction(self, e) -> Fraction:
        raise TypeError(f"arithmetic {self.name!r} has no exact rational values")

    def to_float(self, e) -> float:
        return float(e)

    @property
    def unit_roundoff(self) -> float:
        """2**-prec for floating contexts, 0 for exact ones."""
        return 0.0 if self.prec is None else 2.0 ** (-self.prec)

    def local(self):
        """Context manager entered around algorithms (e.g. a ball precision)."""
        return contextlib.nullcontext()

    # A context may provide a fast exact solver: native_solve(M, B) -> X or
    # raise ZeroDivisionError when M is singular.  None means "use linalg".
    native_solve = None
    # A context may multiply matrices natively: native_matmul(A, B) -> A B (lists of
    # rows); None means the generic sums (:func:`exact_khk.linalg.dense.matmul`).
    native_matmul = None
    # A context may hold the n-th roots of unity exactly, for the n dividing
    # ``roots_of_unity`` (cyclo:N: ζ_N): then dft(rows, n, sign) -> for each list w of
    # n elements, [Σ_i w_i ω^(sign·i·j) for j < n], ω a primitive n-th root of unity,
    # the exact DFT of the structured step (:mod:`exact_khk.systems.lie_poisson.circulant_dft`).
    roots_of_unity = 0
    dft = None
    # A context may evaluate many linear forms at one point at once:
    # linear_forms(rows, consts, dim) prepares rows [(k, a_rk), ...] and constants c_r
    # (the caller caches it), apply_forms(prepared, x) -> [c_r + Σ_k a_rk x_k].  None
    # means "use the generic loops".
    linear_forms = None

    def __repr__(self):
        return f"<arith {self.name}>"

    def __eq__(self, other):
        return isinstance(other, Arith) and other.name == self.name

    def __hash__(self):
        return hash(self.name)


def _digits(n) -> str:
    """str(n) for an integer of any size (Python's int refuses beyond 4300 digits
    unless told otherwise; exact orbits go far beyond)."""
    if type(n) is not int or n.bit_length() < 14_000:
        return str(n)
    with any_int_digits():
        return str(n)


class UnreadableNumber(InputError, TypeError):
    """A value that is not a number of the kind asked for (an :class:`InputError`; also a
    ``TypeError``, as operators and ``except TypeError`` around conversions expect)."""


def _as_fraction(value) -> Fraction:
    """An exact rational from int, Fraction, or anything with numerator/denominator;
    anything else raises :class:`UnreadableNumber` (``Arith.convert``'s error for every
    value it cannot read: NaN, None, text, lists)."""
    if isinstance(value, Fraction):
        return value
    if isinstance(value, int):
        return Fraction(value)
    for num, den in (("numerator", "denominator"), ("p", "q")):
        if hasattr(value, num) and hasattr(value, den):
            return Fraction(int(getattr(value, num)), int(getattr(value, den)))
    raise UnreadableNumber(f"cannot convert {_short(value)} ({type(value).__name__}) to an exact rational "
                           f"(read numbers such as '1/3' with ar(value))")


def bareiss_solve(M, B):
    """Fraction-free (Bareiss) elimination over the integers (int, gmpy2 mpz, ...).

    Returns ``(Y, d)`` with ``M Y = d B`` and ``d = ±det M`` (nonzero): every
    intermediate entry is a minor of ``[M | B]`` and each division is exact, so
    integers never grow beyond Hadamard's bound.  Back substitution is
    fraction-free too: ``d M^{-1} B`` is integral.  Raises :class:`SingularMatrix`.

    >>> bareiss_solve([[2, 1], [1, 3]], [[1], [2]])
    ([[1], [3]], 5)
    """
    n, m = len(M), len(B[0])
    R = [list(M[i]) + list(B[i]) for i in range(n)]
    prev = 1
    for k in range(n):
        p = next((i for i in range(k, n) if R[i][k] != 0), None)
        if p is None:
            raise SingularMatrix(f"no nonzero pivot in column {k}")
        R[k], R[p] = R[p], R[k]
        rk, piv = R[k], R[k][k]
        for i in range(k + 1, n):
            ri = R[i]
            rik = ri[k]
            for j in range(k + 1, n + m):
                ri[j] = (piv * ri[j] - rik * rk[j]) // prev
        prev = piv
    d = prev
    Y = [[0] * m for _ in range(n)]
    for i in reversed(range(n)):
        ri = R[i]
        for c in range(m):
            acc = d * ri[n + c]
            for j in range(i + 1, n):
                acc -= ri[j] * Y[j][c]
            Y[i][c] = acc // ri[i]
    return Y, d


class IntegerKernel:
    """Integer linear algebra behind a rational arithmetic: denominators are
    cleared once and systems are solved over Z (fraction-free).

    ``split(v)`` → (integers, common denominator); ``solve(M, B)`` → rows of
    rationals (:func:`bareiss_solve`).

    The dense Kahan step works on *columns* of rationals in the kernel's own
    form: ``column(x)`` makes one from a sequence, ``values(col)`` gives the
    tuple back, ``clear(col)`` is v = (xi, dx) (x = xi/dx).  ``tensor(rows)``
    stores a constant integer matrix W acting on [xi, dx] (sparse rows here),
    ``apply(W, v)`` is W·[xi, dx], ``square(S, v)`` the N×N matrix with
    vec = V·[xi, dx] (S = ``square_tensor(V)``), ``product(R, v)`` the column
    R·[xi, dx] and ``solve_column(M, b, small)`` the column M⁻¹b; ``small``
    says the answer is expected to be far below Cramer's bound (as along Kahan
    orbits), which an output-sensitive solver can use for the N×N systems with
    N in ``small_answer_dims``.  Subclassed for python-flint, whose
    ``fmpz_mat``/``fmpq_mat`` do all of these in C.
    """

    small_answer_dims = range(0)  # Bareiss: its cost follows the Cramer bound anyway

    def __init__(self, name, make, num, den, gcd):
        self.name, self.make, self.num, self.den, self.gcd = name, make, num, den, gcd

    def split(self, v):
        d = self.den(v[0])
        for t in v[1:]:
            q = self.den(t)
            if q != 1:
                d = d * q // self.gcd(d, q)
        return [self.num(t) * (d // self.den(t)) for t in v], d

    def tensor(self, rows):
        return [[(k, c) for k, c in enumerate(row) if c] for row in rows]

    def apply(self, W, v):
        zero = v[0] * 0
        return [sum((c * v[k] for k, c in row), zero) for row in W]

    def solve(self, M, B):
        Y, d = bareiss_solve(M, B)
        return [[self.make(y, d) for y in row] for row in Y]

    def column(self, x):
        return list(x)

    def values(self, col):
        return tuple(col)

    def clear(self, col):
        xi, d = self.split(col)
        return xi + [d]

    def square_tensor(self, rows):
        """The rows of vec(M) for an N×N matrix M = V·v (row-major), stored once
        per distinct row with each entry's index into them: Kahan systems repeat
        rows (a Lie–Poisson one has at most 4n distinct among its 4n²), and the dense
        step then contracts only those."""
        distinct, index = {}, []
        for row in rows:
            index.append(distinct.setdefault(tuple(row), len(distinct)))
        return self.tensor(list(distinct)), index, math.isqrt(len(rows))

    def square(self, S, v):
        U, index, N = S
        flat = self.apply(U, v)
        return [[flat[k] for k in index[i * N:(i + 1) * N]] for i in range(N)]

    def product(self, R, v):
        return [[t] for t in self.apply(R, v)]

    def solve_column(self, M, b, small=False):
        return [row[0] for row in self.solve(M, b)]


class FlintKernel(IntegerKernel):
    """:class:`IntegerKernel` on python-flint ``fmpz_mat`` (solve: ``fmpz_mat.solve``)."""

    def __init__(self, flint):
        self.flint = flint
        super().__init__("flint", flint.fmpq, lambda e: e.p, lambda e: e.q, flint.fmpz.gcd)

    def tensor(self, rows):
        """(W without its last column, that column or None if it is zero), so that
        W·[xi, dx] is two products with the parts ``clear`` returns."""
        fmpz_mat, last = self.flint.fmpz_mat, [r[-1] for r in rows]
        return fmpz_mat([r[:-1] for r in rows]), fmpz_mat(len(rows), 1, last) if any(last) else None

    def apply(self, W, v):
        (Wx, wd), (xi, d) = W, v
        return Wx * xi if wd is None else Wx * xi + wd * d

    def split(self, v):
        xi, d = self.flint.fmpq_mat(len(v), 1, v).numer_denom()
        return xi.entries(), d

    def solve(self, M, B):
        X = self.flint.fmpz_mat(M).solve(self.flint.fmpz_mat(B))
        m, flat = X.ncols(), X.entries()
        return [flat[i * m:(i + 1) * m] for i in range(X.nrows())]

    # columns are N×1 fmpq_mat: numer_denom() clears denominators in C and
    # gives v = (xi as an N×1 fmpz_mat, dx)
    def column(self, x):
        return self.flint.fmpq_mat(len(x), 1, x)

    def values(self, col):
        return tuple(col.entries())

    def clear(self, col):
        return col.numer_denom()

    def square(self, S, v):
        U, index, N = S
        flat = self.apply(U, v).entries()
        return self.flint.fmpz_mat(N, N, [flat[k] for k in index])

    def product(self, R, v):
        return self.apply(R, v)

    #: N where ``fmpz_mat.solve`` costs what Cramer's bound says while Dixon's
    #: p-adic solve (``fmpq_mat.solve(algorithm="dixon")``) stops at the answer's
    #: size: measured along exact orbits, Dixon is up to 6× faster there for
    #: N = 8..14 from about 128 bits, 2–5× slower at random points (answers of
    #: Cramer size), and about the same as ``fmpz_mat.solve`` at N = 16
    small_answer_dims = range(8, 16)

    def solve_column(self, M, b, small=False):
        if small and M.nrows() in self.small_answer_dims:
            q = self.flint.fmpq_mat
            return q(M).solve(q(b), algorithm="dixon")
        return M.solve(b)


class RationalArith(Arith):
    """Exact arithmetic in Q through a backend rational type ``make(p, q)``.

    ``integers`` (an :class:`IntegerKernel` or None) is the fraction-free
    integer linear algebra used by the dense Kahan step and by
    :func:`~exact_khk.linalg.solve`; ``fraction`` has none and stays the
    plain-elimination reference.
    """

    exact = True
    rational = True

    def __init__(self, name, make, num, den, native_solve=None, integers=None):
        self.name, self._make, self._num, self._den = name, make, num, den
        self.zero, self.one = make(0, 1), make(1, 1)
        self.integers = integers
        if native_solve is not None:
            self.native_solve = native_solve

    def convert(self, value):
        q = _as_fraction(value)
        return self._make(q.numerator, q.denominator)

    def to_fraction(self, e) -> Fraction:
        return Fraction(int(self._num(e)), int(self._den(e)))

    def format(self, e) -> str:
        p, q = self._num(e), self._den(e)  # fmpz / mpz print any size themselves
        return _digits(p) if q == 1 else f"{_digits(p)}/{_digits(q)}"

    def magnitude(self, e) -> float:
        return abs(float(self.to_fraction(e)))


def _fraction_arith():
    return RationalArith("fraction", Fraction, lambda e: e.numerator, lambda e: e.denominator)


def _gmpy2_arith():
    import gmpy2

    num, den = (lambda e: e.numerator), (lambda e: e.denominator)
    return RationalArith("gmpy2", gmpy2.mpq, num, den,
                         integers=IntegerKernel("gmpy2", gmpy2.mpq, num, den, gmpy2.gcd))


def _flint_arith():
    import flint

    def solve(M, B):
        X = flint.fmpq_mat(M).solve(flint.fmpq_mat(B))
        m = X.ncols()
        flat = X.entries()
        return [flat[i * m:(i + 1) * m] for i in range(X.nrows())]

    return RationalArith("flint", flint.fmpq, lambda e: e.p, lambda e: e.q, native_solve=solve,
                         integers=FlintKernel(flint))


class MPArith(Arith):
    """mpmath binary floating point at ``prec`` bits, in a private context.

    Each instance owns its own ``mpmath.MPContext``; the global ``mpmath.mp``
    is never touched.  Conversion of rationals is correctly rounded.  mpmath is
    imported here, when the first ``mp:P`` context is made (not on ``import
    exact_khk``: it costs start-up time to every command that never uses it).
    """

    exact = False
    fourier = True

    def __init__(self, prec: int):
        self.prec = check_precision("mp", prec)
        self.name = f"mp:{prec}"
        import mpmath
        from mpmath import libmp

        self._libmp = libmp
        self.ctx = mpmath.MPContext()
        self.ctx.prec = prec
        self.zero, self.one = self.ctx.zero, self.ctx.one

    def convert(self, value):
        if isinstance(value, self.ctx.mpf):
            return +value
        if isinstance(value, float):  # its exact binary value, rounded (nan/inf kept)
            return self.ctx.mpf(float(value))
        libmp = self._libmp
        if hasattr(value, "_mpf_"):  # an mpf of another mpmath context, rounded to this one
            return self.ctx.make_mpf(libmp.normalize(*value._mpf_, self.prec, libmp.round_nearest)
                                     if value._mpf_[1] else value._mpf_)
        q = _as_fraction(value)
        return self.ctx.make_mpf(libmp.from_rational(q.numerator, q.denominator,
                                                     self.prec, libmp.round_nearest))

    def format(self, e) -> str:
        return self._libmp.to_str(e._mpf_, self._libmp.repr_dps(self.prec))

    def magnitude(self, e) -> float:
        return abs(float(e))

    def is_finite(self, e) -> bool:
        return bool(self.ctx.isfinite(e))

    def from_man_exp(self, man, exp):
        """man·2^exp (integers) correctly rounded to this precision."""
        libmp = self._libmp
        return self.ctx.make_mpf(libmp.from_man_exp(int(man), int(exp), self.prec, libmp.round_nearest))

    def to_fraction(self, e) -> Fraction:
        """The exact rational value of a (finite) binary float."""
        if not self.is_finite(e):
            raise ValueError(f"{self.name}: {e} has no rational value")
        sign, man, exp, _ = e._mpf_
        q = Fraction(int(man)) * Fraction(2) ** int(exp)
        return -q if sign else q


class FloatArith(Arith):
    """IEEE-754 double precision (Python floats)."""

    name = "float"
    exact = False
    fourier = True
    lapack = True
    prec = 53
    zero, one = 0.0, 1.0

    def convert(self, value):
        if isinstance(value, float):
            return float(value)  # a numpy float64 becomes a Python float (bool pivot tests)
        q = _as_fraction(value)
        try:
            return float(q)  # correctly rounded
        except OverflowError:  # |q| ≥ 2^1024 (its size: str(q) may be thousands of digits, or refused)
            raise InputError(f"arith float: a number of about 2^{q.numerator.bit_length() - q.denominator.bit_length()} "
                             f"is too large for float64 (use mp:P)") from None

    def format(self, e) -> str:
        return repr(float(e))

    def is_zero(self, e):
        return bool(e == 0.0)

    def magnitude(self, e) -> float:
        return abs(float(e))

    is_finite = staticmethod(math.isfinite)

    def from_man_exp(self, man, exp):
        """man·2^exp (integers), correctly rounded outside the subnormal range; ±inf on overflow."""
        try:
            return math.ldexp(float(int(man)), int(exp))
        except OverflowError:
            return math.copysign(math.inf, int(man))

    def to_fraction(self, e) -> Fraction:
        return Fraction(e)


# --- the registry of names -------------------------------------------------

def _deferred(module: str, name: str):
    """A factory that imports ``module`` (which registers itself, replacing this
    factory) and calls its ``name``: the arithmetics of :mod:`exact_khk.arith.ball`
    and :mod:`exact_khk.arith.cyclotomic` (python-flint) are known by name without
    importing them."""
    def factory(*args):
        return getattr(importlib.import_module(module), name)(*args)

    return factory


_FIXED = {"fraction": _fraction_arith, "gmpy2": _gmpy2_arith, "flint": _flint_arith,
          "float": FloatArith}
_PARAMETRIZED = {"mp": MPArith, "ball": _deferred("exact_khk.arith.ball", "BallArith"),
                 "cyclo": _deferred("exact_khk.arith.cyclotomic", "CycloArith"),
                 "gf": _deferred("exact_khk.arith.cyclotomic", "GFArith")}
_CACHE: dict[str, Arith] = {}


_PARAM_LETTER: dict[str, str] = {"cyclo": "N"}


def register_arith(prefix: str, factory, parametrized: bool = True, letter: str = "P", replace: bool = False):
    """Make ``prefix:PARAM`` (or a plain ``prefix``) a name for :func:`get_arith`.

    ``factory(int_param)`` (or ``factory()``) returns an :class:`Arith`;
    ``letter`` names the parameter in :func:`arith_names` (``cyclo:N``).  A name that is
    already known (``flint``, ``mp``, ...) is refused unless ``replace=True``: silently
    replacing a built-in arithmetic would change every result computed under its name.
    """
    if not isinstance(prefix, str) or not re.fullmatch(r"[a-z][a-z0-9_]*", prefix, re.ASCII):
        raise InputError(f"register_arith: expected a lower-case name such as 'myarith', got {_short(prefix)}")
    if not callable(factory):
        raise InputError(f"register_arith: the factory must be callable, got {_short(factory)}")
    if prefix in _FIXED or prefix in _PARAMETRIZED:
        if not replace:
            raise InputError(f"register_arith: {prefix!r} is already an arithmetic; pass replace=True to "
                             f"replace it")
        _FIXED.pop(prefix, None)
        _PARAMETRIZED.pop(prefix, None)
        for key in [k for k in _CACHE if k.partition(":")[0] == prefix]:  # instances of the old factory
            del _CACHE[key]
    (_PARAMETRIZED if parametrized else _FIXED)[prefix] = factory
    if parametrized:
        _PARAM_LETTER[prefix] = letter


def arith_names() -> list[str]:
    """The names understood by :func:`get_arith` (``X:P`` for parametrized ones,
    ``cyclo:N``)."""
    return sorted(_FIXED) + sorted(f"{p}:{_PARAM_LETTER.get(p, 'P')}" for p in _PARAMETRIZED)


def get_arith(name=None) -> Arith:
    """The arithmetic called ``name`` (an :class:`Arith` is passed through).

    ``None`` gives the default: the fastest exact arithmetic installed
    (``flint``, else ``gmpy2``, else ``fraction``).
    """
    if isinstance(name, Arith):
        return name
    if name is None:
        return default_arith()
    if not isinstance(name, str):
        raise InputError(f"arith: expected a name such as 'flint' or 'mp:256', got {name!r}")
    key = name.strip().lower()
    if key in _CACHE:
        return _CACHE[key]
    prefix, _, param = key.partition(":")
    if not param and prefix in _FIXED:
        try:
            ar = _FIXED[prefix]()
        except ImportError as exc:
            raise InputError(f"arith: {name!r} needs a package that is not installed ({exc})") from None
    elif param and prefix in _PARAMETRIZED:
        if len(param) > _MAX_PARAM_DIGITS:
            raise InputError(f"arith: {prefix}:P with a parameter of {len(param)} characters is beyond "
                             f"every limit (see exact-khk --help for the arithmetics and their bounds)")
        if not re.fullmatch(r"[+-]?[0-9]+", param, re.ASCII):  # int() would take '٥٣', '5_3', ' 53'
            raise InputError(f"arith: {name!r}: the parameter after ':' must be an integer in ASCII digits")
        value = int(param)
        ar = _PARAMETRIZED[prefix](value)
    else:
        raise InputError(f"arith: unknown arithmetic {name!r}; known: {', '.join(arith_names())}")
    _CACHE[key] = ar
    return ar


def _is_element(ar, value) -> bool:
    """Whether ``value`` is already an element of ``ar`` (a context whose elements
    share a Python type with other contexts', e.g. Q(ζ_N) or F_P, says so by ``owns``)."""
    if type(value) is not type(ar.zero) or isinstance(value, (int, str)):
        return False
    owns = getattr(ar, "owns", None)
    return True if owns is None else owns(value)


def _is_binary_float(value) -> bool:
    """A real number that is not exact: float, numpy floating, gmpy2 mpfr, mpmath mpf."""
    if isinstance(value, (bool, int, Fraction)):
        return False
    if isinstance(value, float) or hasattr(value, "_mpf_"):
        return True
    return isinstance(value, numbers.Real) and not isinstance(value, numbers.Rational)


def to_element(ar, value, name: str = "value"):
    """``value`` as an element of ``ar``, the way every public function reads numbers.

    Accepted: elements of ``ar``; exact rationals as ``'p'``, ``'p/q'``, decimal
    strings, int, Fraction, gmpy2 ``mpq``, python-flint ``fmpq`` (anything with
    numerator/denominator); and, in floating arithmetics only (``float``,
    ``mp:P``, ``ball:P``), binary floats: Python and numpy floats, mpmath ``mpf``.
    A binary float in an exact arithmetic, or anything else, raises
    :class:`~exact_khk.errors.InputError` naming ``name``.
    """
    if _is_element(ar, value):
        if not ar.exact and not ar.is_finite(value):  # e.g. float('nan') handed to ``float``
            raise InputError(f"{name}: expected a finite number, got {_short(value)}")
        return value
    if _is_binary_float(value):
        if ar.exact:
            raise InputError(f"{name}: {value!r} is a binary float, not an exact rational; "
                             f"write it as a string such as '1/10' or as a Fraction")
        finite = getattr(value, "is_finite", None)  # gmpy2 mpfr (whose _mpf_ breaks on nan), mpf, numpy
        if callable(finite) and not finite():
            raise InputError(f"{name}: expected a finite number, got {_short(value)}")
        try:
            out = ar.convert(value if isinstance(value, float) or hasattr(value, "_mpf_") else float(value))
        except (TypeError, ValueError, OverflowError) as exc:
            raise InputError(f"{name}: cannot read {value!r} in {ar.name} ({exc})") from None
        if not ar.is_finite(out):
            raise InputError(f"{name}: expected a finite number, got {value!r}")
        return out
    if isinstance(value, (str, int, Fraction)):
        from exact_khk.parsing import parse_rational

        value = parse_rational(value, name)
    try:  # exact rationals, backend rationals, elements of a subfield, a Dual over a base, ...
        return ar.convert(value)
    except InputError as exc:
        if not isinstance(exc, UnreadableNumber):
            raise
        raise InputError(f"{name}: cannot read {_short(value)} ({type(value).__name__}) as a number of "
                         f"{ar.name}") from None
    except (TypeError, ValueError, ArithmeticError) as exc:
        raise InputError(f"{name}: cannot read {_short(value)} ({type(value).__name__}) as a number of "
                         f"{ar.name} ({exc})") from None


def to_fraction(ar, value):
    """The exact rational value of ``value`` (an element of ``ar``, or anything
    :func:`to_element` reads) as a :class:`~fractions.Fraction`; a point (list or
    tuple) gives a tuple of Fractions.

    Exact for the rational arithmetics (``flint``, ``gmpy2``, ``fraction``), for
    rational elements of ``cyclo:N`` and for binary floats (``float``, ``mp:P``:
    the float's exact value); for ``ball:P`` the ball's midpoint.  Elements with
    no rational value (an irrational element of Q(ζ_N), F_P, non-finite
    floats) raise :class:`~exact_khk.errors.InputError`.
    """
    if isinstance(value, (list, tuple)):
        return tuple(to_fraction(ar, t) for t in value)
    e = to_element(ar, value)
    try:
        if hasattr(e, "to_fraction"):  # e.g. a CycloNumber
            return e.to_fraction()
        return ar.to_fraction(e)
    except InputError:
        raise
    except (TypeError, ValueError, ArithmeticError) as exc:
        raise InputError(f"{ar.name}: {ar.format(e)} has no exact rational value ({exc})") from None


def point_height(ar, x) -> int:
    """Bits of the largest numerator or denominator of a point (or a single
    number) of a rational arithmetic: the height that governs exact costs."""
    if not isinstance(x, (list, tuple)):
        x = (x,)
    if hasattr(x[0], "height_bits"):  # python-flint fmpq: one call per coordinate
        return max(t.height_bits() for t in x)
    K = ar.integers
    if K is not None:
        return max(max(abs(K.num(t)).bit_length(), K.den(t).bit_length()) for t in x)
    return max(max(abs(q.numerator).bit_length(), q.denominator.bit_length())
               for q in map(ar.to_fraction, x))


def default_arith() -> Arith:
    """The fastest exact arithmetic that is installed."""
    for name in ("flint", "gmpy2", "fraction"):
        try:
            return get_arith(name)
        except InputError:
            continue
    raise AssertionError("unreachable: fraction is always available")


def exact_arith_names() -> list[str]:
    """The exact rational arithmetics that are installed, fastest first."""
    out = []
    for name in ("flint", "gmpy2", "fraction"):
        try:
            get_arith(name)
            out.append(name)
        except InputError:
            pass
    return out


def as_point(ar, x, dim: int, name: str = "x"):
    """Convert a point into a tuple of elements of ``ar``; checks the dimension.

    Coordinates are read by :func:`to_element`: strings
    (``'1/3'``, ``'0.25'``), ints, Fractions, gmpy2/python-flint rationals,
    elements of ``ar``; binary floats (Python or numpy) only in floating
    arithmetics, where they must be finite.  Anything else raises
    :class:`~exact_khk.errors.InputError` naming the coordinate."""
    if type(x) is tuple and len(x) == dim and (
            ar.rational and all(type(t) is type(ar.zero) for t in x)
            or ar.lapack and all(type(t) is float for t in x) and all(map(math.isfinite, x))):
        return x  # already a point of ar (e.g. a previous step's result)
    if isinstance(x, (str, bytes, dict, set, frozenset)) or not hasattr(x, "__len__") and not hasattr(x, "__iter__"):
        # (a dict would give its keys, a set no order)
        raise InputError(f"{name}: expected a sequence of {dim} numbers, got {_short(x)}")
    try:
        coords = list(x)
    except TypeError:
        raise InputError(f"{name}: expected a sequence of {dim} numbers, got {_short(x)}") from None
    if len(coords) != dim:
        raise InputError(f"{name}: expected {dim} coordinates, got {len(coords)}")
    out = []
    for i, t in enumerate(coords):
        out.append(to_element(ar, t, f"{name}[{i}]"))
        if not ar.exact and not ar.is_finite(out[-1]):
            raise InputError(f"{name}[{i}]: expected a finite number, got {_short(t)}")
    return tuple(out)
