"""The engine: runs the claim registry (:mod:`~exact_khk.certification.claims`) on one orbit.

:func:`certify_system` iterates the Kahan map Φ_f of a
:class:`~exact_khk.systems.base.System` from x0 and checks, in one arithmetic, with
``==`` for exact ones, every claim the system declares (``claims`` selects; in the
system's ``claim_order`` if it has one), then the system's own controls.  The Lie–Poisson
family's certificate (:func:`exact_khk.certification.lie_poisson.certify`) is this engine
on the family's system (:class:`Run`).  A control that cannot fail on this orbit is recorded as
inapplicable (each claim's rule, and one for all: at a fixed point of Φ_f every
control is inapplicable), and a certificate with no applicable control is
INCONCLUSIVE (:func:`~exact_khk.certification.records.status_of`).

>>> from exact_khk.systems.expressions import ExpressionSystem
>>> top = ExpressionSystem.from_expressions(["x", "y", "z"], field={"x": "y*z", "y": "-2*z*x", "z": "x*y"},
...                                         x0=["1", "2", "3"], eps="1/10")
>>> cert = certify_system(top, steps=5, claims=["reversibility"])
>>> cert.status, [c.name for c in cert.checks]
('VALID', ['reversibility Phi_f', 'control: Phi_f applied twice returns'])
"""

from __future__ import annotations

import time

from exact_khk.arith import get_arith, point_height
from exact_khk.certification.checks import inapplicable, run_check
from exact_khk.certification.claims import CLAIMS, REGISTRY, declared_controls, determinant_or_undecided
from exact_khk.certification.records import Certificate, library_versions
from exact_khk.errors import InputError, PoleError, SingularStepError
from exact_khk.kahan.map import KahanMap
from exact_khk.linalg.dense import SingularMatrix, solve
from exact_khk.parsing import parse_rational, parse_vector


def applicable_claims(system) -> tuple:
    """The claims ``system`` declares something for (reversibility and the Jacobian hold for every Kahan map)."""
    return tuple(name for name, c in REGISTRY.items() if c.declared(system))


def certify_system(system, x0=None, eps=None, steps: int = 20, arith=None, claims=None,
                   progress=None, poisson_points=None) -> Certificate:
    """Certify what ``system`` declares on the orbit of ``x0`` (default: the system's
    own x0 and ε) in ``arith`` (default: the fastest exact arithmetic).

    ``claims``: a subset of :data:`~exact_khk.certification.claims.CLAIMS`, or its names comma-separated
    (default: the system's own list, else every claim it declares something for).  ``progress(name)``
    is called before each check.  ``poisson_points``: evaluate the Poisson-map and Jacobi checks
    at this many evenly spread orbit points (default: all).  A singular step of Φ_f or of a
    commuting map raises :class:`~exact_khk.errors.SingularStepError`.
    """
    t_start = time.perf_counter()
    ar = get_arith(arith)
    x0 = parse_vector(system.default_x0 if x0 is None else x0, "x0", system.dim)
    eps = parse_rational(system.default_eps if eps is None else eps, "eps")
    if eps == 0:
        raise InputError("eps: the step size must be nonzero")
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 1:
        raise InputError(f"steps: expected a positive integer, got {steps!r}")
    if poisson_points is not None and (not isinstance(poisson_points, int) or poisson_points < 1):
        raise InputError(f"poisson_points: expected a positive integer, got {poisson_points!r}")
    known = applicable_claims(system)
    if isinstance(claims, str):  # 'integrals,reversibility', as on the command line
        claims = [c.strip() for c in claims.split(",") if c.strip()]
    wanted = tuple(claims) if claims is not None else (getattr(system, "claims", None) or known)
    if not wanted:  # a certificate of nothing would be VALID: refused
        raise InputError(f"claims: the list is empty; name some of {', '.join(known) or 'the claims'}")
    for c in wanted:
        if c not in REGISTRY:
            raise InputError(f"claims: unknown claim {c!r}; expected some of {', '.join(CLAIMS)}")
        if c not in known:
            raise InputError(f"claims: {system.name} declares nothing to check for {c!r}")
    with ar.local():  # e.g. the working precision of a ball arithmetic
        run = Run(system, x0, eps, steps, ar, progress, poisson_points)
        for name in system.claim_order or REGISTRY:
            if name in wanted:
                REGISTRY[name].check(run)
        declared_controls(run)
        orbit = tuple(tuple(ar.format(t) for t in p) for p in run.pts)
        values = run.integral_values()
    orbits = [run.orbit(m) for m in run.field_names] if run.paper else [run.pts]
    height = max(point_height(ar, p) for pts in orbits for p in pts) if ar.rational else None
    return Certificate(system, tuple(x0), eps, steps, ar.name, (), tuple(run.checks), library_versions(),
                       time.perf_counter() - t_start, height, orbit, values, run.phi.path)


class Run:
    """One certification: the orbit of Φ_f, the maps and orbits of the other fields (on demand),
    the quantities the claims share at orbit points (integrals, gradients, Π; memoised, by the
    system's fast forms where it has them: :meth:`~exact_khk.systems.base.System.fast_forms`),
    and the checks appended to ``checks`` by :meth:`add`.

    A system with a certificate of its own theorems (``certificate_options``: the paper's
    family) is run as that certificate: every map's orbit is computed first (a singular step
    names its map), its own negative controls replace the automatic controls of each claim
    (:meth:`control`), and its statements are worded as the paper's certificate words them."""

    def __init__(self, system, x0, eps, steps, ar, progress, poisson_points=None):
        self.system, self.x0, self.eps, self.steps, self.ar = system, x0, eps, steps, ar
        self.progress, self.checks, self._fixed = progress, [], None
        self.paper = bool(system.certificate_options)
        self.field_names = system.field_names()
        self.e = ar.convert(eps)
        self.f = system.named_field("f")
        self.phi = KahanMap(self.f, eps, ar)
        self._maps, self._orbits, self._dets, self._memo = {"f": self.phi}, {}, {}, {}
        for name in self.field_names if self.paper else ("f",):
            try:
                self.orbit(name)
            except SingularStepError as exc:  # say which map (the message's f' is that map's field)
                if not self.paper:
                    raise
                raise SingularStepError(exc.x, exc.eps, step=exc.step, condition=exc.condition,
                                        detail="; ".join(filter(None, [f"a step of Phi_{name}", exc.detail]))
                                        ) from None
        self.pts = self.orbit("f")
        K = steps  # the Poisson checks' points: all, or poisson_points of them evenly spread
        self.ks = list(range(K)) if poisson_points is None or poisson_points >= K else sorted(
            {round(i * (K - 1) / max(poisson_points - 1, 1)) for i in range(poisson_points)})
        self.integrals = system.integrals()
        self.fast = system.fast_forms(ar, self.e)
        self.shared = self.fast.share_integrals(self.integrals) if self.fast is not None else set()

    def add(self, name, claim, fn, expected=True, degenerate=None):
        """Evaluate and record one check (a control: ``expected`` False, with its inapplicability rule)."""
        if self.progress is not None:
            self.progress(name)
        check = run_check(name, claim, self.ar, fn, expected, degenerate)
        if not expected and check.applicable and self.fixed_point():
            check = inapplicable(check, self.fixed_point())
        self.checks.append(check)

    def fixed_point(self):
        """Why no control can fail on this orbit, or None: x0 is a fixed point of Phi_f (an
        equilibrium), so the orbit is one point, where every function is conserved."""
        if self._fixed is None:
            self._fixed = ("x0 is a fixed point of Phi_f (an equilibrium): the orbit is one point, where every "
                           "function is conserved" if self.same(self.pts[1], self.pts[0]) else "")
        return self._fixed or None

    def same(self, a, b) -> bool:
        """a == b decided exactly (False when undecided or inexact)."""
        ar = self.ar
        return getattr(ar, "decides", ar.exact) and all(ar.is_zero(s - t) is True for s, t in zip(a, b))

    def map(self, name):
        """The Kahan map of the field ``name`` at this ε."""
        if name not in self._maps:
            self._maps[name] = KahanMap(self.system.named_field(name, cyclotomic=True), self.eps, self.ar)
        return self._maps[name]

    def orbit(self, name):
        """The orbit of x0 under the map of the field ``name`` (memoised)."""
        if name not in self._orbits:
            self._orbits[name] = self.map(name).orbit(self.x0, self.steps)
        return self._orbits[name]

    def map_jacobian(self, x, y):
        """(I − εf'(x))^{-1}(I + εf'(y)): dΦ(x) for y = Φ(x)."""
        ar, e = self.ar, self.e
        A = [[(ar.one if i == j else ar.zero) - e * t for j, t in enumerate(row)]
             for i, row in enumerate(self.f.jacobian(ar, x))]
        B = [[(ar.one if i == j else ar.zero) + e * t for j, t in enumerate(row)]
             for i, row in enumerate(self.f.jacobian(ar, y))]
        try:
            return solve(ar, A, B)[0]
        except SingularMatrix:
            raise PoleError("I - eps f'(x) is singular") from None

    def det_jacobian(self, k):
        """det dΦ(x_k) (memoised: the CMOQ and measure claims share it)."""
        if k not in self._dets:
            self._dets[k] = determinant_or_undecided(self.ar, self.map_jacobian(self.pts[k], self.pts[k + 1]))
        return self._dets[k]

    def control(self, *args, **kw):
        """Add an automatic negative control of a claim, unless the system brings the controls
        of a certificate of its own (the engine runs them after every claim)."""
        if not self.paper:
            self.add(*args, **kw)

    def memo(self, key, fn):
        if key not in self._memo:
            self._memo[key] = fn()
        return self._memo[key]

    def value(self, name, m, k):
        """The integral ``name`` at point k of the orbit of the map of the field ``m``."""
        if name in self.shared:
            return self.memo((m, "I*", k), lambda: self._shared_values(m, k))[name]
        fn = self.integrals[name]
        return self.memo((m, "I", name, k), lambda: fn(self.ar, self.orbit(m)[k], self.e))

    def gradient(self, name, k):
        """The gradient of the integral ``name`` at x_k (the Φ_f orbit)."""
        if name in self.shared:
            return self.memo(("f", "grad", name, k), lambda: self._shared_gradient(name, k))
        fn = self.integrals[name]
        return self.memo(("f", "grad", name, k), lambda: fn.gradient(self.ar, self.pts[k], self.e))

    def tensor(self, m, k):
        """Π at point k of the orbit of the map of ``m`` (fast forms: an ``fmpq_mat``)."""
        x = self.orbit(m)[k]
        if self.fast is not None:
            return self.memo((m, "Pi", k), lambda: self.fast.Pi(x))
        return self.memo((m, "Pi", k), lambda: self.system.poisson().matrix(self.ar, x, self.e))

    # the fast forms' integrals: one solve per point for all of them (FlintForms.share_integrals)
    def _solutions(self, k):
        keys = list(self.shared)
        return dict(zip(keys, self.fast.htilde_solutions(self.pts[k], [self.integrals[n].fld for n in keys])))

    def _shared_values(self, m, k):
        x = self.orbit(m)[k]
        try:
            if m == "f":
                z = self.memo(("f", "z", k), lambda: self._solutions(k))[self.fast.base]
                return self.fast.integral_values(x, z)
            return self.fast.integral_values(x)
        except SingularMatrix:
            raise self.fast.pole(self.ar, x) from None

    def _shared_gradient(self, name, k):
        x = self.pts[k]
        try:
            z = self.memo(("f", "z", k), lambda: self._solutions(k))[name]
            w = self.memo(("f", "w", k), lambda: self.fast.htilde_adjoint(x))
        except SingularMatrix:
            raise self.fast.pole(self.ar, x) from None
        return self.fast.gradient(self.integrals[name].fld, x, z, w)

    def integral_values(self) -> dict:
        """{name: [I(x_k) formatted for every k], or None where I has a pole on the orbit}."""
        out = {}
        for name in self.integrals:
            try:
                out[name] = [self.ar.format(self.value(name, "f", k)) for k in range(len(self.pts))]
            except PoleError:
                out[name] = None
        return out
