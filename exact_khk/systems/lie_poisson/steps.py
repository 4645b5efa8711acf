"""The family's fast Kahan steps, as a :class:`~exact_khk.kahan.map.KahanMap` asks for them.

A Kahan map asks its field once, ``field.structured_steps(ar, method, eps)``
(:meth:`~exact_khk.systems.quadratic.QuadraticField.structured_steps`), and solves
every step densely when the answer is None.  A Lie–Poisson field answers with
:class:`CirculantSteps` when its step's blocks are circulant: the 2×2 solve over
circulants (:mod:`~exact_khk.systems.lie_poisson.circulant`, exact, by the DFT in
balls for ``float``/``mp:P``, or by the exact DFT in ``cyclo:N``/``gf:P``:
:mod:`~exact_khk.systems.lie_poisson.circulant_dft`) and the split step
(:mod:`~exact_khk.systems.lie_poisson.split`), chosen by the table of
:mod:`~exact_khk.systems.lie_poisson.paths`.  Every step gives the same rational
point as the dense solve.
"""

from __future__ import annotations

from dataclasses import dataclass

from exact_khk.errors import InputError
from exact_khk.systems.lie_poisson import circulant, circulant_dft
from exact_khk.systems.lie_poisson.paths import SPLIT_N, auto_path
from exact_khk.systems.lie_poisson.split import split_system


@dataclass(frozen=True)
class CirculantSteps:
    """How a map's exact or floating steps are solved besides the dense solve.

    ``split``: exact steps take the split step (:meth:`split_system`) instead of the
    dense one; ``structure``: the
    :class:`~exact_khk.systems.lie_poisson.circulant.CirculantStructure` of the
    structured step (:meth:`step`), taken at every step, or None for none."""

    field: object
    split: bool
    structure: object

    def step(self, x, eps, ar):
        """``(z, κ)``: the structured step z = Φ(x) and, in floating arithmetics, the
        condition estimate κ of the n 2×2 Fourier blocks (None for exact ones).  An exact
        singular step raises :class:`~exact_khk.errors.SingularMatrix`."""
        if ar.exact:
            exact = circulant_dft.exact_step if ar.dft is not None else circulant.exact_step
            return exact(self.structure, x, eps, ar), None
        z, cond, _ = circulant.numeric_step(self.structure, x, eps, ar)
        return z, cond

    def split_system(self, kernel, p, q):
        """The split step's :class:`~exact_khk.systems.lie_poisson.split.SplitSystem` at
        ε = p/q over the integer ``kernel``."""
        return split_system(self.field, kernel, p, q)


def circulant_steps(field, ar, method, eps):
    """The :class:`CirculantSteps` of ``field`` for ``KahanMap(field, eps, ar, method)``,
    ``method`` one of 'auto', 'structured', 'split' (``eps`` an element of ``ar``), or
    None (dense); InputError when 'structured' or 'split' is asked for and impossible."""
    K = ar.integers
    if method == "split":
        if K is None or split_system(field, K, K.num(eps), K.den(eps)) is None:
            raise InputError("method: 'split' needs a rational arithmetic with an integer kernel (flint, "
                             "gmpy2) and a field of dimension 2n, n < 16, whose Jacobian "
                             "blocks are circulant (Lie–Poisson fields)")
        return CirculantSteps(field, True, None)
    n = field.dim // 2
    dft = ar.exact and circulant_dft.applies(ar, n)  # cyclo:N with n | N, gf:P with n | P − 1
    usable = ar.rational or ar.fourier or dft
    st = field.circulant_structure(cyclotomic=dft) if usable else None
    if method == "structured":
        if st is None:
            raise structured_refused(ar, n)
        return CirculantSteps(field, False, st)
    if dft:
        return CirculantSteps(field, False, st) if st is not None else None
    if not ar.exact or K is None:
        return None  # floating arithmetics: dense, i.e. genuine p-bit arithmetic
    # a declared structure splits for every n of SPLIT_N: built by the first split step, not here
    splits = st is not None and n in SPLIT_N
    split, structured = auto_path(n, K.name, splits, st is not None)
    if not split and not structured:
        return None
    return CirculantSteps(field, split, st if structured else None)


def structured_refused(ar, n):
    """The InputError of ``method='structured'`` for a field or arithmetic it cannot serve."""
    why = circulant_dft.why_not(ar, n) if ar.dft is not None else None
    return InputError(f"method: 'structured' {why}" if why else
                      "method: 'structured' needs a field whose Jacobian blocks are circulant "
                      "(Lie–Poisson fields with cyclic Hankel Hessian blocks) and a rational, "
                      "float or mp:P arithmetic, or cyclo:N with n | N or gf:P with n | P - 1")
