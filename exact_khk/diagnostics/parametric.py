"""Parametric integrals: :func:`find_integrals` at many values of ε (and of named parameters),
reconstructed as rational functions of them, then proven as identities.

**Samples.**  The search (:func:`~exact_khk.diagnostics.integrals.find_integrals`, unchanged)
runs at ``s = (ε, a, …)`` drawn at random (small-height nonzero rationals; the parameters not
named keep the system's values).  Each verified integral N/D it returns is the canonical pair
of :func:`~exact_khk.diagnostics.pencils.canonical_pair` (echelon basis of span(N, D) over the
sorted monomials, so its coefficients are rational functions of s); it is scaled so that the
first nonzero coefficient of N and of D (sorted monomials) is 1.  A sample's *shape* is the list
of the supports of the N and D found; the integrals are ordered by shape.  The most frequent
shape is kept; samples of another shape (special values where a coefficient vanishes) are
dropped and counted, and a shape held by fewer than :data:`MIN_SHARE` of the samples is refused.

**Reconstruction** (a dense ansatz, solved exactly): each coefficient c(s) is written as P/Q
with P, Q of total degrees ≤ (a, b) in the k symbols, the bounds tried fewest unknowns
C(k + a, k) + C(k + b, k) − 1 first (:func:`levels`); the linear system
P(s_i) − c_i Q(s_i) = 0 over the samples but the last ``confirm`` is solved over Q
(``fmpz_mat.nullspace``), P/Q reduced by its gcd, and accepted only when it reproduces every
sample, the ``confirm`` unused ones included.  (a, b) needs that many unknowns + ``confirm``
samples; beyond a, b ≤ ``max_degree`` or :data:`MAX_SAMPLES` samples the search stops with an
InputError.  With several symbols, past :data:`DENSE_FIRST` samples the degrees per symbol are
read first from searches along one symbol at a time and P, Q solved in the box of those
degrees (:func:`_boxes`), the total-degree ansatz remaining the fallback.  For one
symbol this is rational interpolation: the reconstruction is unique once it exists.  The
reconstructed N and D are multiplied by the lcm of their coefficients' denominators and divided
by their content, so the reported integral is N/D up to a factor that depends only on s.

**Proof** (a route other than the fit): with M = I − ε f′(x) and r = M x + 2ε f(x), the Kahan map
is x̃ = (y_1, …, y_N)/q with q = det M, y = q M⁻¹ r (fraction-free Bareiss over
Q[x, symbols], :func:`~exact_khk.diagnostics.degrees.bareiss`), f read from the system file
with the named parameters as symbols.  N(x̃)/D(x̃) = N(x)/D(x) holds as rational functions iff
N^h(y, q) q^{deg D} D(x) − D^h(y, q) q^{deg N} N(x) = 0 (N^h the homogenisation in x), which is
expanded exactly (python-flint ``fmpq_mpoly``): a proof for all x, ε and parameter values where
both sides are defined — no probability.  Beyond dimension :data:`EXACT_MAX_DIM` (or with
``proof="sz"``) the identity is checked instead at :data:`SZ_TRIALS` random points over F_p
(x̃ by a linear solve mod p), with the failure bound of :func:`sz_bound` stated.

**Measures and tensors** go the same way: :func:`symbolic_measures` reconstructs the densities of
:func:`~exact_khk.diagnostics.measures.find_measure` (N/D scaled like an integral) and proves
m(x̃) det dΦ(x) = m(x), det dΦ = det K(x̃)/det M with K = I + ε f′;
:func:`symbolic_tensors` those of :func:`~exact_khk.diagnostics.poisson.find_poisson` (all
entries scaled by one factor) and proves K(x̃) π(x) K(x̃)ᵀ = M π(x̃) Mᵀ (that is dΦ π dΦᵀ = π∘Φ)
and the Jacobi identity (exactly; polynomial).

>>> from exact_khk.systems.catalogue import load
>>> res = symbolic_integrals(load("euler-top"), ["eps"], degree=2)
>>> res.symbols, [f.proven for f in res.integrals]
(('eps',), [True, True])
"""

from __future__ import annotations

import itertools
import math
import random
import time
from collections import Counter
from dataclasses import dataclass
from fractions import Fraction
from math import comb

import flint

from exact_khk.arith.cyclotomic import DEFAULT_PRIME
from exact_khk.diagnostics.kernels import monomials, poly_text
from exact_khk.errors import InputError, PoleError, SingularStepError
from exact_khk.parsing import any_int_digits, check_progress, check_count

EPS = "eps"
#: the highest total degree t of a coefficient's numerator and denominator in the symbols
MAX_DEGREE = 12
#: the most searches (samples) one reconstruction may run
MAX_SAMPLES = 400
#: the least share of the samples that must agree on the integrals' shape
MIN_SHARE = Fraction(2, 3)
#: with several symbols, total-degree ansätze are tried up to this many searches, then degrees per symbol
DENSE_FIRST = 40
#: samples beyond those of the linear solve that must agree with a reconstruction
CONFIRM = 3
#: the exact proof (expansion) is used up to this dimension, Schwartz–Zippel over F_p beyond (the
#: five integrals of kqv-lotka-volterra:N=6, degree <= 3: 62 s expanded, under 1 s over F_p)
EXACT_MAX_DIM = 4
#: random points of the Schwartz–Zippel proof
SZ_TRIALS = 3


@dataclass(frozen=True)
class ParametricIntegral:
    """An integral N/D whose coefficients are polynomials in the symbols; ``proven`` says whether
    the identity N(Φ(x))/D(Φ(x)) = N(x)/D(x) was proven (``proof`` says how, or why not)."""

    numerator: str
    denominator: str
    degree: int          # the largest total degree t of a reconstructed coefficient
    proven: bool
    proof: str
    entries: tuple = ()  # a Poisson tensor: its N x N entries (numerator, denominator unused)

    @any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
    def to_json(self) -> dict:
        if self.entries:
            return {"matrix": [list(r) for r in self.entries], "coefficient_degree": self.degree,
                    "proven": self.proven, "proof": self.proof}
        return {"numerator": self.numerator, "denominator": self.denominator, "coefficient_degree": self.degree,
                "proven": self.proven, "proof": self.proof}


@dataclass(frozen=True)
class ParametricSearch:
    """What :func:`symbolic_integrals` found (module docstring)."""

    label: str
    symbols: tuple
    fixed: tuple             # ((name, value), ...) of the parameters and ε not symbolic
    integrals: tuple         # ParametricIntegral: the integrals, densities or tensors
    samples: int             # searches used
    dropped: int             # samples of another shape, or singular
    degree: int              # the ansatz degree t reached
    notes: tuple
    seconds: float
    sample_summary: str = ""  # find_integrals' headline at the first sample kept
    field: str = "f"
    kind: str = "integrals"  # "measure": densities m of invariant measures m(x) dx; "poisson": tensors

    @any_int_digits()
    def to_json(self) -> dict:
        key = {"measure": "densities", "poisson": "tensors"}.get(self.kind, "integrals")
        return {"field": self.label, "kind": self.kind, "symbols": list(self.symbols),
                "fixed": {k: str(v) for k, v in self.fixed},
                key: [f.to_json() for f in self.integrals], "samples": self.samples,
                "dropped_samples": self.dropped, "ansatz_degree": self.degree, "notes": list(self.notes),
                "sample_search": self.sample_summary, "seconds": self.seconds}

    @any_int_digits()
    def summary(self) -> str:
        fixed = ", ".join(f"{k} = {v}" for k, v in self.fixed)
        what, name = {"measure": ("measure densities", "m"), "poisson": ("Poisson tensors", "pi")}.get(
            self.kind, ("integrals", "I"))
        out = [f"parametric {what} of {self.label} in {', '.join(self.symbols)}"
               + (f" ({fixed})" if fixed else ""),
               f"  {self.samples} searches at random values ({self.dropped} dropped: another shape or singular); "
               f"at one sample: {self.sample_summary}"]
        if self.integrals:
            out.append(f"  coefficients reconstructed as P/Q, deg P and deg Q <= {self.degree} in "
                       f"{', '.join(self.symbols)}, each confirmed at {CONFIRM} samples not used to solve "
                       f"(conjecture until proven)")
        for i, f in enumerate(self.integrals, 1):
            if f.entries:
                out.append(f"  {name}{i} = [" + ",\n          ".join(
                    "[" + ", ".join(f'"{e}"' for e in row) + "]" for row in f.entries) + "]")
            else:
                out.append(f"  {name}{i} = ({f.numerator})/({f.denominator})")
            out.append(f"       {'PROVEN' if f.proven else 'NOT proven'}: {f.proof}")
        out += [f"  note: {n}" for n in self.notes]
        out.append(f"  {sum(f.proven for f in self.integrals)} of {len(self.integrals)} proven; "
                   f"time {self.seconds:.2f} s")
        return "\n".join(out)


# --- the system at given values ---------------------------------------------------------------


def _check_symbols(system, symbols) -> tuple:
    """The symbols as a tuple (ε first), each ε or a parameter of ``system`` (InputError otherwise)."""
    if isinstance(symbols, str):
        symbols = symbols.split(",")
    if not isinstance(symbols, (list, tuple)) or not all(isinstance(s, str) for s in symbols):
        raise InputError(f"symbolic: expected names (strings), got {symbols!r}"[:200])
    names = [s.strip() for s in symbols if s and s.strip()]
    if not names:
        raise InputError("symbolic: name eps or parameters of the system")
    params = dict(getattr(system, "parameters", None) or {})
    for s in names:
        if names.count(s) > 1:
            raise InputError(f"symbolic: {s!r} named twice")
        if s != EPS and s not in params:
            have = ", ".join(params) or "none"
            raise InputError(f"symbolic: {s!r} is not a parameter of {getattr(system, 'name', 'the system')} "
                             f"(its parameters: {have}; and eps)")
    if any(s != EPS for s in names) and getattr(system, "kind", None) != "expressions":
        raise InputError("symbolic: parameters can be symbolic only for a system file or catalogue entry")
    return tuple(sorted(names, key=lambda s: (s != EPS, names.index(s))))


def _at_values(system, values: dict):
    """``system`` with the parameters in ``values`` replaced (a new ExpressionSystem)."""
    params = {k: v for k, v in values.items() if k != EPS}
    if not params:
        return system
    from exact_khk.systems.expressions import ExpressionSystem

    spec = system.to_json()
    spec["parameters"] = {**spec.get("parameters", {}), **{k: str(v) for k, v in params.items()}}
    spec.pop("defaults", None)  # the file's point may be singular at other parameter values
    return ExpressionSystem.from_json(spec)


def _draw(rng, name, taken) -> Fraction:
    """A small-height nonzero rational, ε in (0, 1), not drawn before for ``name``."""
    while True:
        v = Fraction(rng.randint(1, 60), rng.randint(61, 400)) if name == EPS else \
            Fraction(rng.choice([-1, 1]) * rng.randint(1, 40), rng.randint(1, 12))
        if v not in taken:
            taken.add(v)
            return v


# --- one sample ------------------------------------------------------------------------------


def _normalised(num, den) -> tuple:
    """(shape, {('n'|'d', exponent): coefficient}) of a verified N/D (dicts), each of N and D
    scaled so that its first coefficient (sorted monomials) is 1."""
    out = {}
    for tag, poly in (("n", num), ("d", den)):
        poly = {e: Fraction(c) for e, c in poly.items() if c}
        lead = poly[min(poly)]
        out.update(((tag, e), c / lead) for e, c in poly.items())
    shape = (tuple(sorted(e for e in num if num[e])), tuple(sorted(e for e in den if den[e])))
    return shape, out


def _sample(system, values, eps_fixed, kw, kind="integrals"):
    """(shape, [coefficient dicts], headline) of the verified integrals (or measure densities) at
    ``values``, or None where the search meets a singular step."""
    sysobj, eps = _at_values(system, values), values.get(EPS, eps_fixed)
    try:
        if kind == "poisson":
            from exact_khk.diagnostics.poisson import find_poisson

            res = find_poisson(sysobj, eps=eps, **kw)
            tensors = [t for t in res.tensors if t.verified]
            headline = f"{len(tensors)} verified tensor{'' if len(tensors) == 1 else 's'}"
            pairs = sorted((_normalised_tensor(t.polys) for t in tensors), key=lambda t: t[0])
            return tuple(p[0] for p in pairs), [p[1] for p in pairs], headline
        if kind == "measure":
            from exact_khk.diagnostics.measures import find_measure

            res = find_measure(sysobj, eps=eps, **kw)
            found = [(dict(d.num), dict(d.den)) for d in res.densities if d.verified]
            headline = f"{len(found)} verified densit{'y' if len(found) == 1 else 'ies'}"
        else:
            from exact_khk.diagnostics.integrals import find_integrals

            res = find_integrals(sysobj, eps=eps, **kw)
            found = [f.polynomials() for f in res.integrals if f.verified]
            headline = res.headline()
    except (SingularStepError, PoleError, ZeroDivisionError):
        return None
    pairs = sorted((_normalised(*pair) for pair in found), key=lambda t: t[0])
    return tuple(p[0] for p in pairs), [p[1] for p in pairs], headline


def _normalised_tensor(polys) -> tuple:
    """(shape, {((a, b), exponent): coefficient}) of a tensor's entries a < b, all scaled by one
    factor so that the first coefficient (sorted keys) is 1."""
    out = {(ab, e): Fraction(c) for ab, terms in polys for e, c in terms if c}
    lead = out[min(out)]
    return tuple(sorted(out)), {key: c / lead for key, c in out.items()}


# --- reconstruction --------------------------------------------------------------------------


def _value(exps, coeffs, point) -> Fraction:
    return sum((c * math.prod(p ** k for p, k in zip(point, e)) for e, c in zip(exps, coeffs)), Fraction(0))


def reconstruct(points, values, t, confirm=CONFIRM, b=None):
    """(P, Q) as {exponent: Fraction} with deg P ≤ t, deg Q ≤ b (default t; total degrees in the
    len(points[0]) symbols), P(s_i) = c_i Q(s_i) and Q(s_i) ≠ 0 at every sample, solved from all
    but the last ``confirm`` samples; None if there is none (or too few samples).

    >>> from fractions import Fraction as F
    >>> pts = [(F(k, 7),) for k in range(1, 9)]
    >>> P, Q = reconstruct(pts, [1 / (1 - 2 * e ** 2) for (e,) in pts], 2)
    >>> P, sorted(Q.items())
    ({(0,): Fraction(1, 1)}, [((0,), Fraction(1, 1)), ((2,), Fraction(-2, 1))])
    """
    k = len(points[0])
    return reconstruct_in(points, values, monomials(k, t), monomials(k, t if b is None else b), confirm)


def reconstruct_in(points, values, num_exps, den_exps, confirm=CONFIRM):
    """:func:`reconstruct` with P and Q in the spans of the monomials ``num_exps``, ``den_exps``."""
    k = len(points[0])
    m = len(num_exps)
    n_solve = len(points) - confirm
    if n_solve < m + len(den_exps) - 1:
        return None
    rows = []
    for s, c in zip(points[:n_solve], values[:n_solve]):
        row = [math.prod(p ** a for p, a in zip(s, e)) for e in num_exps] + \
              [-c * math.prod(p ** a for p, a in zip(s, e)) for e in den_exps]
        den = math.lcm(*(q.denominator for q in row))
        rows.append([int(q * den) for q in row])
    null, nullity = flint.fmpz_mat(rows).nullspace()
    for j in range(nullity):
        vec = [Fraction(int(null[i, j])) for i in range(len(rows[0]))]
        P, Q = vec[:m], vec[m:]
        if not any(Q):
            continue
        P, Q = _reduced(num_exps, P, den_exps, Q, k)
        if all((q := _value(*Q, s)) != 0 and _value(*P, s) == c * q for s, c in zip(points, values)):
            return dict(zip(*P)), dict(zip(*Q))
    return None


def _boxes(k, keys, done, on_line, samples, fill, max_degree, confirm, budget) -> bool:
    """The coefficients not in ``done`` (``keys`` per object) in the box of their degrees per
    symbol: searches along one symbol at a time (the others fixed) give deg_i P and deg_i Q by
    univariate reconstruction, then P and Q are solved in the spans of the monomials with every
    exponent ≤ those (fewer unknowns than a total-degree ansatz when the degrees concentrate on
    few symbols).  ``budget()``: the searches still allowed.  True when every coefficient is then
    reconstructed."""
    todo = [(j, key) for j, ks in enumerate(keys) for key in ks if key not in done[j]]
    degs = {jk: ([0] * k, [0] * k) for jk in todo}
    for i in range(k):
        line, more = on_line(i)
        left = set(todo)
        for a, b in levels(1, max_degree):
            if a + b + 1 + confirm - len(line) > budget():
                return False
            more(a + b + 1 + confirm)
            pts = [p for p, _ in line]
            for j, key in sorted(left):
                out = reconstruct(pts, [c[j][key] for _, c in line], a, confirm, b)
                if out is not None:
                    degs[j, key][0][i] = max((e[0] for e in out[0]), default=0)
                    degs[j, key][1][i] = max((e[0] for e in out[1]), default=0)
                    left.discard((j, key))
            if not left:
                break
        if left:
            return False
    boxes = {jk: tuple([tuple(e) for e in itertools.product(*(range(d + 1) for d in ds))] for ds in pair)
             for jk, pair in degs.items()}
    n = max(len(ne) + len(de) - 1 for ne, de in boxes.values()) + confirm
    if n - len(samples) > budget():
        return False
    fill(n)
    pts = [p for p, _ in samples]
    for (j, key), (ne, de) in boxes.items():
        out = reconstruct_in(pts, [c[j][key] for _, c in samples], ne, de, confirm)
        if out is not None:
            done[j][key] = (*out, max(sum(e) for e in list(out[0]) + list(out[1])))
    return all(len(d) == len(ks) for d, ks in zip(done, keys))


def levels(k, max_degree) -> list:
    """The (deg P, deg Q) bounds tried, fewest unknowns C(k+a, a) + C(k+b, b) − 1 first."""
    return sorted(((a, b) for a in range(max_degree + 1) for b in range(max_degree + 1)),
                  key=lambda ab: (comb(k + ab[0], k) + comb(k + ab[1], k), sum(ab), ab[1]))


def _reduced(num_exps, P, den_exps, Q, k):
    """P/Q divided by gcd(P, Q), Q's first coefficient 1: ((exps, coeffs), (exps, coeffs))."""
    ctx = flint.fmpq_mpoly_ctx.get(tuple(f"s{i}" for i in range(k)), "degrevlex")
    p = ctx.from_dict({e: flint.fmpq(c.numerator, c.denominator) for e, c in zip(num_exps, P) if c})
    q = ctx.from_dict({e: flint.fmpq(c.numerator, c.denominator) for e, c in zip(den_exps, Q) if c})
    g = p.gcd(q) if not p.is_zero() else q
    p, q = p / g, q / g
    lead = q.to_dict()[min(q.to_dict())]
    p, q = p / lead, q / lead

    def split(r):
        d = r.to_dict()
        return [tuple(int(a) for a in e) for e in d], [Fraction(int(c.p), int(c.q)) for c in d.values()]
    return split(p), split(q)


# --- the proof -------------------------------------------------------------------------------


def _field_polys(system, fld, field, R, variables, symbols, fixed):
    """The field's components as elements of R = Q[variables, symbols]."""
    gens = R.gens()
    names = dict(zip(list(variables) + list(symbols), gens))
    spec = system.to_json() if getattr(system, "kind", None) == "expressions" else None
    comps = None
    if spec is not None:
        comps = spec.get("field") if field == "f" else spec.get("fields", {}).get(field)
    if comps is None:
        if len(symbols) > (EPS in symbols):
            raise InputError(f"symbolic: the field {field!r} is not written in the system file")
        return _numeric_field(fld, gens)
    from exact_khk.systems.expression_parser import Parser

    for k, v in fixed:
        if k != EPS:
            names[k] = R.constant(flint.fmpq(v.numerator, v.denominator))
    out = []
    for v in variables:
        num, den = Parser(comps[v], f"field {v}", R, names, {}, "variables and parameters").value
        out.append(num / den)
    return out


def _numeric_field(fld, gens):
    N = fld.dim
    out = []
    for k in range(N):
        s = gens[0] * 0
        for (i, j), c in fld.terms()[k]:
            s += gens[i] * gens[j] * flint.fmpq(*_pq(c))
        for j, c in fld.linear[k]:
            s += gens[j] * flint.fmpq(*_pq(c))
        if fld.const[k]:
            s += flint.fmpq(*_pq(fld.const[k]))
        out.append(s)
    return out


def _pq(c):
    q = Fraction(str(c))
    return q.numerator, q.denominator


def kahan_system(f, R, N, eps):
    """(M, r) with M = I − ε f′(x), r = M x + 2ε f(x): the Kahan map solves M x̃ = r."""
    x = R.gens()[:N]
    M = [[(R.constant(1) if i == j else R.constant(0)) - eps * f[i].derivative(j) for j in range(N)]
         for i in range(N)]
    r = [sum((M[i][j] * x[j] for j in range(N)), R.constant(0)) + 2 * eps * f[i] for i in range(N)]
    return M, r


def kahan_image(f, R, N, eps):
    """(y, q): the Kahan map is x̃ = y/q, polynomials of R (module docstring)."""
    from exact_khk.diagnostics.degrees import bareiss

    q, y = bareiss(*kahan_system(f, R, N, eps), lambda a, b: a / b)
    return y, q


def _mod(v, p):
    return int(v.p) * pow(int(v.q), -1, p) % p


def sz_bound(num, den, M, r, N, p, trials, kind="integrals"):
    """(d, D1, bound): d bounds the total degree (in x and the symbols) of the cleared identity
    A = N^h(y, q) q^{deg D} D(x) − D^h(y, q) q^{deg N} N(x), D1 that of G = q D(x) D^h(y, q) (a
    draw with G = 0 is redrawn), so a false identity passes ``trials`` random points with
    probability ≤ (d / (p − D1))^trials.  With δ, ρ the degrees of M's and r's entries,
    deg q ≤ Nδ and deg y_i ≤ (N−1)δ + ρ (Cramer); a term c(s) x^e of N gives c(s) y^e q^{deg N − |e|}."""
    delta = max(int(e.total_degree()) for row in M for e in row)
    rho = max(int(e.total_degree()) for e in r)
    Y = max(N * delta, (N - 1) * delta + rho)

    def degs(P):
        d = P.to_dict()
        return (max(sum(map(int, e[:N])) for e in d), max(sum(map(int, e[N:])) for e in d), int(P.total_degree()))
    (dn, sn, tn), (dd, sd, td) = degs(num), degs(den)
    if kind == "measure":  # P^h(y,q) q^dQ det K^h(y,q) Q(x) - Q^h(y,q) q^(dP+N+1) P(x), deg K^h <= Y + δ
        d = max(dn * Y + sn + dd * N * delta + N * (Y + delta) + td, dd * Y + sd + (dn + N + 1) * N * delta + tn)
    else:
        d = max(dn * Y + sn + dd * N * delta + td, dd * Y + sd + dn * N * delta + tn)
    d1 = N * delta + td + dd * Y + sd
    return d, d1, min(1.0, d / (p - d1)) ** trials if p > d1 else 1.0


def _regular_points(M, r, N, p, nvars, seed, draws):
    """(x, M(x) mod p, x̃) at random points x of F_p^nvars (x and the symbols) where det M(x) ≠ 0,
    x̃ = M⁻¹ r the Kahan step mod p (its symbols copied), from at most ``draws`` draws."""
    rng = random.Random(f"sz-{seed}")
    for _ in range(draws):
        pt = [rng.randrange(p) for _ in range(nvars)]
        Mp = flint.nmod_mat(N, N, [_mod(e(*pt), p) for row in M for e in row], p)
        if Mp.det() == 0:
            continue
        rp = flint.nmod_mat(N, 1, [_mod(e(*pt), p) for e in r], p)
        yield pt, Mp, [int(v) for v in Mp.solve(rp).entries()] + pt[N:]


def prove_sz(num, den, M, r, N, p=DEFAULT_PRIME, trials=SZ_TRIALS, seed=0, K=None):
    """(holds, evidence): N(x̃) D(x) = D(x̃) N(x) (with ``K`` = :func:`step_jacobian`: the measure
    identity N(x̃) det K(x̃) D(x) = D(x̃) det M(x) N(x)) at ``trials`` random points (x, symbols) of
    F_p^(N+k) where q, D(x), D(x̃) ≠ 0, and the failure bound of :func:`sz_bound`."""
    what = "I(Phi(x)) = I(x)" if K is None else "m(Phi(x)) det dPhi(x) = m(x)"
    nvars = len(num.context().gens())
    done = 0
    for pt, Mp, xt in _regular_points(M, r, N, p, nvars, seed, 20 * trials):
        dx, dxt = _mod(den(*pt), p), _mod(den(*xt), p)
        if dx == 0 or dxt == 0:
            continue
        lhs, rhs = _mod(num(*xt), p) * dx % p, _mod(num(*pt), p) * dxt % p
        if K is not None:
            lhs = lhs * int(flint.nmod_mat(N, N, [_mod(e(*xt), p) for row in K for e in row], p).det()) % p
            rhs = rhs * int(Mp.det()) % p
        if lhs != rhs:
            return False, (f"the identity {what} FAILS at a point of F_{p}^{nvars}: the reconstruction "
                           f"is wrong (raise the samples or the degree)")
        done += 1
        if done == trials:
            break
    else:
        return False, f"no regular point in {20 * trials} draws over F_{p}: not proven"
    d, d1, bound = sz_bound(num, den, M, r, N, p, trials, "integrals" if K is None else "measure")
    return True, (f"identity {what} over F_{p} at {trials} random points (x, symbols) "
                  f"(Schwartz-Zippel), failure probability <= {bound:.3g} = (d/(p - D1))^{trials}, cleared identity "
                  f"of degree d <= {d}, draws redrawn where a denominator of degree <= {d1} vanishes")


def _homogeneous_at(P, y, q, N, deg=None):
    """(P^h(y, q), deg) for P in R homogenised in the first N generators (to degree ``deg``,
    default P's degree in them)."""
    terms = P.to_dict()
    R = P.context()
    if not terms:
        return R.constant(0), deg or 0
    deg = max(sum(map(int, e[:N])) for e in terms) if deg is None else deg
    powers_q = [R.constant(1)]
    for _ in range(deg):
        powers_q.append(powers_q[-1] * q)
    cache = {}

    def ypow(i, k):
        if (i, k) not in cache:
            cache[i, k] = R.constant(1) if k == 0 else ypow(i, k - 1) * y[i]
        return cache[i, k]
    total = R.constant(0)
    for e, c in terms.items():
        rest = R.from_dict({(0,) * N + tuple(e[N:]): c})
        mono = rest * powers_q[deg - sum(map(int, e[:N]))]
        for i in range(N):
            if e[i]:
                mono *= ypow(i, e[i])
        total += mono
    return total, deg


def prove_identity(num, den, y, q, N) -> bool:
    """num(x̃)/den(x̃) == num(x)/den(x) as rational functions (x̃ = y/q), by expansion."""
    a, dn = _homogeneous_at(num, y, q, N)
    b, dd = _homogeneous_at(den, y, q, N)
    return (a * q ** dd * den - b * q ** dn * num).is_zero()


def step_jacobian(f, R, N, eps):
    """K(x) = I + ε f′(x): dΦ(x) = M(x)⁻¹ K(Φ(x))."""
    return [[(R.constant(1) if i == j else R.constant(0)) + eps * f[i].derivative(j) for j in range(N)]
            for i in range(N)]


def prove_measure_identity(num, den, K, y, q, N) -> bool:
    """m(x̃) det dΦ(x) == m(x) for m = num/den as rational functions: det dΦ = det K^h(y, q)/q^(N+1)
    with K^h the entries of K homogenised to degree 1."""
    from exact_khk.diagnostics.degrees import bareiss

    Kh = [[_homogeneous_at(e, y, q, N, 1)[0] for e in row] for row in K]
    det, _ = bareiss(Kh, [num.context().constant(0)] * N, lambda a, b: a / b)
    a, dn = _homogeneous_at(num, y, q, N)
    b, dd = _homogeneous_at(den, y, q, N)
    return (a * q ** dd * det * den - b * q ** (dn + N + 1) * num).is_zero()


def jacobi_holds(pi, N) -> bool:
    """The Jacobi identity of the bivector ``pi`` (N x N polynomials), exactly."""
    for i in range(N):
        for j in range(i + 1, N):
            for k in range(j + 1, N):
                total = pi[0][0] * 0
                for l in range(N):
                    total += (pi[i][l] * pi[j][k].derivative(l) + pi[j][l] * pi[k][i].derivative(l)
                              + pi[k][l] * pi[i][j].derivative(l))
                if not total.is_zero():
                    return False
    return True


def _matmul(A, B):
    n, m, r = len(A), len(B), len(B[0])
    return [[sum((A[i][l] * B[l][j] for l in range(m)), A[0][0] * 0) for j in range(r)] for i in range(n)]


def _transpose(A):
    return [list(col) for col in zip(*A)]


def prove_tensor_identity(pi, K, M, y, q, N) -> bool:
    """dΦ π dΦᵀ = π∘Φ as rational functions: K^h(y, q) π(x) K^h(y, q)ᵀ q^d = M π^h(y, q) Mᵀ q² (d the
    entries' degree, dΦ = M⁻¹ K(x̃), K^h and π^h homogenised)."""
    d = max((sum(map(int, e[:N])) for row in pi for P in row for e in P.to_dict()), default=0)
    Kh = [[_homogeneous_at(e, y, q, N, 1)[0] for e in row] for row in K]
    pih = [[_homogeneous_at(e, y, q, N, d)[0] for e in row] for row in pi]
    lhs = _matmul(_matmul(Kh, pi), _transpose(Kh))
    rhs = _matmul(_matmul(M, pih), _transpose(M))
    qd, q2 = q ** d, q * q
    return all((lhs[i][j] * qd - rhs[i][j] * q2).is_zero() for i in range(N) for j in range(N))


def prove_tensor_sz(pi, K, M, r, N, p=DEFAULT_PRIME, trials=SZ_TRIALS, seed=0):
    """(holds, evidence): K(x̃) π(x) K(x̃)ᵀ = M π(x̃) Mᵀ at ``trials`` random points of F_p where
    det M ≠ 0; failure bound (d/(p − Nδ))^trials, d bounding the degree of the cleared identity
    max(2(Y + δ) + t + dπ·Nδ, 2δ + dπ·Y + s + 2Nδ) (notation of :func:`sz_bound`; t, s the total and
    symbol degrees of π's entries, dπ their degree in x)."""
    nvars = len(pi[0][0].context().gens())

    def at(A, v):
        return flint.nmod_mat(N, N, [_mod(e(*v), p) for row in A for e in row], p)
    done = 0
    for pt, Mp, xt in _regular_points(M, r, N, p, nvars, seed, 20 * trials):
        Kt = at(K, xt)
        if Kt * at(pi, pt) * Kt.transpose() != Mp * at(pi, xt) * Mp.transpose():
            return False, f"dPhi pi dPhi^T = pi o Phi FAILS at a point of F_{p}^{nvars}: the reconstruction is wrong"
        done += 1
        if done == trials:
            break
    else:
        return False, f"no regular point in {20 * trials} draws over F_{p}: not proven"
    delta = max(int(e.total_degree()) for row in M for e in row)
    rho = max(int(e.total_degree()) for e in r)
    Y = max(N * delta, (N - 1) * delta + rho)
    terms = [e for row in pi for P in row for e in P.to_dict()]
    dp = max((sum(map(int, e[:N])) for e in terms), default=0)
    sp_ = max((sum(map(int, e[N:])) for e in terms), default=0)
    tp = max((sum(map(int, e)) for e in terms), default=0)
    d = max(2 * (Y + delta) + tp + dp * N * delta, 2 * delta + dp * Y + sp_ + 2 * N * delta)
    bound = min(1.0, d / (p - N * delta)) ** trials
    return True, (f"dPhi pi dPhi^T = pi o Phi over F_{p} at {trials} random points (x, symbols) (Schwartz-Zippel), "
                  f"failure probability <= {bound:.3g} = (d/(p - D1))^{trials}, cleared identity of degree "
                  f"d <= {d}, D1 = {N * delta}")


# --- the driver ------------------------------------------------------------------------------


@any_int_digits()
def symbolic_measures(system, symbols=(EPS,), degree=2, field="f", eps=None, seed=0, **kw):
    """Invariant measure densities m of :func:`~exact_khk.diagnostics.measures.find_measure` as
    rational functions of the ``symbols``, reconstructed like :func:`symbolic_integrals` (a density
    is scaled by a function of the symbols, which keeps it invariant) and proven as the identity
    m(Φ(x)) det dΦ(x) = m(x)."""
    return symbolic_integrals(system, symbols, degree=degree, field=field, eps=eps, seed=seed, kind="measure", **kw)


@any_int_digits()
def symbolic_tensors(system, symbols=(EPS,), degree=2, field="f", eps=None, seed=0, **kw):
    """Preserved Poisson tensors of :func:`~exact_khk.diagnostics.poisson.find_poisson` as
    polynomial matrices in x and the ``symbols`` (all entries scaled by one function of the
    symbols), proven as dΦ π dΦᵀ = π∘Φ (exactly, or over F_p beyond EXACT_MAX_DIM) and the Jacobi
    identity (exactly)."""
    return symbolic_integrals(system, symbols, degree=degree, field=field, eps=eps, seed=seed, kind="poisson", **kw)


def _tensor(d, R, N, k, K, M, r, exact, names, seed, perturb):
    """One reconstructed tensor, assembled (one scale for all entries) and proven."""
    tags = sorted({key[0] for key in d})
    polys = _assemble_all(d, tags, R, N, k)
    zero = R.constant(0)
    pi = [[zero] * N for _ in range(N)]
    for (a, b), P in polys.items():
        pi[a][b], pi[b][a] = P, -P
    if perturb is not None:
        a, b = tags[0]
        pi[a][b] = pi[a][b] + R.constant(flint.fmpq(*_pq(perturb))) * R.gens()[0] ** 2
        pi[b][a] = -pi[a][b]
    if exact:
        holds = prove_tensor_identity(pi, K, M, *exact, N)
        how = ("dPhi pi dPhi^T = pi o Phi proven exactly in Q(" + ", ".join(names) + ") (python-flint fmpq_mpoly)"
               if holds else "dPhi pi dPhi^T = pi o Phi FAILS as rational functions: the reconstruction is wrong")
    else:
        holds, how = prove_tensor_sz(pi, K, M, r, N, seed=seed)
    jac = jacobi_holds(pi, N)
    how += "; Jacobi identity " + ("proven exactly (polynomial)" if jac else "FAILS")
    deg = max(tt for _, _, tt in d.values())
    entries = tuple(tuple(_text(P, names) for P in row) for row in pi)
    return ParametricIntegral("", "", deg, holds and jac, how, entries)


@any_int_digits()
def symbolic_integrals(system, symbols=(EPS,), degree=None, monomials_list=None, field="f", eps=None,
                       max_degree=MAX_DEGREE, confirm=CONFIRM, seed=0, progress=None, perturb=None, proof="auto",
                       kind="integrals", **find_kw):
    """Integrals of the Kahan map as rational functions of the ``symbols`` (ε and/or parameters of
    the system), reconstructed from :func:`find_integrals` at random values and proven (module
    docstring).  ``degree``/``monomials_list`` and ``find_kw`` go to :func:`find_integrals`; ``eps``
    is the step when ε is not a symbol; ``perturb`` (a negative control) adds perturb·x_1² to the
    first reconstructed numerator before the proof.  ``proof``: "exact"
    (expansion), "sz" (Schwartz–Zippel over F_p), or "auto" (exact up to dimension EXACT_MAX_DIM)."""
    from exact_khk.diagnostics.degrees import eps_of, resolve_field

    t0 = time.perf_counter()
    stage = check_progress(progress) or (lambda name: None)
    sysobj, fld = resolve_field(system, field)
    if sysobj is None:
        raise InputError("symbolic: needs a system (a catalogue name or a system file), not a bare field")
    symbols = _check_symbols(sysobj, symbols)
    if proof not in ("auto", "exact", "sz"):
        raise InputError(f"proof: expected auto, exact or sz, got {proof!r}")
    if kind not in ("integrals", "measure", "poisson"):
        raise InputError(f"kind: expected integrals, measure or poisson, got {kind!r}")
    check_count(max_degree, "max_degree", 0, MAX_DEGREE)
    check_count(confirm, "confirm", 1, 50)
    fixed_eps = None if EPS in symbols else eps_of(sysobj, eps)
    params = dict(getattr(sysobj, "parameters", None) or {})
    fixed = tuple(([(EPS, fixed_eps)] if fixed_eps is not None else [])
                  + [(k, v) for k, v in params.items() if k not in symbols])
    if kind in ("measure", "poisson"):
        kw = dict(degree=degree, field=field, seed=seed, **find_kw)
    else:
        kw = dict(degree=degree, monomials_list=monomials_list, field=field, seed=seed, **find_kw)
        if degree is None and monomials_list is None:
            kw["degree"] = 2
    rng = random.Random(f"symbolic-{seed}")
    taken = {s: set() for s in symbols}
    samples, shapes, dropped, headline, searches = [], [], 0, "", 0
    k = len(symbols)
    notes = []

    def need(a, b):
        return comb(k + a, a) + comb(k + b, b) - 1 + confirm

    def search(values):
        """(point, coefficients, shape) at ``values``, or None (counted as dropped)."""
        nonlocal dropped, headline, searches
        if searches >= MAX_SAMPLES:
            raise InputError(f"symbolic: more than {MAX_SAMPLES} searches (MAX_SAMPLES) needed; name fewer "
                             f"symbols or lower the degree")
        searches += 1
        try:
            out = _sample(sysobj, values, fixed_eps, kw, kind)
        except InputError:
            if not samples:  # the options themselves (or the system at its first values)
                raise
            out = None   # the system at special values (a field that vanishes, ...)
        if out is None:
            dropped += 1
            return None
        headline = headline or out[2]
        stage(f"search {searches}")
        return tuple(values[s] for s in symbols), out[1], out[0]

    def grow(n):
        while len(samples) < n:
            got = search({s: _draw(rng, s, taken[s]) for s in symbols})
            if got is not None:
                samples.append(got[:2])
                shapes.append(got[2])

    # the shape: the majority over the first samples, then only samples of that shape are kept
    grow(need(0, 0))
    shape, count = Counter(shapes).most_common(1)[0]
    if Fraction(count, len(shapes)) < MIN_SHARE:
        raise InputError(f"symbolic: the integrals found differ between the samples ({len(set(shapes))} shapes "
                         f"in {len(shapes)} searches): no common normal form to reconstruct")
    if not shape:
        return ParametricSearch(_label(sysobj, fld), symbols, fixed, (), len(samples), dropped, 0,
                                ("nothing verified at the samples: nothing to reconstruct",),
                                time.perf_counter() - t0, headline, field, kind)

    def keep():
        nonlocal dropped
        kept = [(s, c) for s, c, sh in zip([p[0] for p in samples], [p[1] for p in samples], shapes) if sh == shape]
        dropped += len(samples) - len(kept)
        samples[:] = kept
        shapes[:] = [shape] * len(kept)

    keep()
    keys = [sorted(c) for c in samples[0][1]]
    done = [dict() for _ in keys]  # per integral: key -> (P, Q, max(deg P, deg Q))

    def fill(n):
        while len(samples) < n:
            grow(n)
            keep()

    def dense(a, b):
        fill(need(a, b))
        pts = [s for s, _ in samples]
        for j, ks in enumerate(keys):
            for key in ks:
                if key not in done[j]:
                    out = reconstruct(pts, [c[j][key] for _, c in samples], a, confirm, b)
                    if out is not None:
                        done[j][key] = (*out, max(a, b))
        return all(len(d) == len(ks) for d, ks in zip(done, keys))

    def on_line(i):
        """Searches along symbol i (the others fixed at random values): [(value, coefficients)]."""
        base = {s: _draw(rng, s, taken[s]) for s in symbols}
        line = []

        def more(n):
            nonlocal dropped
            while len(line) < n:
                got = search({**base, symbols[i]: _draw(rng, symbols[i], taken[symbols[i]])})
                if got is not None and got[2] == shape:
                    line.append((got[0][i:i + 1], got[1]))
                elif got is not None:
                    dropped += 1
        return line, more

    finished = False
    for a, b in levels(k, max_degree):
        if k >= 2 and need(a, b) > DENSE_FIRST:
            break
        if dense(a, b):
            finished = True
            break
    if not finished and k >= 2:
        stage("degrees per symbol")
        finished = _boxes(k, keys, done, on_line, samples, fill, max_degree, confirm, lambda: MAX_SAMPLES - searches)
    if not finished:
        for a, b in levels(k, max_degree):
            if need(a, b) + dropped > MAX_SAMPLES:
                raise InputError(f"symbolic: numerator and denominator degrees ({a}, {b}) in {k} symbol(s) need "
                                 f"{need(a, b)} searches, beyond MAX_SAMPLES = {MAX_SAMPLES}: name fewer symbols")
            if dense(a, b):
                break
        else:
            raise InputError(f"symbolic: a coefficient is not a rational function with numerator and denominator "
                             f"of total degree <= {max_degree} in {', '.join(symbols)} (the degree limit)")
    t = max(tt for d in done for _, _, tt in d.values())
    if dropped:
        notes.append(f"{dropped} sample(s) dropped (another shape of what was found, or a singular search)")

    stage("proof")
    variables = _variables(sysobj, fld)
    N = fld.dim
    R = flint.fmpq_mpoly_ctx.get(tuple(variables) + symbols, "degrevlex")
    f = _field_polys(sysobj, fld, field, R, variables, symbols, fixed)
    eps_el = R.gens()[N + symbols.index(EPS)] if EPS in symbols else R.constant(flint.fmpq(*_pq(fixed_eps)))
    M, r = kahan_system(f, R, N, eps_el)
    exact = proof == "exact" or (proof == "auto" and N <= EXACT_MAX_DIM)
    K = step_jacobian(f, R, N, eps_el) if kind in ("measure", "poisson") else None
    what = "I(Phi(x)) = I(x)" if K is None else "m(Phi(x)) det dPhi(x) = m(x)"
    if exact:
        y, q = kahan_image(f, R, N, eps_el)
    out = []
    names = list(variables) + list(symbols)
    for j, d in enumerate(done):
        if kind == "poisson":
            out.append(_tensor(d, R, N, k, K, M, r, exact and (y, q), names, seed, perturb if j == 0 else None))
            continue
        num, den = _assemble(d, "n", R, N, k), _assemble(d, "d", R, N, k)
        if perturb is not None and j == 0:
            num = num + R.constant(flint.fmpq(*_pq(perturb))) * R.gens()[0] ** 2
        deg = max(tt for _, _, tt in d.values())
        if exact:
            holds = prove_identity(num, den, y, q, N) if K is None else prove_measure_identity(num, den, K, y, q, N)
            how = (f"identity {what} proven exactly in Q(" + ", ".join(list(variables) + list(symbols))
                   + ") (python-flint fmpq_mpoly expansion, Kahan map by fraction-free elimination)"
                   if holds else f"the identity {what} FAILS as rational functions: the "
                                 "reconstruction is wrong (raise the samples or the degree)")
        else:
            holds, how = prove_sz(num, den, M, r, N, seed=seed, K=K)
        out.append(ParametricIntegral(_text(num, names), _text(den, names), deg, holds, how))
    return ParametricSearch(_label(sysobj, fld), symbols, fixed, tuple(out), searches - dropped, dropped, t,
                            tuple(notes), time.perf_counter() - t0, headline, field, kind)


def _variables(sysobj, fld):
    names = list(sysobj.coordinate_names()) if hasattr(sysobj, "coordinate_names") else []
    return names if len(names) == fld.dim else [f"x{i}" for i in range(fld.dim)]


def _label(sysobj, fld):
    return f"{getattr(sysobj, 'name', 'field')} {fld.label}"


def _assemble(done, tag, R, N, k):
    """Σ_e c_e(s) x^e over the keys (tag, e) with c_e = P_e/Q_e, times the lcm of the Q_e, divided
    by its content; integer-primitive, the sign of its last monomial +."""
    return _assemble_all(done, [tag], R, N, k)[tag]


def _assemble_all(done, tags, R, N, k):
    """{tag: polynomial} as :func:`_assemble`, all scaled by one factor (a tensor's entries)."""
    S = flint.fmpq_mpoly_ctx.get(tuple(f"s{i}" for i in range(k)), "degrevlex")

    def poly(d):
        return S.from_dict({e: flint.fmpq(c.numerator, c.denominator) for e, c in d.items()})
    parts = {key: (poly(P), poly(Q)) for key, (P, Q, _) in done.items() if key[0] in tags}
    lcm = S.constant(1)
    for _, Q in parts.values():
        lcm = lcm * Q / lcm.gcd(Q)
    coeffs = {key: P * (lcm / Q) for key, (P, Q) in parts.items()}
    content = None
    for c in coeffs.values():
        content = c if content is None else content.gcd(c)
    terms = {tag: {} for tag in tags}
    for (tag, e), c in coeffs.items():
        for se, v in (c / content).to_dict().items():
            terms[tag][tuple(e) + tuple(se)] = v
    polys = {tag: R.from_dict(t) for tag, t in terms.items()}
    values = [c for t in terms.values() for c in t.values()]
    scale = math.lcm(*(int(c.q) for c in values)) / flint.fmpq(math.gcd(*(int(c.p) for c in values)))
    first = next(P.to_dict() for P in polys.values() if not P.is_zero())
    scale = scale if first[max(first)] > 0 else -scale
    return {tag: P * scale for tag, P in polys.items()}


def _text(P, names) -> str:
    """P in system-file syntax (``**``)."""
    return poly_text({tuple(e): Fraction(int(c.p), int(c.q)) for e, c in P.to_dict().items()}, names)


def system_file(system, result: ParametricSearch) -> str:
    """The system's own file (TOML) with the proven integrals of ``result`` added to
    ``[integrals]`` as symbolic_I1, … (parameters keep the file's values there; ``[defaults] eps``
    is set when ε was not a symbol), ready for ``exact-khk certify --system``."""
    from exact_khk.diagnostics.integrals import toml_text
    from exact_khk.systems.catalogue import resolve

    sysobj = resolve(system)
    if getattr(sysobj, "kind", None) != "expressions" or result.field != "f":
        raise InputError("toml: with --symbolic, only for a system file or catalogue entry and the field f")
    spec = sysobj.to_json()
    found = {f"symbolic_I{i}": f"({f.numerator})/({f.denominator})"
             for i, f in enumerate(result.integrals, 1) if f.proven}
    spec["integrals"] = {**spec.get("integrals", {}), **found}
    claims = list(spec.get("claims", ["reversibility", "integrals"]))
    spec["claims"] = claims + (["integrals"] if "integrals" not in claims else [])
    fixed = dict(result.fixed)
    if EPS in fixed:
        spec["defaults"] = {**spec.get("defaults", {}), "eps": str(fixed[EPS])}
    return toml_text(spec)
