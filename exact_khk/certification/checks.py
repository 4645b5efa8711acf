"""Generic checks over an arithmetic context: deciding equalities along orbits.

:func:`compare` decides ``lhs == rhs`` at a sequence of orbit points (exactly,
or rigorously for balls; floating contexts only measure); :func:`run_check`
times it and makes a :class:`~exact_khk.certification.records.Check`.  The item
generators produce the two sides of the generic claims of any Kahan map:
conservation, commutation, reversibility and the Poisson-map property.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

from exact_khk.certification.records import Check
from exact_khk.errors import InputError, PoleError, SingularStepError, UndecidedError
from exact_khk.linalg.dual import jacobiator  # noqa: F401  (one Jacobi identity for every claim)
from exact_khk.linalg.dense import matmul, matvec, transpose


def evidence_of(ar) -> str:
    """The kind of evidence a check in ``ar`` gives: the context's own word
    (e.g. "exact in Q(zeta_3)", "modular: …", "certified enclosure …"), else
    "exact in Q" for exact contexts and "numeric (measured error)" for floating ones."""
    return getattr(ar, "evidence", "exact in Q" if ar.exact else "numeric (measured error)")


def _flatten(v):
    if isinstance(v, (list, tuple)):
        for t in v:
            yield from _flatten(t)
    else:
        yield v


def compare(ar, items, skip_undefined=True):
    """Decide ``lhs == rhs`` for every ``(k, thunk)`` in ``items``, ``thunk() -> (lhs, rhs)``
    (scalars or nested lists of the same shape; ``rhs = None`` means zero).

    Returns ``(holds, residual, detail)``.  Exact (or rigorous) contexts stop at
    the first nonzero difference and report it exactly; floating contexts
    measure the largest |difference| and leave ``holds`` undecided.  A point
    where a side is undefined (singular step, pole) is skipped and listed in
    ``detail`` (``skip_undefined=False``: the error propagates); if no point
    is left, the check is undecided.
    """
    decides = getattr(ar, "decides", ar.exact)
    holds, worst, done, skipped, why = True, 0.0, [], [], ""
    for k, thunk in items:
        try:
            lhs, rhs = thunk()
        except (SingularStepError, PoleError) as exc:
            if not skip_undefined:
                raise
            skipped.append(k)
            why = why or str(exc)
            continue
        done.append(k)
        left = list(_flatten(lhs))
        right = [ar.zero] * len(left) if rhs is None else list(_flatten(rhs))
        if len(left) != len(right):
            raise InputError(f"compare: the two sides have different shapes at x_{k} "
                             f"({len(left)} against {len(right)} entries)")
        for a, b in zip(left, right):
            d = a - b
            if not decides:
                m = ar.magnitude(d)
                worst = m if m > worst or math.isnan(m) else worst  # a NaN stays: never "small"
                continue
            z = ar.is_zero(d)
            if z is False:
                return False, ar.format(d), f"first nonzero residual at x_{k}"
            if z is None:
                holds = None
    if not done:
        return None, "n/a", f"undefined at every point: {why}"
    span = f"{len(done)} orbit points" if len(done) != 1 else f"x_{done[0]}"
    note = f"; skipped k = {skipped}, where undefined (first: {why})" if skipped else ""
    if not decides:
        return None, f"{worst:.3g}", f"max |difference| over {span} (measured, not decided){note}"
    return holds, "0", f"checked at {span}{note}"


def rank(ar, rows):
    """Exact rank of a list of rows over ``ar`` (None if a pivot is undecided)."""
    M = [list(r) for r in rows]
    r = 0
    for col in range(len(M[0]) if M else 0):
        piv = None
        for i in range(r, len(M)):
            z = ar.is_zero(M[i][col])
            if z is None:
                return None
            if z is False:
                piv = i
                break
        if piv is None:
            continue
        M[r], M[piv] = M[piv], M[r]
        for i in range(r + 1, len(M)):
            m = M[i][col] / M[r][col]
            M[i] = [a - m * b for a, b in zip(M[i], M[r])]
        r += 1
    return r


def run_check(name, claim, ar, fn, expected=True, degenerate=None) -> Check:
    """Time ``fn() -> (holds, residual, detail)`` and wrap it in a :class:`Check`;
    a singular step or an undecidable pivot makes it undecided.

    For a control (``expected=False``) that did not fail, ``degenerate()``, if
    given, names why it cannot fail here (or returns None): the control is then
    recorded as inapplicable, not as a failure."""
    t0 = time.perf_counter()
    try:
        holds, residual, detail = fn()
    except (SingularStepError, UndecidedError, PoleError) as exc:
        holds, residual, detail = None, "n/a", f"not evaluable: {exc}"
    return inapplicable_if(Check(name, claim, expected, holds, residual, ar.name, time.perf_counter() - t0,
                                 evidence_of(ar), detail), degenerate)


def inapplicable_if(check: Check, degenerate) -> Check:
    """``check``, recorded as inapplicable when it is a control (``expected`` False) that did
    not fail and ``degenerate()`` names why it cannot fail here (None: it can)."""
    if check.expected or check.holds is False or degenerate is None:
        return check
    why = degenerate()
    return inapplicable(check, why) if why else check


def inapplicable(check: Check, why: str) -> Check:
    """``check`` recorded as an inapplicable control, ``why`` saying why it cannot fail here (also
    when it did fail: at an equilibrium a failing control shows nothing about the map)."""
    return replace(check, applicable=False,
                   detail=f"inapplicable: {why}" + (f"; {check.detail}" if check.detail else ""))


# --- item generators (lazy, so a failing control stops early) -------------------


def lazy_orbit(phi, x0, steps):
    """x0, Φ(x0), … (steps + 1 points), computed on demand."""
    x = phi.point(x0, "x0")
    yield x
    for k in range(1, steps + 1):
        try:
            x = phi.step(x)
        except SingularStepError as exc:
            raise exc.at_step(k) from None
        yield x


def conserved_items(integral, pts):
    """(k, I(x_k) vs I(x_0)) for k >= 1."""
    pts = iter(pts)
    v0 = integral(next(pts))
    for k, x in enumerate(pts, 1):
        yield k, lambda x=x: (integral(x), v0)


def commute_items(phi, psi, pts):
    """(k, Φ(Ψ(x_k)) vs Ψ(x_{k+1})) along an orbit x_k of Φ (Ψ(x_k) computed once)."""
    ys = {}

    def y(k):
        if k not in ys:
            ys[k] = psi.step(pts[k])
        return ys[k]

    for k in range(len(pts) - 1):
        yield k, lambda k=k: (phi.step(y(k)), y(k + 1))


def commute_points_items(phi, psi, pts):
    """(k, Φ(Ψ(x_k)) vs Ψ(Φ(x_k))) at the given points (for maps with unrelated orbits)."""
    for k, x in enumerate(pts):
        yield k, lambda x=x: (phi.step(psi.step(x)), psi.step(phi.step(x)))


def reversible_items(phi_inv, pts):
    """(k, Φ(x_{k+1}, −ε) vs x_k)."""
    for k in range(len(pts) - 1):
        yield k, lambda k=k: (phi_inv.step(pts[k + 1]), pts[k])


def poisson_map_items(phi, Pi_at, pts, ks):
    """(k, dΦ(x_k) Π(x_k) dΦ(x_k)ᵀ vs Π(x_{k+1})) for k in ``ks``."""
    def sides(k):
        D = phi.jacobian(pts[k])
        return matmul(matmul(D, Pi_at(k), phi.arith), transpose(D), phi.arith), Pi_at(k + 1)

    for k in ks:
        yield k, lambda k=k: sides(k)


def bracket(u, P, v):
    """{F, G}_P = ∇Fᵀ P ∇G."""
    Pv = matvec(P, v)
    return sum((a * b for a, b in zip(u, Pv)), u[0] * 0)
