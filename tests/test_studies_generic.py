"""``scale`` and ``hard`` for any system: a system file / expression system, not the Lie–Poisson family.

The system: x' = yz − zx, y' = zx − xy, z' = xy − yz.  The components sum to 0,
so S = x + y + z is a linear integral of the flow, and every Kahan map conserves
a linear integral exactly (proved below with SymPy, independently of the library).
It has no second integral: the heights of its exact orbit double at every step.
"""

import json
import math
import subprocess
import sys
from fractions import Fraction

import flint
import pytest
import sympy

from exact_khk import InputError, KahanMap
from exact_khk.cli.main import main
from exact_khk.studies import common, hard, scaling
from exact_khk.studies.hard import det_polynomial, run_case, singular_step_sizes, system_cases
from exact_khk.studies.scaling import (LOG10_2, declared, exact_orbit, precision_needed, run_orbit,
                                       scaling_study, write_study)
from exact_khk.systems.expressions import ExpressionSystem

VARS = ["x", "y", "z"]
FIELD = ["y*z - z*x", "z*x - x*y", "x*y - y*z"]
X0, EPS, K = ["1", "2", "3"], Fraction(1, 10), 8
TOML = """format = 1
name = "cyclic-linear"
title = "x' = yz - zx, y' = zx - xy, z' = xy - yz"
variables = ["x", "y", "z"]

[field]
x = "y*z - z*x"
y = "z*x - x*y"
z = "x*y - y*z"

[integrals]
S = "x + y + z"

[defaults]
x0 = ["1", "2", "3"]
eps = "1/10"
"""


def make_system(**extra):
    # 'same' is f itself: trivially commuting, it exercises the commutation column
    return ExpressionSystem.from_expressions(VARS, field=FIELD, integrals={"S": "x + y + z"}, x0=X0, eps=EPS,
                                             name="cyclic-linear", **extra)


SYSTEM = make_system(fields={"same": FIELD})


@pytest.fixture(scope="module")
def study():
    return scaling_study(SYSTEM, X0, EPS, K, ["float", "mp:53", "mp:113", "ball:128"], progress=False)


@pytest.fixture
def toml_path(tmp_path):
    p = tmp_path / "cyclic.toml"
    p.write_text(TOML)
    return p


# --- the integral, independently of the library ------------------------------------------------


def test_sympy_proves_the_linear_integral_and_the_library_step():
    x, y = sympy.symbols("x0:3"), sympy.symbols("y0:3")
    env = lambda v: dict(zip(sympy.symbols(VARS), v))  # noqa: E731
    f = lambda v: [sympy.sympify(c).subs(env(v), simultaneous=True) for c in FIELD]  # noqa: E731
    # the symmetric bilinear form B(x, y) = (f(x + y) - f(x) - f(y)) / 2 of the Kahan scheme
    B = [sympy.expand((a - b - c) / 2) for a, b, c in zip(f([p + q for p, q in zip(x, y)]), f(x), f(y))]
    assert sympy.expand(sum(B)) == 0        # so sum(x~ - x) = 2 eps sum B(x, x~) = 0: S is conserved
    # the library's exact step solves the Kahan equations (x~ - x) / (2 eps) = B(x, x~)
    pts = KahanMap(SYSTEM.field("f"), EPS, "fraction").orbit(X0, 3)
    for p, q in zip(pts, pts[1:]):
        sub = {**dict(zip(x, map(sympy.Rational, p))), **dict(zip(y, map(sympy.Rational, q)))}
        for i in range(3):
            assert sympy.Rational(q[i] - p[i]) / (2 * sympy.Rational(EPS)) == B[i].subs(sub)
        assert sum(q) == sum(p) == 6


# --- scale ---------------------------------------------------------------------------------------


def test_declared_is_what_the_system_declares():
    ints, fields = declared(SYSTEM)
    assert list(ints) == ["S"] and list(fields) == ["same"]
    assert declared(ExpressionSystem.from_expressions(VARS, field=FIELD)) == ({}, {})


def test_exact_drift_is_zero():
    # in exact arithmetic every drift and residual is exactly 0 (None), at every step
    run = run_orbit(SYSTEM, X0, EPS, K, "fraction")
    assert run.status == "ok" and len(run.rows) == K + 1
    for r in run.rows:
        assert r.drift_log10 == {"S": None} and r.error_log10 is None
        assert r.commutation_log10 is None and r.reversibility_log10 is None


def drift_bound_log10(prec, k):
    """A bound for |S(x^_k) - S(x_0)| / |S(x_0)| in p-bit arithmetic, from exact data.

    The exact map conserves S at *every* point, so rounding errors are not propagated
    into S: S(x^_k) - S(x_0) = sum_j S(delta_j) with delta_j = x^_{j+1} - Phi(x^_j) the local
    error of step j, plus the rounding of evaluating S.  A step solves M x~ = x,
    M = I - eps f'(x), by elimination with partial pivoting: backward stable, so
    |delta_j| <= c N kappa_j u |x_{j+1}| (Higham, ASNA Thm 9.4/7.2; c = 10 covers the growth
    factor of 3x3 elimination and the rounding in forming M); |S(delta)| <= 3 |delta|, and
    evaluating x + y + z costs at most 2u(|x| + |y| + |z|) <= 6u|x|.  kappa_j and |x_j| are
    taken at the exact points (they differ at the computed points by O(kappa u)); the
    bound is doubled for that.
    """
    phi = KahanMap(SYSTEM.field("f"), EPS, "flint")
    pts = phi.orbit(X0, k)
    u, N = 2.0 ** -prec, 3

    def ninf(M):
        return max(sum(abs(float(v)) for v in row) for row in M)

    kappa = [ninf(phi.system_matrix(x)) * ninf(flint.fmpq_mat(phi.system_matrix(x)).inv().tolist())
             for x in pts[:-1]]
    norm = [max(abs(float(t)) for t in x) for x in pts]
    total = sum(3 * 10 * N * kappa[j] * u * norm[j + 1] for j in range(k)) + 6 * u * norm[k]
    return math.log10(2 * total / 6)


def test_float_drifts_are_measured_and_bounded(study):
    runs = {r.arith: r for r in study.runs}
    assert study.integrals == ("S",) and study.commuting == ("same",)
    for name in ("float", "mp:53", "mp:113"):
        run = runs[name]
        assert run.status == "ok" and run.steps_done == K
        drifts = [r.drift_log10["S"] for r in run.rows]                 # every step has a drift entry
        assert any(d is not None for d in drifts)                       # rounding is seen: not exactly 0
        for k, d in enumerate(drifts):
            assert d is None or d <= drift_bound_log10(run.prec, k)
        half = -(run.prec / 2) * LOG10_2
        for r in run.rows:                                              # Phi_f commutes bitwise with itself
            assert r.commutation_log10 is None
            assert r.reversibility_log10 is None or r.reversibility_log10 < half
    # float (LAPACK's LU) and mp:53 (the library's elimination) round to 53 bits in a different
    # order of operations: both within the bound above, not bitwise equal
    # more precision, smaller drift
    worst = {n: max(d for r in runs[n].rows if (d := r.drift_log10["S"]) is not None) for n in ("float", "mp:113")}
    assert worst["mp:113"] < worst["float"] - 15


def test_ball_drift_encloses_the_exact_value(study):
    run = next(r for r in study.runs if r.arith == "ball:128")
    assert run.encloses is True                          # point, S and residual balls contain the exact values
    for r in run.rows[1:]:
        assert r.drift_log10["S"] is not None and r.drift_log10["S"] < -30
        assert r.commutation_log10 is not None           # a ball's radius is not 0


def test_no_integrals_no_drift_columns(tmp_path):
    bare = ExpressionSystem.from_expressions(VARS, field=FIELD, x0=X0, eps=EPS, name="bare")
    st = scaling_study(bare, X0, EPS, 3, ["float", "ball:64"], progress=False)
    assert st.integrals == () and st.commuting == ()
    assert all(r.drift_log10 == {} and r.commutation_log10 is None for r in st.rows())
    assert all(r.reversibility_log10 is not None for r in st.rows() if r.arith == "ball:64")
    write_study(st, tmp_path, plots=False)
    head = (tmp_path / "scaling.csv").read_text().splitlines()[0].split(",")
    assert head == ["arith", "step", "error_log10", "radius_log10", "reversibility_log10", "encloses",
                    "condition", "seconds"]


def test_write_study_generic(tmp_path, study):
    paths = write_study(study, tmp_path)
    assert sorted(p.name for p in paths) == ["drift_vs_step.png", "enclosure_radius.png", "error_vs_step.png",
                                              "scaling.csv", "scaling.json", "work_precision.png"]
    head = (tmp_path / "scaling.csv").read_text().splitlines()[0].split(",")
    assert head[4:6] == ["drift_log10[S]", "commutation_log10"]
    doc = json.loads((tmp_path / "scaling.json").read_text())
    assert doc["system"]["name"] == doc["system_name"] == "cyclic-linear"
    assert doc["integrals"] == ["S"] and doc["method"]["declared"]["integrals"] == {"S": "x + y + z"}


def test_precision_needed_generic():
    r = precision_needed(SYSTEM, X0, EPS, 6, 10)
    tried = dict(r.tried)
    assert tried[r.bits] is True and tried[r.bits - 1] is False and r.worst_log10 <= -10


def test_height_cap_refuses_a_reference_out_of_reach():
    # heights double per step (996 bits at step 8, 1994 at step 9): with a cap of 1000 bits the
    # reference stops after the first point above it, step 9
    fld = SYSTEM.field("f")
    assert len(exact_orbit(fld, X0, EPS, 9, max_bits=1000)[0]) == 10
    with pytest.raises(InputError, match="1994 bits high at step 9 .* choose at most 9 steps"):
        exact_orbit(fld, X0, EPS, 10, max_bits=1000)


# --- hard ----------------------------------------------------------------------------------------


def independent_det():
    """det(I - eps f'(x0)) by SymPy from the field's expressions."""
    e, v = sympy.Symbol("eps"), sympy.symbols(VARS)
    J = sympy.Matrix([[sympy.diff(sympy.sympify(c), s) for s in v] for c in FIELD])
    J = J.subs(dict(zip(v, map(sympy.Rational, X0))))
    return sympy.Poly((sympy.eye(3) - e * J).det(), e)


def test_det_polynomial_generic():
    p = independent_det()
    assert det_polynomial(SYSTEM.field("f"), X0).as_expr().equals(p.as_expr())
    roots = singular_step_sizes(SYSTEM.field("f"), X0)
    assert [r.lo for r in roots] == [Fraction(-1, 2), Fraction(-1, 4)] and all(r.exact for r in roots)
    assert all(p.eval(sympy.Rational(r.lo)) == 0 for r in roots)


def test_system_cases_and_their_runs():
    cases = system_cases(SYSTEM, long_steps=5, distances=(3, 20))
    assert [c.name for c in cases] == ["near-root 1e-3", "near-root 1e-20", "singular (eps=-1/2)",
                                       "singular (eps=-1/4)", "long orbit 5"]
    assert cases[1].eps == Fraction(-1, 4) + Fraction(1, 10 ** 20)    # nearest root to 0 is -1/4
    assert all(c.system is SYSTEM and c.x0 == (1, 2, 3) for c in cases)
    near = run_case(cases[1], ["float", "mp:113", "mp:256", "ball:512"], digits=10)
    out = {o.arith: o for o in near.outcomes}
    assert near.exact_status == "ok"
    assert out["float"].status == "singular" and out["mp:113"].status == "warned"
    assert out["mp:256"].status == "ok" and out["ball:512"].encloses is True
    assert not any(o.silent_failure for o in near.outcomes) and 53 < near.bits_needed <= 256
    sing = run_case(cases[3], ["float", "mp:113", "ball:128"], precision=False)
    assert sing.exact_status == "singular" and sing.exact_step == 1
    assert all(o.status in ("singular", "undecided") for o in sing.outcomes)
    doc = hard.result_json(sing)
    assert doc["system_name"] == "cyclic-linear" and doc["system"]["variables"] == VARS


def test_long_orbit_stops_where_the_reference_is_out_of_reach(monkeypatch):
    monkeypatch.setattr(common, "MAX_EXACT_BITS", 1000)
    long = system_cases(SYSTEM, long_steps=1000, distances=())[-1]
    assert long.name == "long orbit 9" and "of 1000 asked" in long.description and "1994 bits" in long.description
    r = run_case(long, ["float"], precision=False)          # the exact reference reaches every step
    assert r.exact_status == "ok" and r.outcomes[0].status == "ok" and not r.outcomes[0].silent_failure


def test_long_orbit_case_carries_its_reference(monkeypatch):
    # system_cases computed the exact orbit to choose the steps: run_case reuses it
    long = system_cases(SYSTEM, long_steps=6, distances=())[-1]
    pts, seconds = long.reference
    assert list(pts) == KahanMap(SYSTEM.field("f"), EPS, "flint").orbit(X0, 6) and seconds >= 0
    monkeypatch.setattr(hard, "exact_prefix", lambda *a, **k: pytest.fail("the reference was computed again"))
    r = run_case(long, ["mp:64"], precision=False)
    assert r.exact_status == "ok" and r.exact_seconds == seconds and r.outcomes[0].status == "ok"


# --- the command line ----------------------------------------------------------------------------


def test_cli_scale_system_file(toml_path, tmp_path, capsys):
    out = tmp_path / "out"
    rc = main(["scale", "--system", str(toml_path), "--steps", "6", "--ariths", "float,ball:128",
               "--digits", "6", "--quiet", "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0
    assert text.startswith("cyclic-linear: x' = yz - zx")                  # which system ran
    assert "S drift" in text and "comm" not in text.split("\n")[4]       # no commuting field declared
    assert sorted(p.name for p in out.iterdir()) == ["drift_vs_step.png", "enclosure.json", "enclosure_radius.png",
                                                      "error_vs_step.png", "scaling.csv", "scaling.json",
                                                      "work_precision.png"]
    doc = json.loads((out / "scaling.json").read_text())
    assert doc["system_name"] == "cyclic-linear" and doc["integrals"] == ["S"] and doc["steps"] == 6
    assert doc["digits"]["ball"]["bits"] >= 20 and len(doc["digits"]["enclosure"]["orbit"]) == 7


def test_cli_hard_system_file(toml_path, tmp_path, capsys):
    out = tmp_path / "out"
    rc = main(["hard", "--system", str(toml_path), "--long-steps", "4", "--no-precision", "--quiet",
               "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0
    assert text.startswith("hard cases of cyclic-linear") and "x0 = (1, 2, 3)" in text.split("\n")[0]
    assert "singular (eps=-1/4)" in text and "long orbit 4" in text and "UNFLAGGED" not in text.split("cells:")[0]
    doc = json.loads((out / "hard_cases.json").read_text())
    assert len(doc["cases"]) == 9 and {c["system_name"] for c in doc["cases"]} == {"cyclic-linear"}
    assert (out / "hard_cases.md").read_text().startswith("hard cases of cyclic-linear")
    # --x0 and --eps choose the point and the long orbit's step
    rc = main(["hard", "--system", str(toml_path), "--x0", "1,1,1", "--eps", "1/5", "--long-steps", "2",
               "--no-precision", "--quiet", "--only", "long"])
    text = capsys.readouterr().out
    assert rc == 0 and "x0 = (1, 1, 1)" in text and "eps = 1/5, 2 steps" in text


@pytest.mark.parametrize("argv, option", [
    (["scale", "--n", "3"], "--n"),
    (["scale", "--a", "1,0,2", "--b", "0,1,0", "--c", "3,1,1"], "--a"),
    (["hard", "--x0", "1,2,3"], "--x0"),
    (["hard", "--eps", "1/3"], "--eps"),
])
def test_cli_refuses_options_of_the_other_kind(argv, option, toml_path, capsys):
    if argv[0] == "scale":
        argv = argv + ["--system", str(toml_path)]        # a Lie–Poisson option with --system
    assert main(argv + ["--quiet"]) == 2                  # (hard: a --system option without --system)
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and option in err and "Traceback" not in err


def test_cli_refusal_in_a_fresh_process(toml_path):
    p = subprocess.run([sys.executable, "-m", "exact_khk", "scale", "--system", str(toml_path), "--n", "3"],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.count("\n") == 1 and "--n" in p.stderr and "Traceback" not in p.stderr


def test_cli_bad_system_inputs(toml_path, capsys, monkeypatch):
    monkeypatch.setattr(common, "MAX_EXACT_BITS", 1000)    # 40 steps would reach 2^40 bits
    for argv, msg in ((["hard", "--system", str(toml_path), "--x0", "1,2"], "--x0"),
                      (["hard", "--system", str(toml_path), "--eps", "0"], "--eps"),
                      (["scale", "--system", str(toml_path), "--steps", "40"], "steps")):
        assert main(argv + ["--quiet"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and msg in err


def test_parser_does_not_import_sympy_hard_or_matplotlib():
    from exact_khk.cli.study import HARD_ARITHS

    assert HARD_ARITHS == ",".join(hard.DEFAULT_ARITHS)
    code = ("import sys; from exact_khk.cli.main import build_parser; build_parser(); "
            "print(sorted(m for m in ('exact_khk.studies.hard', 'matplotlib') if m in sys.modules))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and p.stdout.strip() == "[]"


def test_cli_exact_zero_drift_and_no_real_root(tmp_path, capsys):
    # f = (0, x^2): x is conserved bitwise in every arithmetic (its drift prints as -inf), and
    # det(I - eps f'(x0)) = 1 has no root (no near-singular case)
    p = tmp_path / "shear.toml"
    p.write_text('name = "shear"\nvariables = ["x", "y"]\n[field]\nx = "0"\ny = "x**2"\n[integrals]\nX = "x"\n'
                 '[defaults]\nx0 = ["3", "1"]\n')
    assert main(["scale", "--system", str(p), "--steps", "4", "--ariths", "float", "--quiet"]) == 0
    row = capsys.readouterr().out.splitlines()[-1].split()
    assert row[0] == "float" and row[7] == "-inf"          # the X drift column
    assert main(["hard", "--system", str(p), "--long-steps", "3", "--no-precision", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "has no real root in eps: no near-singular case" in out.splitlines()[0]
    assert "near-root" not in out and "long orbit 3" in out
