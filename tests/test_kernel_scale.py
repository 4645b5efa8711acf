"""Orbit kernels at scale (issue 41, item 6): the modular kernel (an ``nmod_mat`` filled row by row,
one echelon form of the first points, the last ones checked by a product) lifted to Q equals, with
==, the kernel computed exactly over Q by ``fmpq_mat.rref`` of the exact orbit's evaluation matrix
(:func:`orbit_kernel_exact`, an independent route: exact orbit, rational arithmetic, no prime);
the memory is planned before the work and a kernel beyond the limit is refused with one line."""

import random
from fractions import Fraction as F

import pytest

from exact_khk.cli.main import main
from exact_khk.diagnostics import find_integrals
from exact_khk.diagnostics.degrees import random_primes, resolve_field
from exact_khk.diagnostics.kernels import (KernelTooLarge, _point, kernel_bytes, lift, monomials, orbit_kernel_exact,
                                           orbit_kernel_mod)
from exact_khk.errors import InputError
from exact_khk.systems.expressions import ExpressionSystem

VOLTERRA = ExpressionSystem.from_expressions(["x", "y", "z"], field=["x*(y - z)", "y*(z - x)", "z*(x - y)"],
                                             name="volterra3")
EULER = ExpressionSystem.from_expressions(["x", "y", "z"], field=["y*z", "-2*x*z", "x*y"], name="euler")
RANDOM = ExpressionSystem.from_expressions(["x", "y", "z"], field=["2*x*y - z**2 + x", "x*z - 3*y**2 + 1",
                                                                   "y*z + x**2 - 2*z"], name="random3")


def lifted(system, degree, seed, eps=F(1, 10), margin=None):
    """(kernel lifted from the modular route, exact kernel over Q) for one orbit."""
    _, fld = resolve_field(system, "f")
    exps = monomials(fld.dim, degree)
    m = len(exps)
    margin = margin or max(8, m // 10)
    steps = m + 2 * margin
    x0 = _point(random.Random(seed), fld.dim)
    per = []
    for p in random_primes(8, seed):
        k = orbit_kernel_mod(fld, eps, x0, exps, steps, p, margin)
        assert k.stable and not k.periodic
        per.append((p, k.basis))
        out = lift(per)
        if out is not None:
            return out, orbit_kernel_exact(fld, eps, x0, exps, steps)
    raise AssertionError("the lift was not confirmed with 8 primes")


@pytest.mark.parametrize("system, degree, margin", [(VOLTERRA, 2, None), (EULER, 2, None), (EULER, 3, None),
                                                    (RANDOM, 1, 2)])
def test_modular_kernel_lifts_to_the_exact_one(system, degree, margin):
    """A random quadratic field has no integral: its kernel has dimension 0 (both routes; a short
    orbit, as the exact heights of a non-integrable map grow geometrically)."""
    mod, exact = lifted(system, degree, seed=3, margin=margin)
    assert mod == exact
    assert (len(exact) == 0) == (system is RANDOM)
    if exact:  # entries that are rationals, not integers: the reconstruction is exercised
        assert any(t.denominator > 1 for v in exact for t in v)


def test_unstable_orbit_is_reported_as_before():
    """An orbit shorter than the candidates: rank still growing, flagged unstable; its kernel is that
    of all its points (compared with the exact route mod p)."""
    _, fld = resolve_field(EULER, "f")
    exps = monomials(3, 3)
    x0 = _point(random.Random(3), 3)
    p = random_primes(1, 0)[0]
    k = orbit_kernel_mod(fld, F(1, 10), x0, exps, 12, p, 4)
    exact = orbit_kernel_exact(fld, F(1, 10), x0, exps, 12)
    assert not k.stable and k.dim == len(exact) > 0
    assert k.basis == [[t.numerator * pow(t.denominator, -1, p) % p for t in v] for v in exact]


def test_kernel_basis_beyond_the_memory_limit_is_refused(monkeypatch, capsys):
    """The evaluation matrix fits (20 bytes × 87 points × 70 candidates, 122 kB) but the kernel
    basis of the KQV chain N = 4 at degree 4 and its 4 multiples do not (dimension > 12 alone gives
    52 bytes × 12 × 70 × 5 = 218 kB; the kernel holds the 35 multiples of x1 + x2 + x3 + x4 − c by the
    monomials of degree <= 3)."""
    _, fld = resolve_field("kqv-lotka-volterra:N=4", "f")
    assert kernel_bytes(70, 87, 0) < 200_000
    with pytest.raises(KernelTooLarge, match="EXACT_KHK_MAX_MEMORY"):
        find_integrals("kqv-lotka-volterra:N=4", degree=4, max_bytes=200_000)
    monkeypatch.setenv("EXACT_KHK_MAX_MEMORY", "200K")
    assert main(["find-integrals", "--system", "kqv-lotka-volterra:N=4", "--degree", "4", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "EXACT_KHK_MAX_MEMORY" in err and "Traceback" not in err and len(err.splitlines()) == 1


def test_bad_input(capsys):
    with pytest.raises(InputError, match="exceed"):
        find_integrals("kqv-lotka-volterra:N=40", degree=4)
    assert main(["find-integrals", "--system", "kqv-lotka-volterra:N=40", "--degree", "4", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--degree" in err


def test_long_kernels_report_their_stages(monkeypatch):
    from exact_khk.diagnostics import kernels

    monkeypatch.setattr(kernels, "PROGRESS_ENTRIES", 0)
    monkeypatch.setattr(kernels, "PROGRESS_ROWS", 10)
    _, fld = resolve_field(EULER, "f")
    said = []
    k = orbit_kernel_mod(fld, F(1, 10), _point(random.Random(3), 3), monomials(3, 3), 40, random_primes(1, 0)[0], 8,
                         progress=said.append)
    assert k.stable
    assert said[:3] == ["evaluation rows 10/33", "evaluation rows 20/33", "evaluation rows 30/33"]
    assert said[-1] == "echelon form 33 x 20 mod p"


@pytest.mark.slow
def test_large_kernel_equals_the_direct_echelon_form():
    """KQV N = 20 at degree <= 3 (1 771 candidates, 2 126 points): the kernel from the echelon form of
    the first points and the product with the last equals the canonical nullspace of all rows."""
    from exact_khk.diagnostics.kernels import _Evaluator, _orbit_mod, canonical_nullspace

    _, fld = resolve_field("kqv-lotka-volterra:N=20", "f")
    exps = monomials(20, 3)
    m, margin = len(exps), len(exps) // 10
    x0, p = _point(random.Random(1), 20), random_primes(1, 0)[0]
    said = []
    k = orbit_kernel_mod(fld, F(1, 10), x0, exps, m + 2 * margin, p, margin, progress=said.append)
    ev = _Evaluator(exps)
    _, _, basis = canonical_nullspace([ev(q, 1, p) for q in _orbit_mod(fld, F(1, 10), x0, m + 2 * margin, p)], m, p)
    assert k.stable and k.basis == basis and k.dim == len(basis) > 0
    assert said and said[-1].startswith("echelon form")


def test_circuits_are_minimal_supports():
    """Every support :func:`circuits` returns is minimal among them (no minimality filter is applied:
    an echelon row's support is a circuit), and each carries a kernel vector (rank drops by one)."""
    import flint

    from exact_khk.diagnostics.fitting import circuits

    _, fld = resolve_field("kqv-lotka-volterra:N=5", "f")
    exps = monomials(5, 2)
    m, p = len(exps), random_primes(1, 0)[0]
    k = orbit_kernel_mod(fld, F(1, 10), _point(random.Random(7), 5), exps, m + 16, p, 8)
    found = [frozenset(S) for S in circuits(k.basis, m, p)]
    assert len(found) > k.dim
    assert not any(T < S for S in found for T in found)
    for S in found[:10]:  # the kernel restricted to S is one line: basis columns outside S have corank 1
        outside = [c for c in range(m) if c not in S]
        M = flint.nmod_mat(len(outside), k.dim, [v[c] for c in outside for v in k.basis], p)
        assert k.dim - M.rank() == 1


def test_rational_reconstruction_beyond_float_range():
    """Moduli beyond 2^1024 (an eps of 400 digits makes the fits' CRT moduli that large): p/q is
    recovered from p·q^-1 mod m, at heights up to the bound sqrt(m/2) (computed exactly)."""
    from fractions import Fraction

    from exact_khk.diagnostics.kernels import rational_reconstruction

    m = 2 ** 2203 - 1  # a Mersenne prime
    q = Fraction(-(7 ** 300), 11 ** 250)
    a = q.numerator * pow(q.denominator, -1, m) % m
    assert rational_reconstruction(a, m) == q
    edge = Fraction(-(2 ** 1100), 2 ** 1101 - 1)  # |p|, q just below sqrt(m/2) ~ 2^1101
    assert rational_reconstruction(edge.numerator * pow(edge.denominator, -1, m) % m, m) == edge
