"""Set-up of the Lie–Poisson family is O(n) / O(n log n): no dense (2n)² data unless a dense path asks.

Structural checks (what is built, memory traced), never timings: scripts/bench_startup.py measures those.
"""

from __future__ import annotations

import tracemalloc
from fractions import Fraction

import pytest

from exact_khk import KahanMap, LiePoissonSystem
from exact_khk.cli.main import main
from exact_khk.systems.lie_poisson.circulant import circulant_structure
from exact_khk.linalg.numtheory import ramanujan_sum
from exact_khk.systems.lie_poisson.system import (_correlate, divisor_classes, involution_circulant, rational_sign_patterns,
                                                  structure_from_system)


def _by_definition(n, signs):
    """α_k = (1/n) Σ_{d|n} s_d c_{n/d}(k), one Ramanujan sum per (d, k)."""
    s = [1 if ch == "+" else -1 for ch in signs]
    return tuple(sum((Fraction(s[cls[0]] * ramanujan_sum(n // d, k), n) for d, cls in divisor_classes(n).items()),
                     Fraction(0)) for k in range(n))


@pytest.mark.parametrize("n", [2, 3, 4, 6, 8, 9, 12, 30])
def test_involution_coefficients_by_gcd_equal_the_definition(n):
    for signs in rational_sign_patterns(n):
        assert involution_circulant(n, signs) == _by_definition(n, signs)


@pytest.mark.parametrize("n", [3, 8, 12])
def test_structure_from_vectors_equals_the_dense_hessian(n):
    """The structure declared from a, b, c is the one read off the dense Hessian, for
    f, g (B_0 and another pattern), control."""
    system = LiePoissonSystem.random(n, 7)
    system = LiePoissonSystem([t / 3 for t in system.a], system.b, [t / 5 for t in system.c])
    other = rational_sign_patterns(n)[1]
    for kind, signs in (("f", None), ("g", None), ("g", other), ("control", None)):
        fld = system.field(kind, signs)
        declared = fld.circulant_structure()
        assert declared == structure_from_system(system, kind, signs)
        fld._cache.pop("circulant")
        assert circulant_structure(fld) == declared, (kind, signs)  # reads the (now built) dense Hessian


@pytest.mark.parametrize("n", [65, 96, 257])
def test_polynomial_correlation_equals_the_sum(n):
    """For n > 64 the first rows of B X(w) come from one integer polynomial product."""
    import random

    rng = random.Random(n)
    w = [Fraction(rng.randint(-9, 9), rng.randint(1, 4)) for _ in range(n)]
    for coeffs in (involution_circulant(n, "-" + "+" * (n - 1)),
                   [Fraction(rng.randint(-3, 3), rng.randint(1, 3)) for _ in range(n)]):
        nonzero = [(k, c) for k, c in enumerate(coeffs) if c]
        expected = tuple(sum((c * w[(j + k) % n] for k, c in nonzero), Fraction(0)) for j in range(n))
        assert _correlate(coeffs, w) == expected


def test_large_n_builds_no_dense_data():
    """Fields and maps at n = 20 000 (exact and float structured) trace O(n) memory and
    leave the (2n)² Hessian and the quadratic terms unbuilt."""
    n = 20_000
    tracemalloc.start()
    try:
        system = LiePoissonSystem.random(n, 1)
        maps = []
        for kind in ("f", "g", "control"):
            fld = system.field(kind)
            maps += [KahanMap(fld, "1/10", "flint"), KahanMap(fld, "1/10", "float", method="structured")]
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert all(m.path == "structured" for m in maps)
    assert peak < 60 * 2 ** 20, peak  # a (2n)² matrix of Fractions would be > 10 GB
    for kind in ("f", "g", "control"):
        fld = system.field(kind)
        assert "not built" in repr(fld.hessian) and "terms" not in fld._cache


def test_cli_refuses_the_exact_step_at_n_20000(capsys):
    """One exact structured step at n = 20 000 needs tens of GB (heights of ~n log n bits):
    refused up front with the limit named; the float structured step runs."""
    assert main(["orbit", "--n", "20000", "--seed", "1", "--steps", "1"]) == 2
    err = capsys.readouterr().err
    assert "EXACT_KHK_MAX_MEMORY" in err and "structured step" in err and err.count("\n") == 1


def test_cli_integrals_refuses_the_exact_solve_at_large_n(capsys):
    """With no steps, `integrals` still divides once per integral at x0 (about a step from
    it): at n = 19 999 that is tens of GB, refused up front (it was killed for memory after
    minutes) and without the orbit command's --method hint, which `integrals` lacks."""
    assert main(["integrals", "--n", "19999", "--seed", "1"]) == 2
    err = capsys.readouterr().err
    assert "EXACT_KHK_MAX_MEMORY" in err and "structured solve" in err and err.count("\n") == 1
    assert "--method" not in err


def test_cli_integrals_counts_the_default_involutions_without_building_them(capsys, monkeypatch):
    """n = 5 000 has 2^20 − 2 rational involutions: refused at once.  The probe for ζ_n used
    to build an n×n-term involution in Q(ζ_n) first (minutes); here building one fails the test."""
    from exact_khk.systems.lie_poisson import system as lp

    def forbidden(*args):
        raise AssertionError("an involution in Q(ζ_n) was built")

    monkeypatch.setattr(lp, "involution_circulant_cyclotomic", forbidden)
    assert main(["integrals", "--n", "5000", "--seed", "1"]) == 2
    assert "MAX_DEFAULT_SIGNS" in capsys.readouterr().err
