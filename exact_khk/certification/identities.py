"""Complete Liouville integrability of the Kahan maps, checked in any exact arithmetic.

For a system with n ≥ 2 the checked claims are (docs/conventions.md, "The integrals H̃ and K̃"):

* ``conservation``  K̃_j(Φ(x), ε) = K̃_j(x, ε) for the n integrals and every map
  Φ ∈ {Φ_f} ∪ {Φ_{g_s} : s a sign pattern ≠ ±I};
* ``commutation``   Φ∘Ψ = Ψ∘Φ for every pair of these maps (same ε);
* ``gradients``     ∇K̃_j = B_j ∇H̃ (exact gradients, :func:`~exact_khk.systems.lie_poisson.invariants.grad_Htilde`);
* ``involutivity``  {K̃_i, K̃_j} = ∇K̃_iᵀ P ∇K̃_j = 0 for P = J(x) and P = Π(x);
* ``rank``          the n gradients ∇K̃_0, …, ∇K̃_{n−1} have rank n;
* two negative controls that must fail: the control map Φ_c (Hessian A·Hs,
  (2I + A)·Hs for n = 2) commutes with Φ_f, and conserves H̃.

The integrals are K̃_j = :func:`~exact_khk.systems.lie_poisson.invariants.Htilde` of the field
g_j with involution B_j = I − 2Π_j (sign − at j only), j = 0..n−1; for n = 2,
where B_1 = −B_0, they are H̃ and K̃_1 (:func:`integral_patterns`).

Two drivers return lists of :class:`~exact_khk.certification.lie_poisson.Check`:

* :func:`liouville_at_points` — exact residuals at the points of an orbit, in
  ``cyclo:N`` (evidence "exact in Q(zeta_N)"), a rational arithmetic, or gf:P;
* :func:`liouville_identities` — Schwartz–Zippel over ``gf:P``: the same
  residuals at random points (x, ε) ∈ F_P^{2n+1}; the failure probability is
  bounded from degree bounds of the cleared identities (:func:`degree_bounds`).

>>> from exact_khk import LiePoissonSystem
>>> s = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")
>>> recs = liouville_at_points(s, ["1", "2", "-1", "1/2", "0", "1"], "1/10", "cyclo:3", steps=1)
>>> [(r.name, r.holds) for r in recs]            # doctest: +NORMALIZE_WHITESPACE
[('conservation', True), ('commutation', True), ('gradients', True), ('involutivity:J', True),
 ('involutivity:Pi', True), ('rank', True), ('control:commutation', False),
 ('control:conservation', False)]
>>> all(r.passed for r in recs), recs[0].evidence
(True, 'exact in Q(zeta_3) at 2 orbit points')
"""

from __future__ import annotations

import random
import time
from dataclasses import replace

from exact_khk.arith import get_arith
from exact_khk.arith.cyclotomic import DEFAULT_PRIME, CycloArith, GFArith
from exact_khk.errors import InputError, PoleError, SingularStepError
from exact_khk.certification.checks import inapplicable_if, rank
from exact_khk.certification.records import Check
from exact_khk.systems.lie_poisson.invariants import Htilde, Pi, grad_Htilde
from exact_khk.kahan.map import KahanMap
from exact_khk.linalg.dense import matvec
from exact_khk.parsing import format_signs, parse_signs
from exact_khk.systems.lie_poisson.system import nontrivial_sign_patterns


# --- sign patterns -----------------------------------------------------------


def involution_patterns(n: int) -> list[str]:
    """All 2^n − 2 sign patterns of involutions B ≠ ±I."""
    return nontrivial_sign_patterns(n)


def integral_patterns(n: int) -> list[str]:
    """Sign patterns of the n integrals: B_j (sign − at j only), j < n;
    for n = 2, where B_1 = −B_0, the identity ('++', i.e. H̃) and B_1.

    >>> integral_patterns(3), integral_patterns(2)
    (['-++', '+-+', '++-'], ['++', '+-'])
    """
    if n == 2:
        return ["++", "+-"]
    return ["+" * j + "-" + "+" * (n - 1 - j) for j in range(n)]


# --- all residuals at one point --------------------------------------------------

CLAIMS = {
    "conservation": "K~_j(Phi(x), eps) = K~_j(x, eps) for the n integrals and every map Phi in "
                    "{Phi_f} + {Phi_g[s]}",
    "commutation": "Phi(Psi(x)) = Psi(Phi(x)) for every pair of maps in {Phi_f} + {Phi_g[s]} (same eps)",
    "gradients": "grad K~_j = B_j grad H~ for the n integrals",
    "involutivity:J": "{K~_i, K~_j} = grad K~_i^T J(x) grad K~_j = 0 for all i < j",
    "involutivity:Pi": "{K~_i, K~_j} = grad K~_i^T Pi(x) grad K~_j = 0 for all i < j",
    "rank": "rank(grad K~_0, ..., grad K~_{n-1}) = n",
    "control:commutation": "the control map Phi_c commutes with Phi_f (must fail)",
    "control:conservation": "H~ is conserved by the control map Phi_c (must fail)",
}


def _first_nonzero(ar, items):
    """'' if every residual is zero, else 'label: value' of the first nonzero one."""
    for label, val in items:
        vals = val if isinstance(val, (list, tuple)) else [val]
        for t in vals:
            if not ar.is_zero(t):
                return f"{label}: {ar.format(t)}"
    return ""


def _patterns(system, patterns):
    if patterns is None:
        return involution_patterns(system.n)
    return [format_signs(parse_signs(p, system.n)) for p in patterns]


class _Counter:
    """``solves``: the solves of the current point (the Schwartz–Zippel bound's S);
    ``progress(done)``, if given, hears the solves of all points so far."""

    def __init__(self, progress=None):
        self.solves, self.done, self.progress = 0, 0, progress

    def add(self, k=1):
        self.solves += k
        self.done += k
        if self.progress is not None:
            self.progress(self.done)


def residuals_at(system, x, eps, ar, patterns=None, pairs="all", counter=None):
    """Residuals of every claim at one point: {claim: [(label, residual), ...]}, plus
    ``'rank'``: the rank of the n gradients.  Raises SingularStepError if some
    map or integral is undefined at x."""
    ar = get_arith(ar)
    cnt = counter if counter is not None else _Counter()
    n = system.n
    pats = _patterns(system, patterns)
    maps = {"f": KahanMap(system.field("f"), eps, ar)}
    maps.update((f"g[{s}]", KahanMap(system.field_for_signs(s), eps, ar)) for s in pats)
    maps_c = {**maps, "c": KahanMap(system.field("control"), eps, ar)}
    e = maps["f"].eps
    x = maps["f"].point(x)

    def step(a, pt, where="x"):  # Phi_a(pt), pt = ``where``; a singular step names both
        cnt.add()
        try:
            return maps_c[a].step(pt)
        except SingularStepError as exc:
            raise SingularStepError(exc.x, exc.eps, condition=exc.condition,
                                    detail=f"a step of Phi_{a} at {where} (f' is that map's field)") from None

    def integral(fld, pt, name, where="x"):  # a pole names the integral and the point
        cnt.add()
        try:
            return Htilde(fld, pt, e, ar)
        except PoleError as exc:
            raise PoleError(f"{exc}; {name} at {where}") from None

    images = {k: step(k, x) for k in maps}
    ints = [system.field_for_signs(s) for s in integral_patterns(n)]
    knames = [f"K~_{j} = K~[{s}]" for j, s in enumerate(integral_patterns(n))]
    K0 = [integral(fld, x, knames[j]) for j, fld in enumerate(ints)]
    out = {name: [] for name in CLAIMS if name != "rank"}
    for k, y in images.items():
        for j, fld in enumerate(ints):
            out["conservation"].append((f"K~_{j} o Phi_{k}", integral(fld, y, knames[j], f"Phi_{k}(x)") - K0[j]))
    names = list(maps)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            if pairs == "all" or a == "f":
                ab, ba = step(a, images[b], f"Phi_{b}(x)"), step(b, images[a], f"Phi_{a}(x)")
                out["commutation"].append((f"Phi_{a} o Phi_{b}", [p - q for p, q in zip(ab, ba)]))
    cnt.add(2 * (n + 1))
    gH = grad_Htilde(system.field("f"), x, e, ar)
    grads = [grad_Htilde(fld, x, e, ar) for fld in ints]
    for j, (s, gK) in enumerate(zip(integral_patterns(n), grads)):
        B = system.involution(s, cyclotomic=True)
        BgH = [sum((ar.convert(b) * g for b, g in zip(row, gH)), ar.zero) for row in B]
        out["gradients"].append((f"grad K~_{j} - B_{j} grad H~", [p - q for p, q in zip(gK, BgH)]))
    for label, P in (("J", system.J(x)), ("Pi", Pi(system, x, e, ar))):
        for i in range(n):
            Pg = matvec(P, grads[i])
            for j in range(i + 1, n):
                br = sum((p * q for p, q in zip(Pg, grads[j])), ar.zero)
                out[f"involutivity:{label}"].append((f"{{K~_{i}, K~_{j}}}_{label}", br))
    cf, yc = step("c", images["f"], "Phi_f(x)"), step("c", x)
    out["control:commutation"].append(("Phi_c o Phi_f - Phi_f o Phi_c",
                                       [p - q for p, q in zip(cf, step("f", yc, "Phi_c(x)"))]))
    hf = system.field("f")
    out["control:conservation"].append(("H~ o Phi_c - H~", integral(hf, yc, "H~", "Phi_c(x)")
                                        - integral(hf, x, "H~")))
    out["rank"] = rank(ar, grads)
    return out


# --- degree bounds for Schwartz–Zippel ---------------------------------------------


def degree_bounds(n: int) -> dict:
    """Upper bounds d for the total degree in (x, ε) (2n + 1 variables) of the
    numerator of each cleared identity, and D1 for any single determinant a
    trial divides by.  Derivation (Cramer's rule; '(a, b)' = degrees of
    numerator and denominator):

    * L = I − εf'(x) has entries of degree ≤ 2, so Φ = adj(L) x / det L is (4n−1, 4n);
    * R = I − ε²(M J(x))² has entries of degree ≤ 4, so H̃ = xᵀ adj(R) M x / det R is (8n−2, 8n);
    * substituting y = N/D of degrees ≤ s into (a, b) gives (m s, m s), m = max(a, b):
      H̃∘Φ is (32n², 32n²), Φ∘Ψ is (16n², 16n²);
    * a difference (a1, b1) − (a2, b2) has numerator degree ≤ max(a1 + b2, a2 + b1):
      conservation ≤ 32n² + 8n, commutation ≤ 32n²;
    * a partial derivative of (a, b) is (a + b − 1, 2b): ∇H̃ is (16n−3, 16n), so
      ∇K̃_j − B_j∇H̃ ≤ 32n − 3, and ∇K̃_iᵀ P ∇K̃_j (one denominator per factor)
      ≤ 2(16n−3) + deg P with deg J = 1, deg Π ≤ 5 (J Hs J Hs J has degree 3, ε² two more);
    * the largest matrices a trial factors are L(y) and R(y) at y = Φ(x) = N/D:
      D·L(y) has entries of degree ≤ 4n + 1 and D²·R(y) of degree ≤ 8n + 2, so
      D1 = 2n (8n + 2) bounds the degree of every determinant.

    >>> degree_bounds(3)["conservation"], degree_bounds(3)["commutation"]
    (312, 288)
    """
    return {"conservation": 32 * n * n + 8 * n, "commutation": 32 * n * n,
            "gradients": 32 * n - 3, "involutivity:J": 32 * n - 5, "involutivity:Pi": 32 * n - 1,
            "determinant": 2 * n * (8 * n + 2)}


# --- drivers -------------------------------------------------------------------------


def _field_name(ar) -> str:
    if isinstance(ar, CycloArith):
        return f"Q(zeta_{ar.N})"
    if isinstance(ar, GFArith):
        return f"F_{ar.P}"
    return "Q"


def _claims(system, patterns, pairs):
    """CLAIMS, saying how many involutions were checked and which pairs."""
    k = len(_patterns(system, patterns))
    out = dict(CLAIMS)
    for name in ("conservation", "commutation"):
        out[name] = out[name].replace("{Phi_g[s]}", f"{{Phi_g[s]}} ({k} involutions s != +-I)")
    if pairs == "f":
        out["commutation"] = f"Phi_f(Phi_g(x)) = Phi_g(Phi_f(x)) for the {k} involutions s (same eps)"
    return out


def _records(system, per_point, ar, seconds, evidence, rank_evidence, rank_rule, claims):
    """Aggregate residual dictionaries of several points into records."""
    n = system.n
    recs = []
    for name, claim in claims.items():
        if name == "rank":
            ranks = [d["rank"] for d in per_point]
            holds = rank_rule(ranks)
            recs.append(Check(name, claim, True, holds, f"ranks {ranks}, n = {n}",
                                    ar.name, seconds, rank_evidence))
            continue
        bad = next((r for r in (_first_nonzero(ar, d[name]) for d in per_point) if r), "")
        recs.append(Check(name, claim, not name.startswith("control"), not bad,
                                bad or "0", ar.name, seconds, evidence(name, bool(bad))))
    return recs


def liouville_at_points(system, x0, eps, arith="cyclo:3", steps=2, patterns=None, pairs="all", progress=None):
    """Check every claim exactly at the points x_0..x_steps of the Φ_f-orbit of x0.

    ``patterns``: the involutions whose maps are checked (default all 2^n − 2);
    ``pairs``: ``'all'`` pairs of maps commute, or ``'f'`` (Φ_f with each Φ_g);
    ``progress(k)``: called with the number of solves (Kahan steps, integrals) made so far.
    In ``cyclo:N`` (n | N) every pattern is exact; a rational arithmetic raises
    :class:`~exact_khk.errors.NotRationalError` for non-rational patterns.
    Evidence: "exact in Q(zeta_N) at K orbit points" (or Q, or F_P: a nonzero
    residual mod P refutes a claim, zero residuals mod P do not prove it).  At a degenerate
    x0 a control that held is inapplicable and a rank below n undecided (:func:`_judged`).
    """
    ar = get_arith(arith)
    if not ar.exact:
        raise InputError(f"arith: liouville_at_points needs an exact arithmetic, got {ar.name}")
    if pairs not in ("all", "f"):
        raise InputError(f"pairs: expected 'all' or 'f', got {pairs!r}")
    t0 = time.perf_counter()
    pts = KahanMap(system.field("f"), eps, ar).orbit(x0, steps)
    per_point, cnt = [], _Counter(progress)
    for k, x in enumerate(pts):
        try:
            per_point.append(residuals_at(system, x, eps, ar, patterns, pairs, cnt))
        except SingularStepError as exc:  # a map Φ_g (or Φ_c) undefined at the orbit point x_k
            raise SingularStepError(exc.x, exc.eps, condition=exc.condition,
                                    detail=f"at the orbit point x = x_{k} of Phi_f"
                                    + (f": {exc.detail}" if exc.detail else "")) from None
        except PoleError as exc:
            raise PoleError(f"{exc} (x = x_{k}, the orbit point of Phi_f)") from None
    where = f"exact in {_field_name(ar)} at {len(pts)} orbit points"
    if isinstance(ar, GFArith):
        where += " (mod P: a nonzero residual refutes, zero residuals do not prove)"
    recs = _records(system, per_point, ar, time.perf_counter() - t0, lambda name, bad: where, where,
                    lambda ranks: all(r == system.n for r in ranks), _claims(system, patterns, pairs))
    return _judged(system, x0, eps, recs)


def _judged(system, x0, eps, recs):
    """The records at orbit points judged by certify's rule (:class:`~exact_khk.systems.
    lie_poisson.controls.ControlDegeneracy`): a control that held where it cannot fail is inapplicable,
    and a rank below n at a degenerate x0 (J(x0) singular, an equilibrium) undecided."""
    from exact_khk.systems.lie_poisson.controls import ControlDegeneracy

    degenerate = ControlDegeneracy(system, x0, eps)
    why = {"control:commutation": degenerate.commutation, "control:conservation": degenerate.control_conserves}
    out = []
    for r in recs:
        if not r.expected:
            r = inapplicable_if(r, why.get(r.name))
        elif r.name == "rank" and r.holds is not True and (reason := degenerate.common()):
            r = replace(r, holds=None, detail=f"undecided: the rank drops at such points: {reason}")
        out.append(r)
    return out


def liouville_identities(system, arith=f"gf:{DEFAULT_PRIME}", trials=3, seed=0,
                         patterns=None, pairs="all", max_draws=None, progress=None):
    """Schwartz–Zippel: the claims as identities of rational functions in (x, ε).

    Draws (x, ε) uniformly from F_P^{2n+1}; a draw where ε = 0 or some map or
    integral is undefined (a singular step) is reported in the residual text and
    redrawn, not counted.  With k counted points and a claim whose cleared
    numerator has degree ≤ d (:func:`degree_bounds`), a false claim passes with
    probability ≤ (d / (P − S·D1 − 1))^k, S the number of solves of a trial and
    D1 the determinant degree bound (the conditioning on non-singular draws).
    This certifies the identity over F_P (the reduction of the Q(ω) identity at a
    prime above P); it implies the identity over Q(ω) unless P divides every
    coefficient of the cleared numerator, which one fixed P cannot exclude.
    A nonzero residual (controls) refutes a claim exactly; rank n at one point
    proves generic rank n (a nonzero minor mod P is a nonzero minor over Q(ω)).
    ``progress``: as for :func:`liouville_at_points`.

    >>> from exact_khk import LiePoissonSystem
    >>> s = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")
    >>> recs = liouville_identities(s, trials=2, seed=1)     # P = 4611686018420360881
    >>> all(r.passed for r in recs), recs[0].evidence.split(";")[0]
    (True, 'probabilistic over F_4611686018420360881 with failure bound <= 4.577e-33')
    """
    ar = get_arith(arith)
    if not isinstance(ar, GFArith):
        raise InputError(f"arith: Schwartz–Zippel checks run over gf:P, got {ar.name}")
    if not isinstance(trials, int) or trials < 1:
        raise InputError(f"trials: expected a positive integer, got {trials!r}")
    n, P = system.n, ar.P
    rng = random.Random(seed)
    t0 = time.perf_counter()
    per_point, skipped, cnt = [], [], _Counter(progress)
    draws = 0
    limit = max_draws if max_draws is not None else 10 * trials
    while len(per_point) < trials:
        if draws >= limit:
            raise InputError(f"trials: only {len(per_point)} of {trials} random points were regular "
                             f"after {draws} draws (P = {P} too small?)")
        draws += 1
        x = [rng.randrange(P) for _ in range(2 * n)]
        e = rng.randrange(P)
        if e == 0:
            skipped.append("eps = 0")
            continue
        try:
            cnt.solves = 0
            per_point.append(residuals_at(system, x, e, ar, patterns, pairs, cnt))
        except (SingularStepError, PoleError) as exc:
            skipped.append(f"singular at x = {x}, eps = {e} ({exc})")
    db = degree_bounds(n)
    slack = P - cnt.solves * db["determinant"] - 1
    k = len(per_point)
    note = f"; {len(skipped)} singular draw(s) redrawn" if skipped else ""

    def evidence(name, bad):
        if name.startswith("control") or bad:
            return f"exact refutation over F_{P}: nonzero residual at a regular point{note}"
        d = db[name]
        bound = min(1.0, d / slack) ** k if slack > 0 else 1.0  # 1: no guarantee (P too small)
        return (f"probabilistic over F_{P} with failure bound <= {bound:.4g}; {k} random points in "
                f"F_P^{2 * n + 1}, cleared numerator degree <= {d} in (x, eps), bound (d/(P - S*D1 - 1))^k "
                f"with S = {cnt.solves} solves, D1 = {db['determinant']}{note}")

    rank_ev = (f"exact over F_{P}: rank n at a random point proves generic rank n over Q(omega) "
               f"(a nonzero n x n minor mod P){note}")
    return _records(system, per_point, ar, time.perf_counter() - t0, evidence, rank_ev,
                    lambda ranks: True if n in ranks else None, _claims(system, patterns, pairs))


def cross_check_mod_p(system, x0, eps, exact_arith, gf_arith, steps=2, patterns=None,
                      integral_signs=None):
    """Orbit points of Φ_f and of every Φ_g, and the integrals K̃ (of the involutions
    ``integral_signs``, default :func:`integral_patterns`), computed in ``exact_arith``
    (Q or Q(ζ_N)) and reduced mod P equal the same computed directly in ``gf_arith``.

    Returns one :class:`~exact_khk.certification.lie_poisson.Check` (``holds`` False names the first mismatch).
    A :class:`~exact_khk.arith.cyclotomic.BadReductionError` is raised where the reduction
    is undefined (a denominator divisible by P).
    """
    ex, gf = get_arith(exact_arith), get_arith(gf_arith)
    t0 = time.perf_counter()
    pats = _patterns(system, patterns)
    fields = [system.field("f")] + [system.field_for_signs(s) for s in pats]
    ints = [system.field_for_signs(s) for s in (integral_signs or integral_patterns(system.n))]
    mismatch = ""
    for fld in fields:
        a = KahanMap(fld, eps, ex).orbit(x0, steps)
        b = KahanMap(fld, eps, gf).orbit(x0, steps)
        for k, (p, q) in enumerate(zip(a, b)):
            vals = [(f"{fld.label} step {k} coordinate {i}", s, t) for i, (s, t) in enumerate(zip(p, q))]
            vals += [(f"K~_{j}({fld.label} step {k})", Htilde(h, p, eps, ex), Htilde(h, q, eps, gf))
                     for j, h in enumerate(ints)]
            mismatch = next((f"{lab}: {ex.format(s)} -> {gf.format(gf.convert(s))} != {gf.format(t)}"
                             for lab, s, t in vals if gf.convert(s) != t), "")
            if mismatch:
                break
        if mismatch:
            break
    return Check("cross-check", f"results in {ex.name} reduced mod {gf.P} equal results in {gf.name}",
                       True, not mismatch, mismatch or "0", f"{ex.name},{gf.name}",
                       time.perf_counter() - t0,
                       f"exact: every coordinate and integral at {steps + 1} orbit points of "
                       f"{len(fields)} maps")
