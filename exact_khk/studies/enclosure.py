"""Certified orbit enclosures without the wrapping effect.

Two ways to enclose the orbit x_k = Φ^k(x_0) of the Kahan map in arb balls at P
bits, each certified to contain the exact orbit at every step:

``naive`` (what ``ball:P`` does)
    X_{k+1} = Φ(X_k) evaluated in ball arithmetic.  Every step wraps the image of
    the box X_k, a parallelepiped, into a new box; the radius then grows like
    the product of the norms of the interval Jacobians — on the default n = 3
    orbit by about 7.8 bits per step, although the true error grows by a small
    fraction of a bit.

``lohner`` (mean-value form with Lohner's QR coordinate change)
    The state is x, and q = (ε, δ) are constant coordinates: ε (so an interval ε is
    propagated by its own derivative ∂Φ/∂ε, not re-added at every step) and the
    offsets δ_j = p_j − m_j of the real parameters of the field (below; none for a
    rational field).  The enclosure is the set c_k + A_k r_k + C_k (q − q̂): a point
    centre c_k (exact dyadic), q̂ = (mid ε, 0) the centre of q, point matrices A_k
    (d×d) and C_k (d×m), and a box r_k centred at 0; q − q̂ ranges over the fixed box
    r_q = ([−rad ε, rad ε], [−r_j, r_j]).  One step:

    1. y ∋ Φ(c_k; q̂): one ball step at the point (c_k, mid ε) with the midpoint
       parameters; c_{k+1} = mid(y) and z = y − c_{k+1} (a tiny box: the centre's
       rounding);
    2. [J_x | J_q] ∋ the derivative of (x, q) ↦ Φ(x; q) for all x in the box
       X_k ⊇ c_k + A_k r_k + C_k r_q and all q in its box, from
       dΦ/dx = (I − ε f'(x))^{-1} (I + ε f'(Φ(x))) with Φ(X_k) enclosed by a naive
       step, ∂Φ/∂ε = (I − ε f'(x))^{-1} (f'(x)(Φ(x) − x) + 2 f(x)) and
       ∂Φ/∂p_j = (I − ε f'(x))^{-1} ε (f_j'(x)(Φ(x) − x) + 2 f_j(x)): both from the
       step's equation (I − ε f'(x))(Φ − x) = 2ε f(x) (the form BallKahan.step
       solves; for a homogeneous f, (I − ε f'(x)) Φ = x is the same equation, as
       f'(x) x = 2 f(x)), differentiated in ε, resp. in p_j with f_j = ∂f/∂p_j(·; p)
       (for f linear in p, f(x; p) = f_0(x) + Σ_j p_j f_j(x), the unit fields):
       −ε f_j'(x)(Φ − x) + (I − ε f'(x)) ∂Φ/∂p_j = 2ε f_j(x);
    3. by the mean-value theorem (row by row, on the segment from (c_k, q̂) to
       (x_k, q), inside the convex box X_k × box(q)),
       x_{k+1} − Φ(c_k; q̂) = J̃_x (x_k − c_k) + J̃_q (q − q̂) with J̃ ∈ [J_x | J_q];
       with x_k − c_k = A_k ρ + C_k (q − q̂), ρ ∈ r_k:
       x_{k+1} ∈ c_{k+1} + z + B ρ + G (q − q̂), B = J_x A_k, G = J_x C_k + J_q;
    4. A_{k+1} = Q of a floating QR factorisation of mid(B) whose columns are first
       sorted by their length times the radius of r_k (Lohner's choice: the first
       axis follows the largest error direction), C_{k+1} = mid(G) (the parameter
       directions, carried exactly, never wrapped); then
       r_{k+1} = (A_{k+1}^{-1} B) r_k + (A_{k+1}^{-1} (G − C_{k+1})) r_q + A_{k+1}^{-1} z
       with A_{k+1}^{-1} enclosed by arb (``arb_mat.inv``), re-centred at 0: it holds
       ρ' = A_{k+1}^{-1}(x_{k+1} − c_{k+1} − C_{k+1}(q − q̂)), so the invariant
       x_{k+1} − c_{k+1} = A_{k+1} ρ' + C_{k+1} (q − q̂) carries over;
    5. the enclosure X_{k+1} = c_{k+1} + A_{k+1} r_{k+1} + C_{k+1} r_q, intersected
       with the naive box Φ(X_k) (both contain x_{k+1}), then joined with c_{k+1}
       (so that the next step's segments lie in the box).

    Every inclusion is rigorous (A_{k+1} is any invertible matrix and C_{k+1} any
    point matrix: their rounding affects the width, never the truth).  The wrapping
    of step 4 acts only on r_k in a basis adapted to the flow, and on the q part
    only through the width of G (of the order of the box's width, so second order
    in the parameters' radii); for an integrable map the tangent map grows
    polynomially, so the radius grows like a power of k: the log-radius like log k,
    not like k.  The method is first order: a wide box (x_0, ε or parameters of
    relative width ≳ 10^-3 on the built-in orbit) is undecided after a few steps.

Where a pivot of I − ε f'(X) cannot be certified nonzero (X too wide, or the
step truly singular), a method stops with status ``'undecided'`` at that step
(:class:`~exact_khk.errors.UndecidedError`): never a wrong enclosure.

>>> from exact_khk.systems.lie_poisson import default_system, DEFAULT_X0
>>> runs = compare(default_system(), DEFAULT_X0, "1/10", 90, 128, check_exact=True)
>>> [(r.method, r.status, r.encloses) for r in runs]
[('naive', 'undecided', True), ('lohner', 'ok', True)]
>>> runs[1].min_correct_bits > 100 > runs[0].rows[-1].correct_bits
True

Real input (:mod:`exact_khk.arith.reals`): x_0 and ε may be intervals, balls or
exact reals such as ``sqrt(2)``.  So may the parameters of a system whose field
has ball coefficients: the Lie–Poisson blocks a, b, c
(:class:`~exact_khk.systems.lie_poisson.real.RealLiePoissonSystem`, where
f(x; p) = Σ_j p_j f_j(x)) and a system file's parameters given as reals
(:class:`~exact_khk.systems.real_expressions.RealExpressionSystem`, coefficients
rational functions of p); every coefficient ball contains the true coefficient for
every p in the box P.  The enclosures then hold for every p ∈ P at once:

* naive: X_{k+1} = Φ(X_k; P) in balls contains Φ(x; p) for every x ∈ X_k, p ∈ P;
* Lohner: the system gives ``system.parameter_fields('f')``, a
  :class:`~exact_khk.systems.quadratic.ParameterFields`: the midpoint field f(·; m)
  (exact rationals) and, for each parameter of nonzero radius r_j, a field f_j whose
  coefficients contain those of ∂f/∂p_j(·; p) for every p ∈ P (for the Lie–Poisson
  blocks, f is linear in p and f_j is the exact unit field; for a system file, the
  derivatives of the rational coefficients, evaluated in balls over P); the δ_j
  are coordinates of q above.  Step 1 steps the centre with the midpoint field
  (its image is exact up to rounding: z does not contain the spread over P);
  step 2 evaluates f, f' with the ball field (its coefficients contain those of
  f(·; p) for every p ∈ P) and f_j, f_j' on X_k, so [J_x | J_q] contains the
  derivative at every point of the box X_k × box(q).  Fix p ∈ P: s ↦ Φ(s; p) is smooth on the box (its pivots are
  certified nonzero there), so step 3 holds for this p's orbit, and by induction
  every X_k contains x_k(p) for every p ∈ P.  The parameters' effect is carried in
  C_k; only the width of G (second order) is wrapped: on the built-in orbit a box
  of width 2·10^-6 in a_2 keeps 21.5 correct bits over 200 steps, where the
  orbits of its two ends alone differ by 2^-21.8 (relative).  A field with ball
  coefficients whose system gives no ``parameter_fields`` (q = (ε) only) is
  still enclosed: step 1 then steps the centre with the ball field, so
  y ∋ Φ(c_k; p) for every p ∈ P and the spread over P is wrapped into r at
  every step (for the Lie–Poisson blocks that wrapping leaves the box above
  undecided at step 12).

The drift of every integral the system declares is enclosed as
I(X_k) − I(X_0); for a point input it contains 0 at every step (the integral is
exact for the Kahan map), and its width bounds what rounding may do.  For a wide
input box, I(X_k) − I(X_0) is the difference of two enclosures over the box (it
bounds |I(x_k) − I(x'_0)| over all x_0, x'_0 in the box, not only x'_0 = x_0).
An integral of a system with ball parameters is evaluated with the same ball
parameters (H̃ and K̃ of :class:`~exact_khk.systems.lie_poisson.real.RealLiePoissonSystem`
use its ball Hessians), so I(X_k; P) − I(X_0; P) contains I(x_k(p); p) − I(x_0; p) = 0
for every p ∈ P.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import flint

from exact_khk.arith import get_arith
from exact_khk.arith.ball import contains_exact
from exact_khk.arith.reals import parse_real, parse_real_vector
from exact_khk.errors import InputError, UndecidedError

METHODS = ("naive", "lohner")
#: the longest enclosure orbit a run may ask for (steps): every step keeps a row, and
#: a lohner step at 256 bits takes a few milliseconds (10⁶ steps: about an hour)
MAX_ENCLOSURE_STEPS = 1_000_000


def _log2(a) -> float | None:
    """log2 of a nonnegative arb's midpoint (any exponent; None for 0)."""
    m = a.mid()
    if m.is_zero():
        return None
    man, exp = m.man_exp()
    man = abs(int(man))
    shift = max(man.bit_length() - 60, 0)
    return math.log2(man >> shift) + shift + int(exp)


def _abs_upper(a):
    """|a| ≤ this exact arb (an upper bound of |a|)."""
    return flint.arb(abs(a).upper())


def _wide(fld) -> bool:
    """Whether a coefficient of the field is a ball of nonzero radius (real parameters)."""
    coefs = [c for terms in fld.terms() for _, c in terms] + [c for row in fld.linear for _, c in row] + list(fld.const)
    return any(isinstance(c, flint.arb) and not c.rad().is_zero() for c in coefs)


class BallKahan:
    """Kahan steps and Jacobians of a quadratic field in arb balls at ``prec`` bits,
    with ε itself a ball; every result encloses the exact one for every point of
    the input balls.  ``params``: the field's real parameters as a
    :class:`~exact_khk.systems.quadratic.ParameterFields` (``centre`` steps with its
    midpoint field, :meth:`jacobian` adds a column ∂Φ/∂p_j per parameter), or None.
    Call inside ``flint.ctx.workprec(prec)``."""

    def __init__(self, fld, prec, params=None):
        self.fld, self.ar, self.dim = fld, get_arith(f"ball:{prec}"), fld.dim
        self.params = params
        self.centre = self if params is None else BallKahan(params.mid, prec)
        # wide coefficients (real parameters in boxes): arb's preconditioned solve (elimination on
        # mid(M)^-1 M), far tighter than its default LU on wide entries (one step of the built-in
        # orbit with a_2 in [1.99, 2.01]: radius 4.7 by LU, 0.09 preconditioned); point coefficients:
        # arb's default solve
        self.algorithm = "precond" if _wide(fld) else None

    def _matrix(self, Jf, eps, sign):
        d = self.dim
        return flint.arb_mat([[(1 if i == j else 0) - sign * eps * Jf[i][j] for j in range(d)] for i in range(d)])

    def _solve(self, M, B):
        try:
            return M.solve(B, algorithm=self.algorithm)
        except ZeroDivisionError:
            raise UndecidedError(f"{self.ar.name}: I - eps f'(x) is not certainly invertible on the enclosure "
                                 f"(a pivot contains 0: the box is too wide or the step is singular)") from None

    def step(self, x, eps):
        """(Φ(x), at) for balls x, ε; ``at`` = (I − ε f'(x) as an arb_mat, f'(x), f(x) or None
        for a homogeneous field), what :meth:`jacobian` needs of x."""
        fld, ar = self.fld, self.ar
        Jf = fld.jacobian(ar, x)
        M = self._matrix(Jf, eps, 1)
        if fld.homogeneous:
            sol = self._solve(M, flint.arb_mat([[t] for t in x]))
            return [sol[i, 0] for i in range(self.dim)], (M, Jf, None)
        fx = fld.evaluate(ar, x)
        sol = self._solve(M, flint.arb_mat([[t] for t in fx]))
        return [x[i] + 2 * eps * sol[i, 0] for i in range(self.dim)], (M, Jf, fx)

    def jacobian(self, x, eps, y, at):
        """The d×N Jacobian [J_x | J_q] of (x, q) ↦ Φ(x; q), q = (ε, p), over the boxes (N = d + 1 +
        the number of parameters), given y ∋ Φ(x, ε) and ``at`` from :meth:`step` (M = I − ε f'(x)):
        columns dΦ/dx, ∂Φ/∂ε and ∂Φ/∂p_j = M⁻¹ ε (f_j'(x)(Φ − x) + 2 f_j(x)) for the unit fields f_j
        (module docstring)."""
        fld, ar, d = self.fld, self.ar, self.dim
        M, Jf, fx = at
        units = self.params.units if self.params is not None else ()
        N = d + 1 + len(units)
        dx = [y[j] - x[j] for j in range(d)]

        def rate(Jg, gx):  # g'(x)(Φ − x) + 2 g(x)
            return [sum((Jg[i][j] * dx[j] for j in range(d)), flint.arb(0)) + 2 * gx[i] for i in range(d)]

        rhs = self._matrix(fld.jacobian(ar, y), eps, -1)
        cols = [rate(Jf, fld.evaluate(ar, x) if fx is None else fx)]
        cols += [[eps * t for t in rate(u.jacobian(ar, x), u.evaluate(ar, x))] for u in units]
        full = flint.arb_mat(d, N)
        for i in range(d):
            for j in range(d):
                full[i, j] = rhs[i, j]
            for j, col in enumerate(cols):
                full[i, d + j] = col[i]
        return self._solve(M, full)


# --- records -------------------------------------------------------------------


@dataclass(frozen=True)
class EnclosureRow:
    """One step of an enclosure: ``rad_log2`` = log2(max_i rad X_i / max_i |mid X_i|)
    (None for radius 0), ``correct_bits`` = −rad_log2 (capped at the precision),
    ``encloses`` whether every X_i contains the exact x_i (None: not checked),
    ``drift``: {integral: (log10 of max |I(X_k) − I(X_0)| / |I(X_0)|, whether the
    enclosure contains 0)}."""

    step: int
    rad_log2: float | None
    correct_bits: float
    encloses: bool | None = None
    drift: dict = field(default_factory=dict)
    seconds: float = 0.0


@dataclass(frozen=True)
class EnclosureRun:
    """An enclosure of K steps by one method at ``prec`` bits.  ``status``: ``'ok'``
    or ``'undecided'`` (``failed_step`` could not be certified; the rows stop
    before it); ``radius_rate``: least-squares slope of rad_log2 against k (bits
    per step); ``min_correct_bits`` over the rows; ``encloses``: every checked
    point contained (None: no exact reference); ``points``: the enclosures
    (tuples of arb, x only) when kept."""

    method: str
    prec: int
    status: str
    steps_done: int
    failed_step: int | None
    message: str
    seconds_per_step: float | None
    radius_rate: float | None
    min_correct_bits: float
    encloses: bool | None
    drift_contains_zero: bool | None
    rows: tuple = field(repr=False, default=())
    points: tuple = field(repr=False, default=())

    def summary(self) -> dict:
        return {k: getattr(self, k) for k in ("method", "prec", "status", "steps_done", "failed_step", "message",
                                              "seconds_per_step", "radius_rate", "min_correct_bits", "encloses",
                                              "drift_contains_zero")}


# --- the two methods ---------------------------------------------------------------


def _naive_steps(K, x, eps):
    while True:
        x, _ = K.step(x, eps)
        yield x


def _lohner_steps(K, x, eps, prec):
    """The enclosures X_1, X_2, … (x part) of the module docstring's Lohner method."""
    import numpy as np

    d = K.dim
    # q = (ε, δ): constant coordinates, δ_j = p_j − m_j ∈ [−r_j, r_j]; rq = q − mid(q), exactly
    rq = flint.arb_mat([[flint.arb(0, eps.rad())]] + [[flint.arb(0, t)] for t in
                                                      (K.params.radii if K.params is not None else ())])
    m = rq.nrows()
    c, e0 = [flint.arb(t.mid()) for t in x], flint.arb(eps.mid())
    r = [flint.arb(0, t.rad()) for t in x]
    A, C = flint.arb_mat(d, d), flint.arb_mat(d, m)
    for i in range(d):
        A[i, i] = 1
    box = list(x)
    while True:
        y, _ = K.centre.step(c, e0)  # at the centre (mid(x), mid(ε), δ = 0): the point parameters m
        cn = [flint.arb(t.mid()) for t in y]
        z = flint.arb_mat([[y[i] - cn[i]] for i in range(d)])
        Y, at = K.step(box, eps)
        J = K.jacobian(box, eps, Y, at)
        Jx = flint.arb_mat([[J[i, j] for j in range(d)] for i in range(d)])
        B = Jx * A
        G = Jx * C + flint.arb_mat([[J[i, d + j] for j in range(m)] for i in range(d)])
        # Lohner's basis: QR of mid(B) with columns sorted by |column| * rad(r_j)
        Bm = np.array([[float(B[i, j].mid()) for j in range(d)] for i in range(d)])
        rads = [t.rad() for t in r]
        top = max(rads, key=lambda t: float(t)) if any(not t.is_zero() for t in rads) else None
        w = np.array([float(t / top) for t in rads]) if top is not None and not top.is_zero() else np.ones(d)
        order = np.argsort(-np.linalg.norm(Bm, axis=0) * w, kind="stable")
        Q, _ = np.linalg.qr(Bm[:, order])
        if not np.all(np.isfinite(Q)) or abs(np.linalg.det(Q)) < 0.5:
            Q = np.eye(d)  # cannot happen for an orthogonal Q; any invertible basis stays rigorous
        An = flint.arb_mat([[float(Q[i, j]) for j in range(d)] for i in range(d)])
        Cn = flint.arb_mat([[G[i, j].mid() for j in range(m)] for i in range(d)])
        try:
            Ainv = An.inv()
        except ZeroDivisionError:  # pragma: no cover - Q is orthogonal
            raise UndecidedError(f"ball:{prec}: the Lohner basis could not be inverted") from None
        # (A⁻¹B) r, not A⁻¹(B r): the product A⁻¹B is nearly triangular, B r would wrap
        rn = (Ainv * B) * flint.arb_mat([[t] for t in r]) + (Ainv * (G - Cn)) * rq + Ainv * z
        r = [flint.arb(0, _abs_upper(rn[i, 0])) for i in range(d)]
        A, C, c = An, Cn, cn
        Ar = A * flint.arb_mat([[t] for t in r]) + C * rq
        box = []
        for i in range(d):
            b = c[i] + Ar[i, 0]
            try:
                b = b.intersection(Y[i])
            except (ValueError, ZeroDivisionError):  # pragma: no cover - both contain x_{k+1}
                raise UndecidedError(f"ball:{prec}: disjoint enclosures at coordinate {i} (a bug; please "
                                     f"report)") from None
            box.append(b.union(c[i]))  # the segment from the centre to x_{k+1} stays in the box
        yield box


def enclose(system, x0, eps, steps, prec=256, method="lohner", exact=None, integrals=None, keep_points=False,
            progress=None) -> EnclosureRun:
    """Enclose ``steps`` Kahan steps of ``system.field('f')`` from ``x0`` at ``prec`` bits.

    ``x0``: a sequence of reals (texts read by :func:`~exact_khk.arith.reals.parse_real`:
    rationals, ``'sqrt(2)'``, ``'[1.2,1.3]'``, ``'1.25+-0.05'``; arb balls) or one
    comma-separated text; ``eps`` likewise one real.  ``method``: ``'naive'`` or
    ``'lohner'``.  ``exact``: the exact orbit (fmpq points) to check containment
    against, exactly, at every step it covers; ``integrals``: {name: I(ar, x, eps)}
    whose drift is enclosed (see :func:`exact_khk.studies.scaling.declared`);
    ``progress(1)`` after each step.  Never raises for an undecided step: the run
    stops there with ``status='undecided'``.
    """
    if method not in METHODS:
        raise InputError(f"method: expected one of {', '.join(METHODS)}, got {method!r}")
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 0:
        raise InputError(f"steps: expected a non-negative integer, got {steps!r}")
    if steps > MAX_ENCLOSURE_STEPS:
        raise InputError(f"steps: {steps} is beyond the limit of {MAX_ENCLOSURE_STEPS:,} enclosure steps "
                         f"(MAX_ENCLOSURE_STEPS)")
    fld = system.field("f")
    x = parse_real_vector(x0, prec, "x0", fld.dim)
    e = parse_real(eps, prec, "eps")
    if e.contains(0):
        raise InputError("eps: the step size (interval) must not contain 0")
    params = getattr(system, "parameter_fields", None)
    K = BallKahan(fld, prec, params("f") if params is not None and method == "lohner" else None)
    ar = K.ar
    rows, points, times = [], [], []
    status, failed, message = "ok", None, ""
    with flint.ctx.workprec(prec):
        start = {}
        for name, I in (integrals or {}).items():
            try:
                start[name] = I(ar, x, e)
            except ArithmeticError:  # a pole or undecided at x0: no drift for this integral
                pass
        it = _naive_steps(K, x, e) if method == "naive" else _lohner_steps(K, x, e, prec)
        X = x
        for k in range(steps + 1):
            if k > 0:
                t = time.perf_counter()
                try:
                    X = next(it)
                except UndecidedError as exc:
                    status, failed, message = "undecided", k, f"step {k}: {exc}"
                    break
                dt = time.perf_counter() - t
                times.append(dt)
            else:
                dt = 0.0
            rows.append(_row(ar, k, X, e, prec, exact, integrals or {}, start, dt))
            if keep_points:
                points.append(tuple(X))
            if progress is not None and k > 0:
                progress(1)
    from exact_khk.studies.common import _slope  # one least-squares slope for every study

    rate = _slope([r.step for r in rows], [r.rad_log2 for r in rows])
    checked = [r.encloses for r in rows if r.encloses is not None]
    drifts = [z for r in rows for _, z in r.drift.values()]
    return EnclosureRun(method, prec, status, len(times), failed, message,
                        sum(times) / len(times) if times else None, rate,
                        min((r.correct_bits for r in rows), default=float(prec)),
                        all(checked) if checked else None, all(drifts) if drifts else None,
                        tuple(rows), tuple(points))


def _row(ar, k, X, eps, prec, exact, integrals, start, dt):
    rad = max((t.rad() for t in X), key=lambda a: (not a.is_zero(), _log2(a) or 0.0))
    norm = max((abs(t.mid()) for t in X), key=lambda a: _log2(a) if not a.is_zero() else -math.inf)
    lr, ln = _log2(rad), _log2(norm)
    rel = None if lr is None else lr - (ln if ln is not None else 0.0)
    bits = float(prec) if rel is None else max(0.0, min(float(prec), -rel))
    enc = None
    if exact is not None and k < len(exact):
        enc = all(contains_exact(t, q) for t, q in zip(X, exact[k]))
    drift = {}
    for name, I in integrals.items():
        if name not in start:
            continue
        try:
            D = I(ar, X, eps) - start[name]
        except ArithmeticError:
            continue
        size = _log2(_abs_upper(D) if not D.is_zero() else D)
        ref = _log2(abs(start[name]))
        drift[name] = (None if size is None else (size - (ref or 0.0)) * math.log10(2), bool(D.contains(0)))
    return EnclosureRow(k, rel, bits, enc, drift, dt)


def compare(system, x0, eps, steps, prec=256, methods=METHODS, check_exact=False, diagnostics=False,
            progress=None) -> list:
    """:func:`enclose` by every method of ``methods`` on the same input (side by side).
    ``check_exact``: compute the exact orbit (x0 and ε must be rational) and check
    every enclosure against it; ``diagnostics``: enclose the declared integrals' drift."""
    from exact_khk.studies.common import declared, exact_prefix

    exact = None
    if check_exact:
        from exact_khk.parsing import parse_rational, parse_vector

        fld = system.field("f")
        pts = parse_vector(x0 if isinstance(x0, str) else [str(t) for t in x0], "x0", fld.dim)
        exact, _, _ = exact_prefix(fld, pts, parse_rational(str(eps), "eps"), steps)
    integrals = declared(system)[0] if diagnostics else None
    return [enclose(system, x0, eps, steps, prec, m, exact, integrals, progress=progress) for m in methods]


# --- in the scaling study: ``lohner:P`` beside the arithmetics --------------------


class LohnerSpec:
    """The name ``lohner:P`` in a list of arithmetics of a scaling study: the Lohner
    enclosure at P bits, compared step by step with the exact orbit like ``ball:P``."""

    exact = False

    def __init__(self, prec):
        from exact_khk.arith import check_precision

        self.prec = check_precision("lohner", prec)
        self.name = f"lohner:{self.prec}"

    def __repr__(self):
        return f"<enclosure {self.name}>"


def parse_spec(name):
    """A :class:`LohnerSpec` for ``'lohner:P'`` (InputError for a bad P), None for any other name."""
    if isinstance(name, LohnerSpec):
        return name
    if not isinstance(name, str) or not name.strip().startswith("lohner"):
        return None
    _, _, p = name.strip().partition(":")
    if not p.strip().isdigit() or len(p.strip()) > 30:
        raise InputError(f"arith: {name!r}: expected lohner:P with P an integer precision in bits")
    return LohnerSpec(int(p))


def _lohner_cpu_per_step(system, x0, eps, steps, prec) -> float:
    """CPU seconds per step (``time.process_time``) of ``steps`` bare Lohner steps from x0."""
    fld = system.field("f")
    params = getattr(system, "parameter_fields", None)
    K = BallKahan(fld, prec, params("f") if params is not None else None)
    with flint.ctx.workprec(prec):
        it = _lohner_steps(K, parse_real_vector([str(t) for t in x0], prec, "x0", fld.dim),
                           parse_real(str(eps), prec, "eps"), prec)
        t = time.process_time()
        for _ in range(steps):
            next(it)
        return (time.process_time() - t) / steps


def scale_run(system, x0, eps, steps, spec, exact, diagnostics=True, progress=None, repeats=1):
    """The Lohner enclosure as an :class:`~exact_khk.studies.scaling.ArithRun` of a scaling
    study: midpoint error and radius against the exact orbit, containment decided
    exactly, the integrals' drift enclosed (I(X_k) − I(X_0): |mid| + rad); time per step:
    the least CPU time of ``repeats`` bare runs of the steps done (as for the other
    arithmetics of a study)."""
    from exact_khk.studies.common import LOG10_2, ArithRun, StepRow, _slope as slope, declared, vs_exact

    integrals = declared(system)[0] if diagnostics else None
    run = enclose(system, [str(t) for t in x0], str(eps), steps, spec.prec, "lohner", exact, integrals,
                  keep_points=True, progress=progress)
    rows = []
    for r, X in zip(run.rows, run.points):
        if r.step >= len(exact):
            break
        ex = exact[r.step]
        err, rad = vs_exact(X, ex, ball=True)
        rows.append(StepRow(spec.name, r.step, err, rad, {k: v for k, (v, _) in r.drift.items()},
                            encloses=r.encloses and all(z for _, z in r.drift.values()), seconds=r.seconds))
    final = rows[-1].error_log10 if rows else None
    bits_left = float(spec.prec) if final is None else min(float(spec.prec), -final / LOG10_2)
    log2 = lambda v: None if v is None else v / LOG10_2  # noqa: E731
    ks = [r.step for r in rows]
    useless = next((r.step for r in rows if r.radius_log10 is not None and r.radius_log10 >= 0), None)
    per_step = (min(_lohner_cpu_per_step(system, x0, eps, run.steps_done, spec.prec) for _ in range(repeats))
                if run.steps_done else None)
    return ArithRun(spec.name, spec.prec, run.status, run.steps_done, run.failed_step, run.message,
                    per_step, final, bits_left, slope(ks, [log2(r.error_log10) for r in rows]),
                    slope(ks, [log2(r.radius_log10) for r in rows]), useless,
                    all(r.encloses for r in rows) if rows else None, None, tuple(rows))
