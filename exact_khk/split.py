"""Exact Kahan steps split over the cyclotomic factors of tⁿ − 1 (n < 16).

By the Chinese remainder theorem Q[t]/(tⁿ − 1) ≅ ∏_{d | n} Q(ζ_d), t ↦ ζ_d.  When
the four n×n blocks C of the step's system M = I − εf'(x) are circulant,
C_ij = c_{(j − i) mod n} (Lie–Poisson fields, :mod:`exact_khk.circulant`), the
character χ_d(u) = Σ_i ζ_d^i u_i satisfies χ_d(C u) = c(ζ_d^{−1}) χ_d(u) with
c(s) = Σ_m c_m s^m.  So M z = r splits into one 2×2 system over Q(ζ_d) per
divisor d of n,

    [c11(ζ_d^{−1})  c12(ζ_d^{−1})] [χ_d(z_u)]   [χ_d(r_u)]
    [c21(ζ_d^{−1})  c22(ζ_d^{−1})] [χ_d(z_v)] = [χ_d(r_v)],

and z comes back by z_i = (1/n) Σ_{d | n} Tr_{Q(ζ_d)/Q}(ζ_d^{−i} χ_d(z)), where
Tr(ζ_d^m) is the Ramanujan sum c_d(m).  Elements of Q(ζ_d) are coefficient
vectors in the basis 1, θ, …, θ^{φ(d)−1} of Z[θ] = Z[t]/Φ_d(t).  Each factor is
solved by Cramer's rule over Z[θ]; numerators and determinant are multiplied
by det* = ∏ σ_k(det), the product of det's other conjugates (θ ↦ θ^k, k prime
to d), so that the denominator is the norm N(det) ∈ Z.  det M = 0 exactly when
some factor's determinant is 0.  With circulant blocks the Hessian is cyclic
Hankel, so each factor's entries are integer forms in χ_d(x_u), χ_d(x_v) and
the common denominator D of x alone, and a step needs only those few sums of
the point.  The whole solve is generated once per field and ε as straight-line
Python over the kernel's integers (``SplitSystem.source``), so that a step
costs its integer operations and nothing else: no matrix is built.

Why it pays: χ_d(z) has (a divisor of) the denominator of z, and along Kahan
orbits z has far fewer bits than Cramer's bound (heights grow by tens of bits
a step).  Each factor's solution is reduced by its own gcd before the factors
are combined, so the gcds run on numbers of about 2h·φ(d) bits for entries of
h bits, where a dense solve reduces numbers of 2n·h bits, and the
recombination runs on small numbers.  Measured in docs/benchmarks.md.

>>> from exact_khk import LiePoissonSystem, KahanMap
>>> fld = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1").field("f")
>>> x = ["1", "0", "0", "0", "1", "0"]
>>> KahanMap(fld, "1/10", "flint", method="split").step(x) == KahanMap(fld, "1/10", "flint", method="dense").step(x)
True
"""

from __future__ import annotations

import math

from .systems import ramanujan_sum

#: the n for which the split step is generated (the code grows like the cube of
#: the largest degree φ(d), and for n ≥ 16 the structured step is as fast)
SPLIT_N = tuple(range(1, 16))

#: the n where ``method='auto'`` takes it: every factor Q(ζ_d), d | n, has degree
#: φ(d) ≤ 4.  Measured along orbits (docs/benchmarks.md; README, "Known
#: limitations") it is then faster than the dense and the structured step at every
#: height tried; with larger factors it is not always (n = 7 loses to the structured
#: step at 5000 bits, n = 11 everywhere).
AUTO_SPLIT_N = (1, 2, 3, 4, 5, 6, 8, 10, 12)

def _factors(n):
    """Per divisor d of n: (d, deg = φ(d), θ^j for j < d as coefficient lists in the
    basis 1, θ, …, θ^{deg−1} of Z[θ] = Z[t]/Φ_d(t), θ = ζ_d)."""
    import flint

    out = []
    for d in (d for d in range(1, n + 1) if n % d == 0):
        phi = flint.fmpz_poly.cyclotomic(d)
        deg = phi.degree()
        powers = []
        for j in range(d):
            c = [int(v) for v in (flint.fmpz_poly([0] * j + [1]) % phi).coeffs()]
            powers.append(c + [0] * (deg - len(c)))
        out.append((d, deg, powers))
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


def _source(rows, n):
    """The source of ``solve(x_0, …, x_{2n−1}, D, gcd) → ((s_0, …), L)``, the split
    solve of :class:`SplitSystem` for these rows; see the module docstring."""
    args = [f"x{i}" for i in range(2 * n)] + ["D"]
    code, k, factors, back = [], 0, _factors(n), [[] for _ in range(2 * n)]
    for j, (d, deg, powers) in enumerate(factors):
        block, k = rows[k:k + 6 * deg], k + 6 * deg
        names = [f"h{j}_{c}" for c in range(2 * deg)]  # χ_d(x_u), then χ_d(x_v)
        code += [f"{h} = {_lin([powers[i % d][c % deg] if i // n == c // deg else 0 for i in range(2 * n)], args)}"
                 for c, h in enumerate(names)]
        names.append("D")
        e = {}  # entry name -> its coefficient names
        for m, name in enumerate("abcdrs"):
            e[name] = [f"{name}{j}_{c}" for c in range(deg)]
            code += [f"{v} = {_lin(block[m * deg + c], names)}" for c, v in enumerate(e[name])]
        a, b, c_, d_, r, s = (e[name] for name in "abcdrs")
        y = [f"y{j}_{c}" for c in range(2 * deg)]  # χ_d(z): the u coefficients, then the v ones
        den, field = f"den{j}", (d, deg, powers)
        # Cramer's rule over Z[θ], then numerators and det times det* = the product of
        # the other conjugates σ_k(det) (θ ↦ θ^k, k prime to d), so that den = N(det) ∈ Z
        m, u, v = ([f"{w}{j}_{c}" for c in range(deg)] for w in "muv")
        code += _product(m, [(1, a, d_), (-1, b, c_)], field)
        code += _product(u, [(1, d_, r), (-1, b, s)], field) + _product(v, [(1, a, s), (-1, c_, r)], field)
        units = [k for k in range(2, d) if math.gcd(k, d) == 1]
        conj, sk = ([f"{w}{j}_{c}" for c in range(deg)] for w in "kw")
        for i, unit in enumerate(units):
            code += [f"{w} = {_lin([powers[unit * c2 % d][c] for c2 in range(deg)], m)}"
                     for c, w in enumerate(sk if i else conj)]
            if i:
                code += _product(conj, [(1, conj, sk)], field)
        if not units:  # d = 1, 2: the factor is Q
            code += [f"{den} = {m[0]}"] + [f"{t} = {w}" for t, w in zip(y, u + v)]
        else:  # N(det) is det·det*'s constant coefficient (the others are 0)
            code += _product([den] + [None] * (deg - 1), [(1, m, conj)], field)
            code += _product(y[:deg], [(1, u, conj)], field) + _product(y[deg:], [(1, v, conj)], field)
        g = f"g{j}"
        code += [f"if not {den}:", "    raise ZeroDivisionError('singular Kahan system')",
                 # reduce this factor's solution y/den on its own (see the module docstring)
                 f"{g} = {den}"] + [f"{g} = gcd({g}, {t})" for t in y] + [
                 f"{g} = -{g} if {den} < 0 else {g}", f"{den} //= {g}"] + [f"{t} //= {g}" for t in y]
        # the inverse transform: n·z_{blk·n + i} is the sum over the factors of
        # Tr(ζ^{−i} χ_d(z_blk)) = Σ_c y_c Tr(ζ^{c − i}), and Tr(ζ_d^m) is the
        # Ramanujan sum c_d(m)
        for blk in range(2):
            for i in range(n):
                traces = [ramanujan_sum(d, (c - i) % d) for c in range(deg)]
                back[blk * n + i].append((y[blk * deg:(blk + 1) * deg], traces))
    dens = [f"den{j}" for j in range(len(factors))]
    for j, (_, deg, _) in enumerate(factors):  # bring every factor to the denominator L
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


def _product(out, terms, field):
    """Source for out = Σ ± x·y in Z[θ] = Z[t]/Φ_d(t) (``terms``: (sign, x, y) with x, y
    lists of coefficient names; ``field``: (d, deg, powers) of :func:`_factors`;
    coefficients whose name in ``out`` is None are not computed)."""
    d, deg, powers = field
    wanted = [c for c, o in enumerate(out) if o is not None]
    code, tmp = [], []  # the coefficients of t^0 … t^{2deg−2} before reduction
    for m in range(2 * deg - 1):
        if not any(powers[m % d][c] for c in wanted):
            tmp.append("0")
            continue
        parts = [f"{'-' if sign < 0 else '+'} {x[i]} * {y[m - i]}"
                 for sign, x, y in terms for i in range(max(0, m - deg + 1), min(m, deg - 1) + 1)]
        tmp.append(f"t{m}")
        code.append(f"t{m} = {' '.join(parts).removeprefix('+ ')}")
    if deg == 1:
        return [f"{out[0]} = {code[0].split(' = ', 1)[1]}"]
    return code + [f"{out[c]} = {_lin([powers[m % d][c] for m in range(len(tmp))], tmp)}" for c in wanted]


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
    for d, deg, powers in _factors(n):
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
