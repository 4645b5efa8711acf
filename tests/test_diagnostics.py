"""Integrability diagnostics: degree growth, recurrence fit, integral discovery, heights."""

import json
import random
import subprocess
import sys
from fractions import Fraction as F

import flint
import pytest
import sympy

from exact_khk import InputError, LiePoissonSystem, get_arith
from exact_khk.cli.main import main
from exact_khk.diagnostics import degree_sequence, exact_degrees, find_integrals, fit_recurrence, height_growth
from exact_khk.diagnostics.degrees import (_Degenerate, cauchy_degree, interpolate, line_degrees, line_run,
                                           polynomial_line_degrees, resolve_field, valued_line_degrees)
from exact_khk.diagnostics.integrals import _Job, verify_exact
from exact_khk.diagnostics.kernels import monomials, orbit_kernel_exact
from exact_khk.systems.expressions import ExpressionSystem
from exact_khk.systems.lie_poisson.invariants import grad_Htilde

from .conftest import DATA

GOOD = 2749534618746033473  # a prime near 2^61.3

EULER = ExpressionSystem.from_expressions(["x", "y", "z"], field=["y*z", "-2*x*z", "x*y"], name="euler")
LV = ExpressionSystem.from_expressions(["u", "v"], field=["u - u*v", "u*v - v"], name="lv")


def golden_cases():
    return json.loads((DATA / "golden_degrees.json").read_text())["cases"]


def system_of(case):
    if "lie_poisson" in case:
        lp = case["lie_poisson"]
        return LiePoissonSystem.from_vectors(lp["a"], lp["b"], lp["c"]), case["field_kind"]
    return ExpressionSystem.from_expressions(case["variables"], field=case["field"]), "f"


# --- degrees --------------------------------------------------------------------------


@pytest.mark.parametrize("case", golden_cases(), ids=lambda c: c["name"])
def test_degrees_match_sympy_golden(case):
    """Modular degrees on random lines and exact composition over Q equal SymPy's
    composition along a fixed rational line (scripts/generate_degree_golden.py)."""
    system, kind = system_of(case)
    gold = case["degrees"]
    res = degree_sequence(system, steps=len(gold) - 1, eps=case["eps"], field=kind)
    assert list(res.degrees) == gold
    assert not res.disagreeing
    _, fld = resolve_field(system, kind)
    # both routes are covered: polynomial arithmetic below dimension 8, values from it
    assert {r["route"] for r in res.to_json()["runs"]} == {"values" if fld.dim >= 8 else "polynomials"}
    ex = exact_degrees(fld, F(case["eps"]), 3, max_terms=3000)
    assert ex == gold[:len(ex)]
    assert len(ex) >= 2 or fld.dim >= 8  # dimension 8: the first composition has C(16, 8) > 3000 terms


def test_exact_mode_reported_and_agrees():
    res = degree_sequence(EULER, steps=10, eps="1/10", exact=3)
    assert res.exact == (1, 3, 9, 19)
    assert "agrees" in res.summary()
    assert res.fit.growth == "polynomial" and res.fit.polynomial_degree == 2 and res.fit.polynomial == "2*k^2 + 1"


def test_non_integrable_control_is_exponential():
    res = degree_sequence(LV, steps=12, eps="1/10")
    assert res.degrees == tuple(2 ** k for k in range(13))
    assert res.fit.growth == "exponential"
    dd = res.fit.dynamical_degree
    assert dd.minimal_polynomial == "x - 2" and dd.enclosure == ("2.0000000000", "2.0000000000")
    cat = degree_sequence("lotka-volterra", steps=10)
    assert cat.fit.growth == "exponential"


def test_lie_poisson_growth_is_polynomial_and_fast_enough():
    s = LiePoissonSystem.random(3, 1)
    res = degree_sequence(s, steps=20, primes=1)
    assert res.degrees[:4] == (1, 6, 12, 18)
    assert res.fit.growth == "polynomial" and res.fit.polynomial_degree == 1
    assert res.fit.dynamical_degree.coefficients == (1, -1)


def test_forced_bad_prime_undercounts_and_is_reported():
    """A prime dividing the numerator of eps makes the map the identity mod p: it
    undercounts at every line; the maximum over primes is still right, the bad
    run is listed and the note names the prime."""
    alone = degree_sequence(EULER, steps=4, eps="3/10", primes=[3])
    assert alone.degrees == (1, 1, 1, 1, 1)  # an undercount, never an overcount
    res = degree_sequence(EULER, steps=4, eps="3/10", primes=[3, GOOD])
    assert res.degrees == (1, 3, 9, 19, 33)
    assert (3, 0) in res.disagreeing and any("3" in n and "bad" in n for n in res.notes)


def test_undercount_frequency_within_schwartz_zippel_bound():
    """Over a small prime, the fraction of random lines that undercount d_k stays
    below the stated bound 2 d (d + 1) / p; never an overcount."""
    _, fld = resolve_field(EULER, "f")
    true = [1, 3, 9]
    for p in (101, 1009):
        rng, under, lines = random.Random(7), [0, 0, 0], 0
        for _ in range(300):
            try:
                d = line_degrees(fld, F(1, 10), p, 2, rng)
            except _Degenerate:
                continue
            lines += 1
            assert all(a <= b for a, b in zip(d, true))
            for k in range(3):
                under[k] += d[k] < true[k]
        for k in range(1, 3):
            assert under[k] / lines <= 2 * true[k] * (true[k] + 1) / p
    res = degree_sequence(EULER, steps=3, eps="1/10")
    assert 0 < res.undercount_bound < 1e-20


CYCLIC_8 = ExpressionSystem.from_expressions(
    [f"x{i}" for i in range(8)],
    field=[f"x{(i + 1) % 8}*x{(i + 2) % 8} - x{i} + {i + 1}*x{(i + 3) % 8}**2" for i in range(8)], name="cyclic-8")


@pytest.mark.parametrize("system, kind, steps", [
    (EULER, "f", 8), (LV, "f", 9), (LiePoissonSystem.random(2, 3), "f", 12), (LiePoissonSystem.random(4, 1), "f", 10),
    (LiePoissonSystem.random(4, 1), "g", 6), (LiePoissonSystem.random(4, 2), "control", 6),
    (LiePoissonSystem.random(5, 1), "f", 5), (CYCLIC_8, "f", 3)],
    ids=["euler", "lv", "lp2-f", "lp4-f", "lp4-g", "lp4-control", "lp5-f", "cyclic8"])
def test_values_route_equals_polynomial_route(system, kind, steps):
    """The degrees read off values at points of the line (Cauchy interpolation) equal those of
    polynomial arithmetic over F_p[t] (checked against SymPy by the golden test), on other
    random lines, at every dimension (the rule picks the route only from dimension 8)."""
    _, fld = resolve_field(system, kind)
    poly = polynomial_line_degrees(fld, F(1, 10), GOOD, steps, random.Random(1))
    vals = valued_line_degrees(fld, F(1, 10), GOOD, steps, random.Random(2))
    assert vals == poly and len(vals) == steps + 1 and vals[-1] > vals[1]


def test_values_route_stops_before_a_degree_past_max_degree():
    """From values a degree above max_degree is never fitted (no fit at D = max_degree): the
    route stops before it, where polynomial arithmetic reports it and stops after it."""
    _, fld = resolve_field(CYCLIC_8, "f")
    assert valued_line_degrees(fld, F(1, 10), GOOD, 6, random.Random(1), max_degree=100) == [1, 8, 64]
    assert polynomial_line_degrees(fld, F(1, 10), GOOD, 6, random.Random(1), max_degree=100) == [1, 8, 64, 512]
    res = degree_sequence(CYCLIC_8, steps=6, eps="1/10", max_degree=100)
    assert res.degrees == (1, 8, 64) and any("stopped after k = 2" in n for n in res.notes)


def test_geometric_growth_hands_over_to_polynomial_arithmetic():
    """From values, degrees that grow geometrically (cyclic-8: 8^k) hand over to polynomial
    arithmetic, which reaches past max_degree; linear growth stays with values."""
    res = degree_sequence(CYCLIC_8, steps=5, eps="1/10", max_degree=1000)
    assert res.degrees == (1, 8, 64, 512, 4096) and res.routes == ("polynomials", "polynomials")
    assert [r["route"] for r in res.to_json()["runs"]] == ["polynomials", "polynomials"]
    lp = degree_sequence(LiePoissonSystem.random(4, 1), steps=8)
    assert lp.degrees == (1,) + tuple(8 * k for k in range(1, 9))
    assert lp.routes == ("values", "values") and "runs from values" in lp.summary()
    _, fld = resolve_field(CYCLIC_8, "f")
    assert valued_line_degrees(fld, F(1, 10), GOOD, 5, random.Random(1), 1000, hand_over=True) is None


def test_no_hand_over_from_the_dimension_of_the_rule(monkeypatch):
    """From DEGREES_HAND_OVER_BELOW_DIM on, geometric growth stays with values (faster there):
    the rule lowered to 8 keeps cyclic-8 on values, which stop before the degree past max_degree."""
    from exact_khk.systems.lie_poisson import paths

    _, fld = resolve_field(CYCLIC_8, "f")
    assert line_run(fld, F(1, 10), GOOD, 5, random.Random(1), 1000)[1] == "polynomials"
    monkeypatch.setattr(paths, "DEGREES_HAND_OVER_BELOW_DIM", 8)
    assert line_run(fld, F(1, 10), GOOD, 5, random.Random(1), 1000) == ([1, 8, 64, 512], "values")


def test_cauchy_degree_exact_at_enough_points_never_above_the_bound():
    """A fraction of degree d through 2D + 1 points: found exactly (reduced, B monic) when D ≥ d;
    when D < d either refused or of degree ≤ D (an undercount, never an overcount)."""
    rng, p = random.Random(5), GOOD
    for _ in range(40):
        da, db = rng.randrange(0, 12), rng.randrange(0, 12)
        A = flint.nmod_poly([rng.randrange(p) for _ in range(da)] + [1 + rng.randrange(p - 1)], p)
        B = flint.nmod_poly([rng.randrange(p) for _ in range(db)] + [1], p)
        d = max(A.degree(), B.degree())
        for D in (max(d - 3, 0), max(d - 1, 0), d, d + 4):
            xs = rng.sample(range(p), 2 * D + 1)
            xs = [x for x in xs if B(x) != 0]
            if len(xs) < 2 * D + 1:
                continue
            fit = cauchy_degree(xs, [A(x) / B(x) for x in xs], p, D)
            if D >= d:
                assert fit == (d, A * B.leading_coefficient() ** -1, B)  # random A, B: coprime here
            else:
                assert fit is None or fit[0] <= D


def test_interpolate_matches_the_values():
    rng, p = random.Random(3), 1009
    xs = rng.sample(range(p), 37)
    vs = [rng.randrange(p) for _ in xs]
    f, m = interpolate(xs, vs, p)
    assert f.degree() < 37 and all(f(x) == v for x, v in zip(xs, vs))
    assert m.degree() == 37 and all(m(x) == 0 for x in xs)


def test_degenerate_lines_raise_on_both_routes():
    """A field whose step matrix is singular everywhere (x0' = 10 x0 at eps = 1/10: the first
    row of I - eps f'(x) vanishes): every line degenerates on either route."""
    names = [f"x{i}" for i in range(8)]
    field = ["10*x0"] + [f"x{(i + 1) % 8}*x{(i + 2) % 8}" for i in range(1, 8)]
    sysobj = ExpressionSystem.from_expressions(names, field=field, name="singular-8")
    _, fld = resolve_field(sysobj, "f")
    for route in (valued_line_degrees, polynomial_line_degrees):
        with pytest.raises(_Degenerate):
            route(fld, F(1, 10), GOOD, 3, random.Random(1))
    with pytest.raises(InputError, match="degenerated"):
        degree_sequence(sysobj, steps=3, eps="1/10", primes=1)


@pytest.mark.parametrize("kw, name", [
    (dict(primes=[4]), "primes"), (dict(primes=[101, 15]), "primes"), (dict(steps=0), "steps"),
    (dict(steps=10 ** 9), "steps"), (dict(lines=0), "lines"), (dict(primes="x"), "primes")])
def test_degree_input_errors(kw, name):
    with pytest.raises(InputError, match=name):
        degree_sequence(EULER, **kw)


# --- recurrence -----------------------------------------------------------------------


def test_recurrence_refuses_short_sequences():
    with pytest.raises(InputError, match="sequence"):
        fit_recurrence([1, 3, 9, 19])
    short = fit_recurrence([1, 3, 9, 19, 33])  # order 3 needs 6 terms, then 3 to confirm
    assert short.growth == "undetermined" and "too short" in short.reason
    assert fit_recurrence([1, 3, 9, 19, 33, 51, 73, 99, 129]).growth == "polynomial"


def test_summary_states_no_recurrence_the_terms_do_not_determine():
    """Five terms whose shortest recurrence has order 3 (6 terms determine it) printed a
    made-up fit "(19/9)*d[k-1] - ..., fitted on 6 terms"; four terms printed "d[k] = 0"."""
    from exact_khk.diagnostics.recurrence import too_short

    five = fit_recurrence([1, 4, 7, 9, 11])
    assert five.order == 3 and not five.determined and five.growth == "undetermined"
    assert "d[k] =" not in five.summary() and "recurrence: not determined" in five.summary()
    assert "order 3, which only 6 terms determine" in five.reason
    four = too_short([1, 6, 12, 18], "4 terms are too short")
    assert not four.determined and "d[k] =" not in four.summary()
    six = fit_recurrence([1, 6, 12, 18, 24, 30])   # determined by its 6 terms, not yet confirmed
    assert six.determined and "fitted on 6 terms, confirmed on 0 more" in six.summary()
    assert fit_recurrence([0, 0, 0, 0, 0]).determined                    # d[k] = 0 is determined


def test_recurrence_refuses_non_integer_fit():
    fit = fit_recurrence([1, 2, 3, 5, 7, 11, 13, 17, 19, 23])  # primes: no recurrence
    assert fit.growth == "undetermined"


def test_dynamical_degree_certified_enclosure():
    fib = fit_recurrence([1, 2, 3, 5, 8, 13, 21, 34, 55, 89, 144])
    lo, hi = (F(t) for t in fib.dynamical_degree.enclosure)
    phi = (1 + 5 ** 0.5) / 2
    assert lo <= F(phi) <= hi and hi - lo <= F(1, 10 ** 10)
    assert fib.dynamical_degree.minimal_polynomial == "x^2 - x - 1"
    quasi = fit_recurrence([1, 2, 1, 2, 1, 2, 1, 2, 1, 2])
    assert quasi.growth == "bounded"


# --- integrals ------------------------------------------------------------------------


def grad_ratio(num, den, x):
    """The gradient of num/den at x, by SymPy (independent of Integral.gradient)."""
    xs = sympy.symbols(f"x0:{len(x)}")

    def poly(p):
        return sum(sympy.Rational(c.numerator, c.denominator) * sympy.prod([v ** int(k) for v, k in zip(xs, e)])
                   for e, c in p.items())

    r = poly(num) / poly(den)
    at = {v: sympy.Rational(t.numerator, t.denominator) for v, t in zip(xs, x)}
    return [F(str(sympy.diff(r, v).subs(at))) for v in xs]


def rank(rows):
    return flint.fmpq_mat(len(rows), len(rows[0]), [flint.fmpq(v.numerator, v.denominator)
                                                    for r in rows for v in r]).rank()


def test_euler_top_integrals_recovered():
    res = find_integrals(EULER, degree=3, eps="1/10")
    assert res.kernel_dim == 8 and res.trivial_dim == 8 and res.new_dim == 0
    assert [t[1:] for t in res.by_degree] == [(0, 0), (2, 2), (8, 0)]
    assert len(res.integrals) == 2 and all(f.verified for f in res.integrals) and res.independent == 2
    # x^2 - z^2 and y^2 + 2 z^2 (Casimir-like quadratics of the flow) combine to the found ones
    x = [F(2, 3), F(-1, 5), F(7, 4)]
    found = [grad_ratio(*f.polynomials(), x) for f in res.integrals]
    known = grad_ratio({(2, 0, 0): F(1), (0, 0, 2): F(-1)}, {(0, 2, 0): F(1), (0, 0, 2): F(2)}, x)
    assert rank(found + [known]) == 2
    assert [f.gradient(x) for f in res.integrals] == found     # the library's exact gradient agrees


@pytest.mark.parametrize("n", [2, 3])
def test_lie_poisson_rediscovers_htilde_and_ktilde(n):
    """From orbits alone: n independent verified integrals; H~ and K~ are functions
    of them (Jacobian rank); for the non-associated control field they are not."""
    s = LiePoissonSystem.random(n, 1)
    ar = get_arith("fraction")
    rng = random.Random(3)
    x = [F(rng.randint(-5, 5), rng.randint(1, 3)) for _ in range(2 * n)]
    H = grad_Htilde(s.field("f"), [ar(t) for t in x], "1/10", ar)
    K = grad_Htilde(s.field("g"), [ar(t) for t in x], "1/10", ar)
    for kind, dependent in (("f", True), ("g", True), ("control", False)):
        res = find_integrals(s, degree=2, field=kind)
        assert res.kernel_dim == n and len(res.integrals) == n and res.independent == n
        assert all(f.verified for f in res.integrals)
        G = [grad_ratio(*f.polynomials(), x) for f in res.integrals]
        assert (rank(G + [H]) == n) is dependent and (rank(G + [K]) == n) is dependent


def test_control_finds_nothing():
    for D in (2, 4):
        res = find_integrals(LV, degree=D, eps="1/10")
        assert res.kernel_dim == 0 and res.integrals == () and all(t[1] == 0 for t in res.by_degree)


def test_modular_and_exact_kernels_agree():
    exps = monomials(3, 2)
    _, fld = resolve_field(EULER, "f")
    job = _Job(fld, F(1, 10), exps, 25, 8, ["x", "y", "z"], [], [])
    x0 = (F(1, 2), F(-3), F(2, 7))
    lifted, _ = job.lifted_kernels([x0], 2, [GOOD], 0, 8)
    assert lifted[0] == orbit_kernel_exact(fld, F(1, 10), x0, exps, 25)


def test_verification_rejects_non_integrals():
    _, fld = resolve_field(EULER, "f")
    x0 = (F(1), F(2), F(3))
    assert verify_exact({(2, 0, 0): F(1), (0, 0, 2): F(-1)}, {(0, 2, 0): F(1), (0, 0, 2): F(2)}, fld, F(1, 10), x0, 5)
    assert not verify_exact({(1, 0, 0): F(1)}, {(0, 1, 0): F(1)}, fld, F(1, 10), x0, 5)


def test_short_orbit_and_special_orbit_are_flagged():
    res = find_integrals(EULER, degree=2, eps="1/10", steps=5)
    assert any("too short" in w for w in res.warnings)
    fixed = find_integrals(EULER, degree=2, eps="1/10", x0=["0", "0", "0"])  # a fixed point
    assert any("periodic" in w for w in fixed.warnings)
    assert fixed.kernel_dim == 2


@pytest.mark.parametrize("kw, name", [
    (dict(degree=60), "degree"), (dict(), "degree"), (dict(monomials_list=["x*w"]), "monomials"),
    (dict(degree=2, x0=["1", "2"]), "x0"), (dict(degree=2, primes=[9]), "primes"), (dict(degree=2, orbits=1), "orbits")])
def test_integral_input_errors(kw, name):
    with pytest.raises(InputError, match=name):
        find_integrals(EULER, eps="1/10", **kw)


def test_user_monomial_list():
    res = find_integrals(EULER, monomials_list=["1", "x^2", "y^2", "z^2"], eps="1/10")
    assert res.kernel_dim == 2 and len(res.integrals) == 2 and all(f.verified for f in res.integrals)


# --- heights --------------------------------------------------------------------------


def test_height_growth_classes():
    assert height_growth(LV.field("f"), ["1/2", "1/3"], "1/10", steps=14).growth == "exponential"
    assert height_growth(EULER.field("f"), ["1", "2", "3"], "1/10", steps=24).growth == "quadratic"
    s = LiePoissonSystem.random(3, 1)
    assert height_growth(s.field("f"), ["1", "2", "-1", "1/2", "0", "1"], "1/10", steps=30).growth == "linear"


def test_height_growth_says_why_it_cannot_fit():
    """A start point so high that max_bits is passed within 3 steps: the message gives the
    start's height and the ways out (it blamed max_bits alone)."""
    s = LiePoissonSystem.random(3, 1)
    with pytest.raises(InputError, match=r"max_bits: the orbit passed 1000 bits after \d steps \(x0 has 300 "
                                         r"bits\).*start from a lower point, or leave the heights out"):
        height_growth(s.field("f"), [str(2 ** 299 + 1), "2", "-1", "1/2", "0", "1"], "1/10", max_bits=1000)


# --- command line ---------------------------------------------------------------------


def test_cli_degrees_and_find_integrals(capsys, tmp_path):
    assert main(["degrees", "--system", "euler-top", "--steps", "8", "--exact", "2"]) == 0
    out = capsys.readouterr().out
    assert "1, 3, 9, 19, 33" in out and "polynomial of degree 2" in out
    assert main(["degrees", "--system", "lotka-volterra", "--steps", "8", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["fit"]["growth"] == "exponential" and d["degrees"][:4] == [1, 2, 4, 8]
    assert main(["find-integrals", "--system", "euler-top", "--degree", "2", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["kernel_dim"] == 2 and len(d["integrals"]) == 2
    assert main(["find-integrals", "--n", "2", "--seed", "1", "--field", "control"]) == 0
    assert "2 functionally independent" in capsys.readouterr().out


@pytest.mark.parametrize("argv, what", [
    (["degrees", "--primes", "4,6"], "--primes"), (["degrees", "--steps", "0"], "--steps"),
    (["find-integrals", "--degree", "99"], "--degree"), (["find-integrals", "--monomials", "q*r"], "--monomials"),
    (["degrees", "--signs", "-++"], "--signs")])
def test_cli_input_errors(argv, what, capsys):
    assert main(argv) == 2
    assert what in capsys.readouterr().err


def test_cli_plot(tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "g.png"
    assert main(["degrees", "--system", "euler-top", "--steps", "10", "--plot", str(out)]) == 0
    assert out.stat().st_size > 1000


@pytest.mark.slow
def test_fifty_iterates_of_a_six_dimensional_map():
    s = LiePoissonSystem.random(3, 1)
    res = degree_sequence(s, steps=50, primes=1)
    assert res.degrees[-1] == 300 and res.fit.polynomial == "6*k for k >= 1"


@pytest.mark.slow
def test_diagnostics_table_quick(tmp_path):
    out = tmp_path / "d.md"
    subprocess.run([sys.executable, "scripts/diagnostics_table.py", "--quick", "--out", str(out)], check=True)
    text = out.read_text()
    assert "| lie-poisson" in text and "euler-top" in text


def test_cli_orbit_reports_the_height_growth(capsys):
    """`orbit` fits the heights of an exact orbit: the non-integrable Kahan Lotka–Volterra
    map (heights double per step) is exponential, the Lie–Poisson orbit is not."""
    assert main(["orbit", "--system", "lotka-volterra", "--steps", "12", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["height_growth"]["growth"] == "exponential"
    assert main(["orbit", "--steps", "12"]) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.startswith("heights (bits)") and "growth linear" in last
    assert main(["orbit", "--steps", "12", "--arith", "float", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["height_growth"] is None   # floats have no height


def test_degree_sequence_reports_progress_in_steps():
    """``progress(k)`` counts the steps over F_p: steps per line, every line; a line that
    passes max_degree early counts as finished (the count ends on the total)."""
    seen = []
    res = degree_sequence("euler-top", steps=6, primes=2, lines=2, progress=seen.append)
    assert seen == list(range(1, 2 * 2 * 6 + 1)) and len(res.degrees) == 7
    seen.clear()
    res = degree_sequence(LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1"), steps=30, primes=1,
                          max_degree=40, progress=seen.append)
    assert len(res.degrees) < 31 and seen[-1] == 30 and seen == sorted(set(seen))


def test_conjugate_pencils_beyond_the_size_limit_are_named_not_expanded(monkeypatch):
    """The symmetric functions of e conjugate pencils have up to C(N + e·D, N) terms (n = 10:
    3.1 million, and the expansion grew past 17 GB): beyond MAX_SYMMETRIC_TERMS they are
    skipped with a note.  n = 3, seed 1 has one conjugate pair (e = 2, bound C(6 + 4, 6) = 210):
    with the limit at 209 its two symmetric functions are skipped, with the default they are found."""
    from exact_khk.diagnostics import pencils

    s = LiePoissonSystem.random(3, 1)
    full = find_integrals(s, degree=2, fit_degree=0)  # the pencils alone (no fit of the kernel's entries)
    assert len(full.integrals) == 3 and not any("MAX_SYMMETRIC_TERMS" in t for t in full.notes)
    monkeypatch.setattr(pencils, "MAX_SYMMETRIC_TERMS", 209)
    cut = find_integrals(s, degree=2, fit_degree=0)
    assert len(cut.integrals) == 1 and all(f.verified for f in cut.integrals)
    assert any("up to 210 terms, beyond the limit of 209 (MAX_SYMMETRIC_TERMS)" in t for t in cut.notes)


def test_find_integrals_reports_its_stages():
    """find-integrals shows its stages (the orbit kernels mod p, the trivial vectors, the
    extraction) on the progress display; a degree 6 search at n = 3 spent minutes silent."""
    stages = []
    res = find_integrals(LiePoissonSystem.random(3, 1), degree=2, progress=stages.append)
    assert res.integrals
    assert stages[0] == "orbit kernel 1 mod p (28 candidates)" and "trivial kernel vectors" in stages
    assert "lift to Q, extract and check the integrals" in stages
    assert stages[-1] == "independent integrals: the kernel's entries, fitted"


def test_restricted_kernel_is_the_nullspace_combination():
    """K ∩ span(columns keep) over F_p (one nmod_mat product) equals the combinations
    Σ_r X[r, k]·basis[r] written out, X the nullspace of the basis on the other columns."""
    import flint

    from exact_khk.diagnostics.kernels import _restricted

    rng, p = random.Random(5), 1009
    for d, m in ((3, 5), (4, 9), (7, 12)):
        basis = [[rng.randrange(p) for _ in range(m)] for _ in range(d)]
        keep = set(rng.sample(range(m), m - d + 2))  # d − 2 conditions: a nonzero intersection
        outside = [c for c in range(m) if c not in keep]
        X, nul = flint.nmod_mat(len(outside), d, [basis[r][c] for c in outside for r in range(d)], p).nullspace()
        naive = [[sum(int(X[r, k]) * basis[r][c] for r in range(d)) % p for c in range(m)] for k in range(nul)]
        got = _restricted(basis, keep, p)
        assert got == naive and len(got) == nul >= 2
        assert all(v[c] == 0 for v in got for c in outside)
