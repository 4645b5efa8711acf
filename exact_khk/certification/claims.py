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

* ``definition`` — I(x) = h(x, Φ(x)) along the orbit of I's own map for every integral
  declaring a definition h (the family's H̃ and K̃: h(x, x̃) = (2ε)^{-1} xᵀ J((x+x̃)/2)^{-1} x̃);
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
* ``involution`` — for every integral I_B declared as the image of I under an involution B:
  ∇I_B = B ∇I and {I, I_B} = 0 for Π and for its ε → 0 limit J; first ∇q_l = A^l ∇q_0 for the
  coefficients of Π's second form, where the tensor declares one;
* ``rank`` — the gradient families the system declares (``gradient_ranks``) have their rank at
  some orbit point (functional independence; undecided if at none);
* ``jacobian`` — the derivative of the step (dual numbers through the solve) equals
  (I − εf'(x))^{-1}(I + εf'(Φ(x)));  control: with f'(x) in place of f'(Φ(x)) it does not
  (inapplicable where f'(Φ(x)) = f'(x));
* ``cmoq`` — for f = K∇H (K constant skew, H cubic; Celledoni, McLachlan, Owren & Quispel 2013,
  their step h = 2ε): the modified energy H̃ = H + (2ε/3) ∇Hᵀ (I − εf')^{-1} f is conserved and
  dx / det(I − εf'(x)) is preserved;  controls: H is not conserved, det dΦ(x) ≠ 1;
* ``measure`` — the declared density m(x, ε) of :meth:`~exact_khk.systems.base.System.measure`
  is preserved: m(Φ(x)) det dΦ(x) = m(x);  control: the density 1 (det dΦ(x) = 1) is not
  (inapplicable when m is a constant: then the claim is that control).

Any system may declare (:class:`~exact_khk.systems.base.System`): ``claim_order``;
``claims_on_every_orbit``, the claims about a map (integrals conserved, Poisson map) checked and
stated per map along every map's computed orbit, the Poisson checks at the ``poisson_points``
subset; ``own_controls_only``, its own negative controls (``negative_controls``, run by
:func:`declared_controls` after the claims) in place of the automatic ones
(:meth:`~exact_khk.certification.engine.Run.control`).  Quantities the claims
share (integrals, gradients, Π) come memoised from the run, by the system's fast forms where it
has them (:meth:`~exact_khk.systems.base.System.fast_forms`; the generic route where None).

The engine runs the registry in three modes (:mod:`~exact_khk.certification.engine`): exact at
the orbit points; as identities over F_P at random draws of (x, ε) (Schwartz–Zippel,
:func:`~exact_khk.certification.engine.identity_checks`); and symbolically over Q(x, ε)
(:func:`~exact_khk.certification.engine.symbolic_checks`).  The claims are written once for
all three: the modes only change the arithmetic and x0 (a random draw or the symbols, one
step; ``run.points`` is then x0 alone, and ``run.point_free`` tells the controls' rules that
there is no point to judge them by), so a claim states its mode evaluations by what it passes
to ``run.add``: ``degree=lambda: Deg(...)``, the bound in (x, ε) of its residual as a rational
function (:class:`Deg`, derived from what the system declares by the rules there), which the
identity mode needs for its failure bound (a check without one is recorded there as not
available, undecided).  Controls need no bound (a nonzero residual refutes exactly), nor does
the rank (rank r at one point proves generic rank r).

Adding a kind of claim is one :class:`Claim` here, each check with its ``degree`` (plus what a
system declares for it).
"""

from __future__ import annotations

from fractions import Fraction
from itertools import combinations, product
from typing import NamedTuple

from exact_khk.arith import get_arith
from exact_khk.certification.checks import (bracket, commute_items, commute_points_items, compare, conserved_items,
                                            inapplicable, jacobiator, lazy_orbit, poisson_map_items, rank,
                                            reversible_items, run_check)
from exact_khk.errors import PoleError, UndecidedError
from exact_khk.kahan.map import KahanMap
from exact_khk.linalg.dense import SingularMatrix, determinant, matvec, solve
from exact_khk.linalg.flintmat import column, fmpq_mat
from exact_khk.linalg.flintmat import rank as flint_rank
from exact_khk.linalg.dual import jacobian as dual_jacobian

#: relative perturbation of the "perturbed point" controls (exact arithmetics)
PERTURBATION = Fraction(1, 2 ** 60)



# --- degrees in (x, eps): the Schwartz–Zippel bounds of the identity mode -----------------


class Deg(NamedTuple):
    """Degree bounds of a rational function of (x, ε) (every x_i and ε a variable of degree 1)
    written num/den: ``num`` and ``den`` bound the total degrees of a numerator and a denominator,
    ``sing`` the degree of the product of every denominator its evaluation divides by (a draw where
    that product vanishes is singular and redrawn).  The rules (``(a, b)`` = (num, den)):

    * a coordinate of x: (1, 0); a declared function: its (deg num, deg den) (:func:`function_deg`);
    * a Kahan step of a quadratic field at y = Y/D (Y, D of degrees ≤ (s, r)): L = D(I − εf'(y))
      has entries of degree ≤ u = max(s, r) + 1 and f(y) = F/D² with deg F ≤ 2t, t = max(s, r + 1),
      so Φ(y) = y + 2ε adj(L) F/(det L · D) (Cramer) is (max(s + Nu, 1 + (N−1)u + 2t), Nu + r),
      dividing by det L (degree Nu): at y = x, (2N + 1, 2N) (:func:`step_deg`);
    * a function (a, b) at y = Y/D as above: p(Y/D) = P̂/D^a with deg P̂ ≤ a·t (a monomial x^α ε^j,
      |α| + j ≤ a, becomes Y^α ε^j D^(a−|α|)), so (a t + (b − m) r, b t + (a − m) r), m = min(a, b),
      dividing by the cleared denominator (degree b t) (:func:`at`);
    * a − b: (max(a1 + b2, a2 + b1), b1 + b2); a·b: (a1 + a2, b1 + b2); a sum of products with
      one denominator per factor: the same as one product; ∂/∂x_i: (a + b − 1, 2b).

    A check's residual is compared at its first point (k = 0, or k = 1 for conservation): it
    vanishes at a random regular draw with probability ≤ num/(P − …) unless it is zero."""

    num: int
    den: int
    sing: int = 0


X = Deg(1, 0)  # a coordinate of x (or ε)


def minus(a, b):
    return Deg(max(a.num + b.den, b.num + a.den), a.den + b.den, a.sing + b.sing)


def times(a, b):
    return Deg(a.num + b.num, a.den + b.den, a.sing + b.sing)


def partial(a):
    return Deg(a.num + a.den - 1, 2 * a.den, a.sing)


def at(fn, y):
    """The function of degrees ``fn`` evaluated at the point of degrees ``y`` (see :class:`Deg`)."""
    t, m = max(y.num, y.den + 1), min(fn.num, fn.den)
    return Deg(fn.num * t + (fn.den - m) * y.den, fn.den * t + (fn.num - m) * y.den,
               y.sing + fn.sing + fn.den * t)


def step_deg(N, y=X):
    """A Kahan step of a quadratic field in dimension N at the point of degrees ``y``."""
    u, t = max(y.num, y.den) + 1, max(y.num, y.den + 1)
    return Deg(max(y.num + N * u, 1 + (N - 1) * u + 2 * t), N * u + y.den, y.sing + N * u)


def jacobian_deg(N):
    """dΦ(x) = (I − εf'(x))^{-1}(I + εf'(Φ(x))): adj/det (2N − 2, 2N) times entries (u, 2N) of
    I + εf'(y) at y = Φ(x) (u = 2N + 2), one denominator per factor."""
    y = step_deg(N)
    return Deg(2 * N - 2 + max(y.num, y.den) + 1, 2 * N + y.den, y.sing + 2 * N)


def function_deg(fn):
    """(deg num, deg den) in (x, ε) of a declared function (a
    :class:`~exact_khk.systems.functions.RationalFunction`, or an object with ``degrees()``),
    or None when it states none."""
    if hasattr(fn, "degrees"):
        a, b = fn.degrees()
        return Deg(a, b, b)
    num, den = getattr(fn, "num", None), getattr(fn, "den", None)
    if num is None or not hasattr(num, "terms"):
        return None
    a, b = (max((sum(e) for e in p.terms), default=0) for p in (num, den))
    return Deg(a, b, b)


def tensor_deg(P):
    """The degree of a Poisson tensor with polynomial entries (``degrees()``, or the entries of a
    :class:`~exact_khk.systems.functions.PolynomialTensor` with constant denominators), else None."""
    if hasattr(P, "degrees"):
        return P.degrees()
    entries = [e for row in getattr(P, "entries", ()) for e in row]
    degs = [function_deg(e) for e in entries]
    if not entries or any(d is None or d.den for d in degs):
        return None
    return max(d.num for d in degs)


def _poly(p):
    return None if p is None else Deg(p, 0)


def _conserved_deg(run, fn):
    """I(Φ(x)) − I(x)."""
    d = function_deg(fn)
    return None if d is None else minus(at(d, step_deg(run.system.dim)), d)


def _definition_deg(run, fn):
    """I(x) − h(x, Φ(x)), h = (2ε)^{-1} xᵀ J(z)^{-1} x̃ with J linear and z = (x + x̃)/2 = Z/D
    (deg Z ≤ 2N + 1, deg D ≤ 2N): xᵀ adj(J(Z)) X̃ / det J(Z) (D cancels) is
    (1 + (N−1)(2N+1) + 2N+1, N(2N+1)), and (2ε)^{-1} adds 1 to both."""
    d, N = function_deg(fn), run.system.dim
    c = N * (2 * N + 1) + 1
    return None if d is None else minus(d, Deg(c, c, 2 * N + c))


def _jacobi_deg(P):
    """Σ Π_im ∂_mΠ_jk (cyclic) for polynomial entries of degree p: 2p − 1."""
    p = tensor_deg(P)
    return None if p is None else Deg(max(2 * p - 1, 0), 0)


def _poisson_map_deg(N, P):
    """dΦ Π dΦᵀ − Π(Φ(x)) (:func:`jacobian_deg`; Π polynomial of degree p)."""
    p, J = tensor_deg(P), jacobian_deg(N)
    return None if p is None else minus(Deg(2 * J.num + p, 2 * J.den, J.sing), at(Deg(p, 0), step_deg(N)))


def _gradient_deg(run, fn, base):
    """∇I_B − B ∇I (B constant)."""
    a, b = function_deg(fn), function_deg(run.integrals[base])
    return None if a is None or b is None else minus(partial(a), partial(b))


def _bracket_deg(run, a, b, q):
    """∇Iᵀ Q ∇I' for the integrals named ``a``, ``b``, Q polynomial of degree q (one denominator per factor)."""
    a, b = function_deg(run.integrals[a]), function_deg(run.integrals[b])
    if a is None or b is None or q is None:
        return None
    ga, gb = partial(a), partial(b)
    return Deg(ga.num + q + gb.num, ga.den + gb.den, ga.sing + gb.sing)


def _det_deg(N):
    """det dΦ(x): entries over one denominator (:func:`jacobian_deg`)."""
    J = jacobian_deg(N)
    return Deg(N * J.num, N * J.den, J.sing)


def _modified_deg(run):
    """H + (2ε/3) ∇Hᵀ (I − εf'(x))^{-1} f for H polynomial of degree h: (I − εf')^{-1} f is
    adj/det (2(N−1) + 2, 2N), times ε∇H (h, 0), plus H: (2N + h, 2N)."""
    N, h = run.system.dim, function_deg(run.system.hamiltonian_form()[1])
    return None if h is None or h.den else Deg(2 * N + h.num, 2 * N, 2 * N)


def _measure_deg(N, m):
    """m(Φ(x)) det dΦ(x) − m(x)."""
    return None if m is None else minus(times(at(m, step_deg(N)), _det_deg(N)), m)


class Claim:
    """One kind of claim (see the module docstring)."""

    def __init__(self, name, declared, check, files):
        self.name, self.declared, self.check, self.files = name, declared, check, files


#: name -> Claim, in the order the claims are checked
REGISTRY: dict = {}


def claim(name, declared=lambda system: True, files=True):
    """Register ``check(run)`` as the claim ``name`` (``files``: a system file's ``claims`` may name it;
    otherwise only a system's own objects declare it)."""
    def register(check):
        REGISTRY[name] = Claim(name, declared, check, files)
        return check
    return register


def orbit_statement(run, what):
    """``what`` at every point of the Φ_f orbit, in the paper's certificate's wording."""
    return f"{what} at the {len(run.pts)} points of the Phi_f orbit"


def at_points(run, sides, ks=None):
    """compare(sides(k)) for k in ``ks`` (default: every point of the Φ_f orbit)."""
    ks = run.points if ks is None else ks
    return lambda: compare(run.ar, ((k, lambda k=k: sides(k)) for k in ks))


# --- closed form = definition -------------------------------------------------------


@claim("definition", lambda system: any(hasattr(fn, "definition") for fn in system.integrals().values()),
       files=False)
def definition(run):
    """I(x) = h(x, Φ(x)) along the orbit of I's own map, for every integral I that declares a
    definition h (a discrete Lagrangian: :meth:`HtildeIntegral.definition`)."""
    ar, e, K, fast = run.ar, run.e, run.steps, run.fast
    for name, fn in run.integrals.items():
        if not hasattr(fn, "definition"):
            continue
        m = fn.fld.label
        pts = run.orbit(m)

        def h(k, fn=fn, pts=pts):
            if fast is not None:
                try:
                    return fast.htilde_definition(pts[k], pts[k + 1])
                except SingularMatrix:
                    pass  # J((x+x~)/2) singular: the generic route raises the PoleError
            return fn.definition(ar, pts[k], pts[k + 1], e)

        run.add(f"integral {name} (closed form = definition)",
                f"{name}(x) {fn.definition_text.format(map=f'Phi_{m}')} at the {K} points "
                f"of the Phi_{m} orbit", at_points(run, lambda k, name=name, m=m, h=h: (run.value(name, m, k), h(k)),
                                                   range(K)), degree=lambda fn=fn: _definition_deg(run, fn))


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
    N = run.system.dim
    for name in run.system.field_names():
        run.add(*reversible(ar, name, run.map(name), run.orbit(name)),
                degree=lambda: minus(step_deg(N, step_deg(N)), X))
    pts = run.pts
    run.control("control: Phi_f applied twice returns",
                "[control, must fail] Phi_f(Phi_f(x, eps), eps) = x at the orbit points",
                lambda: compare(ar, ((k, lambda k=k: (pts[k + 2], pts[k])) for k in range(K - 1)))
                if K >= 2 else compare(ar, [(0, lambda: (run.phi.step(pts[1]), pts[0]))]),
                expected=False,
                degenerate=lambda: "the orbit is 2-periodic (Phi_f(Phi_f(x0)) = x0)"
                if run.same(run.phi.step(pts[1]), pts[0]) else None)


# --- integrals ----------------------------------------------------------------------


@claim("integrals", lambda system: bool(system.integrals()))
def integrals(run):
    ar, K = run.ar, run.steps
    for name, fn in run.integrals.items():
        for m in run.field_names:
            if run.system.claims_on_every_orbit:  # every orbit computed
                statement = f"{name}(x_k) = {name}(x_0) for k = 1..{K} along the Phi_{m} orbit"
                evaluate = at_points(run, lambda k, name=name, m=m: (run.value(name, m, k), run.value(name, m, 0)),
                                     range(1, K + 1))
            elif m == "f":
                statement = f"{name}(x_k) = {name}(x_0) for k = 1..{K} along the Phi_f orbit; {name} = {fn.text}"
                evaluate = lambda fn=fn: compare(ar, conserved_items(lambda x: fn(ar, x, run.e), run.pts))  # noqa: E731
            else:
                statement = f"{name}(y_k) = {name}(y_0) along the Phi_{m} orbit of x0"
                evaluate = lambda fn=fn, m=m: compare(ar, conserved_items(  # noqa: E731
                    lambda x: fn(ar, x, run.e), lazy_orbit(run.map(m), run.x0, K)))
            run.add(f"integral {name} conserved by Phi_{m}", statement, evaluate,
                    degree=lambda fn=fn: _conserved_deg(run, fn))
        _perturbed_point_control(run, name, fn)
        if fn.depends_on_eps:
            _eps_zero_control(run, name, fn)


def _perturbed_point_control(run, name, fn):
    if run.system.own_controls_only:  # as Run.control does, before any work
        return
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
    run.control(f"control: {name} at eps = 0 conserved", f"[control, must fail] the eps -> 0 limit of {name} "
                f"(the continuous-time quantity) is conserved along the Phi_f orbit",
                lambda: compare(ar, conserved_items(lambda x: limit(ar, x, zero), pts)), expected=False,
                degenerate=lambda: f"the eps -> 0 limit of {name} is a constant" if _constant(limit) else None)


def _constant(fn) -> bool:
    """Whether the rational function num/den does not depend on x: den ∂num/∂x_i = num ∂den/∂x_i for every i."""
    dnum, dden = fn.partials()
    return all((fn.den * a - fn.num * b).is_zero() for a, b in zip(dnum, dden))


def declared_controls(run):
    """The system's own controls (checked with every claim list): the functions it claims not
    conserved, then its :class:`~exact_khk.systems.base.Control` s, each with its own degeneracy
    rules (:meth:`~exact_khk.systems.base.System.negative_controls`)."""
    ar, e, pts, K = run.ar, run.e, run.pts, run.steps
    for name, fn in run.system.controls().items():
        run.add(f"control: {name} conserved by Phi_f",
                f"[control, must fail] {name} = {fn.text} is conserved along the Phi_f orbit",
                lambda fn=fn: compare(ar, conserved_items(lambda x: fn(ar, x, e), pts)), expected=False)
    for c in run.system.negative_controls(*((None, None) if run.point_free else (run.x0, run.eps))):
        fn, statement = c.function, c.statement
        if c.kind == "commutes":
            evaluate = lambda c=c: compare(ar, commute_points_items(  # noqa: E731
                run.phi, KahanMap(c.field, run.eps, ar), pts))
        elif c.kind == "conserved":
            evaluate = lambda c=c, fn=fn: compare(ar, conserved_items(  # noqa: E731
                lambda x: fn(ar, x, e), lazy_orbit(KahanMap(c.field, run.eps, ar), run.x0, K)))
        else:  # "perturbed": the last coordinate of x0 moved
            rel = ar.convert(PERTURBATION if ar.exact else Fraction(2, 2 ** ar.prec))
            last = pts[0][-1]
            moved = tuple(pts[0][:-1]) + (rel if ar.is_zero(last) is True else last + last * rel,)
            at_end = (lambda fn=fn: run.value(fn.name, "f", K)) if fn.name in run.integrals else \
                (lambda fn=fn: fn(ar, pts[K], e))
            evaluate = lambda fn=fn, moved=moved, at_end=at_end: compare(  # noqa: E731
                ar, [(0, lambda: (fn(ar, moved, e), at_end()))])
            statement = statement.format(how="2^-60 relative" if ar.exact else "one ulp", K=K)
        if run.progress is not None:
            run.progress(c.name)
        check = run_check(c.name, statement, ar, evaluate, False,
                          degenerate=(lambda c=c: c.degenerate(ar, pts)) if c.degenerate else None)
        why = c.moot() if c.moot is not None and check.applicable else None
        run.origin.append((None, None))
        run.checks.append(inapplicable(check, why) if why else check)


# --- Poisson tensor -----------------------------------------------------------------


@claim("poisson", lambda system: system.poisson() is not None)
def poisson(run):
    ar, e, K, pts, N, fast = run.ar, run.e, run.steps, run.pts, run.system.dim, run.fast
    P = run.system.poisson()
    if hasattr(P, "formula"):
        run.add(f"Poisson tensor {P.name} formula",
                orbit_statement(run, f"{P.name} = {P.text} equals {P.formula_text}"),
                at_points(run, lambda k: fast.Pi_sides(pts[k]) if fast is not None
                          else (run.tensor("f", k), P.formula(ar, pts[k], e))), degree=lambda: _poly(tensor_deg(P)))
    jacobi = (lambda k: fast.jacobiator(pts[k])) if fast is not None else (lambda k: P.jacobiator(ar, pts[k], e))
    if run.system.claims_on_every_orbit:  # per map, at the Poisson points run.ks
        subset = "every point" if len(run.ks) == K else f"{len(run.ks)} of the {K} points (k = {run.ks})"
        run.add(f"Poisson tensor {P.name} Jacobi identity", f"the cyclic sums of Pi_im d_m Pi_jk vanish at {subset} "
                f"of the Phi_f orbit", at_points(run, lambda k: (jacobi(k), None), run.ks),
                degree=lambda: _jacobi_deg(P))
        for m in run.orbit_maps:
            run.add(f"Poisson map Phi_{m}",
                    f"dPhi(x) Pi(x) dPhi(x)^T = Pi(Phi(x)) for Phi_{m} at {subset} of its orbit",
                    lambda m=m: compare(ar, poisson_map_sides(run, m)), degree=lambda: _poisson_map_deg(N, P))
    else:
        run.add("Poisson tensor Jacobi identity", f"the cyclic sums of Pi_im d_m Pi_jk vanish at the {K + 1} "
                f"orbit points", at_points(run, lambda k: (jacobi(k), None)), degree=lambda: _jacobi_deg(P))
        run.add("Poisson map Phi_f", f"dPhi(x) Pi(x) dPhi(x)^T = Pi(Phi(x)) at the {K} orbit points",
                lambda: compare(ar, poisson_map_items(run.phi, lambda k: P.matrix(ar, pts[k], e), pts, range(K))),
                degree=lambda: _poisson_map_deg(N, P))
    run.control("control: Jacobi identity of Pi + W", "[control, must fail] Pi + W, W = e_0^e_1 + x_1 e_1^e_2, "
                "satisfies the Jacobi identity at the orbit points",
                lambda: compare(ar, ((k, lambda k=k: (jacobiator(ar, _plus_w(ar, P, e), pts[k]), None))
                                     for k in range(K + 1))) if N >= 3 else (True, "0", ""),
                expected=False,
                degenerate=lambda: "in dimension 2 every bivector satisfies the Jacobi identity" if N < 3 else None)
    j = next((i for i in range(N) if ar.is_zero(pts[1][i] - pts[0][i]) is False), 0)
    scaled = lambda k: [[(ar.one + pts[k][j]) * t for t in row] for row in P.matrix(ar, pts[k], e)]  # noqa: E731
    run.control(f"control: (1 + x_{j}) Pi preserved", f"[control, must fail] the Kahan map preserves (1 + x_{j}) Pi "
                f"(it would make 1 + x_{j} an integral)",
                lambda: compare(ar, poisson_map_items(run.phi, scaled, pts, range(K))), expected=False)


def poisson_map_sides(run, m):
    """(k, dΦ Π(x_k) dΦᵀ vs Π(x_{k+1})) along the orbit of the map of ``m`` at the points ``run.ks``;
    with fast forms decided multiplied out by I − εf'(x) (no solve: equivalent where the step is
    defined), a failure reporting the residual of dΦ Π dΦᵀ − Π∘Φ itself."""
    phi, pts, fast = run.map(m), run.orbit(m), run.fast
    if fast is None:
        return poisson_map_items(phi, lambda k: run.tensor(m, k), pts, run.ks)
    Pz = lambda k: run.memo((m, "Pi_int", k), lambda: fast.Pi_int(pts[k]))  # noqa: E731
    Pb = lambda k: run.memo((m, "Pi_blocks", k), lambda: fast.Pi_blocks(pts[k]))  # noqa: E731

    def sides(k):
        x, y = pts[k], pts[k + 1]
        holds = fast.poisson_map_blocks(phi, x, y, Pb(k), Pb(k + 1))  # None: no block structure
        if holds is None:
            holds = fast.poisson_map_cleared(phi, x, y, Pz(k), Pz(k + 1))
        if holds:
            return (), ()
        D = fast.dPhi(phi, x, y)
        return (D * run.tensor(m, k) * D.transpose()).entries(), run.tensor(m, k + 1).entries()
    return ((k, lambda k=k: sides(k)) for k in run.ks)


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
    """Φ_f∘Φ_g = Φ_g∘Φ_f for every other field g (option ``pairs`` "all": every pair of maps, at
    the points of the Φ_f orbit)."""
    ar, pts, N = run.ar, run.pts, run.system.dim
    degree = lambda: minus(*[step_deg(N, step_deg(N))] * 2)  # noqa: E731
    names = run.system.field_names()
    for g in names[1:]:
        run.add(*commuting(ar, g, run.phi, run.map(g), pts), degree=degree)
        phi_2g = KahanMap(run.map(g).field, 2 * run.eps, ar)
        run.control(f"control: commutation with Phi_{g} at 2 eps",
                    f"[control, must fail] Phi_f(., eps) commutes with Phi_{g}(., 2 eps) at the Phi_f orbit points",
                    lambda phi_2g=phi_2g: compare(ar, commute_items(run.phi, phi_2g, pts)), expected=False)
    def image(m, k):  # Φ_m(x_k) at a point of the Φ_f orbit, memoised: every pair shares it
        return run.memo((m, "image", k), lambda: run.orbit(m)[1] if k == 0 and m in run.orbit_maps
                        else run.map(m).step(pts[k]))

    for a, b in combinations(names[1:], 2) if run.options["pairs"] == "all" else ():
        run.add(f"commutation Phi_{a} o Phi_{b}", f"Phi_{a}(Phi_{b}(x)) = Phi_{b}(Phi_{a}(x)) at the {len(pts)} "
                f"points x_k of the Phi_f orbit", lambda a=a, b=b: compare(ar, (
                    (k, lambda k=k: (run.map(a).step(image(b, k)), run.map(b).step(image(a, k))))
                    for k in run.points)), degree=degree)


# --- involution -----------------------------------------------------------------------


@claim("involution", lambda system: system.poisson() is not None and any(
    getattr(fn, "base", None) for fn in system.integrals().values()), files=False)
def involution(run):
    """{I, I_B}_J = {I, I_B}_Π = 0 and ∇I_B = B ∇I for every integral I_B declared as the
    image of I under an involution B (J the ε → 0 limit of Π; option ``brackets`` "all": the
    brackets of every pair of integrals, after the gradients); first the identity of the
    gradients of the coefficients of Π's second form, where the tensor declares one."""
    ar, pts, fast = run.ar, run.pts, run.fast
    P = run.system.poisson()
    if hasattr(P, "coefficient_sides"):
        grads = (lambda k: fast.q_gradients(pts[k])) if fast is not None else \
            (lambda k: P.coefficient_gradients(ar, pts[k]))
        run.add("gradients of q_l: grad q_l = A^l grad q_0",
                P.coefficient_statement("closed form" if fast is not None else "dual numbers", len(pts)),
                at_points(run, lambda k: P.coefficient_sides(grads(k))), degree=lambda: Deg(1, 0))
    if fast is not None:
        J = lambda k: fast.J_int(pts[k])  # noqa: E731
        Pi = lambda k: run.memo(("f", "Pi_int", k), lambda: fast.Pi_int(pts[k]))  # noqa: E731
        brk, times = fast.bracket, lambda B, g: (B * column(g)).entries()
    else:
        J, Pi = (lambda k: P.at_eps_zero(ar, pts[k])), (lambda k: run.tensor("f", k))
        brk, times = bracket, matvec
    names = list(run.integrals)
    for name, fn in run.integrals.items():
        if getattr(fn, "base", None) is None:
            continue
        B = [[ar.convert(t) for t in row] for row in run.system.involution(fn.signs, cyclotomic=True)]
        B = B if fast is None else fmpq_mat(B)
        base = fn.base
        run.add(f"integral gradients grad {name} = B grad {base}",
                orbit_statement(run, f"grad {name} = B grad {base} (exact gradients)"),
                at_points(run, lambda k, name=name, B=B, base=base: (run.gradient(name, k),
                                                                     times(B, run.gradient(base, k)))),
                degree=lambda fn=fn, base=base: _gradient_deg(run, fn, base))
        if run.options["brackets"] == "base":
            pairs = [(base, name)]
        elif name == names[-1]:  # "all": every pair of integrals, after the last one's gradients
            pairs = list(combinations(names, 2))
        else:
            continue
        for (a, b), (Q, T) in product(pairs, ((P.limit_name, J), (P.name, Pi))):
            run.add(f"involution {{{a},{b}}}_{Q}", orbit_statement(run, f"grad {a}^T {Q} grad {b} = 0"),
                    at_points(run, lambda k, a=a, b=b, T=T: (brk(run.gradient(a, k), T(k), run.gradient(b, k)), None)),
                    degree=lambda a=a, b=b, Q=Q: _bracket_deg(run, a, b, 1 if Q == P.limit_name else tensor_deg(P)))


# --- rank of the gradients ----------------------------------------------------------


@claim("rank", lambda system: bool(system.integrals()) and bool(system.gradient_ranks(get_arith("fraction"))),
       files=False)
def rank_of_gradients(run):
    """Functional independence: the gradients the system declares (``gradient_ranks``) have
    their rank r at some orbit point.  A generic statement: full rank at one point proves it,
    and the rank drops on critical sets of the integrals (an equilibrium: all gradients vanish).
    So: True with rank r somewhere, None (undecided) if nowhere, False only for a rank above r
    (impossible if the declared relations hold)."""
    ar, npts = run.ar, len(run.points)
    rank_of = flint_rank if run.fast is not None else (lambda rows: rank(ar, rows))
    for name, statement, rows, expected in run.system.gradient_ranks(ar):
        def evaluate(rows=rows, expected=expected):
            if not getattr(ar, "decides", ar.exact):
                return None, "n/a", "rank not decidable in this arithmetic"
            ranks, poles = {}, []
            for k in run.points:
                try:
                    r = rank_of(rows(lambda name, k=k: run.gradient(name, k)))
                except PoleError:
                    poles.append(k)
                    continue
                if r is None:
                    return None, "n/a", f"rank not decidable at step {k}"
                ranks[k] = r
            high = [k for k, r in ranks.items() if r > expected]
            if high:
                return False, f"rank {ranks[high[0]]}", f"rank {ranks[high[0]]} > {expected} at step {high[0]}"
            full = [k for k, r in ranks.items() if r == expected]
            low = [k for k, r in ranks.items() if r < expected]
            notes = (f"; rank below {expected} at k = {low[:8]} (critical points of the integrals)" if low else "") \
                + (f"; gradients undefined (pole) at k = {poles[:8]}" if poles else "")
            if not full:
                return None, f"rank {max(ranks.values(), default=0)}", \
                    f"rank {expected} at no orbit point (a degenerate orbit, e.g. an equilibrium){notes}"
            return True, f"rank {expected}", f"rank {expected} at {len(full)} of {npts} points{notes}"
        run.add(name, statement, evaluate)


# --- the Jacobian of the step -------------------------------------------------------


@claim("jacobian")
def jacobian(run):
    ar, K, pts, f, eps, N = run.ar, run.steps, run.pts, run.f, run.eps, run.system.dim

    def dual_step(k):
        return dual_jacobian(ar, lambda d, xd: KahanMap(f, eps, d, method="dense").step(xd), pts[k])[1]

    run.add("Jacobian of Phi_f", f"the derivative of the step (dual numbers through the solve) equals "
            f"(I - eps f'(x))^-1 (I + eps f'(Phi(x))) at the {K} orbit points",
            lambda: compare(ar, ((k, lambda k=k: (dual_step(k), run.map_jacobian(pts[k], pts[k + 1])))
                                 for k in range(K))), degree=lambda: minus(partial(step_deg(N)), jacobian_deg(N)))
    run.control("control: Jacobian with f'(x) for f'(Phi(x))",
                "[control, must fail] the derivative of the step equals (I - eps f'(x))^-1 (I + eps f'(x))",
                lambda: compare(ar, ((k, lambda k=k: (dual_step(k), run.map_jacobian(pts[k], pts[k])))
                                     for k in range(K))), expected=False,
                degenerate=lambda: "f'(Phi(x)) = f'(x) along the orbit" if all(
                    run.same(sum(f.jacobian(ar, pts[k + 1]), []), sum(f.jacobian(ar, pts[k]), []))
                    for k in range(K)) else None)


# --- Celledoni–McLachlan–Owren–Quispel: modified energy and measure -----------------


@claim("cmoq", lambda system: system.hamiltonian_form() is not None)
def cmoq(run):
    ar, e, K, pts, N = run.ar, run.e, run.steps, run.pts, run.system.dim
    _, H = run.system.hamiltonian_form()
    modified = lambda x: modified_energy(ar, run.f, H, x, e)  # noqa: E731
    run.add("CMOQ modified energy conserved", f"H~(x) = H(x) + (2 eps/3) grad H(x)^T (I - eps f'(x))^-1 f(x) "
            f"is conserved along the Phi_f orbit (k = 1..{K})", lambda: compare(ar, conserved_items(modified, pts)),
            degree=lambda: None if _modified_deg(run) is None else minus(at(_modified_deg(run), step_deg(N)),
                                                                          _modified_deg(run)))

    def det_sides(k):
        D = determinant_or_undecided(ar, run.map_jacobian(pts[k], pts[k + 1]))
        return D * _det_kahan(ar, run.f, pts[k], e), _det_kahan(ar, run.f, pts[k + 1], e)

    run.add("CMOQ invariant measure", "det dPhi(x) det(I - eps f'(x)) = det(I - eps f'(Phi(x))): the measure "
            f"dx / det(I - eps f'(x)) is preserved at the {K} orbit points",
            lambda: compare(ar, ((k, lambda k=k: det_sides(k)) for k in range(K))),
            degree=lambda: minus(times(_det_deg(N), Deg(2 * N, 0, 2 * N)), at(Deg(2 * N, 0), step_deg(N))))
    run.control("control: H conserved", "[control, must fail] the Hamiltonian H itself is conserved along the "
                "Phi_f orbit", lambda: compare(ar, conserved_items(lambda x: H(ar, x, e), pts)), expected=False)
    run.control("control: Phi_f preserves volume", "[control, must fail] det dPhi(x) = 1 at the orbit points",
                lambda: compare(ar, ((k, lambda k=k: (run.det_jacobian(k), ar.one)) for k in range(K))),
                expected=False)


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
                density(pts[k + 1]) * run.det_jacobian(k), density(pts[k]))) for k in range(K))),
            degree=lambda: _measure_deg(run.system.dim, function_deg(m)))
    run.control("control: measure with density 1 preserved",
                "[control, must fail] det dPhi(x) = 1 at the orbit points (the density 1 in place of m)",
                lambda: compare(ar, ((k, lambda k=k: (run.det_jacobian(k), ar.one)) for k in range(K))),
                expected=False, degenerate=lambda: f"the density m = {m.text} is a constant: the claim is this control"
                if hasattr(m, "partials") and _constant(m) else None)


#: the claims a system file can declare, in the order they are checked
CLAIMS = tuple(name for name, c in REGISTRY.items() if c.files)
