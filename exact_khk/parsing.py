"""Parsing of user input into exact rationals, with errors that name the argument.

>>> parse_rational("-3/4", "eps")
Fraction(-3, 4)
>>> parse_vector("1/2,-3,0", "a", length=3)
(Fraction(1, 2), Fraction(-3, 1), Fraction(0, 1))
>>> parse_rational("1/0", "eps")
Traceback (most recent call last):
...
exact_khk.errors.InputError: eps: '1/0' is not a rational number (zero denominator)
"""

from __future__ import annotations

import contextlib
import re
import stat
import sys
from fractions import Fraction
from pathlib import Path

from exact_khk.errors import InputError

#: ASCII digits only (re.ASCII: Python's \d and int() also take Arabic-Indic or full-width digits)
_RATIONAL = re.compile(r"^[+-]?(\d+(/\d+)?|\d*\.\d+([eE][+-]?\d+)?|\d+[eE][+-]?\d+)$", re.ASCII)

#: the largest |exponent| of a decimal such as '1e-300' (10^10000 has 10 001 digits;
#: beyond, merely writing the number down costs more than any computation here)
MAX_EXPONENT = 10_000
#: the longest number text accepted (a million digits)
MAX_DIGITS = 1_000_000
#: the most steps of one orbit (API and command line; beyond, the orbit alone is more
#: than 10⁷ points)
MAX_STEPS = 10_000_000
#: the largest n of the Lie–Poisson family (API and command line): beyond it even the O(n)
#: set-up (drawing the system and x0, the circulant structure) takes minutes and one exact
#: structured step hours
MAX_N = 100_000


@contextlib.contextmanager
def any_int_digits():
    """Lift Python's 4300-digit int↔str limit inside the block and restore it after
    (exact orbits print and parse far larger integers; the caller's setting is kept)."""
    limit = sys.get_int_max_str_digits() if hasattr(sys, "get_int_max_str_digits") else 0
    if limit:
        sys.set_int_max_str_digits(0)
    try:
        yield
    finally:
        if limit:
            sys.set_int_max_str_digits(limit)


def _fraction(text: str) -> Fraction:
    """Fraction(text) for a validated number text, free of Python's 4300-digit
    int/str limit (exact orbits reach far larger numbers)."""
    mantissa, _, exp = text.lower().partition("e")
    if exp and abs(int(exp)) > MAX_EXPONENT:
        raise ValueError(f"exponent {exp} beyond the limit of {MAX_EXPONENT}")
    with any_int_digits():
        if "/" in mantissa:
            num, den = mantissa.split("/")
            return Fraction(int(num), int(den))
        q = Fraction(mantissa)
        return q * Fraction(10) ** int(exp) if exp else q


def parse_rational(value, name: str) -> Fraction:
    """An exact rational from ``'p'``, ``'p/q'``, a decimal like ``'0.1'`` (= 1/10),
    an int, a Fraction, or a backend rational (gmpy2 mpq, flint fmpq).

    Floats are refused: a binary float is rarely the rational a user meant.
    """
    if isinstance(value, bool):
        raise InputError(f"{name}: expected a rational number, got {value!r}")
    if isinstance(value, Fraction):
        return value
    if isinstance(value, int):
        return Fraction(value)
    if isinstance(value, float):
        raise InputError(f"{name}: {value!r} is a binary float, not an exact rational; "
                         f"write it as a string such as '1/10' or as a Fraction")
    if isinstance(value, str):
        text = re.sub(r"\s*/\s*", "/", value.strip())  # '1 / 10' is 1/10; '1 0' is no number
        if len(text) > MAX_DIGITS:
            raise InputError(f"{name}: a number of {len(text)} characters is beyond the limit of {MAX_DIGITS}")
        if not _RATIONAL.match(text):
            raise InputError(f"{name}: {_short(value)} is not a rational number (expected 'p', 'p/q' or a decimal)")
        try:
            return _fraction(text)
        except ZeroDivisionError:
            raise InputError(f"{name}: {_short(value)} is not a rational number (zero denominator)") from None
        except ValueError as exc:
            raise InputError(f"{name}: {_short(value)}: {exc}") from None
    for num, den in (("numerator", "denominator"), ("p", "q")):
        if hasattr(value, num) and hasattr(value, den):
            try:
                return Fraction(int(getattr(value, num)), int(getattr(value, den)))
            except (TypeError, ValueError, ZeroDivisionError):
                break
    raise InputError(f"{name}: cannot read {value!r} ({type(value).__name__}) as a rational number")


def check_count(value, name: str, low: int, high: int) -> int:
    """``value`` if it is an int (not a bool) in [low, high], else InputError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise InputError(f"{name}: expected an integer in [{low}, {high}], got {_short(value)}")
    return value


def check_progress(value, name: str = "progress"):
    """``value`` if it is None or callable (a progress callback), else InputError naming ``name``
    (an int there was a raw TypeError 'int' object is not callable, deep inside a search)."""
    if value is not None and not callable(value):
        raise InputError(f"{name}: expected a function (a progress callback) or None, got {_short(value)}")
    return value


def _short(value, width: int = 60) -> str:
    """repr of ``value``, cut to ``width`` characters for a one-line message (an integer
    beyond Python's int-to-str limit by its size)."""
    try:
        text = repr(value)
    except ValueError:  # e.g. a 5000-digit int: "Exceeds the limit (4300 digits)"
        bits = value.bit_length() if isinstance(value, int) else None
        return f"<an integer of about {int(bits * 0.30103) + 1} digits>" if bits else f"<a {type(value).__name__}>"
    return text if len(text) <= width else text[:width - 12] + f"...({len(text)} ch)"


def read_text_file(path, what: str, max_bytes: int) -> str:
    """The UTF-8 text of a user's input file (``what``: e.g. 'system file'); every
    problem (missing, a folder, too large, not UTF-8, unreadable) is an InputError
    naming the file."""
    try:
        p = Path(path)
        if p.is_dir():
            raise InputError(f"{path}: is a folder, not a {what}")
        if not stat.S_ISREG(p.stat().st_mode):  # /dev/zero would never end, a FIFO would block
            raise InputError(f"{path}: not a regular file (a device or a pipe), not a {what}")
        with open(p, "rb") as fh:  # at most max_bytes + 1 (a file may grow while it is read)
            data = fh.read(max_bytes + 1)
        if len(data) > max_bytes:
            raise InputError(f"{path}: the file is larger than {max_bytes} bytes")
        return data.decode("utf-8")
    except InputError:
        raise
    except FileNotFoundError:
        raise InputError(f"{path}: no such {what}") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a UTF-8 text file") from None
    except (TypeError, ValueError) as exc:  # not a path; a NUL byte in it
        raise InputError(f"{_short(path)}: not a file name ({exc})") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read the {what} ({exc.strerror or exc})") from None


def poly_text(coeffs, var: str = "x", ascending: bool = True) -> str:
    """The text of a univariate polynomial with rational coefficients, lowest degree
    first (``ascending``) or highest first in ``coeffs``; terms are printed from the
    lowest degree when ascending, from the highest otherwise.

    >>> poly_text([Fraction(1, 3), Fraction(-2, 3), 1], "z")
    '1/3 - 2/3*z + z^2'
    >>> poly_text([1, 0, -3, 2], ascending=False)
    'x^3 - 3*x + 2'
    """
    coeffs = list(coeffs)
    deg = len(coeffs) - 1
    parts = []
    for i, c in enumerate(coeffs):
        if c == 0:
            continue
        k = i if ascending else deg - i
        mono = "" if k == 0 else (var if k == 1 else f"{var}^{k}")
        mag = abs(c)
        with any_int_digits():  # coefficients of any size (a recurrence fitted to huge terms)
            body = str(mag) if not mono else (mono if mag == 1 else f"{mag}*{mono}")
        parts.append(("-" if c < 0 else "+", body))
    if not parts:
        return "0"
    head = ("-" if parts[0][0] == "-" else "") + parts[0][1]
    return head + "".join(f" {s} {b}" for s, b in parts[1:])


def parse_vector(value, name: str, length: int | None = None) -> tuple[Fraction, ...]:
    """A tuple of rationals from ``'1/2,-3,0'`` or a sequence; checks the length."""
    if isinstance(value, str):
        parts = [p for p in value.replace(";", ",").split(",")]
        if any(not p.strip() for p in parts):
            raise InputError(f"{name}: empty entry in {value!r} (expected comma-separated rationals)")
    else:
        try:
            parts = list(value)
        except TypeError:
            raise InputError(f"{name}: expected a sequence of rationals, got {value!r}") from None
    out = tuple(parse_rational(p, f"{name}[{i}]") for i, p in enumerate(parts))
    if length is not None and len(out) != length:
        raise InputError(f"{name}: expected {length} entries, got {len(out)}")
    return out


def parse_signs(value, n: int) -> tuple[int, ...]:
    """A sign pattern ``'-++'`` (s_0 first) as a tuple of ±1 of length n."""
    if isinstance(value, str):
        text = value.strip()
        if len(text) != n or any(ch not in "+-" for ch in text):
            raise InputError(f"signs: {value!r} must be {n} characters, each '+' or '-' (s_0 first)")
        return tuple(1 if ch == "+" else -1 for ch in text)
    try:
        out = tuple(value)
    except TypeError:
        raise InputError(f"signs: expected a string such as '-++' or a sequence of +1/-1, "
                         f"got {type(value).__name__}") from None
    # integers ±1 only (numpy ints included): no bools, no floats truncated, no strings
    if len(out) != n or any(isinstance(s, bool) or not hasattr(s, "__index__") or s not in (1, -1)
                            for s in out):
        raise InputError(f"signs: {value!r} must be {n} entries, each the integer +1 or -1")
    return tuple(int(s) for s in out)


def format_signs(signs) -> str:
    return "".join("+" if s > 0 else "-" for s in signs)
