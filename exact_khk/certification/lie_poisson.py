"""The paper's certificate of the Lie–Poisson family: :func:`certify`.

It certifies, in one arithmetic, at every orbit point (docs/conventions.md for the formulas),
through the engine (:mod:`~exact_khk.certification.engine`) and the claims of the registry
(:mod:`~exact_khk.certification.claims`, in the order of ``LiePoissonSystem.claim_order``):

* **definition** — H̃ and each K̃[s] by the closed form (tH 4) equal their definition h(x, Φ(x));
* **integrals** — each is conserved by Φ_f and by every Φ_g[s];
* **commutation** Φ_f∘Φ_g[s] = Φ_g[s]∘Φ_f; **reversibility** Φ(Φ(x, ε), −ε) = x;
* **poisson** — Π = J − ε² J Hs J Hs J equals (1 − ε²q_0)J − ε²Σ_{l≥1} q_l A^l J,
  satisfies the Jacobi identity, and dΦ Π dΦᵀ = Π∘Φ for Φ_f and every Φ_g[s];
* **involution** — ∇q_l = A^l ∇q_0; ∇K̃ = B∇H̃ and {H̃, K̃[s]} = 0 for J and for Π;
* **rank** of the gradients of the integrals the arithmetic can express, and of A^i ∇H̃ (i < n);
* **negative controls** (:func:`~exact_khk.systems.lie_poisson.controls.negative_controls`), which must
  come out False: commutation with the non-associated control field, H̃ under the control map,
  H̃ for a non-admissible Hessian, and H̃ at a point perturbed by 2^-60 (relative).

In the ``flint`` arithmetic the claims take the family's closed forms
(:class:`~exact_khk.systems.lie_poisson.flint_forms.FlintForms`, the same rationals, tested
with ``==``); other arithmetics the generic route (lists of rows, dual numbers).

Each check is a :class:`Check`; the whole is a :class:`Certificate`, valid iff
every claim holds and every control fails.  Exact arithmetics decide with
``ar.is_zero`` and report the exact residual via ``ar.format``; floating ones
only measure the largest |difference| (``holds`` is then ``None``: undecided).
Points where one side of an identity is undefined (a singular step of another
map, a pole) are skipped and listed in the check's ``detail``; a check with no
point left is undecided.

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

from exact_khk.arith import as_point, get_arith
from exact_khk.certification.engine import certify_system, other_modes, symbolic_limit
from exact_khk.errors import InputError
from exact_khk.kahan.map import KahanMap
from exact_khk.parsing import format_signs, parse_signs, parse_vector
from exact_khk.systems.lie_poisson.invariants import htilde_definition as _definition
from exact_khk.systems.lie_poisson.system import DEFAULT_EPS, DEFAULT_X0, check_signs_arith, default_system
from exact_khk.systems.lie_poisson.system import default_involutions as default_signs


def htilde_definition(field, x, eps, arith=None, x_next=None):
    """The integral by its definition: h(x, x̃) = (2ε)^{-1} xᵀ J((x+x̃)/2)^{-1} x̃,
    x̃ = Φ(x, ε) the Kahan step of ``field`` (pass ``x_next`` if already known);
    :func:`~exact_khk.systems.lie_poisson.invariants.htilde_definition`.

    >>> from exact_khk.systems.lie_poisson import default_system
    >>> from exact_khk.systems.lie_poisson.invariants import Htilde
    >>> ar = get_arith("fraction"); f = default_system().field("f")
    >>> x = [ar(t) for t in (1, 0, 0, 0, 1, 0)]
    >>> htilde_definition(f, x, "1/10", ar) == Htilde(f, x, "1/10", ar)
    True
    """
    ar = get_arith(arith)
    x = list(as_point(ar, x, field.dim))
    y = KahanMap(field, eps, ar).step(x) if x_next is None else x_next
    return _definition(field, x, y, eps, ar)


def certify(system=None, x0=None, eps=None, steps: int = 20, arith=None, signs=None,
            poisson_points=None, progress=None, identities=None, prove=False):
    """Certify the theorems on the orbit of ``x0`` (defaults: the built-in system,
    ``DEFAULT_X0``, ``DEFAULT_EPS``) in ``arith`` (default: fastest exact).

    ``signs``: involutions for the associated fields (default:
    :func:`default_signs` — the rational ones except ±I, or all but ±I when the
    arithmetic contains ω = e^{2πi/n}).  ``poisson_points``: evaluate the Poisson-map checks at this many
    evenly spread orbit points (default: all).  ``progress(name)`` is called
    before each check.  A singular step of Φ_f or Φ_g raises
    :class:`SingularStepError`.

    Further evidence, appended as checks of their own kind (the registry's claims in the engine's
    other modes, :func:`~exact_khk.certification.engine.other_modes`): ``identities`` (a ``gf:P``
    name) as identities by Schwartz–Zippel, for every involution gf:P expresses (probabilistic,
    with a stated failure bound); ``prove=True`` as symbolic proofs, for the rational involutions
    (n = 2; refused before any work for other n and for coefficients beyond :data:`PROVE_MAX_BITS`).
    """
    t_start = time.perf_counter()
    system = default_system() if system is None else system
    n = system.n
    ar = get_arith(arith)
    x0 = parse_vector(DEFAULT_X0 if x0 is None else x0, "x0", system.dim)  # the engine checks the rest
    signs = default_signs(n, ar) if signs is None else [format_signs(parse_signs(s, n)) for s in signs]
    signs = list(dict.fromkeys(signs))
    if any(s in ("+" * n, "-" * n) for s in signs):
        raise InputError("signs: ±I are not involutions of interest (K~ = ±H~); leave them out")
    check_signs_arith(n, signs, ar)
    if prove:
        prove_limits(system)
    cert = certify_system(system.with_involutions(signs), x0, DEFAULT_EPS if eps is None else eps, steps, ar,
                          progress=progress, poisson_points=poisson_points)
    rational = system.with_involutions(default_signs(n))
    checks = cert.checks + tuple(other_modes(
        system.with_involutions(default_signs(n, identities)) if identities is not None else rational,
        identities, prove, progress=progress, prove_system=rational))
    return replace(cert, system=system, signs=tuple(signs), checks=checks, seconds=time.perf_counter() - t_start)


#: the largest coefficient (bits of a numerator or denominator of a, b, c) the symbolic proofs take:
#: the rational functions grow with them (the former `prove --n 2` with a_0 = 2^b + 1: 1.9 s at
#: b = 64, 4.8 s at 512, 25 s at 2048, 67 s at 4096)
PROVE_MAX_BITS = 1024


def prove_limits(system):
    """InputError, before any work, for a system beyond the symbolic mode's reach: dimension
    (:data:`~exact_khk.certification.engine.SYMBOLIC_MAX_DIM`) or coefficients (:data:`PROVE_MAX_BITS`)."""
    symbolic_limit(system)
    bits = max(max(abs(q.numerator).bit_length(), q.denominator.bit_length())
               for q in (*system.a, *system.b, *system.c))
    if bits > PROVE_MAX_BITS:
        raise InputError(f"a, b, c: a coefficient of {bits} bits is beyond the {PROVE_MAX_BITS} bits the symbolic "
                         f"proofs take (PROVE_MAX_BITS: they grow to minutes); --identities gf:P checks the "
                         f"same claims as identities")


#: the registry's claims of complete Liouville integrability (:func:`liouville`)
LIOUVILLE_CLAIMS = ("integrals", "commutation", "involution", "rank")


def liouville(system=None, x0=None, eps=None, arith="cyclo:3", steps=2, patterns=None, pairs="all",
              trials=None, seed=0, progress=None) -> list:
    """Complete Liouville integrability: the registry's claims :data:`LIOUVILLE_CLAIMS` run by the
    engine on the family's system with the maps Φ_f and Φ_g[s] of ``patterns`` (default: all
    2^n − 2 involutions) and the integrals H̃ and K̃_j of
    :func:`~exact_khk.certification.identities.integral_patterns`, with the family's negative
    controls: conservation of every integral by every map, commutation of every pair of maps
    (``pairs='f'``: Φ_f with each Φ_g), ∇K̃ = B∇H̃ and {I, I'} = 0 for J and Π for every pair of
    integrals, and the rank of the gradients.  Exactly at the points x_0..x_steps of the Φ_f orbit
    of x0 in an exact ``arith`` (cyclo:N holds every involution for n | N), or as identities over
    gf:P (the engine's identity mode, ``trials`` random draws, default 3; x0 and ε unused).

    >>> recs = liouville(steps=1)
    >>> all(r.passed for r in recs), recs[0].name, recs[0].evidence
    (True, 'integral H~ conserved by Phi_f', 'exact in Q(zeta_3)')
    """
    from exact_khk.arith.cyclotomic import GFArith
    from exact_khk.certification.engine import identity_checks
    from exact_khk.certification.identities import integral_patterns, involution_patterns

    system = default_system() if system is None else system
    n, ar = system.n, get_arith(arith)
    patterns = involution_patterns(n) if patterns is None else [format_signs(parse_signs(p, n)) for p in patterns]
    if pairs not in ("all", "f"):
        raise InputError(f"pairs: expected 'all' or 'f', got {pairs!r}")
    check_signs_arith(n, patterns + integral_patterns(n), ar, "involutions")
    family = system.with_involutions(patterns, integrals=integral_patterns(n))
    options = {"pairs": pairs, "brackets": "all"}
    if isinstance(ar, GFArith):
        return identity_checks(family, ar, trials=3 if trials is None else trials, seed=seed,
                               claims=LIOUVILLE_CLAIMS, progress=progress, options=options)
    if not ar.exact:
        raise InputError(f"arith: liouville needs an exact arithmetic (cyclo:N, gf:P, flint, ...), got {ar.name}")
    x0 = DEFAULT_X0 if x0 is None else x0
    return list(certify_system(family, x0, DEFAULT_EPS if eps is None else eps, steps, ar, claims=LIOUVILLE_CLAIMS,
                               progress=progress, options=options).checks)
