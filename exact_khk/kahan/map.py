"""The Kahan (Kahan–Hirota–Kimura) map of a quadratic vector field.

For f(x) = Q(x) + L x + c and step size ε (one step approximates the time-2ε
flow):

* homogeneous f:  Φ_f(x, ε) = (I − ε f'(x))^{-1} x
* general f:      Φ_f(x, ε) = x + 2ε (I − ε f'(x))^{-1} f(x)
* inverse:        Φ_f(·, ε)^{-1} = Φ_f(·, −ε)
* Jacobian:       dΦ_f(x) = (I − ε f'(x))^{-1} (I + ε f'(Φ_f(x)))

The step is undefined where det(I − ε f'(x)) = 0.  Exact arithmetics detect
this exactly and raise :class:`~exact_khk.errors.SingularStepError`.
Floating arithmetics (``float``, ``mp:P``) compute a condition estimate κ of
I − ε f'(x) at every step (on the dense path |M|₁|M⁻¹|₁: for ``float`` with
M⁻¹ by LAPACK, i.e. ``numpy.linalg.cond(M, 1)``, for ``mp:P`` the same in
binary64 where that is accurate (N·κ ≤ 2^32,
:func:`exact_khk.linalg.floating.binary64_condition`), else with |M⁻¹|₁ in p-bit
arithmetic, estimated by LAPACK's method, a lower bound, or exact for N ≤ 5 — see
:func:`exact_khk.linalg.dense.solve`; on the structured path max_j |M_j|₁ · max_j |M_j⁻¹|₁ over the n 2×2 Fourier
blocks M_j, within a factor 2 of the 2-norm condition number) and

* raise :class:`SingularStepError` (with κ) when a pivot is exactly zero, a
  result is not finite, or κ·2^-p ≥ 1 (no correct bit can be guaranteed);
* warn with :class:`~exact_khk.errors.NearSingularWarning` (carrying κ) when
  κ ≥ 2^(p/2), i.e. conditioning alone may cost more than half the bits.

>>> from exact_khk import LiePoissonSystem, KahanMap
>>> sys3 = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")
>>> phi = KahanMap(sys3.field("f"), eps="1/10", arith="fraction")
>>> y = phi.step(["1", "0", "0", "0", "1", "0"])
>>> [str(t) for t in y]
['72745/57239', '34155/57239', '27780/57239', '-34910/57239', '19745/57239', '-18505/57239']
>>> [str(t) for t in phi.inverse(y)]
['1', '0', '0', '0', '1', '0']

Methods (``method=``): ``'dense'`` solves the 2n×2n system (rational
arithmetics with an integer kernel clear denominators once and solve over Z:
python-flint ``fmpz_mat.solve``, along orbits its Dixon solve once the answers
are known to be small, or Bareiss elimination for gmpy2; ``fraction`` is the
plain-elimination reference); ``'structured'`` and ``'split'`` are fast steps a field
may offer: the map asks the field once
(:meth:`~exact_khk.systems.quadratic.QuadraticField.structured_steps`), which answers
with its steps and the rule choosing among them and the dense solve by dimension,
point height and arithmetic, or with None (every step dense; 'structured' and
'split' refused).  The Lie–Poisson fields offer a 2×2 solve over circulants and a
split over the cyclotomic factors (:mod:`exact_khk.systems.lie_poisson.steps`, rules
and their measurements in :mod:`exact_khk.systems.lie_poisson.paths`).  ``'auto'``
(default) takes what the field's rule chooses.  Every path gives the same rational
point; :attr:`KahanMap.path` says which a map takes.

Floating arithmetics stay dense under ``'auto'``, so that ``float`` and ``mp:P``
results are what p-bit arithmetic gives: the ``float`` step is LAPACK's
partially pivoted LU in binary64 (``numpy.linalg.solve``), which *is* p = 53
dense arithmetic, and ``mp:P`` eliminates with partial pivoting at p bits;
both build I − εf'(x) with numpy (:mod:`exact_khk.linalg.floating`; O(n²) from
the circulant first rows when the field declares them).  ``method='structured'`` with them
computes each step by the DFT in ball arithmetic at p + guard bits and rounds
the result into the arithmetic: far faster for large n (float at n = 4096 in a
fraction of a second) and *more* accurate than a p-bit elimination, so it does
not model p-bit rounding.

>>> dense, fast = (KahanMap(sys3.field("f"), "1/10", "flint", method=m) for m in ("dense", "structured"))
>>> fast.step(y) == dense.step(y)
True
"""

from __future__ import annotations

import functools
import math
import warnings
from fractions import Fraction

from exact_khk.arith import _is_element as _arith_is_element, as_point, get_arith, point_height as _height, to_element  # noqa: F401
from exact_khk.errors import InputError, NearSingularWarning, NumericalError, SingularStepError
from exact_khk.linalg.dense import SingularMatrix, solve
from exact_khk.parsing import MAX_STEPS, _short, parse_rational
from exact_khk.systems.quadratic import QuadraticField

METHODS = ("auto", "dense", "structured", "split")
#: dense exact orbit steps (python-flint, 8 ≤ N < 16): Dixon's solve from this height (crossover measured for N = 8..14;
#: as a whole command, without / with Dixon: ``orbit --n 5 --seed 1 --method dense --steps 150`` 2.55×) ...
SMALL_ANSWER_MIN_BITS = 128
#: ... up to DIXON_BITS·(N − 6) bits (fmpz_mat.solve overtakes it near 16 000,
#: 40 000, 60 000 bits for N = 8, 10, 12)
DIXON_BITS = 10_000

@functools.cache
def _floating():
    """:mod:`exact_khk.linalg.floating` (numpy), imported when a floating map is built."""
    from exact_khk.linalg import floating

    return floating


def _is_element(ar, t) -> bool:
    return _arith_is_element(ar, t)


def _read_eps(ar, eps):
    """``(ε as an element of ar, ε as a Fraction or None)``, read as every public function
    reads numbers (:func:`~exact_khk.arith.to_element`; strings, ints and Fractions exactly);
    InputError unless ε is a finite nonzero number of ``ar``."""
    if _is_element(ar, eps) or not isinstance(eps, (str, int, Fraction)):
        value = to_element(ar, eps, "eps")
        exact = ar.to_fraction(value) if ar.rational else None
    else:
        exact = parse_rational(eps, "eps")
        value = to_element(ar, exact, "eps")
    if ar.is_zero(value) is True:
        if exact and ar.exact:  # F_P: a multiple of P
            raise InputError(f"eps: {_short(str(exact), 40)} is 0 in {ar.name} (a multiple of its "
                             f"characteristic); choose another step size or prime")
        if exact:  # a nonzero rational rounded to 0 (e.g. 10^-5000 in float)
            raise InputError(f"eps: {_short(str(exact), 40)} underflows to 0 in {ar.name} "
                             f"(use mp:P or an exact arithmetic)")
        raise InputError("eps: the step size must be nonzero")
    return value, exact


class KahanMap:
    """Φ_f(·, ε) for a :class:`~exact_khk.systems.quadratic.QuadraticField` in one arithmetic.

    ``eps`` is an exact rational (``'1/10'``, Fraction, int) or an element of
    the arithmetic; ``arith`` a name (see :func:`exact_khk.arith.get_arith`) or
    context, default the fastest exact one; ``method`` one of :data:`METHODS`
    (see the module docstring).  ``steps`` is what the field answered when asked for its
    fast steps (:meth:`~exact_khk.systems.quadratic.QuadraticField.structured_steps`), or
    None: every step dense.  ``structure`` is the structure the structured step uses, or
    None (with one, every step is structured); ``split`` whether exact steps take the
    split step instead of the dense one.  See :attr:`path`.
    """

    method, steps = "dense", None  # for maps built without __init__
    #: whether this map's last dense step found a small answer (see ``_integer_steps``)
    _small_answers = False
    #: the prepared ``float`` step of this map's field and ε (see ``_lapack_step``)
    _float_stepper = None

    def __init__(self, field, eps, arith=None, method="auto"):
        if not isinstance(field, QuadraticField):
            raise InputError(f"field: expected a quadratic field such as system.field('f'), "
                             f"got {_short(field)} ({type(field).__name__})")
        self.field = field
        self.arith = ar = get_arith(arith)
        self.method = method
        self.eps, self.eps_exact = _read_eps(ar, eps)
        self.steps = _ask_field(field, ar, method, self.eps)
        if not ar.exact:
            _floating()  # numpy's import belongs to the set-up, not to the first step's time

    def __repr__(self):
        return f"KahanMap({self.field.label}, eps={self.arith.format(self.eps)}, arith={self.arith.name})"

    @property
    def split(self) -> bool:
        return self.steps is not None and self.steps.split

    @property
    def structure(self):
        return None if self.steps is None else self.steps.structure

    @property
    def path(self) -> str:
        """How the steps are solved: ``'dense'``, ``'structured'`` or ``'split'``."""
        return self._kind()

    def point(self, x, name="x"):
        """``x`` as a tuple of elements of this map's arithmetic."""
        return as_point(self.arith, x, self.field.dim, name)

    def with_eps(self, eps):
        """The same map with another step size (e.g. ``-eps`` for the inverse)."""
        out = KahanMap.__new__(KahanMap)
        out.field, out.arith = self.field, self.arith
        out.eps, out.eps_exact = _read_eps(self.arith, eps)
        # the field's fast steps hold for every ε ≠ 0 if for one (the blocks' structure does not
        # depend on ε)
        out.method, out.steps = self.method, self.steps
        return out

    def system_matrix(self, x, sign=1):
        """I − sign·ε f'(x) (a list of rows); NumericalError if a floating entry overflows."""
        ar, x = self.arith, self.point(x)
        M = self._matrix(x, sign)
        M = M.tolist() if hasattr(M, "tolist") else M
        if not ar.exact and not all(ar.is_finite(t) for row in M for t in row):
            raise NumericalError(f"I - eps*f'(x) overflows {ar.name} at x = ({', '.join(map(ar.format, x))})",
                                 float("inf"))
        return M

    def _matrix(self, x, sign=1):
        """I − sign·ε f'(x): a numpy array for ``float`` (binary64) and, as a list of
        rows, built by numpy for floating arithmetics when the field's blocks are
        circulant (:func:`~exact_khk.linalg.floating.system_matrix`, O(n²))."""
        ar, e = self.arith, self.eps if sign == 1 else -self.eps
        if not ar.exact and _floating().has_system_matrix(self.field, ar):
            M = _floating().system_matrix(self.field, ar, x, e)
            return M if ar.lapack else M.tolist()
        return self.field.step_matrix(ar, x, e)

    def _solve(self, M, B, x, eps):
        """Solve M X = B, turning singularity and ill-conditioning into our errors.
        For ``float`` M and B are numpy arrays and so is X (LAPACK:
        :func:`~exact_khk.linalg.floating.float_solve`)."""
        ar = self.arith
        with ar.local():
            try:
                X, cond = _floating().float_solve(M, B) if ar.lapack else \
                    solve(ar, M, B, condition=_floating().binary64_condition)
            except SingularMatrix:
                raise self._singular(x, eps) from None
        if not ar.exact:
            self._check_condition(X.ravel().tolist() if ar.lapack else [t for row in X for t in row],
                                  cond, x, eps)
        return X

    def _check_condition(self, values, cond, x, eps):
        """The floating policy of the module docstring: raise or warn on κ."""
        ar = self.arith
        # cond is None when the context's solver gives no estimate (balls
        # carry their own error bounds instead).
        bad = values is None or not all(map(ar.is_finite, values))
        # compare in log2: 2.0 ** -prec underflows (and 2.0 ** (prec / 2)
        # overflows) a float for the large precisions of mp:P
        lost = math.inf if cond is not None and (cond != cond or math.isinf(cond)) else (
            math.log2(cond) if cond else 0.0)
        if bad or (cond is not None and lost >= ar.prec):
            raise SingularStepError([ar.format(t) for t in x], ar.format(eps),
                                    condition=float("inf") if bad or math.isinf(lost) else cond)
        if cond is not None and lost >= ar.prec / 2:
            warnings.warn(NearSingularWarning(
                f"Kahan step at eps = {ar.format(eps)} is ill-conditioned: "
                f"condition estimate {cond:.3g} of I - eps*f'(x) in {ar.name} "
                f"(about {lost:.0f} of {ar.prec} bits at risk)", cond), stacklevel=4)

    def _singular(self, x, eps):
        """An exactly zero pivot: det(I − εf'(x)) = 0 in an exact arithmetic; in a
        floating one, no proof of that (the rounded matrix met a zero pivot): κ = ∞."""
        ar = self.arith
        return SingularStepError([ar.format(t) for t in x], ar.format(eps),
                                 condition=None if ar.exact else math.inf)

    def _structured_step(self, x):
        """The field's structured step (``steps.step``), its singularity and κ read as the
        dense step's."""
        ar, eps = self.arith, self.eps
        try:
            z, cond = self.steps.step(x, eps, ar)
        except SingularMatrix:
            raise self._singular(x, eps) from None
        if not ar.exact:
            self._check_condition(z, cond, x, eps)
        return z

    def _integer_steps(self, x):
        """Dense exact steps over Z from the point ``x`` (endless iterator).

        The state is a kernel column (python-flint: an fmpq_mat); with v = [xi, dx]
        (x = xi/dx), D·(I − εf'(x)) and D·((I + εL)x + 2εc) are the contractions
        V·v and R·v (:meth:`~exact_khk.systems.quadratic.QuadraticField.integer_system`),
        then one solve over Z (``fmpz_mat.solve``, or Bareiss for gmpy2).  Once a
        step's answer reaches :data:`SMALL_ANSWER_MIN_BITS` with less than twice
        the height of its point, as along orbits, the next solve is told that the
        answer is small (python-flint then uses Dixon's solve for 8 ≤ N < 16),
        up to the height where ``fmpz_mat.solve`` is faster again (:data:`DIXON_BITS`).
        The map remembers this between calls, so that single steps at orbit
        points (e.g. the commutation checks) profit too.
        """
        K, eps, ar = self.arith.integers, self.eps, self.arith
        V, R = self.field.integer_system(K, K.num(eps), K.den(eps))
        col = K.column(x)
        track = self.field.dim in K.small_answer_dims
        height, top = (_height(ar, x) if track else 0), DIXON_BITS * (self.field.dim - 6)
        small = track and self._small_answers and SMALL_ANSWER_MIN_BITS <= height < top
        while True:
            v = K.clear(col)
            try:
                col = K.solve_column(K.square(V, v), K.product(R, v), small)
            except (SingularMatrix, ZeroDivisionError):
                raise self._singular(x, eps) from None
            x = K.values(col)
            if track:
                grown, height = height, _height(ar, x)
                self._small_answers = height < 2 * grown
                small = self._small_answers and SMALL_ANSWER_MIN_BITS <= height < top
            yield x

    def _split_steps(self, x):
        """Split steps from the point ``x`` (endless); the state between steps is the
        last solution as kernel integers (s, L), x = s/L, so that no step clears
        denominators again."""
        K, eps = self.arith.integers, self.eps
        S = self.steps.split_system(K, K.num(eps), K.den(eps))
        s, L = K.split(x)
        while True:
            try:
                s, L, x = S.solve(s, L)
            except ZeroDivisionError:
                raise self._singular(x, eps) from None
            yield x

    def step(self, x):
        """Φ_f(x, ε)."""
        with self.arith.local():  # e.g. the working precision of ball:P
            return self._step(self.point(x))

    def _kind(self) -> str:
        """How every step is solved: ``'structured'``, ``'split'`` or ``'dense'``."""
        steps = self.steps
        if steps is None:
            return "dense"
        if steps.structure is not None:
            return "structured"
        return "split" if steps.split else "dense"

    def _step(self, x):
        ar, eps = self.arith, self.eps
        kind = self._kind()
        if kind == "structured":
            return self._structured_step(x)
        if kind == "split":
            return next(self._split_steps(x))
        if ar.integers is not None:
            return next(self._integer_steps(x))
        if ar.lapack:
            return self._lapack_step(x)
        M = self._matrix(x)
        if self.field.homogeneous:
            X = self._solve(M, [[t] for t in x], x, eps)
            return tuple(row[0] for row in X)
        fx = self.field.evaluate(ar, x)
        X = self._solve(M, [[t] for t in fx], x, eps)
        two_eps = eps + eps
        return tuple(xi + two_eps * row[0] for xi, row in zip(x, X))

    def _lapack_step(self, x):
        """The ``float`` dense step (:func:`~exact_khk.linalg.floating.float_step`:
        I − εf'(x) built by numpy, ``numpy.linalg.solve`` — LAPACK's partially pivoted LU in
        binary64, i.e. p = 53 dense arithmetic — with the 1-norm κ); the point
        comes back as a tuple of Python floats, checked finite.  The map keeps the step's
        ε-dependent constants (:func:`~exact_khk.linalg.floating.float_stepper`)."""
        if self._float_stepper is None:
            self._float_stepper = _floating().float_stepper(self.field, self.arith, self.eps)
        z, cond = self._float_stepper(x)  # a zero pivot: NaN, found here (κ = ∞, as _singular says)
        self._check_condition(z, cond, x, self.eps)
        return tuple(z)

    def _steps(self, x):
        """Φ(x), Φ²(x), … (endless); the exact dense and split paths keep their
        integer state between steps instead of re-reading the point."""
        kind = self._kind()
        if kind != "structured" and self.arith.integers is not None:
            yield from self._split_steps(x) if kind == "split" else self._integer_steps(x)
        while True:
            x = self._step(x)
            yield x

    def inverse(self, x):
        """Φ_f(x, −ε) = Φ_f^{-1}(x, ε)."""
        return self.with_eps(-self.eps).step(x)

    def orbit(self, x0, steps: int, progress=None):
        """[x0, Φ(x0), …, Φ^steps(x0)]; a singular step raises with its step number.

        ``progress``, if given, is called as ``progress(k)`` after step k (inside the
        arithmetic's working context, e.g. the precision of ``ball:P``).
        """
        if not isinstance(steps, int) or isinstance(steps, bool) or steps < 0:
            raise InputError(f"steps: expected a non-negative integer, got {steps!r}")
        if steps > MAX_STEPS:
            raise InputError(f"steps: {_short(steps)} is beyond the limit of {MAX_STEPS:,} steps (MAX_STEPS; the orbit "
                             f"alone would hold more than 10^7 points)")
        if progress is not None and not callable(progress):
            raise InputError(f"progress: expected a function of the step number, got {_short(progress)}")
        pts = [self.point(x0, "x0")]
        it = self._steps(pts[0])
        with self.arith.local():
            for k in range(1, steps + 1):
                try:
                    pts.append(next(it))
                except SingularStepError as exc:
                    raise exc.at_step(k) from None
                if progress is not None:
                    progress(k)
        return pts

    def jacobian(self, x):
        """dΦ_f(x) = (I − ε f'(x))^{-1} (I + ε f'(Φ_f(x)))."""
        with self.arith.local():
            x = self.point(x)
            y = self._step(x)
            D = self._solve(self._matrix(x), self._matrix(y, sign=-1), x, self.eps)
            return D.tolist() if self.arith.lapack else D


def _ask_field(field, ar, method, eps):
    """The field's fast steps for ``method`` (:meth:`~exact_khk.systems.quadratic.QuadraticField.structured_steps`),
    or None: dense.  The field decides, by its own table of rules."""
    if method not in METHODS:
        raise InputError(f"method: expected one of {', '.join(METHODS)}, got {method!r}")
    return None if method == "dense" else field.structured_steps(ar, method, eps)


def kahan_step(field, x, eps, arith=None):
    """Φ_f(x, ε) (functional form of :meth:`KahanMap.step`)."""
    return KahanMap(field, eps, arith).step(x)


def orbit(field, x0, eps, steps, arith=None, progress=None):
    """The orbit of K = ``steps`` Kahan steps (functional form of :meth:`KahanMap.orbit`)."""
    return KahanMap(field, eps, arith).orbit(x0, steps, progress=progress)


def map_jacobian(field, x, eps, arith=None):
    """dΦ_f(x) (functional form of :meth:`KahanMap.jacobian`)."""
    return KahanMap(field, eps, arith).jacobian(x)


