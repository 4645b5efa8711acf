"""Fraction-free integer linear algebra and the dense integer Kahan step, against
the plain Fraction elimination (the reference) and SymPy."""

import random
from fractions import Fraction

import gmpy2
import pytest
import sympy as sp

from exact_khk import KahanMap, LiePoissonSystem, QuadraticField, SingularStepError, get_arith
from exact_khk.arith import bareiss_solve
from exact_khk.linalg.dense import SingularMatrix, lu_factor, lu_solve, solve

from .conftest import EXACT


def _random_int_system(rng, n, bits):
    M = [[rng.randint(-2 ** bits, 2 ** bits) for _ in range(n)] for _ in range(n)]
    B = [[rng.randint(-2 ** bits, 2 ** bits) for _ in range(2)] for _ in range(n)]
    return M, B


@pytest.mark.parametrize("kind", [int, gmpy2.mpz])
def test_bareiss_matches_fraction_elimination(kind):
    rng = random.Random(5)
    fr = get_arith("fraction")
    for n in range(1, 8):
        for bits in (3, 60):
            M, B = _random_int_system(rng, n, bits)
            if sp.Matrix(M).det() == 0:
                continue
            Y, d = bareiss_solve([[kind(t) for t in r] for r in M], [[kind(t) for t in r] for r in B])
            LU, perm = lu_factor(fr, [[Fraction(t) for t in r] for r in M])
            X = lu_solve(LU, perm, [[Fraction(t) for t in r] for r in B])
            assert [[Fraction(int(y), int(d)) for y in r] for r in Y] == X
            assert abs(int(d)) == abs(sp.Matrix(M).det())  # d = ±det M, from SymPy


def test_bareiss_singular_raises():
    with pytest.raises(SingularMatrix):
        bareiss_solve([[1, 2], [2, 4]], [[1], [1]])
    # negative control: a nonsingular perturbation solves
    assert bareiss_solve([[1, 2], [2, 5]], [[1], [1]])[1] != 0


@pytest.mark.parametrize("arith", EXACT)
def test_solve_every_exact_context_equals_reference(arith):
    rng = random.Random(11)
    ar, fr = get_arith(arith), get_arith("fraction")
    for n in range(2, 7):
        M = [[Fraction(rng.randint(-9, 9), rng.randint(1, 7)) for _ in range(n)] for _ in range(n)]
        B = [[Fraction(rng.randint(-9, 9), rng.randint(1, 7))] for _ in range(n)]
        ref, _ = solve(fr, M, B)
        got, cond = solve(ar, [[ar(t) for t in r] for r in M], [[ar(t) for t in r] for r in B])
        assert cond is None
        assert [[ar.to_fraction(t) for t in r] for r in got] == ref


@pytest.mark.parametrize("arith", [a for a in EXACT if a != "fraction"])
def test_integer_kernel_split_is_exact(arith):
    ar = get_arith(arith)
    v = [ar(Fraction(3, 4)), ar(Fraction(-5, 6)), ar(0), ar(7)]
    ints, d = ar.integers.split(v)
    assert int(d) == 12
    assert [Fraction(int(t), int(d)) for t in ints] == [ar.to_fraction(t) for t in v]


def _generic_field():
    """A homogeneous quadratic field with fractional coefficients (no Lie–Poisson structure)."""
    F = Fraction
    T = [[[F(1, 3), F(-2, 5), 0], [0, 0, F(7, 2)], [1, 0, 0]],
         [[0, F(1, 2), 0], [F(-1, 7), 0, F(2, 3)], [0, 0, -1]],
         [[F(5, 4), 0, 0], [0, F(-3, 2), 0], [0, F(1, 9), F(1, 6)]]]
    return QuadraticField.from_tensor(T)


@pytest.mark.parametrize("arith", [a for a in EXACT if a != "fraction"])
def test_dense_integer_step_equals_fraction_reference(arith):
    fields = [_generic_field()]
    for n in (2, 3, 5):
        s = LiePoissonSystem.random(n, seed=n)
        fields += [s.field("f"), s.field("g"), s.field("control")]
    rng = random.Random(3)
    for fld in fields:
        x = [Fraction(rng.randint(-5, 5), rng.randint(1, 4)) for _ in range(fld.dim)]
        ref = KahanMap(fld, "2/11", "fraction").orbit(x, 3)
        got = KahanMap(fld, "2/11", arith, method="dense").orbit(x, 3)
        assert [[get_arith(arith).to_fraction(t) for t in p] for p in got] == [list(p) for p in ref]


@pytest.mark.parametrize("arith", EXACT)
def test_dense_integer_step_singular(arith):
    """x = 0 direction: with f'(x) = 0 at x = 0 the step is the identity; a rational
    singular ε of the generic field (root of det(I − εf'(x)) from SymPy) raises."""
    fld = _generic_field()
    x = [Fraction(1), Fraction(0), Fraction(0)]
    Jf = sp.Matrix(fld.jacobian(get_arith("fraction"), x)).applyfunc(sp.Rational)
    lam = sp.Symbol("lam")
    roots = [r for r in sp.roots(Jf.charpoly(lam).as_expr(), lam, filter="Q") if r != 0]
    assert roots
    eps = Fraction(int(sp.numer(1 / roots[0])), int(sp.denom(1 / roots[0])))
    with pytest.raises(SingularStepError) as info:
        KahanMap(fld, eps, arith, method="dense").step(x)
    assert info.value.eps == str(eps)
    KahanMap(fld, eps + Fraction(1, 1000), arith, method="dense").step(x)  # negative control
