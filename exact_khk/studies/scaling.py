"""Precision-scaling studies: how much of a drift is rounding, how fast it grows,
and what precision buys at what cost.

:func:`run_orbit` iterates one orbit in one arithmetic and compares it step by
step with the exact orbit; :func:`scaling_study` does that for a list of
arithmetics; :func:`precision_needed` finds a precision keeping D correct
digits over K steps (one less does not) and :func:`precision_rule` fits
bits ≈ D·log2(10) + c·K + const.

How every number is obtained (also stored in ``ScalingStudy.method``):

* the reference is the **exact** orbit (python-flint ``fmpq``);
* a floating value (``float``, ``mp:P``) is a dyadic rational: it is converted
  exactly and |approx − exact| is computed in exact rational arithmetic; a
  ball contributes its midpoint exactly and its radius exactly;
* errors are normwise relative: max_i |x̂_i − x_i| / max_i |x_i|, reported as
  log10 (``None`` when the error is exactly 0; absolute when the reference is 0);
* the diagnostics are what the system declares (:func:`declared`): for every
  integral I, its drift I(x̂_k) evaluated **in the arithmetic** at the computed
  point, minus the exact I(x_0), relative to |I(x_0)| (for balls: |mid − exact|
  + rad, an upper bound) — for the Lie–Poisson family H̃ and K̃ (associated field
  g of B_0); for every field g declared to commute with f, the commutation
  residual |Φ_f(Φ_g(x̂)) − Φ_g(Φ_f(x̂))| / |x̂| (the largest over the fields);
  for every system the reversibility residual |Φ_f(Φ_f(x̂), −ε) − x̂| / |x̂|;
  residuals are computed in the arithmetic (the exact values are 0) and
  evaluated exactly; balls: |mid| + rad;
* time per step: CPU time of the orbit step alone (``time.process_time``: what other
  processes on a loaded machine take is not counted), the minimum over ``repeats``
  runs of the orbit (the first with the diagnostics, the others bare).

>>> from exact_khk.systems.lie_poisson import default_system, DEFAULT_X0
>>> s = default_system()
>>> st = scaling_study(s, DEFAULT_X0, "1/10", 5, ["float", "mp:113", "ball:113"], progress=False)
>>> [r.arith for r in st.runs]
['float', 'mp:113', 'ball:113']
>>> st.runs[0].final_error_log10 > st.runs[1].final_error_log10   # 113 bits beat 53
True
>>> st.runs[2].encloses                                           # certified enclosures
True
>>> st.integrals, sorted(st.runs[1].rows[0].drift_log10)         # the declared integrals' drifts
(('H~', 'K~'), ['H~', 'K~'])
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import asdict, dataclass

import flint

from exact_khk.arith import get_arith
from exact_khk.arith.ball import BallArith, contains_exact
from exact_khk.errors import InputError, NearSingularWarning, SingularStepError, UndecidedError
from exact_khk.kahan.map import KahanMap
from exact_khk.parsing import parse_rational, parse_vector
from exact_khk.studies.common import (LOG10_2, MAX_EXACT_BITS, ArithRun, ScalingStudy,  # noqa: F401
                                     StepRow, _err_bound, _norm, _rel, _slope, declared, exact_orbit, exact_prefix,
                                     log10q, to_fmpq, vs_exact)

DEFAULT_ARITHS = ("float", "mp:53", "mp:64", "mp:113", "mp:256", "mp:1024", "mp:4096",
                  "ball:64", "ball:256", "ball:1024", "ball:4096", "lohner:256")

METHOD = {
    "reference": "exact orbit in python-flint fmpq",
    "error": "normwise relative max_i|x_i - exact_i| / max_i|exact_i|, computed exactly from the "
             "binary value (balls: midpoint); log10; None = exactly 0",
    "radius": "balls: max_i rad_i / max_i|exact_i| (certified bound on the error), log10",
    "drift": "per declared integral I (see 'declared'): |I(x_k) - I(x_0)| / |I(x_0)| (absolute when "
             "I(x_0) = 0): I(x_k) evaluated in the arithmetic at the computed point, I(x_0) exact; balls: "
             "|mid - exact| + rad; log10",
    "commutation": "max over the fields g declared to commute with f of |Phi_f(Phi_g(x_k)) - "
                   "Phi_g(Phi_f(x_k))| / |x_k| in the arithmetic; evaluated exactly (balls: |mid| + rad); log10",
    "reversibility": "|Phi_f(Phi_f(x_k), -eps) - x_k| / |x_k| in the arithmetic; log10",
    "seconds": "CPU time of the orbit step alone (time.process_time); per run: the minimum over "
               "'repeats' runs of the orbit",
    "encloses": "balls: every point and every integral enclosure contains the exact value and every "
                "residual enclosure contains 0 (decided in exact rational arithmetic)",
}


# --- exact helpers -------------------------------------------------------------


def cpu_per_step(step, x, steps) -> float:
    """CPU seconds per step (``time.process_time``) of ``steps`` calls x = step(x) from ``x``."""
    t = time.process_time()
    for _ in range(steps):
        x = step(x)
    return (time.process_time() - t) / steps


def run_orbit(system, x0, eps, steps, arith, exact=None, diagnostics=True, progress=None,
              repeats=1) -> ArithRun:
    """Iterate ``steps`` Kahan steps of ``system.field('f')`` in ``arith``
    and compare every point with the exact orbit ``exact`` (computed if None);
    ``diagnostics``: also the drifts and residuals of what the system declares
    (:func:`declared`).

    Never raises for a singular or undecided step: the run stops there and its
    ``status`` says why.  Near-singular warnings are caught and recorded (the
    largest condition estimate is kept).  Balls run inside ``ar.local()``.
    ``seconds_per_step``: the least CPU time per step of this run and ``repeats`` − 1
    bare runs of the same steps.
    """
    ar = get_arith(arith)
    eps = parse_rational(eps, "eps")
    fld = system.field("f")
    x0 = parse_vector(list(x0), "x0", fld.dim)
    if exact is None:
        exact, _ = exact_orbit(fld, x0, eps, steps)
    exact = exact[: steps + 1]
    integrals, commuting = declared(system) if diagnostics else ({}, {})
    try:  # x0 and eps are valid rationals (read above): ar may still not hold them
        phi = KahanMap(fld, eps, ar)
        maps = [KahanMap(g, eps, ar) for g in commuting.values()]
        with ar.local():
            x = phi.point(x0, "x0")
    except InputError as exc:
        return ArithRun(ar.name, ar.prec, "unrepresentable", 0, None, str(exc), None, None, None, None,
                        None, None, None, None)
    flint_ar = get_arith("flint")
    start = {name: I(flint_ar, exact[0], eps) for name, I in integrals.items()}
    ball = isinstance(ar, BallArith)
    rows, times, status, failed, message, conds = [], [], "ok", None, "", []
    with ar.local():
        for k in range(steps + 1):
            if k >= len(exact):  # the exact orbit stopped (singular): nothing to compare
                break
            ex = exact[k]
            err, rad = vs_exact(x if ball else [to_fmpq(ar, xi) for xi in x], ex, ball)
            encl = all(contains_exact(xi, ei) for xi, ei in zip(x, ex)) if ball else None
            y, dt, cond = None, 0.0, None
            if k < steps:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always", NearSingularWarning)
                    t = time.process_time()
                    try:
                        y = phi.step(x)
                    except SingularStepError as exc:
                        status, failed, message = "singular", k + 1, str(exc.at_step(k + 1))
                        cond = exc.condition
                    except UndecidedError as exc:
                        status, failed, message = "undecided", k + 1, f"step {k + 1}: {exc}"
                    dt = time.process_time() - t
                for w in caught:
                    if issubclass(w.category, NearSingularWarning):
                        cond = max(cond or 0.0, w.message.condition)
                        if status == "ok":
                            status, message = "warned", f"step {k + 1}: {w.message}"
                    else:  # pragma: no cover - unrelated warnings pass through
                        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
                if cond is not None:
                    conds.append(cond)
            extra = {}
            if diagnostics and (y is not None or k == steps):
                with warnings.catch_warnings():  # diagnostics only: the orbit step recorded its own
                    warnings.simplefilter("ignore", NearSingularWarning)
                    extra = _diagnostics(ar, phi, maps, integrals, start, x, y, eps, ball)
                if ball:
                    encl = encl and extra.pop("encl")
            rows.append(StepRow(ar.name, k, err, rad, encloses=encl, condition=cond,
                                seconds=dt, **extra))
            if y is None:
                break
            times.append(dt)
            x = y
            if progress is not None:
                progress(1)
    per_step = sum(times) / len(times) if times else None
    if times and repeats > 1:
        with ar.local(), warnings.catch_warnings():
            warnings.simplefilter("ignore", NearSingularWarning)  # the first run recorded them
            x1 = phi.point(x0, "x0")
            per_step = min([per_step] + [cpu_per_step(phi.step, x1, len(times)) for _ in range(repeats - 1)])
    ks = [r.step for r in rows]
    log2 = lambda v: None if v is None else v / LOG10_2  # noqa: E731
    final = rows[-1].error_log10 if rows else None
    prec = ar.prec
    bits_left = None if final is None else min(float(prec), -final / LOG10_2)
    if final is None and rows:
        bits_left = float(prec) if prec else None
    useless = next((r.step for r in rows if r.radius_log10 is not None and r.radius_log10 >= 0), None)
    encloses = all(r.encloses for r in rows) if ball else None
    return ArithRun(ar.name, prec, status, len(times), failed, message, per_step,
                    final, bits_left,
                    _slope(ks, [log2(r.error_log10) for r in rows]),
                    _slope(ks, [log2(r.radius_log10) for r in rows]) if ball else None,
                    useless, encloses, max(conds) if conds else None, tuple(rows))


def _diagnostics(ar, phi, maps, integrals, start, x, y, eps, ball):
    """Integral drifts and residuals at x (y = Φ_f(x), computed if None); see METHOD.
    ``maps``: the Kahan maps of the commuting fields; ``start``: the exact I(x_0)."""
    # undefined here: PoleError, SingularStepError, UndecidedError (balls), float overflow
    undefined = ArithmeticError
    xn = _norm([to_fmpq(ar, t) for t in x])
    zero = flint.fmpq(0)
    drift, out, encl = {}, {}, True
    for name, I in integrals.items():
        try:
            v = I(ar, x, eps)
            drift[name] = _rel(_err_bound(ar, v, start[name]), abs(start[name]))
        except undefined:
            continue
        encl = encl and (not ball or contains_exact(v, start[name]))
    out["drift_log10"] = drift

    def residual(key, pairs):  # max_i |u_i - v_i| / |x| over the pairs (u, v), exactly 0 for exact maps
        nonlocal encl
        res = [a - b for u, v in pairs for a, b in zip(u, v)]
        out[key] = _rel(max(_err_bound(ar, r, zero) for r in res), xn)
        encl = encl and (not ball or all(contains_exact(r, zero) for r in res))

    try:
        y = phi.step(x) if y is None else y
        residual("reversibility_log10", [(phi.with_eps(-phi.eps).step(y), x)])
        if maps:
            residual("commutation_log10", [(phi.step(m.step(x)), m.step(y)) for m in maps])
    except undefined:
        pass
    if ball:
        out["encl"] = encl
    return out


# --- the study -----------------------------------------------------------------


def _tqdm(total, progress, desc):
    if not progress:
        return None
    from tqdm import tqdm
    import sys

    return tqdm(total=total, desc=desc, file=sys.stderr, leave=False, delay=2.0)  # shown after 2 s


def scaling_study(system, x0, eps, steps, ariths=DEFAULT_ARITHS, diagnostics=True,
                  progress=True, repeats=5) -> ScalingStudy:
    """Iterate the orbit of Φ_f in every arithmetic of ``ariths`` and compare each
    step with the exact orbit (see the module docstring for how); times per step are
    the least CPU time of ``repeats`` runs (the exact orbit's too).

    A singular exact orbit raises :class:`SingularStepError` (there is no reference).
    """
    if not isinstance(steps, int) or steps < 1:
        raise InputError(f"steps: expected a positive integer, got {steps!r}")
    from exact_khk.studies import enclosure

    ariths = [enclosure.parse_spec(a) or get_arith(a) for a in ariths]
    if not ariths:
        raise InputError("ariths: give at least one arithmetic")
    eps = parse_rational(eps, "eps")
    fld = system.field("f")
    x0 = parse_vector(list(x0), "x0", fld.dim)
    if not isinstance(repeats, int) or isinstance(repeats, bool) or repeats < 1:
        raise InputError(f"repeats: expected a positive integer, got {repeats!r}")
    exact, t_exact = exact_orbit(fld, x0, eps, steps)
    if repeats > 1:
        phi = KahanMap(fld, eps, "flint")
        x1 = phi.point(x0, "x0")
        t_exact = min([t_exact] + [cpu_per_step(phi.step, x1, steps) for _ in range(repeats - 1)])
    bar = _tqdm(steps * len(ariths), progress, "scale")
    runs = []
    try:
        for ar in ariths:
            if bar is not None:
                bar.set_postfix_str(ar.name)
            update = bar.update if bar is not None else None
            if isinstance(ar, enclosure.LohnerSpec):
                runs.append(enclosure.scale_run(system, x0, eps, steps, ar, exact, diagnostics, progress=update,
                                                repeats=repeats))
            else:
                runs.append(run_orbit(system, x0, eps, steps, ar, exact, diagnostics, progress=update,
                                      repeats=repeats))
    finally:
        if bar is not None:
            bar.close()
    last = exact[-1]
    height = max(max(int(t.p).bit_length(), int(t.q).bit_length()) for t in last)
    integrals, commuting = declared(system) if diagnostics else ({}, {})
    method = dict(METHOD, declared={"integrals": {name: getattr(I, "text", "") for name, I in integrals.items()},
                                    "commuting_fields": list(commuting)})
    return ScalingStudy(system, tuple(x0), eps, steps, t_exact, height, tuple(runs), method,
                        tuple(integrals), tuple(commuting), repeats)


# --- precision needed ------------------------------------------------------------


@dataclass(frozen=True)
class PrecisionResult:
    """A precision P (bits) with D correct digits over K steps, P − 1 without.

    ``kind`` ``'mp'``: every point of the ``mp:P`` orbit has relative error
    ≤ 10^-D, confirmed against the exact orbit; ``'ball'``: every ``ball:P``
    enclosure has relative radius ≤ 10^-D and contains the exact point (a
    certified enclosure of the whole orbit to D digits).  ``bits`` passes and
    ``bits - 1`` fails (both evaluated); ``tried`` lists (P, passed).
    """

    kind: str
    digits: int
    steps: int
    bits: int
    tried: tuple
    worst_log10: float | None


def _passes(system, x0, eps, steps, digits, kind, P, exact):
    run = run_orbit(system, x0, eps, steps, f"{kind}:{P}", exact, diagnostics=False)
    if run.status in ("singular", "undecided") or run.steps_done < steps:
        return False, None
    key = "radius_log10" if kind == "ball" else "error_log10"
    vals = [getattr(r, key) for r in run.rows]
    worst = max((v for v in vals if v is not None), default=None)
    ok = worst is None or worst <= -digits
    if kind == "ball":
        ok = ok and run.encloses
    return ok, worst


def precision_needed(system, x0, eps, steps, digits, kind="mp", exact=None) -> PrecisionResult:
    """A precision P (bits) such that ``kind:P`` keeps ``digits`` correct digits at every
    step 0..``steps`` and ``kind:(P - 1)`` does not, both evaluated against the exact orbit.

    The search starts at ⌈D·log2 10⌉ and keeps a failing ``lo`` below a passing ``hi``. Each
    probe is the precision the last run predicts, if errors and radii scale like 2^−P (P +
    ⌈(w + D)/log10 2⌉ from its worst log10 w), clamped into (lo, hi). While nothing has
    passed, the j-th probe up is clamped to [P + 2^(j−1), 2P] and a run without a worst
    value (undecided, singular) doubles P; once lo and hi exist, after two predictions that
    did not halve the interval a probe bisects it (so about one probe per doubling and at
    most 3 per halving). Where passing is not monotone in P (rounding), the answer is a
    boundary of that kind, not necessarily the least P that passes.

    >>> from exact_khk.systems.lie_poisson import default_system, DEFAULT_X0
    >>> r = precision_needed(default_system(), DEFAULT_X0, "1/10", 10, 20)
    >>> r.bits >= 67 and r.worst_log10 <= -20
    True
    """
    if kind not in ("mp", "ball"):
        raise InputError(f"kind: expected 'mp' or 'ball', got {kind!r}")
    if not isinstance(digits, int) or digits < 1:
        raise InputError(f"digits: expected a positive integer, got {digits!r}")
    eps = parse_rational(eps, "eps")
    fld = system.field("f")
    x0 = parse_vector(list(x0), "x0", fld.dim)
    if exact is None:
        exact, _ = exact_orbit(fld, x0, eps, steps)
    tried = {}
    # P = 1 counts as failing; guessed: P came from a prediction; misses: predictions since
    # the last bisection that did not halve the interval; grow: the least step up
    lo, hi, P, guessed, misses, grow = 1, None, max(2, math.ceil(digits / LOG10_2)), False, 0, 1
    while True:
        ok, worst = tried[P] = _passes(system, x0, eps, steps, digits, kind, P, exact)
        width = None if hi is None else hi - lo
        lo, hi = (lo, P) if ok else (P, hi)
        if hi is not None and hi - lo <= 1:
            break
        informative = worst is not None and (ok or worst > -digits)
        guess = P + math.ceil((worst + digits) / LOG10_2) if informative else None
        if hi is None:  # nothing passed yet: up by at least 1, 2, 4, ... and at most doubling
            guessed = guess is not None
            P, grow = (min(2 * P, max(guess, P + grow)) if guessed else 2 * P), 2 * grow
            if P > 1 << 20:
                raise InputError(f"digits: {digits} digits over {steps} steps need more than 2^20 bits")
            continue
        misses += guessed and width is not None and 2 * (hi - lo) > width
        guessed = guess is not None and misses < 2
        P = min(max(guess, lo + 1), hi - 1) if guessed else (lo + hi) // 2
        misses = misses if guessed else 0
    return PrecisionResult(kind, digits, steps, hi, tuple(sorted((p, r[0]) for p, r in tried.items())),
                           tried[hi][1])


@dataclass(frozen=True)
class PrecisionRule:
    """bits ≈ D·log2(10) + c·K + const, fitted by least squares over ``results``."""

    kind: str
    digits: int
    c: float
    const: float
    results: tuple

    def predict(self, digits, steps) -> float:
        return digits / LOG10_2 + self.c * steps + self.const


def precision_rule(system, x0, eps, steps, digits, kind="mp", step_counts=None) -> PrecisionRule:
    """Fit the rule over K in ``step_counts`` (default K/4, K/2, 3K/4, K).

    >>> from exact_khk.systems.lie_poisson import default_system, DEFAULT_X0
    >>> rule = precision_rule(default_system(), DEFAULT_X0, "1/10", 8, 10)
    >>> math.isfinite(rule.c) and rule.predict(10, 8) > 33
    True
    """
    eps = parse_rational(eps, "eps")
    Ks = sorted({max(1, steps * i // 4) for i in range(1, 5)} if step_counts is None else set(step_counts))
    if len(Ks) < 2:
        raise InputError("steps: need at least two distinct step counts to fit c (use K >= 2)")
    fld = system.field("f")
    exact, _ = exact_orbit(fld, parse_vector(list(x0), "x0", fld.dim), eps, max(Ks))
    res = tuple(precision_needed(system, x0, eps, K, digits, kind, exact) for K in Ks)
    ys = [r.bits - digits / LOG10_2 for r in res]
    c = _slope(Ks, ys)
    const = sum(ys) / len(ys) - c * sum(Ks) / len(Ks)
    return PrecisionRule(kind, digits, c, const, res)


# --- outputs -------------------------------------------------------------------------


def jsonable(obj):
    """``obj`` with non-finite floats written as strings ('inf', 'nan'): strict JSON."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return str(obj)
    if isinstance(obj, dict):
        return {k: jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    return obj


def study_json(study: ScalingStudy) -> dict:
    """The study as a JSON-ready dict (summaries, per-step rows, method)."""
    return jsonable({"system": study.system.to_json(), "system_name": study.system.name,
                     "integrals": list(study.integrals), "commuting_fields": list(study.commuting),
                     "x0": [str(t) for t in study.x0], "eps": str(study.eps), "steps": study.steps,
                     "exact": {"arith": "flint", "seconds_per_step": study.exact_seconds_per_step,
                               "final_height_bits": study.exact_final_height_bits},
                     "method": study.method, "runs": [r.summary() for r in study.runs],
                     "rows": [asdict(r) for r in study.rows()]})


def write_study(study: ScalingStudy, out_dir, plots=True) -> list:
    """Write ``scaling.csv``, ``scaling.json`` and (``plots``) the figures of
    :func:`plot_study` into ``out_dir``; returns the paths written.  The CSV has a
    column ``drift_log10[NAME]`` per declared integral, and ``commutation_log10``
    only when the system declares commuting fields."""
    import csv
    import json
    import pathlib

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "scaling.csv", out / "scaling.json"]
    columns = []  # (header, value of a row); one drift column per declared integral
    for k in StepRow.__dataclass_fields__:
        if k == "drift_log10":
            columns += [(f"drift_log10[{name}]", lambda r, name=name: r.drift_log10.get(name))
                        for name in study.integrals]
        elif k != "commutation_log10" or study.commuting:
            columns.append((k, lambda r, k=k: getattr(r, k)))
    import io

    from exact_khk.studies.output import write_atomic

    buf = io.StringIO(newline="")
    w = csv.writer(buf)
    w.writerow([head for head, _ in columns])
    for r in study.rows():
        w.writerow(["" if value(r) is None else value(r) for _, value in columns])
    write_atomic(paths[0], buf.getvalue(), "--out")
    write_atomic(paths[1], json.dumps(study_json(study), indent=1) + "\n", "--out")
    if plots:
        paths += plot_study(study, out)
    return paths


#: every file a scaling study may write into its folder (one set per run)
STUDY_FILES = ("scaling.csv", "scaling.json", "enclosure.json", "work_precision.png", "error_vs_step.png",
               "drift_vs_step.png", "enclosure_radius.png")


def remove_stale(out_dir, written) -> list:
    """Remove the files of :data:`STUDY_FILES` in ``out_dir`` that this run did not write
    (left by an earlier study in the same folder, they would describe another run);
    returns their paths, for the caller to say so."""
    import pathlib

    keep = {pathlib.Path(p).name for p in written}
    gone = []
    for name in STUDY_FILES:
        path = pathlib.Path(out_dir) / name
        if name not in keep and path.is_file():
            path.unlink()
            gone.append(path)
    return gone


def plot_study(study: ScalingStudy, out_dir) -> list:
    """The figures of a study (:mod:`exact_khk.studies.plots`): ``work_precision.png``,
    ``error_vs_step.png`` (bits lost relative to each precision), ``drift_vs_step.png``
    (when integrals were checked) and ``enclosure_radius.png`` (when ball:P or
    lohner:P ran)."""
    import pathlib

    from exact_khk.studies import plots

    out = pathlib.Path(out_dir)
    title = f"{study.system.name}, eps={study.eps}, K={study.steps} steps"
    certified = lambda run: run.radius_rate is not None or run.arith.startswith(("ball", "lohner"))  # noqa: E731
    points = []  # (label, precision, CPU s/step, correct bits at step K, kind)
    for run in study.runs:
        last = run.rows[-1] if run.rows else None
        cert = certified(run)
        y = (last.radius_log10 if cert else last.error_log10) if last else None
        if run.steps_done < study.steps or last is None or last.step < study.steps:
            why = f"{run.status} at step {run.failed_step}" if run.failed_step else "stopped"
            points.append((f"{run.arith} ({why})", run.prec, run.seconds_per_step, 0.0, "stopped"))
        else:  # an error exactly 0 keeps every bit carried; a radius beyond |x|: no bit
            bits = float(run.prec or 53) if y is None else max(0.0, -y / LOG10_2)
            points.append((run.arith + (" (certified radius)" if cert else ""), run.prec, run.seconds_per_step,
                           bits, "radius" if cert else "error"))
    styles = plots.style([run.arith for run in study.runs])
    paths = [out / "work_precision.png", out / "error_vs_step.png"]
    plots.work_precision(points, "work-precision: " + title, study.exact_seconds_per_step, paths[0], styles,
                         repeats=study.repeats)
    series = []
    for run in study.runs:
        key = "radius_log10" if certified(run) else "error_log10"
        series.append((run.arith + (" (radius)" if certified(run) else ""), run.prec,
                       [(r.step, getattr(r, key)) for r in run.rows]))
    plots.bits_lost(series, "bits lost against the exact orbit: " + title, paths[1], styles)
    if study.integrals:
        paths.append(out / "drift_vs_step.png")
        plots.drift([(run.arith, [(r.step, r.drift_log10) for r in run.rows]) for run in study.runs],
                    list(study.integrals), title, paths[-1], styles)
    encl = [run for run in study.runs if certified(run)]
    if encl:
        paths.append(out / "enclosure_radius.png")
        plots.enclosure_radius(
            [(f"{run.arith}" + (f", {run.radius_rate:.3g} bits/step" if run.radius_rate is not None else "")
              + (f", {run.status} at step {run.failed_step}" if run.failed_step else ""),
              [(r.step, r.radius_log10 / LOG10_2) for r in run.rows if r.radius_log10 is not None])
             for run in encl], "certified enclosure radius: " + title, paths[-1], styles=styles)
    return paths


def orbit_enclosure(system, x0, eps, steps, prec):
    """The ``ball:prec`` orbit: a list of tuples of arb balls, each certified to contain
    the exact orbit point (raises UndecidedError / SingularStepError like a step)."""
    ar = get_arith(f"ball:{prec}")
    phi = KahanMap(system.field("f"), eps, ar)
    with ar.local():
        return phi.orbit(x0, steps)
