"""Certification of the paper's theorems on orbits, as records (never printed here).

:func:`certify` iterates Φ_f and every associated Φ_g[s] from a point and checks,
in one arithmetic, at every orbit point (docs/conventions.md for the formulas):

* **integrals** — H̃ and each K̃[s] by the closed form (tH 4) equal their
  definition h(x, Φ(x)); each is conserved by Φ_f and by every Φ_g[s];
* **commutation** Φ_f∘Φ_g[s] = Φ_g[s]∘Φ_f; **reversibility** Φ(Φ(x, ε), −ε) = x;
* **Poisson** — Π = J − ε² J Hs J Hs J equals (1 − ε²q_0)J − ε²Σ_{l≥1} q_l A^l J,
  satisfies the Jacobi identity, and dΦ Π dΦᵀ = Π∘Φ for Φ_f and every Φ_g[s];
  ∇K̃ = B∇H̃ and ∇q_l = A^l ∇q_0;
* **involution** {H̃, K̃[s]} = 0 for J and for Π (gradients exact: by closed forms);
* **rank** of the gradients of the integrals the arithmetic can express, and of
  A^i ∇H̃ (i < n);
* **negative controls**, which must come out False: commutation with the
  non-associated control field, H̃ under the control map, H̃ for a
  non-admissible Hessian, and H̃ at a point perturbed by 2^-60 (relative).

In the ``flint`` arithmetic the matrices are python-flint ``fmpq_mat``/``fmpz_mat``
and the derivatives closed forms (:mod:`exact_khk.certification.lie_poisson_flint`:
the same rationals, tested with ``==``); the Poisson-map identity is decided
multiplied out by I − εf'(x) (no solve; a failure still reports the residual of
dΦ Π dΦᵀ − Π∘Φ), and all the integrals at a point share one solve.  Other
arithmetics use lists of rows and dual numbers.

Each check is a :class:`Check`; the whole is a :class:`Certificate`, valid iff
every claim holds and every control fails.  Exact arithmetics decide with
``ar.is_zero`` and report the exact residual via ``ar.format``; floating ones
only measure the largest |difference| (``holds`` is then ``None``: undecided).
A context can declare ``evidence`` (e.g. ``"probabilistic"``) and ``decides``
(its ``is_zero`` is rigorous although it is not exact, as for balls).  Points
where one side of an identity is undefined (a singular step of another map, a
pole) are skipped and listed in the check's ``detail``; a check with no point
left is undecided.

>>> cert = certify(steps=3, signs=["-++"])
>>> cert.valid, cert.arith
(True, 'flint')
>>> [c.holds for c in cert.checks if c.name.startswith("control:")]
[False, False, False, False]
>>> cert.check("commutation Phi_f o Phi_g[-++]").residual
'0'
"""

from __future__ import annotations

import time
from dataclasses import replace
from fractions import Fraction

from exact_khk.arith import as_point, get_arith, point_height
from exact_khk.linalg.dual import jacobian
from exact_khk.certification.checks import (bracket, commute_points_items, compare, conserved_items, inapplicable,
                                            lazy_orbit, poisson_map_items, rank, run_check)
from exact_khk.certification.proofs import PROVE_MAX_N
from exact_khk.certification.records import Certificate, library_versions
from exact_khk.errors import InputError, PoleError, SingularStepError
from exact_khk.systems.lie_poisson.invariants import (Htilde, Pi, Pi_from_q, _eps, grad_Htilde,
                         q_coefficients, shift_index)
from exact_khk.systems.lie_poisson.invariants import _pole as htilde_pole
from exact_khk.kahan.map import KahanMap
from exact_khk.certification.lie_poisson_flint import FlintForms
from exact_khk.certification.claims import commuting, reversible
from exact_khk.certification.controls import ControlDegeneracy, non_admissible_hessian  # noqa: F401
from exact_khk.linalg.flintmat import column, fmpq_mat, uses_flint
from exact_khk.linalg.flintmat import rank as flint_rank
from exact_khk.linalg.dense import SingularMatrix, matvec, solve
from exact_khk.parsing import format_signs, parse_rational, parse_signs, parse_vector
from exact_khk.systems.lie_poisson.system import (DEFAULT_EPS, DEFAULT_X0, check_signs_arith, default_system,
                                                  divisor_classes, expresses_omega, is_rational_pattern)
from exact_khk.systems.lie_poisson.system import default_involutions as default_signs

#: relative size of the perturbation of the last coordinate of x0 in the
#: "perturbed point" control, for exact arithmetics (floating ones use one ulp)
PERTURBATION = Fraction(1, 2 ** 60)



# --- the certificate ------------------------------------------------------------


def htilde_definition(field, x, eps, arith=None, x_next=None):
    """The integral by its definition: h(x, x̃) = (2ε)^{-1} xᵀ J((x+x̃)/2)^{-1} x̃,
    x̃ = Φ(x, ε) the Kahan step of ``field`` (pass ``x_next`` if already known).

    Raises :class:`PoleError` where J((x+x̃)/2) is singular (for instance on every
    orbit with Σ u_i = 0, an invariant hyperplane of the Kahan map, where J is singular).

    >>> from exact_khk.systems.lie_poisson import default_system
    >>> from exact_khk.systems.lie_poisson.invariants import Htilde
    >>> ar = get_arith("fraction"); f = default_system().field("f")
    >>> x = [ar(t) for t in (1, 0, 0, 0, 1, 0)]
    >>> htilde_definition(f, x, "1/10", ar) == Htilde(f, x, "1/10", ar)
    True
    """
    ar = get_arith(arith)
    e = _eps(ar, eps)
    x = list(as_point(ar, x, field.dim))
    y = list(KahanMap(field, e, ar).step(x) if x_next is None else as_point(ar, x_next, field.dim, "x_next"))
    half = ar.one / ar.convert(2)
    m = [(a + b) * half for a, b in zip(x, y)]
    with ar.local():
        try:
            z, _ = solve(ar, field.system.J(m), [[t] for t in y])
        except SingularMatrix:
            raise PoleError("h(x, x~) is undefined: J((x+x~)/2) is singular at x = ("
                            + ", ".join(ar.format(t) for t in x) + ")") from None
    return sum((a * r[0] for a, r in zip(x, z)), ar.zero) / (e + e)


def expressible_rank(n: int, signs) -> int:
    """Dimension of the span of I and the involutions ``signs`` (= rank of their sign vectors)."""
    ar = get_arith("fraction")
    rows = [[Fraction(1)] * n] + [[Fraction(v) for v in parse_signs(s, n)] for s in signs]
    return rank(ar, rows)


class _Orbit:
    """A Kahan map, its orbit and memoised quantities along it."""

    def __init__(self, field, eps, ar, x0, steps):
        self.phi = KahanMap(field, eps, ar)
        self.pts = self.phi.orbit(x0, steps)
        self._memo = {}

    def memo(self, key, fn):
        if key not in self._memo:
            self._memo[key] = fn()
        return self._memo[key]


def _poisson_points(steps, poisson_points):
    if poisson_points is None or poisson_points >= steps:
        return list(range(steps))
    return sorted({round(i * (steps - 1) / max(poisson_points - 1, 1)) for i in range(poisson_points)})


def certify(system=None, x0=None, eps=None, steps: int = 20, arith=None, signs=None,
            poisson_points=None, progress=None, identities=None, prove=False) -> Certificate:
    """Certify the theorems on the orbit of ``x0`` (defaults: the built-in system,
    ``DEFAULT_X0``, ``DEFAULT_EPS``) in ``arith`` (default: fastest exact).

    ``signs``: involutions for the associated fields (default:
    :func:`default_signs` — the rational ones except ±I, or all but ±I when the
    arithmetic contains ω = e^{2πi/n}).  ``poisson_points``: evaluate the Poisson-map checks at this many
    evenly spread orbit points (default: all).  ``progress(name)`` is called
    before each check.  A singular step of Φ_f or Φ_g raises
    :class:`SingularStepError`.

    Further evidence, appended as checks of their own kind: ``identities`` (a
    ``gf:P`` name) adds the Schwartz–Zippel identity checks of
    :func:`exact_khk.certification.identities.liouville_identities` for every involution
    (probabilistic, with a stated failure bound); ``prove=True`` adds the
    symbolic proofs of :func:`exact_khk.certification.proofs.prove_all` (n = 2 in
    seconds, n = 3 in minutes; refused before any work for other n).
    """
    t_start = time.perf_counter()
    system = default_system() if system is None else system
    n = system.n
    ar = get_arith(arith)
    x0 = parse_vector(DEFAULT_X0 if x0 is None else x0, "x0", system.dim)
    eps = parse_rational(DEFAULT_EPS if eps is None else eps, "eps")
    if eps == 0:
        raise InputError("eps: the step size must be nonzero")
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 1:
        raise InputError(f"steps: expected a positive integer, got {steps!r}")
    if poisson_points is not None and (not isinstance(poisson_points, int) or poisson_points < 1):
        raise InputError(f"poisson_points: expected a positive integer, got {poisson_points!r}")
    signs = default_signs(n, ar) if signs is None else [format_signs(parse_signs(s, n)) for s in signs]
    signs = list(dict.fromkeys(signs))
    if any(s in ("+" * n, "-" * n) for s in signs):
        raise InputError("signs: ±I are not involutions of interest (K~ = ±H~); leave them out")
    check_signs_arith(n, signs, ar)
    if prove and not 2 <= n <= PROVE_MAX_N:
        raise InputError(f"prove: symbolic proofs are available for n = 2 and 3 only (got n = {n})")
    with ar.local():  # e.g. the working precision of a ball arithmetic
        checks, heights, (orbit, values, path) = _run_checks(system, x0, eps, steps, ar, signs,
                                                             poisson_points, progress)
    if identities is not None:
        from exact_khk.certification.identities import liouville_identities

        if progress is not None:
            progress("identities (Schwartz–Zippel)")
        checks += [replace(r, name=f"identity: {r.name}")
                   for r in liouville_identities(system, identities, trials=2, seed=0)]
    if prove:
        from exact_khk.certification.proofs import prove_all

        checks += prove_all(system, progress)
    return Certificate(system, tuple(x0), eps, steps, ar.name, tuple(signs), tuple(checks),
                       library_versions(), time.perf_counter() - t_start, heights,
                       orbit=orbit, values=values, path=path)


def _run_checks(system, x0, eps, steps, ar, signs, poisson_points, progress):
    """The checks of :func:`certify` (arguments already validated), the orbit height, and
    the record (orbit, values, path): the Phi_f orbit as strings, the integrals' values
    along it (memoised by the checks; None for an integral with a pole on the orbit)
    and how its steps were solved."""
    n = system.n
    fields = {"f": system.field("f")} | {s: system.field("g", s, cyclotomic=True) for s in signs}
    integral = {"f": "H~"} | {s: f"K~[{s}]" for s in signs}
    mapname = {"f": "Phi_f"} | {s: f"Phi_g[{s}]" for s in signs}
    orbits = {}
    for key, fld in fields.items():
        try:
            orbits[key] = _Orbit(fld, eps, ar, x0, steps)
        except SingularStepError as exc:  # say which map (the message's f' is that map's field)
            raise SingularStepError(exc.x, exc.eps, step=exc.step, condition=exc.condition,
                                    detail="; ".join(filter(None, [f"a step of {mapname[key]}", exc.detail]))
                                    ) from None
    F = orbits["f"]
    npts = steps + 1
    checks = []
    # flint: the matrices as fmpq_mat and the derivatives by closed forms (lie_poisson_flint);
    # every other arithmetic: lists of rows and dual numbers
    fast = FlintForms(system, _eps(ar, eps)) if uses_flint(ar) else None

    def add(name, claim, fn, expected=True, degenerate=None, moot=None):
        """``moot()``: why the control shows nothing here even if it fails (then inapplicable)."""
        if progress is not None:
            progress(name)
        check = run_check(name, claim, ar, fn, expected, degenerate=degenerate)
        why = moot() if moot is not None and check.applicable else None
        checks.append(inapplicable(check, why) if why else check)

    def add_eq(name, claim, ks, sides, expected=True):  # sides(k) -> (lhs, rhs) at point k
        add(name, claim, lambda: compare(ar, ((k, lambda k=k: sides(k)) for k in ks)), expected)

    # flint: the integrals that are x^T B z with one z = R^-1 Hs x per point (lie_poisson_flint)
    shared = fast.share_integrals({key: (fld, None if key == "f" else system.involution(key))
                                   for key, fld in fields.items()
                                   if key == "f" or is_rational_pattern(n, key)}) if fast is not None else set()

    def shared_values(orb, k):
        try:
            if orb is F:
                return fast.integral_values(orb.pts[k], F.memo(("z", k), lambda: shared_solutions(k))["f"])
            return fast.integral_values(orb.pts[k])
        except SingularMatrix:
            raise htilde_pole(ar, list(orb.pts[k]), fast.eps) from None

    def value(key, orb, k):  # integral `key` at point k of orbit `orb`
        if key in shared:
            return orb.memo(("I*", k), lambda: shared_values(orb, k))[key]
        return orb.memo(("I", key, k), lambda: Htilde(fields[key], orb.pts[k], eps, ar))

    def grad(key, k):  # gradient of integral `key` at point k of the f-orbit
        if key in shared:
            return F.memo(("grad", key, k), lambda: shared_gradient(key, k))
        return F.memo(("grad", key, k), lambda: grad_Htilde(fields[key], F.pts[k], eps, ar))

    def shared_solutions(k):  # flint: z_key = R^-1 M_key x for every shared key at point k of the f-orbit
        keys = list(shared)
        return dict(zip(keys, fast.htilde_solutions(F.pts[k], [fields[key] for key in keys])))

    def shared_gradient(key, k):  # flint: each z_key solved from M_key, w shared (lie_poisson_flint)
        x = F.pts[k]
        try:
            z = F.memo(("z", k), lambda: shared_solutions(k))[key]
            w = F.memo(("w", k), lambda: fast.htilde_adjoint(x))
        except SingularMatrix:
            raise htilde_pole(ar, list(x), fast.eps) from None
        return fast.gradient(fields[key], x, z, w)

    def Pi_at(orb):  # Π at point k of the orbit: an fmpq_mat with flint, else a list of rows
        if fast is not None:
            return lambda k: orb.memo(("Pi", k), lambda: fast.Pi(orb.pts[k]))
        return lambda k: orb.memo(("Pi", k), lambda: Pi(system, orb.pts[k], eps, ar))

    def q_grads(k):  # ∇q_l at point k of the f-orbit, l = 0..n-1
        if fast is not None:
            return fast.q_gradients(F.pts[k])
        return jacobian(ar, lambda d, xd: q_coefficients(system, xd, d), F.pts[k])[1]

    def Pi_sides(k):  # Π by its definition and by the q_l formula at point k of the f-orbit
        if fast is not None:
            return fast.Pi_sides(F.pts[k])
        return Pi_at(F)(k), Pi_from_q(system, F.pts[k], eps, ar)

    def jacobi_at(k):
        if fast is not None:
            return fast.jacobiator(F.pts[k])
        return system.poisson().jacobiator(ar, F.pts[k], eps)  # the tensor the system declares

    def poisson_map(orb):
        if fast is None:
            return poisson_map_items(orb.phi, Pi_at(orb), orb.pts, ks)
        P = Pi_at(orb)
        Pz = lambda k: orb.memo(("Pi_int", k), lambda: fast.Pi_int(orb.pts[k]))  # noqa: E731
        Pb = lambda k: orb.memo(("Pi_blocks", k), lambda: fast.Pi_blocks(orb.pts[k]))  # noqa: E731

        def sides(k):
            # decided as (I + eps f'(y)) Pi(x) (I + eps f'(y))^T = (I - eps f'(x)) Pi(y) (I - eps f'(x))^T
            # (y = Phi(x)), equivalent because I - eps f'(x) is invertible where the step is defined;
            # if it fails, the residual reported is that of dPhi Pi dPhi^T = Pi(y) itself
            x, y = orb.pts[k], orb.pts[k + 1]
            holds = fast.poisson_map_blocks(orb.phi, x, y, Pb(k), Pb(k + 1))  # None: no block structure
            if holds is None:
                holds = fast.poisson_map_cleared(orb.phi, x, y, Pz(k), Pz(k + 1))
            if holds:
                return (), ()
            D = fast.dPhi(orb.phi, x, y)
            return (D * P(k) * D.transpose()).entries(), P(k + 1).entries()
        return ((k, lambda k=k: sides(k)) for k in ks)

    def J_at(k):  # J at point k of the f-orbit (flint: J(ξ) and d with x = ξ/d)
        if fast is not None:
            return fast.J_int(F.pts[k])
        return system.J(list(F.pts[k]))

    def Pi_for_bracket(k):
        if fast is not None:
            return F.memo(("Pi_int", k), lambda: fast.Pi_int(F.pts[k]))
        return Pi_at(F)(k)

    def brk(g1, P, g2):  # {F, G}_P = ∇Fᵀ P ∇G
        if fast is not None:
            return fast.bracket(g1, P, g2)
        return bracket(g1, P, g2)

    def involution_times(B, g):  # B ∇H~
        if fast is not None:
            return (B * column(g)).entries()
        return matvec(B, g)

    def rank_of(rows_):
        if fast is not None:
            return flint_rank(rows_)
        return rank(ar, rows_)

    # 1. integrals: closed form = definition; conservation by every map
    def definition(key, orb, k):  # h(x_k, x_k+1) of the integral `key` along its orbit
        if fast is not None:
            try:
                return fast.htilde_definition(orb.pts[k], orb.pts[k + 1])
            except SingularMatrix:
                pass  # J((x+x~)/2) singular: the generic route raises the PoleError
        return htilde_definition(fields[key], orb.pts[k], eps, ar, orb.pts[k + 1])

    for key, orb in orbits.items():
        add_eq(f"integral {integral[key]} (closed form = definition)",
               f"{integral[key]}(x) by (tH 4) equals h(x, {mapname[key]}(x)) = (2 eps)^-1 x^T J((x+x~)/2)^-1 x~ "
               f"at the {steps} points of the {mapname[key]} orbit",
               range(steps), lambda k, key=key, orb=orb: (
                   value(key, orb, k), definition(key, orb, k)))
    for ikey in orbits:
        for mkey, orb in orbits.items():
            add_eq(f"integral {integral[ikey]} conserved by {mapname[mkey]}",
                   f"{integral[ikey]}(x_k) = {integral[ikey]}(x_0) for k = 1..{steps} along the {mapname[mkey]} orbit",
                   range(1, npts), lambda k, ikey=ikey, orb=orb: (value(ikey, orb, k), value(ikey, orb, 0)))
    # 2. commutation, 3. reversibility
    for s in signs:
        add(*commuting(ar, f"g[{s}]", F.phi, orbits[s].phi, F.pts))
    for key, orb in orbits.items():
        add(*reversible(ar, "f" if key == "f" else f"g[{key}]", orb.phi, orb.pts))
    # 4. Poisson structure
    ks = _poisson_points(steps, poisson_points)
    subset = "every point" if len(ks) == steps else f"{len(ks)} of the {steps} points (k = {ks})"
    add_eq("Poisson tensor Pi formula",
           f"Pi = J - eps^2 J Hs J Hs J equals (1 - eps^2 q_0) J - eps^2 sum_(l>=1) q_l A^l J at the {npts} "
           f"points of the Phi_f orbit",
           range(npts), Pi_sides)
    add_eq("Poisson tensor Pi Jacobi identity",
           f"the cyclic sums of Pi_im d_m Pi_jk vanish at {subset} of the Phi_f orbit",
           ks, lambda k: (jacobi_at(k), None))
    for key, orb in orbits.items():
        add(f"Poisson map {mapname[key]}",
            f"dPhi(x) Pi(x) dPhi(x)^T = Pi(Phi(x)) for {mapname[key]} at {subset} of its orbit",
            lambda orb=orb: compare(ar, poisson_map(orb)))
    # 5. gradients and involution
    add_eq("gradients of q_l: grad q_l = A^l grad q_0",
           f"the exact gradients ({'closed form' if fast is not None else 'dual numbers'}) of "
           f"q_l = tr((A^T)^l (J Hs)^2)/(2n) satisfy grad q_l = "
           f"A^l grad q_0 at the {npts} points of the Phi_f orbit",
           range(npts), lambda k: (lambda g: (g[1:], [[g[0][i] for i in shift_index(n, l)]
                                                      for l in range(1, n)]))(q_grads(k)))
    for s in signs:
        B = [[ar.convert(t) for t in row] for row in system.involution(s, cyclotomic=True)]
        B = B if fast is None else fmpq_mat(B)
        add_eq(f"integral gradients grad K~[{s}] = B grad H~",
               f"grad K~[{s}] = B grad H~ (exact gradients) at the {npts} points of the Phi_f orbit",
               range(npts), lambda k, s=s, B=B: (grad(s, k), involution_times(B, grad("f", k))))
        add_eq(f"involution {{H~,K~[{s}]}}_J",
               f"grad H~^T J grad K~[{s}] = 0 at the {npts} points of the Phi_f orbit",
               range(npts), lambda k, s=s: (brk(grad("f", k), J_at(k), grad(s, k)), None))
        add_eq(f"involution {{H~,K~[{s}]}}_Pi",
               f"grad H~^T Pi grad K~[{s}] = 0 at the {npts} points of the Phi_f orbit",
               range(npts), lambda k, s=s: (brk(grad("f", k), Pi_for_bracket(k), grad(s, k)), None))
    # 6. independence
    r_expr = expressible_rank(n, signs)
    n_rational = len(divisor_classes(n))
    over = (f"all n = {n} integrals are expressible in {ar.name}" if expresses_omega(ar, n) or n_rational == n
            else f"over Q only {n_rational} of the n = {n} integrals are expressible (the others need Q(omega))")

    def rank_fn(rows_at, expected):
        # Functional independence is a generic statement: full rank at one point proves it,
        # and the rank drops on critical sets of the integrals (an equilibrium: all gradients
        # vanish).  So: True with full rank somewhere, None (undecided) if nowhere, False only
        # for a rank above the dimension of the span (impossible if grad K~ = B grad H~).
        def fn():
            if not getattr(ar, "decides", ar.exact):
                return None, "n/a", "rank not decidable in this arithmetic"
            ranks, poles = {}, []
            for k in range(npts):
                try:
                    r = rank_of(rows_at(k))
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
        return fn

    add(f"rank of integral gradients ({', '.join(integral.values())})",
        f"the gradients of the {len(integral)} integrals expressible here have rank {r_expr} "
        f"(the dimension of their span: functional independence, proved by one orbit point of full rank; "
        f"the rank may drop at critical points) on the Phi_f orbit; {over}",
        rank_fn(lambda k: [grad(key, k) for key in orbits], r_expr))
    add("rank of integral gradients A^i grad H~ (i < n)",
        f"the gradients A^i grad H~ (i = 0..{n - 1}) of the n integrals H~_i have full rank n = {n} "
        f"(functional independence, proved by one orbit point of full rank) on the Phi_f orbit",
        rank_fn(lambda k: [[grad("f", k)[s] for s in shift_index(n, i)] for i in range(n)], n))
    # 7. negative controls (each with the degenerate sets where it cannot fail:
    # there it is recorded as inapplicable, see ControlDegeneracy)
    ctrl = system.field("control")
    phi_c = KahanMap(ctrl, eps, ar)
    degen = ControlDegeneracy(system, x0, eps)
    add("control: commutation with non-associated field",
        f"[control, must fail] Phi_f commutes with the Kahan map of the control field "
        f"({'A Hs' if n >= 3 else '(2I + A) Hs'}) at the points of the Phi_f orbit",
        lambda: compare(ar, commute_points_items(F.phi, phi_c, F.pts)), expected=False,
        degenerate=degen.commutation)
    add("control: integral H~ conserved by Phi_control",
        "[control, must fail] H~ is conserved along the orbit of the control map",
        lambda: compare(ar, conserved_items(lambda x: Htilde(fields["f"], x, eps, ar),
                                            lazy_orbit(phi_c, x0, steps))), expected=False,
        degenerate=degen.control_conserves)
    bad_field = system.field_from_hessian(non_admissible_hessian(system), "non-admissible")
    add("control: integral H~ conserved for a non-admissible Hessian",
        "[control, must fail] with " + ("Hs[0][0]" if n >= 3 else "Hs[0][2] = Hs[2][0]") + " raised by 1 "
        "(block X(" + ("a" if n >= 3 else "b") + ") not cyclic Hankel), the closed "
        "form H~ is conserved by the Kahan map of J(x) Hs' x",
        lambda: compare(ar, conserved_items(lambda x: Htilde(bad_field, x, eps, ar),
                                            lazy_orbit(KahanMap(bad_field, eps, ar), x0, steps))),
        expected=False, degenerate=degen.non_admissible)
    rel = ar.convert(PERTURBATION if ar.exact else Fraction(2, 2 ** ar.prec))
    how = "2^-60 relative" if ar.exact else "one ulp"
    add("control: integral H~ at a perturbed point",
        f"[control, must fail] H~ at x0 with its last coordinate perturbed by {how} equals "
        f"H~(x_{steps}) on the orbit",
        lambda: compare(ar, [(0, lambda: (Htilde(fields["f"], _perturb(ar, F.pts[0], rel), eps, ar),
                                          value("f", F, steps)))]), expected=False,
        degenerate=lambda: degen.perturbed(F.pts[steps], ar), moot=degen.equilibrium)
    values = {}
    for key in orbits:
        try:
            values[integral[key]] = [ar.format(value(key, F, k)) for k in range(npts)]
        except PoleError:
            values[integral[key]] = None
    record = (tuple(tuple(ar.format(t) for t in p) for p in F.pts), values, F.phi.path)
    return checks, orbit_height(ar, [p for orb in orbits.values() for p in orb.pts]), record


def orbit_height(ar, pts):
    """Largest bit length of a numerator or denominator on the points (None unless
    the arithmetic is exact and rational)."""
    return max(point_height(ar, p) for p in pts) if ar.rational else None


def _perturb(ar, x, rel):
    """x with its last coordinate multiplied by (1 + rel) (set to rel if it is 0)."""
    last = x[-1]
    new = rel if ar.is_zero(last) is True else last + last * rel
    return tuple(x[:-1]) + (new,)
