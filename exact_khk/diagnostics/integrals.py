"""Integral discovery from orbits: the Hirota–Kimura-basis method (Petrera–Pfadler–Suris).

**Kernels.**  Given candidate monomials φ_1, …, φ_m (all monomials of degree ≤ D,
or a user list) and an orbit x_k = Φ^k(x_0), the *orbit kernel*
K(x_0) = {c : Σ_j c_j φ_j(x_k) = 0 for all k} is the space of polynomials in the
span that vanish on the orbit.  A conserved I = N/D with N, D in the span gives
N − I(x_0) D ∈ K(x_0); so does every multiple x_j·P of a kernel polynomial P
that stays in the span ('trivial' vectors: T = Σ_j x_j·(K ∩ span S_j),
S_j = {φ : x_j φ ∈ span}).  K(x_0) is computed over F_p as the nullspace of the
(orbit length) × m evaluation matrix (python-flint ``nmod_mat``), for several
orbits and primes.

**Integrals.**  The kernels of a few generic orbits are found modulo several
primes and lifted to Q by Chinese remaindering and rational reconstruction
(canonical bases; more primes until a prime not used for the lift confirms
it).  With W = Σ_i K(x_i), :mod:`.pencils` writes the integrals as ratios of
kernel polynomials when W has one common denominator (dim W = dim K + 1) or
consists of independent pencils N_a − h_a D_a (dim W = 2 dim K; pencils
conjugate over a number field give rational symmetric functions).  Each is
reported only after an exact check (rational arithmetic) that it is conserved
on a fresh orbit not used to find it; ``independent`` is the rank of their
Jacobian at a random rational point.  In degree mode the table ``by_degree``
gives dim K ∩ span(degree ≤ D) and the *new* directions (not in
K_{D-1} + Σ_j x_j K_{D-1}); integrals are extracted at the lowest degree with a
kernel, and new directions at a higher degree D from the candidates
{1} ∪ {degree exactly D}, which hold no product of a lower-degree kernel
polynomial with a non-constant monomial.

**Every integral the kernel shows** (:mod:`.fitting`): the integrals above are reduced to an
independent set (exact Jacobian rank at a rational point; a power or product of kept ones is
named in a note), the number the kernel shows is the rank of its entries' Jacobian mod p, and
entries of sparse kernel vectors that are not functions of those kept are fitted as N/D
(coefficients may be polynomial in one kept integral or in all of them), checked exactly on a
fresh orbit and kept only if they raise the exact rank (``Job.complete``).  With a linear
integral L found, the sparse vectors of the kernel of the candidates free of one variable of L
come first: on L = c they hold the other integrals without the products (L − c)·φ.

**Where it cannot conclude** (``warnings`` and ``notes``):

* orbit too short — fewer points than candidates + margin, or the rank of the
  evaluation matrix still grew in the last ``margin`` rows (then K is too big);
* an orbit on a smaller invariant set — a periodic orbit mod p, or a kernel
  larger than that of other random orbits (the generic dimension is the
  minimum over orbits; larger ones are flagged and not used);
* trivial vectors, or a span W of another shape (mixed denominators,
  hyperplane-type relations) — the kernel dimensions are reported, the
  integrals are not written as formulas;
* lift unstable or the exact check failing — the integral is not reported.

>>> from exact_khk.systems.expressions import ExpressionSystem
>>> euler = ExpressionSystem.from_expressions(["x", "y", "z"], field=["y*z", "-2*x*z", "x*y"])
>>> res = find_integrals(euler, degree=2, eps="1/10")
>>> res.kernel_dim, res.trivial_dim, len(res.integrals), res.independent
(2, 0, 2, 2)
"""

from __future__ import annotations

import math
import random
import time
from dataclasses import dataclass, field as dc_field
from fractions import Fraction
from math import comb

import flint

from exact_khk.diagnostics.degrees import check_primes, eps_of, random_primes, resolve_field
from exact_khk.diagnostics.fitting import (MAX_FIT_UNKNOWNS, MAX_PLAIN_FIT_UNKNOWNS, EntryFitter, FitCache,
                                           FitTooLarge, circuits, entry_jacobian, entry_line, orbit_with_tangents,
                                           rank_mod)
from exact_khk.diagnostics.hkbases import hk_basis_integrals
from exact_khk.diagnostics.kernels import (_point, _rref_rows, by_degree, independent_count, jacobian_rows, lift,
                                           monomial_text, monomials, orbit_kernel_mod, parse_monomials, poly_text,
                                           trivial_dim, KernelTooLarge, kernel_bytes)
from exact_khk.diagnostics.pencils import (canonical_pair, echelon_pencil, interpolated_pencils,
                                           pencil_integrals, ratio_integrals)
from exact_khk.errors import InputError, PoleError, SingularStepError
from exact_khk.parsing import any_int_digits, check_progress, check_count, parse_vector

#: candidates at most: 20 variables at degree <= 4 (10 626) measured, one orbit kernel 293 s CPU and
#: 2.3 GB peak (docs/benchmarks.md, "find-integrals at 10⁴ candidates")
MAX_MONOMIALS = 11_000
#: the highest degree of a fitted numerator or denominator (:mod:`.fitting`; --fit-degree)
MAX_FIT_DEGREE = 12
#: orbits drawn beyond ``orbits`` to replace those on smaller invariant sets
MORE_ORBITS = 12
#: sparse kernel vectors whose entries are fitted, and fits (one entry at one degree) tried, at most
MAX_CIRCUITS = 60
MAX_FITS = 200
#: sparse kernel vectors whose entries' variables are computed to order them (_Job.ordered_supports), from the
#: level sets and from the full kernel each, at most
MAX_ORDERED = 600
#: level sets L = c of a linear integral L at most, for pencils interpolated in c (Job.level_pencils)
MAX_LEVELS = 40
#: the degree of a fit's coefficients in the integrals already found (the Lagrange top's integrals
#: beyond m3 have coefficients of degree 3 in m3)
MAX_KNOWN_DEGREE = 3
#: the same in all of them together (k of them: C(k + J, J) coefficient monomials, 20 for k = 3 at J = 3; the
#: Clebsch system's fits at (δ, J) = (2, 3) in I1..I3, 1 120 unknowns, took 12 of its 63 CPU seconds, all failing)
MAX_ALL_KNOWN_DEGREE = 2


# --- exact evaluation and verification -------------------------------------------------


def _exact_orbit(fld, eps, x0, steps):
    from exact_khk.kahan.map import KahanMap
    phi = KahanMap(fld, eps, "flint")
    return phi.orbit(x0, steps)


def verify_exact(num: dict, den: dict, fld, eps, x0, steps) -> bool:
    """True when num/den (dict polynomials) is conserved along the exact orbit of
    ``x0`` (``steps`` steps, flint rationals) and den(x_0) ≠ 0.

    Evaluated fraction-free: with x = ξ/δ (δ the common denominator) and the
    homogenisations P^h, Q^h (degrees a, b), P(x)/Q(x) = P^h(ξ, δ) δ^b / (Q^h(ξ, δ) δ^a)."""
    N = fld.dim
    (n, a), (d, b) = _homogenised(num, N), _homogenised(den, N)
    ref = None
    for x in _exact_orbit(fld, eps, x0, steps):
        delta = math.lcm(*(int(t.q) for t in x))
        pt = [flint.fmpz(int(t.p) * (delta // int(t.q))) for t in x] + [flint.fmpz(delta)]
        nv, dv = n(*pt) * flint.fmpz(delta) ** b, d(*pt) * flint.fmpz(delta) ** a
        if ref is None:
            if dv == 0:
                return False
            ref = (nv, dv)
        elif nv * ref[1] != ref[0] * dv:
            return False
    return True


def _homogenised(poly: dict, N: int):
    """(P^h as fmpz_mpoly in x0..x(N-1), w; deg P) for a polynomial with rational coefficients
    (scaled to integers: the ratio changes by a constant, which conservation ignores)."""
    deg = max((sum(e) for e in poly), default=0)
    den = math.lcm(*(c.denominator for c in poly.values())) if poly else 1
    ctx = flint.fmpz_mpoly_ctx.get(tuple(f"x{i}" for i in range(N)) + ("w",), "degrevlex")
    return ctx.from_dict({tuple(e) + (deg - sum(e),): int(c * den) for e, c in poly.items()}), deg


@dataclass(frozen=True)
class Integral:
    """A conserved rational function num/den (coefficients over the candidates)."""

    numerator: str
    denominator: str
    num: tuple       # ((exponents, Fraction), ...)
    den: tuple
    verified: bool

    def polynomials(self):
        """(numerator, denominator) as dicts {exponent tuple: Fraction}."""
        return dict(self.num), dict(self.den)

    def gradient(self, x) -> list:
        """The exact gradient of num/den at the rational point ``x`` (Fractions; a
        PoleError where the denominator vanishes).

        >>> from fractions import Fraction as F
        >>> r = Integral("x^2", "y", (((2, 0), F(1)),), (((0, 1), F(1)),), True)
        >>> r.gradient([F(1), F(2)])             # (2x/y, -x^2/y^2)
        [Fraction(1, 1), Fraction(-1, 4)]
        """
        x = [Fraction(t) for t in x]

        def value(poly, j=None):  # poly at x, or its derivative in x_j
            total = Fraction(0)
            for e, c in poly:
                if j is not None and e[j] == 0:
                    continue
                term = c * (e[j] if j is not None else 1)
                for i, k in enumerate(e):
                    term *= x[i] ** (k - (i == j))
                total += term
            return total

        n0, d0 = value(self.num), value(self.den)
        if d0 == 0:
            raise PoleError(f"the denominator {self.denominator} of a found integral vanishes at the point")
        return [(d0 * value(self.num, j) - n0 * value(self.den, j)) / d0 ** 2 for j in range(len(x))]

    @any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
    def to_json(self) -> dict:
        return {"numerator": self.numerator, "denominator": self.denominator, "verified": self.verified}


@dataclass(frozen=True)
class IntegralSearch:
    """What :func:`find_integrals` found (module docstring)."""

    label: str
    candidates: tuple          # monomial texts
    orbit_dims: tuple          # kernel dimension of each orbit (mod the first prime)
    kernel_dim: int            # generic dimension
    trivial_dim: int
    by_degree: tuple           # ((D, dim K_D, new_D), ...) in degree mode (kernels.by_degree)
    span_dim: int              # w = dim W
    integrals: tuple
    independent: int
    primes: tuple
    warnings: tuple
    seconds: float
    notes: tuple = dc_field(default=())
    certificate: tuple = None  # (rational point, rank of the integrals' Jacobian there, exact)
    visible: int = None        # independent integrals the kernel shows (rank of its entries' Jacobian mod p)

    @property
    def new_dim(self) -> int:
        """Kernel directions that are not products of smaller kernel polynomials."""
        return self.kernel_dim - self.trivial_dim

    @any_int_digits()
    def to_json(self) -> dict:
        return {"field": self.label, "candidates": list(self.candidates), "orbit_kernel_dims": list(self.orbit_dims),
                "kernel_dim": self.kernel_dim, "trivial_dim": self.trivial_dim, "new_dim": self.new_dim,
                "kernel_dim_by_degree": [list(t) for t in self.by_degree], "span_dim": self.span_dim,
                "integrals": [i.to_json() for i in self.integrals], "independent": self.independent,
                "primes": list(self.primes), "warnings": list(self.warnings), "notes": list(self.notes),
                "kernel_shows": self.visible,
                "independence_certificate": None if self.certificate is None else
                {"point": [str(t) for t in self.certificate[0]], "jacobian_rank": self.certificate[1]},
                "seconds": self.seconds}

    def headline(self) -> str:
        """'kernel k, extracted j, independent r' (and what the kernel shows, when computed)."""
        shows = "" if self.visible is None else f" (the kernel shows {self.visible} independent integral" \
            f"{'' if self.visible == 1 else 's'})"
        return (f"kernel {self.kernel_dim}, extracted {len(self.integrals)}, independent {self.independent}"
                + shows)

    @any_int_digits()
    def summary(self) -> str:
        out = [f"integral search for {self.label}: {len(self.candidates)} candidate monomials",
               f"  orbit kernel dimensions {list(self.orbit_dims)}: generic {self.kernel_dim} "
               f"({self.trivial_dim} trivial = products with smaller kernel polynomials, {self.new_dim} new)"]
        if self.by_degree:
            out.append("  kernel dimension by degree (new directions): "
                       + ", ".join(f"<= {d}: {k} ({new})" for d, k, new in self.by_degree))
        for i, f in enumerate(self.integrals, 1):
            out.append(f"  I{i} = ({_short(f.numerator)}) / ({_short(f.denominator)})"
                       + ("" if f.verified else "  [NOT verified]"))
        if self.integrals:
            out.append(f"  {sum(f.verified for f in self.integrals)} verified exactly on a fresh orbit (evidence, "
                       f"not a proof: `certify` a system file with them); {self.independent} functionally "
                       f"independent" + ("" if self.certificate is None else
                                         f" (proven: Jacobian rank {self.certificate[1]} at {_fmt(self.certificate[0])})"))
        elif self.kernel_dim == 0:
            out.append("  no integral with numerator and denominator in the span of the candidates")
        out += [f"  warning: {w}" for w in self.warnings] + [f"  note: {n}" for n in self.notes]
        out.append(f"  {self.headline()}")
        out.append(f"  time {self.seconds:.2f} s")
        return "\n".join(out)


@any_int_digits()
def find_integrals(system, degree=None, monomials_list=None, field="f", eps=None, homogeneous=False,
                   orbits=3, steps=None, margin=None, primes=None, seed=0, x0=None, verify_steps=6,
                   max_primes=16, progress=None, fit_degree=None, max_bytes=None):
    """Search conserved rational functions of the Kahan map whose numerator and
    denominator lie in the span of the candidates (module docstring).

    ``degree``: all monomials of degree ≤ degree (== with ``homogeneous``), or
    ``monomials_list`` (texts or exponent tuples); ``orbits`` random orbits (at
    least 2; 4 are used for pencils) plus ``x0`` if given, of ``steps`` steps
    (default: candidates + 2·margin); ``primes`` a list, or a count of random
    primes to start with (default 2; more are drawn, up to ``max_primes``, until
    the rational lift is confirmed by a prime it was not computed from); ``progress(stage)``
    is called with the name of each stage as it starts; ``fit_degree`` bounds the degree of the
    numerators and denominators of integrals fitted from the kernel's entries
    (:mod:`.fitting`; default twice the largest candidate degree, 0: no fit); with ``max_bytes``,
    a search whose evaluation matrices would need more memory (:func:`planned_bytes`) is refused
    before any work (InputError naming EXACT_KHK_MAX_MEMORY)."""
    t0 = time.perf_counter()
    stage = check_progress(progress) or (lambda name: None)
    sysobj, fld = resolve_field(system, field)
    eps = eps_of(sysobj, eps)
    N = fld.dim
    variables = list(sysobj.coordinate_names()) if hasattr(sysobj, "coordinate_names") else []
    if len(variables) != N:
        variables = [f"x{i}" for i in range(N)]
    if (degree is None) == (monomials_list is None):
        raise InputError("degree: give either degree or monomials_list")
    if degree is not None:
        check_count(degree, "degree", 1, 40)
        count = comb(N + degree - 1, degree) if homogeneous else comb(N + degree, degree)
        if count > MAX_MONOMIALS:
            raise InputError(f"degree: {count} candidate monomials of degree <= {degree} in {N} variables "
                             f"exceed {MAX_MONOMIALS}; choose a smaller degree or a list")
        exps = monomials(N, degree, homogeneous)
    else:
        exps = parse_monomials(monomials_list, variables)
        if len(exps) > MAX_MONOMIALS:
            raise InputError(f"monomials: {len(exps)} candidates exceed {MAX_MONOMIALS}")
    m = len(exps)
    check_count(orbits, "orbits", 2, 50)
    margin = check_count(margin if margin is not None else max(8, m // 10), "margin", 1, 10_000)
    steps = check_count(steps if steps is not None else m + 2 * margin, "steps", 1, 1_000_000)
    if max_bytes is not None:
        check_count(max_bytes, "max_bytes", 1, 2 ** 62)  # an int of bytes: never NaN, which disables every comparison
    if max_bytes is not None and planned_bytes(m, steps) > max_bytes:
        raise InputError(f"degree: {m} candidates over orbits of {steps + 1} points need about "
                         f"{planned_bytes(m, steps) / 2 ** 30:.3g} GiB for the evaluation matrices, beyond the memory "
                         f"limit of {max_bytes / 2 ** 30:.3g} GiB (EXACT_KHK_MAX_MEMORY)")
    check_count(verify_steps, "verify_steps", 1, 1000)
    check_count(max_primes, "max_primes", 1, 1000)
    top_degree = max(sum(e) for e in exps)
    fit_degree = check_count(2 * top_degree if fit_degree is None else fit_degree, "fit_degree", 0, MAX_FIT_DEGREE)
    seed = check_count(seed, "seed", -2 ** 63, 2 ** 63)
    plist = list(check_primes(primes, seed=seed))
    rng = random.Random(f"integrals-{seed}")
    start = [] if x0 is None else [parse_vector(x0, "x0", N)]  # exact rationals only, as everywhere
    starts = start + [_point(rng, N) for _ in range(orbits)]
    job = _Job(fld, eps, exps, steps, margin, variables, [], [])
    job.max_bytes, job.progress = max_bytes, progress
    if steps + 1 < m + margin:
        job.warnings.append(f"orbit too short: {steps + 1} points for {m} candidates (+ margin {margin}); "
                            f"the kernel has dimension >= {m - steps - 1} for that reason alone")
    p0 = plist[0]

    def kernel(x):
        stage(f"orbit kernel {len(ks) + 1} mod p ({m} candidates)")
        return job.kernel(x, p0, stage)

    ks = []
    for x in starts:
        k = kernel(x)
        if k is not None:
            ks.append(k)
    while _generic_count(ks) < 4 and len(starts) < orbits + MORE_ORBITS:
        # more orbits until 4 share the generic (smallest) kernel: 4 are needed for pencils, and an
        # orbit on a smaller invariant set (a larger kernel) is replaced rather than used
        starts.append(_point(rng, N))
        k = kernel(starts[-1])
        if k is not None:
            ks.append(k)
    good = [k for k in ks if k.stable and not k.periodic]
    for k in ks:
        if k.periodic:
            job.warnings.append(f"orbit of {_fmt(k.x0)} is periodic mod p (a finite set): its kernel is spurious")
        elif not k.stable:
            job.warnings.append(f"orbit of {_fmt(k.x0)} too short: the rank still grew in its last {margin} points")
    if len(good) < 2:
        job.warnings.append("fewer than two usable orbits: nothing concluded")
        return job.result(sysobj, ks, 0, 0, (), 0, (), 0, (p0,), t0)
    d = min(k.dim for k in good)
    for k in good:
        if k.dim > d:
            job.warnings.append(f"orbit of {_fmt(k.x0)} has a {k.dim}-dimensional kernel > generic {d}: it lies on "
                                f"a smaller invariant set (not used)")
    generic = [k for k in good if k.dim == d]
    stage("trivial kernel vectors")
    tdim = trivial_dim(generic[0].basis, exps, p0)
    table = by_degree(generic[0].basis, exps, p0) if degree is not None and not homogeneous else ()
    if table:
        tdim = d - table[-1][2]
    w = _rref_rows([v for k in generic for v in k.basis], m, p0)[1]
    integrals, independent, used = (), 0, (p0,)
    low = next((D for D, dim, _ in table if dim), None)
    if d == 0:
        job.notes.append("no polynomial in the span vanishes on the orbits: no integral of this shape")
    elif table and low < degree:
        sub = find_integrals(system, degree=low, field=field, eps=eps, orbits=orbits, primes=plist, seed=seed,
                             verify_steps=verify_steps, max_primes=max_primes, progress=progress, fit_degree=0)
        integrals, independent, used = sub.integrals, sub.independent, sub.primes
        job.notes += [f"integrals extracted at degree {low}, where the kernel first appears"] + list(sub.notes)
        job.warnings += list(sub.warnings)
        for D, new in [(D, new) for D, _, new in table if D > low and new]:
            # {1} ∪ (degree exactly D) holds no product (L − c)·m of a lower-degree kernel
            # polynomial with a monomial of degree ≥ 1: the new integrals separate there
            top = ["1"] + [monomial_text(e, variables) for e in monomials(N, D, True)]
            more = find_integrals(system, monomials_list=top, field=field, eps=eps, orbits=orbits, primes=plist,
                                  seed=seed, verify_steps=verify_steps, max_primes=max_primes, progress=progress,
                                  fit_degree=0)
            found = [f for f in more.integrals if f.verified]
            integrals += tuple(found)
            job.notes.append(f"{new} new kernel direction(s) at degree {D}: {len(found)} integral(s) extracted from "
                             f"the candidates 1 and the monomials of degree exactly {D}"
                             + ("" if found else " (" + "; ".join(more.notes) + ")"))
        independent = independent_count([f.polynomials() for f in integrals if f.verified], rng)
    elif tdim:
        job.notes.append("trivial kernel vectors present: integrals not extracted")
    else:
        stage("lift to Q, extract and check the integrals")
        integrals, used = job.extract(generic, d, w, plist, seed, max_primes, verify_steps)
        independent = independent_count([f.polynomials() for f in integrals if f.verified], rng)
    if d and fit_degree:
        stage("independent integrals: the kernel's entries, fitted")
        integrals, independent, certificate, visible = job.complete(generic[0], integrals, fit_degree, plist,
                                                                    seed, max_primes, verify_steps)
        return job.result(sysobj, ks, d, tdim, table, w, integrals, independent, used, t0, certificate, visible)
    return job.result(sysobj, ks, d, tdim, table, w, integrals, independent, used, t0)


def fit_shapes(N, k, fit_degree, nvars=None) -> list:
    """The fits tried for one entry, fewest unknowns first: (T, δ, J) with N/D of degree ≤ δ in x and
    coefficients of degree ≤ J in the integrals I_i, i ∈ T, of the k found (J = 0: T empty).

    T is one found integral or all of them: a pair (N, D) with coefficients in I_1 alone is unique
    modulo the vanishing vectors only where no other I_i may multiply it, and costs fewer unknowns
    (Lagrange top, m3 and J found: an integral fitted at (δ, J) = (3, 3) in m3 alone, 2·84·4
    unknowns; in m3 and J, 2·84·10, beyond MAX_FIT_UNKNOWNS).

    >>> fit_shapes(2, 1, 1)
    [((), 1, 0), ((0,), 1, 1), ((0,), 1, 2), ((0,), 1, 3)]
    """
    sets = [(i,) for i in range(k)] + ([tuple(range(k))] if k > 1 else [])
    n = lambda T: N if nvars is None else nvars[T]  # noqa: E731
    size = lambda t: 2 * comb(n(t[0]) + t[1], t[1]) * comb(len(t[0]) + t[2], t[2])  # noqa: E731
    shapes = [((), D, 0) for D in range(1, fit_degree + 1)]
    shapes += [(T, D, J) for T in sets for D in range(1, fit_degree + 1)
               for J in range(1, (MAX_KNOWN_DEGREE if len(T) == 1 else MAX_ALL_KNOWN_DEGREE) + 1)]
    limit = lambda t: MAX_FIT_UNKNOWNS if t[2] else MAX_PLAIN_FIT_UNKNOWNS  # noqa: E731
    return sorted((t for t in shapes if size(t) <= limit(t)), key=lambda t: (size(t), t[1], t[2], t[0]))


def planned_bytes(m, steps) -> int:
    """The memory of one orbit kernel's evaluation matrix over (steps + 1) points (:func:`.kernels.kernel_bytes`)."""
    return kernel_bytes(m, steps + 1, 0)


def _generic_count(ks) -> int:
    """How many stable, non-periodic orbits have the smallest kernel dimension among them."""
    dims = [k.dim for k in ks if k.stable and not k.periodic]
    return dims.count(min(dims)) if dims else 0


def _rank(rows, N) -> int:
    return flint.fmpq_mat(len(rows), N, [v for r in rows for v in r]).rank() if rows else 0


def _grad_mod(f, x, p) -> list:
    """[the gradient of the integral f at the rational point x, mod p], or [] at a pole / p | a denominator."""
    try:
        g = f.gradient(x)
        return [[t.numerator * pow(t.denominator, -1, p) % p for t in g]]
    except (PoleError, ValueError):
        return []


def _short(text, limit=240):
    """A long polynomial cut for the summary (``to_json`` has it in full)."""
    if len(text) <= limit:
        return text
    return text[:limit].rsplit(" ", 1)[0] + f" ... ({text.count(' + ') + text.count(' - ') + 1} terms)"


def _fmt(x):
    return "(" + ", ".join(str(t) for t in x) + ")"


class _Job:
    """The fixed data of one search, and its extraction steps."""

    max_bytes = None  # the memory limit of one orbit kernel's basis or one fit (find_integrals' max_bytes)
    progress = None   # find_integrals' progress(stage)

    def __init__(self, fld, eps, exps, steps, margin, variables, warnings, notes):
        self.fld, self.eps, self.exps, self.steps, self.margin = fld, eps, exps, steps, margin
        self.variables, self.warnings, self.notes = variables, warnings, notes

    def kernel(self, x, p, progress=None):
        try:
            return orbit_kernel_mod(self.fld, self.eps, x, self.exps, self.steps, p, self.margin, progress,
                                    self.max_bytes)
        except KernelTooLarge:
            raise
        except (SingularStepError, ZeroDivisionError, InputError):
            return None

    def lifted_kernels(self, xs, d, plist, seed, max_primes):
        """The kernels of the orbits of ``xs`` over Q (canonical bases), and the primes used."""
        per, used = [], []
        fresh = iter(p for p in random_primes(max_primes + len(plist), seed + 1) if p not in plist)
        for p in list(plist) + list(fresh):
            if len(used) >= max_primes:
                break
            kk = [self.kernel(x, p) for x in xs]
            if any(k is None or k.dim != d for k in kk):
                continue  # an unlucky prime
            per.append((p, [v for k in kk for v in k.basis]))
            used.append(p)
            out = lift(per)
            if out is not None:
                return [out[i * d:(i + 1) * d] for i in range(len(xs))], tuple(used)
        self.warnings.append(f"rational reconstruction of the kernels not confirmed with {len(used)} primes")
        return None, tuple(used)

    def extract(self, generic, d, w, plist, seed, max_primes, verify_steps):
        """Integrals as ratios (w = d + 1) or from pencils (w = 2d): :mod:`.pencils`."""
        if w - d == 1:
            K, used = self.lifted_kernels([k.x0 for k in generic[:2]], d, plist, seed, max_primes)
            pairs = None if K is None else ratio_integrals(K, self.exps)
        elif w == 2 * d and len(generic) >= 4:
            K, used = self.lifted_kernels([k.x0 for k in generic[:4]], d, plist, seed, max_primes)
            pairs = None if K is None else pencil_integrals(K, self.exps, self.notes)
        else:
            self.notes.append(f"orbit kernels of dimension {d} span a space of dimension {w}: neither one common "
                              f"denominator (w = d + 1) nor independent pencils (w = 2d); integrals not extracted")
            return (), tuple(plist[:1])
        if not pairs:
            return (), used
        vx = _point(random.Random(f"verify-{seed}"), self.fld.dim)
        out = tuple(Integral(poly_text(a, self.variables), poly_text(b, self.variables), tuple(sorted(a.items())),
                             tuple(sorted(b.items())), verify_exact(a, b, self.fld, self.eps, vx, verify_steps))
                    for a, b in pairs)
        if any(not f.verified for f in out):
            self.warnings.append("some lifted ratios failed the exact check on a fresh orbit (not integrals)")
        return out, used

    def result(self, sysobj, ks, d, tdim, table, w, integrals, independent, used, t0, certificate=None,
               visible=None):
        label = f"{sysobj.name if sysobj is not None else 'field'} {self.fld.label}"
        return IntegralSearch(label, tuple(monomial_text(e, self.variables) for e in self.exps),
                              tuple(k.dim for k in ks), d, tdim, table, w, tuple(integrals), independent,
                              tuple(used), tuple(self.warnings), time.perf_counter() - t0, tuple(self.notes),
                              certificate, visible)

    def integral(self, num, den, verify_point, verify_steps):
        return Integral(poly_text(num, self.variables), poly_text(den, self.variables), tuple(sorted(num.items())),
                        tuple(sorted(den.items())), verify_exact(num, den, self.fld, self.eps, verify_point,
                                                                 verify_steps))

    def complete(self, ref, integrals, fit_degree, plist, seed, max_primes, verify_steps):
        """Every independent integral the kernel shows (:mod:`.fitting`): the verified ``integrals``
        reduced to an independent set (exact Jacobian rank at a rational point, each kept only if it
        raises it), then entries of the canonical kernel that are not functions of those, fitted as
        N/D of degree ≤ ``fit_degree`` and checked exactly on a fresh orbit.
        (integrals, rank, (point, rank) certificate or None, visible count or None)."""
        N = self.fld.dim
        point, kept, rows = self.rank_point(seed), [], []
        for f in integrals:
            if not f.verified:
                continue
            r = jacobian_rows([f.polynomials()], point)
            if r is None or _rank(rows + r, N) == len(rows):
                self.notes.append(f"({_short(f.numerator, 60)}) / ({_short(f.denominator, 60)}) is a function of the "
                                  f"integrals kept (Jacobian rank at {_fmt(point)}): not listed")
                continue
            kept.append(f)
            rows += r
        p0 = plist[0]
        data = entry_jacobian(self.fld, self.eps, ref.x0, self.exps, self.steps, p0, seed)
        if data is None:
            self.notes.append("the kernel's entries were not differentiated (orbit singular mod p, or beyond "
                              "MAX_TANGENT_WORK): the number of integrals it shows is not stated")
            return tuple(kept), len(rows), ((point, len(rows)) if rows else None), None
        pivots, _, values, grads = data
        visible = rank_mod(list(grads.values()), N, p0)
        primes = list(plist) + [p for p in random_primes(max_primes + len(plist), seed + 1) if p not in plist]
        vx = _point(random.Random(f"verify-{seed}"), N)
        mod_rows = [g for f in kept for g in _grad_mod(f, ref.x0, p0)]

        def accepted(f) -> bool:
            """Keep ``f`` if it was verified exactly on a fresh orbit and raises the exact rank."""
            r = jacobian_rows([f.polynomials()], point)
            if not f.verified or r is None or _rank(rows + r, N) == len(rows):
                return False
            kept.append(f)
            rows.extend(r)
            mod_rows.extend(_grad_mod(f, ref.x0, p0))
            return True

        for num, den, text in self.level_pencils(kept, plist, seed, max_primes) if len(kept) < visible else ():
            if not accepted(self.integral(*canonical_pair(num, den), vx, verify_steps)):
                continue
            self.notes.append(f"I{len(kept)} from a pencil of the kernel on the level sets {text} = c (candidates "
                              f"free of one of its variables), its coefficients interpolated in c")
        budget, cache = MAX_FITS, FitCache()
        for sub, data in self.ordered_supports(kept, ref, p0, seed)[:MAX_CIRCUITS]:
            if len(kept) >= visible or budget <= 0:
                break
            fitters = {}
            # one entry per sparse vector (its entries are functions of the same conserved point): of those
            # not functions of the integrals found, the one in fewest variables
            raising = [kg for kg in sorted(data[3].items())
                       if rank_mod(mod_rows + [kg[1]], N, p0) > rank_mod(mod_rows, N, p0)]
            for key, grad in sorted(raising, key=lambda kg: sum(1 for g in kg[1] if g))[:1]:
                pair = None
                for T, delta, J, variables in self.fit_plan(sub, data[0], key, grad, kept, fit_degree, p0, seed):
                    if budget <= 0:  # checked fit by fit: one support's fits may be many and long
                        break
                    budget -= 1
                    if T not in fitters:
                        fitters[T] = EntryFitter(self.fld, self.eps, sub, self.steps, data[0], seed, self.margin,
                                                 [kept[i].polynomials() for i in T], self.progress, self.max_bytes,
                                                 cache)
                    try:
                        pair = fitters[T].fit(key, delta, primes, J, variables)
                    except FitTooLarge as exc:  # said once: the larger fits are refused the same way
                        if not any("EXACT_KHK_MAX_MEMORY" in w for w in self.warnings):
                            self.warnings.append(f"{exc}: not tried, nor any fit as large")
                        continue
                    if pair is not None:
                        break
                if pair is None:
                    continue
                if not accepted(self.integral(*canonical_pair(*pair), vx, verify_steps)):
                    continue
                self.notes.append(f"I{len(kept)} fitted (degree <= {delta}"
                                  + (f", coefficients of degree <= {J} in "
                                     + ", ".join(f"I{i + 1}" for i in T) if J else "")
                                  + ") from the kernel vector supported on "
                                  f"{', '.join(monomial_text(e, self.variables) for e in sub)}")
        for num, den, note in hk_basis_integrals(self, ref, mod_rows, primes, seed, lambda: visible - len(kept)):
            if accepted(self.integral(*canonical_pair(num, den), vx, verify_steps)):
                self.notes.append(f"I{len(kept)} {note}")
        if len(kept) < visible:
            self.warnings.append(f"the kernel shows {visible} independent integrals (rank of its entries' Jacobian "
                                 f"mod p), {len(kept)} extracted: the others have no numerator and denominator of "
                                 f"degree <= {fit_degree} (--fit-degree) that the fit found")
        return tuple(kept), len(rows), ((point, len(rows)) if rows else None), visible

    def ordered_supports(self, kept, ref, p, seed) -> list:
        """[(candidates, :func:`.fitting.entry_jacobian` data)] of the sparse kernel vectors whose entries are
        fitted: those on the level sets of the linear integrals found (:meth:`level_circuits`), then those of
        the full kernel (:func:`.fitting.circuits`), MAX_ORDERED of each (smallest supports first), each once
        and with one free column, ordered by the fewest variables a non-constant entry depends on (its
        gradient mod p at the reference point), then by the variables their candidates use.  A fit's unknowns
        grow with the variables of its entry, and the candidates' variables do not bound them (KQV N = 14: the
        supports x2, x3, x1·x3 use 3 variables, their entries depend on 13 or 14 (through x2 + … + x14);
        the three-term supports x_{k-2}x_k, x_{k-2}x_{k+1}, x_{k-1}x_{k+1} have entries in 4 variables)."""
        N = self.fld.dim
        subs = self.level_circuits(kept, ref.x0, p, seed)[:MAX_ORDERED]
        subs += [[self.exps[c] for c in S] for S in circuits(ref.basis, len(self.exps), p, seed)[:MAX_ORDERED]]
        try:
            orbit = orbit_with_tangents(self.fld, self.eps, ref.x0, self.steps, p)  # shared by all supports
        except (SingularStepError, ZeroDivisionError, InputError):
            return []
        seen, out = set(), []
        for sub in subs:
            if frozenset(sub) in seen:  # found both on a level set and in the full kernel: the same vector
                continue
            seen.add(frozenset(sub))
            data = entry_jacobian(self.fld, self.eps, ref.x0, sub, self.steps, p, seed, orbit)
            own = [] if data is None or len(data[1]) != 1 else [sum(1 for g in grad if g % p)
                                                                 for grad in data[3].values() if any(grad)]
            if own:
                out.append((min(own), sum(any(e[j] for e in sub) for j in range(N)), sub, data))
        out.sort(key=lambda t: t[:2])
        return [(sub, data) for _, _, sub, data in out]

    def fit_plan(self, sub, pivots, key, grad, kept, fit_degree, p, seed) -> list:
        """The fits (T, δ, J, variables) tried for the entry ``key`` of the kernel of ``sub``, fewest unknowns
        first (:func:`fit_shapes`), in the variables the entry depends on (``grad``, its gradient mod p at
        the reference point: N/D free of a variable it does not depend on exists whenever one exists) and
        those of the integrals I_i, i ∈ T; without those that cannot equal the entry on a random line over
        F_p (:meth:`.fitting.EntryLine.admits`; none when the entry's degree there, never above its degree
        over Q, exceeds what every fit can reach: N/D of degree ≤ δ with coefficients of degree ≤ J in the
        I_i (degrees a_i) has degree ≤ δ + J·Σ a_i)."""
        N = self.fld.dim
        own = {l for l in range(N) if grad[l] % p}
        pairs = [f.polynomials() for f in kept]
        degs = [max(max(map(sum, num)), max(map(sum, den))) for num, den in pairs]
        uses = [{l for e in list(num) + list(den) for l in range(N) if e[l]} for num, den in pairs]
        sets = [()] + [(i,) for i in range(len(kept))] + ([tuple(range(len(kept)))] if len(kept) > 1 else [])
        variables = {T: tuple(sorted(own.union(*(uses[i] for i in T)))) for T in sets}
        shapes = fit_shapes(N, len(kept), fit_degree, {T: len(v) for T, v in variables.items()})
        if not shapes:
            return []
        line = entry_line(self.fld, self.eps, sub, min(self.steps, len(sub) + self.margin), pivots, key, p,
                          random.Random(f"line-{seed}"), max(D + J * sum(degs[i] for i in T) for T, D, J in shapes))
        if line is None:
            return [(T, D, J, variables[T]) for T, D, J in shapes]
        if line.A is None:
            return []
        on_line = [(line.restrict(num), line.restrict(den)) for num, den in pairs]
        return [(T, D, J, variables[T]) for T, D, J in shapes if line.admits([on_line[i] for i in T], D, J)]

    def linear_integral(self, kept):
        """(j, L, text) for the first linear integral L kept (num or den of degree 1, the other
        constant) and its variable x_j of highest index, or None."""
        for f in kept:
            num, den = f.polynomials()
            for a, b, text in ((num, den, f.numerator), (den, num, f.denominator)):
                if max(map(sum, a)) == 1 and max(map(sum, b)) == 0:
                    j = max(i for e in a for i, k in enumerate(e) if k)
                    return j, a, text
        return None

    def level_pencils(self, kept, plist, seed, max_primes) -> list:
        """Integrals (num, den, text of L) from the pencils of the orbit kernels on the level sets
        L = c of a linear integral L kept: on L = c (c = 1, 2, ..., MAX_LEVELS) four orbits of rational
        points give kernels of the candidates free of x_j; where they are independent pencils
        (w = 2d, :func:`.pencils.pencil_integrals`) each pencil's echelon basis is recorded, and its
        coefficients, rational functions of c, are reconstructed (:func:`.pencils.interpolated_pencils`)
        with c replaced by L(x).  (Lagrange top: on m3 = c the orbit kernels of degree ≤ 2 have
        dimension 3 and span 6 over four orbits; two of the pencils separated there, J and the
        modified energy, are the same for every four orbits on a level and interpolate; the third
        changes with the orbits at the same c, so it is no pencil and is not interpolated.)"""
        found = self.linear_integral(kept)
        if found is None:
            return []
        j, L, text = found
        N = self.fld.dim
        sub = [e for e in self.exps if not e[j]]
        job = _Job(self.fld, self.eps, sub, self.steps, self.margin, self.variables, [], [])
        rng = random.Random(f"levels-{seed}")
        zero = (0,) * N
        by_level = {}
        for c in range(1, MAX_LEVELS + 1):
            pts = []
            for _ in range(4):
                y = list(_point(rng, N))
                rest = sum(a * y[i] for e, a in L.items() if e != zero for i, k in enumerate(e) if k and i != j)
                y[j] = (Fraction(c) - L.get(zero, 0) - rest) / L[tuple(int(i == j) for i in range(N))]
                pts.append(tuple(y))
            ks = [job.kernel(x, plist[0]) for x in pts]
            if any(k is None or not k.stable or k.periodic for k in ks) or len({k.dim for k in ks}) != 1:
                continue
            d = ks[0].dim
            if not d or _rref_rows([v for k in ks[:2] for v in k.basis], len(sub), plist[0])[1] != 2 * d:
                continue
            K, _ = job.lifted_kernels(pts, d, plist, seed, max_primes)
            if K is None:
                continue
            level = {}
            for P, Q in pencil_integrals(K, sub, []):
                ep = echelon_pencil(P, Q, sub)
                if ep is not None:
                    level[(ep[0], tuple(i for i in range(len(sub)) if ep[1][0][i] or ep[1][1][i]))] = ep[1]
            if not level:
                continue
            by_level[Fraction(c)] = level
            if len(by_level) >= 6 and len(by_level) % 4 == 2:
                out = interpolated_pencils(by_level, sub, L, N)
                if len(out) == max(len(v) for v in by_level.values()):
                    return [(a, b, text) for a, b in out]  # every pencil interpolated
        return [(a, b, text) for a, b in interpolated_pencils(by_level, sub, L, N)]

    def level_circuits(self, kept, x0, p, seed) -> list:
        """Sparse kernel vectors on the level set of the linear integrals found (lists of candidates).

        On an orbit a linear integral L = c fixes one variable x_j as an affine function of the
        others; the candidates free of x_j then hold the remaining integrals with coefficients
        polynomial in c, without the products (L − c)·φ that mix them with L in the full kernel
        (Lagrange top: m3; on m3 = c the orbit kernels of degree ≤ 2 have dimension 3, with no
        products of m3 − c)."""
        elim = []
        for f in kept:
            num, den = f.polynomials()
            if max(map(sum, num)) <= 1 and max(map(sum, den)) == 0:
                lin = num
            elif max(map(sum, den)) <= 1 and max(map(sum, num)) == 0:
                lin = den
            else:
                continue
            j = next((j for j in reversed(range(self.fld.dim)) if j not in elim and
                      any(e[j] for e in lin)), None)
            if j is not None:
                elim.append(j)
        sub = [e for e in self.exps if not any(e[j] for j in elim)]
        if not elim or len(sub) == len(self.exps):
            return []
        try:
            k = orbit_kernel_mod(self.fld, self.eps, x0, sub, self.steps, p, self.margin)
        except (SingularStepError, ZeroDivisionError, InputError):
            return []
        if not k.dim or not k.stable:
            return []
        return [[sub[c] for c in S] for S in circuits(k.basis, len(sub), p, seed)]

    def rank_point(self, seed):
        rng = random.Random(f"rank-{seed}")
        return [flint.fmpq(rng.randint(-30, 30), rng.randint(1, 7)) for _ in range(self.fld.dim)]


# --- output that goes straight back in: a system file with the found integrals ----------


def system_file(system, result: IntegralSearch, eps, field="f", x0=None) -> str:
    """A system file (TOML, docs/system-files.md) that ``exact-khk certify --system`` reads: the
    system's own file (an expression system) or its field written out (any other, variables
    x0..x(N-1)), with the verified integrals of ``result`` added to ``[integrals]`` as found_I1, …
    and ``[defaults] eps`` set to the ε they were found at (their coefficients are numbers for that
    ε only); ``claims`` include "integrals"."""
    sysobj, fld = resolve_field(system, field)
    found = {f"found_I{i}": f"({f.numerator})/({f.denominator})" for i, f in enumerate(result.integrals, 1)
             if f.verified}
    if getattr(sysobj, "kind", None) == "expressions" and field == "f":
        spec = sysobj.to_json()
    else:
        names = [f"x{i}" for i in range(fld.dim)]
        spec = {"format": 1, "kind": "expressions",
                "name": f"{getattr(sysobj, 'name', 'field')}-{field}".replace(" ", "-").replace("=", ""),
                "title": f"the field {fld.label} of {getattr(sysobj, 'name', 'a quadratic field')}",
                "variables": names, "field": {v: _component(fld, k, names) for k, v in enumerate(names)}}
    spec["integrals"] = {**spec.get("integrals", {}), **found}
    claims = list(spec.get("claims", ["reversibility", "integrals"]))
    spec["claims"] = claims + (["integrals"] if "integrals" not in claims else [])
    defaults = dict(spec.get("defaults", {}))
    defaults["eps"] = str(eps)
    if x0 is not None:
        defaults["x0"] = [str(t) for t in x0]
    spec["defaults"] = defaults
    return toml_text(spec)


def _component(fld, k, names) -> str:
    poly = {}
    for (i, j), c in fld.terms()[k]:
        e = [0] * fld.dim
        e[i] += 1
        e[j] += 1
        poly[tuple(e)] = poly.get(tuple(e), 0) + Fraction(str(c))
    for j, c in fld.linear[k]:
        e = [0] * fld.dim
        e[j] = 1
        poly[tuple(e)] = poly.get(tuple(e), 0) + Fraction(str(c))
    if fld.const[k]:
        poly[(0,) * fld.dim] = Fraction(str(fld.const[k]))
    return poly_text(poly, names)


def toml_text(spec: dict) -> str:
    """A dict of strings, numbers, lists and tables as TOML (strings JSON-quoted, which TOML reads)."""
    import json

    def value(v):
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(t) for t in v) + "]"
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, int):
            return str(v)
        return json.dumps(str(v), ensure_ascii=False)

    def table(name, d, out):
        plain = [(k, v) for k, v in d.items() if not isinstance(v, dict)]
        if name is not None and (plain or not d):
            out.append(f"\n[{name}]")
        out += [f"{json.dumps(str(k)) if not k.replace('_', '').replace('-', '').isalnum() else k} = {value(v)}"
                for k, v in plain]
        for k, v in d.items():
            if isinstance(v, dict):
                table(k if name is None else f"{name}.{k}", v, out)

    out = []
    table(None, spec, out)
    return "\n".join(out) + "\n"
