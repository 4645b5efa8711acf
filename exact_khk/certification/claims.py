"""The claim registry: each kind of claim a system can declare, defined once.

A :class:`Claim` has a ``name`` (as ``--claims`` and system files' ``claims`` name
it), ``declared(system)`` (whether the system declares something to check for it)
and ``check(run)``, which adds, on the orbit of ``run``
(:class:`~exact_khk.certification.engine.Run`), its statements and its negative
controls: ``run.add(name, statement, evaluate, expected, degenerate)`` with
``evaluate() -> (holds, residual, detail)`` exact at the orbit points
(:func:`~exact_khk.certification.checks.compare`) and ``degenerate() -> reason or
None`` the rule that makes a control that did not fail inapplicable on *this*
orbit.  Every control of every claim is inapplicable at a fixed point of Φ_f
(the engine's rule: on a one-point orbit every function is conserved).

The claims, in the order they are checked (:data:`CLAIMS`):

* ``reversibility`` — Φ(Φ(x, ε), −ε) = x for every declared field;  control: Φ_f(Φ_f(x, ε), ε) = x
  (inapplicable on 2-periodic orbits);
* ``integrals`` — every declared integral I(x, ε) is conserved by Φ_f and by every commuting map;
  controls: I at x0 moved by δ = 2^-60 along a coordinate with ∂I/∂x_j(x0) ≠ 0 differs from I(x_K)
  (inapplicable at a critical point of I), and the ε → 0 limit I(x, 0) is not conserved (when I
  depends on ε; inapplicable when that limit is a constant); every declared control function is
  not conserved;
* ``poisson`` — the declared tensor Π satisfies the Jacobi identity and dΦ(x) Π(x) dΦ(x)ᵀ = Π(Φ(x));
  controls: Π + W, W = e_0∧e_1 + x_1 e_1∧e_2, violates the Jacobi identity (inapplicable in
  dimension 2, where every bivector is Poisson), and (1 + x_j)Π is not preserved;
* ``commutation`` — Φ_f∘Φ_g = Φ_g∘Φ_f for every declared field g at the same ε;  control: with Φ_g
  at step 2ε they do not commute;
* ``jacobian`` — the derivative of the step (dual numbers through the solve) equals
  (I − εf'(x))^{-1}(I + εf'(Φ(x)));  control: with f'(x) in place of f'(Φ(x)) it does not
  (inapplicable where f'(Φ(x)) = f'(x));
* ``cmoq`` — for f = K∇H (K constant skew, H cubic; Celledoni, McLachlan, Owren & Quispel 2013,
  their step h = 2ε): the modified energy H̃ = H + (2ε/3) ∇Hᵀ (I − εf')^{-1} f is conserved and
  dx / det(I − εf'(x)) is preserved;  controls: H is not conserved, det dΦ(x) ≠ 1;
* ``measure`` — the declared density m(x, ε) of :meth:`~exact_khk.systems.base.System.measure`
  is preserved: m(Φ(x)) det dΦ(x) = m(x);  control: the density 1 (det dΦ(x) = 1) is not
  (inapplicable when m is a constant: then the claim is that control).

Adding a kind of claim is one :class:`Claim` here (plus what a system declares for it).
"""

from __future__ import annotations

from fractions import Fraction

from exact_khk.certification.checks import (commute_items, compare, conserved_items, jacobiator, lazy_orbit,
                                            poisson_map_items, reversible_items)
from exact_khk.errors import PoleError, UndecidedError
from exact_khk.kahan.map import KahanMap
from exact_khk.linalg.dense import SingularMatrix, determinant, solve
from exact_khk.linalg.dual import jacobian as dual_jacobian

#: relative perturbation of the "perturbed point" control (exact arithmetics)
PERTURBATION = Fraction(1, 2 ** 60)


class Claim:
    """One kind of claim (see the module docstring)."""

    def __init__(self, name, declared, check):
        self.name, self.declared, self.check = name, declared, check


#: name -> Claim, in the order the claims are checked
REGISTRY: dict = {}


def claim(name, declared=lambda system: True):
    """Register ``check(run)`` as the claim ``name``."""
    def register(check):
        REGISTRY[name] = Claim(name, declared, check)
        return check
    return register


# --- reversibility ------------------------------------------------------------------


def reversible(ar, name, phi, pts):
    """(check name, statement, evaluate) of Φ(Φ(x, ε), −ε) = x along the orbit ``pts`` of the map
    ``phi`` of the field ``name`` (also the paper's certificate's, for f and every g[s])."""
    inv = phi.with_eps(-phi.eps)
    return (f"reversibility Phi_{name}", f"Phi_{name}(Phi_{name}(x, eps), -eps) = x at the {len(pts) - 1} points "
            f"of its orbit", lambda: compare(ar, reversible_items(inv, pts)))


def commuting(ar, name, phi_f, phi_g, pts):
    """(check name, statement, evaluate) of Φ_f∘Φ_g = Φ_g∘Φ_f at the points ``pts`` of the Φ_f orbit,
    Φ_g the map of the field ``name`` (also the paper's certificate's, for every g[s])."""
    return (f"commutation Phi_f o Phi_{name}", f"Phi_f(Phi_{name}(x)) = Phi_{name}(Phi_f(x)) at the {len(pts) - 1} "
            f"points x_k of the Phi_f orbit", lambda: compare(ar, commute_items(phi_f, phi_g, pts)))


@claim("reversibility")
def reversibility(run):
    ar, K = run.ar, run.steps
    for name in run.system.field_names():
        run.add(*reversible(ar, name, run.map(name), run.orbit(name)))
    pts = run.pts
    run.add("control: Phi_f applied twice returns",
            "[control, must fail] Phi_f(Phi_f(x, eps), eps) = x at the orbit points",
            lambda: compare(ar, ((k, lambda k=k: (pts[k + 2], pts[k])) for k in range(K - 1)))
            if K >= 2 else compare(ar, [(0, lambda: (run.phi.step(pts[1]), pts[0]))]),
            expected=False,
            degenerate=lambda: "the orbit is 2-periodic (Phi_f(Phi_f(x0)) = x0)"
            if run.same(run.phi.step(pts[1]), pts[0]) else None)


# --- integrals ----------------------------------------------------------------------


@claim("integrals", lambda system: bool(system.integrals()))
def integrals(run):
    ar, e, K, pts = run.ar, run.e, run.steps, run.pts
    others = [n for n in run.system.field_names() if n != "f"]
    for name, fn in run.system.integrals().items():
        value = lambda x, fn=fn: fn(ar, x, e)  # noqa: E731
        run.add(f"integral {name} conserved by Phi_f", f"{name}(x_k) = {name}(x_0) for k = 1..{K} along "
                f"the Phi_f orbit; {name} = {fn.text}", lambda value=value: compare(ar, conserved_items(value, pts)))
        for g in others:
            run.add(f"integral {name} conserved by Phi_{g}", f"{name}(y_k) = {name}(y_0) along the Phi_{g} "
                    f"orbit of x0", lambda value=value, g=g: compare(
                        ar, conserved_items(value, lazy_orbit(run.map(g), run.x0, K))))
        _perturbed_point_control(run, name, fn)
        if fn.depends_on_eps:
            _eps_zero_control(run, name, fn)


def _perturbed_point_control(run, name, fn):
    ar, e, pts = run.ar, run.e, run.pts
    grad = []
    try:
        grad = fn.gradient(ar, pts[0], e)
    except (PoleError, ArithmeticError):
        pass
    j = next((i for i, g in enumerate(grad) if ar.is_zero(g) is False), None)
    if j is None:
        run.add(f"control: {name} at a perturbed point", f"[control, must fail] {name} at x0 moved along "
                f"a coordinate differs from {name}(x_K)", lambda: (None, "n/a", "no coordinate to perturb"),
                expected=False, degenerate=lambda: f"grad {name}(x0) = 0: x0 is a critical point of {name}")
        return
    rel = ar.convert(PERTURBATION if ar.exact else Fraction(2, 2 ** ar.prec))
    moved = list(pts[0])
    moved[j] = rel if ar.is_zero(moved[j]) is True else moved[j] + moved[j] * rel
    how = "2^-60 relative" if ar.exact else "one ulp"
    run.add(f"control: {name} at a perturbed point",
            f"[control, must fail] {name} at x0 with x_{j} moved by {how} (d{name}/dx_{j}(x0) != 0) equals "
            f"{name}(x_{run.steps})",
            lambda: compare(ar, [(0, lambda: (fn(ar, moved, e), fn(ar, pts[-1], e)))]), expected=False)


def _eps_zero_control(run, name, fn):
    ar, pts = run.ar, run.pts
    limit = fn.at_eps_zero()
    if limit is None:
        return
    zero = ar.zero
    run.add(f"control: {name} at eps = 0 conserved", f"[control, must fail] the eps -> 0 limit of {name} "
            f"(the continuous-time quantity) is conserved along the Phi_f orbit",
            lambda: compare(ar, conserved_items(lambda x: limit(ar, x, zero), pts)), expected=False,
            degenerate=lambda: f"the eps -> 0 limit of {name} is a constant" if _constant(limit) else None)


def _constant(fn) -> bool:
    """Whether the rational function num/den does not depend on x: den ∂num/∂x_i = num ∂den/∂x_i for every i."""
    dnum, dden = fn.partials()
    return all((fn.den * a - fn.num * b).is_zero() for a, b in zip(dnum, dden))


def declared_controls(run):
    """The system's own controls: functions claimed not conserved (checked with every claim list)."""
    ar, e, pts = run.ar, run.e, run.pts
    for name, fn in run.system.controls().items():
        run.add(f"control: {name} conserved by Phi_f",
                f"[control, must fail] {name} = {fn.text} is conserved along the Phi_f orbit",
                lambda fn=fn: compare(ar, conserved_items(lambda x: fn(ar, x, e), pts)), expected=False)


# --- Poisson tensor -----------------------------------------------------------------


@claim("poisson", lambda system: system.poisson() is not None)
def poisson(run):
    ar, e, K, pts, N = run.ar, run.e, run.steps, run.pts, run.system.dim
    P = run.system.poisson()
    run.add("Poisson tensor Jacobi identity", f"the cyclic sums of Pi_im d_m Pi_jk vanish at the {K + 1} "
            f"orbit points", lambda: compare(ar, ((k, lambda k=k: (P.jacobiator(ar, pts[k], e), None))
                                                for k in range(K + 1))))
    run.add("Poisson map Phi_f", f"dPhi(x) Pi(x) dPhi(x)^T = Pi(Phi(x)) at the {K} orbit points",
            lambda: compare(ar, poisson_map_items(run.phi, lambda k: P.matrix(ar, pts[k], e), pts, range(K))))
    run.add("control: Jacobi identity of Pi + W", "[control, must fail] Pi + W, W = e_0^e_1 + x_1 e_1^e_2, "
            "satisfies the Jacobi identity at the orbit points",
            lambda: compare(ar, ((k, lambda k=k: (jacobiator(ar, _plus_w(ar, P, e), pts[k]), None))
                                 for k in range(K + 1))) if N >= 3 else (True, "0", ""),
            expected=False,
            degenerate=lambda: "in dimension 2 every bivector satisfies the Jacobi identity" if N < 3 else None)
    j = next((i for i in range(N) if ar.is_zero(pts[1][i] - pts[0][i]) is False), 0)
    scaled = lambda k: [[(ar.one + pts[k][j]) * t for t in row] for row in P.matrix(ar, pts[k], e)]  # noqa: E731
    run.add(f"control: (1 + x_{j}) Pi preserved", f"[control, must fail] the Kahan map preserves (1 + x_{j}) Pi "
            f"(it would make 1 + x_{j} an integral)",
            lambda: compare(ar, poisson_map_items(run.phi, scaled, pts, range(K))), expected=False)


def _plus_w(ar, P, e):
    """The bivector Π + W, W = e_0∧e_1 + x_1 e_1∧e_2 (a matrix function for
    :func:`~exact_khk.linalg.dual.jacobiator`)."""
    def matrix(d, x):
        M = [list(r) for r in P.matrix(d, x, d.convert(e))]
        M[0][1], M[1][0] = M[0][1] + d.one, M[1][0] - d.one
        M[1][2], M[2][1] = M[1][2] + x[1], M[2][1] - x[1]
        return M
    return matrix


# --- commutation --------------------------------------------------------------------


@claim("commutation", lambda system: len(system.field_names()) > 1)
def commutation(run):
    ar, pts = run.ar, run.pts
    for g in run.system.field_names()[1:]:
        run.add(*commuting(ar, g, run.phi, run.map(g), pts))
        phi_2g = KahanMap(run.system.field(g), 2 * run.eps, ar)
        run.add(f"control: commutation with Phi_{g} at 2 eps",
                f"[control, must fail] Phi_f(., eps) commutes with Phi_{g}(., 2 eps) at the Phi_f orbit points",
                lambda phi_2g=phi_2g: compare(ar, commute_items(run.phi, phi_2g, pts)), expected=False)


# --- the Jacobian of the step -------------------------------------------------------


@claim("jacobian")
def jacobian(run):
    ar, K, pts, f, eps = run.ar, run.steps, run.pts, run.f, run.eps

    def dual_step(k):
        return dual_jacobian(ar, lambda d, xd: KahanMap(f, eps, d, method="dense").step(xd), pts[k])[1]

    run.add("Jacobian of Phi_f", f"the derivative of the step (dual numbers through the solve) equals "
            f"(I - eps f'(x))^-1 (I + eps f'(Phi(x))) at the {K} orbit points",
            lambda: compare(ar, ((k, lambda k=k: (dual_step(k), run.map_jacobian(pts[k], pts[k + 1])))
                                 for k in range(K))))
    run.add("control: Jacobian with f'(x) for f'(Phi(x))",
            "[control, must fail] the derivative of the step equals (I - eps f'(x))^-1 (I + eps f'(x))",
            lambda: compare(ar, ((k, lambda k=k: (dual_step(k), run.map_jacobian(pts[k], pts[k])))
                                 for k in range(K))), expected=False,
            degenerate=lambda: "f'(Phi(x)) = f'(x) along the orbit" if all(
                run.same(sum(f.jacobian(ar, pts[k + 1]), []), sum(f.jacobian(ar, pts[k]), []))
                for k in range(K)) else None)


# --- Celledoni–McLachlan–Owren–Quispel: modified energy and measure -----------------


@claim("cmoq", lambda system: system.hamiltonian_form() is not None)
def cmoq(run):
    ar, e, K, pts = run.ar, run.e, run.steps, run.pts
    _, H = run.system.hamiltonian_form()
    modified = lambda x: modified_energy(ar, run.f, H, x, e)  # noqa: E731
    run.add("CMOQ modified energy conserved", f"H~(x) = H(x) + (2 eps/3) grad H(x)^T (I - eps f'(x))^-1 f(x) "
            f"is conserved along the Phi_f orbit (k = 1..{K})", lambda: compare(ar, conserved_items(modified, pts)))

    def det_sides(k):
        D = determinant_or_undecided(ar, run.map_jacobian(pts[k], pts[k + 1]))
        return D * _det_kahan(ar, run.f, pts[k], e), _det_kahan(ar, run.f, pts[k + 1], e)

    run.add("CMOQ invariant measure", "det dPhi(x) det(I - eps f'(x)) = det(I - eps f'(Phi(x))): the measure "
            f"dx / det(I - eps f'(x)) is preserved at the {K} orbit points",
            lambda: compare(ar, ((k, lambda k=k: det_sides(k)) for k in range(K))))
    run.add("control: H conserved", "[control, must fail] the Hamiltonian H itself is conserved along the "
            "Phi_f orbit", lambda: compare(ar, conserved_items(lambda x: H(ar, x, e), pts)), expected=False)
    run.add("control: Phi_f preserves volume", "[control, must fail] det dPhi(x) = 1 at the orbit points",
            lambda: compare(ar, ((k, lambda k=k: (run.det_jacobian(k), ar.one)) for k in range(K))), expected=False)


def modified_energy(ar, field, H, x, e):
    """H(x) + (2ε/3) ∇H(x)ᵀ (I − εf'(x))^{-1} f(x) (Celledoni–McLachlan–Owren–Quispel,
    their step h = 2ε)."""
    A = [[(ar.one if i == j else ar.zero) - e * t for j, t in enumerate(row)] for i, row in enumerate(field.jacobian(ar, x))]
    try:
        z, _ = solve(ar, A, [[t] for t in field.evaluate(ar, x)])
    except SingularMatrix:
        raise PoleError("modified energy: I - eps f'(x) is singular") from None
    g = H.gradient(ar, x, e)
    two_thirds = ar.convert(Fraction(2, 3))
    return H(ar, x, e) + two_thirds * e * sum((a * r[0] for a, r in zip(g, z)), ar.zero)


def determinant_or_undecided(ar, M):
    """det M; in balls, an elimination with no pivot certainly nonzero is undecided
    (:class:`UndecidedError`); in floating arithmetic an exactly zero pivot column gives 0."""
    try:
        return determinant(ar, M)
    except SingularMatrix:
        if getattr(ar, "decides", False):
            raise UndecidedError(f"{ar.name}: no pivot of the {len(M)}x{len(M)} determinant is certainly "
                                 f"nonzero at this precision (raise P)") from None
        return ar.zero


def _det_kahan(ar, field, x, e):
    return determinant_or_undecided(ar, [[(ar.one if i == j else ar.zero) - e * t for j, t in enumerate(row)]
                                         for i, row in enumerate(field.jacobian(ar, x))])


# --- an invariant measure -----------------------------------------------------------


@claim("measure", lambda system: system.measure() is not None)
def measure(run):
    ar, e, K, pts = run.ar, run.e, run.steps, run.pts
    m = run.system.measure()
    density = lambda x: m(ar, x, e)  # noqa: E731
    run.add("invariant measure", f"m(Phi(x)) det dPhi(x) = m(x), m = {m.text}: the measure m(x) dx is preserved "
            f"at the {K} orbit points", lambda: compare(ar, ((k, lambda k=k: (
                density(pts[k + 1]) * run.det_jacobian(k), density(pts[k]))) for k in range(K))))
    run.add("control: measure with density 1 preserved", "[control, must fail] det dPhi(x) = 1 at the orbit points "
            "(the density 1 in place of m)",
            lambda: compare(ar, ((k, lambda k=k: (run.det_jacobian(k), ar.one)) for k in range(K))), expected=False,
            degenerate=lambda: f"the density m = {m.text} is a constant: the claim is this control"
            if hasattr(m, "partials") and _constant(m) else None)


#: the claims a system can declare, in the order they are checked
CLAIMS = tuple(REGISTRY)
