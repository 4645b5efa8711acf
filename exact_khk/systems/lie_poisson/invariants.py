"""Integrals of the Kahan maps of the Lie–Poisson family (docs/conventions.md, "The integrals H̃ and K̃", (tH 4)).

For a Lie–Poisson field f(x) = J(x) M x (M = Hs for f, B Hs for an associated
field g):

    H̃_M(x, ε) = xᵀ (I − ε² (M J(x))²)^{-1} M x

(= 2 H_M(x) + O(ε²), even in ε).  K̃ is the same with M = B Hs.

>>> from exact_khk import LiePoissonSystem, get_arith
>>> from exact_khk.systems.lie_poisson import default_system, DEFAULT_X0
>>> s = default_system(); ar = get_arith("fraction")
>>> x = [ar(t) for t in (1, 0, 0, 0, 1, 0)]
>>> Htilde(s.field("f"), x, "1/10", ar)
Fraction(229600, 64011)
"""

from __future__ import annotations

import math
import warnings

from exact_khk.systems.lie_poisson import circulant, circulant_dft
from exact_khk.arith import get_arith, as_point, to_element
from exact_khk.errors import InputError, NearSingularWarning, NumericalError, PoleError
from exact_khk.linalg.dense import SingularMatrix, matmul, matvec, solve, transpose


def _eps(ar, eps):
    """ε as an element of ``ar``, read as the Kahan map reads it
    (:func:`exact_khk.arith.to_element`: ``'1/10'``, int, Fraction, backend
    rationals, elements of ``ar`` or of its base for a dual context; binary
    floats only in floating arithmetics); ε = 0 is refused."""
    e = to_element(ar, eps, "eps")
    if ar.is_zero(e) is True:
        raise InputError("eps: the step size must be nonzero")
    return e


def _point(ar, x, dim, name="x"):
    """A point as a list of elements of ``ar``, read as the Kahan map reads it
    (:func:`exact_khk.arith.as_point`)."""
    return list(as_point(ar, x, dim, name))


def _floating(ar) -> bool:
    """``float`` and ``mp:P`` (not balls, which carry their own error bounds, nor duals)."""
    return not ar.exact and getattr(ar, "fourier", False)


def hessian_in(ar, field):
    """The field's constant matrix M converted into ``ar`` (cached on the field)."""
    key = ("hessian", ar.name)
    hit = field._cache.get(key)
    if hit is None:
        hit = [[ar.convert(t) for t in row] for row in field.hessian]
        field._cache[key] = hit
    return hit


def Htilde(field, x, eps, arith=None, method="auto"):
    """H̃(x, ε) = xᵀ (I − ε²(M J(x))²)^{-1} M x for a :class:`LiePoissonField`.

    Raises :class:`~exact_khk.errors.PoleError` where I − ε²(M J(x))² is
    singular (there the integral has a pole).

    Exact rational arithmetics with python-flint solve the 2n×2n system as a
    2×2 system over circulants (:func:`exact_khk.systems.lie_poisson.circulant.exact_htilde`) when
    the Hessian blocks are cyclic Hankel (measured at orbit points, docs/benchmarks.md:
    n = 3, 8, 16 about 10×, 164×, 567× faster than the dense solve; as whole commands
    see the rule table of :mod:`~exact_khk.systems.lie_poisson.paths`); the result is
    the same rational number.  In ``cyclo:N`` with n | N and ``gf:P`` with n | P − 1 (fields over Q(ω)
    included) it is n 2×2 systems over Q(ζ_N) or F_P by the exact DFT
    (:func:`exact_khk.systems.lie_poisson.circulant_dft.exact_htilde`).
    ``method='dense'`` forces the 2n×2n solve.
    """
    ar = get_arith(arith)
    if not hasattr(field, "system") or field.system is None:
        raise InputError("field: H̃ is defined for Lie–Poisson fields f(x) = J(x) M x")
    if method not in ("auto", "dense"):
        raise InputError(f"method: expected 'auto' or 'dense', got {method!r}")
    e = _eps(ar, eps)
    x = _point(ar, x, field.dim)
    n, st = field.system.n, None
    if method == "auto" and ar.exact and circulant_dft.applies(ar, n):
        st, structured = field.circulant_structure(cyclotomic=True), circulant_dft.exact_htilde
    elif method == "auto" and ar.rational and circulant.flint is not None:
        st, structured = circulant.circulant_structure(field), circulant.exact_htilde
    if st is not None:
        try:
            return structured(st, x, e, ar)
        except SingularMatrix:
            raise _pole(ar, x, e) from None
    with ar.local():  # e.g. the working precision of ball:P
        return _htilde(ar, field, x, e)


def _pole(ar, x, e):
    if not ar.exact:
        return NumericalError(f"H~ cannot be evaluated in {ar.name} at x = ({_fmt_point(ar, x)}), "
                              f"eps = {ar.format(e)}: a pivot of I - eps^2 (M J(x))^2 is exactly 0 in "
                              f"floating point (not a proven pole; use more bits or an exact arithmetic)",
                              math.inf)
    return PoleError("H~ has a pole at x = (" + ", ".join(ar.format(t) for t in x)
                     + f"), eps = {ar.format(e)}: I - eps^2 (M J(x))^2 is singular")


def _fmt_point(ar, x, width=200):
    text = ", ".join(ar.format(t) for t in x)
    return text if len(text) <= width else text[:width] + "..."


def floating_policy(ar, cond, values, what, x, e):
    """The conditioning policy of floating steps (:mod:`exact_khk.kahan.map`) for a
    floating evaluation of ``what`` (H~, its gradient): raise
    :class:`~exact_khk.errors.NumericalError` when a value is not finite
    (overflow) or κ·2^-p ≥ 1 (κ the 1-norm condition estimate of the solved
    matrix: no correct bit can be guaranteed); warn with
    :class:`~exact_khk.errors.NearSingularWarning` when κ ≥ 2^(p/2)."""
    if any(not ar.is_finite(t) for t in values):
        raise NumericalError(f"{what} overflows {ar.name} at x = ({_fmt_point(ar, x)}), eps = {ar.format(e)}: "
                             f"a value is beyond the range of the arithmetic (use mp:P or an exact "
                             f"arithmetic)", math.inf)
    if cond is None:
        return
    lost = math.inf if cond != cond or math.isinf(cond) else (math.log2(cond) if cond > 0 else 0.0)
    if lost >= ar.prec:
        raise NumericalError(f"{what} cannot be evaluated in {ar.name} at x = ({_fmt_point(ar, x)}), "
                             f"eps = {ar.format(e)}: I - eps^2 (M J(x))^2 is numerically singular "
                             f"(condition estimate {cond:.3g} >= 2^{ar.prec}, no bit can be trusted; not a "
                             f"proven pole: use more bits or an exact arithmetic)", cond)
    if lost >= ar.prec / 2:
        warnings.warn(NearSingularWarning(
            f"{what} at eps = {ar.format(e)} is ill-conditioned: condition estimate {cond:.3g} of "
            f"I - eps^2 (M J(x))^2 in {ar.name} (about {lost:.0f} of {ar.prec} bits at risk)", cond),
            stacklevel=3)


def _ldexp(ar, t, k):
    """t·2^k in a binary floating arithmetic (exact unless it leaves the range)."""
    if hasattr(ar, "ctx"):
        return ar.ctx.ldexp(t, k)
    try:
        return math.ldexp(t, k)
    except OverflowError:
        return math.copysign(math.inf, t)


def _htilde_floating(ar, field, x, e):
    """H̃ in ``float``/``mp:P``, scaled so that nothing overflows, with the floating
    conditioning policy (:func:`floating_policy`).

    H̃ is homogeneous: J is linear, so H̃(λy, ε) = λ² H̃(y, λε).  With λ = 2^k
    (exact) and y = x/λ of magnitude about 1, ε' = λε, S = M J(y):

    * |ε'| ≤ 1:  H̃(x, ε) = λ² yᵀ (I − ε'² S²)^{-1} M y;
    * |ε'| > 1:  H̃(x, ε) = ε^{-2} yᵀ (δ I − S²)^{-1} M y with δ = ε'^{-2},

    the same rational function, but no intermediate value is larger than the
    result requires (at x ≈ 10^160 in float64, S² would overflow)."""
    big = max(ar.magnitude(t) for t in x)
    if big == 0:
        return ar.zero
    if not math.isfinite(big):  # a magnitude beyond float range (mp:P): scale by its exponent
        k = int(ar.ctx.mag(max(x, key=lambda t: abs(t)))) if hasattr(ar, "ctx") else 0
    else:
        k = math.frexp(big)[1]
    y = [_ldexp(ar, t, -k) for t in x]
    ep = _ldexp(ar, e, k)
    M = hessian_in(ar, field)
    N = len(y)
    S = matmul(M, field.system.J(y), ar)
    S2 = matmul(S, S, ar)
    My = [[sum((M[i][j] * y[j] for j in range(N)), ar.zero)] for i in range(N)]
    small = ar.magnitude(ep) <= 1
    if small:
        e2 = ep * ep
        R = [[(ar.one if i == j else ar.zero) - e2 * S2[i][j] for j in range(N)] for i in range(N)]
    else:
        delta = ar.one / (ep * ep)
        R = [[(delta if i == j else ar.zero) - S2[i][j] for j in range(N)] for i in range(N)]
    try:
        z, cond = solve(ar, R, My)
    except SingularMatrix:
        raise _pole(ar, x, e) from None
    floating_policy(ar, cond, [t[0] for t in z], "H~", x, e)
    value = sum((y[i] * z[i][0] for i in range(N)), ar.zero)
    # times λ² = 2^(2k), or (λ/ε')² = 1/ε² in the second form
    value = _ldexp(ar, value, 2 * k) if small else value / (e * e)
    floating_policy(ar, None, [value], "H~", x, e)
    return value


def _htilde(ar, field, x, e):
    if _floating(ar):
        return _htilde_floating(ar, field, x, e)
    M = hessian_in(ar, field)
    x = list(x)
    S = matmul(M, field.system.J(x), ar)
    S2 = matmul(S, S, ar)
    e2 = e * e
    N = len(x)
    R = [[(ar.one if i == j else ar.zero) - e2 * S2[i][j] for j in range(N)] for i in range(N)]
    Mx = [[sum((M[i][j] * x[j] for j in range(N)), ar.zero)] for i in range(N)]
    try:
        z, _ = solve(ar, R, Mx)
    except SingularMatrix:
        raise _pole(ar, x, e) from None
    return sum((x[i] * z[i][0] for i in range(N)), ar.zero)


def shift_index(n: int, l: int) -> list[int]:
    """σ with (A^l)[j][σ(j)] = 1, so (A^l v)[j] = v[σ(j)] and (A^l M)[j] = M[σ(j)]."""
    return [(j + l) % n if j < n else n + (j - n + l) % n for j in range(2 * n)]


def q_coefficients(system, x, arith=None):
    """[q_0, …, q_{n-1}] at x: q_l = tr((Aᵀ)^l (J(x) Hs)²)/(2n), so that
    (J(x) Hs)² = Σ_l q_l A^l (docs/conventions.md)."""
    ar = get_arith(arith)
    n = system.n
    x = _point(ar, x, system.dim)
    S = matmul(system.J(x), hessian_in(ar, system.field("f")), ar)
    S2 = matmul(S, S, ar)
    two_n = ar.convert(2 * n)
    return [sum((S2[i][s] for i, s in enumerate(shift_index(n, l))), ar.zero) / two_n for l in range(n)]


def Pi(system, x, eps, arith=None):
    """The invariant Poisson tensor by its definition Π(x) = J − ε² J Hs J Hs J (J = J(x))."""
    ar = get_arith(arith)
    e = _eps(ar, eps)
    J = system.J(_point(ar, x, system.dim))
    JH = matmul(J, hessian_in(ar, system.field("f")), ar)
    T = matmul(matmul(JH, JH, ar), J, ar)
    e2 = e * e
    return [[a - e2 * b for a, b in zip(ra, rb)] for ra, rb in zip(J, T)]


def Pi_from_q(system, x, eps, arith=None):
    """Π(x) = (1 − ε² q_0) J − ε² Σ_{l≥1} q_l A^l J (the paper's formula, sum from l = 1)."""
    ar = get_arith(arith)
    e = _eps(ar, eps)
    e2 = e * e
    x = _point(ar, x, system.dim)
    J = system.J(x)
    q = q_coefficients(system, x, ar)
    out = [[(ar.one - e2 * q[0]) * t for t in row] for row in J]
    for l in range(1, system.n):
        c = e2 * q[l]
        for j, s in enumerate(shift_index(system.n, l)):
            out[j] = [a - c * t for a, t in zip(out[j], J[s])]
    return out


def _J_form(n, u, v, k):
    """uᵀ J(e_k) v = Σ_{(i+j) ≡ k} (u_i v_{n+j} − u_{n+i} v_j)."""
    s = u[0] * 0
    for i in range(n):
        j = (k - i) % n
        s = s + u[i] * v[n + j] - u[n + i] * v[j]
    return s


def grad_Htilde(field, x, eps, arith=None):
    """The exact gradient of :func:`Htilde` at x, by a closed form (two solves).

    With R = I − ε²S², S = M J(x), z = R^{-1} M x and w = R^{-T} x:
    ∂_k H̃ = z_k + (Mᵀw)_k + ε² [ (Mᵀw)ᵀ J(e_k) S z + (Mᵀ Sᵀ w)ᵀ J(e_k) z ] for k < n
    (J is linear in u = x[:n]), and without the bracket for k ≥ n.  Tests compare
    it with :func:`grad_Htilde_dual` and with SymPy's derivative.  In the ``flint``
    arithmetic the products and solves are python-flint matrices (the same rationals).

    >>> from exact_khk import LiePoissonSystem, get_arith
    >>> s = LiePoissonSystem.from_vectors("1,0", "0,1", "2,1"); ar = get_arith("fraction")
    >>> [str(t) for t in grad_Htilde(s.field("f"), [ar(t) for t in (1, 0, 0, 1)], "1/3", ar)]
    ['332/121', '-152/121', '14/11', '58/11']
    """
    ar = get_arith(arith)
    e = _eps(ar, eps)
    x = _point(ar, x, field.dim)
    if ar.rational and type(ar.zero).__module__.startswith("flint"):  # python-flint fmpq elements
        return _grad_htilde_flint(field, x, e)
    M = hessian_in(ar, field)
    n, N = field.system.n, len(M)
    S = matmul(M, field.system.J(x), ar)
    S2 = matmul(S, S, ar)
    e2 = e * e
    R = [[(ar.one if i == j else ar.zero) - e2 * S2[i][j] for j in range(N)] for i in range(N)]
    with ar.local():
        try:
            zw, cond = solve(ar, R, [[t] for t in matvec(M, x)])
            ww, _ = solve(ar, transpose(R), [[t] for t in x])
        except SingularMatrix:
            raise _pole(ar, x, e) from None
    z, w = [r[0] for r in zw], [r[0] for r in ww]
    if _floating(ar):
        floating_policy(ar, cond, z + w, "grad H~", x, e)
    Mt = transpose(M)
    a = matvec(Mt, w)
    b = matvec(S, z)
    c = matvec(Mt, matvec(transpose(S), w))
    return [z[k] + a[k] + (e2 * (_J_form(n, a, b, k) + _J_form(n, c, z, k)) if k < n else ar.zero)
            for k in range(N)]


def _hessian_flint(field):
    """The field's constant matrix M as an ``fmpq_mat`` (cached on the field)."""
    from exact_khk.linalg import flintmat

    hit = field._cache.get("hessian:fmpq_mat")
    if hit is None:
        hit = field._cache["hessian:fmpq_mat"] = flintmat.mat(field.hessian)
    return hit


def _grad_htilde_flint(field, x, e):
    """:func:`grad_Htilde` in the ``flint`` arithmetic: the same closed form with
    ``fmpq_mat`` products and solves (the same rationals), and the forms
    uᵀ J(e_k) v for all k at once as one product in Q[t]/(tⁿ − 1):
    Σ_k (uᵀ J(e_k) v) t^k = u_u(t) v_v(t) − u_v(t) v_u(t) mod tⁿ − 1."""
    from exact_khk.linalg import flintmat

    fmpq, fmpq_mat = flintmat.flint.fmpq, flintmat.fmpq_mat
    n = field.system.n
    N = 2 * n
    M = _hessian_flint(field)
    u = list(x[:n])
    zero = fmpq(0)
    J = fmpq_mat(N, N, [t for i in range(n) for t in [zero] * n + [u[(i + j) % n] for j in range(n)]]
                 + [t for i in range(n) for t in [-u[(i + j) % n] for j in range(n)] + [zero] * n])
    S = M * J
    e2 = e * e
    R = fmpq_mat(N, N, [int(i == j) for i in range(N) for j in range(N)]) - e2 * (S * S)
    xc = flintmat.column(x)
    try:
        zc = R.solve(M * xc)
        wc = R.transpose().solve(xc)
    except ZeroDivisionError:
        raise _pole(get_arith("flint"), x, e) from None
    Mt = M.transpose()
    a = Mt * wc
    z, a_, b, c = zc.entries(), a.entries(), (S * zc).entries(), (Mt * (S.transpose() * wc)).entries()
    poly = flintmat.flint.fmpq_poly
    forms = poly(a_[:n]) * poly(b[n:]) - poly(a_[n:]) * poly(b[:n]) \
        + poly(c[:n]) * poly(z[n:]) - poly(c[n:]) * poly(z[:n])
    folded = [zero] * n
    for k, t in enumerate(forms.coeffs()):
        folded[k % n] += t
    return [z[k] + a_[k] + (e2 * folded[k] if k < n else zero) for k in range(N)]


def grad_Htilde_dual(field, x, eps, arith=None):
    """The exact gradient of :func:`Htilde` by forward-mode dual numbers (an
    independent route to :func:`grad_Htilde`; no differences)."""
    from exact_khk.linalg.dual import gradient

    ar = get_arith(arith)
    e = _eps(ar, eps)
    return gradient(ar, lambda d, xd: Htilde(field, xd, e, d), _point(ar, x, field.dim))


# --- the family's integrals and Poisson tensor as the System interface asks them -------------


def htilde_definition(field, x, y, eps, arith=None):
    """The integral by its definition: h(x, y) = (2ε)^{-1} xᵀ J((x+y)/2)^{-1} y, y = Φ(x, ε) the
    Kahan step of ``field`` (for y = Φ(x) it equals H̃(x)).

    Raises :class:`PoleError` where J((x+y)/2) is singular (for instance on every orbit with
    Σ u_i = 0, an invariant hyperplane of the Kahan map, where J is singular)."""
    ar = get_arith(arith)
    e = _eps(ar, eps)
    x, y = list(as_point(ar, x, field.dim)), list(as_point(ar, y, field.dim, "x_next"))
    half = ar.one / ar.convert(2)
    m = [(a + b) * half for a, b in zip(x, y)]
    with ar.local():
        try:
            z, _ = solve(ar, field.system.J(m), [[t] for t in y])
        except SingularMatrix:
            raise PoleError("h(x, x~) is undefined: J((x+x~)/2) is singular at x = ("
                            + ", ".join(ar.format(t) for t in x) + ")") from None
    return sum((a * r[0] for a, r in zip(x, z)), ar.zero) / (e + e)


class HtildeIntegral:
    """H̃ of a Lie–Poisson field as a :class:`~exact_khk.systems.base.Function`
    (``I(ar, x, eps)``, exact gradient by :func:`grad_Htilde`); ``H~`` for f, ``K~[s]`` for g[s].

    What the certificate's claims read besides: ``fld`` (the field whose Kahan map has the
    discrete Lagrangian h, :meth:`definition`), and for K̃[s] ``base`` = ``"H~"`` and ``signs``
    (∇K̃ = B ∇H̃ with B = B[signs]: ``involution(cyclotomic=True)`` of the system)."""

    depends_on_eps = True
    definition_text = "by (tH 4) equals h(x, {map}(x)) = (2 eps)^-1 x^T J((x+x~)/2)^-1 x~"

    def __init__(self, name, fld, text, base=None, signs=None):
        self.name, self.fld, self.text, self.base, self.signs = name, fld, text, base, signs

    def __call__(self, ar, x, eps):
        return Htilde(self.fld, x, eps, ar)

    def gradient(self, ar, x, eps):
        return grad_Htilde(self.fld, x, eps, ar)

    def definition(self, ar, x, y, eps):
        """h(x, y) (:func:`htilde_definition`): equals H̃(x) for y = Φ(x)."""
        return htilde_definition(self.fld, x, y, eps, ar)

    def degrees(self):
        """Degree bounds (numerator, denominator) in (x, ε): H̃ = xᵀ adj(R) M x / det R with
        R = I − ε²(M J(x))² of entries of degree ≤ 4 (Cramer): (4N − 2, 4N), N = 2n."""
        N = self.fld.dim
        return 4 * N - 2, 4 * N

    def at_eps_zero(self):
        """The ε → 0 limit is 2H = xᵀ M x, which the certificate's own controls cover: None."""
        return None

    def __repr__(self):
        return f"HtildeIntegral({self.name}: {self.text})"


class PiTensor:
    """Π(x, ε) = J − ε² J Hs J Hs J as a :class:`~exact_khk.systems.base.Tensor`; besides,
    its second form (:meth:`formula`, the paper's), its ε → 0 limit J(x) (:meth:`at_eps_zero`)
    and the identity ∇q_l = A^l ∇q_0 of the coefficients of that form (:meth:`coefficient_sides`)."""

    name, text, depends_on_eps = "Pi", "J - eps^2 J Hs J Hs J", True
    formula_text = "(1 - eps^2 q_0) J - eps^2 sum_(l>=1) q_l A^l J"
    limit_name = "J"

    def __init__(self, system):
        self.system = system

    def matrix(self, ar, x, eps):
        return Pi(self.system, x, eps, ar)

    def formula(self, ar, x, eps):
        return Pi_from_q(self.system, x, eps, ar)

    def at_eps_zero(self, ar, x):
        return self.system.J(list(x))

    def degrees(self):
        """The degree in (x, ε) of the polynomial entries of Π (J Hs J Hs J cubic, times ε²) and of
        its second form (q_l quadratic, ε² q_l A^l J): 5."""
        return 5

    def jacobiator(self, ar, x, eps):
        from exact_khk.linalg.dual import jacobiator

        return jacobiator(ar, lambda d, xd: Pi(self.system, xd, d.convert(eps), d), x)

    def coefficient_statement(self, how, npts):
        return (f"the exact gradients ({how}) of q_l = tr((A^T)^l (J Hs)^2)/(2n) satisfy grad q_l = "
                f"A^l grad q_0 at the {npts} points of the Phi_f orbit")

    def coefficient_sides(self, grads):
        """([∇q_1, …], [A ∇q_0, A² ∇q_0, …]) from ``grads`` = [∇q_0, …, ∇q_{n−1}]."""
        n = self.system.n
        return grads[1:], [[grads[0][i] for i in shift_index(n, l)] for l in range(1, n)]

    def coefficient_gradients(self, ar, x):
        """[∇q_0, …, ∇q_{n−1}] at x by dual numbers."""
        from exact_khk.linalg.dual import jacobian

        return jacobian(ar, lambda d, xd: q_coefficients(self.system, xd, d), x)[1]
