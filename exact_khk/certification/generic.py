"""Certification of any quadratic system: what the system declares, checked on orbits.

:func:`certify_system` iterates the Kahan map Φ_f of a
:class:`~exact_khk.systems.base.System` (and the map of every field declared to
commute with f) from x0 and checks, in one arithmetic, with ``==`` for exact
ones (the claims a system does not declare are left out; ``claims`` selects):

* ``reversibility`` — Φ(Φ(x, ε), −ε) = x;  control: Φ(Φ(x, ε), ε) = x
  (inapplicable on 2-periodic orbits, e.g. at an equilibrium);
* ``integrals`` — every declared integral I(x, ε) is conserved by Φ_f and by
  every commuting map;  controls: I at x0 moved by δ = 2^-60 along a coordinate
  with ∂I/∂x_j(x0) ≠ 0 differs from I(x_K) (inapplicable at a critical point of
  I), and the ε → 0 limit I(x, 0) is not conserved (when I depends on ε);
* every declared control function is not conserved (always checked);
* ``poisson`` — the declared tensor Π satisfies the Jacobi identity, and
  dΦ(x) Π(x) dΦ(x)ᵀ = Π(Φ(x));  controls: the Jacobi identity fails for
  Π + W, W = e_0∧e_1 + x_1 e_1∧e_2 (inapplicable in dimension 2, where every
  bivector is Poisson), and (1 + x_j)Π is not preserved for a coordinate x_j
  that changes along the orbit;
* ``commutation`` — Φ_f∘Φ_g = Φ_g∘Φ_f for every declared field g, at the same ε;
  control: with Φ_g at step 2ε they do not commute;
* ``jacobian`` — the derivative of the step (forward-mode dual numbers through
  the solve) equals (I − εf'(x))^{-1}(I + εf'(Φ(x)));  control: with f'(x) in
  place of f'(Φ(x)) it does not (inapplicable where f'(Φ(x)) = f'(x));
* ``cmoq`` — for f = K∇H (K constant skew, H cubic; Celledoni, McLachlan,
  Owren & Quispel 2013, with their step h = 2ε): the modified energy
  H̃(x) = H(x) + (2ε/3) ∇H(x)ᵀ (I − εf'(x))^{-1} f(x) is conserved and the
  measure dx / det(I − εf'(x)) is preserved, det dΦ(x) · det(I − εf'(x)) =
  det(I − εf'(Φ(x)));  controls: H is not conserved, det dΦ(x) ≠ 1.

>>> from exact_khk.systems.expressions import ExpressionSystem
>>> top = ExpressionSystem.from_expressions(["x", "y", "z"], field={"x": "y*z", "y": "-2*z*x", "z": "x*y"},
...                                         x0=["1", "2", "3"], eps="1/10")
>>> cert = certify_system(top, steps=5, claims=["reversibility"])
>>> cert.status, [c.name for c in cert.checks]
('VALID', ['reversibility Phi_f', 'control: Phi_f applied twice returns'])
"""

from __future__ import annotations

import time
from fractions import Fraction

from exact_khk.arith import get_arith, point_height
from exact_khk.linalg.dual import jacobian as dual_jacobian
from exact_khk.certification.checks import (commute_items, compare, conserved_items, jacobiator, lazy_orbit,
                                            poisson_map_items, reversible_items, run_check)
from exact_khk.certification.records import Certificate, library_versions
from exact_khk.errors import InputError, PoleError, UndecidedError
from exact_khk.kahan.map import KahanMap
from exact_khk.linalg.dense import SingularMatrix, determinant, solve
from exact_khk.parsing import parse_rational, parse_vector

#: the claims a system can declare, in the order they are checked
CLAIMS = ("reversibility", "integrals", "poisson", "commutation", "jacobian", "cmoq")
#: relative perturbation of the "perturbed point" control (exact arithmetics)
PERTURBATION = Fraction(1, 2 ** 60)


def applicable_claims(system) -> tuple:
    """The claims ``system`` declares something for (reversibility and the
    Jacobian hold for every Kahan map)."""
    has = {"reversibility": True, "jacobian": True, "integrals": bool(system.integrals()),
           "poisson": system.poisson() is not None, "commutation": len(system.field_names()) > 1,
           "cmoq": system.hamiltonian_form() is not None}
    return tuple(c for c in CLAIMS if has[c])


def certify_system(system, x0=None, eps=None, steps: int = 20, arith=None, claims=None,
                   progress=None) -> Certificate:
    """Certify what ``system`` declares on the orbit of ``x0`` (default: the system's
    own x0 and ε) in ``arith`` (default: the fastest exact arithmetic).

    ``claims``: a subset of :data:`CLAIMS`, or its names comma-separated (default: the system's own list, else
    every claim it declares something for).  ``progress(name)`` is called before
    each check.  A singular step of Φ_f or of a commuting map raises
    :class:`~exact_khk.errors.SingularStepError`.
    """
    t_start = time.perf_counter()
    ar = get_arith(arith)
    x0 = parse_vector(system.default_x0 if x0 is None else x0, "x0", system.dim)
    eps = parse_rational(system.default_eps if eps is None else eps, "eps")
    if eps == 0:
        raise InputError("eps: the step size must be nonzero")
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 1:
        raise InputError(f"steps: expected a positive integer, got {steps!r}")
    known = applicable_claims(system)
    if isinstance(claims, str):  # 'integrals,reversibility', as on the command line
        claims = [c.strip() for c in claims.split(",") if c.strip()]
    wanted = tuple(claims) if claims is not None else (getattr(system, "claims", None) or known)
    if not wanted:  # a certificate of nothing would be VALID: refused
        raise InputError(f"claims: the list is empty; name some of {', '.join(known) or 'the claims'}")
    for c in wanted:
        if c not in CLAIMS:
            raise InputError(f"claims: unknown claim {c!r}; expected some of {', '.join(CLAIMS)}")
        if c not in known:
            raise InputError(f"claims: {system.name} declares nothing to check for {c!r}")
    run = _Run(system, x0, eps, steps, ar, progress)
    with ar.local():
        for c in CLAIMS:
            if c in wanted:
                getattr(run, c)()
        run.declared_controls()
        orbit = tuple(tuple(ar.format(t) for t in p) for p in run.pts)
        values = run.integral_values()
    height = max(point_height(ar, p) for p in run.pts) if ar.rational else None
    return Certificate(system, tuple(x0), eps, steps, ar.name, (), tuple(run.checks), library_versions(),
                       time.perf_counter() - t_start, height, orbit, values, run.phi.path)


class _Run:
    """One certification: the orbit of Φ_f and the checks appended to ``checks``."""

    def __init__(self, system, x0, eps, steps, ar, progress):
        self.system, self.x0, self.eps, self.steps, self.ar = system, x0, eps, steps, ar
        self.progress, self.checks = progress, []
        self.f = system.field("f")
        self.phi = KahanMap(self.f, eps, ar)
        self.pts = self.phi.orbit(x0, steps)
        self.e = ar.convert(eps)

    def add(self, name, claim, fn, expected=True, degenerate=None):
        if self.progress is not None:
            self.progress(name)
        self.checks.append(run_check(name, claim, self.ar, fn, expected, degenerate))

    def _same(self, a, b) -> bool:
        """a == b decided exactly (False when undecided or inexact)."""
        ar = self.ar
        return getattr(ar, "decides", ar.exact) and all(ar.is_zero(s - t) is True for s, t in zip(a, b))

    def integral_values(self) -> dict:
        out = {}
        for name, fn in self.system.integrals().items():
            try:
                out[name] = [self.ar.format(fn(self.ar, x, self.e)) for x in self.pts]
            except PoleError:
                out[name] = None
        return out

    # --- the claims ----------------------------------------------------------------
    def reversibility(self):
        ar, K = self.ar, self.steps
        for name in self.system.field_names():
            phi = self.phi if name == "f" else KahanMap(self.system.field(name), self.eps, ar)
            pts = self.pts if name == "f" else phi.orbit(self.x0, K)
            inv = phi.with_eps(-phi.eps)
            self.add(f"reversibility Phi_{name}", f"Phi_{name}(Phi_{name}(x, eps), -eps) = x at the {K} points "
                     f"of its orbit", lambda inv=inv, pts=pts: compare(ar, reversible_items(inv, pts)))
        pts = self.pts
        self.add("control: Phi_f applied twice returns",
                 "[control, must fail] Phi_f(Phi_f(x, eps), eps) = x at the orbit points",
                 lambda: compare(ar, ((k, lambda k=k: (pts[k + 2], pts[k])) for k in range(K - 1)))
                 if K >= 2 else compare(ar, [(0, lambda: (self.phi.step(pts[1]), pts[0]))]),
                 expected=False,
                 degenerate=lambda: "the orbit is 2-periodic (Phi_f(Phi_f(x0)) = x0)"
                 if self._same(self.phi.step(pts[1]), pts[0]) else None)

    def integrals(self):
        ar, e, K, pts = self.ar, self.e, self.steps, self.pts
        integrals = self.system.integrals()
        others = [n for n in self.system.field_names() if n != "f"]
        for name, fn in integrals.items():
            value = lambda x, fn=fn: fn(ar, x, e)  # noqa: E731
            self.add(f"integral {name} conserved by Phi_f", f"{name}(x_k) = {name}(x_0) for k = 1..{K} along "
                     f"the Phi_f orbit; {name} = {fn.text}", lambda value=value: compare(ar, conserved_items(value, pts)))
            for g in others:
                phi_g = KahanMap(self.system.field(g), self.eps, ar)
                self.add(f"integral {name} conserved by Phi_{g}", f"{name}(y_k) = {name}(y_0) along the Phi_{g} "
                         f"orbit of x0", lambda value=value, phi_g=phi_g: compare(
                             ar, conserved_items(value, lazy_orbit(phi_g, self.x0, K))))
            self._perturbed_point_control(name, fn)
            if fn.depends_on_eps:
                self._naive_control(name, fn)

    def declared_controls(self):
        ar, e, pts = self.ar, self.e, self.pts
        for name, fn in self.system.controls().items():
            self.add(f"control: {name} conserved by Phi_f",
                     f"[control, must fail] {name} = {fn.text} is conserved along the Phi_f orbit",
                     lambda fn=fn: compare(ar, conserved_items(lambda x: fn(ar, x, e), pts)), expected=False)

    def _perturbed_point_control(self, name, fn):
        ar, e, pts = self.ar, self.e, self.pts
        grad = []
        try:
            grad = fn.gradient(ar, pts[0], e)
        except (PoleError, ArithmeticError):
            pass
        j = next((i for i, g in enumerate(grad) if ar.is_zero(g) is False), None)
        if j is None:
            self.add(f"control: {name} at a perturbed point", f"[control, must fail] {name} at x0 moved along "
                     f"a coordinate differs from {name}(x_K)", lambda: (None, "n/a", "no coordinate to perturb"),
                     expected=False, degenerate=lambda: f"grad {name}(x0) = 0: x0 is a critical point of {name}")
            return
        rel = ar.convert(PERTURBATION if ar.exact else Fraction(2, 2 ** ar.prec))
        moved = list(pts[0])
        moved[j] = rel if ar.is_zero(moved[j]) is True else moved[j] + moved[j] * rel
        how = "2^-60 relative" if ar.exact else "one ulp"
        self.add(f"control: {name} at a perturbed point",
                 f"[control, must fail] {name} at x0 with x_{j} moved by {how} (d{name}/dx_{j}(x0) != 0) equals "
                 f"{name}(x_{self.steps})",
                 lambda: compare(ar, [(0, lambda: (fn(ar, moved, e), fn(ar, pts[-1], e)))]), expected=False)

    def _naive_control(self, name, fn):
        ar, pts = self.ar, self.pts
        limit = fn.at_eps_zero()
        if limit is None:
            return
        zero = ar.zero
        self.add(f"control: {name} at eps = 0 conserved", f"[control, must fail] the eps -> 0 limit of {name} "
                 f"(the continuous-time quantity) is conserved along the Phi_f orbit",
                 lambda: compare(ar, conserved_items(lambda x: limit(ar, x, zero), pts)), expected=False)

    def poisson(self):
        ar, e, K, pts, N = self.ar, self.e, self.steps, self.pts, self.system.dim
        P = self.system.poisson()
        self.add("Poisson tensor Jacobi identity", f"the cyclic sums of Pi_im d_m Pi_jk vanish at the {K + 1} "
                 f"orbit points", lambda: compare(ar, ((k, lambda k=k: (P.jacobiator(ar, pts[k], e), None))
                                                     for k in range(K + 1))))
        self.add("Poisson map Phi_f", f"dPhi(x) Pi(x) dPhi(x)^T = Pi(Phi(x)) at the {K} orbit points",
                 lambda: compare(ar, poisson_map_items(self.phi, lambda k: P.matrix(ar, pts[k], e), pts, range(K))))
        self.add("control: Jacobi identity of Pi + W", "[control, must fail] Pi + W, W = e_0^e_1 + x_1 e_1^e_2, "
                 "satisfies the Jacobi identity at the orbit points",
                 lambda: compare(ar, ((k, lambda k=k: (jacobiator(ar, _plus_w(ar, P, e), pts[k]), None))
                                      for k in range(K + 1))) if N >= 3 else (True, "0", ""),
                 expected=False,
                 degenerate=lambda: "in dimension 2 every bivector satisfies the Jacobi identity" if N < 3 else None)
        j = next((i for i in range(N) if ar.is_zero(pts[1][i] - pts[0][i]) is False), 0)
        scaled = lambda k: [[(ar.one + pts[k][j]) * t for t in row] for row in P.matrix(ar, pts[k], e)]  # noqa: E731
        self.add(f"control: (1 + x_{j}) Pi preserved", f"[control, must fail] the Kahan map preserves (1 + x_{j}) Pi "
                 f"(it would make 1 + x_{j} an integral)",
                 lambda: compare(ar, poisson_map_items(self.phi, scaled, pts, range(K))), expected=False,
                 degenerate=lambda: "x_0 is a fixed point of Phi_f" if self._same(pts[1], pts[0]) else None)

    def commutation(self):
        ar, K, pts = self.ar, self.steps, self.pts
        for g in self.system.field_names()[1:]:
            phi_g = KahanMap(self.system.field(g), self.eps, ar)
            self.add(f"commutation Phi_f o Phi_{g}", f"Phi_f(Phi_{g}(x)) = Phi_{g}(Phi_f(x)) at the {K} points x_k "
                     f"of the Phi_f orbit", lambda phi_g=phi_g: compare(ar, commute_items(self.phi, phi_g, pts)))
            phi_2g = KahanMap(self.system.field(g), 2 * self.eps, ar)
            self.add(f"control: commutation with Phi_{g} at 2 eps",
                     f"[control, must fail] Phi_f(., eps) commutes with Phi_{g}(., 2 eps) at the Phi_f orbit points",
                     lambda phi_2g=phi_2g: compare(ar, commute_items(self.phi, phi_2g, pts)), expected=False,
                     degenerate=lambda: "x_0 is a fixed point of Phi_f" if self._same(pts[1], pts[0]) else None)

    def _map_jacobian(self, x, y, late=True):
        """(I − εf'(x))^{-1}(I + εf'(y)) with y = Φ(x) (``late``) or y = x."""
        ar, e = self.ar, self.e
        A = [[(ar.one if i == j else ar.zero) - e * t for j, t in enumerate(row)]
             for i, row in enumerate(self.f.jacobian(ar, x))]
        B = [[(ar.one if i == j else ar.zero) + e * t for j, t in enumerate(row)]
             for i, row in enumerate(self.f.jacobian(ar, y if late else x))]
        try:
            return solve(ar, A, B)[0]
        except SingularMatrix:
            raise PoleError("I - eps f'(x) is singular") from None

    def jacobian(self):
        ar, K, pts = self.ar, self.steps, self.pts
        eps = self.eps

        def dual_step(k):
            vals, rows = dual_jacobian(ar, lambda d, xd: KahanMap(self.f, eps, d, method="dense").step(xd), pts[k])
            return rows

        self.add("Jacobian of Phi_f", f"the derivative of the step (dual numbers through the solve) equals "
                 f"(I - eps f'(x))^-1 (I + eps f'(Phi(x))) at the {K} orbit points",
                 lambda: compare(ar, ((k, lambda k=k: (dual_step(k), self._map_jacobian(pts[k], pts[k + 1])))
                                      for k in range(K))))
        self.add("control: Jacobian with f'(x) for f'(Phi(x))",
                 "[control, must fail] the derivative of the step equals (I - eps f'(x))^-1 (I + eps f'(x))",
                 lambda: compare(ar, ((k, lambda k=k: (dual_step(k), self._map_jacobian(pts[k], None, late=False)))
                                      for k in range(K))), expected=False,
                 degenerate=lambda: "f'(Phi(x)) = f'(x) along the orbit" if all(
                     self._same(sum(self.f.jacobian(ar, pts[k + 1]), []), sum(self.f.jacobian(ar, pts[k]), []))
                     for k in range(K)) else None)

    def cmoq(self):
        ar, e, K, pts = self.ar, self.e, self.steps, self.pts
        _, H = self.system.hamiltonian_form()
        modified = lambda x: modified_energy(ar, self.f, H, x, e)  # noqa: E731
        self.add("CMOQ modified energy conserved", f"H~(x) = H(x) + (2 eps/3) grad H(x)^T (I - eps f'(x))^-1 f(x) "
                 f"is conserved along the Phi_f orbit (k = 1..{K})", lambda: compare(ar, conserved_items(modified, pts)))

        def det_sides(k):
            D = _determinant(ar, self._map_jacobian(pts[k], pts[k + 1]))
            return D * _det_kahan(ar, self.f, pts[k], e), _det_kahan(ar, self.f, pts[k + 1], e)

        self.add("CMOQ invariant measure", "det dPhi(x) det(I - eps f'(x)) = det(I - eps f'(Phi(x))): the measure "
                 f"dx / det(I - eps f'(x)) is preserved at the {K} orbit points",
                 lambda: compare(ar, ((k, lambda k=k: det_sides(k)) for k in range(K))))
        self.add("control: H conserved", "[control, must fail] the Hamiltonian H itself is conserved along the "
                 "Phi_f orbit", lambda: compare(ar, conserved_items(lambda x: H(ar, x, e), pts)), expected=False)
        self.add("control: Phi_f preserves volume", "[control, must fail] det dPhi(x) = 1 at the orbit points",
                 lambda: compare(ar, ((k, lambda k=k: (_determinant(ar, self._map_jacobian(pts[k], pts[k + 1])),
                                                       ar.one)) for k in range(K))), expected=False,
                 degenerate=lambda: "x_0 is a fixed point of Phi_f" if self._same(pts[1], pts[0]) else None)


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


def _determinant(ar, M):
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
    return _determinant(ar, [[(ar.one if i == j else ar.zero) - e * t for j, t in enumerate(row)]
                            for i, row in enumerate(field.jacobian(ar, x))])


def _plus_w(ar, P, e):
    """The bivector Π + W, W = e_0∧e_1 + x_1 e_1∧e_2 (a matrix function for
    :func:`~exact_khk.certification.checks.jacobiator`)."""
    def matrix(d, x):
        M = [list(r) for r in P.matrix(d, x, d.convert(e))]
        M[0][1], M[1][0] = M[0][1] + d.one, M[1][0] - d.one
        M[1][2], M[2][1] = M[1][2] + x[1], M[2][1] - x[1]
        return M
    return matrix


