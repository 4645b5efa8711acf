"""Assertion helpers for users' own pytest suites.

Each helper runs one check of :mod:`exact_khk.certify` along an orbit and raises
``AssertionError`` with the exact first nonzero residual (and where it
occurred) when the property fails.  In a floating arithmetic, pass ``tol``: the
measured largest |difference| must not exceed it.

>>> from exact_khk import KahanMap, LiePoissonSystem
>>> from exact_khk.systems.lie_poisson.invariants import Htilde
>>> s = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")
>>> phi = KahanMap(s.field("f"), "1/10", "fraction")
>>> assert_conserved(phi, lambda x: Htilde(s.field("f"), x, "1/10", phi.arith), ["1", "0", "0", "0", "1", "0"], 5)
>>> assert_conserved(phi, lambda x: x[0], ["1", "0", "0", "0", "1", "0"], 5)
Traceback (most recent call last):
...
AssertionError: not conserved by KahanMap(f, eps=1/10, arith=fraction): first nonzero residual at x_1: 15506/57239
"""

from __future__ import annotations

from exact_khk.certification.checks import (commute_items, compare, conserved_items, poisson_map_items, reversible_items)
from exact_khk.errors import InputError


def _assert(phi, items, what, tol):
    ar = phi.arith
    decides = ar.exact or getattr(ar, "decides", False)
    if not decides and tol is None:
        raise InputError(f"arithmetic {ar.name} is not exact: pass tol= (a bound on the measured error)")
    if tol is not None and (isinstance(tol, bool) or not isinstance(tol, (int, float)) or not tol >= 0):
        raise InputError(f"tol: expected a nonnegative number, got {tol!r}")
    try:
        holds, residual, detail = compare(ar, items, skip_undefined=False)
    except (TypeError, AttributeError) as exc:  # e.g. a function returning a float in an exact arithmetic
        raise InputError(f"{what}: the values cannot be compared in {ar.name} ({exc}); "
                         f"return numbers of the map's arithmetic (phi.arith)") from None
    if decides:
        if holds is not True:
            raise AssertionError(f"{what}: {detail}: {residual}" if holds is False else f"{what}: undecided ({detail})")
        return
    if not float(residual) <= tol:
        raise AssertionError(f"{what}: measured error {residual} > tol = {tol:g} ({detail})")


def _inverse(phi):
    return phi.with_eps(-phi.eps)


def _map(phi):
    """``phi`` if it is a :class:`~exact_khk.kahan.map.KahanMap`, else InputError."""
    from exact_khk.kahan.map import KahanMap

    if not isinstance(phi, KahanMap):
        raise InputError(f"phi: expected a KahanMap (e.g. KahanMap(system.field('f'), '1/10')), "
                         f"got {type(phi).__name__}")
    return phi


def assert_conserved(phi, integral, x0, steps, tol=None):
    """``integral(x)`` is the same at every point of the orbit of ``phi`` (a KahanMap) from x0.

    Here and below, a singular step or a pole raises (it is not skipped)."""
    _map(phi)
    _assert(phi, conserved_items(integral, phi.orbit(x0, steps)), f"not conserved by {phi!r}", tol)


def assert_commute(phi, psi, x0, steps, tol=None):
    """Φ(Ψ(x)) = Ψ(Φ(x)) at every point of the orbit of ``phi`` from x0."""
    _map(phi), _map(psi)
    _assert(phi, commute_items(phi, psi, phi.orbit(x0, steps)), f"{phi!r} and {psi!r} do not commute", tol)


def assert_reversible(phi, x0, steps, tol=None):
    """Φ(Φ(x, ε), −ε) = x at every point of the orbit of ``phi`` from x0."""
    _map(phi)
    _assert(phi, reversible_items(_inverse(phi), phi.orbit(x0, steps)), f"{phi!r} is not reversible", tol)


def assert_poisson_map(phi, poisson, x0, steps, tol=None):
    """dΦ(x) P(x) dΦ(x)ᵀ = P(Φ(x)) along the orbit; ``poisson(x)`` returns the tensor P(x)."""
    _map(phi)
    pts = phi.orbit(x0, steps)
    _assert(phi, poisson_map_items(phi, lambda k: poisson(pts[k]), pts, range(steps)),
            f"{phi!r} is not a Poisson map", tol)


def assert_certificate_valid(cert):
    """Every claim of a :class:`~exact_khk.certify.Certificate` holds and every control fails."""
    from exact_khk.certification.records import Certificate

    if not isinstance(cert, Certificate):
        raise InputError(f"cert: expected a Certificate (from certify()), got {type(cert).__name__}")
    if not cert.valid:
        bad = [f"{c.name}: holds={c.holds}, residual {c.residual} ({c.detail})" for c in cert.checks if not c.passed]
        raise AssertionError(cert.verdict() + "\n" + "\n".join(bad))
