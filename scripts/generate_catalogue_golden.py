#!/usr/bin/env python3
"""Golden data for the catalogue of classic KHK systems, by an independent route.

This script does NOT import exact_khk.  It reads every system file of
``exact_khk/systems/catalogue/*.toml`` with ``tomllib``, rebuilds the field with
SymPy and checks every claim the file makes, with exact rationals only:

* the Kahan map in the package's convention (one step approximates the time-2ε
  flow, h = 2ε):  x~ = x + 2ε (I - ε f'(x))^{-1} f(x), each step solved with
  SymPy's ``Matrix.LUsolve``, and the defining equation
  (x~ - x)/(2ε) = B(x, x~) + L(x + x~)/2 + c re-checked at every step;
* the same map once more in closed form, x + 2ε adj(A) f / det(A) with
  A = I - ε f'(x), with ε a symbol (compared with the first orbit step);
* every ``[integrals]`` entry conserved (==) along the stored exact orbit and,
  where affordable, PROVED: I(Φ(x)) = I(x) as an identity of rational functions,
  checked as a polynomial identity in SymPy's sparse polynomial ring after
  clearing the denominators (d^k N(X/d) Den(x) = d^k Den(X/d) N(x), where
  Φ = X/d);
* every ``[controls]`` entry NOT conserved along the orbit (a proof of that), and
  REJECTED by the symbolic prover (a negative control of the prover itself);
* the Poisson tensor: the Jacobi identity (symbolic) and dΦ Π dΦ^T = Π∘Φ
  (on the orbit with dΦ = (I - εf'(x))^{-1}(I + εf'(x~)), and symbolically for
  small dimensions, as B Π(x) B^T = A Π(x~) A^T with A = I - εf'(x),
  B = I + εf'(x~));
* the Jacobian formula dΦ = (I - εf'(x))^{-1}(I + εf'(x~)): symbolically, and
  against SymPy's ``jacobian`` of the closed-form map at the first point;
* reversibility Φ(Φ(x, ε), -ε) = x on the orbit (and symbolically when small);
* for ``[hamiltonian]`` systems (Celledoni-McLachlan-Owren-Quispel): f = K grad H,
  the modified energy H + (2ε/3) grad H^T (I - εf')^{-1} f (its formula, and its
  conservation), and the measure dx/det(I - εf'(x)), i.e.
  det dΦ(x) = det(I - εf'(x~))/det(I - εf'(x)) (on the orbit, and symbolically
  through det(I + εf'(y)) = det(I - εf'(y)) and the Jacobian formula);
* regularity of the first 60 steps from the default x0 and ε: no singular step
  and no pole of an integral.  Exactly on the stored steps; beyond them (orbits of
  non-integrable maps grow exponentially in height) by reduction modulo the prime
  p = 2^61 - 1: if x_k is p-integral and det(I - εf'(x_k)) is non-zero mod p, it
  is non-zero over Q and x_{k+1} is p-integral again, so a mod-p orbit with no
  zero determinant and no zero denominator certifies the rational orbit.

It writes ``tests/data/golden_catalogue.json``:
{name: {"file", "parameters", "x0", "eps", "steps", "orbit" (steps + 1 points of
"p/q" strings), "integrals": {name: [value at each point]}, "controls": {...},
"verified": {claim: "symbolic" | "orbit"}, "regularity", "modp", "sizes", ...}}
and exits non-zero if any claim fails, so that a wrong integral never stays in a
catalogue file.

Run:  python scripts/generate_catalogue_golden.py   (1-2 minutes; --only NAME ... to check
      some systems without writing the file)
"""

from __future__ import annotations

import argparse
import json
import pathlib
import random
import re
import signal
import sys
import time
from contextlib import contextmanager

try:  # Python 3.11+; tomli (a dependency of the package before 3.11) otherwise
    import tomllib
except ImportError:  # pragma: no cover
    import tomli as tomllib

import sympy as sp
from sympy.polys.domains import QQ
from sympy.polys.rings import ring

from script_io import write_atomic

if hasattr(sys, "set_int_max_str_digits"):
    sys.set_int_max_str_digits(0)

ROOT = pathlib.Path(__file__).resolve().parent.parent
CATALOGUE = ROOT / "exact_khk" / "systems" / "catalogue"
OUT = ROOT / "tests" / "data" / "golden_catalogue.json"

EPS = sp.Symbol("eps")
REGULAR_STEPS = 60            # steps certified regular from the defaults
DEFAULT_STORED = 60           # exact orbit steps stored in the JSON ...
STORED_STEPS = {              # ... except where heights grow too fast to store 60
    "lagrange-top": 30,       # integrable, but 6 coordinates: 60 steps would be ~3.3 MB
    "lotka-volterra": 12,     # not integrable: heights double at every step
    "cmoq-cubic": 30,         # integrable, but 60 steps would be ~1.2 MB
}
MODP = 2**61 - 1
SYMBOLIC_TIME_LIMIT = 600     # seconds; a safety net only (a timeout is reported, never hidden)

# Which symbolic proofs are attempted.  "eps": ε stays a symbol (a proof for every step
# size); "fixed": ε is the default step (a proof for that step size, x symbolic).  Every
# [integrals] entry is attempted (mode "eps" unless listed under "integrals"); a mode of
# None skips the attempt (the claim is then checked on the orbit only).  The choice only
# affects cost: an attempted proof either succeeds or fails the run.
PROOFS = {
    "euler-top": {"poisson": "eps", "reversibility": "eps", "jacobian": "eps"},
    "lotka-volterra": {"poisson": "eps", "reversibility": "eps", "jacobian": "eps"},
    # reversibility of the 6-dimensional map is checked on the orbit only (its symbolic
    # identity has degree ~25 in 7 variables and took over 10 minutes)
    "lagrange-top": {"jacobian": "eps"},
    "cmoq-cubic": {"jacobian": "eps", "cmoq_measure": "eps", "reversibility": "eps"},
}

# Published forms that the catalogue files do not list (docs/catalogue.md says why), checked
# here too, in our convention, so that the documentation's statements about them are checked.
LITERATURE = {
    "euler-top": {
        # Hirota-Kimura / Petrera-Suris ratios; their eps -> 0 limit is the constant 1
        "HK_ratio_12": "(1 - eps**2*a2*a3*x1**2)/(1 - eps**2*a3*a1*x2**2)",
        "HK_ratio_23": "(1 - eps**2*a3*a1*x2**2)/(1 - eps**2*a1*a2*x3**2)",
    },
}

FAILURES: list[str] = []


def fail(msg: str) -> None:
    FAILURES.append(msg)
    print("  FAIL:", msg, flush=True)


class Timeout(Exception):
    pass


@contextmanager
def time_limit(seconds: int):
    def handler(signum, frame):
        raise Timeout()
    old = signal.signal(signal.SIGALRM, handler)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


# --------------------------------------------------------------------------- parsing

_RATIONAL = re.compile(r"^[+-]?(\d+(/\d+)?|\d*\.\d+|\d+\.\d*)$")


def rational(value, what: str) -> sp.Rational:
    """An exact rational from a TOML integer or a string 'p', 'p/q' or a decimal."""
    if isinstance(value, bool) or not isinstance(value, (int, str)):
        raise ValueError(f"{what}: {value!r} is not an exact rational (use a string)")
    if isinstance(value, int):
        return sp.Integer(value)
    text = value.strip().replace(" ", "")
    if not _RATIONAL.match(text):
        raise ValueError(f"{what}: {value!r} is not a rational")
    return sp.Rational(text)


def expression(text: str, names: dict, what: str) -> sp.Expr:
    """A SymPy expression from the restricted syntax of system files."""
    if not isinstance(text, (str, int)):
        raise ValueError(f"{what}: expected a string, got {text!r}")
    expr = sp.sympify(str(text), locals=dict(names), rational=True)
    bad = expr.free_symbols - set(names.values())
    if bad:
        raise ValueError(f"{what}: unknown names {sorted(map(str, bad))}")
    if expr.atoms(sp.Function) or expr.atoms(sp.Float):
        raise ValueError(f"{what}: functions/floats are not allowed")
    for p in expr.atoms(sp.Pow):
        if not p.exp.is_Integer:
            raise ValueError(f"{what}: non-integer exponent in {p}")
    return expr


class System:
    """A catalogue file, parsed with SymPy (parameters substituted)."""

    def __init__(self, path: pathlib.Path):
        self.path = path
        self.data = data = tomllib.loads(path.read_text(encoding="utf-8"))
        self.name = data["name"]
        if self.name != path.stem:
            raise ValueError(f"{path.name}: name {self.name!r} differs from the file name")
        self.var_names = list(data["variables"])
        self.X = [sp.Symbol(v) for v in self.var_names]
        self.N = len(self.X)
        self.param_values = {k: rational(v, f"parameters.{k}") for k, v in data.get("parameters", {}).items()}
        self.P = {k: sp.Symbol(k) for k in self.param_values}
        names = {v: s for v, s in zip(self.var_names, self.X)} | self.P
        self.psub = {self.P[k]: v for k, v in self.param_values.items()}
        field_names = names  # eps not allowed in a field
        all_names = names | {"eps": EPS}

        def ex(text, what, allowed=all_names):
            return expression(text, allowed, what).xreplace(self.psub)

        f_field = None
        if "field" in data:
            f_field = sp.Matrix([ex(data["field"][v], f"field.{v}", field_names) for v in self.var_names])
        self.K = self.H = None
        if "hamiltonian" in data:
            h = data["hamiltonian"]
            self.K = sp.Matrix([[rational(c, "hamiltonian.K") for c in row] for row in h["K"]])
            self.H = ex(h["H"], "hamiltonian.H", field_names)
            grad = sp.Matrix([sp.diff(self.H, x) for x in self.X])
            f_ham = (self.K * grad).applyfunc(sp.expand)
        if f_field is None and self.H is None:
            raise ValueError(f"{self.name}: neither [field] nor [hamiltonian]")
        self.f = (f_field if f_field is not None else f_ham).applyfunc(sp.expand)
        self.f_ham = f_ham if self.H is not None else None
        for comp in self.f:
            if sp.Poly(comp, *self.X).total_degree() > 2:
                raise ValueError(f"{self.name}: field of degree > 2")
        self.J = self.f.jacobian(self.X)
        zero = {x: 0 for x in self.X}
        self.c = self.f.xreplace(zero)
        self.L = self.J.xreplace(zero)
        self.Q = (self.f - self.L * sp.Matrix(self.X) - self.c).applyfunc(sp.expand)
        self.integrals = {k: ex(v, f"integrals.{k}") for k, v in data.get("integrals", {}).items()}
        self.controls = {k: ex(v, f"controls.{k}") for k, v in data.get("controls", {}).items()}
        self.poisson = None
        if "poisson" in data:
            rows = data["poisson"]["matrix"]
            self.poisson = sp.Matrix([[ex(c, "poisson.matrix") for c in row] for row in rows])
        d = data.get("defaults", {})
        self.x0 = [rational(v, "defaults.x0") for v in d["x0"]]
        self.eps = rational(d["eps"], "defaults.eps")
        self.steps = STORED_STEPS.get(self.name, DEFAULT_STORED)

    def at(self, expr, x, eps=None):
        s = dict(zip(self.X, x))
        if eps is not None:
            s[EPS] = eps
        return expr.xreplace(s)

    def bilinear(self, x, y):
        """B(x, y) = (Q(x + y) - Q(x) - Q(y))/2."""
        s = [a + b for a, b in zip(x, y)]
        return (self.at(self.Q, s) - self.at(self.Q, x) - self.at(self.Q, y)) / 2


# --------------------------------------------------------------------------- exact orbit

def kahan_step(S: System, x, eps):
    """x~ = x + 2 eps (I - eps f'(x))^{-1} f(x) with SymPy's LUsolve; returns (x~, A)."""
    A = sp.eye(S.N) - eps * S.at(S.J, x)
    if A.det() == 0:
        raise ZeroDivisionError("singular step")
    y = A.LUsolve(S.at(S.f, x))
    return [xi + 2 * eps * yi for xi, yi in zip(x, y)], A


def exact_orbit(S: System):
    pts = [list(S.x0)]
    mats = []
    for k in range(S.steps):
        xn, A = kahan_step(S, pts[-1], S.eps)
        pts.append(xn)
        mats.append(A)
    return pts, mats


# --------------------------------------------------------------------------- polynomial-ring proofs

class Ring:
    """The Kahan map in SymPy's sparse polynomial ring: Phi(x) = X(x)/d(x)."""

    def __init__(self, S: System, mode: str, eps_value=None):
        self.S, self.mode = S, mode
        gens = list(S.var_names) + (["eps"] if mode == "eps" else [])
        self.R, *g = ring(gens, QQ)
        self.x = g[:S.N]
        self.eps_value = EPS if mode == "eps" else (S.eps if eps_value is None else eps_value)
        self.e = g[S.N] if mode == "eps" else self.R(QQ(int(self.eps_value.p), int(self.eps_value.q)))
        self.f = [self.conv(c) for c in S.f]
        self.Jm = [[self.conv(S.J[i, j]) for j in range(S.N)] for i in range(S.N)]
        n = S.N
        self.A = [[(self.R.one if i == j else self.R.zero) - self.e * self.Jm[i][j] for j in range(n)] for i in range(n)]
        self.d = det(self.A)
        self.X = []
        for i in range(n):
            Ai = [[(self.f[r] if c == i else self.A[r][c]) for c in range(n)] for r in range(n)]
            self.X.append(self.d * self.x[i] + 2 * self.e * det(Ai))
        # coordinates the map leaves fixed (linear integrals x_i, e.g. m3 of the Lagrange top):
        # X_i = d x_i is checked here as a polynomial identity, and compose() then uses x_i~ = x_i,
        # which lowers the degree of the identities to be checked
        self.fixed = [self.X[i] == self.d * self.x[i] for i in range(n)]

    def conv(self, expr):
        expr = sp.expand(sp.sympify(expr).xreplace({EPS: self.eps_value}))
        return self.R.from_expr(expr) if expr != 0 else self.R.zero

    def fraction(self, expr):
        num, den = sp.fraction(sp.together(expr.xreplace({EPS: self.eps_value})))
        return self.conv(num), self.conv(den)

    def xdeg(self, p, moving=False):
        """Degree of p in x (only in the coordinates not fixed by the map if moving)."""
        n = self.S.N
        idx = [i for i in range(n) if not (moving and self.fixed[i])]
        return max((sum(m[i] for i in idx) for m in p.monoms()), default=0)

    def compose(self, p, k, X=None, d=None):
        """d^k p(X/d) (k >= x-degree of p); with the default X, coordinates fixed by the map
        are kept as they are (x_i~ = x_i) and k need only bound the degree in the others."""
        if X is None:
            X = [self.x[i] if self.fixed[i] else self.X[i] for i in range(self.S.N)]
            fixed = self.fixed
        else:
            fixed = [False] * self.S.N
        d = self.d if d is None else d
        cache = {}

        def power(base, i, e):
            key = (i, e)
            if key not in cache:
                cache[key] = base ** e
            return cache[key]

        dp = {}
        out = self.R.zero
        for m, c in p.terms():
            deg = sum(e for e, fx in zip(m[:self.S.N], fixed) if not fx)
            term = self.R(c)
            for i, e in enumerate(m[:self.S.N]):
                if e:
                    term *= power(X[i], i, e)
            if len(m) > self.S.N and m[self.S.N]:
                term *= self.R.gens[self.S.N] ** m[self.S.N]
            if k - deg not in dp:
                dp[k - deg] = d ** (k - deg)
            out += term * dp[k - deg]
        return out


def det(M):
    """Fraction-free (Bareiss) determinant of a square list of ring elements."""
    n = len(M)
    M = [row[:] for row in M]
    R = M[0][0].ring
    sign, prev = 1, R.one
    for k in range(n - 1):
        if M[k][k] == 0:
            for p in range(k + 1, n):
                if M[p][k] != 0:
                    M[k], M[p] = M[p], M[k]
                    sign = -sign
                    break
            else:
                return R.zero
        for i in range(k + 1, n):
            for j in range(k + 1, n):
                M[i][j] = (M[i][j] * M[k][k] - M[i][k] * M[k][j]).exquo(prev)
        prev = M[k][k]
    return sign * M[n - 1][n - 1]


def prove_integral(Rg: Ring, expr) -> bool:
    num, den = Rg.fraction(expr)
    k = max(Rg.xdeg(num, True), Rg.xdeg(den, True))
    return Rg.compose(num, k) * den - Rg.compose(den, k) * num == 0


def prove_jacobian(Rg: Ring) -> bool:
    """A(x) Jac(X/d) = I + eps f'(X/d), multiplied by d^2:
    A (d dX - X dd^T) = d^2 I + eps d (J0 d + J1(X))   (f' is affine in x)."""
    n = Rg.S.N
    dd = [Rg.d.diff(Rg.x[j]) for j in range(n)]
    lhs_core = [[Rg.d * Rg.X[i].diff(Rg.x[j]) - Rg.X[i] * dd[j] for j in range(n)] for i in range(n)]
    for i in range(n):
        for j in range(n):
            lhs = sum((Rg.A[i][k] * lhs_core[k][j] for k in range(n)), Rg.R.zero)
            Jij = Rg.Jm[i][j]  # affine in x: d * J(X/d) = J0*d + J1(X)
            dJ = Rg.compose(Jij, 1)
            rhs = (Rg.d ** 2 if i == j else Rg.R.zero) + Rg.e * Rg.d * dJ
            if lhs != rhs:
                return False
    return True


def prove_reversibility(Rg: Ring) -> bool:
    """X(X/d, -eps)/d(X/d, -eps) = x."""
    S, n = Rg.S, Rg.S.N
    if Rg.mode == "eps":
        e = Rg.R.gens[n]
        Xm = [p.compose(e, -e) for p in Rg.X]
        dm = Rg.d.compose(e, -e)
    else:
        other = Ring(S, "fixed", -Rg.eps_value)
        Xm = [Rg.R.from_expr(p.as_expr()) if p != 0 else Rg.R.zero for p in other.X]
        dm = Rg.R.from_expr(other.d.as_expr())
    k = max([Rg.xdeg(dm)] + [Rg.xdeg(p) for p in Xm])
    dh = Rg.compose(dm, k)
    return all(Rg.compose(Xm[i], k) == Rg.x[i] * dh for i in range(n))


def prove_poisson(Rg: Ring, Pi: sp.Matrix) -> bool:
    """B Pi(x) B^T = A Pi(x~) A^T with B = I + eps f'(x~), all multiplied out."""
    n = Rg.S.N
    P = [[Rg.fraction(Pi[i, j]) for j in range(n)] for i in range(n)]
    if any(not den.is_ground for row in P for (_, den) in row):
        raise NotImplementedError("symbolic Poisson check implemented for polynomial tensors")
    Pn = [[num.quo_ground(den.LC) for (num, den) in row] for row in P]
    k = max(Rg.xdeg(p) for row in Pn for p in row)
    Pt = [[Rg.compose(p, k) for p in row] for row in Pn]           # d^k Pi(x~)
    dB = [[(Rg.d if i == j else Rg.R.zero) + Rg.e * Rg.compose(Rg.Jm[i][j], 1) for j in range(n)] for i in range(n)]

    def mul(M1, M2):
        return [[sum((M1[i][t] * M2[t][j] for t in range(n)), Rg.R.zero) for j in range(n)] for i in range(n)]

    def tr(M1):
        return [[M1[j][i] for j in range(n)] for i in range(n)]
    lhs = mul(mul(dB, Pn), tr(dB))                                   # d^2 B Pi B^T
    rhs = mul(mul(Rg.A, Pt), tr(Rg.A))                               # d^k A Pi(x~) A^T
    for i in range(n):
        for j in range(n):
            if lhs[i][j] * Rg.d ** k != rhs[i][j] * Rg.d ** 2:
                return False
    return True


def prove_even_charpoly(Rg: Ring) -> bool:
    """det(I + eps f'(y)) = det(I - eps f'(y)) for all y (true for f' = K Hess H)."""
    n = Rg.S.N
    Bp = [[(Rg.R.one if i == j else Rg.R.zero) + Rg.e * Rg.Jm[i][j] for j in range(n)] for i in range(n)]
    return det(Bp) == Rg.d


def jacobi_identity(S: System, Pi: sp.Matrix) -> bool:
    n = S.N
    for i in range(n):
        for j in range(i + 1, n):
            for k in range(j + 1, n):
                s = sum(Pi[i, l] * sp.diff(Pi[j, k], S.X[l]) + Pi[j, l] * sp.diff(Pi[k, i], S.X[l])
                        + Pi[k, l] * sp.diff(Pi[i, j], S.X[l]) for l in range(n))
                if sp.cancel(sp.together(s)) != 0:
                    return False
    return True


# --------------------------------------------------------------------------- modular regularity

def modp_orbit(S: System, steps: int, p: int = MODP):
    """The orbit mod p from the defaults: certifies regularity (see the module doc).
    Returns (ok, message, integral values mod p at every point)."""
    def red(q):
        q = sp.Rational(q)
        if q.q % p == 0:
            raise ZeroDivisionError(f"{q} is not p-integral")
        return int(q.p) * pow(int(q.q), -1, p) % p

    def poly_mod(expr):
        P = sp.Poly(sp.expand(expr), *S.X)
        return [(red(c), m) for m, c in zip(P.monoms(), P.coeffs())]

    def ev(terms, x):
        tot = 0
        for c, m in terms:
            t = c
            for xi, e in zip(x, m):
                if e:
                    t = t * pow(xi, e, p) % p
            tot += t
        return tot % p

    eps = red(S.eps)
    F = [poly_mod(c) for c in S.f]
    Jt = [[poly_mod(S.J[i, j]) for j in range(S.N)] for i in range(S.N)]
    ints = {}
    for k, expr in S.integrals.items():
        num, den = sp.fraction(sp.together(expr.xreplace({EPS: S.eps})))
        ints[k] = (poly_mod(num), poly_mod(den))
    x = [red(v) for v in S.x0]
    values = {k: [] for k in ints}
    for step in range(steps + 1):
        for k, (num, den) in ints.items():
            dv = ev(den, x)
            if dv == 0:
                return False, f"denominator of {k} is 0 mod p at step {step}", values
            values[k].append(ev(num, x) * pow(dv, -1, p) % p)
        if step == steps:
            break
        n = S.N
        A = [[((1 if i == j else 0) - eps * ev(Jt[i][j], x)) % p for j in range(n)] + [ev(F[i], x)] for i in range(n)]
        for col in range(n):                      # Gauss-Jordan mod p
            piv = next((r for r in range(col, n) if A[r][col]), None)
            if piv is None:
                return False, f"det(I - eps f') = 0 mod p at step {step}", values
            A[col], A[piv] = A[piv], A[col]
            inv = pow(A[col][col], -1, p)
            A[col] = [v * inv % p for v in A[col]]
            for r in range(n):
                if r != col and A[r][col]:
                    fac = A[r][col]
                    A[r] = [(a - fac * b) % p for a, b in zip(A[r], A[col])]
        x = [(x[i] + 2 * eps * A[i][n]) % p for i in range(n)]
    return True, f"{steps} steps regular mod p = {p}", values


# --------------------------------------------------------------------------- per system

def rstr(q) -> str:
    return str(sp.Rational(q))


def check_system(S: System) -> dict:
    print(f"\n== {S.name} ({S.N} variables, {len(S.integrals)} integrals, {len(S.controls)} controls, "
          f"x0 = {[str(v) for v in S.x0]}, eps = {S.eps}, {S.steps} stored steps)", flush=True)
    verified: dict[str, str] = {}
    notes: list[str] = []
    proofs = PROOFS.get(S.name, {})
    t0 = time.time()

    # Hamiltonian consistency
    if S.f_ham is not None:
        if (S.f - S.f_ham).applyfunc(sp.expand) != sp.zeros(S.N, 1):
            fail(f"{S.name}: [field] differs from K grad H")
        if S.K.T != -S.K:
            fail(f"{S.name}: K is not skew-symmetric")
        verified["hamiltonian:f=K*gradH"] = "symbolic"

    # exact orbit + defining equation
    pts, mats = exact_orbit(S)
    eps = S.eps
    ok = True
    for k in range(S.steps):
        x, y = pts[k], pts[k + 1]
        lhs = [(b - a) / (2 * eps) for a, b in zip(x, y)]
        rhs = S.bilinear(x, y) + S.L * sp.Matrix([(a + b) / 2 for a, b in zip(x, y)]) + S.c
        if any(lhs[i] != rhs[i] for i in range(S.N)):
            fail(f"{S.name}: defining equation fails at step {k}")
            ok = False
            break
    if ok:
        verified["kahan:defining_equation"] = "orbit"
    print(f"  orbit of {S.steps} steps: {time.time() - t0:.1f} s", flush=True)

    # closed-form map with symbolic eps, compared with the first step
    A = sp.eye(S.N) - EPS * S.J
    dA = sp.expand(A.det())
    Phi = [S.X[i] + 2 * EPS * sp.expand((A.adjugate() * S.f)[i]) / dA for i in range(S.N)]
    x1 = [S.at(c, pts[0], eps) for c in Phi]
    if x1 != pts[1]:
        fail(f"{S.name}: closed-form map differs from the LUsolve step")
    else:
        verified["kahan:closed_form_map"] = "orbit"

    # reversibility on the orbit
    ok = True
    for k in range(S.steps):
        back, _ = kahan_step(S, pts[k + 1], -eps)
        if back != pts[k]:
            fail(f"{S.name}: Phi(Phi(x, eps), -eps) != x at step {k}")
            ok = False
            break
    if ok:
        verified["reversibility"] = "orbit"

    # integrals on the orbit
    int_values = {}
    for name, expr in S.integrals.items():
        vals = [S.at(expr, x, eps) for x in pts]
        if any(not v.is_Rational for v in vals):
            fail(f"{S.name}: integral {name} has a pole on the orbit")
            continue
        int_values[name] = vals
        if any(v != vals[0] for v in vals):
            k = next(i for i, v in enumerate(vals) if v != vals[0])
            fail(f"{S.name}: integral {name} NOT conserved (step {k})")
        else:
            verified[f"integral:{name}"] = "orbit"
    # functional independence at x0
    if S.integrals:
        G = sp.Matrix([[sp.diff(expr, x) for x in S.X] for expr in S.integrals.values()])
        rank = G.xreplace(dict(zip(S.X, S.x0)) | {EPS: eps}).rank()
    else:
        rank = 0

    # controls on the orbit
    ctl_values = {}
    for name, expr in S.controls.items():
        vals = [S.at(expr, x, eps) for x in pts]
        ctl_values[name] = vals
        if all(v == vals[0] for v in vals):
            fail(f"{S.name}: control {name} IS conserved along the orbit")
        else:
            verified[f"control:{name}:not_conserved"] = "orbit"

    # Jacobian formula against SymPy's jacobian of the closed-form map at x0
    Phi_e = [c.xreplace({EPS: eps}) for c in Phi]
    sub0 = dict(zip(S.X, pts[0]))
    Jsym = sp.Matrix([[sp.diff(Phi_e[i], S.X[j]).xreplace(sub0) for j in range(S.N)] for i in range(S.N)])
    dPhi0 = mats[0].LUsolve(sp.eye(S.N) + eps * S.at(S.J, pts[1]))
    if Jsym != dPhi0:
        fail(f"{S.name}: dPhi formula differs from SymPy's jacobian at x0")
    else:
        verified["jacobian:formula_vs_sympy_jacobian_at_x0"] = "orbit"

    # Poisson tensor
    if S.poisson is not None:
        Pi = S.poisson
        if (Pi + Pi.T).applyfunc(sp.expand) != sp.zeros(S.N, S.N):
            fail(f"{S.name}: Poisson matrix not skew")
        if jacobi_identity(S, Pi):
            verified["poisson:jacobi_identity"] = "symbolic"
        else:
            fail(f"{S.name}: Poisson tensor violates the Jacobi identity")
        ok = True
        for k in range(S.steps):
            x, y = pts[k], pts[k + 1]
            dPhi = mats[k].LUsolve(sp.eye(S.N) + eps * S.at(S.J, y))
            if k == 0 and dPhi != Jsym:
                fail(f"{S.name}: dPhi at x0 differs from SymPy's jacobian")
            if dPhi * S.at(Pi, x, eps) * dPhi.T != S.at(Pi, y, eps):
                fail(f"{S.name}: Poisson tensor not preserved at step {k}")
                ok = False
                break
        if ok:
            verified["poisson:preserved"] = "orbit"

    # CMOQ: modified energy formula and measure on the orbit
    if S.H is not None:
        grad = sp.Matrix([sp.diff(S.H, x) for x in S.X])
        formula = S.H + sp.Rational(2, 3) * EPS * (grad.T * A.adjugate() * S.f)[0] / dA
        tilde = [k for k, e in S.integrals.items() if sp.cancel(sp.together(e - formula)) == 0]
        if not tilde:
            fail(f"{S.name}: no [integrals] entry equals the CMOQ modified energy")
        else:
            verified[f"cmoq:modified_energy_formula({tilde[0]})"] = "symbolic"
            if f"integral:{tilde[0]}" in verified:
                verified["cmoq:modified_energy_conserved"] = "orbit"
        ok = True
        for k in range(S.steps):
            x, y = pts[k], pts[k + 1]
            dPhi = mats[k].LUsolve(sp.eye(S.N) + eps * S.at(S.J, y))
            rhs = (sp.eye(S.N) - eps * S.at(S.J, y)).det() / mats[k].det()
            if dPhi.det() != rhs:
                fail(f"{S.name}: det dPhi != det(I - eps f'(x~))/det(I - eps f'(x)) at step {k}")
                ok = False
                break
        if ok:
            verified["cmoq:measure_dx/det(I-eps*f')"] = "orbit"
    print(f"  orbit checks: {time.time() - t0:.1f} s", flush=True)

    # symbolic proofs
    rings: dict[str, Ring] = {}

    def get_ring(mode):
        if mode not in rings:
            rings[mode] = Ring(S, mode)
        return rings[mode]

    def attempt(claim, mode, fn):
        t = time.time()
        try:
            with time_limit(SYMBOLIC_TIME_LIMIT):
                good = fn(get_ring(mode))
        except Timeout:
            notes.append(f"symbolic proof of {claim} timed out after {SYMBOLIC_TIME_LIMIT} s")
            print(f"  {claim}: symbolic attempt timed out", flush=True)
            return
        if good:
            verified[claim] = "symbolic"
            what = "all eps" if mode == "eps" else f"eps = {S.eps}"
            notes.append(f"{claim}: proved as a rational-function identity in x ({what})")
            print(f"  {claim}: proved symbolically ({what}) in {time.time() - t:.1f} s", flush=True)
        else:
            fail(f"{S.name}: symbolic check of {claim} FAILED")

    for name in S.integrals:
        mode = proofs.get("integrals", {}).get(name, "eps")
        if mode is not None and f"integral:{name}" in verified:
            attempt(f"integral:{name}", mode, lambda Rg, e=S.integrals[name]: prove_integral(Rg, e))
    # published forms not listed in the file (documentation claims): orbit and symbolic
    literature = {}
    names = {v: s for v, s in zip(S.var_names, S.X)} | S.P | {"eps": EPS}
    for lname, text in LITERATURE.get(S.name, {}).items():
        expr = expression(text, names, f"literature {lname}").xreplace(S.psub)
        vals = [S.at(expr, x, eps) for x in pts]
        if any(v != vals[0] for v in vals) or not vals[0].is_Rational:
            fail(f"{S.name}: published integral {lname} not conserved on the orbit")
            continue
        if prove_integral(get_ring("eps"), expr):
            literature[lname] = {"expression": text, "verified": "symbolic", "value_at_x0": rstr(vals[0])}
            print(f"  published form {lname}: conserved on the orbit and proved symbolically (all eps)", flush=True)
        else:
            fail(f"{S.name}: published integral {lname}: symbolic proof failed")

    # negative controls of the prover itself: it must REJECT every [controls] entry
    for name, expr in S.controls.items():
        try:
            with time_limit(SYMBOLIC_TIME_LIMIT):
                rejected = not prove_integral(get_ring("eps"), expr)
        except Timeout:
            notes.append(f"prover negative control {name} timed out")
            continue
        if rejected:
            verified[f"control:{name}:rejected_by_prover"] = "symbolic"
        else:
            fail(f"{S.name}: the symbolic prover ACCEPTS the control {name}")
    if "jacobian" in proofs:
        attempt("jacobian:formula", proofs["jacobian"], prove_jacobian)
    if "reversibility" in proofs:
        attempt("reversibility", proofs["reversibility"], prove_reversibility)
    if "poisson" in proofs and S.poisson is not None:
        attempt("poisson:preserved", proofs["poisson"], lambda Rg: prove_poisson(Rg, S.poisson))
    if "cmoq_measure" in proofs:
        # with the (proved) Jacobian formula, det dPhi = det(I + eps f'(x~))/det(I - eps f'(x))
        attempt("cmoq:det(I+eps*f')=det(I-eps*f')", proofs["cmoq_measure"], prove_even_charpoly)
        if (verified.get("cmoq:det(I+eps*f')=det(I-eps*f')") == "symbolic"
                and verified.get("jacobian:formula") == "symbolic"):
            verified["cmoq:measure_dx/det(I-eps*f')"] = "symbolic"
    if S.H is not None and "cmoq:modified_energy_conserved" in verified:
        tname = next(k for k in verified if k.startswith("cmoq:modified_energy_formula(")).split("(")[1][:-1]
        if verified.get(f"integral:{tname}") == "symbolic":
            verified["cmoq:modified_energy_conserved"] = "symbolic"

    # extra evidence for integrals not proved symbolically: random rational points, one step each
    rnd = random.Random(20240601)
    extra = {}
    for name, expr in S.integrals.items():
        if verified.get(f"integral:{name}") != "orbit":
            continue
        good = 0
        for _ in range(20):
            x = [sp.Rational(rnd.randint(-9, 9), rnd.randint(1, 5)) for _ in range(S.N)]
            try:
                y, _A = kahan_step(S, x, eps)
            except ZeroDivisionError:
                continue
            a, b = S.at(expr, x, eps), S.at(expr, y, eps)
            if not (a.is_Rational and b.is_Rational):
                continue
            if a != b:
                fail(f"{S.name}: integral {name} not conserved at a random point {x}")
                break
            good += 1
        extra[name] = f"conserved exactly on {S.steps} orbit steps and on one step from each of {good} random rational points"

    # regularity of the first 60 steps: exact on the stored steps, mod p for all
    ok, msg, modvals = modp_orbit(S, REGULAR_STEPS)
    if not ok:
        fail(f"{S.name}: regularity mod p: {msg}")
    else:
        verified[f"regular:{REGULAR_STEPS}_steps"] = "orbit"
    modp_info = {"p": MODP, "steps": REGULAR_STEPS, "regular": ok}
    if ok:
        for name, vals in modvals.items():
            if any(v != vals[0] for v in vals):
                fail(f"{S.name}: integral {name} not conserved mod p within {REGULAR_STEPS} steps")
        modp_info["integrals_conserved_mod_p"] = True
    regularity = {
        "steps": REGULAR_STEPS,
        "exact_steps": S.steps,
        "method": ("exact (SymPy) on all steps" if S.steps >= REGULAR_STEPS else
                   f"exact (SymPy) on steps 0..{S.steps}; steps 0..{REGULAR_STEPS} by reduction mod p = 2^61 - 1 "
                   "(non-zero det(I - eps f') and non-zero integral denominators mod p imply non-zero over Q)"),
    }

    orbit_chars = sum(len(str(c)) for x in pts for c in x)
    maxdig = max(len(str(abs(c.p))) for c in pts[-1])
    sizes = {"orbit_chars": orbit_chars, "max_numerator_digits_last_point": maxdig,
             "note": "" if S.steps >= REGULAR_STEPS else
             f"stored {S.steps} steps only: heights grow too fast to store {REGULAR_STEPS}"}
    print(f"  rank of the integrals' gradients at x0: {rank}; orbit {orbit_chars} chars; "
          f"{time.time() - t0:.1f} s total", flush=True)
    for claim, how in verified.items():
        print(f"    {how:8s} {claim}")

    return {
        "file": str(S.path.relative_to(ROOT)),
        "variables": S.var_names,
        "parameters": {k: rstr(v) for k, v in S.param_values.items()},
        "x0": [rstr(v) for v in S.x0],
        "eps": rstr(S.eps),
        "steps": S.steps,
        "orbit": [[rstr(c) for c in x] for x in pts],
        "integrals": {k: [rstr(v) for v in vals] for k, vals in int_values.items()},
        "controls": {k: [rstr(v) for v in vals] for k, vals in ctl_values.items()},
        "integrals_gradient_rank_at_x0": int(rank),
        "verified": verified,
        "evidence": extra,
        "literature_forms": literature,
        "regularity": regularity,
        "modp": modp_info,
        "sizes": sizes,
        "notes": notes,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="*", help="catalogue names to check (default: all)")
    ap.add_argument("--no-write", action="store_true", help="check only, do not write the JSON")
    args = ap.parse_args(argv)
    t0 = time.time()
    files = sorted(CATALOGUE.glob("*.toml"))
    out = {}
    for path in files:
        if args.only and path.stem not in args.only:
            continue
        try:
            S = System(path)
        except Exception as exc:  # a malformed file is a failure, not a crash
            fail(f"{path.name}: cannot parse: {exc}")
            continue
        out[S.name] = check_system(S)
    dt = time.time() - t0
    print(f"\n{len(out)} systems in {dt:.1f} s")
    if FAILURES:
        print(f"{len(FAILURES)} FAILURE(S):")
        for f in FAILURES:
            print("  -", f)
        print("golden file NOT written")
        return 1
    if not args.no_write and not args.only:
        text = json.dumps(out, indent=1)
        write_atomic(OUT, text + "\n")
        print(f"wrote {OUT.relative_to(ROOT)} ({len(text) / 1e6:.2f} MB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
