"""The structured step (2×2 systems over circulants) against the dense step.

Exact: compared with ``==`` to the plain Fraction elimination (the reference).
Floating: the DFT step runs in python-flint ball arithmetic, so the ball radius
r is a rigorous bound on |mid − Φ(x)|; the returned value is mid rounded to
nearest, within u·|z| more (u = 2^-p).  We assert |z − Φ(x)| ≤ r + u·|z| with
Φ(x) computed exactly, and that r ≤ u·max|z| (the error is rounding-sized).
"""

import random
import warnings
from fractions import Fraction

import pytest
import sympy as sp

from exact_khk import (InputError, KahanMap, LiePoissonSystem, NearSingularWarning, QuadraticField,
                       SingularStepError, get_arith, rational_sign_patterns)
from exact_khk.systems.lie_poisson.circulant import circulant_structure, exact_htilde, exact_step, numeric_step
from exact_khk.systems.lie_poisson.system import structure_from_system
from exact_khk.systems.lie_poisson.invariants import Htilde
from exact_khk.systems.lie_poisson.system import random_point

from .conftest import EXACT


def _fields(n):
    s = LiePoissonSystem.random(n, seed=100 + n)
    out = [s.field("f"), s.field("f", power=1), s.field("control")]
    out += [s.field("g", sg) for sg in rational_sign_patterns(n)[:3]]
    return out


def _point(rng, n, den=5):
    return [Fraction(rng.randint(-4, 4), rng.randint(1, den)) for _ in range(2 * n)]


@pytest.mark.parametrize("n", range(2, 9))
def test_structured_equals_dense_exact(n):
    rng = random.Random(n)
    for fld in _fields(n):
        assert circulant_structure(fld) is not None
        x = _point(rng, n)
        eps = Fraction(rng.randint(1, 9), rng.randint(2, 20))
        ref = KahanMap(fld, eps, "fraction", method="dense").orbit(x, 2)
        for arith in EXACT:
            got = KahanMap(fld, eps, arith, method="structured").orbit(x, 2)
            ar = get_arith(arith)
            assert [[ar.to_fraction(t) for t in p] for p in got] == [list(p) for p in ref], (n, fld.label)


@pytest.mark.parametrize("n", [16, 20, 32])
def test_structured_equals_dense_at_larger_n(n):
    """The structured step (closed-form Cramer, fixed-point division checked exactly) gives
    the dense flint point along an orbit, beyond the heights where auto switches."""
    from exact_khk.systems.lie_poisson.system import random_point

    fld = LiePoissonSystem.random(n, n).field("f")
    x = random_point(n, n)
    assert (KahanMap(fld, "1/7", "flint", method="structured").orbit(x, 3)
            == KahanMap(fld, "1/7", "flint", method="dense").orbit(x, 3))


@pytest.mark.parametrize("n", [4, 8, 12])
def test_structured_step_at_points_with_vanishing_parts(n):
    """The exact step splits x along tⁿ − 1 = (tᵏ − 1)(tᵏ + 1), k = n/2 (recursively): points
    whose part mod tᵏ + 1 or mod tᵏ − 1 vanishes (u_{i+k} = ±u_i) — including the zero
    point and a point with one nonzero coordinate — step as the dense solve says."""
    rng = random.Random(n)
    fld = LiePoissonSystem.random(n, seed=n).field("f")
    k = n // 2
    half = [Fraction(rng.randint(-4, 4), rng.randint(1, 6)) for _ in range(2 * k)]
    u, v = half[:k], half[k:]
    points = [u + u + v + v, u + [-t for t in u] + v + [-t for t in v],
              [Fraction(0)] * (2 * n), [Fraction(3, 7)] + [Fraction(0)] * (2 * n - 1)]
    for x in points:
        ref = KahanMap(fld, "2/9", "fraction", method="dense").orbit(x, 2)
        got = KahanMap(fld, "2/9", "flint", method="structured").orbit(x, 2)
        assert [[Fraction(int(t.p), int(t.q)) for t in p] for p in got] == [list(p) for p in ref]
    assert len(set(ref)) == 3  # control: the last point moves


def test_structure_from_vectors_matches_field():
    for n in range(2, 7):
        s = LiePoissonSystem.random(n, seed=n)
        for kind, signs, power in [("f", None, 0), ("f", None, n + 1), ("control", None, 0),
                                   *(("g", sg, 0) for sg in rational_sign_patterns(n))]:
            assert structure_from_system(s, kind, signs, power) == \
                circulant_structure(s.field(kind, signs, power)), (n, kind, signs, power)


def test_htilde_structured_equals_dense():
    rng = random.Random(2)
    ar = get_arith("flint")
    for n in range(2, 8):
        for fld in _fields(n)[:4]:
            x = [ar(t) for t in _point(rng, n)]
            eps = ar(Fraction(1, rng.randint(3, 12)))
            assert exact_htilde(circulant_structure(fld), x, eps, ar) == Htilde(fld, x, eps, ar, method="dense")


def test_htilde_structured_is_conserved():
    s = LiePoissonSystem.random(6, seed=4)
    phi = KahanMap(s.field("f"), "1/9", "flint", method="structured")
    st = phi.structure
    pts = phi.orbit([1, 0, 2, -1, 0, 1, 1, 1, 0, 2, 0, -1], 3)
    values = {exact_htilde(st, p, phi.eps, phi.arith) for p in pts}
    assert len(values) == 1
    # negative control: H̃ of the control field's map (a different Hessian) is not conserved
    ctrl = KahanMap(s.field("control"), "1/9", "flint").orbit(pts[0], 2)
    assert len({exact_htilde(st, p, phi.eps, phi.arith) for p in ctrl}) > 1


def _singular_setup():
    """n = 4, Σu = 0: the t = 1 block of f'(x) is triangular with eigenvalue λ = (Σc)(Σv) = 2,
    so ε = 1/2 makes det(I − εf'(x)) vanish at the root t = 1 of t⁴ − 1."""
    s = LiePoissonSystem.from_vectors("1,2,0,-1", "0,1,1,3", "1,0,2,-1")
    x = [Fraction(t) for t in (1, -1, 2, -2, 1, 0, 0, 0)]
    return s, x, Fraction(1, 2)


def test_singular_structured_step_is_exactly_the_dense_singularity():
    s, x, eps = _singular_setup()
    ar = get_arith("fraction")
    Jf = sp.Matrix(s.field("f").jacobian(ar, x)).applyfunc(sp.Rational)
    assert (sp.eye(8) - sp.Rational(eps) * Jf).det() == 0  # independent check with SymPy
    for arith in EXACT:
        with pytest.raises(SingularStepError) as info:
            KahanMap(s.field("f"), eps, arith, method="structured").orbit(x, 2)
        err = info.value
        assert err.step == 1 and err.eps == "1/2" and err.x == ["1", "-1", "2", "-2", "1", "0", "0", "0"]
    # negative control: a nearby ε is regular, and structured == dense there
    near = KahanMap(s.field("f"), eps + Fraction(1, 1000), "flint", method="structured").step(x)
    assert near == KahanMap(s.field("f"), eps + Fraction(1, 1000), "flint", method="dense").step(x)


@pytest.mark.parametrize("name", ["float", "mp:64", "mp:200"])
def test_dft_step_within_rigorous_bound(name):
    ar = get_arith(name)
    rng = random.Random(7)
    u = ar.unit_roundoff
    for n in (2, 3, 5, 8, 32):
        s = LiePoissonSystem.random(n, seed=n)
        for kind in ("f", "g", "control"):
            st = structure_from_system(s, kind)
            x = _point(rng, n, den=8)
            eps = Fraction(1, 10)
            exact = exact_step(st, x, eps, get_arith("fraction"))
            z, cond, rad = numeric_step(st, [ar(t) for t in x], ar(eps), ar)
            zmax = max(abs(ar.to_fraction(t)) for t in z)
            assert 1 <= cond < 1e6 and rad <= u * zmax
            # ar(eps) is a binary number, not 1/10: the reference is the exact step at that ε
            exact = exact_step(st, [ar.to_fraction(ar(t)) for t in x], ar.to_fraction(ar(eps)),
                               get_arith("fraction"))
            err = max(abs(ar.to_fraction(a) - b) for a, b in zip(z, exact))
            assert err <= rad + u * zmax, (name, n, kind, float(err), rad)
            # negative control: the exact step at a slightly different ε is far outside the bound
            other = exact_step(st, x, eps * (1 + Fraction(1, 2 ** 20)), get_arith("fraction"))
            assert max(abs(ar.to_fraction(a) - b) for a, b in zip(z, other)) > rad + u * zmax


def test_dft_step_through_kahanmap_matches_dense_float():
    """The DFT step (method='structured') and the dense float LU agree within the dense
    step's first-order bound (3N·ρ·κ₁·u·|z|, ρ ≤ 4 here), since the DFT step is within rounding."""
    s = LiePoissonSystem.random(6, seed=1)
    fld = s.field("g")
    x = _point(random.Random(1), 6)
    fast = KahanMap(fld, "1/10", "float", method="structured")
    assert fast.structure is not None
    dense = KahanMap(fld, "1/10", "float")
    assert dense.structure is None  # auto: floating arithmetic stays genuine p-bit arithmetic
    z1, z2 = fast.step(x), dense.step(x)
    M = KahanMap(fld, "1/10", "fraction").system_matrix([Fraction(t) for t in x])
    from exact_khk.linalg.dense import identity, norm1, solve
    fr = get_arith("fraction")
    Minv, _ = solve(fr, M, identity(fr, 12))
    kappa = norm1(fr, M) * norm1(fr, Minv)
    zmax = max(abs(t) for t in z1)
    assert max(abs(a - b) for a, b in zip(z1, z2)) <= 3 * 12 * 4 * kappa * 2.0 ** -53 * zmax


def test_structured_float_condition_policy():
    s, x, eps = _singular_setup()
    fld = s.field("f")
    # ε = 1/2 is a binary number: the Fourier block at t = 1 is exactly singular
    for name in ("float", "mp:80"):
        with pytest.raises(SingularStepError) as info:
            KahanMap(fld, eps, name, method="structured").step(x)
        assert info.value.condition == float("inf")
    # a hair away: warning with κ ≈ 2^30 (≥ 2^(53/2)), not an error
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        KahanMap(fld, eps * (1 + Fraction(1, 2 ** 30)), "float", method="structured").step(x)
    near = [w for w in rec if issubclass(w.category, NearSingularWarning)]
    assert near and 2.0 ** 26 < near[0].message.condition < 2.0 ** 40
    # negative control: well away from the singularity, no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        KahanMap(fld, eps * Fraction(3, 4), "float", method="structured").step(x)


def test_auto_choice_and_fallbacks():
    big, small = LiePoissonSystem.random(16, 1), LiePoissonSystem.random(2, 1)
    assert KahanMap(big.field("g"), "1/3", "flint").structure is not None
    assert KahanMap(big.field("g"), "1/3", "fraction").structure is None  # the reference stays dense
    assert KahanMap(small.field("f"), "1/3", "flint").structure is None  # n = 2: the split step
    assert KahanMap(small.field("f"), "1/3", "flint").split
    assert KahanMap(small.field("f"), "1/3", "float").structure is None
    assert not KahanMap(small.field("f"), "1/3", "float").split
    assert not KahanMap(small.field("f"), "1/3", "fraction").split
    assert KahanMap(big.field("f"), "1/3", "mp:100").structure is None  # floating: dense unless asked
    assert KahanMap(big.field("f"), "1/3", "mp:100", method="structured").structure is not None
    # a generic quadratic field, and a Hessian whose blocks are not cyclic Hankel: dense
    generic = QuadraticField.from_tensor([[[0, 1], [0, 0]], [[1, 0], [0, 0]]])
    assert KahanMap(generic, "1/3", "flint").structure is None
    rng = random.Random(0)
    M = [[Fraction(rng.randint(-2, 2)) for _ in range(6)] for _ in range(6)]
    odd = LiePoissonSystem.random(3, 1).field_from_hessian(M)
    assert circulant_structure(odd) is None
    phi = KahanMap(odd, "1/3", "flint")
    assert phi.structure is None and not phi.split
    x = [1, 0, 2, -1, 1, 1]
    assert [phi.arith.to_fraction(t) for t in phi.step(x)] == list(KahanMap(odd, "1/3", "fraction").step(x))
    with pytest.raises(InputError, match="method"):
        KahanMap(odd, "1/3", "flint", method="structured")
    with pytest.raises(InputError, match="method"):
        KahanMap(small.field("f"), "1/3", "flint", method="fast")


def test_structured_step_at_n_256():
    """Exact step at n = 256 (the structure from the vectors: building the dense field
    would need (2n)³ tensor entries), checked against the equivalent form (docs/conventions.md)
    Φ(x) = (I + εf'(Φ(x))) x, an equation the solver never used."""
    from exact_khk.systems.lie_poisson.circulant import circulant_ring, kahan_system, reflect

    n = 256
    s = LiePoissonSystem.random(n, seed=3)
    st = structure_from_system(s, "f")
    ar = get_arith("flint")
    rng = random.Random(3)
    x = [ar(Fraction(rng.randint(-2, 2), 256)) for _ in range(2 * n)]
    e = ar(Fraction(1, 10))
    z = exact_step(st, x, e, ar)
    R = circulant_ring(n)
    # (I − (−ε) f'(z)) applied to x̂, as products in R
    (a11, a12, a21, a22), _ = kahan_system(R.hankel_polys(st), R.poly(reflect(z[:n])),
                                           R.poly(reflect(z[n:])), -e, R.mul)
    xu, xv = R.poly(reflect(x[:n])), R.poly(reflect(x[n:]))
    assert R.mul(a11, xu) + R.mul(a12, xv) == R.poly(reflect(z[:n]))
    assert R.mul(a21, xu) + R.mul(a22, xv) == R.poly(reflect(z[n:]))
    assert z != tuple(x)  # negative control: the step moved the point


def test_large_n_structured_step_never_builds_the_dense_tensor():
    """The Lie–Poisson field builds its (2n)^3 quadratic terms only on demand; the
    structured step (auto for flint at n ≥ 16) never needs them."""
    from exact_khk.systems.lie_poisson.system import random_point

    s = LiePoissonSystem.random(16, 3)
    fld = s.field("f")
    phi = KahanMap(fld, "1/10", "flint")
    assert phi.structure is not None and phi.path == "structured"
    x = random_point(16, 3)
    y = phi.step(x)
    assert list(phi.inverse(y)) == [phi.arith(t) for t in x]   # the step is undone exactly
    assert "terms" not in fld._cache      # neither the step nor its inverse built the (2n)^3 terms
    # (structured equals dense: test_structured_equals_dense_exact, n = 2..8, and tests/test_lift.py up to n = 17;
    # test_structured_equals_dense_at_larger_n: orbits at n = 16, 20, 32)


def test_exact_orbit_at_n_256_is_reversible():
    """Three exact steps at n = 256 through the public API (about 2 s), undone exactly."""
    s = LiePoissonSystem.random(256, 1)
    phi = KahanMap(s.field("f"), "1/10", "flint")
    pts = phi.orbit(random_point(256, 1), 3)
    assert all(phi.inverse(pts[k + 1]) == pts[k] for k in range(3))
    assert len(set(pts)) == 4  # control: the orbit moves


# --- the exact DFT over Q(ζ_N), n | N (systems/lie_poisson/circulant_dft.py) -------------------------------

def _cyclo_fields(n, rng):
    """f, the control and g for two rational and up to three non-rational sign patterns."""
    s = LiePoissonSystem.random(n, seed=40 + n)
    out = [s.field("f"), s.field("control")] + [s.field("g", sg) for sg in rational_sign_patterns(n)[:2]]
    patterns = {"".join(rng.choice("+-") for _ in range(n)) for _ in range(6)} - {"+" * n}
    return out + [s.field("g", p, cyclotomic=True) for p in sorted(patterns)[:3]]


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_cyclotomic_dft_step_and_htilde_equal_dense(n):
    """At points of Q(ζ_N) with ε in Q(ζ_N) (N = n and 2n), the DFT step and H̃ equal the dense
    solve over Q(ζ_N), for fields over Q and over Q(ω); ``auto`` takes the DFT step at every n."""
    from exact_khk.systems.lie_poisson import circulant_dft

    rng = random.Random(n)
    for N in (n, 2 * n):
        ar = get_arith(f"cyclo:{N}")
        for fld in _cyclo_fields(n, rng):
            st = fld.circulant_structure(cyclotomic=True)
            assert st is not None, fld.label
            x = [ar(rng.randint(-3, 3)) + ar.gen * rng.randint(-2, 2) for _ in range(2 * n)]
            eps = ar(Fraction(1, rng.randint(3, 9))) + ar.gen / 11
            auto, dense = (KahanMap(fld, eps, ar, method=m) for m in ("auto", "dense"))
            assert auto.path == "structured" and dense.path == "dense"
            assert auto.orbit(x, 2) == dense.orbit(x, 2), (n, N, fld.label)
            assert circulant_dft.exact_step(st, x, eps, ar) == dense.step(x)
            assert Htilde(fld, x, eps, ar) == Htilde(fld, x, eps, ar, method="dense"), (n, N, fld.label)


#: a prime with 2..12 | P − 1 (the library's default for gf:P)
GF_PRIME = 4611686018420360881


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6, 7])
def test_finite_field_dft_step_and_htilde_equal_dense(n):
    """In gf:P with P ≡ 1 (mod n) the DFT over F_P gives the dense solve's step and H̃,
    for fields over Q and over Q(ω) (ω mapped to the n-th root of unity of gf:P)."""
    from exact_khk.systems.lie_poisson import circulant_dft

    rng, ar = random.Random(n), get_arith(f"gf:{GF_PRIME}")
    for fld in _cyclo_fields(n, rng):
        st = fld.circulant_structure(cyclotomic=True)
        x = [ar(rng.randint(-10 ** 12, 10 ** 12)) for _ in range(2 * n)]
        eps = ar(Fraction(rng.randint(1, 9), rng.randint(2, 20)))
        auto, dense = (KahanMap(fld, eps, ar, method=m) for m in ("auto", "dense"))
        assert auto.path == "structured"
        assert auto.orbit(x, 3) == dense.orbit(x, 3), (n, fld.label)
        assert circulant_dft.exact_step(st, x, eps, ar) == dense.step(x)
        assert Htilde(fld, x, eps, ar) == Htilde(fld, x, eps, ar, method="dense"), (n, fld.label)


def test_finite_field_dft_is_the_sum_over_powers_of_omega():
    """GFArith.dft against the defining sums; a prime without the n-th roots is refused."""
    ar = get_arith(f"gf:{GF_PRIME}")
    rng = random.Random(1)
    for n in (1, 2, 3, 5, 12):
        w = [ar(rng.randint(0, 10 ** 18)) for _ in range(n)]
        omega = ar.root_of_unity(n)
        for sign in (1, -1):
            want = [sum((w[i] * omega ** ((sign * i * j) % n) for i in range(n)), ar.zero) for j in range(n)]
            assert ar.dft([w], n, sign) == [want]
    with pytest.raises(InputError, match="no primitive 5-th root of unity"):
        get_arith("gf:7").dft([[1, 2, 3, 4, 5]], 5)
    for arith in ("gf:7", "cyclo:6"):  # bad lengths and sizes: typed errors, never FLINT's abort
        bad = get_arith(arith)
        assert bad.dft([], 3) == []
        for rows, n in (([[1, 2]], 3), ([[1, 2, 3]], -3), ([[1, 2, 3]], 0), ([[1, 2, 3]], True)):
            with pytest.raises(InputError):
                bad.dft(rows, n)
        with pytest.raises(InputError, match="sign"):
            bad.dft([[1, 2, 3]], 3, 2)
    with pytest.raises(InputError, match="DFT_MAX_SIZE"):  # refused before any allocation
        get_arith("cyclo:10000").dft([[0] * 10000], 10000)
    with pytest.raises(InputError, match="DFT_MAX_SIZE"):
        get_arith(f"gf:{GF_PRIME}").dft([[0] * 5040], 5040)
    fld = LiePoissonSystem.random(5, seed=1).field("f")
    assert KahanMap(fld, "1/10", "gf:7").path == "dense"  # 5 ∤ 6


def test_cyclotomic_dft_needs_the_roots_of_unity():
    """cyclo:N holds the n-th roots of unity only for n | N: otherwise auto stays dense and
    'structured' is refused; balls (whose == is no identity) are never read as a structure."""
    fld = LiePoissonSystem.random(4, seed=1).field("f")
    assert KahanMap(fld, "1/10", "cyclo:6").path == "dense"
    assert KahanMap(fld, "1/10", "cyclo:8").path == "structured"
    # beyond the memory bounds of linear algebra on coefficients (the transform would have
    # (n·φ)² = (4·4000)² entries): the dense path, elimination over Q(ζ_N), as before
    assert KahanMap(fld, "1/10", "cyclo:10000").path == "dense"
    assert KahanMap(fld, "1/10", "cyclo:1000").path == "dense"  # φ = 400 > 128
    with pytest.raises(InputError, match="4 does not divide 6"):
        KahanMap(fld, "1/10", "cyclo:6", method="structured")
    with pytest.raises(InputError, match="memory bounds"):
        KahanMap(fld, "1/10", "cyclo:10000", method="structured")
    with pytest.raises(InputError, match="needs a field whose Jacobian blocks are circulant"):
        KahanMap(fld, "1/10", "ball:64", method="structured")
    import flint
    from exact_khk.systems.lie_poisson.circulant import hankel_first_row
    assert hankel_first_row([[flint.arb(1), flint.arb(2)], [flint.arb(2), flint.arb(1)]], cyclotomic=True) is None


def test_cyclotomic_dft_singular_step_and_pole():
    """The singular step of ``_singular_setup`` (a zero at the frequency t = 1) is found by
    the DFT in cyclo:4 exactly as by the dense solve; a nearby ε is regular and equal."""
    s, x, eps = _singular_setup()
    fld = s.field("f")
    for method in ("auto", "dense"):
        phi = KahanMap(fld, eps, "cyclo:4", method=method)
        with pytest.raises(SingularStepError) as info:
            phi.orbit(x, 2)
        assert info.value.step == 1, method
    near = eps + Fraction(1, 1000)
    assert KahanMap(fld, near, "cyclo:4").step(x) == KahanMap(fld, near, "cyclo:4", method="dense").step(x)


def test_cyclotomic_dft_htilde_pole():
    """A pole of H̃ at the frequency t = 1: there M J(x) acts on (𝟙, 0), (0, 𝟙) as
    Σu·[[−Σb, Σa], [−Σc, Σb]], whose square is (Σu)²((Σb)² − ΣaΣc)·I = 4·I for the system
    below and Σu = 1, so I − ε²(M J(x))² is singular at ε = 1/2 (SymPy confirms)."""
    from exact_khk.errors import PoleError

    s = LiePoissonSystem.from_vectors("1,0,0,0", "1,1,0,0", "1,-1,0,0")
    fld, x = s.field("f"), [Fraction(t) for t in (2, -1, 0, 0, 1, 3, 0, -2)]
    M, J = sp.Matrix(s.hessian), sp.Matrix(s.J(x))
    assert (sp.eye(8) - sp.Rational(1, 4) * (M * J) ** 2).det() == 0  # independent check
    for method in ("auto", "dense"):
        with pytest.raises(PoleError):
            Htilde(fld, x, Fraction(1, 2), "cyclo:4", method=method)
    # negative control: at ε = 1/3 H̃ exists, and the DFT gives the dense value
    assert Htilde(fld, x, Fraction(1, 3), "cyclo:4") == Htilde(fld, x, Fraction(1, 3), "cyclo:4", method="dense")
