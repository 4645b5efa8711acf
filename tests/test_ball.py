"""Ball arithmetic ball:P: precision, honest predicates, certified enclosures."""

from fractions import Fraction

import flint
import pytest

from exact_khk import InputError, KahanMap, UndecidedError, get_arith
from exact_khk.arith.ball import BallArith, ball_mid, ball_rad, contains_exact
from exact_khk.systems.lie_poisson.invariants import Htilde
from exact_khk.systems.lie_poisson.system import DEFAULT_X0, LiePoissonSystem, default_system


def test_registered_and_flags():
    ar = get_arith("ball:80")
    assert isinstance(ar, BallArith)
    assert (ar.name, ar.prec, ar.exact) == ("ball:80", 80, False)
    with pytest.raises(InputError, match="ball precision"):
        get_arith("ball:1")


def test_is_zero_three_valued():
    ar = get_arith("ball:64")
    assert ar.is_zero(flint.arb(0)) is True
    assert ar.is_zero(flint.arb(1)) is False
    assert ar.is_zero(flint.arb(0, 1e-10)) is None          # contains 0, not exactly 0
    assert ar.is_zero(flint.arb(1, 1e-10)) is False
    with ar.local():
        third = ar(Fraction(1, 3))
    assert ar.is_zero(third - third) is None                 # dependency problem: [0 +/- r]


def test_local_sets_and_restores_precision():
    before = flint.ctx.prec
    with get_arith("ball:300").local():
        assert flint.ctx.prec == 300
    assert flint.ctx.prec == before


def test_native_solve_undecided_never_wrong():
    ar = get_arith("ball:64")
    M = [[ar(1), ar(2)], [ar(2), ar(4)]]                    # exactly singular
    with pytest.raises(UndecidedError, match="no pivot"):
        ar.native_solve(M, [[ar(1)], [ar(1)]])
    # negative control: a regular system is solved and the ball holds the exact answer
    X = ar.native_solve([[ar(2), ar(1)], [ar(1), ar(3)]], [[ar(1)], [ar(2)]])
    assert contains_exact(X[0][0], Fraction(1, 5)) and contains_exact(X[1][0], Fraction(3, 5))
    assert not contains_exact(X[0][0], Fraction(1, 5) + Fraction(1, 10 ** 6))


def test_exactly_singular_step_is_undecided():
    # n = 2: det(I - eps f'(x0)) = 0 exactly at eps = -1/6 (exact arithmetic raises
    # SingularStepError there, see test_hard); a ball step must not return a number.
    s2 = LiePoissonSystem.from_vectors("1,2", "0,1", "3,1")
    ar = get_arith("ball:128")
    with ar.local(), pytest.raises(UndecidedError):
        KahanMap(s2.field("f"), "-1/6", ar).step(["-2", "-2", "-2", "1"])


def test_contains_exact_is_exact():
    with flint.ctx.workprec(200):
        a = flint.arb(flint.fmpq(1, 3))
    # arb.contains rounds 1/3 at the global 53 bits and answers False; we decide exactly
    assert contains_exact(a, Fraction(1, 3))
    assert not contains_exact(a, Fraction(1, 3) + 2 * Fraction(int(ball_rad(a).p), int(ball_rad(a).q)))


def test_format_and_float():
    ar = get_arith("ball:64")
    with ar.local():
        x = ar(Fraction(1, 3))
    text = ar.format(x, digits=10)
    assert text.startswith("[0.3333333333 +/- ") and text.endswith("]")
    assert ar.to_float(x) == pytest.approx(1 / 3, rel=2 ** -52)
    assert ar.to_fraction(x) == Fraction(int(ball_mid(x).p), int(ball_mid(x).q))


def _orbit_radius(prec, steps=5):
    ar = get_arith(f"ball:{prec}")
    phi = KahanMap(default_system().field("f"), "1/10", ar)
    pts = phi.orbit(DEFAULT_X0, steps)  # KahanMap.step enters ar.local() itself
    return max(float(ball_rad(t)) for t in pts[-1]), pts


def test_precision_is_really_P():
    # radii shrink with P: the whole computation (matrix build included) runs at P bits
    radii = [_orbit_radius(P)[0] for P in (64, 128, 256)]
    assert radii[0] > radii[1] > radii[2] > 0
    # |x| <= 5 on this orbit and the ball loses about 2 bits per step (wrapping):
    # 5 steps at 256 bits must leave the radius below 2^-256 * 2^40 (generous, and
    # impossible if any operation had run at flint's default 53 bits).
    assert radii[2] < 2.0 ** (-256 + 40)
    # the same without the library entering ar.local(): the user's own ball
    # arithmetic outside it runs at flint's global 53 bits (the control), inside at P
    ar = get_arith("ball:256")
    third_outside = ar.one / ar.convert(3)
    with ar.local():
        third_inside = ar.one / ar.convert(3)
    assert float(ball_rad(third_outside)) > 2.0 ** -60
    assert float(ball_rad(third_inside)) < 2.0 ** -250


@pytest.mark.parametrize("prec", [64, 128])
def test_ball_orbit_encloses_exact_orbit(prec):
    steps = 10
    _, balls = _orbit_radius(prec, steps)
    exact = KahanMap(default_system().field("f"), "1/10", "flint").orbit(DEFAULT_X0, steps)
    for bp, ep in zip(balls, exact):
        assert all(contains_exact(b, e) for b, e in zip(bp, ep))
    # negative control: a shifted exact point is not enclosed
    shift = 1000 * max(ball_rad(b) for b in balls[-1])
    assert not all(contains_exact(b, e + shift) for b, e in zip(balls[-1], exact[-1]))


def test_htilde_enclosure_contains_exact_invariant():
    s = default_system()
    fld = s.field("f")
    ar = get_arith("ball:128")
    exact0 = Htilde(fld, KahanMap(fld, "1/10", "flint").point(DEFAULT_X0), "1/10", "flint")
    _, balls = _orbit_radius(128, 6)
    with ar.local():
        for p in balls:
            h = Htilde(fld, p, Fraction(1, 10), ar)   # H~ is conserved: every ball holds H~(x0)
            assert contains_exact(h, exact0)
            assert float(ball_rad(h)) < 1e-20
