"""Real parameters of the Lie–Poisson family in ``enclose`` (exact_khk.systems.lie_poisson.real).

An enclosure computed with ball blocks a, b, c must contain the exact orbit of every
rational parameter value in the boxes (decided exactly, ``contains_exact``); an
irrational block is checked against an mpmath orbit at three times the precision,
computed here from the Kahan formula (I − εf'(x)) x' = x with f(x) = J(x) Hs x written
out independently of the library.
"""

from __future__ import annotations

import pathlib
from fractions import Fraction

import flint
import mpmath
import pytest
import sympy

from exact_khk.arith import get_arith
from exact_khk.arith.ball import arb_to_fmpq, contains_exact
from exact_khk.cli.main import main
from exact_khk.errors import InputError
from exact_khk.studies import enclosure
from exact_khk.studies.scaling import declared, exact_prefix
from exact_khk.systems.lie_poisson import DEFAULT_X0, LiePoissonSystem
from exact_khk.systems.expressions import ExpressionSystem, load_system, tomllib
from exact_khk.systems.lie_poisson.real import RealLiePoissonSystem
from exact_khk.systems.real_expressions import RealExpressionSystem

X0 = ",".join(DEFAULT_X0)
B, C = "0,1,0", "3,1,1"


def _exact_orbit(a, b, c, steps, eps="1/10"):
    fld = LiePoissonSystem.from_vectors(a, b, c).field("f")
    orbit, _, err = exact_prefix(fld, list(DEFAULT_X0), eps, steps)
    assert err is None and len(orbit) == steps + 1
    return orbit


def _contains(points, orbit):
    return all(contains_exact(t, q) for X, x in zip(points, orbit) for t, q in zip(X, x))


@pytest.mark.parametrize("a", ["[1,1],0,[2,2]", "sqrt(1),0,4/2", "1+-0,0,[2,2]"])
def test_point_reals_equal_to_rationals_reproduce_the_rational_run(a):
    real = RealLiePoissonSystem.from_reals(a, B, C, 128)
    rational = LiePoissonSystem.from_vectors("1,0,2", B, C)
    orbit = _exact_orbit("1,0,2", B, C, 15)
    for method in enclosure.METHODS:
        r = enclosure.enclose(real, X0, "1/10", 15, 128, method, keep_points=True)
        q = enclosure.enclose(rational, X0, "1/10", 15, 128, method, orbit, keep_points=True)
        assert r.status == q.status and r.steps_done == q.steps_done > 0
        assert all(x.mid() == y.mid() and x.rad() == y.rad() for P, Q in zip(r.points, q.points)
                   for x, y in zip(P, Q)), method  # the same balls, step by step
        assert _contains(r.points, orbit) and q.encloses


def test_width_zero_non_dyadic_interval_encloses_the_rational_orbit():
    real = RealLiePoissonSystem.from_reals("[1/3,1/3],0,2", B, "3,[1/7,1/7],1", 128)
    orbit = _exact_orbit("1/3,0,2", B, "3,1/7,1", 10)
    for method in enclosure.METHODS:
        run = enclosure.enclose(real, X0, "1/10", 10, 128, method, orbit, keep_points=True)
        assert run.status == "ok" and run.encloses and _contains(run.points, orbit)


def test_interval_box_contains_the_orbits_of_sampled_rational_parameters():
    lo, hi = Fraction(2) - Fraction(1, 10 ** 9), Fraction(2) + Fraction(1, 10 ** 9)
    blo, bhi = Fraction(1) - Fraction(1, 10 ** 10), Fraction(1) + Fraction(3, 10 ** 10)
    real = RealLiePoissonSystem.from_reals(f"1,0,[{lo},{hi}]", f"0,[{blo},{bhi}],0", C, 128)
    steps = 12
    runs = [enclosure.enclose(real, X0, "1/10", steps, 128, m, keep_points=True) for m in enclosure.METHODS]
    assert runs[1].status == "ok" and runs[1].min_correct_bits > 10
    samples = [(lo, blo), (hi, bhi), (lo, bhi), (hi, blo), (Fraction(2), Fraction(1)),
               (lo + Fraction(1, 3 * 10 ** 9), blo + Fraction(2, 7 * 10 ** 10))]
    for a2, b1 in samples:
        orbit = _exact_orbit(f"1,0,{a2}", f"0,{b1},0", C, steps)
        for run in runs:
            assert _contains(run.points, orbit), (run.method, a2, b1)
    # a parameter outside the box: its orbit leaves the Lohner enclosure
    orbit = _exact_orbit(f"1,0,{hi + Fraction(1, 10 ** 6)}", "0,1,0", C, steps)
    assert not _contains(runs[1].points, orbit)


def test_integrals_are_evaluated_with_the_ball_parameters():
    lo, hi = Fraction(199, 100), Fraction(201, 100)
    real = RealLiePoissonSystem.from_reals(f"1,0,[{lo},{hi}]", B, C, 128)
    ints, _ = declared(real)
    ar = get_arith("ball:128")
    x0 = [ar.convert(Fraction(t)) for t in DEFAULT_X0]
    for a2 in (lo, hi, Fraction(2)):
        rational = LiePoissonSystem.from_vectors(f"1,0,{a2}", B, C)
        exact, _ = declared(rational)
        for name, I in ints.items():
            v = I(ar, x0, flint.arb(flint.fmpq(1, 10)))
            assert contains_exact(v, exact[name](get_arith("fraction"), [Fraction(t) for t in DEFAULT_X0],
                                                 Fraction(1, 10))), (name, a2)
    # the drift of a real run contains 0; with the integrals of another system (a_0 = 1), it does not
    irr = RealLiePoissonSystem.from_reals("sqrt(2),0,2", B, C, 128)
    run = enclosure.enclose(irr, X0, "1/10", 10, 128, "lohner", integrals=declared(irr)[0])
    assert run.drift_contains_zero is True and run.rows[-1].drift["H~"][0] < -20
    run = enclosure.enclose(irr, X0, "1/10", 10, 128, "lohner", integrals=ints)
    assert run.drift_contains_zero is False


# --- an irrational block against an independent high-precision orbit ---------------


def _reference_orbit(a, b, c, x0, eps, steps, dps_bits):
    """x_{k+1} solves (I − ε f'(x_k)) x_{k+1} = x_k, f(x) = J(x) Hs x, in mpmath."""
    n = len(a)
    with mpmath.workprec(dps_bits):
        hank = lambda w: [[w[(i + j) % n] for j in range(n)] for i in range(n)]  # noqa: E731
        Xa, Xb, Xc = hank(a), hank(b), hank(c)
        Hs = mpmath.matrix([ra + rb for ra, rb in zip(Xa, Xb)] + [rb + rc for rb, rc in zip(Xb, Xc)])

        def J(x):
            Xu = hank([x[i] for i in range(n)])
            M = mpmath.matrix(2 * n, 2 * n)
            for i in range(n):
                for j in range(n):
                    M[i, n + j], M[n + i, j] = Xu[i][j], -Xu[i][j]
            return M

        def jac(x):  # f'(x) v = J(x) Hs v + J(v) Hs x
            D = mpmath.matrix(2 * n, 2 * n)
            JH, Hx = J(x) * Hs, Hs * x
            for j in range(2 * n):
                e = mpmath.matrix(2 * n, 1)
                e[j] = 1
                col = JH * e + J(e) * Hx
                for i in range(2 * n):
                    D[i, j] = col[i]
            return D

        x = mpmath.matrix([mpmath.mpf(t.numerator) / t.denominator for t in x0])
        out = [x]
        for _ in range(steps):
            x = mpmath.lu_solve(mpmath.eye(2 * n) - eps * jac(x), x)
            out.append(x)
        return out


def _mp_in_ball(ball, v, slack):
    man, exp = v.man_exp  # exactly (mpmath.mpf(v) would round v to the global 53 bits); man is unsigned
    man = -int(man) if v < 0 else int(man)
    q = flint.fmpq(int(man) << exp) if exp >= 0 else flint.fmpq(int(man), 1 << -exp)
    return abs(q - arb_to_fmpq(ball.mid())) <= arb_to_fmpq(ball.rad()) + slack


def test_irrational_block_against_an_independent_mpmath_orbit():
    prec, steps = 128, 20
    with mpmath.workprec(3 * prec):
        a = [mpmath.sqrt(2), mpmath.mpf(0), mpmath.mpf(2)]
        ref = _reference_orbit(a, [0, 1, 0], [3, 1, 1], [Fraction(t) for t in DEFAULT_X0], mpmath.mpf(1) / 10,
                               steps, 3 * prec)
    slack = flint.fmpq(1, 2 ** 300)  # the reference's own error, far below every radius
    good = RealLiePoissonSystem.from_reals("sqrt(2),0,2", B, C, prec)
    for method in enclosure.METHODS:
        run = enclosure.enclose(good, X0, "1/10", steps, prec, method, keep_points=True)
        assert run.status == "ok" and run.steps_done == steps
        for X, r in zip(run.points, ref):
            assert all(_mp_in_ball(t, r[i], slack) for i, t in enumerate(X)), method
    # negative control: sqrt(2) + 2^-100 instead of sqrt(2) misses the reference
    wrong = RealLiePoissonSystem.from_reals("sqrt(2)+2^(-100),0,2", B, C, prec)
    run = enclosure.enclose(wrong, X0, "1/10", steps, prec, "lohner", keep_points=True)
    assert run.status == "ok"
    assert all(_mp_in_ball(t, ref[0][i], slack) for i, t in enumerate(run.points[0]))
    assert not all(_mp_in_ball(t, ref[-1][i], slack) for i, t in enumerate(run.points[-1]))


# --- the command line and the API's errors --------------------------------------------


def _cli(capsys, *argv):
    code = main(["enclose", *argv, "--quiet"])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_real_blocks(capsys):
    code, out, err = _cli(capsys, "--a", "sqrt(2),0,[1.99999,2.00001]", "--b", B, "--c", C, "--x0", X0,
                          "--steps", "5")
    assert code == 0, err
    assert "real blocks" in out and "lohner   ok" in out
    code, out, err = _cli(capsys, "--a", "1,0,2", "--b", B, "--c", C, "--x0", X0, "--steps", "3",
                          "--check-exact")
    assert code == 0 and "lohner   ok" in out  # rational blocks: unchanged, checked exactly
    assert out.splitlines()[0].startswith("Lie–Poisson system n=3: a=(1, 0, 2)")


@pytest.mark.parametrize("argv", [
    ["--a", "sqrt(2),0,2", "--b", B, "--c", C, "--x0", X0, "--check-exact"],
    ["--a", "sqrt(2,0,2", "--b", B, "--c", C, "--x0", X0],
    ["--a", "sqrt(2),0,2", "--b", "0,1", "--c", C, "--x0", X0],
    ["--a", "1,0,[2.1,1.9]", "--b", B, "--c", C, "--x0", X0],
    ["--a", "1,0,sqrt(" + "1" * 3000 + ")", "--b", B, "--c", C, "--x0", X0],
    ["--a", "1,0,nan", "--b", B, "--c", C, "--x0", X0],
    ["--a", "inf,0,2", "--b", B, "--c", C, "--x0", X0],
    ["--a", "1,0,log(0)", "--b", B, "--c", C, "--x0", X0],
    ["--a", "1,0,1e999999999", "--b", B, "--c", C, "--x0", X0],
    ["--a", "sqrt(2),0,2", "--b", B, "--c", C],
    ["--a", "sqrt(2),0,2", "--b", B, "--x0", X0],
    ["--a", "sqrt(2)", "--b", "0", "--c", "1", "--x0", "1,2"],
    ["--system", "euler-top", "--a", "sqrt(2),0,2"],
])
def test_cli_bad_real_blocks_are_one_line_exit_2(capsys, argv):
    code, out, err = _cli(capsys, *argv, "--steps", "2")
    assert code == 2, (out, err)
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err


def test_other_commands_keep_rational_blocks(capsys):
    assert main(["orbit", "--a", "sqrt(2),0,2", "--b", B, "--c", C, "--x0", X0, "--steps", "1"]) == 2
    assert "--a" in capsys.readouterr().err


@pytest.mark.parametrize("args", [("1,0,[3,2]", B, C), ("1,0", B, C), ("1,0,2", "0,1", C), ("nan,0,2", B, C),
                                  ("1", "0", "1"), ("1,0,x", B, C)])
def test_api_errors_are_input_errors(args):
    with pytest.raises(InputError):
        RealLiePoissonSystem.from_reals(*args, prec=64)


def test_api_refuses_non_balls_and_non_rational_involutions():
    with pytest.raises(InputError):
        RealLiePoissonSystem((Fraction(1), Fraction(0)), (flint.arb(0),) * 2, (flint.arb(1),) * 2)
    s = RealLiePoissonSystem.from_reals("sqrt(2),0,1,0", "0,1,0,0", "1,1,1,2", 64)
    with pytest.raises(InputError):
        s.field("g", "+-++", cyclotomic=True)
    assert s.field("g").signs == "-+++" and s.field("control").label == "control"


# --- parameters as Lohner coordinates (ParameterFields) ------------------------------


def _coefficients(fld):
    return {(i, key): c for i, terms in enumerate(fld.terms()) for key, c in terms}


@pytest.mark.parametrize("kind,signs,power", [("f", None, 0), ("f", None, 1), ("g", None, 0), ("control", None, 0)])
def test_parameter_fields_are_the_rational_fields_at_every_parameter(kind, signs, power):
    """f(·; p) = mid + Σ_j (p_j − m_j) f_j, exactly, against the rational system built at p."""
    real = RealLiePoissonSystem.from_reals("sqrt(2),0,[1.9,2.1]", "0,1+-1/8,0", "3,1,1", 64)
    lin = real.parameter_fields(kind, signs, power)
    assert lin.names == ("a_0", "a_2", "b_1")
    mids = [arb_to_fmpq(t.mid()) for t in (real.a[0], real.a[2], real.b[1])]
    ball = _coefficients(real.field(kind, signs, power))
    for p in [mids, [Fraction(7, 5), Fraction(19, 10), Fraction(9, 8)], [Fraction(3, 2), Fraction(21, 10), 1]]:
        a, b = [str(p[0]), "0", str(p[1])], ["0", str(p[2]), "0"]
        exact = _coefficients(LiePoissonSystem.from_vectors(",".join(a), ",".join(b), C).field(kind, signs, power))
        units = [_coefficients(u) for u in lin.units]
        mid = _coefficients(lin.mid)
        keys = set(exact) | set(mid) | {k for u in units for k in u}
        for key in keys:
            v = Fraction(mid.get(key, 0)) + sum((Fraction(str(q)) - Fraction(str(m))) * Fraction(u.get(key, 0))
                                               for q, m, u in zip(p, mids, units))
            assert v == exact.get(key, 0), key
    for key, c in _coefficients(lin.mid).items():  # the ball field contains the midpoint field
        assert contains_exact(ball[key], c), key
    assert RealLiePoissonSystem.from_reals("1,0,[2,2]", B, C, 64).parameter_fields() is None


def _boxed(a2, b1, eps=(Fraction(1, 10), Fraction(1, 10))):
    """The real system with a_2 ∈ [a2], b_1 ∈ [b1] (pairs lo, hi), and the ε text."""
    real = RealLiePoissonSystem.from_reals(f"1,0,[{a2[0]},{a2[1]}]", f"0,[{b1[0]},{b1[1]}],0", C, 128)
    return real, f"[{eps[0]},{eps[1]}]"


def test_parameter_box_contains_exact_orbits_over_many_steps():
    """A box of width 2·10^-6 in a_2 (and 4·10^-7 in b_1, 2·10^-9 in ε): the Lohner enclosure
    stays decided over 40 steps (before parameters were coordinates: undecided at step 12) and
    contains the exact orbits of the corners, the centre and interior points."""
    a2 = (Fraction(2) - Fraction(1, 10 ** 6), Fraction(2) + Fraction(1, 10 ** 6))
    b1 = (Fraction(1) - Fraction(1, 10 ** 7), Fraction(1) + Fraction(3, 10 ** 7))
    eps = (Fraction(1, 10) - Fraction(1, 10 ** 9), Fraction(1, 10) + Fraction(1, 10 ** 9))
    real, e = _boxed(a2, b1, eps)
    steps = 40
    run = enclosure.enclose(real, X0, e, steps, 128, "lohner", keep_points=True)
    assert run.status == "ok" and run.min_correct_bits > 15
    samples = [(x, y, z) for x in a2 for y in b1 for z in eps]
    samples += [(Fraction(2), Fraction(1), Fraction(1, 10)),
                (a2[0] + Fraction(1, 3 * 10 ** 6), b1[1] - Fraction(2, 7 * 10 ** 7), eps[0] + Fraction(1, 10 ** 10))]
    for x, y, z in samples:
        orbit = _exact_orbit(f"1,0,{x}", f"0,{y},0", C, steps, z)
        assert _contains(run.points, orbit), (x, y, z)
    # negative control: a_2 outside the box by 10^-7 (a twentieth of its width)
    orbit = _exact_orbit(f"1,0,{a2[1] + Fraction(1, 10 ** 7)}", "0,1,0", C, steps)
    assert not _contains(run.points, orbit)


def test_parameters_as_coordinates_keep_the_true_spread():
    """Box of width 2·10^-12 in a_2: the enclosure after 100 steps is within 1 bit of the
    spread of the exact orbits of the box's two ends (a lower bound of every enclosure)."""
    lo, hi = Fraction(2) - Fraction(1, 10 ** 12), Fraction(2) + Fraction(1, 10 ** 12)
    real, _ = _boxed((lo, hi), (1, 1))
    steps = 100
    run = enclosure.enclose(real, X0, "1/10", steps, 128, "lohner", keep_points=True)
    assert run.status == "ok"
    ends = [_exact_orbit(f"1,0,{t}", B, C, steps)[-1] for t in (lo, hi)]
    assert _contains(run.points[-1:], [ends[0]]) and _contains(run.points[-1:], [ends[1]])
    spread = max(abs(p - q) for p, q in zip(*ends)) / 2  # fmpq, exact
    rad = max(arb_to_fmpq(t.rad()) for t in run.points[-1])
    assert spread <= rad <= 2 * spread  # within one bit (measured: 1.0000002)


# --- a system file's parameters as reals: enclose --system FILE --param NAME=REAL --------------

SCALED = pathlib.Path(__file__).parent / "data" / "scaled-euler-top.toml"


def _file_system(**values):
    """The test file's system with some parameters replaced by exact rationals (the exact reference)."""
    table = tomllib.loads(SCALED.read_text())
    table["parameters"].update({k: str(v) for k, v in values.items()})
    return ExpressionSystem(table)


def _file_orbit(steps, **values):
    fld = _file_system(**values).field("f")
    orbit, _, err = exact_prefix(fld, ["1", "2", "-1"], "1/5", steps)
    assert err is None and len(orbit) == steps + 1
    return orbit


def _real_file(*assignments, prec=128):
    return RealExpressionSystem.from_assignments(load_system(SCALED), list(assignments), prec)


@pytest.mark.parametrize("name,lo,hi", [("a3", Fraction(29, 10), Fraction(31, 10)),
                                         ("s", Fraction(9, 10), Fraction(11, 10))])
def test_parameter_fields_of_a_file_against_the_rational_files(name, lo, hi):
    """Every coefficient ball contains the rational file's coefficient at sampled parameters;
    mid is the file at the midpoint exactly; df/dp contains the difference quotients' limit,
    checked by exact finite differences of the rational files (linear a3: equal; 1/s: between)."""
    real = _real_file(f"{name}=[{lo},{hi}]")
    pf = real.parameter_fields()
    assert pf.names == (name,)
    m = (lo + hi) / 2
    at_mid = _coefficients(_file_system(**{name: m}).field("f"))
    assert _coefficients(pf.mid) == {k: Fraction(c) for k, c in at_mid.items()}
    ball, unit = _coefficients(real.field("f")), _coefficients(pf.units[0])
    assert all(t.is_finite() for t in unit.values())
    for p in (lo, hi, m, lo + (hi - lo) / 3):
        exact = _coefficients(_file_system(**{name: p}).field("f"))
        assert set(exact) == set(ball) and all(contains_exact(ball[k], flint.fmpq(c.numerator, c.denominator))
                                               for k, c in exact.items())
    h = (hi - lo) / 10 ** 6
    for p in (lo, hi - h):
        a, b = (_coefficients(_file_system(**{name: t}).field("f")) for t in (p, p + h))
        for k in set(a) | set(b):
            q = (Fraction(b.get(k, 0)) - Fraction(a.get(k, 0))) / h  # a derivative at some point in [p, p + h]
            assert contains_exact(unit[k], flint.fmpq(q.numerator, q.denominator)) if k in unit else q == 0, k
    assert _real_file("s=[1/2,3/2]").parameter_fields() is None  # den² in balls contains 0: no coordinates


@pytest.mark.parametrize("name,width,steps", [("a3", Fraction(1, 10 ** 6), 30), ("s", Fraction(1, 10 ** 7), 30)])
def test_file_parameter_box_contains_exact_orbits(name, width, steps):
    """A box around a3 = 3 (linear) or s = 1 (in a denominator): the Lohner and naive enclosures
    contain the exact orbits of the corners, the centre and an interior point of the file with
    those rational values; a value outside the box is missed."""
    c = {"a3": Fraction(3), "s": Fraction(1)}[name]
    lo, hi = c - width, c + width
    real = _real_file(f"{name}=[{lo},{hi}]")
    runs = [enclosure.enclose(real, "1,2,-1", "1/5", steps, 128, m, keep_points=True) for m in enclosure.METHODS]
    assert runs[1].status == "ok" and runs[1].min_correct_bits > 10
    for p in (lo, hi, c, lo + width / 3):
        orbit = _file_orbit(steps, **{name: p})
        for run in runs:
            assert _contains(run.points, orbit), (run.method, p)
    assert not _contains(runs[1].points, _file_orbit(steps, **{name: hi + width / 10}))


def test_file_parameters_width_zero_and_integrals():
    base = load_system(SCALED)
    orbit = _file_orbit(12)
    for method in enclosure.METHODS:  # width zero: the balls of the rational file
        r = enclosure.enclose(_real_file("a3=[3,3]", "s=1"), "1,2,-1", "1/5", 12, 128, method, keep_points=True)
        q = enclosure.enclose(base, "1,2,-1", "1/5", 12, 128, method, orbit, keep_points=True)
        assert r.steps_done == q.steps_done == 12 and q.encloses
        assert all(x.mid() == y.mid() and x.rad() == y.rad() for P, Q in zip(r.points, q.points) for x, y in zip(P, Q))
    # integrals: H12 does not mention a3 or s and is kept (its drift encloses 0); H23 is skipped
    real = _real_file("a3=3+-1e-9")
    assert list(real.integrals()) == ["H12"] and "a3" in real.skipped["H23"] and "H23 skipped" in real.describe()
    run = enclosure.enclose(real, "1,2,-1", "1/5", 20, 128, "lohner", integrals=declared(real)[0])
    assert run.drift_contains_zero is True
    assert list(_real_file("a1=1+-1e-9", "s=1").integrals()) == []


def test_cli_param(capsys):
    code, out, err = _cli(capsys, "--system", str(SCALED), "--param", "s=1+-1e-9", "--param", "a3=sqrt(9)",
                          "--steps", "20")
    assert code == 0, err
    assert "real parameters" in out and "lohner   ok" in out and "H23 skipped" in out


@pytest.mark.parametrize("params", [["b=1"], ["a3"], ["a3="], ["=1"], ["a3=[1,"], ["a3=1", "a3=2"], ["s=[-1,1]"],
                                    ["a3=nan"], ["s=0"]])
def test_cli_bad_param_is_one_line_exit_2(capsys, params):
    argv = ["--system", str(SCALED), "--steps", "2"] + [t for p in params for t in ("--param", p)]
    code, out, err = _cli(capsys, *argv)
    assert code == 2, (out, err)
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err


@pytest.mark.parametrize("argv", [["--param", "a=1"],
                                  ["--system", str(SCALED), "--param", "s=1+-1e-9", "--check-exact"],
                                  ["--a", "1,0,2", "--b", B, "--c", C, "--x0", X0, "--param", "a=1"]])
def test_cli_param_needs_a_system_file(capsys, argv):
    code, out, err = _cli(capsys, *argv, "--steps", "2")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--param" in err, (out, err)


# --- a [hamiltonian]-only file: f = K∇H re-read with the real parameters -------------------

Q = sympy.symbols("q1 q2 p1 p2")
PA, PB, PK = sympy.symbols("a b k")
#: H and K written once in SymPy; the file's texts are their str() (which the parser reads)
H_SYM = ((Q[2] ** 2 + Q[3] ** 2 + Q[0] ** 2 + Q[1] ** 2) / 2 + PA * Q[0] ** 2 * Q[1] + Q[1] ** 3 / (3 * PB)
         + PA ** 2 * Q[2] * Q[1] - Q[0] / 2)
K_SYM = sympy.Matrix([[0, 0, PK, 0], [0, 0, 0, 1], [-PK, 0, 0, 0], [0, -1, 0, 0]])
HAM_VALUES = {"a": "1", "b": "2", "k": "1"}


def _ham_table(K=None, H=None, **values):
    """The test file as a TOML table: [hamiltonian] only, parameters a (polynomial in H), b (in a
    denominator of H) and k (in K); ``values`` override [parameters], K/H the texts."""
    K = K or [[str(e) for e in row] for row in K_SYM.tolist()]
    return {"name": "ham-test", "variables": [str(q) for q in Q],
            "parameters": dict(HAM_VALUES, **{n: str(v) for n, v in values.items()}),
            "hamiltonian": {"K": K, "H": H or str(H_SYM)},
            "integrals": {"H": str(H_SYM), "E": "q2**2/2 + p2**2/2"},
            "defaults": {"x0": ["1/5", "-1/10", "1/4", "1/5"], "eps": "1/10"}}


def _ham_toml(path, K=None, H=None, **values):
    t = _ham_table(K, H, **values)
    q = lambda s: '"' + s + '"'  # noqa: E731
    lines = [f'name = "{t["name"]}"', "variables = [" + ", ".join(map(q, t["variables"])) + "]", "[parameters]"]
    lines += [f"{n} = {q(v)}" for n, v in t["parameters"].items()]
    lines += ["[hamiltonian]", "K = [" + ", ".join("[" + ", ".join(map(q, row)) + "]" for row in t["hamiltonian"]["K"])
              + "]", f"H = {q(t['hamiltonian']['H'])}", "[integrals]"]
    lines += [f"{n} = {q(v)}" for n, v in t["integrals"].items()]
    lines += ["[defaults]", "x0 = [" + ", ".join(map(q, t["defaults"]["x0"])) + "]", f'eps = "{t["defaults"]["eps"]}"']
    path.write_text("\n".join(lines) + "\n")
    return path


def _sympy_field(free=(), **values):
    """{(i, exponents): coefficient} of K∇H, differentiated by SymPy, at the file's parameter
    values overridden by ``values``; the parameters named in ``free`` stay symbolic."""
    subs = {s: sympy.Rational(str(values.get(str(s), HAM_VALUES[str(s)]))) for s in (PA, PB, PK)
            if str(s) not in free}
    f = K_SYM * sympy.Matrix([sympy.diff(H_SYM, q) for q in Q])
    out = {}
    for i, fi in enumerate(f):
        for m, c in sympy.Poly(sympy.expand(fi.subs(subs)), *Q).terms():
            if c != 0:
                out[(i, m)] = c
    return out


def _all_coefficients(fld):
    """{(i, exponents): coefficient} over the quadratic, linear and constant terms."""
    n, out = fld.dim, {}
    for i in range(n):
        for (j, k), c in fld.quad[i]:
            out[(i, tuple((t == j) + (t == k) for t in range(n)))] = c
        for j, c in fld.linear[i]:
            out[(i, tuple(int(t == j) for t in range(n)))] = c
        if not (isinstance(fld.const[i], Fraction) and fld.const[i] == 0):
            out[(i, (0,) * n)] = fld.const[i]
    return out


def _q(c):
    """A SymPy or Python rational as an fmpq."""
    c = c if isinstance(c, Fraction) else Fraction(int(sympy.Rational(c).p), int(sympy.Rational(c).q))
    return flint.fmpq(c.numerator, c.denominator)


def _ham_real(*assignments, prec=128, **values):
    return RealExpressionSystem.from_assignments(ExpressionSystem(_ham_table(**values)), list(assignments), prec)


def test_hamiltonian_file_width_zero_parameters_give_the_rational_field():
    """--param a=3/4 (dyadic: exact balls) and b=2/3, k=[5/7,5/7] (not dyadic: balls around the
    value) give the field of the same file with those values in [parameters], and SymPy's K∇H."""
    base = _ham_table()
    assert "field" not in base
    for assignments, values in ((["a=3/4"], {"a": Fraction(3, 4)}),
                                (["a=[3/4,3/4]", "b=0.5"], {"a": Fraction(3, 4), "b": Fraction(1, 2)}),
                                (["b=2/3", "k=[5/7,5/7]"], {"b": Fraction(2, 3), "k": Fraction(5, 7)})):
        system = _ham_real(*assignments)
        real = _all_coefficients(system.field("f"))
        rational = _all_coefficients(ExpressionSystem(_ham_table(**values)).field("f"))
        expected = _sympy_field(**values)
        assert set(real) == set(rational) == set(expected), assignments
        assert all(_q(Fraction(rational[key])) == _q(c) for key, c in expected.items())
        dyadic = all(v.denominator & (v.denominator - 1) == 0 for v in values.values())
        for key, c in expected.items():
            ball = real[key]
            assert ball.is_finite() and contains_exact(ball, _q(c)), (assignments, key)
            if dyadic:
                assert ball.rad() == 0 and arb_to_fmpq(ball.mid()) == _q(c), (assignments, key)
        if dyadic:  # every parameter a point: no parameter coordinates
            assert system.parameter_fields() is None


@pytest.mark.parametrize("name,lo,hi", [("a", Fraction(1, 2), Fraction(3, 2)),
                                         ("b", Fraction(3, 2), Fraction(5, 2)),
                                         ("k", Fraction(9, 10), Fraction(11, 10))])
def test_hamiltonian_file_interval_parameter_against_sympy(name, lo, hi):
    """With name ∈ [lo, hi]: each coefficient ball contains SymPy's K∇H at lo, hi, the midpoint
    and an interior point; parameter_fields' mid is K∇H at the midpoint exactly, and its unit
    contains SymPy's ∂(K∇H)/∂name at those points."""
    real = _ham_real(f"{name}=[{lo},{hi}]")
    ball = _all_coefficients(real.field("f"))
    pf = real.parameter_fields()
    assert pf.names == (name,)
    m = (lo + hi) / 2
    assert {k: _q(Fraction(c)) for k, c in _all_coefficients(pf.mid).items()} == \
        {k: _q(c) for k, c in _sympy_field(**{name: m}).items()}
    unit = _all_coefficients(pf.units[0])
    symbolic = _sympy_field(free=(name,))
    derivative = {key: sympy.diff(c, sympy.Symbol(name)) for key, c in symbolic.items()}
    assert {key for key, d in derivative.items() if d != 0} <= set(unit) <= set(ball)  # unit may hold zeros
    for p in (lo, hi, m, lo + (hi - lo) / 3):
        exact = _sympy_field(**{name: p})
        assert set(exact) == set(ball), p
        for key, c in exact.items():
            assert ball[key].is_finite() and contains_exact(ball[key], _q(c)), (p, key)
        at = {sympy.Symbol(name): sympy.Rational(p.numerator, p.denominator)}
        for key, u in unit.items():
            d = _q(sympy.S(derivative.get(key, 0)).subs(at))
            assert (u.is_finite() and contains_exact(u, d)) if not isinstance(u, Fraction) else _q(u) == d, (p, key)


def test_hamiltonian_file_enclosure_contains_the_exact_orbit(capsys, tmp_path):
    """exact-khk enclose --system FILE --param a=[...] runs; the Lohner and naive enclosures over
    the box contain the exact orbits of the file at rational a inside it (ends, centre,
    interior), and miss the orbit of a value outside."""
    path = _ham_toml(tmp_path / "ham.toml")
    lo, hi = Fraction(1) - Fraction(1, 10 ** 6), Fraction(1) + Fraction(1, 10 ** 6)
    code, out, err = _cli(capsys, "--system", str(path), "--param", f"a=[{lo},{hi}]", "--steps", "5")
    assert code == 0, err
    assert "real parameters" in out and "lohner   ok" in out and "naive    ok" in out
    assert "integral H skipped" in out and "integrals kept: E" in out
    steps = 5
    real = RealExpressionSystem.from_assignments(load_system(path), [f"a=[{lo},{hi}]"], 128)
    x0, eps = ["1/5", "-1/10", "1/4", "1/5"], "1/10"
    runs = [enclosure.enclose(real, ",".join(x0), eps, steps, 128, m, keep_points=True) for m in enclosure.METHODS]
    assert all(run.status == "ok" and run.steps_done == steps for run in runs)

    def orbit(a):
        fld = ExpressionSystem(_ham_table(a=a)).field("f")
        pts, _, e = exact_prefix(fld, x0, eps, steps)
        assert e is None and len(pts) == steps + 1
        return pts

    for a in (lo, hi, Fraction(1), lo + Fraction(1, 3 * 10 ** 6)):
        for run in runs:
            assert _contains(run.points, orbit(a)), (run.method, a)
    assert not _contains(runs[1].points, orbit(hi + Fraction(1, 10 ** 4)))


@pytest.mark.parametrize("K,H,param,says", [
    # K depends on x: refused by the file's own reader (K is constant), before --param
    ([["0", "0", "1 + (k - 1)*q1", "0"], ["0", "0", "0", "1"], ["-1", "0", "0", "0"], ["0", "-1", "0", "0"]],
     None, "k=[0.9,1.1]", "q1 is a variable"),
    # K skew at k = 1 only
    ([["0", "0", "k", "0"], ["0", "0", "0", "1"], ["-1", "0", "0", "0"], ["0", "-1", "0", "0"]],
     None, "k=[0.9,1.1]", "skew-symmetric"),
    (None, None, "b=[-1,1]", "may be 0"),  # H's term q2**3/(3*b): b's box contains 0
    (None, str(H_SYM) + " + (a - 1)/q1", "a=[0.9,1.1]", "depends on the variables"),  # 0 at a = 1 only
    # the same, where ∂(numerator)/∂q1 / denominator would cancel to a polynomial (a wrong field)
    (None, str(H_SYM) + " + (a - 1)*(q1**3 + 1)/q1", "a=[0.9,1.1]", "hamiltonian H: with real a, the denominator"),
    (None, str(H_SYM) + " + (a - 1)*q1**4", "a=[0.9,1.1]", "degree 3"),
    (None, str(H_SYM) + " + eps*q1", "a=[0.9,1.1]", "eps is not allowed"),  # also by the file's reader
])
def test_hamiltonian_file_refusals_are_one_line_exit_2(capsys, tmp_path, K, H, param, says):
    path = _ham_toml(tmp_path / "bad.toml", K, H)
    code, out, err = _cli(capsys, "--system", str(path), "--param", param, "--steps", "2")
    assert code == 2, (out, err)
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err and says in err, err
    if "q1 is a variable" not in says and "eps" not in says:  # the file itself is fine at its own values
        assert main(["enclose", "--system", str(path), "--steps", "2", "--quiet"]) == 0
        capsys.readouterr()


def test_hamiltonian_reader_refuses_x_in_K():
    """The K entries are re-read in the same ring as H (x allowed by the parser), and an entry
    involving x is refused with one line (a file cannot reach this: its reader refuses first)."""
    real = _ham_real("k=[0.9,1.1]")
    spec = _ham_table()["hamiltonian"]
    for entry, what in (("k*q1", "numerator"), ("1/(1 + q2 - q2 + p1)", "denominator")):
        K = [row[:] for row in spec["K"]]
        K[0][2] = entry
        says = f"hamiltonian K\\[0\\]\\[2\\]: .*the {what} .* depends on the variables"
        with pytest.raises(InputError, match=says) as exc:
            real._read_hamiltonian({"K": K, "H": spec["H"]})
        assert "\n" not in str(exc.value)
    assert real._read_hamiltonian(spec) == real._rows  # the spec itself is accepted
