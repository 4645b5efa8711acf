"""Integrability diagnostics of Kahan maps (docs/diagnostics.md).

* :func:`degree_sequence` (:mod:`.degrees`) — degrees d_k of the iterates Φ^k,
  by restriction to random lines over F_p, with an undercount bound, and the
  exact fit of :mod:`.recurrence`: shortest integer recurrence, dynamical
  degree as an algebraic number, growth class (bounded / polynomial /
  exponential);
* :func:`find_integrals` (:mod:`.integrals`) — conserved rational functions
  with numerator and denominator in a span of candidate monomials, found from
  orbits (Hirota–Kimura bases), modular kernels lifted to Q and verified
  exactly;
* :func:`height_growth` (:mod:`.heights`) — bits of the exact orbit per step.
"""

from exact_khk.diagnostics.degrees import DegreeSequence, degree_sequence, exact_degrees
from exact_khk.diagnostics.heights import HeightGrowth, height_growth, plot_growth
from exact_khk.diagnostics.integrals import IntegralSearch, find_integrals
from exact_khk.diagnostics.recurrence import RecurrenceFit, fit_recurrence

__all__ = ["DegreeSequence", "degree_sequence", "exact_degrees", "HeightGrowth", "height_growth", "plot_growth",
           "IntegralSearch", "find_integrals", "RecurrenceFit", "fit_recurrence"]
