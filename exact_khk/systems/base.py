"""The one interface every system implements: what a quadratic system knows.

A *system* is a quadratic vector field f on K^dim together with what is known
about it.  Generic code (the Kahan map, the certificate, the diagnostics) asks
a system; it never tests which family a system belongs to.

* ``dim``, ``variables``, ``name``, :meth:`describe`, :meth:`to_json`;
* :meth:`field` — the main field ``"f"`` and the other fields named in
  :meth:`field_names`; every field other than ``"f"`` is claimed to commute
  with f: Φ_f∘Φ_g = Φ_g∘Φ_f for the *same* ε;
* :meth:`integrals` — rational functions I(x, ε) claimed conserved by Φ_f (and
  by the Kahan map of every commuting field);
* :meth:`poisson` — a Poisson tensor Π(x, ε) claimed to satisfy the Jacobi
  identity and to be preserved, dΦ(x) Π(x) dΦ(x)ᵀ = Π(Φ(x)), or None;
* :meth:`controls` — functions claimed **not** conserved (user-declared
  negative controls, on top of the automatic ones);
* :meth:`hamiltonian_form` — (K, H) when f = K∇H with K constant skew and H
  cubic (Celledoni–McLachlan–Owren–Quispel: modified energy and invariant
  measure), else None;
* ``default_x0``, ``default_eps``, :meth:`random_point`.

:func:`named_field` resolves the name of a field as the command line, the sweep
tasks and the diagnostics take it (for the Lie–Poisson family also ``'b0'``, a
sign pattern and ``'g[SIGNS]'``).

A :class:`Function` is evaluated in any arithmetic context ``ar``
(:mod:`exact_khk.arith`): ``fn(ar, x, eps)`` returns an element of ``ar`` or
raises :class:`~exact_khk.errors.PoleError` where its denominator vanishes;
``fn.gradient(ar, x, eps)`` returns the list of its partial derivatives in x.
"""

from __future__ import annotations

from fractions import Fraction

from exact_khk.errors import InputError
from exact_khk.parsing import parse_signs


class Function:
    """A rational function of x (and ε) evaluated over an arithmetic context.

    Subclasses implement :meth:`__call__` and :meth:`gradient`; ``name`` is a
    short label, ``text`` a human-readable formula, ``depends_on_eps`` whether
    ε occurs in it.
    """

    name = "?"
    text = ""
    depends_on_eps = True

    def __call__(self, ar, x, eps):  # pragma: no cover - abstract
        raise NotImplementedError

    def gradient(self, ar, x, eps):  # pragma: no cover - abstract
        raise NotImplementedError

    def __repr__(self):
        return f"{type(self).__name__}({self.name}: {self.text})"


class Tensor:
    """A bivector field Π(x, ε): ``matrix(ar, x, eps)`` (rows of elements of ``ar``)
    and ``jacobiator(ar, x, eps)`` — the list of cyclic sums
    Σ_m (Π_im ∂_mΠ_jk + Π_jm ∂_mΠ_ki + Π_km ∂_mΠ_ij), i < j < k, all zero iff the
    Jacobi identity holds at x."""

    name = "Pi"
    text = ""
    depends_on_eps = True

    def matrix(self, ar, x, eps):  # pragma: no cover - abstract
        raise NotImplementedError

    def jacobiator(self, ar, x, eps):  # pragma: no cover - abstract
        raise NotImplementedError


class System:
    """Base class of systems (see the module docstring).  Defaults: nothing is
    known beyond the field."""

    name = "system"
    kind = "quadratic"
    dim = 0
    variables: tuple = ()
    default_x0: tuple = ()
    default_eps = Fraction(1, 10)
    #: steps certified by default (a system file may lower it where heights grow fast)
    default_steps = 20

    @staticmethod
    def from_expressions(variables, **parts) -> "System":
        """A system from expressions (see :meth:`exact_khk.systems.expressions.ExpressionSystem.from_expressions`
        and docs/system-files.md)."""
        from exact_khk.systems.expressions import ExpressionSystem

        return ExpressionSystem.from_expressions(variables, **parts)

    @staticmethod
    def load(spec) -> "System":
        """A catalogue system by name (``'euler-top'``) or a system file by path."""
        from exact_khk.systems.catalogue import resolve

        return resolve(spec)

    def describe(self) -> str:
        return f"{self.name} (dimension {self.dim})"

    def to_json(self) -> dict:  # pragma: no cover - abstract
        raise NotImplementedError

    def field(self, name: str = "f"):  # pragma: no cover - abstract
        raise NotImplementedError

    def field_names(self) -> tuple:
        return ("f",)

    def integrals(self) -> dict:
        return {}

    def poisson(self):
        return None

    def controls(self) -> dict:
        return {}

    def hamiltonian_form(self):
        return None

    def random_point(self, seed: int, bound: int = 3) -> tuple:
        """A reproducible small-integer point (not all zero)."""
        import random

        rng = random.Random(f"x0-{seed}")
        while True:
            x = tuple(Fraction(rng.randint(-bound, bound)) for _ in range(self.dim))
            if any(x):
                return x


def named_field(system, name="f", cyclotomic=False):
    """The field of ``system`` called ``name``; every bad name is an InputError naming it.

    For the Lie–Poisson family: ``'f'``, ``'control'``, ``'g'`` or its alias ``'b0'``
    (g for B_0 = '-+…+'), and ``'g[SIGNS]'`` or the bare pattern ``'SIGNS'`` (g for
    that involution).  ``cyclotomic``: build a g of a non-rational pattern over Q(ω)
    (see :meth:`~exact_khk.systems.lie_poisson.system.LiePoissonSystem.field`) — a
    bool, or a function returning one, called only when a pattern is named (deciding
    whether an arithmetic holds ω costs O(n²)).  Other systems: a field name of the
    system, checked by the system.

    >>> from exact_khk.systems.lie_poisson.system import default_system
    >>> s = default_system()
    >>> [named_field(s, t).label for t in ("f", "g", "b0", "+--", "g[+--]", "control")]
    ['f', 'g[-++]', 'g[-++]', 'g[+--]', 'g[+--]', 'control']
    >>> named_field(s, "g[")
    Traceback (most recent call last):
    ...
    exact_khk.errors.InputError: field: expected f, g, b0, g[SIGNS], a sign pattern SIGNS or control for the Lie–Poisson family, got 'g['
    """
    if not isinstance(name, str):
        raise InputError(f"field: expected a field name, got {name!r}")
    if system.kind != "lie-poisson" or name in ("f", "g", "control"):
        return system.field(name)
    if name == "b0":
        return system.field("g")
    if name.startswith("g[") and name.endswith("]"):
        signs = name[2:-1]
    elif name and set(name) <= set("+-"):
        signs = name
    else:
        raise InputError(f"field: expected f, g, b0, g[SIGNS], a sign pattern SIGNS or control for the "
                         f"Lie–Poisson family, got {name!r}")
    parse_signs(signs, system.n)  # a bad pattern is refused before ω is asked for
    return system.field("g", signs=signs, cyclotomic=cyclotomic() if callable(cyclotomic) else cyclotomic)
