"""The split step (one 2×2 system per cyclotomic factor of tⁿ − 1) against the dense step.

Exact results are compared with ``==`` to the dense step (a different algorithm:
one 2n×2n integer solve) and to the plain Fraction elimination, and checked in
the step's defining equation (I − εf'(x)) x̃ = x evaluated in Fraction arithmetic.
"""

import random
import re
from fractions import Fraction

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from exact_khk import (InputError, KahanMap, LiePoissonSystem, QuadraticField, SingularStepError,
                       get_arith, rational_sign_patterns)
from exact_khk.systems.lie_poisson import split as split_mod
from exact_khk.systems.lie_poisson.paths import AUTO_SPLIT_MAX_N, SPLIT_N
from exact_khk.systems.lie_poisson.split import split_system
from exact_khk.systems.lie_poisson.system import random_point

KERNELS = ["flint", "gmpy2"]


def _fields(n, seed):
    s = LiePoissonSystem.random(n, seed=seed)
    return [s.field("f"), s.field("f", power=1), s.field("control"),
            *(s.field("g", sg) for sg in rational_sign_patterns(n)[:2])]


def _outcome(phi, x, steps):
    """The orbit, or the singular step's message (which names the point and ε)."""
    try:
        return phi.orbit(x, steps)
    except SingularStepError as exc:
        return str(exc)


def _residual_zero(fld, x, y, eps):
    """(I − εf'(x)) y == x in plain Fraction arithmetic (homogeneous fields)."""
    fr = get_arith("fraction")
    xs, ys = [Fraction(str(t)) for t in x], [Fraction(str(t)) for t in y]
    M = KahanMap(fld, eps, fr, method="dense").system_matrix(xs)
    return [sum(a * b for a, b in zip(row, ys)) for row in M] == xs


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6, 7, 8])
@pytest.mark.parametrize("arith", KERNELS)
def test_split_equals_dense(n, arith):
    rng = random.Random(n)
    for seed in range(2):
        for fld in _fields(n, seed):
            eps = Fraction(rng.randint(1, 9), rng.randint(2, 20)) * rng.choice([1, -1])
            x = random_point(n, seed)
            split = KahanMap(fld, eps, arith, method="split")
            got = _outcome(split, x, 6)
            assert got == _outcome(KahanMap(fld, eps, arith, method="dense"), x, 6), (n, fld.label)
            if not isinstance(got, str):
                assert _residual_zero(fld, got[0], got[1], eps)
                assert split.inverse(got[1]) == got[0]
                assert got[1] != got[0]  # negative control: the step moved the point


@pytest.mark.parametrize("n", [9, 10, 12, 15])
def test_split_equals_dense_with_larger_factors(n):
    """Factors Q(ζ_d) of degree 6 (n = 9), 4 (n = 10, 12) and 8 (n = 15), where det*
    is a product of 3 to 7 conjugates."""
    s = LiePoissonSystem.random(n, seed=1)
    for fld in (s.field("f"), s.field("g", rational_sign_patterns(n)[1])):
        x = random_point(n, 1)
        got = KahanMap(fld, "-2/9", "flint", method="split").orbit(x, 3)
        assert got == KahanMap(fld, "-2/9", "flint", method="dense").orbit(x, 3)


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6, 8])
def test_split_equals_fraction_reference(n):
    fld = LiePoissonSystem.random(n, seed=7).field("f")
    x = [Fraction(3, 7), Fraction(-2, 5)] + [Fraction(k, 3) for k in range(2 * n - 2)]
    ref = KahanMap(fld, "1/11", "fraction").orbit(x, 3)
    got = KahanMap(fld, "1/11", "flint", method="split").orbit(x, 3)
    assert [[Fraction(int(t.p), int(t.q)) for t in p] for p in got] == [list(p) for p in ref]


def test_split_singular_step_names_point_and_eps():
    """An orbit that runs into det(I − εf'(x)) = 0 (n = 2, step 5): the split and the
    dense step fail at the same step, with the same point and ε."""
    fld = LiePoissonSystem.random(2, seed=3).field("f")
    messages = set()
    for arith in KERNELS:
        for method in ("split", "dense"):
            with pytest.raises(SingularStepError) as exc:
                KahanMap(fld, "1/7", arith, method=method).orbit(random_point(2, 2), 12)
            messages.add(str(exc.value))
    assert len(messages) == 1
    assert "step 5" in messages.pop()


def test_split_inverse_singular_at_critical_point():
    """Φ⁻¹ is undefined at Φ(x) when det(I + εf'(Φ(x))) = 0 (see test_properties)."""
    fld = LiePoissonSystem.from_vectors("1,3", "-1,-3", "2,-3").field("f")
    x = ["-3/2", "-8/3", "-3", "-8/3"]
    for arith in KERNELS:
        phi = KahanMap(fld, "-3/2", arith, method="split")
        with pytest.raises(SingularStepError):
            phi.inverse(phi.step(x))


def test_split_two_dimensional_field():
    """n = 1: any field on Q² has 1×1 (circulant) blocks; the split system (read off the
    field's integer system) is Cramer's rule with one reduction and steps as the dense solve.
    A Kahan map takes the split step only for fields that offer it (``structured_steps``):
    this generic field is solved densely and refuses ``method='split'``."""
    F = Fraction
    fld = QuadraticField.from_tensor([[[0, F(1, 2)], [F(1, 2), 0]], [[0, F(-1, 2)], [F(-1, 2), 0]]],
                                     linear=[[0, 0], [0, 1]], const=[1, 2])
    for arith in KERNELS:
        K = get_arith(arith).integers
        S = split_system(fld, K, 1, 10)
        s, L = K.split(KahanMap(fld, "1/10", arith).point(["1/3", "2/5"]))
        points = []
        for _ in range(8):
            s, L, y = S.solve(s, L)
            points.append(tuple(y))
        assert points == KahanMap(fld, "1/10", arith, method="dense").orbit(["1/3", "2/5"], 8)[1:]
        assert not KahanMap(fld, "1/10", arith).split
        with pytest.raises(InputError, match="'split' needs a field whose Jacobian blocks are circulant"):
            KahanMap(fld, "1/10", arith, method="split")


def test_split_refuses_what_it_cannot_do():
    with pytest.raises(InputError, match="split"):
        KahanMap(LiePoissonSystem.random(16, 1).field("f"), "1/3", "flint", method="split")
    for arith in ("fraction", "float", "mp:60"):
        with pytest.raises(InputError, match="split"):
            KahanMap(LiePoissonSystem.random(3, 1).field("f"), "1/3", arith, method="split")
    assert split_system(LiePoissonSystem.random(16, 1).field("f"), get_arith("flint").integers, 1, 3) is None
    assert 16 not in SPLIT_N


@pytest.mark.parametrize("n, flint_path, gmpy2_path", [
    (2, "split", "split"), (6, "split", "split"), (7, "structured", "dense"),
    (11, "structured", "dense"), (12, "structured", "dense"), (15, "structured", "dense"),
    (16, "structured", "dense"),
])
def test_auto_paths(n, flint_path, gmpy2_path):
    """The auto rule as documented (paths.AUTO_SPLIT_MAX_N, SPLIT_N)."""
    fld = LiePoissonSystem.random(n, 1).field("f")
    assert KahanMap(fld, "1/10", "flint").path == flint_path
    assert KahanMap(fld, "1/10", "gmpy2").path == gmpy2_path
    assert KahanMap(fld, "1/10", "fraction").path == "dense"


def test_split_rejects_non_circulant_blocks():
    """A field on Q⁴ whose Jacobian blocks are not circulant has no split system."""
    F = Fraction
    T = [[[F(0)] * 4 for _ in range(4)] for _ in range(4)]
    T[0][0][1] = T[0][1][0] = F(1)  # f_0 = 2 x0 x1: not circulant in (x0, x1)
    fld = QuadraticField.from_tensor(T)
    assert split_system(fld, get_arith("flint").integers, 1, 3) is None
    with pytest.raises(InputError, match="split"):
        KahanMap(fld, "1/3", "flint", method="split")


@pytest.mark.parametrize("arith, ns", [("flint", range(2, AUTO_SPLIT_MAX_N + 1)), ("gmpy2", (2, 5, 6))])
def test_auto_takes_split_from_the_start(monkeypatch, arith, ns):
    """Every step of an auto orbit from a low point is a split solve where auto splits
    (n ≤ AUTO_SPLIT_MAX_N), and the orbit is the dense orbit exactly;
    with flint at n = 11 (a factor of degree 10) auto does not split."""
    calls, real = [], split_mod.SplitSystem.__init__

    def spy(self, *args):  # count the calls of every generated solve
        real(self, *args)
        solve = self.solve
        self.solve = lambda xi, d: calls.append(d) or solve(xi, d)

    monkeypatch.setattr(split_mod.SplitSystem, "__init__", spy)
    for n in ns:
        fld = LiePoissonSystem.random(n, 1).field("f")
        auto = KahanMap(fld, "1/10", arith)
        assert auto.split and auto.path == "split"
        calls.clear()
        assert auto.orbit(random_point(n, 1), 5) == KahanMap(fld, "1/10", arith, method="dense").orbit(
            random_point(n, 1), 5)
        assert len(calls) == 5
    assert not KahanMap(LiePoissonSystem.random(11, 1).field("f"), "1/10", "flint").split


def test_split_source_uses_characters():
    """The generated step computes the characters χ_d(x) once and writes the
    factors' entries in them."""
    fld = LiePoissonSystem.random(3, 1).field("f")
    src = split_system(fld, get_arith("flint").integers, 1, 10).source
    for h in ("x0 + x1 + x2", "x0 - x2", "x1 - x2"):
        assert re.search(rf"\bh\d+ = {re.escape(h)}$", src, re.M)
    body = [line for line in src.splitlines()[2:] if not line.lstrip().startswith("h")]
    assert body and not any(re.search(r"\bx\d", line) for line in body)  # x only through the characters


tall = st.fractions(min_value=-10 ** 30, max_value=10 ** 30, max_denominator=10 ** 30)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(st.sampled_from([2, 3, 4, 5, 6, 8]), st.integers(0, 10_000), st.sampled_from(["f", "g", "control"]),
       st.lists(tall, min_size=16, max_size=16), st.fractions(-5, 5, max_denominator=7).filter(bool))
def test_split_equals_dense_at_tall_points(n, seed, kind, coords, eps):
    """Random points with 100-bit entries (answers of Cramer size, no small-answer luck)."""
    fld = LiePoissonSystem.random(n, seed).field(kind)
    x = coords[:2 * n]
    dense = KahanMap(fld, eps, "flint", method="dense")
    split = KahanMap(fld, eps, "flint", method="split")
    try:
        y = dense.step(x)
    except SingularStepError:
        with pytest.raises(SingularStepError):
            split.step(x)
        return
    assert split.step(x) == y


@pytest.mark.parametrize("n", [2, 3, 4, 6, 7])
def test_structure_rows_are_the_integer_system_rows(n):
    """The split step's first rows from the declared structure (O(n²)) equal the rows of
    the field's whole integer system, built from its rational Jacobian (the generic route),
    up to one common factor; a structure with one entry changed does not (control)."""
    from dataclasses import replace

    from exact_khk.systems.lie_poisson.split import structure_rows

    s = LiePoissonSystem.random(n, seed=3)
    for fld in (s.field("f"), s.field("control"), s.field("g", signs="-" + "+" * (n - 1))):
        struct = fld.circulant_structure()
        for p, q in ((1, 10), (-3, 7)):
            V, R0 = fld.integer_rows(p, q)

            def proportional(declared):
                first, R = structure_rows(declared, p, q)
                a, b = R[0][0], R0[0][0]
                return all([t * b for t in first[bi][bj][k]] == [t * a for t in V[bi * n * 2 * n + bj * n + k]]
                           for bi in range(2) for bj in range(2) for k in range(n)) and \
                    all([t * b for t in r] == [t * a for t in r0] for r, r0 in zip(R, R0))
            assert proportional(struct)
            # the dense step's whole integer system (built from the structure) at a point
            K, v = get_arith("gmpy2").integers, [(-1) ** i * (i * i + 1) for i in range(2 * n)] + [5]
            Vs, Rs = fld.integer_system(K, p, q)
            M, r = K.square(Vs, v), K.apply(Rs, v)
            Mg = [[sum(c * t for c, t in zip(V[i * 2 * n + j], v)) for j in range(2 * n)] for i in range(2 * n)]
            rg = [sum(c * t for c, t in zip(row, v)) for row in R0]
            a, b = structure_rows(struct, p, q)[1][0][0], R0[0][0]  # the two common factors
            assert [[t * b for t in row] for row in M] == [[t * a for t in row] for row in Mg]
            assert [t * b for t in r] == [t * a for t in rg]
            (m11, m12), row2 = struct.m
            bad = replace(struct, m=((m11, (m12[0] + 1,) + m12[1:]), row2))
            assert not proportional(bad)


def test_auto_builds_the_split_system_only_when_it_steps():
    """Choosing the path costs nothing: at n = 7 (structured) the split system is never
    built; at n = 6 (split) by the first step."""
    built = lambda fld: any(isinstance(k, tuple) and k[0] == "split" for k in fld._cache)  # noqa: E731
    for n, used in ((7, False), (6, True)):
        fld = LiePoissonSystem.random(n, seed=1).field("f")
        phi = KahanMap(fld, "1/10", "flint")
        assert not built(fld)
        phi.step(random_point(n, 1))
        assert built(fld) is used
