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
recombination; det M = 0 exactly when a factor's determinant is 0.  With
circulant blocks the Hessian is cyclic Hankel, so each factor's entries are
integer forms in χ_d(x_u), χ_d(x_v) and the common denominator D of x alone,
and a step needs only those few sums of the point.  The whole
solve is generated once per field and ε as straight-line Python over the
kernel's integers (``SplitSystem.source``), so that a step costs its integer
operations and nothing else: no matrix is built.

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

    ``rows`` are the integer rows (over [x_0, …, x_{2n−1}, D]) of every factor's
    entries and right-hand side, coefficient by coefficient (see :func:`_build`).
    The whole solve is generated once as straight-line Python (``source``: the
    linear forms, Cramer's rule per factor, the gcd reductions and the inverse
    transform), so that a step costs only its integer operations; the integers
    are the kernel's own (python-flint ``fmpz`` or gmpy2 ``mpz``).  Build it with
    :func:`split_system`.
    """

    def __init__(self, kernel, rows, n):
        self.kernel, self.n = kernel, n
        self.source = _source(rows, n)
        namespace = {}
        exec(compile(self.source, f"<split step, n = {n}>", "exec"), namespace)
        self._solve = namespace["solve"]

    def solve(self, xi, d):
        """(s, L) with z = s/L the solution at the point x = xi/d (kernel integers);
        raises ZeroDivisionError if the system is singular."""
        return self._solve(*xi, d, self.kernel.gcd)

    def step(self, x):
        """The solution at the point ``x`` (a sequence of the kernel's rationals), as
        a tuple of them."""
        s, L = self.solve(*self.kernel.split(x))
        make = self.kernel.make
        return tuple([make(t, L) for t in s])


def _lin(coeffs, names):
    """The integer linear form Σ c·name as Python source."""
    out = ""
    for c, name in zip(coeffs, names):
        if c:
            sign = "-" if c < 0 else ("+" if out else "")
            out += (f" {sign} " if out else sign) + (name if abs(c) == 1 else f"{abs(c)} * {name}")
    return out or "0"


def _term(c, name):
    """`` + c·name`` as source (empty for c = 0)."""
    return "" if not c else f" {'-' if c < 0 else '+'} " + (name if abs(c) == 1 else f"{abs(c)} * {name}")


def _source(rows, n):
    """The source of ``solve(x_0, …, x_{2n−1}, D, gcd) → ((s_0, …), L)``, the split
    solve of :class:`SplitSystem` for these rows; see the module docstring."""
    args = [f"x{i}" for i in range(2 * n)] + ["D"]
    code, k, factors, back = [], 0, _factors(n), [[] for _ in range(2 * n)]
    for j, (d, deg, p, q, powers) in enumerate(factors):
        block, k = rows[k:k + 6 * deg], k + 6 * deg
        names = [f"h{j}_{c}" for c in range(2 * deg)]  # χ_d(x_u), then χ_d(x_v)
        code += [f"{h} = {_lin([powers[i % d][c % deg] if i // n == c // deg else 0 for i in range(2 * n)], args)}"
                 for c, h in enumerate(names)]
        names.append("D")
        e = {}  # entry name -> its coefficient names
        for m, name in enumerate("abcdrs"):
            e[name] = [f"{name}{j}_{c}" for c in range(deg)]
            code += [f"{v} = {_lin(block[m * deg + c], names)}" for c, v in enumerate(e[name])]
        y = [f"y{j}_{c}" for c in range(2 * deg)]  # χ_d(z): the u coefficients, then the v ones
        a, b, c_, d_, r, s = (e[name] for name in "abcdrs")
        den = f"den{j}"
        if deg == 1:
            code += [f"{den} = {a[0]} * {d_[0]} - {b[0]} * {c_[0]}",
                     f"{y[0]} = {d_[0]} * {r[0]} - {b[0]} * {s[0]}",
                     f"{y[1]} = {a[0]} * {s[0]} - {c_[0]} * {r[0]}"]
        else:  # over Z[θ], θ² = pθ + q: Cramer's rule times the conjugate of det
            code += _cross(f"m{j}", a, d_, b, c_, p, q)  # det = a·d − b·c
            code += [f"k{j}_0 = m{j}_0{_term(p, f'm{j}_1')}", f"k{j}_1 = -m{j}_1",  # its conjugate
                     f"{den} = m{j}_0 * k{j}_0{_term(q, f'm{j}_1 * k{j}_1')}"]  # its norm
            code += _cross(f"u{j}", d_, r, b, s, p, q) + _times(y[:2], f"u{j}", f"k{j}", p, q)
            code += _cross(f"v{j}", a, s, c_, r, p, q) + _times(y[2:], f"v{j}", f"k{j}", p, q)
        g = f"g{j}"
        code += [f"if not {den}:", "    raise ZeroDivisionError('singular Kahan system')",
                 # reduce this factor's solution y/den on its own (see the module docstring)
                 f"{g} = {den}"] + [f"{g} = gcd({g}, {t})" for t in y] + [
                 f"{g} = -{g} if {den} < 0 else {g}", f"{den} //= {g}"] + [f"{t} //= {g}" for t in y]
        # the inverse transform: n·z_{blk·n + i} is the sum over the factors of
        # Tr(ζ^{−i} χ_d(z_blk)); for ζ^{−i} = z0 + z1·θ and χ_d(z_blk) = y0 + y1·θ,
        # Tr(ζ^{−i}) = 2·z0 + p·z1 and Tr(ζ^{−i}·θ) = 2q·z1 + p(z0 + p·z1)
        for blk in range(2):
            for i in range(n):
                z0, z1 = powers[-i % d]
                traces = [z0] if deg == 1 else [2 * z0 + p * z1, 2 * q * z1 + p * (z0 + p * z1)]
                back[blk * n + i].append((y[blk * deg:(blk + 1) * deg], traces))
    dens = [f"den{j}" for j in range(len(factors))]
    for j, (_, deg, *_) in enumerate(factors):  # bring every factor to the denominator L
        others = " * ".join(dens[:j] + dens[j + 1:])
        if others:
            code += [f"{t} *= {others}" for t in (f"y{j}_{c}" for c in range(2 * deg))]
    code.append(f"L = {' * '.join([str(n)] + dens)}")
    outs = [_lin([t for _, tr in terms for t in tr], [v for ys, _ in terms for v in ys]) for terms in back]
    code.append(f"return ({', '.join(outs)},), L")
    return f"def solve({', '.join(args)}, gcd):\n" + "".join(f"    {line}\n" for line in code)


def _in_characters(rows, n, d, deg, powers):
    """Rows over [x, D] of one factor as rows over the coefficients of χ_d(x_u),
    χ_d(x_v) and D, or None if one is not such a form.  With circulant blocks
    every one is: the Hessian is then cyclic Hankel in each block (as for
    Lie–Poisson fields, MATH.md), and the generated step computes those few
    sums once."""
    out = []
    for row in rows:
        # χ_d(x_blk) = Σ_i ζ^i x_{blk·n + i} with ζ^c = θ^c for c < deg: α_c is the x_c entry
        alpha = [row[blk * n + c] for blk in range(2) for c in range(deg)]
        if any(row[blk * n + i] != sum(alpha[blk * deg + c] * powers[i % d][c] for c in range(deg))
               for blk in range(2) for i in range(n)):
            return None
        out.append(alpha + [row[-1]])
    return out


def _cross(out, x, y, z, w, p, q):
    """Source for out = x·y − z·w in Z[θ], θ² = pθ + q (``out_0``, ``out_1``; the
    arguments are coefficient-name pairs)."""
    return [f"t = {x[1]} * {y[1]} - {z[1]} * {w[1]}",
            f"{out}_0 = {x[0]} * {y[0]} - {z[0]} * {w[0]}{_term(q, 't')}",
            f"{out}_1 = {x[0]} * {y[1]} + {x[1]} * {y[0]} - {z[0]} * {w[1]} - {z[1]} * {w[0]}{_term(p, 't')}"]


def _times(out, x, y, p, q):
    """Source for out = x·y in Z[θ] (``out``: two names; x, y: name prefixes)."""
    return [f"t = {x}_1 * {y}_1",
            f"{out[0]} = {x}_0 * {y}_0{_term(q, 't')}",
            f"{out[1]} = {x}_0 * {y}_1 + {x}_1 * {y}_0{_term(p, 't')}"]


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
        block = []
        for bi in range(2):  # entries c_{bi,bj}(ζ^{−1}) = Σ_m c_m ζ^{−m}
            for bj in range(2):
                for c in range(deg):
                    block.append([sum(row(bi * n, bj * n + m)[w] * powers[-m % d][c] for m in range(n))
                                 for w in range(width)])
        for bi in range(2):  # right-hand side χ_d(r) = Σ_i ζ^i r_i
            for c in range(deg):
                block.append([sum(R[bi * n + i][w] * powers[i % d][c] for i in range(n)) for w in range(width)])
        block = _in_characters(block, n, d, deg, powers)
        if block is None:
            return None
        rows += block
    # per factor, in _factors order: a, b, c, d, r, s (each as deg coefficients over χ_d(x), D)
    return SplitSystem(kernel, rows, n)
