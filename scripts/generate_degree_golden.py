"""Regenerate tests/data/golden_degrees.json: degrees of Kahan iterates by an independent route.

This script does NOT use exact_khk.  Each field is a SymPy expression (the
Lie–Poisson ones built from X(w), J(x) and the Hessian as in
docs/conventions.md), and the iterates are composed exactly over Q along one
fixed line x(t) = a + t·b with small integer a, b, straight from the definition
of the Kahan step,

    Φ(x) = x + 2ε (I − ε f'(x))^{-1} f(x).

With x = P/Q (P a vector of polynomials in t, Q a polynomial): A = Q·(I − εf'(P/Q))
and F = Q²·f(P/Q) are polynomial (f is quadratic), and

    Φ(P/Q) = (P·det A + 2ε adj(A) F) / (Q·det A),

computed with SymPy's DomainMatrix over QQ[t] (determinant and adjugate),
reduced by the gcd of all N + 1 coordinates.  The degree of the reduced point
is the projective degree of Φ^k restricted to the line, which is deg Φ^k for
a generic line (exact_khk's tests compare its modular and exact degrees with
these numbers).

Run:  python scripts/generate_degree_golden.py   (takes about a minute; ``--check`` compares
with the file instead of writing it, ``--out`` writes elsewhere)
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import sympy as sp
from sympy.polys.matrices import DomainMatrix

from script_io import write_or_check

OUT = pathlib.Path(__file__).resolve().parent.parent / "tests" / "data" / "golden_degrees.json"
t = sp.Symbol("t")
QQt = sp.QQ[t]


def hankel(w):
    n = len(w)
    return sp.Matrix(n, n, lambda i, j: w[(i + j) % n])


def lie_poisson_field(a, b, c, kind):
    """f(x) = J(x) M x with M = Hs ('f') or (A Hs for n >= 3, (2I + A) Hs for n = 2) ('control')."""
    a, b, c = ([sp.Rational(s) for s in v.split(",")] for v in (a, b, c))
    n = len(a)
    xs = sp.symbols(f"x0:{2 * n}")
    Xa, Xb, Xc, Xu = hankel(a), hankel(b), hankel(c), hankel(list(xs[:n]))
    Hs = sp.Matrix(sp.BlockMatrix([[Xa, Xb], [Xb, Xc]]))
    J = sp.Matrix(sp.BlockMatrix([[sp.zeros(n), Xu], [-Xu, sp.zeros(n)]]))
    P = sp.Matrix(n, n, lambda i, j: 1 if j == (i + 1) % n else 0)
    A = sp.Matrix(sp.BlockMatrix([[P, sp.zeros(n)], [sp.zeros(n), P]]))
    M = Hs if kind == "f" else (A * Hs if n >= 3 else (2 * sp.eye(2 * n) + A) * Hs)
    f = J * M * sp.Matrix(xs)
    return list(xs), [sp.expand(e) for e in f]


def expression_field(variables, exprs):
    xs = sp.symbols(variables)
    return list(xs), [sp.expand(sp.sympify(e, locals=dict(zip(variables, xs)))) for e in exprs]


def line_degrees(xs, f, eps, a, b, steps):
    N = len(xs)
    eps = sp.Rational(eps)
    jac = sp.Matrix(f).jacobian(xs)
    P = [sp.Poly(ai + bi * t, t, domain=sp.QQ) for ai, bi in zip(a, b)]
    Q = sp.Poly(1, t, domain=sp.QQ)
    degrees = [1]
    for _ in range(steps):
        Qe = Q.as_expr()
        sub = {x: p.as_expr() / Qe for x, p in zip(xs, P)}
        A = [[sp.Poly(sp.cancel(Qe * ((1 if i == j else 0) - eps * jac[i, j].subs(sub))), t, domain=sp.QQ)
              for j in range(N)] for i in range(N)]
        F = [sp.Poly(sp.cancel(Qe ** 2 * fi.subs(sub)), t, domain=sp.QQ) for fi in f]
        Ad = DomainMatrix([[QQt.from_sympy(e.as_expr()) for e in row] for row in A], (N, N), QQt)
        det = Ad.det()
        adj = Ad.adjugate()
        Fd = DomainMatrix([[QQt.from_sympy(e.as_expr())] for e in F], (N, 1), QQt)
        aF = adj.matmul(Fd).to_Matrix()
        det_p = sp.Poly(QQt.to_sympy(det), t, domain=sp.QQ)
        num = [P[i] * det_p + sp.Poly(2 * eps * aF[i, 0], t, domain=sp.QQ) for i in range(N)]
        den = Q * det_p
        g = den
        for p in num:
            g = sp.gcd(g, p)
        P = [sp.div(p, g)[0] for p in num]
        Q = sp.div(den, g)[0]
        degrees.append(max([Q.degree()] + [p.degree() for p in P if not p.is_zero]))
    return degrees


CASES = [
    # name, builder, eps, a, b, steps
    ("euler-top", ("expr", ["x", "y", "z"], ["y*z", "-2*x*z", "x*y"]), "1/10", [1, -2, 3], [2, 1, -1], 5),
    ("lotka-volterra", ("expr", ["u", "v"], ["u - u*v", "u*v - v"]), "1/10", [2, -1], [1, 3], 7),
    ("generic-2d", ("expr", ["x", "y"], ["x*y - y + 1", "x**2 + 2*y"]), "1/3", [1, 2], [-1, 1], 5),
    ("lie-poisson-2-f", ("lp", "1,2", "0,1", "-1,3", "f"), "1/7", [1, 0, 2, -1], [1, 3, -1, 2], 4),
    ("lie-poisson-2-control", ("lp", "1,2", "0,1", "-1,3", "control"), "1/7", [1, 0, 2, -1], [1, 3, -1, 2], 4),
    ("lie-poisson-3-f", ("lp", "1,0,2", "0,1,0", "3,1,1", "f"), "1/10", [1, 2, -1, 1, 0, 1], [2, -1, 1, 0, 3, 1], 2),
    # dimension 8: exact_khk reads these degrees off values at points of the line
    ("lie-poisson-4-f", ("lp", "1,0,2,-1", "0,1,0,2", "3,1,1,0", "f"), "1/10",
     [1, 2, -1, 1, 0, 1, 2, -2], [2, -1, 1, 0, 3, 1, -1, 1], 2),
    ("cyclic-8", ("expr", [f"x{i}" for i in range(8)],
                  [f"x{(i + 1) % 8}*x{(i + 2) % 8} - x{i} + {i + 1}*x{(i + 3) % 8}**2" for i in range(8)]),
     "1/10", [1, 0, -1, 2, 1, -2, 0, 1], [1, 1, 2, -1, 0, 1, 3, -1], 2),
]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=pathlib.Path, default=OUT, help=f"the JSON file (default {OUT})")
    ap.add_argument("--check", action="store_true", help="compare with --out instead of writing it")
    args = ap.parse_args(argv)
    cases = []
    for name, spec, eps, a, b, steps in CASES:
        t0 = time.time()
        if spec[0] == "expr":
            xs, f = expression_field(spec[1], spec[2])
            source = {"variables": spec[1], "field": spec[2]}
        else:
            xs, f = lie_poisson_field(*spec[1:])
            source = {"lie_poisson": {"a": spec[1], "b": spec[2], "c": spec[3]}, "field_kind": spec[4]}
        degrees = line_degrees(xs, f, eps, a, b, steps)
        print(f"{name}: {degrees} ({time.time() - t0:.1f} s)", flush=True)
        cases.append({"name": name, **source, "eps": eps, "line": {"a": a, "b": b}, "degrees": degrees})
    return write_or_check(args.out, {"generator": "scripts/generate_degree_golden.py (SymPy only)",
                                     "degree": "projective degree of Phi^k restricted to the line a + t b, over Q",
                                     "cases": cases}, args.check)


if __name__ == "__main__":
    sys.exit(main())
