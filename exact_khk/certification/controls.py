"""The advice on a degenerate point (:func:`degenerate_point`).

A negative control that did not fail at a point of a degenerate set is recorded as
*inapplicable* (``run_check(..., degenerate=...)``), never as a failure; the degenerate sets
of the Lie–Poisson family's controls: :class:`~exact_khk.systems.lie_poisson.controls.ControlDegeneracy`.
"""

from __future__ import annotations


def degenerate_point(cert) -> str | None:
    """For an INCONCLUSIVE certificate whose point is degenerate, a message saying why and how to
    pick another; else None.  Degenerate: a check undefined at every orbit point (a singular
    step or a pole of some map or function the certificate evaluates), a rank below full at every
    orbit point (the orbit lies where the integrals' gradients are dependent), or no applicable control."""
    if cert.status != "INCONCLUSIVE":
        return None
    how = ("choose another x0 (--x0 with other coordinates, or --seed N for a point drawn off the "
           "degenerate sets of every map the certificate steps)")
    for c in cert.checks:
        if c.applicable and c.holds is None and ("undefined at every point" in c.detail
                                                 or c.detail.startswith("not evaluable")
                                                 or "at no orbit point (a degenerate orbit" in c.detail):
            why = c.detail.split("; ")[0]
            return f"x0 is degenerate for this system: '{c.name}' is {why[:240]}; {how}"
    controls = [c for c in cert.checks if not c.expected]
    if controls and not any(c.applicable for c in controls):
        why = next((c.detail[len("inapplicable: "):].split("; ")[0] for c in controls
                    if "fixed point" in c.detail or "equilibrium" in c.detail), controls[0].detail)
        return f"x0 is degenerate for this system: no negative control can fail there ({why[:240]}); {how}"
    return None
