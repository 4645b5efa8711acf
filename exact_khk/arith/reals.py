"""Real (not only rational) input: intervals and exact reals, read into arb balls.

A *real* is given as text and read into a python-flint ``arb`` ball at a
working precision P (bits) that is guaranteed to contain it.  Three forms:

* an **expression** of exact numbers: integers, fractions ``p/q`` and decimals,
  ``+ - * / ^ **`` (``^`` is a power), parentheses, the constants ``pi`` and
  ``e``, and the functions ``sqrt exp log sin cos tan atan``, e.g.
  ``sqrt(2)``, ``1/3 + pi/4``, ``2^(1/3)``;
* an **interval** ``[lo, hi]`` with lo ≤ hi expressions: the ball contains every
  real of the interval;
* a **ball** ``m+-r`` (or ``m±r``) with r ≥ 0: every real within r of m.

**How decimals are read.**  A decimal such as ``0.1`` is the exact rational it
denotes (1/10), as everywhere in exact_khk — not the binary double nearest to
it, and not a measured value with an implied uncertainty.  To say "0.1, known
to ±5·10⁻³", write ``0.1+-0.005`` or ``[0.095,0.105]``.  Exact input that is
not dyadic (1/10, sqrt(2)) becomes a ball of radius about 2^-P·|x|; a width-zero
interval ``[1/2,1/2]`` is the number 1/2 (exactly, when dyadic).

>>> import flint
>>> x = parse_real("sqrt(2)", 128)
>>> with flint.ctx.workprec(128):
...     print(x.overlaps(flint.arb(2).sqrt()), x.rad() < flint.arb(2) ** -120)
True True
>>> parse_real("1.25+-0.05", 64).contains(flint.arb("1.3"))
True
>>> parse_real("[1/2, 1/2]", 64).is_exact()
True
>>> [(round(float(t.lower()), 6), round(float(t.upper()), 6))  # arb radii are rounded up (30 bits)
...  for t in parse_real_vector("[1,2], sqrt(2), 0.5+-1/8", 64, "x0", 3)]
[(1.0, 2.0), (1.414214, 1.414214), (0.375, 0.625)]
>>> parse_real("[2, 1]", 64)
Traceback (most recent call last):
...
exact_khk.errors.InputError: x: empty interval '[2, 1]' (the lower end is above the upper end)
>>> parse_real("1+-(-1)", 64)
Traceback (most recent call last):
...
exact_khk.errors.InputError: x: negative radius in '1+-(-1)'

Malformed text, a negative radius, an empty interval, a non-finite value
(``log(0)``, ``1/0``) or a text longer than :data:`MAX_REAL_CHARS` raises
:class:`~exact_khk.errors.InputError` naming the input.
"""

from __future__ import annotations

import ast

import flint

from exact_khk.arith import check_precision
from exact_khk.errors import InputError
from exact_khk.parsing import _short, parse_rational

#: the longest text of one real (characters)
MAX_REAL_CHARS = 2000
#: the largest |exponent| of a power with an integer exponent (beyond: refused, the
#: number would not fit in memory as an exact rational, and a ball of it is useless)
MAX_POWER = 100_000

_FUNCTIONS = {"sqrt": "sqrt", "exp": "exp", "log": "log", "sin": "sin", "cos": "cos", "tan": "tan",
              "atan": "atan"}


def _const(name):
    return {"pi": flint.arb.pi, "e": flint.arb.const_e}[name]()


def _exact(node):
    """The exact rational of a numeric literal (decimals read exactly), else None."""
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
        return node.value
    return None


def _eval(node, text, name, literal):
    """arb value of an expression node, at the precision in force."""
    if isinstance(node, ast.Expression):
        return _eval(node.body, text, name, literal)
    if isinstance(node, ast.Constant) and not isinstance(node.value, bool) and isinstance(node.value, (int, float)):
        # the literal's own text, read exactly (0.1 is 1/10, not the nearest double)
        seg = ast.get_source_segment(literal, node) or repr(node.value)
        q = parse_rational(seg, name)  # with the parser's limits (an exponent of 10^11 is refused, not computed)
        return flint.arb(flint.fmpq(q.numerator, q.denominator))
    if isinstance(node, ast.Name) and node.id in ("pi", "e"):
        return _const(node.id)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.UAdd, ast.USub)):
        v = _eval(node.operand, text, name, literal)
        return -v if isinstance(node.op, ast.USub) else v
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow)):
        a = _eval(node.left, text, name, literal)
        if isinstance(node.op, ast.Pow):
            k = _exact(node.right) if not isinstance(node.right, ast.UnaryOp) else None
            if isinstance(k, int):
                if abs(k) > MAX_POWER:
                    raise InputError(f"{name}: the exponent {k} in {_short(text, 60)} is beyond {MAX_POWER}")
                return a ** k
            b = _eval(node.right, text, name, literal)
            return a ** b
        b = _eval(node.right, text, name, literal)
        if isinstance(node.op, ast.Add):
            return a + b
        if isinstance(node.op, ast.Sub):
            return a - b
        if isinstance(node.op, ast.Mult):
            return a * b
        if b.contains(0):
            raise InputError(f"{name}: division by a quantity that may be 0 in {_short(text, 60)}")
        return a / b
    if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _FUNCTIONS
            and len(node.args) == 1 and not node.keywords):
        v = _eval(node.args[0], text, name, literal)
        return getattr(v, _FUNCTIONS[node.func.id])()
    raise InputError(f"{name}: cannot read {_short(text, 60)} as a real (allowed: numbers such as 2, 1/3, 0.25, "
                     f"+ - * / ^, parentheses, pi, e, {', '.join(_FUNCTIONS)}; intervals [lo,hi]; balls m+-r)")


def _expression(text, prec, name):
    text = text.strip()
    literal = text.replace("^", "**")
    try:
        tree = ast.parse(literal, mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        raise InputError(f"{name}: cannot read {_short(text, 60)} as a real (malformed expression)") from None
    try:
        with flint.ctx.workprec(prec + 20):  # guard bits: the final ball is rounded to P below
            v = _eval(tree, text, name, literal)
    except RecursionError:
        raise InputError(f"{name}: {_short(text, 60)} is nested too deeply") from None
    except (ValueError, ZeroDivisionError, OverflowError, AssertionError) as exc:
        raise InputError(f"{name}: cannot evaluate {_short(text, 60)} ({exc})") from None
    if not v.is_finite():
        raise InputError(f"{name}: {_short(text, 60)} is not a finite real (a pole, log of 0, or overflow)")
    return v


def parse_real(text, prec: int, name: str = "x"):
    """The real ``text`` (an expression, ``[lo, hi]`` or ``m+-r``; see the module
    docstring) as an arb ball at ``prec`` bits that contains it."""
    prec = check_precision("ball", prec)
    if isinstance(text, flint.arb):
        return text
    if not isinstance(text, str):
        text = str(text)
    t = text.strip()
    if not t:
        raise InputError(f"{name}: expected a real, got an empty text")
    if len(t) > MAX_REAL_CHARS:
        raise InputError(f"{name}: the text has {len(t)} characters, beyond the limit of {MAX_REAL_CHARS} for one "
                         f"real (MAX_REAL_CHARS)")
    if t.startswith("["):
        if not t.endswith("]") or t.count("[") != 1 or t.count("]") != 1:
            raise InputError(f"{name}: malformed interval {_short(t, 60)} (expected [lo, hi])")
        parts = _split_top(t[1:-1], name)
        if len(parts) != 2:
            raise InputError(f"{name}: malformed interval {_short(t, 60)} (expected [lo, hi] with two ends)")
        lo, hi = (_expression(p, prec, name) for p in parts)
        if lo > hi:
            raise InputError(f"{name}: empty interval {_short(t, 60)} (the lower end is above the upper end)")
        with flint.ctx.workprec(prec):
            if lo.mid() == hi.mid() and lo.rad() == hi.rad():
                return +lo  # width zero: the same ball as the number itself
            return lo.union(hi)
    for sep in ("+-", "±", "+/-"):
        if sep in t:
            m_text, _, r_text = t.partition(sep)
            if not m_text.strip() or not r_text.strip():
                raise InputError(f"{name}: malformed ball {_short(t, 60)} (expected m+-r)")
            m, r = _expression(m_text, prec, name), _expression(r_text, prec, name)
            if r < 0 or r.mid() < 0:
                raise InputError(f"{name}: negative radius in {_short(t, 60)}")
            with flint.ctx.workprec(prec):
                rad = flint.arb(abs(r).upper())  # an upper bound of r, exactly
                return +m if rad.is_zero() else m + flint.arb(0, rad)
    v = _expression(t, prec, name)
    with flint.ctx.workprec(prec):
        return +v  # rounded to P bits, outward


def _split_top(text, name):
    """Split at commas outside brackets and parentheses."""
    parts, depth, cur = [], 0, []
    for ch in text:
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
            if depth < 0:
                raise InputError(f"{name}: unbalanced brackets in {_short(text, 60)}")
        if ch == "," and depth == 0:
            parts.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    if depth != 0:
        raise InputError(f"{name}: unbalanced brackets in {_short(text, 60)}")
    parts.append("".join(cur))
    return parts


def parse_real_vector(text, prec: int, name: str = "x0", dim: int | None = None) -> tuple:
    """A comma-separated vector of reals (commas inside ``[..]`` or ``(..)`` do not
    separate), or a sequence of texts/numbers, as a tuple of arb balls."""
    if isinstance(text, str):
        if len(text) > MAX_REAL_CHARS * max(dim or text.count(",") + 1, 1):
            raise InputError(f"{name}: the text has {len(text)} characters, beyond the limit of "
                             f"{MAX_REAL_CHARS} per coordinate")
        items = [p.strip() for p in _split_top(text, name)]
    else:
        items = [t if isinstance(t, (str, flint.arb)) else _number_text(t) for t in text]
    if dim is not None and len(items) != dim:
        raise InputError(f"{name}: expected {dim} coordinates, got {len(items)}")
    return tuple(parse_real(t, prec, f"{name}[{i}]") for i, t in enumerate(items))


def _number_text(t):
    """An exact number (int, Fraction, fmpq, mpq) as text; binary floats are refused."""
    if isinstance(t, float):
        raise InputError(f"{t!r} is a binary float; write reals as text ('0.1', 'sqrt(2)', '[1,2]')")
    if hasattr(t, "numerator") and hasattr(t, "denominator"):
        return f"{int(t.numerator)}/{int(t.denominator)}"
    if hasattr(t, "p") and hasattr(t, "q"):
        return f"{int(t.p)}/{int(t.q)}"
    return str(t)


def is_rational_text(text) -> bool:
    """Whether a real given as text is a plain rational (no interval, ball, constant
    or function): then the exact orbit can serve as the reference."""
    from exact_khk.parsing import parse_rational

    if not isinstance(text, str):
        return not isinstance(text, (float, flint.arb))
    try:
        parse_rational(text, "x")
        return True
    except InputError:
        return False
