"""Exact Kahan steps and H̃ by the DFT, in an arithmetic that holds the n-th roots of unity.

Over a field K with a primitive n-th root of unity ω (``cyclo:N`` with n | N: ω = ζ_N^(N/n);
``gf:P`` with n | P − 1),
tⁿ − 1 = Π_j (t − ωʲ) splits, so the ring R = K[t]/(tⁿ − 1) of the circulant blocks of
I − εf'(x) (:mod:`exact_khk.systems.lie_poisson.circulant`) is Kⁿ by evaluation at the ωʲ — exactly,
not only over C.  A Kahan step is then n independent 2×2 systems over K (the frequencies),
between one exact DFT of the point and one inverse DFT of the answer; the floating step
(:func:`~exact_khk.systems.lie_poisson.circulant.numeric_step`) is the same computation in balls.  This is
what makes the associated fields of the non-rational involutions (Hessians over Q(ω),
``liouville``) cheap: the dense alternative is a 2n·φ(N)-dimensional rational system (in
F_P, f'(x) entry by entry and a 2n×2n solve).

The step is undefined exactly when a frequency's determinant is 0 (det(I − εf'(x)) is the
product of the n determinants): :class:`~exact_khk.linalg.dense.SingularMatrix`.

>>> from exact_khk import LiePoissonSystem, get_arith
>>> s = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")
>>> g = s.field("g", "+-+", cyclotomic=True)
>>> ar = get_arith("cyclo:3")
>>> st = g.circulant_structure(cyclotomic=True)
>>> x = [ar(t) for t in (1, 0, 0, 0, 1, 0)]
>>> z = exact_step(st, x, ar("1/10"), ar)
>>> from exact_khk.linalg.dense import solve
>>> M = g.step_matrix(ar, x, ar("1/10"))
>>> z == tuple(row[0] for row in solve(ar, M, [[t] for t in x])[0])
True
"""

from __future__ import annotations

from exact_khk.systems.lie_poisson.circulant import _mul, cramer, htilde_system, kahan_system, reflect
from exact_khk.linalg.dense import SingularMatrix
from exact_khk.systems.lie_poisson.paths import exact_dft_fits


def applies(ar, n: int) -> bool:
    """Whether ``ar`` holds the n-th roots of unity and their exact DFT, within the memory
    bounds of :func:`~exact_khk.systems.lie_poisson.paths.exact_dft_fits`."""
    return ar.dft is not None and ar.roots_of_unity % n == 0 and exact_dft_fits(ar, n)


def why_not(ar, n: int):
    """Why an arithmetic with an exact DFT (``ar.dft``) cannot take it at this n, or None."""
    if ar.roots_of_unity % n:
        return (f"needs the {n}-th roots of unity, which {ar.name} does not hold "
                f"({n} does not divide {ar.roots_of_unity})")
    if not exact_dft_fits(ar, n):
        return (f"in {ar.name} at n = {n} would need an exact DFT on n·φ = "
                f"{n * (getattr(ar, 'coefficient_degree', None) or 1)} coefficients, beyond the memory "
                f"bounds of exact_khk/systems/lie_poisson/paths.py (use a smaller N)")
    return None


def _hankel_values(st, ar, reflected):
    """The four Hankel polynomials m_kl of ``st`` (reflected: m̂_kl) at the n powers of ω,
    cached on the structure (a field's own: ``liouville`` steps 2ⁿ maps in turn)."""
    cache = st.__dict__.get("_dft_values")
    if cache is None:
        cache = {}
        object.__setattr__(st, "_dft_values", cache)
    key = (ar.name, reflected)
    if key not in cache:
        rows = [reflect(list(w)) if reflected else list(w) for row in st.m for w in row]
        cache[key] = ar.dft(rows, st.n)
    return cache[key]


def _frequencies(ar, m, system, u, v, eps, scale=1):
    """The answers z_j/scale of the 2×2 systems ``system`` (:func:`kahan_system` or
    :func:`htilde_system`) at every frequency j, from the Hankel values m and the values
    u, v of the point, by Cramer's rule; SingularMatrix when a determinant is 0."""
    def divide(det, rhs):
        if ar.is_zero(det):
            raise SingularMatrix("a frequency's 2x2 determinant is 0")
        inv = ar.one / (det * scale)
        return tuple(inv * t for t in rhs)

    out = []
    for j in range(len(u)):
        a, r = system(((m[0][j], m[1][j]), (m[2][j], m[3][j])), u[j], v[j], eps, _mul, ar.one)
        out.append(cramer(a, r, _mul, divide))
    return out


def exact_step(st, x, eps, ar):
    """Φ_f(x, ε) = (I − εf'(x))⁻¹x in ``ar`` (exact, with the n-th roots of unity).

    As :func:`~exact_khk.systems.lie_poisson.circulant.exact_step`: û, v̂ the reflected halves of x,
    at each frequency the 2×2 system of :func:`~exact_khk.systems.lie_poisson.circulant.kahan_system`,
    and the answer's reflected halves from the inverse DFT (its 1/n folded into the
    frequencies' divisions)."""
    n = st.n
    uh, vh = ar.dft([reflect(list(x[:n])), reflect(list(x[n:]))], n)
    z = _frequencies(ar, _hankel_values(st, ar, False), kahan_system, uh, vh, eps, scale=n)
    zu, zv = ar.dft([[t[0] for t in z], [t[1] for t in z]], n, -1)
    return tuple(reflect(zu) + reflect(zv))


def exact_htilde(st, x, eps, ar):
    """H̃(x, ε) = xᵀ(I − ε²(M J(x))²)⁻¹ M x in ``ar`` (exact, with the n-th roots of unity).

    As :func:`~exact_khk.systems.lie_poisson.circulant.exact_htilde` (reflected Hankel polynomials,
    the plain halves u, v); xᵀz is the constant coefficient of u ẑ_u + v ẑ_v, the mean
    over the frequencies of the products of their values."""
    n = st.n
    u, v = ar.dft([list(x[:n]), list(x[n:])], n)
    z = _frequencies(ar, _hankel_values(st, ar, True), htilde_system, u, v, eps)
    total = ar.zero
    for j in range(n):
        total = total + u[j] * z[j][0] + v[j] * z[j][1]
    return total / ar.convert(n)
