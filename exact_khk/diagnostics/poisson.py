"""Poisson tensors preserved by a Kahan map, and their Casimirs.

**Preservation** of a bivector π is dΦ(x) π(x) dΦ(x)ᵀ = π(x̃), linear in π's
coefficients.  The ansatz: every entry π_ab (a < b) a polynomial of degree ≤ D;
the condition at random points of F_p^N (N(N − 1)/2 equations per point, dΦ from
nmod_mat solves) gives a kernel lifted to Q (:mod:`.darboux`).  **Jacobi** is
quadratic: on the (small) solution space Σ t_a π_a the Jacobiator's coefficients
are quadratic forms in t, solved over Q with SymPy (k ≤ :data:`MAX_JACOBI_DIM`
basis tensors); every solution is checked by the exact Jacobi identity in
``fmpq_mpoly`` (a proof), in dimension 2 every bivector is Poisson.

**Casimirs** c = U/V with π∇c = 0, i.e. π(V∇U − U∇V) = 0, linear in U for a fixed
V: V runs over 1 and the Darboux polynomials of :func:`~.measures.find_measure`
(and their factors), U over the polynomials of degree ≤ deg V (≤ the Casimir
degree for V = 1); solutions U ∝ V (constants) are dropped.  Each is proven by the
exact polynomial identity π(V∇U − U∇V) = 0 and checked for conservation on a
fresh exact orbit (a Casimir of a preserved tensor need not be conserved; the
record says which).

**Verification** of each tensor: exact Jacobi identity; dΦ π dΦᵀ = π∘Φ with
Fractions at the points of a fresh exact orbit; the identity over F_p at random
points of a prime not used to find it — cleared of denominators
(dΦ = adj M · M₂ / A², π(x̃) = π^h(Ñ, A)/A^D) it is G = 0 with
deg G ≤ 4N + D(N + 1), so a false pass has probability ≤ (deg G/(p − N))^k;
negative control (must fail): (1 + x_j)π with x_j changing along the orbit is not
preserved (inapplicable when no coordinate changes).

>>> from exact_khk.systems.expressions import ExpressionSystem
>>> lv = ExpressionSystem.from_expressions(["x", "y"], field=["x - x*y", "x*y - y"])
>>> res = find_poisson(lv, degree=2, eps="1/10")
>>> [t.entries[0][1] for t in res.tensors]
['x*y']
"""

from __future__ import annotations

import random
import time
from dataclasses import dataclass
from fractions import Fraction

import flint

from exact_khk.diagnostics.darboux import (MARGIN, ModMap, _Evaluator, _q, eval_poly, lifted_kernel,
                                           mpoly_ctx, primitive, rows_of_points)
from exact_khk.diagnostics.degrees import eps_of, random_primes, resolve_field
from exact_khk.diagnostics.kernels import independent_count, monomials
from exact_khk.diagnostics.measures import (SZ_POINTS, Check, _fresh_orbit, _variables, expr, find_measure,
                                            verified)
from exact_khk.errors import InputError
from exact_khk.parsing import any_int_digits, check_progress, check_count, parse_vector

#: the largest dimension of the preserved-tensor space on which the Jacobi identity is solved
MAX_JACOBI_DIM = 4


@dataclass(frozen=True)
class Casimir:
    text: str
    num: tuple
    den: tuple
    conserved: object      # True/False on a fresh exact orbit

    @any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
    def to_json(self):
        return {"casimir": self.text, "proven": True, "conserved_by_map": self.conserved}


@dataclass(frozen=True)
class Tensor:
    entries: tuple         # N x N texts (system-file syntax)
    polys: tuple           # {(a, b): dict} items for a < b
    rank: int
    checks: tuple
    casimirs: tuple

    @property
    def verified(self) -> bool:
        """The exact orbit check held, no other check failed, and every applicable control failed."""
        return verified(self.checks)

    @any_int_digits()
    def to_json(self):
        return {"matrix": [list(r) for r in self.entries], "rank": self.rank, "verified": self.verified,
                "checks": [c.to_json() for c in self.checks], "casimirs": [c.to_json() for c in self.casimirs]}


@dataclass(frozen=True)
class PoissonSearch:
    label: str
    eps: Fraction
    degree: int
    variables: tuple
    kernel_dim: int
    tensors: tuple
    primes: tuple
    notes: tuple
    seconds: float

    @any_int_digits()
    def to_json(self):
        return {"field": self.label, "eps": str(self.eps), "degree": self.degree, "kernel_dim": self.kernel_dim,
                "tensors": [t.to_json() for t in self.tensors], "primes": list(self.primes),
                "notes": list(self.notes), "seconds": self.seconds}

    @any_int_digits()
    def toml(self) -> str:
        good = [t for t in self.tensors if t.verified]
        if not good:
            return f"# no preserved Poisson tensor found at degree <= {self.degree}\n"
        rows = ",\n          ".join("[" + ", ".join(f'"{e}"' for e in r) + "]" for r in good[0].entries)
        return f"[poisson]\n# found by exact-khk find-poisson at eps = {self.eps}\nmatrix = [{rows}]\n"

    @any_int_digits()
    def summary(self) -> str:
        out = [f"Poisson search for {self.label} at eps = {self.eps}: entries of degree <= {self.degree}",
               f"  preserved bivectors (dPhi pi dPhi^T = pi o Phi): a space of dimension {self.kernel_dim}"]
        if not self.tensors:
            out.append("  no preserved Poisson tensor of this degree (nothing found)")
        for n, t in enumerate(self.tensors, 1):
            out.append(f"  Poisson tensor {n} (rank {t.rank}) [{'VERIFIED' if t.verified else 'NOT verified'}]:")
            N = len(t.entries)
            out += [f"    pi[{a}][{b}] = {t.entries[a][b]}" for a in range(N) for b in range(a + 1, N)
                    if t.entries[a][b] != "0"]
            for c in t.checks:
                mark = {True: "holds", False: "fails", None: "inapplicable"}[c.holds]
                out.append(f"    {c.name}: {mark} ({c.detail})")
            for c in t.casimirs:
                out.append(f"    Casimir {c.text}  (pi grad C = 0 proven exactly; conserved by the map on a fresh "
                           f"orbit: {'yes' if c.conserved else 'no'})")
            if t.rank < N and not t.casimirs:
                out.append("    no Casimir found among U/V, V = 1 or a Darboux polynomial")
        out += [f"  note: {n}" for n in self.notes]
        out.append(f"  primes {len(self.primes)}; time {self.seconds:.2f} s")
        return "\n".join(out)


@any_int_digits()
def find_poisson(system, degree=2, field="f", eps=None, seed=0, verify_steps=3, casimir_degree=2,
                 measure_degree=2, x0=None, progress=None) -> PoissonSearch:
    """Preserved Poisson tensors with polynomial entries of degree ≤ ``degree`` and their Casimirs
    (module docstring); ``x0``: the start of the exact orbit checks (default a fresh reproducible point)."""
    t0 = time.perf_counter()
    stage = check_progress(progress) or (lambda name: None)
    sysobj, fld = resolve_field(system, field)
    eps = eps_of(sysobj, eps)
    N = fld.dim
    check_count(degree, "degree", 0, 8)
    check_count(casimir_degree, "casimir_degree", 1, 8)
    check_count(verify_steps, "verify_steps", 1, 100)
    check_count(measure_degree, "measure_degree", 1, 12)
    seed = check_count(seed, "seed", -2 ** 63, 2 ** 63)
    x0 = None if x0 is None else parse_vector(x0, "x0", N)  # exact rationals only, as everywhere
    if N < 2:  # no unknowns: the search for rows would never end
        raise InputError(f"system: dimension {N}: a Poisson tensor needs dimension >= 2 (the only 1 x 1 "
                         "skew-symmetric matrix is 0)")
    variables = _variables(sysobj, N)
    exps = monomials(N, degree)
    m = len(exps)
    pairs = [(a, b) for a in range(N) for b in range(a + 1, N)]
    unknowns = m * len(pairs)
    ev = _Evaluator(exps)
    notes = []

    def make_rows(p, rng):
        mm = ModMap(fld, eps, p)

        def rows_at(at):
            x, xt, D, _, _ = at
            D = [[int(D[i, j]) for j in range(N)] for i in range(N)]
            vx, vt = ev(x, 1, p), ev(xt, 1, p)
            out = []
            for i, j in pairs:
                row = []
                for a, b in pairs:
                    w = (D[i][a] * D[j][b] - D[i][b] * D[j][a]) % p
                    same = (a, b) == (i, j)
                    row += [((t if same else 0) - w * s) % p for t, s in zip(vt, vx)]
                out.append(row)
            return out
        return rows_of_points(N, unknowns + MARGIN, mm, rows_at, rng)

    stage("preserved bivectors")
    basis, used = lifted_kernel(make_rows, unknowns, seed, progress=progress)
    primes = set(used)
    tensors_q = [{pr: {e: v[k * m + j] for j, e in enumerate(exps) if v[k * m + j]} for k, pr in enumerate(pairs)}
                 for v in basis]
    stage("Jacobi identity")
    poissons = _jacobi_solutions(tensors_q, N, notes)
    darboux = []
    if poissons and N > 2:
        stage("Darboux polynomials for Casimirs")
        ms = find_measure(sysobj if sysobj is not None else fld, degree=measure_degree, field=field, eps=eps, seed=seed)
        for d in ms.darboux:
            darboux += [dict(P) for P in d.polys if dict(P) not in darboux]
    tensors = []
    for pi in poissons:
        pi = _normalised(pi)
        stage("verify the tensor")
        tensors.append(_tensor(fld, eps, pi, N, degree, variables, seed, verify_steps, primes, darboux,
                               casimir_degree, x0))
    label = f"{sysobj.name if sysobj is not None else 'field'} {fld.label}"
    if not basis:
        notes.append(f"nothing found: no nonzero bivector with entries of degree <= {degree} is preserved "
                     "(proven: the kernel is 0 modulo a prime, so it is 0 over Q; try a higher --degree)")
    return PoissonSearch(label, eps, degree, tuple(variables), len(basis), tuple(tensors), tuple(sorted(primes)),
                         tuple(notes), time.perf_counter() - t0)


# --- Jacobi ------------------------------------------------------------------------


def _mp(ctx, poly):
    return ctx.from_dict({e: _q(c) for e, c in poly.items()})


def _matrix(ctx, pi, N):
    zero = ctx.from_dict({})
    P = [[zero for _ in range(N)] for _ in range(N)]
    for (a, b), poly in pi.items():
        P[a][b] = _mp(ctx, poly)
        P[b][a] = -P[a][b]
    return P


def jacobiator(P, Q, N):
    """The bilinear Jacobiator Σ_cyc Σ_s P_is ∂_s Q_jl over i < j < l (list of polys)."""
    out = []
    for i in range(N):
        for j in range(i + 1, N):
            for l in range(j + 1, N):
                total = 0 * P[0][0]
                for a, b, c in ((i, j, l), (j, l, i), (l, i, j)):
                    for s in range(N):
                        if not P[a][s].is_zero() and not Q[b][c].is_zero():
                            total = total + P[a][s] * Q[b][c].derivative(s)
                out.append(total)
    return out


def _jacobi_solutions(tensors, N, notes):
    """The Poisson tensors among Σ t_a π_a (rational solutions of the Jacobi identity)."""
    k = len(tensors)
    if k == 0:
        return []
    if N == 2:
        if k > 1:
            notes.append(f"{k} independent preserved bivectors (dimension 2: all Poisson); their ratios are "
                         "integrals; the first is reported")
        return tensors[:1]
    ctx = mpoly_ctx(N)
    mats = [_matrix(ctx, t, N) for t in tensors]
    if k == 1:
        ok = all(j.is_zero() for j in jacobiator(mats[0], mats[0], N))
        if not ok:
            notes.append("the preserved bivector does not satisfy the Jacobi identity")
        return tensors if ok else []
    if k > MAX_JACOBI_DIM:
        notes.append(f"{k} independent preserved bivectors: beyond {MAX_JACOBI_DIM} (MAX_JACOBI_DIM) the Jacobi "
                     "identity is checked on the basis only")
        return [t for t, M in zip(tensors, mats) if all(j.is_zero() for j in jacobiator(M, M, N))]
    import sympy

    ts = sympy.symbols(f"t0:{k}")
    eqs = {}
    for a in range(k):
        for b in range(k):
            for n, poly in enumerate(jacobiator(mats[a], mats[b], N)):
                for e, c in poly.to_dict().items():
                    key = (n, tuple(e))
                    eqs[key] = eqs.get(key, 0) + sympy.Rational(int(c.p), int(c.q)) * ts[a] * ts[b]
    system = [sympy.expand(q) for q in eqs.values() if sympy.expand(q) != 0]
    found = []
    for c in range(k):  # projective charts: t_0 = .. = t_{c-1} = 0, t_c = 1
        fixed = {ts[i]: 0 for i in range(c)}
        fixed[ts[c]] = 1
        rest = [t for t in ts if t not in fixed]
        eq = [q for q in (sympy.expand(q.subs(fixed)) for q in system) if q != 0]
        sols = [{}] if not eq else sympy.solve(eq, rest, dict=True) if rest else []
        for sol in sols:
            vals = dict(fixed)
            free = [t for t in rest if t not in sol]
            if free:
                note = (f"the Jacobi identity leaves {len(free)} parameter(s) free on the chart t{c} = 1 of the "
                        "preserved space: a family of Poisson tensors; one member per chart is reported")
                if note not in notes:
                    notes.append(note)
            vals.update({t: 0 for t in free})
            vals.update({t: v.subs({f: 0 for f in free}) for t, v in sol.items()})
            vals = {t: sympy.sympify(v) for t, v in vals.items()}
            if not all(v.is_Rational for v in vals.values()):
                notes.append("a Poisson tensor with irrational coefficients exists in the preserved space "
                             "(not reported)")
                continue
            t = [Fraction(int(vals[s].p), int(vals[s].q)) for s in ts]
            found.append(t)
    out = []
    for t in found:
        pi = {}
        for coef, tensor in zip(t, tensors):
            for pr, poly in tensor.items():
                for e, c in poly.items():
                    pi.setdefault(pr, {})
                    pi[pr][e] = pi[pr].get(e, 0) + coef * c
        pi = {pr: {e: c for e, c in poly.items() if c} for pr, poly in pi.items()}
        M = _matrix(ctx, pi, N)
        if any(pi.values()) and all(j.is_zero() for j in jacobiator(M, M, N)):
            out.append(pi)
    if not out:
        notes.append(f"{k} preserved bivectors, but no rational combination satisfies the Jacobi identity")
    return out


def _normalised(pi):
    """Scaled to coprime integer coefficients, the first nonzero entry's first coefficient positive."""
    allc = {(pr, e): c for pr, poly in sorted(pi.items()) for e, c in poly.items()}
    prim = primitive({(i,): c for i, c in enumerate(allc.values())})
    scale = prim[(0,)] / next(iter(allc.values()))
    return {pr: {e: c * scale for e, c in poly.items()} for pr, poly in pi.items()}


# --- verification ------------------------------------------------------------------


def _tensor(fld, eps, pi, N, degree, variables, seed, steps, used, darboux, casimir_degree, x0) -> Tensor:
    ctx = mpoly_ctx(N)
    entries = [["0"] * N for _ in range(N)]
    for (a, b), poly in pi.items():
        if poly:
            entries[a][b] = expr(poly, variables)
            neg = expr({e: -c for e, c in poly.items()}, variables)
            entries[b][a] = neg
    checks = []
    if N == 2:
        checks.append(Check("Jacobi identity", True, "dimension 2: every bivector is Poisson"))
    else:
        M = _matrix(ctx, pi, N)
        checks.append(Check("Jacobi identity", all(j.is_zero() for j in jacobiator(M, M, N)),
                            "exact, as a polynomial identity (fmpq_mpoly)"))

    def full(x):
        P = [[flint.fmpq(0)] * N for _ in range(N)]
        for (a, b), poly in pi.items():
            P[a][b] = flint.fmpq(eval_poly(poly, x))  # the orbit's points are fmpq
            P[b][a] = -P[a][b]
        return P

    orbit = _fresh_orbit(fld, eps, seed, steps, {(0,) * N: 1}, {(0,) * N: 1}, x0)
    moving = None
    if orbit is None:
        checks.append(Check("exact orbit", None, "no orbit without a singular step was found"))
    else:
        x0, data = orbit

        def preserved(scale):
            for x, xt, _, _, D in data:
                P, Pt = full(x), full(xt)
                s, st = scale(x), scale(xt)
                lhs = [[s * sum(D[i][a] * P[a][b] * D[j][b] for a in range(N) for b in range(N))
                        for j in range(N)] for i in range(N)]
                if any(lhs[i][j] != st * Pt[i][j] for i in range(N) for j in range(N)):
                    return False
            return True
        checks.append(Check("exact orbit", preserved(lambda x: 1),
                            f"dPhi pi dPhi^T = pi o Phi exactly (fmpq) at {len(data)} points of the orbit of "
                            f"({', '.join(map(str, x0))})"))
        moving = next((j for j in range(N) if any(x[j] != xt[j] for x, xt, *_ in data)), None)
        if moving is None:
            checks.append(Check("control: (1 + x_j) pi", None, "every coordinate is constant along the orbit"))
        else:
            checks.append(Check("control: (1 + x_j) pi", preserved(lambda x: 1 + x[moving]),
                                f"[must fail] (1 + {variables[moving]}) pi preserved on the same orbit"))
    p = next(q for q in random_primes(len(used) + 8, seed + 7907) if q not in used)
    mm, rng = ModMap(fld, eps, p), random.Random(f"sz-poisson-{seed}")
    pm = {pr: {e: c.numerator * pow(c.denominator, -1, p) for e, c in poly.items()} for pr, poly in pi.items()}

    def at_mod(x):
        P = [[0] * N for _ in range(N)]
        for (a, b), poly in pm.items():
            P[a][b] = eval_poly(poly, x) % p
            P[b][a] = -P[a][b] % p
        return flint.nmod_mat(N, N, [v for r in P for v in r], p)
    ok, k = True, 0
    while k < SZ_POINTS:
        at = mm.at([rng.randrange(p) for _ in range(N)])
        if at is None:
            continue
        x, xt, D, _, _ = at
        k += 1
        ok = ok and D * at_mod(x) * D.transpose() == at_mod(xt)
    bound = 4 * N + degree * (N + 1)
    checks.append(Check("identity over F_p", ok, f"{SZ_POINTS} random points mod a fresh {p.bit_length()}-bit prime; "
                        f"deg G <= {bound}, false pass <= ({bound}/(p - {N}))^{SZ_POINTS}"))
    rank = _rank(pi, N, seed)
    casimirs = _casimirs(fld, eps, pi, N, rank, variables, seed, steps, darboux, casimir_degree, x0) \
        if rank < N else ()
    return Tensor(tuple(tuple(r) for r in entries), tuple(sorted((pr, tuple(sorted(poly.items())))
                                                                 for pr, poly in pi.items())),
                  rank, tuple(checks), casimirs)


def _rank(pi, N, seed):
    rng = random.Random(f"rank-{seed}")
    best = 0
    for _ in range(3):
        x = [Fraction(rng.randint(-50, 50), rng.randint(1, 9)) for _ in range(N)]
        P = [[flint.fmpq(0)] * N for _ in range(N)]
        for (a, b), poly in pi.items():
            v = Fraction(eval_poly(poly, x))
            P[a][b], P[b][a] = flint.fmpq(v.numerator, v.denominator), -flint.fmpq(v.numerator, v.denominator)
        best = max(best, flint.fmpq_mat(N, N, [t for r in P for t in r]).rank())
    return best


def _casimirs(fld, eps, pi, N, rank, variables, seed, steps, darboux, casimir_degree, x0):
    """Casimirs U/V (module docstring), functionally independent, at most N − rank."""
    ctx = mpoly_ctx(N)
    P = _matrix(ctx, pi, N)
    one = {(0,) * N: Fraction(1)}
    out, pairs = [], []
    for V in [one] + darboux:
        if len(out) >= N - rank:
            break
        dV = max(sum(e) for e in V)
        exps = monomials(N, dV if dV else casimir_degree)
        m = len(exps)
        Vm = _mp(ctx, V)
        mons = [ctx.from_dict({e: 1}) for e in exps]
        cols = []  # for each monomial φ: the vector π(V∇φ − φ∇V) of polys
        for ph in mons:
            g = [Vm * ph.derivative(s) - ph * Vm.derivative(s) for s in range(N)]
            cols.append([sum((P[i][s] * g[s] for s in range(N)), 0 * Vm) for i in range(N)])

        def make_rows(p, rng, cols=cols):
            rows = []
            while len(rows) < m + MARGIN:
                x = [rng.randrange(p) for _ in range(N)]
                for i in range(N):
                    rows.append([int(_eval_mod(col[i], x, p)) for col in cols])
            return rows
        basis, _ = lifted_kernel(make_rows, m, seed)
        for v in basis:
            U = primitive({e: c for e, c in zip(exps, v) if c})
            Um = _mp(ctx, U)
            if (Um.total_degree() == Vm.total_degree() and (divmod(Um, Vm)[1].is_zero())) or not U:
                continue  # U ∝ V: a constant
            # proof: π(V∇U − U∇V) = 0 exactly
            g = [Vm * Um.derivative(s) - Um * Vm.derivative(s) for s in range(N)]
            if not all(sum((P[i][s] * g[s] for s in range(N)), 0 * Vm).is_zero() for i in range(N)):
                continue
            if independent_count(pairs + [(U, V)], random.Random(seed)) <= len(pairs):
                continue
            pairs.append((U, V))
            text = expr(U, variables) if V == one else \
                f"({expr(U, variables)})/({expr(V, variables)})"
            out.append(Casimir(text, tuple(sorted(U.items())), tuple(sorted(V.items())),
                               _conserved(fld, eps, U, V, seed, steps, x0)))
    return tuple(out)


def _eval_mod(poly, x, p):
    total = 0
    for e, c in poly.to_dict().items():
        term = int(c.p) * pow(int(c.q), -1, p)
        for xi, k in zip(x, e):
            if k:
                term = term * pow(xi, int(k), p) % p
        total += term
    return total % p


def _conserved(fld, eps, U, V, seed, steps, x0):
    orbit = _fresh_orbit(fld, eps, seed, steps, U, V, x0)
    if orbit is None:
        return None
    _, data = orbit
    vals = [flint.fmpq(eval_poly(U, x)) / eval_poly(V, x) for x, *_ in data] + \
        [flint.fmpq(eval_poly(U, data[-1][1])) / eval_poly(V, data[-1][1])]
    return len(set(vals)) == 1


__all__ = ["find_poisson", "PoissonSearch", "Tensor", "Casimir", "jacobiator"]
