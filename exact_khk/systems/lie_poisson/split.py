"""Exact Kahan steps split over the cyclotomic factors of tⁿ − 1 (n < 16).

By the Chinese remainder theorem Q[t]/(tⁿ − 1) ≅ ∏_{d | n} Q(ζ_d), t ↦ ζ_d.  When
the four n×n blocks C of the step's system M = I − εf'(x) are circulant,
C_ij = c_{(j − i) mod n} (Lie–Poisson fields, :mod:`exact_khk.systems.lie_poisson.circulant`), the
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

from exact_khk.systems.lie_poisson.circulant import structure_rows
from exact_khk.systems.lie_poisson.paths import SPLIT_N
from exact_khk.linalg.numtheory import ramanujan_sum

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
    transform), so that a step costs only its integer operations, on the kernel's
    integers (python-flint ``fmpz`` or gmpy2 ``mpz``).  Build it with
    :func:`split_system`.
    """

    def __init__(self, kernel, rows, n):
        self.kernel, self.n = kernel, n
        self.source, consts = _source(rows, n)
        integer = lambda c: kernel.num(kernel.make(c, 1))  # noqa: E731  (c as a kernel integer)
        namespace = {k: integer(c) for k, c in consts.items()} | {"gcd": kernel.gcd, "Q": kernel.make}
        exec(compile(self.source, f"<split step, n = {n}>", "exec"), namespace)
        #: solve(xi, d) → (s, L, z): the solution z (a tuple of the kernel's rationals)
        #: at the point x = xi/d, and z = s/L as kernel integers (L may be negative);
        #: raises ZeroDivisionError if the system is singular
        self.solve = namespace["solve"]


class _Emitter:
    """Straight-line code in fresh names.  Integer constants are named (``C12``,
    ``Cm3``) so that they can be bound to the kernel's integers (python-flint
    multiplies an fmpz by an fmpz about twice as fast as by an int); a value
    that is identically 0 is ``None`` and its terms are dropped; an expression
    already computed is not computed again."""

    def __init__(self):
        self.lines, self.consts, self.known = [], {}, {}

    def const(self, c):
        name = f"C{c}" if c > 0 else f"Cm{-c}"
        self.consts[name] = c
        return name

    def form(self, terms):
        """The expression Σ c·v over (c, v), v a name or None, or None if it is 0."""
        terms = sorted([(c, v) for c, v in terms if c and v is not None], key=lambda t: t[0] < 0)
        if not terms:
            return None
        c, v = terms[0]  # a positive term first: a leading minus would cost a negation
        out = v if c == 1 else ("-" + v if c == -1 else f"{self.const(c)} * {v}")
        for c, v in terms[1:]:
            out += (" - " if c < 0 else " + ") + (v if abs(c) == 1 else f"{self.const(abs(c))} * {v}")
        return out

    def let(self, expr, prefix="t"):
        """A name holding ``expr``: None for None, ``expr`` if it is a name, else a new
        name (or the one that already holds this expression)."""
        if expr is None or expr.isidentifier():
            return expr
        if expr not in self.known:
            self.known[expr] = name = f"{prefix}{len(self.known)}"
            self.lines.append(f"{name} = {expr}")
        return self.known[expr]


def _source(rows, n):
    """(source of ``solve((x_0, …, x_{2n−1}), D) → ((s_0, …), L, (s_0/L, …))``, its
    constants) for the split solve of :class:`SplitSystem` with these rows; see the
    module docstring.  The source's globals are the constants, ``gcd`` and ``Q``
    (the kernel's rationals)."""
    args = [f"x{i}" for i in range(2 * n)] + ["D"]
    out, k, factors, back = _Emitter(), 0, _factors(n), [[] for _ in range(2 * n)]
    # per factor, the characters χ_d(x_u), χ_d(x_v) and the entries' rows over them and D
    forms = []
    for d, deg, powers in factors:
        block, k = rows[k:k + 6 * deg], k + 6 * deg
        h = [out.let(out.form([(powers[i % d][c % deg] if i // n == c // deg else 0, x)
                               for i, x in enumerate(args[:-1])]), "h") for c in range(2 * deg)]
        forms.append([[(c, v) for c, v in zip(row, h + ["D"]) if c and v is not None] for row in block])
    # a scaled term c·v that occurs in more than one entry is computed once
    uses = {}
    for row in {tuple(row) for block in forms for row in block}:
        for c, v in row:
            uses[abs(c), v] = uses.get((abs(c), v), 0) + 1
    scaled = {key: out.let(f"{out.const(key[0])} * {key[1]}", "p")
              for key, m in uses.items() if m > 1 and key[0] > 1}
    dens, ys = [], []
    for (d, deg, powers), block in zip(factors, forms):
        e = [out.let(out.form([((c > 0) - (c < 0), scaled[abs(c), v]) if (abs(c), v) in scaled else (c, v)
                               for c, v in row]), "e") for row in block]
        a, b, c_, d_, r, s = (e[m * deg:(m + 1) * deg] for m in range(6))
        field = (d, deg, powers)
        # Cramer's rule over Z[θ], then numerators and det times det* = the product of
        # the other conjugates σ_k(det) (θ ↦ θ^k, k prime to d), so that den = N(det) ∈ Z
        m = _product(out, [(1, a, d_), (-1, b, c_)], field)
        u = _product(out, [(1, d_, r), (-1, b, s)], field)
        v = _product(out, [(1, a, s), (-1, c_, r)], field)
        y, den, conj = u + v, m[0], None  # y = χ_d(z): the u coefficients, then the v ones
        for unit in (k for k in range(2, d) if math.gcd(k, d) == 1):
            sk = [out.let(out.form([(powers[unit * c2 % d][c], w) for c2, w in enumerate(m)]), "k")
                  for c in range(deg)]
            conj = sk if conj is None else _product(out, [(1, conj, sk)], field)
        if conj is not None:  # N(det) is det·det*'s constant coefficient (the others are 0)
            den = _product(out, [(1, m, conj)], field, wanted=1)[0]
            y = _product(out, [(1, u, conj)], field) + _product(out, [(1, v, conj)], field)
        den = out.let(den or "0")  # 0: the system is singular at every point
        out.lines += [f"if not {den}:", "    raise ZeroDivisionError('singular Kahan system')"]
        # reduce this factor's solution y/den on its own (see the module docstring)
        g = den
        for t in y:
            if t is not None:
                g = out.let(f"gcd({g}, {t})", "g")
        dens.append(out.let(f"{den} // {g}", "den"))
        ys.append([out.let(f"{t} // {g}", "y") if t is not None else None for t in y])
        # the inverse transform: n·z_{blk·n + i} is the sum over the factors of
        # Tr(ζ^{−i} χ_d(z_blk)) = Σ_c y_c Tr(ζ^{c − i}), and Tr(ζ_d^m) is the
        # Ramanujan sum c_d(m)
        for blk in range(2):
            for i in range(n):
                back[blk * n + i] += [(ramanujan_sum(d, (c - i) % d), len(ys) - 1, blk * deg + c)
                                      for c in range(deg)]
    for j, y in enumerate(ys):  # bring every factor to the common denominator L
        others = out.let(" * ".join(dens[:j] + dens[j + 1:]) or None, "o")
        if others is not None:
            ys[j] = [out.let(f"{t} * {others}", "z") if t is not None else None for t in y]
    L = out.let(" * ".join(([out.const(n)] if n > 1 else []) + dens), "L")
    outs = [out.let(out.form([(tr, ys[j][c]) for tr, j, c in terms]) or "0", "s") for terms in back]
    point = ", ".join(f"Q({t}, {L})" for t in outs)
    return _text(args, out.lines + [f"return ({', '.join(outs)},), {L}, ({point},)"]), out.consts


def _text(args, lines):
    lines = [f"{', '.join(args[:-1])}, = xi"] + lines
    return "def solve(xi, D):\n" + "".join(f"    {line}\n" for line in lines)


def _product(out, terms, field, wanted=None):
    """Names (or None for 0) of the coefficients of Σ ± x·y in Z[θ] = Z[t]/Φ_d(t)
    (``terms``: (sign, x, y), x and y lists of names or None; ``field``: (d, deg,
    powers) of :func:`_factors`); only the first ``wanted`` coefficients if given."""
    d, deg, powers = field
    wanted = range(deg if wanted is None else wanted)
    tmp = []  # the coefficients of t^0 … t^{2deg−2} before reduction
    for m in range(2 * deg - 1):
        if not any(powers[m % d][c] for c in wanted):
            tmp.append(None)
            continue
        parts = [(sign, f"{x[i]} * {y[m - i]}") for sign, x, y in terms
                 for i in range(max(0, m - deg + 1), min(m, deg - 1) + 1)
                 if x[i] is not None and y[m - i] is not None]
        tmp.append(out.let(out.form(parts)))
    return [out.let(out.form([(powers[m % d][c], t) for m, t in enumerate(tmp)])) for c in wanted]


def _in_characters(rows, n, pos):
    """Rows (lists over [x, D]) of one factor as rows over the coefficients of
    χ_d(x_u), χ_d(x_v) and D, or None if one is not such a form (``pos``: the deg × n
    matrix of the coordinates (θ^i)_c).  With circulant blocks every one is: the Hessian
    is then cyclic Hankel in each block (as for Lie–Poisson fields, docs/conventions.md),
    and the generated step computes those few sums once."""
    import flint

    # χ_d(x_blk) = Σ_i ζ^i x_{blk·n + i} with ζ^c = θ^c for c < deg: α_c is the x_c entry,
    # and the x_i entry must be Σ_c α_c·(θ^i)_c
    deg, alpha = pos.nrows(), []
    for blk in range(2):
        A = flint.fmpz_mat([[r[blk * n + c] for c in range(deg)] for r in rows])
        if A * pos != flint.fmpz_mat([r[blk * n:(blk + 1) * n] for r in rows]):
            return None
        alpha.append(A.tolist())
    return [[int(t) for t in a + b + [r[-1]]] for a, b, r in zip(*alpha, rows)]


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
    n = field.dim // 2
    st = field.circulant_structure()
    if st is not None:
        first, R = structure_rows(st, p, q)
        row = lambda i, j: first[i // n][j // n][j % n]  # noqa: E731  (i the first row of its block)
    else:  # undeclared: the field's whole integer system, checked circulant block by block
        V, R = field.integer_rows(p, q)
        row = lambda i, j: V[i * 2 * n + j]  # noqa: E731  (the row of entry (i, j) of M)
        if any(row(bi * n + i, bj * n + j) != row(bi * n, bj * n + (j - i) % n)
               for bi in range(2) for bj in range(2) for i in range(n) for j in range(n)):
            return None
    import flint

    # the first rows c_m of the four blocks and the right-hand side's rows, over [x, D]
    F = [flint.fmpz_mat([row(bi * n, bj * n + m) for m in range(n)]) for bi in range(2) for bj in range(2)]
    F += [flint.fmpz_mat(R[bi * n:(bi + 1) * n]) for bi in range(2)]
    rows = []
    for d, deg, powers in _factors(n):
        # entries c_{bi,bj}(ζ^{−1}) = Σ_m c_m ζ^{−m}, right-hand side χ_d(r) = Σ_i ζ^i r_i
        neg = flint.fmpz_mat([[powers[-m % d][c] for m in range(n)] for c in range(deg)])
        pos = flint.fmpz_mat([[powers[i % d][c] for i in range(n)] for c in range(deg)])
        block = _in_characters([r for k, B in enumerate(F) for r in ((neg if k < 4 else pos) * B).tolist()], n, pos)
        if block is None:
            return None
        rows += block
    # per factor, in _factors order: a, b, c, d, r, s (each as deg coefficients over χ_d(x), D)
    return SplitSystem(kernel, rows, n)
