"""Shared ground of the studies: exact reference orbits, error measures against them,
the integrals and commuting fields a study follows, and the per-step records.

:mod:`~exact_khk.studies.scaling` and :mod:`~exact_khk.studies.enclosure` both build on it
(neither imports the other's helpers, so the two modules form no import circle).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from fractions import Fraction

import flint

from exact_khk.arith import get_arith, point_height
from exact_khk.arith.ball import BallArith, ball_mid, ball_rad
from exact_khk.errors import InputError, SingularStepError
from exact_khk.kahan.map import KahanMap


LOG10_2 = math.log10(2)
#: the exact reference orbit stops past this height (bits of its largest numerator or
#: denominator).  Heights that double each step (a non-integrable map) pass it within
#: about 20 steps, where one exact step already takes seconds; the Lie–Poisson orbits
#: grow by about 9 bits per step (n = 3).
MAX_EXACT_BITS = 1 << 19


def to_fmpq(ar, e) -> flint.fmpq:
    """The exact rational value of an element (a ball's midpoint)."""
    if isinstance(ar, BallArith):
        return ball_mid(e)
    if isinstance(e, flint.fmpq):
        return e
    q = ar.to_fraction(e)
    return flint.fmpq(q.numerator, q.denominator)


def log10q(q) -> float | None:
    """log10 |q| of an exact rational (any size), None for 0."""
    q = flint.fmpq(q)
    return None if q == 0 else _log10_ratio(abs(int(q.p)), int(q.q))


def _log10_ratio(a: int, b: int) -> float:
    """log10(a/b) for positive integers of any size, to within about 10^-14: the binary
    exponents are subtracted as integers, before the one multiplication by log10 2."""
    sa, sb = max(a.bit_length() - 64, 0), max(b.bit_length() - 64, 0)
    return (math.log2(a >> sa) - math.log2(b >> sb) + (sa - sb)) * LOG10_2


def _norm(qs):
    return max(abs(q) for q in qs)


def _err_bound(ar, e, exact):
    """An exact rational bound of |e − exact| (balls: |mid − exact| + rad)."""
    d = abs(to_fmpq(ar, e) - exact)
    return d + ball_rad(e) if isinstance(ar, BallArith) else d


def _rel(num, den):
    """log10 of num/den; of num when den = 0 (a relative size of a zero reference is meaningless)."""
    return log10q(num / den if den != 0 else num)


def _log10_gap(x, e) -> float | None:
    """log10 |x − e| of two rationals, None when they are equal.  The difference is not
    reduced to lowest terms: against a reference thousands of bits high that gcd, and the
    comparisons of a max over rationals, cost far more than the logarithms."""
    num = x.p * e.q - e.p * x.q
    return None if num == 0 else _log10_ratio(abs(int(num)), int(x.q * e.q))


def vs_exact(xs, ex, ball=False) -> tuple:
    """``(error, radius)``: log10 of max_i |mid(x_i) − e_i| / ‖e‖∞ and, for balls, of
    max_i rad(x_i) / ‖e‖∞ (None: 0; relative to 1 when e = 0), as :func:`_rel` gives
    them, from logarithms (``xs`` in any arithmetic, balls when ``ball``)."""
    ref = max((v for v in map(log10q, ex) if v is not None), default=0.0)

    def rel(logs):
        logs = [v for v in logs if v is not None]
        return max(logs) - ref if logs else None

    mids = [ball_mid(t) if ball else t for t in xs]
    err = rel(_log10_gap(m, e) for m, e in zip(mids, ex))
    return err, (rel(log10q(ball_rad(t)) for t in xs) if ball else None)


# --- what the diagnostics check ------------------------------------------------


def declared(system) -> tuple[dict, dict]:
    """What the diagnostics check: ({name: integral ``I(ar, x, eps)``}, {name: field
    declared to commute with f}).

    What the system says a study follows (:meth:`~exact_khk.systems.base.System.tracked`):
    by default its integrals and the fields after ``'f'``; the Lie–Poisson family gives
    H̃ of f, K̃ of the associated field g of B_0, and that g.

    >>> from exact_khk.systems.lie_poisson import default_system
    >>> ints, fields = declared(default_system())
    >>> list(ints), list(fields)
    (['H~', 'K~'], ['g[-++]'])
    """
    return system.tracked()


# --- records -------------------------------------------------------------------


@dataclass(frozen=True)
class StepRow:
    """One orbit point in one arithmetic, compared with the exact point (see METHOD).

    ``drift_log10`` has one entry per declared integral whose value could be
    computed here (no entry at a pole, or without diagnostics); the log10 values
    are None when the quantity is exactly 0."""

    arith: str
    step: int
    error_log10: float | None
    radius_log10: float | None = None
    drift_log10: dict = field(default_factory=dict)  # declared integral name -> log10 drift
    commutation_log10: float | None = None
    reversibility_log10: float | None = None
    encloses: bool | None = None
    condition: float | None = None
    seconds: float = 0.0


@dataclass(frozen=True)
class ArithRun:
    """An orbit in one arithmetic: per-step rows and a summary.

    ``status``: ``'ok'``, ``'warned'`` (NearSingularWarning at some step),
    ``'singular'`` (SingularStepError), ``'undecided'`` (UndecidedError, balls) or
    ``'unrepresentable'`` (the arithmetic cannot hold x0 or ε: beyond float64's range, a
    bad reduction mod P; ``message`` says which; no step);
    ``failed_step`` is the step that raised; ``steps_done`` counts the steps that
    returned a point (one more than the compared rows when the exact orbit
    stopped first: the step the exact map refuses was still attempted).  ``bits_left``: correct bits of the
    last point (min(prec, −log2 error)); ``loss_rate``: least-squares slope of
    log2(error) against the step number (bits lost per step); for balls
    ``radius_rate`` is the same for the radius and ``useless_step`` the first step
    whose radius is ≥ the norm of the point (no correct digit left).
    """

    arith: str
    prec: int | None
    status: str
    steps_done: int
    failed_step: int | None
    message: str
    seconds_per_step: float | None
    final_error_log10: float | None
    bits_left: float | None
    loss_rate: float | None
    radius_rate: float | None
    useless_step: int | None
    encloses: bool | None
    max_condition: float | None
    rows: tuple = field(repr=False, default=())

    def summary(self) -> dict:
        d = asdict(self)
        d.pop("rows")
        return d


@dataclass(frozen=True)
class ScalingStudy:
    """Result of :func:`scaling_study`: the runs, the exact timing, how numbers were
    obtained, and the names of the integrals and commuting fields the diagnostics
    checked (empty without diagnostics)."""

    system: object
    x0: tuple
    eps: Fraction
    steps: int
    exact_seconds_per_step: float
    exact_final_height_bits: int
    runs: tuple
    method: dict
    integrals: tuple = ()
    commuting: tuple = ()
    repeats: int = 1

    def rows(self):
        return [r for run in self.runs for r in run.rows]


# --- one orbit -----------------------------------------------------------------


def exact_prefix(fld, x0, eps, steps, max_bits=None):
    """(points, seconds per step, error): the exact orbit (python-flint ``fmpq``) up
    to the first undefined step, or to the first point higher than ``max_bits``
    (included; default :data:`MAX_EXACT_BITS`); ``error`` is that step's
    SingularStepError or None."""
    max_bits = MAX_EXACT_BITS if max_bits is None else max_bits
    phi = KahanMap(fld, eps, "flint")
    pts, err = [phi.point(x0, "x0")], None
    t = time.process_time()
    for k in range(1, steps + 1):
        try:
            pts.append(phi.step(pts[-1]))
        except SingularStepError as exc:
            err = exc.at_step(k)
            break
        if point_height(phi.arith, pts[-1]) > max_bits:
            break
    return pts, (time.process_time() - t) / max(len(pts) - 1, 1), err


def exact_orbit(fld, x0, eps, steps, max_bits=None):
    """(points, seconds per step) of the exact orbit; raises SingularStepError, and
    InputError when a point before step ``steps`` is higher than ``max_bits``
    (default :data:`MAX_EXACT_BITS`; the last point may be higher)."""
    max_bits = MAX_EXACT_BITS if max_bits is None else max_bits
    pts, sec, err = exact_prefix(fld, x0, eps, steps, max_bits)
    if err is not None:
        raise err
    if len(pts) <= steps:
        raise InputError(f"steps: the exact reference orbit is {point_height(get_arith('flint'), pts[-1])} bits "
                         f"high at step {len(pts) - 1} (more than {max_bits}): its heights grow too fast for "
                         f"{steps} steps (the map is likely not integrable); choose at most {len(pts) - 1} steps")
    return pts, sec


def _slope(ks, ys):
    """Least-squares slope of ys against ks (None with fewer than two points)."""
    pts = [(k, y) for k, y in zip(ks, ys) if y is not None]
    if len(pts) < 2:
        return None
    mk = sum(k for k, _ in pts) / len(pts)
    my = sum(y for _, y in pts) / len(pts)
    den = sum((k - mk) ** 2 for k, _ in pts)
    return sum((k - mk) * (y - my) for k, y in pts) / den if den else None
