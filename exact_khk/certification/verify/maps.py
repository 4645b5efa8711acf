"""Kahan maps of quadratic fields, written out for the verifier: the field and its
Jacobian from coefficients, one step by Gaussian elimination, orbits, the derivative of
a step, the Jacobi identity of a bivector, and the Lie–Poisson family's matrices
(J(x), Hs, the involutions B, the closed form H~) from the vectors a, b, c.

Everything is over a field of :mod:`.fields`; a singular step or a pole raises
:class:`~.fields.Undefined`.
"""

from __future__ import annotations

from fractions import Fraction

from exact_khk.certification.verify.fields import (Dual, Undefined, _Cyclotomic, _eliminate, _matmul, _matvec,
                                                   _dot, _Rationals, solve, transpose)


def _identity_minus(e, D, sign=-1):
    """I + sign·e·D."""
    se = sign * e
    return [[(1 if i == j else 0) + se * t for j, t in enumerate(r)] for i, r in enumerate(D)]


class _Quadratic:
    """f_i(x) = Σ q x_j x_k + Σ l x_j + c_i with coefficients in the field."""

    def __init__(self, dim, quad, linear, const):
        self.dim, self.quad, self.linear, self.const = dim, quad, linear, const

    def jacobian(self, x):
        """f'(x): ∂(q x_j x_k)/∂x_j = q x_k (and symmetrically), plus L."""
        N = self.dim
        J = [[0] * N for _ in range(N)]
        for i in range(N):
            for j, k, q in self.quad[i]:
                J[i][j] = J[i][j] + q * x[k]
                J[i][k] = J[i][k] + q * x[j]
            for j, l in self.linear[i]:
                J[i][j] = J[i][j] + l
        return J

    def evaluate(self, x):
        """f(x)."""
        out = []
        for i in range(self.dim):
            s = self.const[i]
            for j, k, q in self.quad[i]:
                s = s + q * x[j] * x[k]
            for j, l in self.linear[i]:
                s = s + l * x[j]
            out.append(s)
        return out

    @property
    def homogeneous(self):
        return not any(self.linear) and all(c == 0 for c in self.const)

    def kahan_rhs(self, e, x):
        """(I + e L) x + 2 e c: the right-hand side of the step equation (I − e f'(x)) Φ(x) = ."""
        return [x[i] + e * _dot([l for _, l in self.linear[i]], [x[j] for j, _ in self.linear[i]])
                + 2 * e * self.const[i] for i in range(self.dim)]


def _expression_field(fld, F) -> _Quadratic:
    """The quadratic field of an ExpressionSystem's ``field(name)`` (its coefficient tuples)."""
    quad = [[(j, k, F.of(Fraction(c))) for (j, k), c in terms] for terms in fld.quad]
    lin = [[(j, F.of(Fraction(c))) for j, c in row] for row in fld.linear]
    return _Quadratic(fld.dim, quad, lin, [F.of(Fraction(c)) for c in fld.const])


def _hankel(w):
    n = len(w)
    return [[w[(i + j) % n] for j in range(n)] for i in range(n)]


def _lp_hessian(a, b, c):
    """Hs = [[X(a), X(b)], [X(b), X(c)]], X(w)[i][j] = w[(i+j) mod n]."""
    Xa, Xb, Xc = _hankel(a), _hankel(b), _hankel(c)
    return [ra + rb for ra, rb in zip(Xa, Xb)] + [rb + rc for rb, rc in zip(Xb, Xc)]


def _lp_J(x, n):
    """J(x) = [[0, X(u)], [−X(u), 0]], u = x[:n]."""
    Xu = _hankel(list(x[:n]))
    zero = 0 * x[0]
    return [[zero] * n + list(r) for r in Xu] + [[-t for t in r] + [zero] * n for r in Xu]


def _lp_field(n, Hs) -> _Quadratic:
    """f(x) = J(x) Hs x written out: for i < n, f_i = Σ_l u_{(i+l) mod n} (Hs x)_{n+l};
    for i = n + i', f_i = −Σ_l u_{(i'+l) mod n} (Hs x)_l."""
    N = 2 * n
    quad = []
    for i in range(N):
        row, sign, ii = (n, 1, i) if i < n else (0, -1, i - n)
        acc = {}
        for l in range(n):
            j = (ii + l) % n  # the u-coordinate multiplying (Hs x)_{row + l}
            for m in range(N):
                h = Hs[row + l][m]
                if h != 0:
                    key = (min(j, m), max(j, m))
                    acc[key] = acc.get(key, 0) + sign * h
        quad.append([(j, k, q) for (j, k), q in sorted(acc.items()) if q != 0])
    return _Quadratic(N, quad, [[] for _ in range(N)], [0] * N)


def _involution(n, signs, F):
    """B = Bc ⊕ Bc, Bc[i][j] = α_{(j−i) mod n}, α_k = (1/n) Σ_j s_j ω^{−jk}, ω = ζ_n,
    computed in Q(ζ_n) and mapped into F (ζ_n to F's primitive n-th root of unity)."""
    s = [1 if ch == "+" else -1 for ch in signs]
    K = _Cyclotomic(n)
    alpha = [sum((K.of(Fraction(s[j], n), (-j * k) % n) for j in range(n)), K.zero).c for k in range(n)]
    if isinstance(F, _Rationals) and any(len(a) > 1 for a in alpha):
        raise Undefined(f"the involution {signs!r} is not rational")
    if all(len(a) <= 1 for a in alpha):
        vals = [F.of(a[0] if a else Fraction(0)) for a in alpha]
    else:
        w = F.root_of_unity(n)
        vals = []
        for a in alpha:
            v, p = F.zero, F.one
            for t in a:
                v, p = v + p * F.of(t), p * w
            vals.append(v)
    Bc = [[vals[(j - i) % n] for j in range(n)] for i in range(n)]
    Z = [F.zero] * n
    return [list(r) + Z for r in Bc] + [Z + list(r) for r in Bc]


#: where H~_M has a pole
HTILDE_POLE = "I - eps^2 (M J(x))^2 is singular"


def _htilde_matrices(M, x, e, n):
    """(J(x), M J(x), S = I − ε²(M J(x))²)."""
    J = _lp_J(x, n)
    MJ = _matmul(M, J)
    return J, MJ, _identity_minus(e * e, _matmul(MJ, MJ))


def _htilde(M, x, e, n):
    """H~_M(x, ε) = xᵀ (I − ε²(M J(x))²)⁻¹ M x; Undefined at a pole."""
    return _dot(x, solve(_htilde_matrices(M, x, e, n)[2], _matvec(M, x), HTILDE_POLE))


# --- steps, orbits, derivatives ---------------------------------------------------------


def step(f, e, x):
    """Φ_f(x, e): the solution y of (I − e f'(x)) y = (I + e L) x + 2 e c (Undefined if singular)."""
    return solve(_identity_minus(e, f.jacobian(x)), f.kahan_rhs(e, x), "singular step: I - eps f'(x) is singular")


def orbit(f, e, x0, steps):
    """[x0, Φ(x0), …] (steps + 1 points)."""
    return list(lazy_orbit(f, e, x0, steps))


def lazy_orbit(f, e, x0, steps):
    """The orbit, one point at a time (a singular step raises when it is reached)."""
    x = list(x0)
    yield x
    for _ in range(steps):
        x = step(f, e, x)
        yield x


def dphi(f, e, x, y):
    """dΦ(x) = (I − e f'(x))⁻¹ (I + e f'(y)), y = Φ(x) (with y = x: the control's wrong formula)."""
    _, X = _eliminate(_identity_minus(e, f.jacobian(x)), _identity_minus(e, f.jacobian(y), 1))
    if X is None:
        raise Undefined("I - eps f'(x) is singular")
    return X


def dual_step(f, e, x):
    """The derivative of the step x -> Φ(x), by dual numbers through the solve."""
    return gradients(lambda y: step(f, e, y), x)


def determinant(M):
    return _eliminate(M)[0]


def jacobiator(matrix, x):
    """The cyclic sums Σ_m (Π_im ∂_mΠ_jk + Π_jm ∂_mΠ_ki + Π_km ∂_mΠ_ij), i < j < k, of the
    bivector ``matrix(point)`` at x (derivatives by dual numbers)."""
    N, zero = len(x), 0 * x[0]
    parts = [[Dual.parts(t, N, zero) for t in row] for row in matrix(Dual.variables(x))]
    P, dP = [[t[0] for t in row] for row in parts], [[t[1] for t in row] for row in parts]
    out = []
    for i in range(N):
        for j in range(i + 1, N):
            for k in range(j + 1, N):
                s = zero
                for m in range(N):
                    s = s + P[i][m] * dP[j][k][m] + P[j][m] * dP[k][i][m] + P[k][m] * dP[i][j][m]
                out.append(s)
    return out


def gradient(fn, x):
    """∇fn(x) by dual numbers (fn of a point, any field element or dual out)."""
    return gradients(lambda y: [fn(y)], x)[0]


def gradients(fn, x):
    """[∇fn_i(x)] of a vector function fn, by one pass of dual numbers."""
    return [list(Dual.parts(v, len(x), 0 * x[0])[1]) for v in fn(Dual.variables(x))]


def lp_shift(n):
    """A = P ⊕ P, P[i][(i+1) mod n] = 1 (rational entries)."""
    N = 2 * n
    A = [[Fraction(0)] * N for _ in range(N)]
    for i in range(n):
        A[i][(i + 1) % n] = A[n + i][n + (i + 1) % n] = Fraction(1)
    return A


def shift_index(n, l):
    """σ with (A^l v)[j] = v[σ(j)]."""
    return [(j + l) % n if j < n else n + (j - n + l) % n for j in range(2 * n)]


def lp_q(Hs, x, n):
    """q_l = tr((Aᵀ)^l (J(x) Hs)²)/(2n), l = 0..n−1."""
    S = _matmul(_lp_J(x, n), Hs)
    S2 = _matmul(S, S)
    return [sum((S2[i][s] for i, s in enumerate(shift_index(n, l))), 0 * x[0]) / (2 * n) for l in range(n)]


def lp_pi(Hs, x, e, n):
    """Π(x) = J − ε² J Hs J Hs J (the definition)."""
    J = _lp_J(x, n)
    JH = _matmul(J, Hs)
    T = _matmul(_matmul(JH, JH), J)
    return [[a - e * e * b for a, b in zip(ra, rb)] for ra, rb in zip(J, T)]


def lp_pi_from_q(Hs, x, e, n):
    """Π(x) = (1 − ε² q_0) J − ε² Σ_{l≥1} q_l A^l J (the paper's formula)."""
    J = _lp_J(x, n)
    q = lp_q(Hs, x, n)
    out = [[(1 - e * e * q[0]) * t for t in row] for row in J]
    for l in range(1, n):
        c = e * e * q[l]
        for j, s in enumerate(shift_index(n, l)):
            out[j] = [a - c * t for a, t in zip(out[j], J[s])]
    return out


def htilde_gradient(M, x, e, n):
    """∇H~_M(x) in closed form: with S = I − ε²(M J(x))², z = S⁻¹ M x, w = S⁻ᵀ x, u = Mᵀ w,
    ∂_m H~ = z_m + u_m + ε² (uᵀ J(e_m) M J z + (Mᵀ J(x)ᵀ u)ᵀ J(e_m) z)  (J is linear in x;
    J(e_m) = 0 for m >= n).  Undefined at a pole."""
    J, MJ, S = _htilde_matrices(M, x, e, n)
    z, w = solve(S, _matvec(M, x), HTILDE_POLE), solve(transpose(S), x, HTILDE_POLE)
    Mt = transpose(M)
    u = _matvec(Mt, w)
    a = _matvec(MJ, z)
    r = _matvec(Mt, _matvec(transpose(J), u))

    def form(p, q, k):  # pᵀ J(e_k) q
        return sum((p[i] * q[n + (k - i) % n] - p[n + i] * q[(k - i) % n] for i in range(n)), 0 * x[0])
    return [z[m] + u[m] + (e * e * (form(u, a, m) + form(r, z, m)) if m < n else 0) for m in range(2 * n)]


def h_definition(x, y, e, n):
    """h(x, y) = (2ε)⁻¹ xᵀ J((x + y)/2)⁻¹ y (Undefined where J(m) is singular)."""
    return _dot(x, solve(_lp_J([(a + b) / 2 for a, b in zip(x, y)], n), y, "J((x+x~)/2) is singular")) / (2 * e)


__all__ = ["_Quadratic", "_Rationals", "_Cyclotomic"]
