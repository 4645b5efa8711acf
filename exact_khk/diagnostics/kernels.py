"""Modular kernels of monomial evaluation matrices along Kahan orbits, and their lift to Q.

The building blocks of :mod:`.integrals`: candidate monomials, their evaluation
along an orbit over F_p, the canonical kernel basis (from the reduced echelon
form of the evaluation matrix), trivial (product) kernel vectors, and Chinese
remaindering with rational reconstruction.

>>> monomials(2, 2)
[(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)]
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass
from fractions import Fraction

import flint

from exact_khk.errors import InputError
from exact_khk.parsing import _short, any_int_digits


# --- candidate monomials --------------------------------------------------------------


def monomials(dim: int, degree: int, homogeneous: bool = False) -> list:
    """Exponent tuples of the monomials in ``dim`` variables of degree ≤ ``degree``
    (exactly ``degree`` if homogeneous), by degree then lexicographically.

    >>> monomials(2, 2)
    [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)]
    """
    out = []
    for d in range(degree if homogeneous else 0, degree + 1):
        out += sorted(_of_degree(dim, d), reverse=True)
    return out


def _of_degree(dim, d):
    if dim == 1:
        return [(d,)]
    return [(i,) + rest for i in range(d + 1) for rest in _of_degree(dim - 1, d - i)]


#: the highest degree of a listed candidate monomial (the bound of ``degree``)
MAX_MONOMIAL_DEGREE = 40


def parse_monomials(spec, variables) -> list:
    """Exponent tuples from a list of monomials such as ``["1", "x*y", "z^2", "x**2*y"]``
    (or exponent tuples), in the given variables.

    >>> parse_monomials(["1", "x*y", "y^2"], ["x", "y"])
    [(0, 0), (1, 1), (0, 2)]
    """
    if isinstance(spec, (str, bytes, dict)) or not hasattr(spec, "__iter__"):
        raise InputError(f"monomials: expected a list of monomials such as ['1', 'x*y'], got {_short(spec)}")
    N = len(variables)
    index = {v: i for i, v in enumerate(variables)}
    out = []
    for item in spec:
        if isinstance(item, (tuple, list)):
            if len(item) != N or any(not isinstance(e, int) or isinstance(e, bool) or e < 0 for e in item):
                raise InputError(f"monomials: {_short(item)} is not a tuple of {N} nonnegative exponents")
            exps = list(item)
        else:
            exps = _exponents(item, index, variables)
        out.append(tuple(exps))
        if sum(exps) > MAX_MONOMIAL_DEGREE:
            raise InputError(f"monomials: {_short(item)} has degree {sum(exps)}, beyond the limit of "
                             f"{MAX_MONOMIAL_DEGREE} (MAX_MONOMIAL_DEGREE, as for --degree)")
    if len(set(out)) != len(out):
        raise InputError("monomials: the list repeats a monomial")
    if not out:
        raise InputError("monomials: the list is empty")
    return out


def _exponents(item, index, variables) -> list:
    """The exponents of one monomial's text such as 'x*y^2' or 'x**2*y'."""
    exps = [0] * len(variables)
    text = str(item).replace(" ", "").replace("**", "^")
    if text != "1":
        for factor in text.split("*"):
            name, _, power = factor.partition("^")
            if name not in index or (power and not (power.isascii() and power.isdigit())) or len(power) > 6:
                raise InputError(f"monomials: cannot read {_short(item)} (variables: {', '.join(variables)})")
            exps[index[name]] += int(power or 1)
    return exps


def monomial_text(e, variables) -> str:
    """A monomial in system-file syntax (``**``), which :func:`parse_monomials` reads back.

    >>> monomial_text((2, 1), ["x", "y"])
    'x**2*y'
    """
    parts = [v if k == 1 else f"{v}**{k}" for v, k in zip(variables, e) if k]
    return "*".join(parts) or "1"


def poly_text(poly: dict, variables) -> str:
    """A polynomial {exponents: coefficient} as text, by degree.

    >>> from fractions import Fraction as F
    >>> poly_text({(0, 0): F(1), (2, 0): F(-1, 2), (1, 1): F(3)}, ["x", "y"])
    '1 - 1/2*x**2 + 3*x*y'
    """
    parts = []
    for e in sorted(poly, key=lambda e: (sum(e), [-k for k in e])):
        c = poly[e]
        if c == 0:
            continue
        mono = monomial_text(e, variables)
        mag = abs(c)
        with any_int_digits():  # coefficients of any size (e.g. at an eps of 5000 digits)
            body = str(mag) if mono == "1" else mono if mag == 1 else f"{mag}*{mono}"
        parts.append((" - " if c < 0 else " + ") + body)
    if not parts:
        return "0"
    text = "".join(parts)
    return ("-" + text[3:]) if text.startswith(" - ") else text[3:]


class _Evaluator:
    """Values of the monomials ``exps`` at a point, each as an earlier one times a variable or, where
    the set lacks every such parent, times a product of two variables (the sign-invariant sets of
    :mod:`.hkbases` hold e − x_j x_k, not e − x_j); otherwise as a product of powers."""

    def __init__(self, exps):
        N = len(exps[0]) if exps else 0
        pos = {e: i for i, e in enumerate(exps)}
        self.pairs, used = [], {}   # the products x_j x_k needed, and their index among the factors
        self.plan = []
        for i, e in enumerate(exps):
            divisors = itertools.chain(((j,) for j in range(N) if e[j]),  # generated as far as needed
                                       ((j, k) for j in range(N) for k in range(j, N) if e[j] and e[k] > (j == k)))
            for q in divisors:
                f = tuple(a - q.count(j) for j, a in enumerate(e))
                if pos.get(f, i) < i:
                    if len(q) == 2 and q not in used:
                        used[q] = N + len(self.pairs)
                        self.pairs.append(q)
                    self.plan.append((pos[f], q[0] if len(q) == 1 else used[q], e))
                    break
            else:
                self.plan.append((None, None, e))

    def __call__(self, x, one, mod=None):
        factors = list(x) + [x[j] * x[k] for j, k in self.pairs]
        vals = []
        for parent, j, e in self.plan:
            if parent is not None:
                v = vals[parent] * factors[j]
            else:
                v = one
                for xi, k in zip(x, e):
                    if k:
                        v = v * xi ** k
            vals.append(v % mod if mod else v)
        return vals


@functools.lru_cache(maxsize=32)
def evaluator(exps: tuple) -> _Evaluator:
    """The :class:`_Evaluator` of ``exps``, planned once for the many orbits a search evaluates them on
    (a fit's pool: the Lagrange top's search planned 13 544 of them, 10 of its 120 s)."""
    return _Evaluator(exps)


# --- modular kernels ------------------------------------------------------------------


def _point(rng, dim, bound=9):
    return tuple(Fraction(rng.choice([i for i in range(-bound, bound + 1) if i]), rng.randint(1, 4))
                 for _ in range(dim))


def _orbit_mod(fld, eps, x0, steps, p):
    from exact_khk.kahan.map import KahanMap
    phi = KahanMap(fld, eps, f"gf:{p}")
    return [[int(t) for t in pt] for pt in phi.orbit(x0, steps)]


def orbit_mod_or_none(fld, eps, x0, steps, p):
    """:func:`_orbit_mod`, or None where the orbit meets a singular step mod p."""
    from exact_khk.errors import SingularStepError
    try:
        return _orbit_mod(fld, eps, x0, steps, p)
    except (SingularStepError, ZeroDivisionError, InputError):
        return None


@dataclass
class _OrbitKernel:
    x0: tuple
    basis: list          # canonical kernel basis rows (ints mod p)
    dim: int
    stable: bool
    periodic: bool


#: bytes per entry of the evaluation matrix of one orbit kernel (:func:`kernel_bytes`): the ``nmod_mat``
#: and its reduced echelon copy, 8 each, and FLINT's working space: peak RSS growth 2 349 MB for
#: 20 variables at degree <= 4 (10 626 candidates × 11 689 + 1 062 points), 19.8 bytes per entry
MATRIX_BYTES_PER_ENTRY = 20
#: bytes per entry of a kernel basis held as lists (a Python int below 2^62 and its list slot, 44, and
#: the list of all entries an ``nmod_mat`` is built from, 8); the basis and its N multiples x_j·v
#: (:func:`trivial_dim`, :func:`by_degree`) are held at once
BASIS_BYTES_PER_ENTRY = 52
#: rows of the evaluation matrix filled between two progress reports, for matrices of more than
#: PROGRESS_ENTRIES entries (about 1 s of filling on the shared 2-core machine)
PROGRESS_ROWS = 1000
PROGRESS_ENTRIES = 10 ** 6


class KernelTooLarge(InputError):
    """The kernel basis of an orbit would need more memory than allowed (found after the echelon form)."""


def kernel_bytes(m, points, margin) -> int:
    """The planned memory of one orbit kernel of ``m`` candidates over ``points`` orbit points
    (:func:`orbit_kernel_mod`): the evaluation matrix of all but the last ``margin`` points and its
    echelon form, MATRIX_BYTES_PER_ENTRY each entry, and the last ``margin`` rows."""
    return MATRIX_BYTES_PER_ENTRY * max(points - margin, 1) * m + 8 * min(margin, points) * m


def evaluation_matrix(exps, pts, p, progress=None):
    """The ``nmod_mat`` of the monomials ``exps`` at the points ``pts`` (ints mod p), filled row by row:
    no list of all its entries is held (a Python int costs 44 bytes, the matrix entry 8)."""
    m = len(exps)
    A = flint.nmod_mat(len(pts), m, p)
    ev = evaluator(tuple(exps))
    for i, q in enumerate(pts):
        for j, v in enumerate(ev(q, 1, p)):
            if v:
                A[i, j] = v
        if progress and i % PROGRESS_ROWS == PROGRESS_ROWS - 1:
            progress(f"evaluation rows {i + 1}/{len(pts)}")
    return A


def orbit_kernel_mod(fld, eps, x0, exps, steps, p, margin, progress=None, max_bytes=None) -> _OrbitKernel:
    """The kernel K(x0) over F_p (canonical basis from the reduced echelon form of the
    evaluation matrix) and whether its rank had stabilised: the rank of the first points
    (all but the last ``margin``) is that of the whole orbit exactly when the last ``margin``
    rows annihilate the kernel of the first ones, and then the two kernels are equal; so one
    echelon form (of the first points) and one product decide both.  ``progress(text)`` hears
    of the stages of a long kernel; with ``max_bytes``, a kernel basis beyond it raises
    :class:`KernelTooLarge` before it is written out."""
    say = progress or (lambda text: None)
    pts = _orbit_mod(fld, eps, x0, steps, p)
    periodic = len({tuple(q) for q in pts}) < len(pts)
    m = len(exps)
    head = len(pts) - margin
    if head < 1:  # too short to tell: the kernel of all points, not stable
        pivots, _free, basis = _kernel_of(evaluation_matrix(exps, pts, p), m, p, max_bytes, len(x0) + 1)
        return _OrbitKernel(tuple(x0), basis, m - len(pivots), False, periodic)
    A = evaluation_matrix(exps, pts[:head], p, say if m * head > PROGRESS_ENTRIES else None)
    if m * head > PROGRESS_ENTRIES:
        say(f"echelon form {head} x {m} mod p")
    pivots, _free, basis = _kernel_of(A, m, p, max_bytes, len(x0) + 1)
    del A
    stable = True
    if basis:
        V = flint.nmod_mat(m, len(basis), [v[c] for c in range(m) for v in basis], p)
        stable = not any(int(t) for t in (evaluation_matrix(exps, pts[head:], p) * V).entries())
    if not stable:  # the orbit is set aside as too short; its kernel is that of all points
        pivots, _free, basis = _kernel_of(evaluation_matrix(exps, pts, p), m, p, max_bytes, len(x0) + 1)
    return _OrbitKernel(tuple(x0), basis, m - len(pivots), stable, periodic)


def _kernel_of(A, m, p, max_bytes=None, copies=1):
    """(pivots, free, canonical basis) of the nullspace of the ``nmod_mat`` A (:func:`canonical_nullspace`);
    ``copies`` bases of its size are planned against ``max_bytes``."""
    R, rank = A.rref()
    pivots = _rref_pivots(R, rank, m)
    need = BASIS_BYTES_PER_ENTRY * (m - rank) * m * copies
    if max_bytes is not None and need > max_bytes:
        raise KernelTooLarge(f"degree: the orbit kernel has dimension {m - rank} over {m} candidates: its basis "
                             f"and its multiples need about {_size(need)}, beyond the memory limit "
                             f"of {_size(max_bytes)} (EXACT_KHK_MAX_MEMORY)")
    return _canonical(R, pivots, m, p)


def _size(b) -> str:
    return f"{b / 2 ** 30:.3g} GiB" if b >= 2 ** 30 else f"{b / 2 ** 20:.3g} MiB"


def _canonical(R, pivots, m, p):
    """(pivots, free, v_f = e_f − Σ_i R[i, f] e_{pivot_i}) from the reduced echelon form R."""
    piv = set(pivots)
    free = [c for c in range(m) if c not in piv]
    basis = []
    for f in free:
        v = [0] * m
        v[f] = 1
        for i, c in enumerate(pivots):
            v[c] = (-int(R[i, f])) % p
        basis.append(v)
    return pivots, free, basis


def _rref_pivots(R, rank, m):
    pivots, row = [], 0
    for c in range(m):
        if row < rank and int(R[row, c]) != 0:
            pivots.append(c)
            row += 1
    return pivots


def canonical_nullspace(rows, m, p):
    """(pivots, free, canonical basis vectors) of the nullspace of ``rows`` (ints mod p, m columns):
    v_f = e_f − Σ_i R[i, f] e_{pivot_i} from the reduced echelon form R."""
    R, rank = flint.nmod_mat(len(rows), m, [v for r in rows for v in r], p).rref()
    return _canonical(R, _rref_pivots(R, rank, m), m, p)


def orbit_kernel_exact(fld, eps, x0, exps, steps) -> list:
    """The canonical kernel basis of K(x0) over Q, from the exact orbit (python-flint
    ``fmpq_mat``; for cross-checks of the modular route on small cases)."""
    from exact_khk.kahan.map import KahanMap
    pts = KahanMap(fld, eps, "flint").orbit(x0, steps)
    ev = _Evaluator(exps)
    m = len(exps)
    R, rank = flint.fmpq_mat(len(pts), m, [v for q in pts for v in ev(q, flint.fmpq(1))]).rref()
    pivots = [next(j for j in range(m) if R[i, j] != 0) for i in range(rank)]
    basis = []
    for f in (c for c in range(m) if c not in set(pivots)):
        v = [Fraction(0)] * m
        v[f] = Fraction(1)
        for i, c in enumerate(pivots):
            v[c] = -Fraction(int(R[i, f].p), int(R[i, f].q))
        basis.append(v)
    return basis


def _rref_rows(rows, m, p):
    """(reduced echelon basis rows, rank) of the span of ``rows`` over F_p."""
    if not rows:
        return [], 0
    R, rank = flint.nmod_mat(len(rows), m, [v for r in rows for v in r], p).rref()
    return [[int(R[i, j]) for j in range(m)] for i in range(rank)], rank


def _restricted(basis, keep, p, combine=None):
    """Basis vectors of K ∩ span(columns ``keep``) over F_p: the combinations
    Σ_r X[r, k]·basis[r] for the nullspace X of the basis on the other columns
    (``combine(X, nul, basis, p)`` forms them; default one ``nmod_mat`` product)."""
    d, m = len(basis), len(basis[0]) if basis else 0
    outside = [c for c in range(m) if c not in keep]
    if not d:
        return []
    if not outside:
        return [list(v) for v in basis]
    X, nul = flint.nmod_mat(len(outside), d, [basis[r][c] for c in outside for r in range(d)], p).nullspace()
    return (combine or _combine)(X, nul, basis, p) if nul else []


def _combine(X, nul, basis, p):
    """The rows Σ_r X[r, k]·basis[r], k < nul, as one product over F_p (nul × d times d × m)."""
    d, m = len(basis), len(basis[0])
    Y = flint.nmod_mat(nul, d, [X[r, k] for k in range(nul) for r in range(d)], p) \
        * flint.nmod_mat(d, m, [t for v in basis for t in v], p)
    flat = [int(t) for t in Y.entries()]
    return [flat[k * m:(k + 1) * m] for k in range(nul)]


def _multiples(vectors, exps, p):
    """The vectors x_j·v (j = 0..N-1) of those v whose multiple stays in the span."""
    pos = {e: i for i, e in enumerate(exps)}
    out = []
    for j in range(len(exps[0])):
        shift = lambda e: e[:j] + (e[j] + 1,) + e[j + 1:]  # noqa: E731
        keep = {i for i, e in enumerate(exps) if shift(e) in pos}
        for v in _restricted(vectors, keep, p):
            w = [0] * len(exps)
            for i in keep:
                w[pos[shift(exps[i])]] = v[i]
            out.append(w)
    return out


def trivial_dim(basis, exps, p) -> int:
    """dim T, T = Σ_j x_j·(K ∩ span S_j) ⊂ K (module docstring), over F_p."""
    return _rref_rows(_multiples(basis, exps, p), len(exps), p)[1] if basis else 0


def by_degree(basis, exps, p) -> tuple:
    """((D, dim K_D, new_D), ...): K_D = K ∩ span(degree ≤ D), new_D = dim K_D −
    dim(K_{D-1} + Σ_j x_j K_{D-1}) (the directions not coming from lower degrees)."""
    top = max(sum(e) for e in exps)
    out, prev = [], []
    for D in range(1, top + 1):
        KD = _restricted(basis, {i for i, e in enumerate(exps) if sum(e) <= D}, p)
        old = _rref_rows(prev + _multiples(prev, exps, p), len(exps), p)[1] if prev else 0
        out.append((D, len(KD), len(KD) - old))
        prev = KD
    return tuple(out)


# --- lifting to Q ---------------------------------------------------------------------


def rational_reconstruction(a: int, m: int):
    """p/q ≡ a (mod m) with |p|, q ≤ sqrt(m/2), or None (Wang's algorithm).

    >>> rational_reconstruction(Fraction(3, 7).numerator * pow(7, -1, 1009) % 1009, 1009)
    Fraction(3, 7)
    """
    bound = math.isqrt(m // 2)  # exact: a float square root overflows beyond 2^1024 and rounds below
    r0, r1, s0, s1 = m, a % m, 0, 1
    while r1 > bound:
        q = r0 // r1
        r0, r1, s0, s1 = r1, r0 - q * r1, s1, s0 - q * s1
    if s1 == 0 or abs(s1) > bound:
        return None
    return Fraction(r1, s1)


def lift(rows_by_prime):
    """Rational rows from the same echelon basis mod several primes, or None when
    the reconstruction is not yet confirmed by a prime it was not computed from."""
    primes = [p for p, _ in rows_by_prime]
    if len(primes) < 2:
        return None
    *head, (plast, rlast) = rows_by_prime
    M, vals = 1, None
    for p, rows in head:
        flat = [v for r in rows for v in r]
        if vals is None:
            vals = list(flat)
        else:  # CRT
            inv = pow(M, -1, p)
            vals = [v + M * (((x - v) * inv) % p) for v, x in zip(vals, flat)]
        M *= p
    out = []
    for v in vals:
        q = rational_reconstruction(v, M)
        if q is None:
            return None
        out.append(q)
    check = [v for r in rlast for v in r]
    if any(q.denominator % plast == 0 or (q.numerator * pow(q.denominator, -1, plast) - x) % plast
           for q, x in zip(out, check)):
        return None
    if not rlast:  # a kernel of dimension 0
        return []
    m = len(rlast[0])
    return [out[i * m:(i + 1) * m] for i in range(len(rlast))]


def to_mpoly(poly: dict, dim: int):
    """A dict polynomial as a python-flint ``fmpq_mpoly`` in x0..x(dim-1)."""
    ctx = flint.fmpq_mpoly_ctx.get(tuple(f"x{i}" for i in range(dim)), "degrevlex")
    return ctx.from_dict({e: flint.fmpq(c.numerator, c.denominator) for e, c in poly.items()})


def independent_count(pairs, rng) -> int:
    """Rank of the Jacobian of the functions num/den (dict polynomials) at a random
    small rational point, exactly: the number of functionally independent ones
    (a lower bound, equal with high probability)."""
    if not pairs:
        return 0
    N = len(next(iter(pairs[0][0] or pairs[0][1])))
    for _ in range(5):
        x = [flint.fmpq(rng.randint(-30, 30), rng.randint(1, 7)) for _ in range(N)]
        rows = jacobian_rows(pairs, x)
        if rows is not None:
            return flint.fmpq_mat(len(rows), N, [v for r in rows for v in r]).rank()
    return 0


def jacobian_rows(pairs, x):
    """The gradients of the functions num/den at the rational point ``x`` (flint rationals; rows
    scaled by den(x)², which leaves the rank alone), or None where a denominator vanishes."""
    N = len(x)
    rows = []
    for num, den in pairs:
        n, d = to_mpoly(num, N), to_mpoly(den, N)
        n0, d0 = n(*x), d(*x)
        if d0 == 0:
            return None
        rows.append([d0 * n.derivative(j)(*x) - n0 * d.derivative(j)(*x) for j in range(N)])
    return rows
