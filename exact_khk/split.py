"""Exact Kahan steps split over the cyclotomic factors of tⁿ − 1 (n = 1, 2, 3, 4, 6).

By the Chinese remainder theorem Q[t]/(tⁿ − 1) ≅ ∏_{d | n} Q(ζ_d), t ↦ ζ_d.  When
the four n×n blocks C of the step's system M = I − εf'(x) are circulant,
C_ij = c_{(j − i) mod n} (Lie–Poisson fields, :mod:`exact_khk.circulant`), the
character χ_d(u) = Σ_i ζ_d^i u_i satisfies χ_d(C u) = c(ζ_d^{−1}) χ_d(u) with
c(s) = Σ_m c_m s^m.  So M z = r splits into one 2×2 system over Q(ζ_d) per
divisor d of n,

    [c11(ζ_d^{−1})  c12(ζ_d^{−1})] [χ_d(z_u)]   [χ_d(r_u)]
    [c21(ζ_d^{−1})  c22(ζ_d^{−1})] [χ_d(z_v)] = [χ_d(r_v)],

and z comes back by z_i = (1/n) Σ_{d | n} Tr_{Q(ζ_d)/Q}(ζ_d^{−i} χ_d(z)).  For n
in :data:`SPLIT_N` every factor has degree at most 2: Q (d = 1, 2) or Q(θ) with
θ = ζ_d, θ² = pθ + q (d = 3, 4, 6).  A step is then Cramer's rule over Z or
Z[θ] in each factor, one division by the determinant's norm, and an integer
recombination; det M = 0 exactly when a factor's determinant is 0.

Why it pays: χ_d(z) has (a divisor of) the denominator of z, and along Kahan
orbits z has far fewer bits than Cramer's bound (heights grow by tens of bits
a step).  Each factor's solution is reduced by its own gcd before the factors
are combined, so the gcds run on numbers of about 2h bits (Q) or 4h bits
(Z[θ]) for entries of h bits, where a dense solve reduces numbers of 2n·h
bits, and the recombination runs on small numbers.  Measured in
docs/benchmarks.md.

>>> from exact_khk import LiePoissonSystem, KahanMap
>>> fld = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1").field("f")
>>> x = ["1", "0", "0", "0", "1", "0"]
>>> KahanMap(fld, "1/10", "flint", method="split").step(x) == KahanMap(fld, "1/10", "flint", method="dense").step(x)
True
"""

from __future__ import annotations

#: the n for which every cyclotomic factor of tⁿ − 1 has degree ≤ 2
SPLIT_N = (1, 2, 3, 4, 6)

_THETA = {3: (-1, -1), 4: (0, -1), 6: (1, -1)}  # ζ_d² = p·ζ_d + q


def _factors(n):
    """Per divisor d of n: (d, degree, p, q, ζ_d^j for j < d as (a, b) = a + bθ)."""
    out = []
    for d in range(1, n + 1):
        if n % d:
            continue
        if d <= 2:
            out.append((d, 1, 0, 0, [((-1) ** (j * (d - 1)), 0) for j in range(d)]))
        else:
            p, q = _THETA[d]
            powers = [(1, 0)]
            for _ in range(d - 1):  # (a + bθ)θ = bq + (a + bp)θ
                a, b = powers[-1]
                powers.append((b * q, a + b * p))
            out.append((d, 2, p, q, powers))
    return out


class SplitSystem:
    """The Kahan system of one field and ε as 2×2 systems over the factors Q(ζ_d).

    ``tensor`` (in ``kernel``'s form) maps v = [xi, dx] to the flat list of
    every factor's entries and right-hand side, coefficient by coefficient;
    ``step(v)`` solves.  Build it with :func:`split_system`.
    """

    def __init__(self, kernel, tensor, n):
        self.kernel, self.tensor, self.n = kernel, tensor, n
        self.factors = [(deg, p, q) for _, deg, p, q, _ in _factors(n)]
        # The inverse transform as a constant tensor: n·z_{blk·n + i} is the sum, over
        # the factors and the coefficients y_c of χ_d(z_blk) = y_0 (+ y_1 θ), of
        # Tr(ζ^{−i}) y_0 (+ Tr(ζ^{−i} θ) y_1), where for ζ^{−i} = z0 + z1 θ
        # Tr(ζ^{−i}) = 2·z0 + p·z1 and Tr(ζ^{−i} θ) = 2q·z1 + p(z0 + p·z1).  The
        # solution vector lists per factor the u coefficients, then the v ones.
        width = 2 * sum(deg for deg, _, _ in self.factors)
        rows = [[0] * (width + 1) for _ in range(2 * n)]
        col = 0
        for d, deg, p, q, powers in _factors(n):
            for blk in range(2):
                for i in range(n):
                    z0, z1 = powers[-i % d]
                    traces = [z0] if deg == 1 else [2 * z0 + p * z1, 2 * q * z1 + p * (z0 + p * z1)]
                    rows[blk * n + i][col:col + deg] = traces
                col += deg
        self.back = kernel.tensor(rows)

    def solve(self, v):
        """(s, L) with z = s/L the solution for the point v = [xi, dx]; raises
        ZeroDivisionError if the system is singular."""
        K = self.kernel
        e, gcd = K.apply_flat(self.tensor, v), K.gcd
        k, dens, ys = 0, [], []
        for deg, p, q in self.factors:
            if deg == 1:
                a, b, c, d, r, s = e[k:k + 6]
                den, y = a * d - b * c, (d * r - b * s, a * s - c * r)
            else:
                a0, a1, b0, b1, c0, c1, d0, d1, r0, r1, s0, s1 = e[k:k + 12]
                D0, D1 = _cross(a0, a1, d0, d1, b0, b1, c0, c1, p, q)
                C0, C1 = D0 + p * D1, -D1  # the conjugate of D
                den = D0 * C0 + q * D1 * C1  # the norm D·conj(D)
                y = (_times(*_cross(d0, d1, r0, r1, b0, b1, s0, s1, p, q), C0, C1, p, q)
                     + _times(*_cross(a0, a1, s0, s1, c0, c1, r0, r1, p, q), C0, C1, p, q))
            k += 6 * deg
            if not den:
                raise ZeroDivisionError("singular Kahan system")
            g = den  # reduce this factor's solution y/den on its own (see the module docstring)
            for t in y:
                g = gcd(g, t)
            if den < 0:
                g = -g
            dens.append(den // g)
            ys.append([t // g for t in y])
        L = self.n
        for den in dens:
            L *= den
        scaled = []
        for den, y in zip(dens, ys):
            f = L // (self.n * den)
            scaled += [t * f for t in y]
        return K.apply_flat(self.back, K.vector(scaled)), L

    def step(self, v):
        """The solution as a tuple of the kernel's rationals."""
        s, L = self.solve(v)
        make = self.kernel.make
        return tuple([make(t, L) for t in s])


def _cross(x0, x1, y0, y1, z0, z1, w0, w1, p, q):
    """x·y − z·w in Z[θ], θ² = pθ + q (elements as coefficient pairs)."""
    t = x1 * y1 - z1 * w1
    return x0 * y0 - z0 * w0 + q * t, x0 * y1 + x1 * y0 - z0 * w1 - z1 * w0 + p * t


def _times(x0, x1, y0, y1, p, q):
    """x·y in Z[θ]."""
    t = x1 * y1
    return x0 * y0 + q * t, x0 * y1 + x1 * y0 + p * t


def split_system(field, kernel, p, q):
    """The :class:`SplitSystem` of ``field`` at ε = p/q over ``kernel``, or None when
    the dimension is not 2n with n in :data:`SPLIT_N` or a block of the system is
    not circulant.  Cached on the field with its integer system."""
    N = field.dim
    if N % 2 or N // 2 not in SPLIT_N:
        return None
    return field.cached_system(("split", kernel.name), int(p), int(q),
                               lambda p, q: _build(field, kernel, p, q))


def _build(field, kernel, p, q):
    V, R = field.integer_rows(p, q)
    n = field.dim // 2
    row = lambda i, j: V[i * 2 * n + j]  # noqa: E731  (the row of entry (i, j) of M)
    if any(row(bi * n + i, bj * n + j) != row(bi * n, bj * n + (j - i) % n)
           for bi in range(2) for bj in range(2) for i in range(n) for j in range(n)):
        return None
    width, rows = len(R[0]), []
    for d, deg, _, _, powers in _factors(n):
        for bi in range(2):  # entries c_{bi,bj}(ζ^{−1}) = Σ_m c_m ζ^{−m}
            for bj in range(2):
                for c in range(deg):
                    rows.append([sum(row(bi * n, bj * n + m)[w] * powers[-m % d][c] for m in range(n))
                                 for w in range(width)])
        for bi in range(2):  # right-hand side χ_d(r) = Σ_i ζ^i r_i
            for c in range(deg):
                rows.append([sum(R[bi * n + i][w] * powers[i % d][c] for i in range(n)) for w in range(width)])
    # per factor, in _factors order: a, b, c, d, r, s (each as deg coefficients)
    return SplitSystem(kernel, kernel.tensor(rows), n)
