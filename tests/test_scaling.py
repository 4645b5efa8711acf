"""Precision-scaling studies: errors against the exact orbit, fitted rates, precision needed."""

import json
import math
from fractions import Fraction

import flint
import pytest

from exact_khk import KahanMap, SingularStepError
from exact_khk.cli.main import main
from exact_khk.studies.scaling import (DEFAULT_ARITHS, LOG10_2, exact_orbit, precision_needed,
                               precision_rule, run_orbit, scaling_study, write_study)
from exact_khk.systems.lie_poisson.system import DEFAULT_X0, LiePoissonSystem, default_system

K = 5
EPS = Fraction(1, 10)


@pytest.fixture(scope="module")
def study():
    return scaling_study(default_system(), DEFAULT_X0, EPS, K, ["float", "mp:53", "mp:113", "mp:256",
                                                                "ball:64", "ball:256"], progress=False)


def _ninf(M):
    return max(sum(abs(float(v)) for v in row) for row in M)


def first_order_bound_log10(prec):
    """A first-order rounding-error bound for K steps at ``prec`` bits, from exact data.

    Step k solves M_k x_{k+1} = x_k with partial pivoting: backward stable, so its
    relative error is <= c N kappa_k u (Higham, ASNA Thm 9.4/7.2; c = 4 covers the
    growth factor of 6x6 elimination and the normwise form); an error already in x_k
    is carried by dPhi(x_k).  So |err_K| <= sum_k c N kappa_k u |x_{k+1}| prod_{j>k} |dPhi(x_j)|,
    everything computed exactly (flint) and relative to |x_K|.
    """
    phi = KahanMap(default_system().field("f"), EPS, "flint")
    pts = phi.orbit(DEFAULT_X0, K)
    N, u = len(pts[0]), 2.0 ** -prec
    kappa = [_ninf(phi.system_matrix(x)) * _ninf(flint.fmpq_mat(phi.system_matrix(x)).inv().tolist())
             for x in pts[:-1]]
    jac = [_ninf(phi.jacobian(x)) for x in pts]
    norm = [max(abs(float(t)) for t in x) for x in pts]
    total = sum(4 * N * kappa[k] * u * norm[k + 1] * math.prod(jac[k + 1:K]) for k in range(K))
    return math.log10(total / norm[K])


def test_errors_decrease_with_precision(study):
    runs = {r.arith: r for r in study.runs}
    errs = [runs[a].final_error_log10 for a in ("mp:53", "mp:113", "mp:256")]
    assert errs[0] > errs[1] > errs[2]
    for a in ("float", "mp:53", "mp:113", "mp:256"):
        assert runs[a].status == "ok" and runs[a].steps_done == K
        assert runs[a].final_error_log10 <= first_order_bound_log10(runs[a].prec)
    # float (LAPACK's LU) and mp:53 (the library's elimination) both round to 53 bits, in a
    # different order of operations: each within the first-order bound above, not equal


def test_ball_runs_enclose_and_rates_are_positive(study):
    for run in study.runs:
        if run.arith.startswith("ball"):
            assert run.encloses is True
            # wrapping: the certified radius grows; the fitted growth rate is positive and finite
            assert math.isfinite(run.radius_rate) and run.radius_rate > 0
            r = run.rows[-1]
            assert r.error_log10 <= r.radius_log10            # the midpoint error is within the radius
            assert r.drift_log10["H~"] is not None and r.commutation_log10 is not None
        else:
            assert run.encloses is None and math.isfinite(run.loss_rate)


def test_diagnostics_are_rounding_sized(study):
    # H~ drift, commutation and reversibility residuals are exactly 0 for the exact
    # maps: in mp:P they are rounding errors, far below 2^-(P/2) for this tame orbit
    for run in study.runs:
        if run.arith.startswith("mp") or run.arith == "float":
            half = -(run.prec / 2) * LOG10_2
            for r in run.rows[:-1]:
                assert set(r.drift_log10) == {"H~", "K~"}
                assert r.drift_log10["H~"] < half and r.drift_log10["K~"] < half
                assert r.commutation_log10 < half and r.reversibility_log10 < half


def test_enclosure_check_can_fail():
    # negative control: a wrong "exact" reference (last point moved far outside the
    # ball) must make the certified enclosure check fail
    s = default_system()
    exact, _ = exact_orbit(s.field("f"), DEFAULT_X0, EPS, 3)
    wrong = exact[:-1] + [tuple(t + flint.fmpq(1, 10 ** 9) for t in exact[-1])]
    good = run_orbit(s, DEFAULT_X0, EPS, 3, "ball:128", exact, diagnostics=False)
    bad = run_orbit(s, DEFAULT_X0, EPS, 3, "ball:128", wrong, diagnostics=False)
    assert good.encloses is True and bad.encloses is False


def test_undecided_ball_stops_with_status():
    # ball:24 cannot keep a certain pivot for long on this orbit: "undecided", no number
    run = run_orbit(default_system(), DEFAULT_X0, EPS, 40, "ball:24", diagnostics=False)
    assert run.status == "undecided" and run.failed_step is not None
    assert run.steps_done == run.failed_step - 1 and "no pivot" in run.message
    assert run.encloses is True


def test_singular_reference_raises():
    s2 = LiePoissonSystem.from_vectors("1,2", "0,1", "3,1")
    with pytest.raises(SingularStepError):
        scaling_study(s2, ["-2", "-2", "-2", "1"], "-1/6", 2, ["float"], progress=False)


def test_precision_needed_is_minimal_and_confirmed():
    s, D = default_system(), 10
    r = precision_needed(s, DEFAULT_X0, EPS, K, D)
    tried = dict(r.tried)
    assert tried[r.bits] is True and tried[r.bits - 1] is False
    assert r.bits >= math.ceil(D / LOG10_2) - 1 and r.worst_log10 <= -D
    # independent confirmation against the exact orbit
    ok = run_orbit(s, DEFAULT_X0, EPS, K, f"mp:{r.bits}", diagnostics=False)
    assert max(x.error_log10 for x in ok.rows if x.error_log10 is not None) <= -D
    below = run_orbit(s, DEFAULT_X0, EPS, K, f"mp:{r.bits - 1}", diagnostics=False)
    assert max(x.error_log10 for x in below.rows if x.error_log10 is not None) > -D


def _search(monkeypatch, model, digits=10):
    """precision_needed over a model of the runs: ``model(P)`` -> (passed, worst log10 or None)."""
    from exact_khk.studies import scaling
    probes = []

    def passes(system, x0, eps, steps, D, kind, P, exact):
        probes.append(P)
        return model(P)

    monkeypatch.setattr(scaling, "_passes", passes)
    r = precision_needed(default_system(), DEFAULT_X0, EPS, 1, digits, exact=[DEFAULT_X0])
    assert len(set(probes)) == len(probes)  # never the same precision twice
    tried = dict(r.tried)
    assert tried[r.bits] is True and (r.bits == 2 or tried[r.bits - 1] is False)
    return r.bits, probes


def _scaling(T, undecided_below=0):
    """Runs whose worst error is 10^-10.01 · 2^(T - P): P >= T passes."""
    def model(P):
        w = None if P < undecided_below else -10.01 - (P - T) * LOG10_2
        return w is not None and w <= -10, w
    return model


def test_precision_search_follows_the_error_model(monkeypatch):
    # the long-orbit case's ball search: runs below 4352 bits undecided, so the search
    # doubles to 8704, predicts 7869 and confirms 7868 fails (bisection: 12 more probes)
    bits, probes = _search(monkeypatch, _scaling(7869, undecided_below=4353))
    assert bits == 7869 and probes == [34 << k for k in range(9)] + [7869, 7868]
    # a first probe that passes is walked down; a failing one up
    assert _search(monkeypatch, _scaling(20)) == (20, [34, 20, 19])
    assert _search(monkeypatch, _scaling(50)) == (50, [34, 50, 49])


def test_precision_search_survives_a_wrong_model(monkeypatch):
    # every exact threshold T is found although the reported errors mislead the predictions
    # (too optimistic, too pessimistic, no information): bisection takes over
    for T in (2, 3, 35, 100, 1000, 5000):
        for lie in (-1000.0, 1000.0, None, -10.5, -9.5):
            bits, probes = _search(monkeypatch, lambda P, T=T, lie=lie: (P >= T, lie))
            # up: steps of at least 1, 2, 4, ...; then at most 3 probes per halving of (lo, hi)
            assert bits == T and len(probes) <= T.bit_length() + 3 * max(T, 34).bit_length() + 2
    # passing not monotone in P: the answer is still a boundary (bits passes, bits - 1 fails)
    _search(monkeypatch, lambda P: (P >= 60 or P % 7 == 0, -11.0 if P >= 60 or P % 7 == 0 else -5.0))


def test_errors_from_logarithms_match_exact_rationals():
    from exact_khk.studies.scaling import vs_exact
    import mpmath
    import random
    rng = random.Random(5)
    for h in (3, 80, 3000, 9000):
        for _ in range(40):
            ex = [flint.fmpq(rng.getrandbits(h) * rng.choice([-1, 0, 1]), rng.getrandbits(h) | 1) for _ in range(3)]
            xs = [e + flint.fmpq(rng.getrandbits(20) * rng.choice([-1, 0, 1]), 1 << rng.randrange(300)) for e in ex]
            err, rad = vs_exact(xs, ex)
            gap = max(abs(x - e) for x, e in zip(xs, ex))
            ref = max(abs(e) for e in ex)
            assert rad is None and (err is None) == (gap == 0)
            if err is not None:  # the exact ratio's log10 at 200 bits
                q = gap / ref if ref != 0 else gap
                with mpmath.workprec(200):
                    assert abs(err - float(mpmath.log10(mpmath.mpf(int(q.p)) / int(q.q)))) < 1e-13


def test_precision_rule_fit():
    rule = precision_rule(default_system(), DEFAULT_X0, EPS, 8, 10, kind="ball")
    assert math.isfinite(rule.c) and rule.c > 0          # ball radii grow: more bits per step
    for r in rule.results:
        assert r.kind == "ball" and abs(rule.predict(10, r.steps) - r.bits) < 12


def test_write_study(tmp_path, study):
    paths = write_study(study, tmp_path)
    names = sorted(p.name for p in paths)
    expected = {"error_vs_step.png", "scaling.csv", "scaling.json", "work_precision.png", "drift_vs_step.png"}
    if any(r.arith.startswith("ball") for r in study.runs):
        expected.add("enclosure_radius.png")
    assert set(names) == expected
    lines = (tmp_path / "scaling.csv").read_text().splitlines()
    assert len(lines) == 1 + sum(len(r.rows) for r in study.runs)
    head = lines[0].split(",")
    assert head[4:7] == ["drift_log10[H~]", "drift_log10[K~]", "commutation_log10"]
    doc = json.loads((tmp_path / "scaling.json").read_text())
    assert [r["arith"] for r in doc["runs"]] == [r.arith for r in study.runs] and "error" in doc["method"]
    assert doc["integrals"] == ["H~", "K~"] and doc["commuting_fields"] == ["g[-++]"]
    assert doc["system"]["family"] == "lie-poisson" and doc["system"]["a"] == ["1", "0", "2"]
    assert set(doc["rows"][0]["drift_log10"]) == {"H~", "K~"}
    assert (tmp_path / "work_precision.png").read_bytes()[:4] == b"\x89PNG"


def test_cli_scale(tmp_path, capsys):
    rc = main(["scale", "--steps", "3", "--ariths", "float,ball:64", "--digits", "8", "--quiet",
               "--out", str(tmp_path), "--no-plots"])
    out = capsys.readouterr().out
    assert rc == 0 and "bits left" in out and "fitted rule" in out
    enc = json.loads((tmp_path / "enclosure.json").read_text())
    assert enc["certified"] is True and len(enc["orbit"]) == 4


@pytest.mark.parametrize("argv, msg", [
    (["scale", "--ariths", "flint"], "--ariths"),
    (["scale", "--ariths", "nope:3"], "arith"),
    (["scale", "--arith", "float"], "--arith"),
    (["scale", "--digits", "0"], "--digits"),
    (["scale", "--steps", "0"], "--steps"),
])
def test_cli_scale_bad_input(argv, msg, capsys):
    assert main(argv + ["--quiet"]) == 2
    err = capsys.readouterr().err
    assert msg in err and err.count("\n") == 1


@pytest.mark.slow
def test_default_study_long():
    st = scaling_study(default_system(), DEFAULT_X0, EPS, 200, DEFAULT_ARITHS, progress=False)
    mp = [r for r in st.runs if r.arith.startswith("mp")]
    assert all(a.final_error_log10 > b.final_error_log10 for a, b in zip(mp, mp[1:]))
    assert all(r.encloses for r in st.runs if r.arith.startswith("ball"))


def test_a_rerun_leaves_no_file_of_an_earlier_study(tmp_path, capsys):
    """A study's files are one set: files of an earlier run in the folder that this run
    does not write are removed, and the command says so."""
    from exact_khk.cli.main import main

    out = tmp_path / "out"
    assert main(["scale", "--steps", "3", "--ariths", "float,ball:64", "--digits", "3", "--quiet",
                 "--out", str(out)]) == 0
    assert {"enclosure.json", "enclosure_radius.png"} <= {p.name for p in out.iterdir()}
    capsys.readouterr()
    assert main(["scale", "--steps", "3", "--ariths", "float", "--quiet", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "removed from an earlier run" in text and "enclosure.json" in text
    assert sorted(p.name for p in out.iterdir()) == ["drift_vs_step.png", "error_vs_step.png", "scaling.csv",
                                                     "scaling.json", "work_precision.png"]
