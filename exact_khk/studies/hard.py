"""Hard cases: where floating arithmetic breaks, and whether the tool says so.

:func:`catalogue` builds the Lie–Poisson cases (ε approaching a root of
det(I − εf′(x0)) at distances 10^-3 … 10^-30, exactly singular steps, large ε,
large coordinates, a long orbit, a nearly degenerate Hessian, an orbit passing
close to a point where the map is undefined); :func:`system_cases` builds the
cases of any system from its x0 (ε approaching the real root of
det(I − εf′(x0)) nearest 0, an exactly singular step at every rational root,
a long orbit); :func:`run_case` runs one case in several
arithmetics and in exact arithmetic and records what each returned, whether
the trouble was flagged (NearSingularWarning with its condition estimate,
SingularStepError, UndecidedError) and the precision needed.

The singular step sizes are certified: det(I − εf′(x)) = ε^N χ(1/ε) with χ the
characteristic polynomial of f′(x) (exact, python-flint); its real roots are
isolated by SymPy in intervals with rational endpoints and refined to any
width, so the distance of a chosen ε to the root is known to within that width.

>>> from exact_khk.systems.lie_poisson import LiePoissonSystem
>>> s2 = LiePoissonSystem.from_vectors("1,2", "0,1", "3,1")
>>> det_polynomial(s2.field("f"), ["1", "2", "-1", "1/2"])
Poly(-1188*eps**4 + 402*eps**3 + 190*eps**2 + eps + 1, eps, domain='QQ')
>>> [round(float(r.mid), 12) for r in singular_step_sizes(s2.field("f"), ["1", "2", "-1", "1/2"])]
[-0.274291885177, 0.607625218511]
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from fractions import Fraction

import flint
import sympy

from exact_khk.arith import get_arith, point_height
from exact_khk.errors import InputError
from exact_khk.kahan.map import KahanMap
from exact_khk.parsing import parse_rational, parse_vector
from exact_khk.studies.scaling import LOG10_2, exact_prefix, jsonable, precision_needed, run_orbit
from exact_khk.systems.base import System
from exact_khk.systems.lie_poisson.system import DEFAULT_X0, LiePoissonSystem, default_system, random_point

DEFAULT_ARITHS = ("float", "mp:113", "mp:256", "ball:128", "ball:512")
DISTANCES = (3, 6, 10, 15, 20, 30)  # ε = ε* + 10^-d
EPS_SYMBOL = sympy.Symbol("eps")
#: the height (bits) of x0 up to which the hard cases are built: isolating the real roots of
#: det(I − εf′(x0)) (SymPy) grows fast with its coefficients' size; `hard --system euler-top`
#: with x0 = (2^b, 1, 1): 2.3 s at b = 2048, 4.9 s at 4096, 21 s at 8192, over 60 s at 16 600
HARD_MAX_X0_BITS = 8192


# --- certified singular step sizes ---------------------------------------------


def det_polynomial(fld, x) -> sympy.Poly:
    """det(I − ε f′(x)) as an exact polynomial in ε (SymPy ``Poly`` over QQ)."""
    ar = get_arith("flint")
    x = KahanMap(fld, 1, ar).point(x)
    chi = flint.fmpq_mat(fld.jacobian(ar, x)).charpoly()  # det(λI − f′), coefficients low → high
    coeffs = [sympy.Rational(int(c.p), int(c.q)) for c in chi.coeffs()]
    N = len(coeffs) - 1
    return sympy.Poly(sum(c * EPS_SYMBOL ** (N - i) for i, c in enumerate(coeffs)), EPS_SYMBOL,
                      domain="QQ")


@dataclass(frozen=True)
class RootEnclosure:
    """A real root ε* of det(I − εf′(x)) with lo ≤ ε* ≤ hi (exact rationals);
    lo == hi when the root is rational (then exact)."""

    lo: Fraction
    hi: Fraction

    @property
    def mid(self) -> Fraction:
        return (self.lo + self.hi) / 2

    @property
    def exact(self) -> bool:
        return self.lo == self.hi


def _frac(r) -> Fraction:
    r = sympy.Rational(r)
    return Fraction(int(r.p), int(r.q))


def singular_step_sizes(fld, x, width=Fraction(1, 10 ** 60)) -> list[RootEnclosure]:
    """Every real root of det(I − εf′(x)) in an interval of width ≤ ``width``, sorted."""
    p = det_polynomial(fld, x)
    out = []
    for (a, b), _mult in p.intervals():
        if a != b:
            a, b = p.refine_root(a, b, eps=sympy.Rational(width.numerator, width.denominator))
        out.append(RootEnclosure(_frac(a), _frac(b)))
    return sorted(out, key=lambda r: r.lo)


# --- the catalogue ---------------------------------------------------------------


@dataclass(frozen=True)
class HardCase:
    """One hard case: a system, x0, ε, a number of steps, and what makes it hard."""

    name: str
    description: str
    system: System
    x0: tuple
    eps: Fraction
    steps: int
    #: (exact orbit points 0..steps, seconds they took) when the case was built from them
    #: (:func:`system_cases`' long orbit): :func:`run_case` does not compute them again
    reference: tuple | None = field(default=None, compare=False, repr=False)


#: the n = 2 system used for the singular cases; at (1, 2, -1, 1/2) its
#: det(I − εf′) has the irrational real roots (1 ± √7)/6, and at
#: (-2, -2, -2, 1) the rational root −1/6 (found by a search over small points).
S2_VECTORS = ("1,2", "0,1", "3,1")
S2_X0 = ("1", "2", "-1", "1/2")


def _scaled(x, lam):
    return tuple(lam * parse_rational(t, "x0") for t in x)


def catalogue(long_steps: int = 1000, distances=DISTANCES) -> list[HardCase]:
    """The hard cases (deterministic; see the module docstring)."""
    s2, s3 = LiePoissonSystem.from_vectors(*S2_VECTORS), default_system()
    x2, x3 = _scaled(S2_X0, 1), _scaled(DEFAULT_X0, 1)
    root = singular_step_sizes(s2.field("f"), x2)[-1]  # (1 + √7)/6 ≈ 0.6076
    cases = []
    for d in distances:
        cases.append(HardCase(
            f"near-root 1e-{d}", f"eps = eps* + 1e-{d}, eps* = (1+sqrt 7)/6 a root of det(I - eps f'(x0)) "
            f"(certified to {float(root.hi - root.lo):.0e})", s2, x2, root.mid + Fraction(1, 10 ** d), 2))
    cases += [
        HardCase("singular (eps=-1/6)", "det(I - eps f'(x0)) = 0 exactly at step 1; -1/6 is not a binary float",
                 s2, _scaled(("-2", "-2", "-2", "1"), 1), Fraction(-1, 6), 1),
        HardCase("singular (eps=-1/4)", "det(I - eps f'(x0)) = 0 exactly at step 1; -1/4 is a binary float",
                 s2, _scaled(("-2", "-2", "-2", "0"), 1), Fraction(-1, 4), 1),
        HardCase("large eps 1e6", "default n = 3 system, eps = 10^6", s3, x3, Fraction(10 ** 6), 20),
        HardCase("large coords 1e150", "default system, x0 scaled by 10^150 (like eps = 10^149)",
                 s3, _scaled(DEFAULT_X0, 10 ** 150), Fraction(1, 10), 5),
        HardCase("large coords 1e300", "default system, x0 scaled by 10^300 (near the float range)",
                 s3, _scaled(DEFAULT_X0, 10 ** 300), Fraction(1, 10), 5),
        HardCase(f"long orbit {long_steps}", f"n = 3 system of --seed 39 (a bounded orbit that does not "
                 f"settle), eps = 1/10, {long_steps} steps", LiePoissonSystem.random(3, 39),
                 random_point(3, 39), Fraction(1, 10), long_steps),
        HardCase("near-degenerate Hessian", "n = 2, a = b = (1, 0), c = (1 + 1e-12, 0): Hs has rank 2 + O(1e-12)",
                 LiePoissonSystem.from_vectors("1,0", "1,0", [1 + Fraction(1, 10 ** 12), 0]),
                 x2, Fraction(1, 10), 50),
        _near_undefined_case(s2, x2, root),
    ]
    return cases


def _near_undefined_case(s2, y_a, root, back=3, delta=Fraction(1, 10 ** 12)):
    """x0 = Φ^{-3}(y) exactly, with y = λ y_a within 1e-12 of the singular set of
    Φ(·, 1/10): det(I − ε f′(λ y_a)) = det(I − ελ f′(y_a)) vanishes at ελ = ε*."""
    eps = Fraction(1, 10)
    y = _scaled(y_a, (root.mid + delta) / eps)
    phi = KahanMap(s2.field("f"), eps, "flint")
    x = phi.point(y)
    for _ in range(back):
        x = phi.inverse(x)
    x0 = tuple(Fraction(int(t.p), int(t.q)) for t in x)
    return HardCase("near undefined point", f"orbit of eps = 1/10 whose point x_{back} lies 1e-12 (in the "
                    f"ray parameter) from the set det(I - eps f'(x)) = 0; x0 = Phi^-{back}(x_{back}) exactly",
                    s2, x0, eps, back + 2)


def _sci(q: Fraction, digits: int) -> str:
    """A rational in scientific notation to ``digits`` significant digits, at any magnitude
    (float() overflows beyond 1e308 and underflows below 1e-308; x0 may hold huge numbers).

    >>> _sci(Fraction(1, 3), 6), _sci(Fraction(10 ** 900, 7), 6), _sci(Fraction(1, 10 ** 900), 1)
    ('0.333333', '1.42857e+899', '1e-900')
    """
    try:
        f = float(q)
        if f or not q:  # in binary64's range: %g of the float, e.g. '0.333333', '1e-12'
            return f"{f:.{digits}g}"
    except OverflowError:
        pass
    return flint.arb(flint.fmpq(q.numerator, q.denominator)).str(digits, radius=False)


def system_cases(system, x0=None, eps=None, long_steps: int = 1000, distances=DISTANCES) -> list[HardCase]:
    """The hard cases of any system at x0 and ε (default: the system's own):

    * ``near-root 1e-d``: ε* + 10^-d, 2 steps, for the real root ε* of
      det(I − εf′(x0)) nearest 0 (certified: :func:`singular_step_sizes`);
    * ``singular (eps=r)``: 1 step at every rational root r (det = 0 exactly);
    * ``long orbit K``: K = ``long_steps`` steps at ε, fewer if the exact orbit
      grows higher than :data:`~exact_khk.studies.common.MAX_EXACT_BITS` first.

    >>> from exact_khk.systems.expressions import ExpressionSystem
    >>> s = ExpressionSystem.from_expressions(["x", "y"], field=["x*y", "y*y"], x0=["1", "2"], eps="1/10")
    >>> det_polynomial(s.field("f"), s.default_x0)            # (1 - 2 eps)(1 - 4 eps)
    Poly(8*eps**2 - 6*eps + 1, eps, domain='QQ')
    >>> [c.name for c in system_cases(s, long_steps=30, distances=(3,))]
    ['near-root 1e-3', 'singular (eps=1/4)', 'singular (eps=1/2)', 'long orbit 30']
    """
    x0 = parse_vector(list(system.default_x0 if x0 is None else x0), "x0", system.dim)
    eps = parse_rational(system.default_eps if eps is None else eps, "eps")
    if eps == 0:
        raise InputError("eps: the step size must be nonzero")
    bits = point_height(get_arith("fraction"), x0)
    if bits > HARD_MAX_X0_BITS:
        raise InputError(f"x0: a point of {bits} bits is beyond the {HARD_MAX_X0_BITS} bits up to which the hard "
                         f"cases are built (HARD_MAX_X0_BITS: the real roots of det(I - eps f'(x0)) take minutes)")
    roots = singular_step_sizes(system.field("f"), x0)
    cases = []
    if roots:
        root = min(roots, key=lambda r: abs(r.mid))
        how = "rational, exact" if root.exact else f"certified to {_sci(root.hi - root.lo, 1)}"
        cases += [HardCase(f"near-root 1e-{d}", f"eps = eps* + 1e-{d}, eps* ~ {_sci(root.mid, 6)} the real root of "
                           f"det(I - eps f'(x0)) nearest 0 ({how})", system, x0, root.mid + Fraction(1, 10 ** d), 2)
                  for d in distances]
    cases += [HardCase(f"singular (eps={r.lo})", "det(I - eps f'(x0)) = 0 exactly at step 1 (a rational root)",
                       system, x0, r.lo, 1) for r in roots if r.exact]
    t = time.perf_counter()
    pts, _, err = exact_prefix(system.field("f"), x0, eps, long_steps)
    seconds = time.perf_counter() - t
    steps = long_steps if err is not None else len(pts) - 1
    short = "" if steps == long_steps else (f" (of {long_steps} asked: the exact orbit is "
                                            f"{point_height(get_arith('flint'), pts[-1])} bits high at step {steps})")
    cases.append(HardCase(f"long orbit {steps}", f"the orbit of x0 at eps = {eps}, {steps} steps{short}",
                          system, x0, eps, steps, None if err is not None else (tuple(pts), seconds)))
    return cases


# --- running a case --------------------------------------------------------------


@dataclass(frozen=True)
class CaseOutcome:
    """What one arithmetic returned on a case.

    ``status``: ``ok`` / ``warned`` / ``singular`` / ``undecided`` / ``unrepresentable``
    (x0 or ε beyond the arithmetic; ``message`` says why); ``step`` where it
    was flagged; ``condition`` the largest condition estimate seen;
    ``error_log10`` the relative error of the last point compared with the exact
    orbit (balls: of the midpoint; ``radius_log10`` the certified bound);
    ``flagged`` whether the tool raised or warned; ``silent_failure`` True when a
    number was returned without any flag although it is wrong (more than half the
    bits lost: error > 2^(-p/2)) or the exact map is undefined there; a ball (whose
    radius states its own accuracy) fails silently only if it misses the exact value.
    """

    arith: str
    status: str
    step: int | None
    condition: float | None
    error_log10: float | None
    radius_log10: float | None
    encloses: bool | None
    flagged: bool
    silent_failure: bool
    seconds: float
    message: str = ""


@dataclass(frozen=True)
class CaseResult:
    """A case's outcomes, its exact status and the precision needed (``mp`` bits
    for ``digits`` correct digits at every step; None where the exact map is undefined)."""

    case: HardCase
    exact_status: str
    exact_step: int | None
    exact_seconds: float
    outcomes: tuple
    digits: int
    bits_needed: int | None
    ball_bits_needed: int | None = None


def classify(run, exact_failed_step=None):
    """(flagged, silent_failure) of an :class:`~exact_khk.studies.scaling.ArithRun` (see
    :class:`CaseOutcome`); ``exact_failed_step``: where the exact map is undefined."""
    flagged = run.status != "ok"
    beyond = (exact_failed_step is not None and run.steps_done >= exact_failed_step
              and run.status in ("ok", "warned"))
    if run.encloses is not None:  # a ball's radius is its own flag: it fails by missing the value
        return flagged, run.encloses is False or (not flagged and beyond)
    last = run.rows[-1].error_log10 if run.rows else None
    wrong = last is not None and last > -(run.prec / 2) * LOG10_2
    return flagged, not flagged and (wrong or beyond)


#: the stages of one case reported to ``progress``: the exact orbit, each arithmetic, and
#: with ``precision`` the two precision searches (mp and ball)
def case_stages(ariths, precision=True) -> int:
    return 1 + len(ariths) + (2 if precision else 0)


def run_case(case: HardCase, ariths=DEFAULT_ARITHS, digits: int = 10,
             precision: bool = True, progress=None) -> CaseResult:
    """Run ``case`` in exact arithmetic and in every arithmetic of ``ariths``; ``progress(stage)``
    (optional) is called with the name of each stage (:func:`case_stages`) as it starts."""
    report = progress if progress is not None else (lambda stage: None)
    fld = case.system.field("f")
    report(f"{case.name}: exact")
    if case.reference is not None:
        (exact, t_exact), err = case.reference, None
        exact = list(exact)
    else:
        t = time.perf_counter()
        exact, _, err = exact_prefix(fld, case.x0, case.eps, case.steps)
        t_exact = time.perf_counter() - t
    outcomes = []
    for name in ariths:
        ar = get_arith(name)
        report(f"{case.name}: {ar.name}")
        t = time.perf_counter()
        run = run_orbit(case.system, case.x0, case.eps, case.steps, ar, exact, diagnostics=False)
        dt = time.perf_counter() - t
        last = run.rows[-1] if run.rows else None
        flagged, silent = classify(run, None if err is None else err.step)
        step = run.failed_step if run.failed_step is not None else (
            _first_warned(run) if run.status == "warned" else None)
        outcomes.append(CaseOutcome(ar.name, run.status, step, run.max_condition,
                                    last.error_log10 if last else None,
                                    last.radius_log10 if last else None, run.encloses,
                                    flagged, silent, dt, run.message))
    bits = ball_bits = None
    if precision:
        report(f"{case.name}: precision (mp)")
    if precision and err is None:
        bits = precision_needed(case.system, case.x0, case.eps, case.steps, digits, "mp", exact).bits
    if precision:
        report(f"{case.name}: precision (ball)")
    if precision and err is None:
        ball_bits = precision_needed(case.system, case.x0, case.eps, case.steps, digits, "ball", exact).bits
    return CaseResult(case, "ok" if err is None else "singular", None if err is None else err.step,
                      t_exact, tuple(outcomes), digits, bits, ball_bits)


def _first_warned(run):
    return next((r.step + 1 for r in run.rows if r.condition is not None), None)


def run_catalogue(cases=None, ariths=DEFAULT_ARITHS, digits=10, precision=True, progress=True):
    """Run every case (default: :func:`catalogue`); returns a list of :class:`CaseResult`.
    ``progress``: True for a tqdm bar over the cases on stderr, or a callable given each
    stage's name (:func:`run_case`)."""
    cases = catalogue() if cases is None else cases
    if callable(progress):
        return [run_case(c, ariths, digits, precision, progress) for c in cases]
    if progress:
        import sys

        from tqdm import tqdm

        cases = tqdm(cases, desc="hard", file=sys.stderr, leave=False, delay=2.0)  # shown after 2 s
    return [run_case(c, ariths, digits, precision) for c in cases]


# --- views -----------------------------------------------------------------------


def cell(o: CaseOutcome) -> str:
    """A short table cell: what the arithmetic returned."""
    err = "" if o.error_log10 is None else f"err 1e{o.error_log10:.0f}"
    if o.status == "ok":
        text = f"ok, {err}" if err else "ok, exact"
    elif o.status == "warned":
        text = f"WARN κ={o.condition:.0e} @{o.step}, {err}"
    elif o.status == "singular":
        kappa = "" if o.condition is None else f" κ={o.condition:.0e}"
        text = f"SINGULAR{kappa} @{o.step}"
    elif o.status == "unrepresentable":
        text = "OUT OF RANGE"  # x0 or ε: the run's message says which
    else:
        text = f"UNDECIDED @{o.step}"
    if o.radius_log10 is not None and o.status in ("ok", "warned"):
        text += f", rad 1e{o.radius_log10:.0f}"
    if o.silent_failure:
        text += " **UNFLAGGED**"
    return text


def markdown_table(results) -> str:
    """The hard-case table as GitHub markdown."""
    if not results:
        return ""
    names = [o.arith for o in results[0].outcomes]
    d = results[0].digits
    head = ["case", "exact"] + names + [f"mp bits for {d} digits", f"ball bits for {d} digits"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in results:
        ex = "ok" if r.exact_status == "ok" else f"SINGULAR (det = 0) @{r.exact_step}"
        cells = [r.case.name, ex] + [cell(o) for o in r.outcomes] + [
            "—" if r.bits_needed is None else str(r.bits_needed),
            "—" if r.ball_bits_needed is None else str(r.ball_bits_needed)]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def result_json(r: CaseResult) -> dict:
    """A case result as a JSON-ready dict (exact inputs as strings)."""
    c = r.case
    return jsonable({
        "case": c.name, "description": c.description, "system": c.system.to_json(),
        "system_name": c.system.name, "x0": [str(t) for t in c.x0], "eps": str(c.eps),
        "steps": c.steps, "exact_status": r.exact_status, "exact_step": r.exact_step,
        "exact_seconds": r.exact_seconds, "digits": r.digits, "mp_bits_needed": r.bits_needed,
        "ball_bits_needed": r.ball_bits_needed, "outcomes": [o.__dict__ for o in r.outcomes]})

