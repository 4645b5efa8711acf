"""Independent check of the degrees d_k of the Kahan map of the Volterra chains (docs/atlas.md, Findings):
SymPy only (no exact_khk code).  The Kahan step of the homogeneous quadratic field f is
x' = x + 2 eps (I - eps f'(x))^{-1} f(x); on homogeneous coordinates (Q, P) of a point, with
A = Q I - eps f'(P) (f' is linear), x' = (det(A) P + 2 eps adj(A) f(P)) / (Q det A).  Iterated on the
line x = a + t b (a, b fixed rationals) over Q[t], with the gcd of the N + 1 components divided out,
the degree of the curve Phi^k(line) is max(deg) — the degree d_k of Phi^k for a generic line, and a
lower bound for any line.

    python scripts/check_volterra_degrees.py [N] [K] [periodic|open]
"""
import sys
from functools import reduce

import sympy as sp
from sympy.polys.matrices import DomainMatrix

N = int(sys.argv[1]) if len(sys.argv) > 1 else 5
K = int(sys.argv[2]) if len(sys.argv) > 2 else 3
periodic = (sys.argv[3] if len(sys.argv) > 3 else "periodic") == "periodic"
eps = sp.Rational(1, 10)
t = sp.symbols("t")
xs = sp.symbols(f"x0:{N}")


def at(k):
    if periodic:
        return xs[k % N]
    return xs[k] if 0 <= k < N else 0


f = sp.Matrix([xs[k] * (at(k + 1) - at(k - 1)) for k in range(N)])
J = f.jacobian(xs)
a = [sp.Rational(p, q) for p, q in [(1, 3), (-2, 7), (3, 5), (1, 11), (-4, 9), (5, 13)][:N]]
b = [sp.Rational(p, q) for p, q in [(2, 5), (1, 4), (-3, 8), (7, 3), (1, 6), (-2, 9)][:N]]
R = sp.QQ[t]
Jt = [[sp.lambdify(xs, J[i, j]) for j in range(N)] for i in range(N)]  # J is linear in x
ft = [sp.lambdify(xs, f[i]) for i in range(N)]
Q = R.one
P = [R.convert(a[i] + b[i] * t) for i in range(N)]
degs = [1]
for k in range(1, K + 1):
    # A = Q I - eps f'(P) and f(P) over QQ[t] (f' linear, f quadratic in P: polynomial arithmetic only)
    A = DomainMatrix([[(Q if i == j else R.zero) - R.convert(eps) * Jt[i][j](*P) for j in range(N)]
                      for i in range(N)], (N, N), R)
    fP = DomainMatrix([[ft[i](*P)] for i in range(N)], (N, 1), R)
    det = A.det()
    upd = A.adjugate() * fP
    newP = [det * P[i] + R.convert(2 * eps) * upd[i, 0].element for i in range(N)]
    newQ = Q * det
    g = reduce(R.gcd, newP + [newQ])
    Q, P = R.exquo(newQ, g), [R.exquo(p, g) for p in newP]
    degs.append(max(v.degree() if v else 0 for v in [Q] + P))
    print(f"k = {k}: degree {degs[-1]}", flush=True)
print("degrees", degs, "; (4^(k+1) - 1)/3 =", [(4 ** (k + 1) - 1) // 3 for k in range(K + 1)])
