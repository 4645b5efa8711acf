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

The same registry in the other modes: :func:`identity_checks` (identities over F_P at random
draws, with each claim's degree bound; ``certify --identities``, ``liouville --arith gf:P``) and
:func:`symbolic_checks` (proofs over Q(x, ε); ``certify --prove``, ``prove``).

>>> from exact_khk.systems.expressions import ExpressionSystem
>>> top = ExpressionSystem.from_expressions(["x", "y", "z"], field={"x": "y*z", "y": "-2*z*x", "z": "x*y"},
...                                         x0=["1", "2", "3"], eps="1/10")
>>> cert = certify_system(top, steps=5, claims=["reversibility"])
>>> cert.status, [c.name for c in cert.checks]
('VALID', ['reversibility Phi_f', 'control: Phi_f applied twice returns'])
"""

from __future__ import annotations

import time
from dataclasses import replace

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


def wanted_claims(system, claims=None) -> tuple:
    """The claims to check: ``claims`` (a list, or names comma-separated), else the system's own
    list, else every claim it declares something for; InputError for an unknown or undeclared one."""
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
    return wanted


def run_claims(run, wanted):
    """Check the claims ``wanted`` on ``run`` (in the system's ``claim_order``), then its own controls."""
    for name in run.system.claim_order or REGISTRY:
        if name in wanted:
            run.claim = name
            REGISTRY[name].check(run)
    run.claim = None
    declared_controls(run)


def certify_system(system, x0=None, eps=None, steps: int = 20, arith=None, claims=None,
                   progress=None, poisson_points=None, identities=None, prove=False, options=None) -> Certificate:
    """Certify what ``system`` declares on the orbit of ``x0`` (default: the system's
    own x0 and ε) in ``arith`` (default: the fastest exact arithmetic).

    ``claims``: a subset of :data:`~exact_khk.certification.claims.CLAIMS`, or its names comma-separated
    (default: the system's own list, else every claim it declares something for; ``options``: the
    claims' options, :attr:`Run.options`).  ``progress(name)``
    is called before each check.  ``poisson_points``: evaluate the Poisson-map and Jacobi checks
    at this many evenly spread orbit points (default: all).  A singular step of Φ_f or of a
    commuting map raises :class:`~exact_khk.errors.SingularStepError`.  The same claims in the other
    modes are appended: ``identities`` (a gf:P name) by :func:`identity_checks` (two draws),
    ``prove`` by :func:`symbolic_checks` (refused before any work beyond :data:`SYMBOLIC_MAX_DIM`).
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
    wanted = wanted_claims(system, claims)
    if prove:
        symbolic_limit(system)
    with ar.local():  # e.g. the working precision of a ball arithmetic
        run = Run(system, x0, eps, steps, ar, progress, poisson_points, options=options)
        run_claims(run, wanted)
        orbit = tuple(tuple(ar.format(t) for t in p) for p in run.pts)
        values = run.integral_values()
    height = max(point_height(ar, p) for m in run.orbit_maps for p in run.orbit(m)) if ar.rational else None
    checks = run.checks + other_modes(system, identities, prove, wanted, progress, options=options)
    return Certificate(system, tuple(x0), eps, steps, ar.name, (), tuple(checks), library_versions(),
                       time.perf_counter() - t_start, height, orbit, values, run.phi.path)


def other_modes(system, identities=None, prove=False, claims=None, progress=None, prove_system=None,
                options=None) -> list:
    """The records of the identity mode over ``identities`` (gf:P; two draws) and of the symbolic
    mode (``prove``; on ``prove_system`` if given), as ``certify`` appends them."""
    out = []
    if identities is not None:
        out += identity_checks(system, identities, trials=2, seed=0, claims=claims, progress=progress,
                               options=options)
    if prove:
        out += symbolic_checks(prove_system or system, claims, progress, options=options)
    return out


class Run:
    """One certification: the orbit of Φ_f, the maps and orbits of the other fields (on demand),
    the quantities the claims share at orbit points (integrals, gradients, Π; memoised, by the
    system's fast forms where it has them: :meth:`~exact_khk.systems.base.System.fast_forms`),
    and the checks appended to ``checks`` by :meth:`add`.

    It runs the claims as the system declares (:class:`~exact_khk.systems.base.System`): in its
    ``claim_order``; ``claims_on_every_orbit``: every map's orbit (``orbit_maps``) computed first (a
    singular step names its map), the claims about a map checked and stated per map;
    ``own_controls_only``: its own negative controls replace the automatic ones (:meth:`control`)."""

    def __init__(self, system, x0, eps, steps, ar, progress, poisson_points=None, point_free=False, options=None):
        self.system, self.x0, self.eps, self.steps, self.ar = system, x0, eps, steps, ar
        self.progress, self.checks, self._fixed = progress, [], None
        #: per check: (the claim it belongs to, its degree bound or None); the claim being checked
        self.origin, self.claim = [], None
        #: x0 generic (the modes: a random or a symbolic point): the controls' point-free rules only
        self.point_free = point_free
        #: the claims' options: ``pairs`` "f" (Φ_f with each other map commutes) or "all" (every pair
        #: of maps); ``brackets`` "base" ({I, I_B} for each I_B = image of I) or "all" (every pair)
        self.options = {"pairs": "f", "brackets": "base", **(options or {})}
        self.field_names = system.field_names()
        #: the maps whose orbits the claims follow: every map's, or Φ_f's alone
        self.orbit_maps = self.field_names if system.claims_on_every_orbit else ("f",)
        self.e = ar.convert(eps)
        self.f = system.named_field("f")
        self.phi = KahanMap(self.f, eps, ar)
        self._maps, self._orbits, self._dets, self._memo = {"f": self.phi}, {}, {}, {}
        for name in self.orbit_maps:
            try:
                self.orbit(name)
            except SingularStepError as exc:  # say which map (the message's f' is that map's field)
                if not system.claims_on_every_orbit:
                    raise
                raise SingularStepError(exc.x, exc.eps, step=exc.step, condition=exc.condition,
                                        detail="; ".join(filter(None, [f"a step of Phi_{name}", exc.detail]))
                                        ) from None
        self.pts = self.orbit("f")
        #: the orbit points a check at every point evaluates: x0 alone at a generic x0 (``point_free``:
        #: an identity at x0 is one at every point)
        self.points = range(1) if point_free else range(len(self.pts))
        K = steps  # the Poisson checks' points: all, or poisson_points of them evenly spread
        self.ks = list(range(K)) if poisson_points is None or poisson_points >= K else sorted(
            {round(i * (K - 1) / max(poisson_points - 1, 1)) for i in range(poisson_points)})
        self.integrals = system.integrals()
        self.fast = system.fast_forms(ar, self.e)
        self.shared = self.fast.share_integrals(self.integrals) if self.fast is not None else set()

    def add(self, name, claim, fn, expected=True, degenerate=None, degree=None):
        """Evaluate and record one check (a control: ``expected`` False, with its inapplicability rule;
        a claim: ``degree() -> Deg`` bounds its residual as a rational function of (x, ε), for the
        identity mode, :func:`~exact_khk.certification.modes.identity_checks`)."""
        self.origin.append((self.claim, degree))
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
        """Add an automatic negative control of a claim, unless the system declares that its own
        controls replace them (``own_controls_only``; the engine runs those after every claim)."""
        if not self.system.own_controls_only:
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


# --- the other modes: identities over F_P (Schwartz–Zippel) and symbolic proofs ------------

#: the largest dimension the symbolic mode takes, measured on a loaded 2-core machine: every claim
#: of the Euler top (N = 3) in 0.3 s, of the family's n = 2 (N = 4, 3 maps) in 6 s; in N = 6 the
#: Lagrange top took 10 s, but Clebsch's reversibility did not finish in 5 minutes and the
#: family's n = 3 spends 1.5 CPU minutes on H~ conserved by Phi_f alone (of dozens of such claims)
SYMBOLIC_MAX_DIM = 4


def _undefined(check) -> bool:
    """Whether a check met a pole or a singular step (its draw is then redrawn)."""
    return check.holds is None or "skipped" in check.detail or "undefined" in check.detail


def identity_checks(system, arith=None, trials=2, seed=0, claims=None, progress=None, max_draws=None,
                    options=None) -> list:
    """The registry's claims as identities of rational functions in (x, ε), by Schwartz–Zippel over
    ``arith`` = gf:P (default P = DEFAULT_PRIME): each draw (x, ε) uniform in F_P^{N+1} is a run of
    the engine with x0 = x and one step; a draw where ε = 0 or a claim meets a pole or a singular
    step is redrawn (counted in the records).  A claim's check merged over the ``trials`` draws holds
    iff its residual is zero at every one; with d its declared degree bound (``degree`` of
    :meth:`Run.add`, :class:`~exact_khk.certification.claims.Deg`) a false identity passes with
    probability ≤ (d/(P − S·D1 − 1))^k, k the draws, S the checks and D1 the largest degree of the
    denominators one check divides by (conditioning on regular draws).  A check with no bound is
    recorded as not available (undecided).  A nonzero residual refutes exactly (the controls); rank
    r at a random point proves generic rank r (a nonzero r x r minor mod P is one over Q).

    >>> from exact_khk.systems.catalogue import resolve
    >>> recs = identity_checks(resolve("euler-top"), trials=2)
    >>> all(r.passed for r in recs), recs[0].name, recs[0].evidence.split(";")[0]
    (True, 'identity: reversibility Phi_f', 'probabilistic over F_4611686018420360881 with failure bound <= 4.519e-35')
    """
    import random

    from exact_khk.arith.cyclotomic import DEFAULT_PRIME, GFArith

    ar = get_arith(arith or f"gf:{DEFAULT_PRIME}")
    if not isinstance(ar, GFArith):
        raise InputError(f"arith: Schwartz–Zippel checks run over gf:P, got {ar.name}")
    if not isinstance(trials, int) or isinstance(trials, bool) or trials < 1:
        raise InputError(f"trials: expected a positive integer, got {trials!r}")
    wanted, N, P = wanted_claims(system, claims), system.dim, ar.P
    rng, runs, singular, t0 = random.Random(seed), [], [], time.perf_counter()
    limit = max_draws if max_draws is not None else 10 * trials
    while len(runs) < trials:
        if len(runs) + len(singular) >= limit:
            raise InputError(f"trials: only {len(runs)} of {trials} random points were regular after "
                             f"{limit} draws (P = {P} too small?)")
        x, e = [rng.randrange(P) for _ in range(N)], rng.randrange(P)
        if e == 0:
            singular.append("eps = 0")
            continue
        try:
            run = Run(system, x, e, 1, ar, progress, point_free=True, options=options)
            run_claims(run, wanted)
        except (SingularStepError, PoleError) as exc:
            singular.append(str(exc))
            continue
        bad = next((c for c, (_, deg) in zip(run.checks, run.origin) if c.expected and deg and _undefined(c)), None)
        if bad is not None:
            singular.append(f"{bad.name}: {bad.detail}")
            continue
        runs.append(run)
    degs = [deg() if deg else None for _, deg in runs[0].origin]
    bounded = [d for d, c in zip(degs, runs[0].checks) if d is not None and c.expected]
    S, D1, k = len(bounded), max((d.sing for d in bounded), default=0), len(runs)
    slack = P - S * D1 - 1
    note = f"; {len(singular)} singular draw(s) redrawn (first: {singular[0][:120]})" if singular else ""
    seconds = time.perf_counter() - t0
    out = []
    for i, (first, (claim, _), d) in enumerate(zip(runs[0].checks, runs[0].origin, degs)):
        at_draws = [run.checks[i] for run in runs]
        false = next(((j, c) for j, c in enumerate(at_draws) if c.holds is False and c.applicable), None)
        if claim == "rank":
            holds = True if any(c.holds for c in at_draws) else first.holds
            evidence = (f"exact over F_{P}: rank r at a random point proves generic rank r over Q (a nonzero "
                        f"r x r minor mod P){note}")
        elif false is not None:
            j, first = false
            holds = False
            evidence = f"exact refutation over F_{P}: nonzero residual at a regular point (draw {j}){note}"
        elif not first.expected:
            holds, evidence = first.holds, f"exact over F_{P}: held at the {k} random points (x, eps){note}"
        elif d is None:
            holds, evidence = None, "not available in the identity mode: no degree bound stated for this check"
            first = replace(first, residual="n/a", detail=evidence)
        else:
            bound = min(1.0, d.num / slack) ** k if slack > 0 else 1.0  # 1: no guarantee (P too small)
            # zero residuals prove nothing where the bound is 1: undecided, never "holds"
            holds = True if all(c.holds for c in at_draws) and bound < 1.0 else None
            first = replace(first, detail=f"zero at each of the {k} draws" if holds else
                            f"zero at each of the {k} draws, but P is too small for a bound below 1: undecided"
                            if all(c.holds for c in at_draws) else first.detail)
            evidence = (f"probabilistic over F_{P} with failure bound <= {bound:.4g}; {k} random points in "
                        f"F_P^{N + 1}, cleared numerator degree <= {d.num} in (x, eps), bound (d/(P - S*D1 - 1))^k "
                        f"with S = {S} checks, D1 = {D1} (the degree of the denominators one check divides by)"
                        f"{note}")
        out.append(replace(first, name=f"identity: {first.name}", holds=holds, arith=ar.name, seconds=seconds,
                           claim=f"{first.claim} [as an identity in (x, eps): x0 random in F_P^{N}, one step]",
                           evidence=evidence))
    return out


def symbolic_limit(system) -> int:
    """The dimension of ``system``; InputError beyond :data:`SYMBOLIC_MAX_DIM`."""
    N = system.dim
    if N > SYMBOLIC_MAX_DIM:
        raise InputError(f"prove: symbolic proofs are offered up to dimension {SYMBOLIC_MAX_DIM} "
                         f"(SYMBOLIC_MAX_DIM: in dimension 6 Clebsch and the family's n = 3 take beyond minutes), "
                         f"{system.name} has dimension {N}; "
                         f"--identities checks the same claims over F_P")
    return N


def symbolic_checks(system, claims=None, progress=None, options=None) -> list:
    """The registry's claims proved as identities of rational functions: the engine run once with
    x0 = (x_0, …, x_{N−1}) and ε symbols of Q(x, ε) (:class:`~exact_khk.certification.proofs.
    RationalFunctionArith`) and one step, so ``==`` of the two sides is the identity itself.
    Refused beyond :data:`SYMBOLIC_MAX_DIM`.

    >>> from exact_khk.systems.catalogue import resolve
    >>> recs = symbolic_checks(resolve("euler-top"))
    >>> all(r.passed for r in recs), recs[0].evidence
    (True, 'symbolic proof: identity in Q(x0, x1, x2, eps)')
    """
    from exact_khk.certification.proofs import RationalFunctionArith

    N = symbolic_limit(system)
    wanted = wanted_claims(system, claims)
    ar = RationalFunctionArith([f"x{i}" for i in range(N)] + ["eps"])
    g = ar.gens()
    run = Run(system, g[:N], g[N], 1, ar, progress, point_free=True, options=options)
    run_claims(run, wanted)
    ring = f"Q({', '.join(ar.symbols)})"
    out = []
    for c, (claim, _) in zip(run.checks, run.origin):
        what = "rank over" if claim == "rank" else "identity in" if c.holds else "a nonzero difference in"
        evidence = (f"symbolic {'proof' if c.holds else 'disproof'}: {what} {ring}" if c.holds is not None
                    else f"symbolic: not decided in {ring}")
        residual = c.residual if len(c.residual) <= 300 else f"{c.residual[:300]}... ({len(c.residual)} characters)"
        out.append(replace(c, name=f"proof: {c.name}", residual=residual, evidence=evidence,
                           claim=f"{c.claim} [as an identity of rational functions in (x, eps), one step]"))
    return out
