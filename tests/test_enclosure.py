"""Certified enclosures (exact_khk.studies.enclosure) and real input (exact_khk.arith.reals).

Every enclosure must contain the exact orbit, decided exactly (|q − mid| ≤ rad in
rationals); where a method cannot certify, it stops "undecided" — never a wrong box.
"""

from __future__ import annotations

import random
from fractions import Fraction

import flint
import mpmath
import pytest

from exact_khk.arith.ball import contains_exact
from exact_khk.arith.reals import parse_real, parse_real_vector
from exact_khk.errors import InputError
from exact_khk.kahan.map import KahanMap
from exact_khk.studies import enclosure
from exact_khk.studies.scaling import declared, exact_prefix
from exact_khk.systems.catalogue import resolve
from exact_khk.systems.lie_poisson import DEFAULT_EPS, DEFAULT_X0, LiePoissonSystem, default_system


def _systems():
    yield default_system(), [str(t) for t in DEFAULT_X0], str(DEFAULT_EPS)
    for name in ("euler-top", "lotka-volterra", "lagrange-top", "cmoq-cubic"):
        s = resolve(name)
        yield s, [str(t) for t in s.default_x0], str(s.default_eps)


@pytest.mark.parametrize("seed", range(12))
def test_enclosures_contain_the_exact_orbit_on_random_short_orbits(seed):
    rng = random.Random(seed)
    cases = list(_systems())
    if seed % 3 == 0:
        s = LiePoissonSystem.random(rng.choice([2, 3, 4]), seed)
        cases = [(s, [str(t) for t in s.random_point(seed)] if hasattr(s, "random_point") else None, "1/10")]
    system, x0, eps = cases[seed % len(cases)]
    fld = system.field("f")
    if x0 is None:
        x0 = [str(Fraction(rng.randint(-9, 9), rng.randint(1, 5))) for _ in range(fld.dim)]
    else:
        x0 = [str(Fraction(t) + Fraction(rng.randint(-3, 3), rng.randint(2, 7))) for t in x0]
    eps = str(Fraction(rng.randint(1, 4), rng.choice([7, 10, 13, 20])))
    steps, prec = 12, rng.choice([24, 40, 64])  # low precisions stress the "undecided" exit
    try:
        exact, _, err = exact_prefix(fld, x0, eps, steps)
    except Exception:  # an undefined starting step: nothing to enclose
        pytest.skip("singular start")
    for method in enclosure.METHODS:
        run = enclosure.enclose(system, x0, eps, steps, prec, method, exact, keep_points=True)
        assert run.status in ("ok", "undecided")
        for k, X in enumerate(run.points):
            if k < len(exact):
                assert all(contains_exact(t, q) for t, q in zip(X, exact[k])), (method, k)
        assert run.encloses in (True, None)
        if err is not None:  # the exact step is singular: the enclosure cannot pass it
            assert run.steps_done < err.step if hasattr(err, "step") and err.step else True


def test_lohner_beats_naive_and_contains_the_exact_orbit():
    runs = enclosure.compare(default_system(), DEFAULT_X0, DEFAULT_EPS, 60, 128, check_exact=True,
                             diagnostics=True)
    naive, lohner = runs
    assert lohner.status == "ok" and lohner.encloses is True and lohner.drift_contains_zero is True
    assert lohner.min_correct_bits > 100
    assert naive.status == "undecided" or naive.rows[-1].correct_bits < lohner.rows[-1].correct_bits - 50


def test_interval_inputs_enclose_every_point_inside():
    """An x0 box and an eps interval: exact orbits of rational points inside are enclosed."""
    system = resolve("euler-top")
    box = ["[0.99,1.01]", "2+-1/100", "-1"]
    eps = "[0.199,0.201]"
    runs = {m: enclosure.enclose(system, box, eps, 10, 128, m, keep_points=True) for m in enclosure.METHODS}
    rng = random.Random(1)
    fld = system.field("f")
    for _ in range(5):
        x0 = [Fraction(99, 100) + Fraction(rng.randint(0, 200), 10000), 2 + Fraction(rng.randint(-100, 100), 10000),
              Fraction(-1)]
        e = Fraction(199, 1000) + Fraction(rng.randint(0, 20), 10000)
        exact = KahanMap(fld, e, "flint").orbit(x0, 10)
        for run in runs.values():
            for k, X in enumerate(run.points):
                assert all(contains_exact(t, q) for t, q in zip(X, exact[k])), (run.method, k)
    assert runs["lohner"].rows[-1].correct_bits >= runs["naive"].rows[-1].correct_bits - 1


def test_width_zero_intervals_reproduce_the_rational_results():
    s = default_system()
    x0 = [str(t) for t in DEFAULT_X0]
    boxed = [f"[{t},{t}]" for t in x0]
    for m in enclosure.METHODS:
        a = enclosure.enclose(s, x0, "1/10", 8, 96, m, keep_points=True)
        b = enclosure.enclose(s, boxed, "[1/10, 1/10]", 8, 96, m, keep_points=True)
        c = enclosure.enclose(s, x0, "1/10+-0", 8, 96, m, keep_points=True)
        for P, Q, R in zip(a.points, b.points, c.points):
            for p, q, r in zip(P, Q, R):
                assert p.mid() == q.mid() == r.mid() and p.rad() == q.rad() == r.rad()


def test_irrational_inputs_against_an_mpmath_reference():
    system = resolve("euler-top")
    x0 = ["sqrt(2)", "pi/3", "-exp(1/5)"]
    eps = "1/(4*sqrt(7))"
    ctx = mpmath.MPContext()
    ctx.prec = 600
    ref_x0 = [ctx.sqrt(2), ctx.pi / 3, -ctx.exp(ctx.mpf(1) / 5)]
    ref_eps = 1 / (4 * ctx.sqrt(7))
    ref = KahanMap(system.field("f"), ref_eps, "mp:600").orbit(ref_x0, 30)
    for m in enclosure.METHODS:
        run = enclosure.enclose(system, x0, eps, 30, 200, m, keep_points=True)
        assert run.status == "ok"
        for X, R in zip(run.points, ref):
            for t, r in zip(X, R):
                # the 600-bit reference is within 2^-500 of the exact orbit; widen by that
                with flint.ctx.workprec(600):
                    assert (t + flint.arb(0, flint.arb(2) ** -500)).contains(flint.arb(ctx.nstr(r, 180)))


def test_undecided_never_wrong_near_a_singular_step():
    """At a precision too low for the orbit, the run stops undecided; what it returned is right."""
    s = default_system()
    x0 = [str(t) for t in DEFAULT_X0]
    exact, _, _ = exact_prefix(s.field("f"), x0, "1/10", 80)
    run = enclosure.enclose(s, x0, "1/10", 80, 16, "naive", exact)
    assert run.status == "undecided" and run.encloses is True and run.failed_step is not None


@pytest.mark.parametrize("text", ["[1,2", "[2,1]", "1+-", "+-1", "1+-(-1)", "[1,2,3]", "sqrt(", "__import__('os')",
                                  "x", "1/0", "log(0)", "2^1000000", "", "[1;2]", "1e99999999999", "(" * 400 + "1"
                                  + ")" * 400, "lambda: 1", "[1, 2]]"])
def test_malformed_reals_are_refused(text):
    with pytest.raises(InputError):
        parse_real(text, 64)


def test_decimal_reads_the_exact_rational():
    with flint.ctx.workprec(300):
        x = parse_real("0.1", 300)
        assert contains_exact(x, flint.fmpq(1, 10)) and x.rad() < flint.arb(2) ** -295
    assert len(parse_real_vector("[1,2],(3),sqrt(2)", 64, "x0", 3)) == 3
    with pytest.raises(InputError):
        parse_real_vector("1,2", 64, "x0", 3)


def test_enclose_refuses_absurd_requests():
    s = default_system()
    with pytest.raises(InputError):
        enclosure.enclose(s, DEFAULT_X0, "1/10", enclosure.MAX_ENCLOSURE_STEPS + 1)
    with pytest.raises(InputError):
        enclosure.enclose(s, DEFAULT_X0, "1/10", 3, 10 ** 7)
    with pytest.raises(InputError):
        enclosure.enclose(s, DEFAULT_X0, "[-1,1]", 3)
    with pytest.raises(InputError):
        enclosure.enclose(s, DEFAULT_X0, "1/10", 3, method="taylor")
    assert declared(s)[0]


def test_cli_enclose_and_scale_lohner(tmp_path, capsys):
    from exact_khk.cli.main import main

    assert main(["enclose", "--steps", "30", "--prec", "128", "--check-exact", "--quiet", "--out",
                 str(tmp_path / "e")]) == 0
    out = capsys.readouterr().out
    assert "lohner   ok" in out and "NO" not in out.split("method", 1)[1].split("\n", 2)[1]
    assert (tmp_path / "e" / "enclosure.json").exists() and (tmp_path / "e" / "enclosure_radius.png").exists()
    assert main(["enclose", "--system", "euler-top", "--x0", "[0.999999,1.000001],sqrt(2),-1", "--eps",
                 "1/5+-1e-9", "--steps", "10", "--quiet"]) == 0
    assert main(["scale", "--steps", "12", "--ariths", "float,ball:128,lohner:128", "--quiet", "--out",
                 str(tmp_path / "s")]) == 0
    out = capsys.readouterr().out
    assert "lohner:128 ok" in out and "MISSES" not in out
    names = {p.name for p in (tmp_path / "s").iterdir()}
    assert {"work_precision.png", "error_vs_step.png", "drift_vs_step.png", "enclosure_radius.png"} <= names
    assert not [n for n in names if n.startswith(".tmp")]
