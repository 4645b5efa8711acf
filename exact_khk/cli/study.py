"""``exact-khk scale`` and ``exact-khk hard``: precision-scaling studies and hard cases.

Thin views over :mod:`exact_khk.studies.scaling` and :mod:`exact_khk.studies.hard`,
for the Lie–Poisson family or any ``--system NAME|FILE``.  The hard cases (which
need SymPy) are imported when ``hard`` runs, not when the parser is built.
"""

from __future__ import annotations

import json
import math
import pathlib
import sys

from exact_khk.cli.options import (Progress, add_json_option, add_system_options, check_dense, check_resources,
                                   json_command, shows_progress, system_from_args)
from exact_khk.certification.records import library_versions
from exact_khk.errors import InputError
from exact_khk.parsing import parse_rational, parse_vector
from exact_khk.studies import scaling
from exact_khk.studies.output import prepare_folder, write_atomic


#: the default of ``hard --ariths`` (= exact_khk.studies.hard.DEFAULT_ARITHS, written here so that
#: building the parser does not import SymPy; a test keeps them equal)
HARD_ARITHS = "float,mp:113,mp:256,ball:128,ball:512"
#: the largest phase-space dimension of scale/enclose: every arithmetic solves a dense
#: N×N system per step (and the Jacobian N right-hand sides), O(N³) multiprecision operations
MAX_STUDY_DIM = 200
#: the most correct digits asked of --digits: the precision searches double from
#: D·log2(10) bits and run the orbit at each; beyond, one search runs for hours
MAX_DIGITS = 2000
#: the longest orbit of the hard cases' long-orbit case (steps; every arithmetic runs it)
MAX_LONG_STEPS = 100_000


def _check_dim(system, what):
    if system.dim > MAX_STUDY_DIM:
        raise InputError(f"{what}: dimension {system.dim} is beyond the limit of {MAX_STUDY_DIM} for precision "
                         f"studies (MAX_STUDY_DIM; every arithmetic solves a dense {system.dim}x{system.dim} system "
                         f"per step)")


def _check_reference(what, system, x0, eps, steps):
    """Refuse up front, by the estimate of ``orbit`` (:func:`~exact_khk.cli.options.check_resources`),
    an exact reference orbit (python-flint, as :func:`~exact_khk.studies.scaling.exact_prefix`
    computes it) beyond the memory limit."""
    from exact_khk.kahan.map import KahanMap

    phi = KahanMap(system.field("f"), eps, "flint")
    check_resources(f"{what} (its exact reference orbit)", system, phi, x0, steps,
                    dense=phi.structure is None and not phi.split)


def _check_digits(digits, option="--digits"):
    if digits is not None and not 1 <= digits <= MAX_DIGITS:
        raise InputError(f"{option}: expected 1 <= D <= {MAX_DIGITS} (MAX_DIGITS), got {digits}")


def register(sub):
    p = sub.add_parser("scale", help="compare floating and ball orbits with the exact orbit, step by step",
                       description="Iterate the orbit of Phi_f in several arithmetics and compare every step "
                       "with the exact orbit: relative error, drift of every integral the system declares "
                       "(Lie–Poisson family: H~, K~), commutation residual with every field it declares "
                       "commuting (Lie–Poisson: g of B_0), reversibility residual, time per step; fitted bits "
                       "lost per step; work-precision plots.")
    add_system_options(p, steps_default=50)
    p.add_argument("--ariths", default=",".join(scaling.DEFAULT_ARITHS),
                   help="comma-separated floating/ball arithmetics, and lohner:P for the Lohner enclosure at P "
                        "bits (see 'exact-khk enclose'; default: %(default)s)")
    p.add_argument("--digits", type=int, help="also find mp:P and ball:P keeping D correct digits over K "
                   "steps (P - 1 not) and fit bits = D*log2(10) + c*K + const")
    p.add_argument("--out", help="directory for scaling.csv, scaling.json, work_precision.png, "
                   "error_vs_step.png (and enclosure.json with --digits)")
    add_json_option(p, "the study (as scaling.json)")
    p.add_argument("--no-plots", action="store_true", help="with --out: skip the PNG figures")
    p.add_argument("--no-diagnostics", action="store_true",
                   help="only the orbit error (skip the integral drifts and the residuals)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_scale)

    e = sub.add_parser("enclose", help="certified enclosure of an orbit (naive balls and Lohner), real inputs",
                       description="Enclose K steps of the orbit in arb balls at P bits by the naive ball "
                       "iteration and by the Lohner mean-value enclosure (no wrapping), side by side; print the "
                       "radius growth in bits per step, the correct bits, and the enclosures of every declared "
                       "integral's drift I(x_k) - I(x_0). --x0 and --eps take reals: rationals and decimals "
                       "(read as the exact rational they denote), exact reals such as sqrt(2) or pi/4, intervals "
                       "[lo,hi] and balls m+-r (see docs/precision.md). So do the Lie–Poisson blocks --a/--b/--c, e.g. --a "
                       "'sqrt(2),0,2+-1e-12': every enclosure then holds for every parameter value in the boxes; "
                       "so does a system file's parameter given by --param NAME=REAL.")
    add_system_options(e, steps_default=1000)
    e.add_argument("--param", action="append", metavar="NAME=REAL",
                   help="with --system: override the file's parameter NAME by a real (same syntax as --x0; "
                        "repeatable); integrals that mention it are skipped")
    e.add_argument("--prec", type=int, default=256, help="working precision P in bits (default 256)")
    e.add_argument("--methods", default="naive,lohner", help="naive, lohner or both (default: %(default)s)")
    e.add_argument("--check-exact", action="store_true",
                   help="also check every enclosure against the exact orbit (rational x0, eps, a, b, c only; "
                        "the exact orbit's height grows along it)")
    e.add_argument("--no-diagnostics", action="store_true", help="skip the integrals' drift")
    e.add_argument("--out", help="folder for enclosure.json and enclosure_radius.png")
    add_json_option(e, "the enclosure (as enclosure.json)")
    e.set_defaults(func=cmd_enclose)

    h = sub.add_parser("hard", help="run the catalogue of hard cases (near-singular steps, ...)",
                       description="Run each hard case in exact arithmetic and in floating and ball "
                       "arithmetics; print what each returned, whether the trouble was flagged, and "
                       "the precision needed. Without --system: the Lie–Poisson catalogue; with --system: "
                       "eps approaching the real root of det(I - eps f'(x0)) nearest 0, an exactly singular "
                       "step at each rational root, and a long orbit, all from the system's x0.")
    h.add_argument("--system", metavar="NAME|FILE",
                   help="build the cases from a catalogue system or a system file (.toml) instead of "
                        "running the Lie–Poisson catalogue")
    h.add_argument("--x0", help="with --system: the point of the cases (default: the system's x0)")
    h.add_argument("--eps", help="with --system: the step size eps of the long orbit; one Kahan step approximates the "
                                 "flow over time 2*eps (h = 2 eps) (default: the system's)")
    h.add_argument("--ariths", default=HARD_ARITHS,
                   help="comma-separated floating/ball arithmetics (default: %(default)s)")
    h.add_argument("--digits", type=int, default=10,
                   help="correct digits for the 'bits needed' columns (default 10)")
    h.add_argument("--long-steps", type=int, default=1000, help="steps of the long-orbit case (default 1000)")
    h.add_argument("--only", help="run only the cases whose name contains this text")
    h.add_argument("--no-precision", action="store_true", help="skip the precision-needed searches")
    h.add_argument("--markdown", action="store_true", help="print the table as GitHub markdown")
    h.add_argument("--out", help="directory for hard_cases.json and hard_cases.md")
    add_json_option(h, "the results (as hard_cases.json)")
    h.add_argument("--quiet", action="store_true", help="no progress bar")
    h.set_defaults(func=cmd_hard)


def _ariths(text, lohner=False):
    """The arithmetics of ``--ariths`` (``lohner``: also ``lohner:P``, the Lohner enclosure)."""
    names = [t.strip() for t in text.split(",") if t.strip()]
    if not names:
        raise InputError("--ariths: give at least one arithmetic")
    if len(names) > 32:
        raise InputError(f"--ariths: {len(names)} arithmetics; at most 32 in one study")
    from exact_khk.arith import get_arith
    from exact_khk.studies.enclosure import parse_spec

    out = []
    for name in names:
        spec = parse_spec(name)
        if spec is not None:
            if not lohner:
                raise InputError(f"--ariths: {name!r}: the Lohner enclosure runs in 'scale' and 'enclose' only")
            out.append(spec)
            continue
        ar = get_arith(name)
        if ar.exact:
            raise InputError(f"--ariths: {name!r} is exact; the exact orbit is always the reference, "
                             "list floating or ball arithmetics")
        out.append(ar)
    return out


def _drift(name):
    """A row's drift of integral ``name``: None where not computed, -inf where exactly 0."""
    def get(row):
        if name not in row.drift_log10:
            return None
        v = row.drift_log10[name]
        return -math.inf if v is None else v
    return get


def _fmt(v, spec=".1f"):
    if v == -math.inf:  # log10 of an exact 0
        return "-inf"
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


@json_command
def cmd_scale(args):
    system, x0, eps = system_from_args(args)
    if args.arith is not None:
        raise InputError("--arith: scale compares several arithmetics; use --ariths")
    if args.steps < 1:
        raise InputError("--steps: scale needs at least one step")
    _check_digits(args.digits)
    _check_dim(system, "scale")
    ariths = _ariths(args.ariths, lohner=True)
    _check_reference("scale", system, x0, eps, args.steps)
    if args.out:
        prepare_folder(args.out)
    print(system.describe())
    study = scaling.scaling_study(system, x0, eps, args.steps, ariths,
                                  diagnostics=not args.no_diagnostics, progress=shows_progress(args))
    print(f"x0 = ({', '.join(str(t) for t in x0)}), eps = {eps}, K = {args.steps} steps; reference: exact orbit "
          f"(flint, {study.exact_seconds_per_step * 1e3:.3g} ms/step, last point {study.exact_final_height_bits} bits)")
    print("errors are relative, computed exactly against the exact orbit (balls: midpoint error; "
          "radius = certified bound); log10 values; rates are least-squares slopes in bits/step")
    if not args.no_diagnostics:
        ints = ", ".join(study.integrals) or "none"
        print(f"declared integrals (drift columns): {ints}; commuting fields (comm): "
              f"{', '.join(study.commuting) or 'none'}; rev = reversibility residual")
    # the diagnostic columns: (header, value of a row or None when not computed there; a drift
    # computed and exactly 0 is -inf)
    diag = [] if args.no_diagnostics else (
        [(f"{name} drift", _drift(name)) for name in study.integrals]
        + ([("comm", lambda r: r.commutation_log10)] if study.commuting else [])
        + [("rev", lambda r: r.reversibility_log10)])
    width = [max(8, len(head)) for head, _ in diag]
    print(f"{'arith':<10} {'status':<10} {'steps':>5} {'err@K':>8} {'bits left':>9} {'lost/step':>9} "
          f"{'rad/step':>8} " + "".join(f"{head:>{w}} " for (head, _), w in zip(diag, width)) + f"{'ms/step':>8}")
    for run in study.runs:
        ms = None if run.seconds_per_step is None else run.seconds_per_step * 1e3
        last = [next((v for v in map(value, reversed(run.rows)) if v is not None), None) for _, value in diag]
        print(f"{run.arith:<10} {run.status:<10} {run.steps_done:>5} {_fmt(run.final_error_log10):>8} "
              f"{_fmt(run.bits_left):>9} {_fmt(run.loss_rate, '.3f'):>9} {_fmt(run.radius_rate, '.2f'):>8} "
              + "".join(f"{_fmt(v):>{w}} " for v, w in zip(last, width)) + f"{_fmt(ms, '.3f'):>8}")
        if run.message:
            print(f"  {run.arith}: {run.message}")
        if run.useless_step is not None:
            print(f"  {run.arith}: enclosure useless (radius >= |x|) from step {run.useless_step}")
        if run.encloses is False:
            print(f"  {run.arith}: ENCLOSURE MISSES THE EXACT VALUE (a bug; please report)")
    doc = scaling.study_json(study)
    doc["versions"] = library_versions()
    if args.digits is not None:
        doc["digits"] = _digits_report(system, x0, eps, args, study)
    if args.out:
        paths = scaling.write_study(study, args.out, plots=not args.no_plots)
        out = pathlib.Path(args.out)
        write_atomic(out / "scaling.json", json.dumps(doc, indent=1) + "\n", "--out")
        if args.digits is not None and doc["digits"].get("enclosure") is not None:
            p = out / "enclosure.json"
            write_atomic(p, json.dumps(doc["digits"]["enclosure"], indent=1) + "\n", "--out")
            paths.append(p)
        print("wrote " + ", ".join(str(p) for p in paths))
        stale = scaling.remove_stale(out, paths)
        if stale:
            print("removed from an earlier run in the same folder: " + ", ".join(str(p) for p in stale))
    return doc


def _digits_report(system, x0, eps, args, study):
    D, K = args.digits, args.steps
    print(f"\nprecision needed for {D} correct digits at every step 0..K (K = {K}):")
    rep = {"digits": D, "steps": K}
    for kind, how in (("mp", "mp:P orbit error <= 10^-D, confirmed against the exact orbit"),
                      ("ball", "ball:P radius <= 10^-D * |x| and the ball contains the exact point "
                               "(certified)")):
        rule = scaling.precision_rule(system, x0, eps, K, D, kind)
        bits = {r.steps: r.bits for r in rule.results}
        print(f"  {kind:<4}: {bits[K]} bits ({how}); by K: "
              + ", ".join(f"K={k}: {b}" for k, b in bits.items()))
        print(f"        fitted rule: bits = D*log2(10) + c*K + const with c = {rule.c:.3f} bits/step, "
              f"const = {rule.const:.1f}")
        rep[kind] = {"bits": bits[K], "bits_by_steps": {str(k): b for k, b in bits.items()},
                     "c": rule.c, "const": rule.const, "criterion": how}
    P = rep["ball"]["bits"]
    pts = scaling.orbit_enclosure(system, x0, eps, K, P)
    ar = scaling.get_arith(f"ball:{P}")
    rep["enclosure"] = {"arith": ar.name, "digits": D, "certified": True,
                        "orbit": [[ar.format(t, digits=D + 3) for t in p] for p in pts]}
    print(f"  certified enclosure of the whole orbit to {D} digits: ball:{P}"
          + (" (written to enclosure.json)" if args.out else ""))
    return rep


@json_command
def cmd_hard(args):
    from exact_khk.studies import hard  # SymPy (the certified roots): only when the command runs

    ariths = _ariths(args.ariths)
    _check_digits(args.digits)
    if args.out:
        prepare_folder(args.out)  # before the work, as scale and enclose
    if not 1 <= args.long_steps <= MAX_LONG_STEPS:
        raise InputError(f"--long-steps: expected 1 <= K <= {MAX_LONG_STEPS:,} (MAX_LONG_STEPS), got {args.long_steps}")
    title = ""
    if args.system is None:
        for opt, value in (("--x0", args.x0), ("--eps", args.eps)):
            if value is not None:
                raise InputError(f"{opt} applies only with --system (the catalogue fixes its own points and steps)")
        with Progress(args, None, "hard: building the cases", unit="s") as progress:
            cases = hard.catalogue(long_steps=args.long_steps)
    else:
        from exact_khk.systems.catalogue import resolve

        system = resolve(args.system)
        check_dense("hard", system)  # before the cases search the file's default point (N^3 work)
        x0 = None if args.x0 is None else parse_vector(args.x0, "--x0", system.dim)
        eps = None if args.eps is None else parse_rational(args.eps, "--eps")
        if eps == 0:
            raise InputError("--eps: the step size must be nonzero")
        with Progress(args, None, "hard: building the cases", unit="s") as progress:
            cases = hard.system_cases(system, x0, eps, long_steps=args.long_steps)
        title = f"hard cases of {system.describe()}, x0 = ({', '.join(str(t) for t in cases[-1].x0)})"
        if not any(c.name.startswith("near-root") for c in cases):
            title += "; det(I - eps f'(x0)) has no real root in eps: no near-singular case"
        print(title)
    if args.only:
        cases = [c for c in cases if args.only.lower() in c.name.lower()]
        if not cases:
            raise InputError(f"--only: no case name contains {args.only!r}")
    precision = not args.no_precision
    with Progress(args, len(cases) * hard.case_stages(ariths, precision), "hard", unit="stage") as progress:
        results = hard.run_catalogue(cases, ariths, args.digits, precision=precision, progress=progress)
    table = hard.markdown_table(results)
    legend = ("cells: ok / WARN (NearSingularWarning, κ = condition estimate, @step) / SINGULAR "
              "(SingularStepError) / UNDECIDED (ball pivot not certain) / OUT OF RANGE (the arithmetic "
              "cannot hold x0 or ε, e.g. beyond float64); err = relative error of the "
              "last point vs the exact orbit (balls: midpoint), rad = certified ball radius; "
              "**UNFLAGGED** = a wrong number returned without a flag")
    if args.markdown:
        print(table)
        print("\n" + legend)
    else:
        for r in results:
            print(f"{r.case.name}: {r.case.description}")
            print(f"  exact: {r.exact_status}" + ("" if r.exact_step is None else f" at step {r.exact_step}"))
            for o in r.outcomes:
                print(f"  {o.arith:<9} {hard.cell(o)}")
            if r.bits_needed is not None:
                print(f"  precision for {r.digits} digits: mp {r.bits_needed} bits, ball {r.ball_bits_needed} bits")
        print(legend)
    doc = {"cases": [hard.result_json(r) for r in results], "legend": legend, "versions": library_versions()}
    if args.out:
        out = pathlib.Path(args.out)
        write_atomic(out / "hard_cases.json", json.dumps(doc, indent=1) + "\n", "--out")
        write_atomic(out / "hard_cases.md", (title + "\n\n" if title else "") + table + "\n\n" + legend + "\n",
                     "--out")
        print(f"wrote {out / 'hard_cases.json'}, {out / 'hard_cases.md'}", file=sys.stderr)
    return doc


@json_command
def cmd_enclose(args):
    from exact_khk.arith.reals import is_rational_text, parse_real, parse_real_vector
    from exact_khk.studies import enclosure

    if args.arith is not None:
        raise InputError("--arith: enclose works in arb balls; choose the precision with --prec")
    from exact_khk.arith import check_precision

    try:
        check_precision("ball", args.prec)
    except InputError as exc:
        raise InputError(f"--prec: {exc}") from None
    if args.steps < 1 or args.steps > enclosure.MAX_ENCLOSURE_STEPS:
        raise InputError(f"--steps: expected 1 <= K <= {enclosure.MAX_ENCLOSURE_STEPS:,} (MAX_ENCLOSURE_STEPS), "
                         f"got {args.steps}")
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    bad = [m for m in methods if m not in enclosure.METHODS]
    if not methods or bad or len(set(methods)) != len(methods):
        raise InputError(f"--methods: expected naive, lohner or both, got {args.methods!r}")
    x0_text, eps_text = args.x0, args.eps
    # the system (real --a/--b/--c: arb blocks) and its defaults; --x0 and --eps are read as reals below
    system, x0_default, eps_default = system_from_args(args, reals=args.prec)
    if args.param is not None:
        from exact_khk.systems.real_expressions import RealExpressionSystem

        system = RealExpressionSystem.from_assignments(system, args.param, args.prec)
    _check_dim(system, "enclose")
    x0 = parse_real_vector(x0_text, args.prec, "--x0", system.dim) if x0_text is not None else \
        tuple(parse_real(str(t), args.prec, "--x0") for t in x0_default)
    eps = parse_real(eps_text, args.prec, "--eps") if eps_text is not None else parse_real(str(eps_default), args.prec)
    if eps.contains(0):
        raise InputError("--eps: the step size must be nonzero (the interval must not contain 0)")
    exact = None
    if args.check_exact:
        if getattr(system, "prec", None) is not None:
            raise InputError("--check-exact needs rational --a/--b/--c and no --param (the exact orbit is the "
                             "reference); real parameters are enclosed, not checked")
        rational = (x0_text is None or all(is_rational_text(t.strip()) for t in x0_text.split(","))) and \
            (eps_text is None or is_rational_text(eps_text))
        if not rational:
            raise InputError("--check-exact needs a rational --x0 and --eps (the exact orbit is the reference)")
        xq = x0_default if x0_text is None else parse_vector(x0_text, "--x0", system.dim)
        eq = eps_default if eps_text is None else parse_rational(eps_text, "--eps")
        _check_reference("enclose --check-exact", system, xq, eq, args.steps)
    if args.out:
        prepare_folder(args.out)
    if args.check_exact:
        exact, _, _ = scaling.exact_prefix(system.field("f"), xq, eq, args.steps)
    integrals = None if args.no_diagnostics else scaling.declared(system)[0]
    print(system.describe())
    with _flint_prec(args.prec):
        print(f"x0 = ({', '.join(t.str(12, radius=True) for t in x0)}), eps = {eps.str(12, radius=True)}, "
              f"K = {args.steps} steps, {args.prec} bits")
    bar = scaling._tqdm(args.steps * len(methods), shows_progress(args), "enclose")
    runs = []
    try:
        for m in methods:
            runs.append(enclosure.enclose(system, x0, eps, args.steps, args.prec, m, exact, integrals,
                                          keep_points=False, progress=bar.update if bar is not None else None))
    finally:
        if bar is not None:
            bar.close()
    print("radius = max_i rad(x_k,i) / max_i |x_k,i| (log2); correct bits = -log2(radius); rate = least-squares "
          "slope of log2(radius) against k")
    print(f"{'method':<8} {'status':<10} {'steps':>6} {'bits/step':>10} {'min bits':>9} {'bits@K':>8} "
          f"{'ms/step':>8} {'exact':>6} {'drift 0':>8}")
    for r in runs:
        last = r.rows[-1]
        ms = None if r.seconds_per_step is None else r.seconds_per_step * 1e3
        ex = "-" if r.encloses is None else ("yes" if r.encloses else "NO")
        dz = "-" if r.drift_contains_zero is None else ("yes" if r.drift_contains_zero else "no")
        print(f"{r.method:<8} {r.status:<10} {r.steps_done:>6} {_fmt(r.radius_rate, '.5f'):>10} "
              f"{r.min_correct_bits:>9.1f} {last.correct_bits:>8.1f} {_fmt(ms, '.3f'):>8} {ex:>6} {dz:>8}")
        if r.message:
            print(f"  {r.method}: {r.message}")
        if r.encloses is False:
            print(f"  {r.method}: ENCLOSURE MISSES THE EXACT VALUE (a bug; please report)")
        if last.drift:
            print(f"  {r.method}: drift at step {last.step}: " + ", ".join(
                f"{name} {_fmt(v)} (contains 0: {'yes' if z else 'no'})" for name, (v, z) in last.drift.items()))
    doc = {"system": system.to_json(), "system_name": system.name, "prec": args.prec, "steps": args.steps,
           "x0": [t.str(30, radius=True) for t in x0], "eps": eps.str(30, radius=True),
           "exact_checked_steps": None if exact is None else len(exact) - 1,
           "runs": [dict(r.summary(), rows=[{"step": w.step, "rad_log2": w.rad_log2, "correct_bits": w.correct_bits,
                                              "encloses": w.encloses, "drift": w.drift} for w in r.rows])
                    for r in runs], "versions": library_versions()}
    if args.out:
        from exact_khk.studies import plots

        out = pathlib.Path(args.out)
        write_atomic(out / "enclosure.json", json.dumps(scaling.jsonable(doc), indent=1) + "\n", "--out")
        series = [(f"{r.method}, {_fmt(r.radius_rate, '.3g')} bits/step", [(w.step, w.rad_log2) for w in r.rows])
                  for r in runs]
        plots.enclosure_radius(series, f"{system.name}, {args.prec} bits, K={args.steps}: certified enclosure "
                               f"radius", out / "enclosure_radius.png", target_bits=100)
        print(f"wrote {out / 'enclosure.json'}, {out / 'enclosure_radius.png'}")
    return scaling.jsonable(doc)


def _flint_prec(prec):
    import flint

    return flint.ctx.workprec(prec)
