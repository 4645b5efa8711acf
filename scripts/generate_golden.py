"""Regenerate tests/data/golden_orbits.json by an independent route.

This script does NOT use exact_khk.  It builds every matrix with SymPy straight
from the formulas of docs/conventions.md — X(w), J(x), Hs, B = Σ_j s_j Π_j with
Π_j = (1/n) Σ_k ω^{-jk} A^k (ω = exp(2πi/n), simplified symbolically), the
Jacobian f'(x) = J(x) M + [J(e_0) y, …, J(e_{n-1}) y, 0, …, 0] with y = M x — and
takes each Kahan step with SymPy's exact ``Matrix.LUsolve``.  The library's own
tests then compare its orbits with ``==`` against these strings.

Run:  python scripts/generate_golden.py   (takes a few seconds; ``--check`` compares with the
file instead of writing it, ``--out`` writes elsewhere)
"""

from __future__ import annotations

import argparse
import pathlib
import sys

import sympy as sp

from script_io import write_or_check

OUT = pathlib.Path(__file__).resolve().parent.parent / "tests" / "data" / "golden_orbits.json"

CASES = [
    # n, a, b, c, x0, eps, field, signs, steps
    (2, "1,2", "0,1", "-1,3", "1,0,2,1", "1/7", "f", None, 6),
    (2, "1,2", "0,1", "-1,3", "1,0,2,1", "1/7", "g", "-+", 6),
    (2, "1,2", "0,1", "-1,3", "1,0,2,1", "1/7", "control", None, 5),
    (3, "1,0,2", "0,1,0", "3,1,1", "1,2,-1,1/2,0,1", "1/10", "f", None, 6),
    (3, "1,0,2", "0,1,0", "3,1,1", "1,2,-1,1/2,0,1", "1/10", "g", "-++", 6),
    (3, "1,0,2", "0,1,0", "3,1,1", "1,2,-1,1/2,0,1", "1/10", "g", "+--", 5),
    (3, "1,0,2", "0,1,0", "3,1,1", "1,2,-1,1/2,0,1", "-1/3", "control", None, 5),
    (4, "1,-1,0,2", "2,0,1,1", "0,1,-2,1", "1,0,1,2,-1,1,0,1", "1/5", "f", None, 5),
    (4, "1,-1,0,2", "2,0,1,1", "0,1,-2,1", "1,0,1,2,-1,1,0,1", "1/5", "g", "++-+", 5),
    (4, "1,-1,0,2", "2,0,1,1", "0,1,-2,1", "1,0,1,2,-1,1,0,1", "1/5", "g", "-+-+", 4),
    (5, "1,0,0,2,-1", "0,1,1,0,0", "2,0,1,0,1", "1,1,0,-1,2,0,1,0,0,1", "1/4", "f", None, 4),
]


def vec(s):
    return [sp.Rational(t) for t in s.split(",")]


def hankel(w):
    n = len(w)
    return sp.Matrix(n, n, lambda i, j: w[(i + j) % n])


def J_of(x, n):
    Xu = hankel(list(x[:n]))
    Z = sp.zeros(n, n)
    return sp.Matrix(sp.BlockMatrix([[Z, Xu], [-Xu, Z]]))


def shift(n):
    P = sp.Matrix(n, n, lambda i, j: 1 if j == (i + 1) % n else 0)
    return sp.diag(P, P)


def involution(n, signs):
    A = shift(n)
    w = sp.exp(2 * sp.pi * sp.I / n)
    B = sp.zeros(2 * n, 2 * n)
    for j, ch in enumerate(signs):
        s = 1 if ch == "+" else -1
        Pi = sum((w ** (-j * k) * A ** k for k in range(n)), sp.zeros(2 * n, 2 * n)) / n
        B += s * Pi
    B = B.applyfunc(lambda t: sp.nsimplify(sp.simplify(sp.expand_complex(t))))
    assert all(t.is_Rational for t in B), f"involution {signs} is not rational"
    assert B * B == sp.eye(2 * n)
    return B


def kahan_step(M, x, eps, n):
    N = 2 * n
    y = M * x
    Jx = J_of(x, n)
    cols = [J_of(sp.Matrix([1 if i == k else 0 for i in range(N)]), n) * y for k in range(n)]
    Jp = sp.Matrix.hstack(*cols, sp.zeros(N, n))
    fprime = Jx * M + Jp
    return (sp.eye(N) - eps * fprime).LUsolve(x)


def run(case):
    n, a, b, c, x0, eps, field, signs, steps = case
    a, b, c = vec(a), vec(b), vec(c)
    Hs = sp.Matrix(sp.BlockMatrix([[hankel(a), hankel(b)], [hankel(b), hankel(c)]]))
    A = shift(n)
    if field == "f":
        M = Hs
    elif field == "g":
        M = involution(n, signs) * Hs
    else:
        M = (A if n >= 3 else 2 * sp.eye(2 * n) + A) * Hs
    x = sp.Matrix(vec(x0))
    e = sp.Rational(eps)
    orbit = [x]
    for _ in range(steps):
        orbit.append(kahan_step(M, orbit[-1], e, n))
    return {"n": n, "a": [str(t) for t in a], "b": [str(t) for t in b], "c": [str(t) for t in c],
            "x0": [str(t) for t in vec(x0)], "eps": eps, "field": field, "signs": signs,
            "steps": steps, "orbit": [[str(t) for t in p] for p in orbit]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=pathlib.Path, default=OUT, help=f"the JSON file (default {OUT})")
    ap.add_argument("--check", action="store_true", help="compare with --out instead of writing it")
    args = ap.parse_args(argv)
    data = {"generator": "scripts/generate_golden.py (SymPy Matrix.LUsolve, independent of exact_khk)",
            "sympy": sp.__version__, "cases": [run(c) for c in CASES]}
    return write_or_check(args.out, data, args.check)


if __name__ == "__main__":
    sys.exit(main())
