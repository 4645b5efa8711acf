"""Independent study of the Kahan map of the Clebsch system (issue 41): its Hirota–Kimura bases, the
degrees of the integrals they give, how many are independent, and a proof that given integrals are
conserved.  SymPy, Fractions and plain integer arithmetic mod p only (no exact_khk code).

The system (tests/test_find_integrals.py CLEBSCH): m' = p x (Omega p), p' = p x m with
Omega = diag(w1, w2, w3), i.e. m1' = (w3 - w2) p2 p3, ..., p1' = p2 m3 - p3 m2, ...; Kahan step in the
project's convention x~ = x + 2 eps (I - eps f'(x))^{-1} f(x).

1. The orbit kernel over all 28 monomials of degree <= 2 (mod p) and its support; the exact kernel over
   Q on that support from one exact orbit (Fractions).
2. HK bases: every minimal set S of support monomials with dim(K ∩ span S) = 1 (a circuit), from the
   exact kernel.
3. For every circuit and pair (i, j) of its entries: the degrees (deg N, deg D) of the integral c_i/c_j
   along a random line x0 = a + t b (values at t = 1, 2, ... mod p, univariate rational
   reconstruction), and its gradient mod p (dual numbers x0 + delta e_l along the orbit); the rank of
   the gradients, cumulated by degree, says which degree first shows 1, 2, 3, 4 independent integrals.
4. ``--prove FILE.json`` (the JSON of ``exact-khk find-integrals --json``, or any list of
   {"numerator", "denominator"} with ** or ^): each I = N/D (degrees n, d) is conserved, proven by
   Schwartz–Zippel.  With x~ = X/Delta (Delta = det(I - eps f'(x)) of degree <= 6, X = Delta x +
   2 eps adj(I - eps f') f of degree <= 7) and P^h the homogenisation, I(x~) = I(x) where defined iff
   R0 = N^h(X, Delta) Delta^d D(x) - N(x) D^h(X, Delta) Delta^n = 0, a polynomial of degree <= 7(n + d).
   R = R0 Delta D(x) D^h(X, Delta) (degree <= B = 7(n + d) + 6 + 8d) vanishes at every point drawn: there
   either a denominator vanishes or I(x~) = I(x) is checked exactly.  If I were not conserved, R0 and so
   R would be nonzero polynomials (Delta, D and D o Phi are nonzero, Phi being birational), and R would
   vanish at a uniform random point of [-S, S]^6 with probability <= B / (2S + 1) (Schwartz–Zippel):
   k draws leave probability <= (B / (2S + 1))^k.  Then the exact rank of the Jacobian of all of them at
   a rational point (SymPy).

    python scripts/check_clebsch_integrals.py [--omega 1,2,5] [--eps 1/10] [--prove FILE.json]

Findings (eps = 1/10, Omega = diag(1, 2, 5) and diag(1, 2, 4), the same at both; about 3 min):
* the kernel at degree <= 2 has dimension 4 and lives on 1, p_k^2, m_k p_k, m_k^2 (10 monomials);
* 93 HK bases: {1, p1^2, p2^2, p3^2}; four of size 6 inside {1, p_k^2, m_k p_k}; 88 of size 7, each with two
  or three m_k^2.  The ratios of the first have degrees (2, 2) and Jacobian rank 1 (one integral,
  (1/eps^2 + (w3 - w1) p1^2 + (w3 - w2) p2^2)/(p1^2 + p2^2 + p3^2) up to a Moebius map, as find-integrals
  reports it at both Omega); those inside {1, p_k^2, m_k p_k} rank 3;
* cumulated by degree, the ratios' rank is 1 at degree 2, 2 at 6 (c_{m3p3}/c_{m2p2}, degrees (6, 6)), 3 at 8,
  and 4 only at 10: c_1/c_{m3p3} of {1, p3^2, m1p1, m2p2, m3p3, m1^2, m2^2}, degrees (10, 8); higher ratios
  have degrees 12 to 20;
* --prove on `exact-khk find-integrals --system clebsch --json` (Omega = (1, 2, 4)): its 4 integrals, of
  degrees 2/2, 8/8, 8/8, 10/8 (the last three over one denominator of degree 8), are conserved (12 points
  each, failure probability <= (196/(2*10^12 + 1))^12) with exact Jacobian rank 4.
"""
import argparse
import itertools
import json
import random
import sys
from fractions import Fraction as F

import sympy as sp

ap = argparse.ArgumentParser()
ap.add_argument("--omega", default="1,2,5")
ap.add_argument("--eps", default="1/10")
ap.add_argument("--prove", default=None)
ap.add_argument("--points", type=int, default=12)
args = ap.parse_args()
w1, w2, w3 = (sp.Rational(s) for s in args.omega.split(","))
eps = sp.Rational(args.eps)
X = sp.symbols("m1 m2 m3 p1 p2 p3")
m1, m2, m3, p1, p2, p3 = X
f = sp.Matrix([(w3 - w2) * p2 * p3, (w1 - w3) * p3 * p1, (w2 - w1) * p1 * p2,
               p2 * m3 - p3 * m2, p3 * m1 - p1 * m3, p1 * m2 - p2 * m1])
A = sp.eye(6) - eps * f.jacobian(X)          # linear in x
P = 2 ** 61 - 1
print(f"Clebsch system, Omega = diag({w1}, {w2}, {w3}), eps = {eps}; Kahan step x + 2 eps (I - eps f')^-1 f")


def terms(e, mod=None):
    poly = sp.Poly(sp.expand(e), *X)
    if mod is None:
        return [(mon, F(int(c.p), int(c.q))) for mon, c in poly.terms()]
    return [(mon, int(c.p) * pow(int(c.q), -1, mod) % mod) for mon, c in poly.terms()]


A_q, f_q = [[terms(A[i, j]) for j in range(6)] for i in range(6)], [terms(f[i]) for i in range(6)]
A_p, f_p = [[terms(A[i, j], P) for j in range(6)] for i in range(6)], [terms(f[i], P) for i in range(6)]
TWO_EPS_P = int((2 * eps).p) * pow(int((2 * eps).q), -1, P) % P


class Dual:
    """a + b delta mod P with delta^2 = 0 (derivatives along the orbit)."""
    __slots__ = ("a", "b")

    def __init__(self, a, b=0):
        self.a, self.b = a % P, b % P

    def __add__(self, o):
        o = o if isinstance(o, Dual) else Dual(o)
        return Dual(self.a + o.a, self.b + o.b)

    __radd__ = __add__

    def __sub__(self, o):
        o = o if isinstance(o, Dual) else Dual(o)
        return Dual(self.a - o.a, self.b - o.b)

    def __mul__(self, o):
        o = o if isinstance(o, Dual) else Dual(o)
        return Dual(self.a * o.a, self.a * o.b + self.b * o.a)

    __rmul__ = __mul__

    def inv(self):
        ia = pow(self.a, -1, P)
        return Dual(ia, -self.b * ia * ia)

    def __bool__(self):
        return bool(self.a or self.b)


class Mod:
    """Arithmetic of plain integers mod P, Fractions or Duals behind one interface."""

    def __init__(self, kind):
        self.kind = kind

    def const(self, c):
        return c if self.kind != "dual" else Dual(c)

    def ev(self, ts, x):
        s = self.const(0)
        for mon, c in ts:
            v = self.const(c)
            for xi, k in zip(x, mon):
                for _ in range(k):
                    v = v * xi
            s = s + v
        return s % P if self.kind == "mod" else s

    def inv(self, v):
        return pow(v, -1, P) if self.kind == "mod" else (v.inv() if self.kind == "dual" else 1 / v)

    def nz(self, v):
        return v.a != 0 if self.kind == "dual" else v != 0

    def red(self, v):
        return v % P if self.kind == "mod" else v

    def solve(self, M, b):
        n = len(b)
        M = [row[:] + [bb] for row, bb in zip(M, b)]
        for c in range(n):
            r = next(r for r in range(c, n) if self.nz(M[r][c]))
            M[c], M[r] = M[r], M[c]
            iv = self.inv(M[c][c])
            M[c] = [self.red(v * iv) for v in M[c]]
            for r in range(n):
                if r != c and M[r][c]:
                    k = M[r][c]
                    M[r] = [self.red(a - k * b) for a, b in zip(M[r], M[c])]
        return [M[i][n] for i in range(n)]

    def step(self, x):
        At, ft = (A_q, f_q) if self.kind == "exact" else (A_p, f_p)
        y = self.solve([[self.ev(At[i][j], x) for j in range(6)] for i in range(6)], [self.ev(t, x) for t in ft])
        two_eps = F(2 * eps.p, eps.q) if self.kind == "exact" else TWO_EPS_P
        return [self.red(a + two_eps * b) for a, b in zip(x, y)]

    def orbit(self, x, n):
        out = [x]
        for _ in range(n):
            out.append(self.step(out[-1]))
        return out


def monomials(d):
    return [e for e in itertools.product(range(d + 1), repeat=6) if sum(e) <= d]


def mono_val(e, x, one):
    v = one
    for xi, k in zip(x, e):
        for _ in range(k):
            v = v * xi
    return v


def rref_mod(rows, m):
    """(R, pivots): the reduced echelon form mod P of ``rows`` over their first m columns."""
    R, piv, r0 = [r[:] for r in rows], [], 0
    for c in range(m):
        r = next((r for r in range(r0, len(R)) if R[r][c]), None)
        if r is None:
            continue
        R[r0], R[r] = R[r], R[r0]
        iv = pow(R[r0][c], -1, P)
        R[r0] = [v * iv % P for v in R[r0]]
        for r in range(len(R)):
            if r != r0 and R[r][c]:
                k = R[r][c]
                R[r] = [(a - k * b) % P for a, b in zip(R[r], R[r0])]
        piv.append(c)
        r0 += 1
    return R, piv


def nullspace_mod(rows, m):
    R, piv = rref_mod(rows, m)
    out = []
    for fc in [c for c in range(m) if c not in piv]:
        v = [0] * m
        v[fc] = 1
        for i, c in enumerate(piv):
            v[c] = -R[i][fc] % P
        out.append(v)
    return out


def name(e):
    return "*".join(f"{s}" + (f"**{k}" if k > 1 else "") for s, k in zip(X, e) if k) or "1"


rng = random.Random(2026)
mod, dual, exact = Mod("mod"), Mod("dual"), Mod("exact")

# 1. the kernel over all monomials of degree <= 2, mod P, and its support
all2 = monomials(2)
x0 = [rng.randrange(P) for _ in range(6)]
K28 = nullspace_mod([[mono_val(e, x, 1) % P for e in all2] for x in mod.orbit(x0, 40)], len(all2))
support = [e for k, e in enumerate(all2) if any(v[k] for v in K28)]
print(f"1. orbit kernel over the {len(all2)} monomials of degree <= 2: dimension {len(K28)} (mod p, 41 points), "
      f"support {len(support)} monomials: {', '.join(map(name, support))}")
xq = [F(rng.randint(-9, 9), rng.randint(1, 5)) for _ in range(6)]
rows = [[mono_val(e, x, F(1)) for e in support] for x in exact.orbit(xq, len(support) + 4)]
K = sp.Matrix(rows).nullspace()
print(f"   exact kernel on the support over Q (orbit of {len(rows)} points from {[str(t) for t in xq]}): "
      f"dimension {len(K)}")
m = len(support)
Kb = [list(v) for v in K]


def dim_in(S):  # dim K ∩ span S = dim K - rank of K restricted to the other columns
    other = [c for c in range(m) if c not in S]
    return len(Kb) - (sp.Matrix([[v[c] for c in other] for v in Kb]).rank() if other else 0)


# 2. HK bases: the circuits (minimal sets S with a one-dimensional kernel), exactly
circ = []
for r in range(1, m + 1):
    for S in itertools.combinations(range(m), r):
        if not any(set(C) <= set(S) for C in circ) and dim_in(S) >= 1:
            assert dim_in(S) == 1
            circ.append(S)
sizes = {}
for S in circ:
    sizes[len(S)] = sizes.get(len(S), 0) + 1
print(f"2. HK bases (circuits, exact): {len(circ)}; by size {dict(sorted(sizes.items()))}")
for S in circ:
    if len(S) < max(sizes):
        print("   ", ", ".join(name(support[c]) for c in S))


# 3. degrees along a line and gradients of every ratio c_i/c_j
def circuit_vector(rows_, S, kind):
    """The kernel vector on S of evaluation rows (ints mod P or Duals), normalised to c_S[-1] = 1."""
    if kind == "mod":
        ns = nullspace_mod([[r[c] for c in S] for r in rows_], len(S))
        return ns[0] if len(ns) == 1 and ns[0][-1] == 1 else None
    ra = [[r[c].a for c in S] for r in rows_]
    ns = nullspace_mod(ra, len(S))
    if len(ns) != 1 or ns[0][-1] != 1:
        return None
    c = ns[0]
    rhs = [-sum(r[k].b * ck for k, ck in zip(S, c)) % P for r in rows_]
    # c' with c'_last = 0: ra[:, :-1] c' = rhs (consistent, full column rank)
    aug = [row[:-1] + [b] for row, b in zip(ra, rhs)]
    n = len(S) - 1
    R, piv = rref_mod(aug, n)
    assert piv == list(range(n)) and all(not R[r][n] for r in range(n, len(R)))
    return c, [R[i][n] for i in range(n)] + [0]


TOP = 24  # the highest degree read along the line


def ratfun(ts, gs):
    """(N, D) as SymPy polynomials in t over GF(P), N/D reduced, matching the values gs at ts
    (degrees <= TOP): at degree bound d the solutions (N, D) form a space of dimension d - d0 + 1 once
    d >= d0 = max(deg N, deg D) (multiples of the reduced pair), so one solve at TOP gives d0."""
    def solve(d):
        return nullspace_mod([[pow(t, k, P) for k in range(d + 1)] + [-g * pow(t, k, P) % P for k in range(d + 1)]
                              for t, g in zip(ts, gs)], 2 * d + 2)
    d0 = TOP + 1 - len(solve(TOP))
    ns = solve(d0)
    if d0 < 0 or len(ns) != 1:
        return None
    v = ns[0]
    return (sp.Poly(list(reversed(v[:d0 + 1])), T, modulus=P), sp.Poly(list(reversed(v[d0 + 1:])), T, modulus=P))


T = sp.symbols("t")


def rank_mod(rows_):
    return 6 - len(nullspace_mod(rows_, 6)) if rows_ else 0


a, b = [rng.randrange(P) for _ in range(6)], [rng.randrange(P) for _ in range(6)]
ts = list(range(1, 2 * TOP + 6))
line = [[[mono_val(e, x, 1) % P for e in support] for x in mod.orbit([(u + t * v) % P for u, v in zip(a, b)], m + 6)]
        for t in ts]
xg = [rng.randrange(P) for _ in range(6)]
drows = []
for l in range(6):
    orb = dual.orbit([Dual(v, int(i == l)) for i, v in enumerate(xg)], m + 6)
    drows.append([[mono_val(e, x, Dual(1)) for e in support] for x in orb])
table = []  # (degree pair, circuit, i, j, gradient)
for S in circ:
    vals = [circuit_vector(rows_, S, "mod") for rows_ in line]
    # c_i / c_last along the line as reduced N_i / D_i (c_last = 1)
    fun = [ratfun(ts, [v[i] for v in vals]) for i in range(len(S) - 1)]
    fun.append((sp.Poly(1, T, modulus=P), sp.Poly(1, T, modulus=P)))
    der = [circuit_vector(drows[l], S, "dual") for l in range(6)]
    c0 = der[0][0]
    for i, j in itertools.combinations(range(len(S)), 2):
        if fun[i] is None or fun[j] is None:
            deg = None
        else:
            num, den = fun[i][0] * fun[j][1], fun[i][1] * fun[j][0]
            g = sp.gcd(num, den)
            deg = (sp.quo(num, g).degree(), sp.quo(den, g).degree())
        grad = [(d[1][i] * c0[j] - c0[i] * d[1][j]) * pow(c0[j], -2, P) % P for d in der]
        table.append((deg, S, i, j, grad))
print(f"3. the {len(table)} ratios c_i/c_j of the circuits: degrees (numerator, denominator) along a line, "
      f"and the rank of their gradients mod p cumulated by degree")
by = {}
for deg, S, i, j, g in table:
    by.setdefault(max(deg) if deg else 99, []).append((deg, S, i, j, g))
cum = []
for d in sorted(by):
    before = rank_mod(cum)
    cum += [g for *_, g in by[d]]
    print(f"   degree {d if d < 99 else f'> {TOP}'}: {len(by[d])} ratios, rank {rank_mod([g for *_, g in by[d]])}, "
          f"cumulated {rank_mod(cum)}")
    if rank_mod(cum) > before:
        for deg, S, i, j, g in by[d]:
            if rank_mod(cum[:0] + [r for dd in sorted(by) if dd < d for *_, r in by[dd]] + [g]) > before:
                print(f"     e.g. c_{name(support[S[i]])}/c_{name(support[S[j]])} of {{"
                      + ", ".join(name(support[c]) for c in S) + f"}}: degrees {deg}")
                break
for label, group in [("{1, p_k^2}", lambda e: e[0] + e[1] + e[2] == 0),
                     ("{1, p_k^2, m_k p_k}", lambda e: max(e[:3]) < 2)]:
    gr = [g for deg, S, i, j, g in table if all(group(support[c]) for c in S)]
    print(f"   ratios of circuits inside {label}: rank {rank_mod(gr)}")

# 4. proofs of conservation of given integrals
if args.prove:
    data = json.load(open(args.prove))
    items = data.get("integrals", data) if isinstance(data, dict) else data
    loc = dict(zip(map(str, X), X))
    pairs = [(sp.Poly(sp.sympify(it["numerator"].replace("^", "**"), locals=loc), *X),
              sp.Poly(sp.sympify(it["denominator"].replace("^", "**"), locals=loc), *X)) for it in items]
    S_BOX = 10 ** 12
    prng = random.Random(41)
    for k, (N, D) in enumerate(pairs, 1):
        Nt, Dt = terms(N.as_expr()), terms(D.as_expr())
        n, d = N.total_degree(), D.total_degree()
        B = 7 * (n + d) + 6 + 8 * d
        ok = draws = 0
        while ok < args.points:
            draws += 1
            x = [F(prng.randint(-S_BOX, S_BOX)) for _ in range(6)]
            try:
                y = exact.step(x)
            except StopIteration:        # det(I - eps f'(x)) = 0
                continue
            dx, dy = exact.ev(Dt, x), exact.ev(Dt, y)
            if dx == 0 or dy == 0:
                continue
            assert exact.ev(Nt, x) / dx == exact.ev(Nt, y) / dy, f"I{k} is NOT conserved at {x}"
            ok += 1
        print(f"4. I{k} (degrees {n}/{d}, {len(N.terms())}/{len(D.terms())} terms): I(x~) = I(x) exactly at {ok} "
              f"random integer points of [-10^12, 10^12]^6 ({draws} drawn); a nonzero R of degree <= {B} vanishes "
              f"at all the points drawn with probability <= ({B}/(2*10^12 + 1))^{draws}")
    pt = {s: sp.Rational(prng.randint(-30, 30), prng.randint(1, 7)) for s in X}
    J = sp.Matrix([[sp.diff(N.as_expr() / D.as_expr(), s).subs(pt) for s in X] for N, D in pairs])
    print(f"   exact Jacobian rank of the {len(pairs)} integrals at {[str(v) for v in pt.values()]}: {J.rank()}")
sys.stdout.flush()
