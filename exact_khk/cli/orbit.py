"""``exact-khk orbit``: iterate a Kahan map and print the orbit (a thin view of
:class:`~exact_khk.kahan.map.KahanMap`)."""

from __future__ import annotations

import math
from fractions import Fraction

from exact_khk.arith import get_arith, point_height
from exact_khk.cli.options import (Progress, add_field_options, add_json_option, add_system_options, check_output,
                                   check_resources, field_name, system_from_args, write_json)
from exact_khk.kahan.map import METHODS, KahanMap


def register(sub):
    p = sub.add_parser("orbit", help="iterate a Kahan map and print the orbit",
                       description="Iterate the Kahan map of a quadratic field (the built-in Lie–Poisson system, "
                       "the family with --n/--a/--b/--c/--seed, or --system NAME|FILE) and print the orbit.")
    add_system_options(p)
    add_field_options(p)
    p.add_argument("--method", choices=METHODS, default="auto",
                   help="how each step is solved: dense (one 2n x 2n solve), structured (2x2 over "
                        "Q[t]/(t^n - 1), or the DFT for floating arithmetics), split (exact, n < 16: "
                        "2x2 over each factor of t^n - 1); default auto: the fastest measured path")
    add_json_option(p, "the orbit (exact 'p/q' strings, all digits of floats)")
    p.set_defaults(func=cmd_orbit)


def cmd_orbit(args):
    check_output(args.json)
    system, x0, eps = system_from_args(args)
    ar = get_arith(args.arith)
    fld = _field(system, args, ar)
    phi = KahanMap(fld, eps, ar, method=args.method)
    check_resources("orbit", system, phi, x0, args.steps, dense=phi.structure is None and not phi.split)
    with Progress(args, args.steps, "orbit") as progress:
        pts = phi.orbit(x0, args.steps, progress=progress)
    growth = _height_growth(ar, pts)
    if args.json is not None:
        from exact_khk.certification.records import library_versions

        write_json({"system": system.to_json(), "field": fld.label, "signs": getattr(fld, "signs", None),
                    "eps": str(eps), "steps": args.steps, "arith": ar.name, "exact": ar.exact,
                    "method": args.method, "path": phi.path,
                    "x0": [str(t) for t in x0],
                    "orbit": [[ar.format(t) for t in p] for p in pts],
                    "height_growth": growth.to_json() if growth else None,
                    "versions": library_versions()}, args.json)
        if args.json == "-":
            return 0
    print(system.describe())
    kind = "exact" if ar.exact else f"{ar.prec}-bit floating point"
    print(f"field {fld.label}, eps = {_abbreviate(eps)}, {args.steps} steps, arithmetic {ar.name} ({kind}), "
          f"method {args.method}: {phi.path}")
    if not (ar.rational or not ar.exact):  # Q(zeta), F_p: no real approximation to show
        for k, p in enumerate(pts):
            print(f"{k:>4}  (" + ", ".join(ar.format(t) for t in p) + ")")
        return 0
    if ar.exact:
        print("coordinates are the exact rationals rounded to 8 significant digits for display; "
              "'bits' is the largest numerator/denominator bit length (--json prints them exactly)")
    else:
        print(f"coordinates are the {ar.name} values rounded to 8 significant digits (--json prints all digits)")
    head = f"{'k':>4}  " + "  ".join(f"{name[:15]:>15}" for name in _names(system))
    print(head + ("   bits" if ar.exact else ""))
    for k, p in enumerate(pts):
        row = f"{k:>4}  " + "  ".join(f"{_display(ar, t):>15}" for t in p)
        if ar.exact:
            row += f"  {point_height(ar, p):>5}"
        print(row)
    if growth:
        print(growth.summary())
    return 0


def _height_growth(ar, pts):
    """The height growth of an exact rational orbit of at least 4 steps
    (:mod:`exact_khk.diagnostics.heights`), else None."""
    if not ar.rational or len(pts) < 5:
        return None
    from exact_khk.diagnostics.heights import classify_heights

    return classify_heights([point_height(ar, p) for p in pts])




def _field(system, args, ar):
    """The field to iterate (:meth:`~exact_khk.systems.base.System.named_field`); a non-rational
    involution is built over Q(ω) when ``ar`` holds ω (asked only when a pattern is named)."""
    from exact_khk.systems.lie_poisson.system import expresses_omega

    return system.named_field(field_name(system, args), cyclotomic=lambda: expresses_omega(ar, system.n))


def _display(ar, t) -> str:
    """t to 8 significant digits, also beyond the float range (exact rationals of
    any size, mp:P floats with huge exponents)."""
    try:
        v = ar.to_float(t)
        if math.isfinite(v) and abs(v) > 1e-300:
            return f"{v:.8g}"
    except (OverflowError, ValueError, ZeroDivisionError):
        pass
    if ar.rational:  # beyond the float range: the leading digits of a 64-bit arb ball, cheap at any height
        return _leading(*_parts(t))
    try:
        q = ar.to_fraction(t)
    except (TypeError, ValueError, ArithmeticError):
        return ar.format(t)[:15]
    if q == 0:
        return "0"
    sign, q = ("-" if q < 0 else ""), abs(q)
    e = (q.numerator.bit_length() - q.denominator.bit_length()) * 30103 // 100000  # ≈ log10 q
    m = q / Fraction(10) ** e
    while m >= 10:
        m, e = m / 10, e + 1
    while m < 1:
        m, e = m * 10, e - 1
    digits = round(m * 10 ** 7)
    if digits >= 10 ** 8:
        digits, e = digits // 10, e + 1
    text = str(digits)
    return f"{sign}{text[0]}.{text[1:].rstrip('0') or '0'}e{e:+d}"


def _parts(t):
    """(numerator, denominator) of an exact rational of any backend (fmpq, mpq, Fraction)."""
    return (t.p, t.q) if hasattr(t, "p") else (t.numerator, t.denominator)


#: the most characters a number takes in the header; beyond, its leading digits and size
MAX_SHOWN_CHARS = 60


def _leading(p, q) -> str:
    """p/q to 8 significant digits by a 64-bit arb ball (p, q integers of any size)."""
    import flint

    p, q = (t if isinstance(t, flint.fmpz) else flint.fmpz(int(t)) for t in (p, q))  # gmpy2's mpz: by int
    with flint.ctx.workprec(64):
        text = (flint.arb(p) / flint.arb(q)).mid().str(8, radius=False)
    mantissa, e, exponent = text.partition("e")
    if "." in mantissa:
        mantissa = mantissa.rstrip("0").rstrip(".") if e else mantissa
    return mantissa + e + exponent


def _abbreviate(q) -> str:
    """A rational in full, or beyond :data:`MAX_SHOWN_CHARS` characters (estimated from bit
    lengths: printing a 10^5-digit integer costs seconds) its 8 leading digits and its size."""
    p, d = _parts(q)
    digits = [int(abs(v).bit_length() * 0.30103) + 1 for v in (p, d)]
    if sum(digits) + 1 <= MAX_SHOWN_CHARS:
        return str(q)
    return f"{_leading(p, d)} (a rational of about {digits[0]:,}/{digits[1]:,} digits; --json prints it exactly)"


def _names(system):
    return list(system.coordinate_names())
