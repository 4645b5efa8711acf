"""Typed errors and warnings of exact_khk.

Every error a user can provoke with bad input is an :class:`InputError` (a
``ValueError``) whose message names the offending argument; an undefined Kahan
step is a :class:`SingularStepError` naming the point and the step size.
"""

from __future__ import annotations


class ExactKHKError(Exception):
    """Base class of all exact_khk errors."""


class InputError(ExactKHKError, ValueError):
    """Malformed or inconsistent input (names the argument at fault)."""


class NotRationalError(InputError):
    """An involution asked for over Q whose entries are not rational."""


class SingularStepError(ExactKHKError, ArithmeticError):
    """The Kahan step is undefined: det(I - eps f'(x)) = 0 (or numerically so).

    Attributes: ``x`` (the point, as strings), ``eps`` (string), ``step``
    (index of the step in an orbit, or None), ``condition`` (condition
    estimate for floating arithmetic, ``inf`` where its elimination met an
    exactly zero pivot; None when an exact arithmetic found det = 0).
    """

    def __init__(self, x, eps, *, step=None, condition=None, detail=""):
        self.x, self.eps, self.step, self.condition, self.detail = x, eps, step, condition, detail
        super().__init__(self._message())

    def _message(self):
        where = f"step {self.step}: " if self.step is not None else ""
        why = "det(I - eps*f'(x)) = 0" if self.condition is None else (
            f"I - eps*f'(x) is numerically singular (condition estimate {self.condition:.3g})")
        pt = "(" + ", ".join(self.x) + ")"
        extra = f"; {self.detail}" if self.detail else ""
        return f"{where}Kahan step undefined at x = {pt}, eps = {self.eps}: {why}{extra}"

    def at_step(self, step):
        """The same error, annotated with the orbit step at which it happened."""
        return SingularStepError(self.x, self.eps, step=step, condition=self.condition,
                                 detail=self.detail)


class PoleError(ExactKHKError, ArithmeticError):
    """A rational function evaluated at a pole: an integral such as H̃ where
    I − ε²(M J(x))² is singular, or h(x, x̃) where J((x+x̃)/2) is singular.
    Not a singular Kahan step."""


class NumericalError(PoleError):
    """A floating evaluation (``float``, ``mp:P``) that gives no trustworthy
    number: a value beyond the arithmetic's range (overflow), a non-finite
    result, or a condition estimate κ with κ·2^-p ≥ 1 (no correct bit can be
    guaranteed).  It does **not** claim a pole: the message says so, and an
    exact arithmetic (or more bits) decides.  A subclass of :class:`PoleError`
    so that code skipping points where a function is undefined skips these too.

    Attribute ``condition``: the condition estimate (``inf`` for overflow), or None.
    """

    def __init__(self, message, condition=None):
        super().__init__(message)
        self.condition = condition


class UndecidedError(ExactKHKError, ArithmeticError):
    """Ball (interval) arithmetic cannot decide a question at this precision,
    e.g. no pivot is certainly nonzero.  Never a wrong answer: "undecided"."""


class SingularMatrix(ArithmeticError):
    """Internal: a linear system's matrix is singular (exactly, or a floating
    pivot is exactly zero).  Raised by the elimination kernels of every layer
    (:mod:`exact_khk.linalg`, an arithmetic's integer solver) and turned by their
    callers into :class:`SingularStepError`, :class:`PoleError` or an "undefined"
    check; it never reaches a user.  Not an :class:`ExactKHKError`."""


class OutputError(ExactKHKError, OSError):
    """An output destination that cannot be written (checked before the work
    starts where possible); the message names the path and the reason."""


class NearSingularWarning(UserWarning):
    """A floating step was taken with an ill-conditioned matrix I - eps f'(x).

    Attribute ``condition``: the 1-norm condition estimate of I - eps f'(x).
    """

    def __init__(self, message, condition):
        super().__init__(message)
        self.condition = condition
