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
  negative controls, on top of the automatic ones); :meth:`negative_controls` — controls
  of other kinds (:class:`Control`: a field that must not commute, a map that must not
  conserve a function, a perturbed point), with their own degeneracy rules;
* :meth:`hamiltonian_form` — (K, H) when f = K∇H with K constant skew and H
  cubic (Celledoni–McLachlan–Owren–Quispel: modified energy and invariant
  measure), else None;
* ``claim_order``, ``claims_on_every_orbit``, ``own_controls_only`` — how the certificate
  runs the claims, for any system declaring them;
* ``default_x0``, ``default_eps``, :meth:`random_point`.

The constructors ``System.load(spec)`` (a catalogue name or a system file) and
``System.from_expressions(variables, ...)`` live with their implementations
(:mod:`exact_khk.systems.catalogue` attaches them; ``from exact_khk import System``
has them): this file imports no implementation of the interface.

:meth:`System.named_field` resolves the name of a field as the command line, the
sweep tasks and the diagnostics take it (the Lie–Poisson family also takes ``'b0'``,
a sign pattern and ``'g[SIGNS]'``).

A :class:`Function` is evaluated in any arithmetic context ``ar``
(:mod:`exact_khk.arith`): ``fn(ar, x, eps)`` returns an element of ``ar`` or
raises :class:`~exact_khk.errors.PoleError` where its denominator vanishes;
``fn.gradient(ar, x, eps)`` returns the list of its partial derivatives in x.
"""

from __future__ import annotations

from fractions import Fraction

from exact_khk.errors import InputError


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


class Control:
    """A negative control a system declares: a statement that must FAIL on the orbit (the engine
    evaluates it, :func:`~exact_khk.certification.claims.declared_controls`).  ``kind``:

    * ``"commutes"`` — Φ_f∘Φ_g = Φ_g∘Φ_f at the points of the Φ_f orbit, g = ``field``;
    * ``"conserved"`` — ``function`` is conserved along the orbit of x0 under the map of ``field``;
    * ``"perturbed"`` — ``function`` at x0 with its last coordinate moved by 2^-60 (relative; one
      ulp in floating arithmetic) equals its value at x_K (``statement`` names ``{how}`` and ``{K}``).

    ``degenerate(ar, pts)`` (pts: the Φ_f orbit): why it cannot fail on this orbit, or None (then a
    control that did not fail is inapplicable); ``moot()``: why it shows nothing even when it fails.
    These rules are the control's own (the engine adds no rule of its own on top)."""

    def __init__(self, kind, name, statement, field=None, function=None, degenerate=None, moot=None):
        self.kind, self.name, self.statement = kind, name, statement
        self.field, self.function, self.degenerate, self.moot = field, function, degenerate, moot


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
    #: what the literature claims about the Kahan map (a system file's [literature] table)
    literature: dict = {}
    #: options of a certificate of the system's own theorems beyond the declared claims
    #: (``certify(system, signs=...)``); empty: the certificate of what it declares
    certificate_options: tuple = ()
    #: the command-line option that sets the dimension (None: the system file's variables)
    size_option = None

    def describe(self) -> str:
        return f"{self.name} (dimension {self.dim})"

    @property
    def short_name(self) -> str:
        """The system in a one-line message."""
        return self.name

    def coordinate_names(self) -> tuple:
        """Names of the coordinates in output (orbit columns, monomials)."""
        return tuple(self.variables)

    def to_json(self) -> dict:  # pragma: no cover - abstract
        raise NotImplementedError

    def field(self, name: str = "f"):  # pragma: no cover - abstract
        raise NotImplementedError

    def field_names(self) -> tuple:
        return ("f",)

    def named_field(self, name="f", cyclotomic=False):
        """The field called ``name`` as the command line, the sweep tasks and the
        diagnostics take it (here: a field name of the system; ``cyclotomic`` is for
        families whose names may ask for Q(ω)); every bad name is an InputError."""
        if not isinstance(name, str):
            raise InputError(f"field: expected a field name, got {name!r}")
        return self.field(name)

    def integrals(self) -> dict:
        return {}

    def poisson(self):
        return None

    def controls(self) -> dict:
        return {}

    def hamiltonian_form(self):
        return None

    def negative_controls(self, x0, eps) -> list:
        """The :class:`Control` s of a certificate at x0 and ε (after every claim); none by default."""
        return []

    #: the order in which the certificate checks the claims (None: the registry's,
    #: :data:`~exact_khk.certification.claims.CLAIMS`)
    claim_order = None
    #: check and state the claims about a map (integrals conserved, Poisson map) per map along every
    #: map's orbit, each computed first (a singular step names its map), the Poisson ones at the
    #: ``poisson_points`` subset (False: along Φ_f's orbit; a commuting map's, lazily, for its integrals)
    claims_on_every_orbit = False
    #: :meth:`negative_controls` replace the claims' automatic controls (False: both are checked)
    own_controls_only = False

    def fast_forms(self, ar, eps):
        """An evaluator of the claims' quantities by closed forms of this system in ``ar`` at the
        step ``eps`` (an element of ``ar``): the same values as the generic route, faster; None:
        the generic route (the protocol is that of
        :class:`~exact_khk.systems.lie_poisson.flint_forms.FlintForms`)."""
        return None

    def gradient_ranks(self, ar) -> list:
        """Ranks claimed of gradients of the integrals, as (name, statement, rows, rank) with
        ``rows(grad)`` the rows at a point from ``grad(name)`` (the gradient of the integral
        ``name`` there); functional independence where full rank holds at one point."""
        return []

    def measure(self):
        """A density m(x, ε) (a :class:`Function`) claimed invariant: m(Φ(x)) det dΦ(x) = m(x); or None."""
        return None

    def tracked(self) -> tuple:
        """(integrals, commuting fields) that studies follow along an orbit (default: all of them)."""
        return self.integrals(), {name: self.field(name) for name in self.field_names()[1:]}

    def seeded_point(self, seed: int, eps=None, skip: int = 0) -> tuple:
        """The point a command draws for ``--seed``: off the degenerate sets the system knows of
        (default: :meth:`random_point`); ``skip``: the draws of the same seed to pass over (a command
        redraws when a later step from the point is singular)."""
        return self.random_point(seed + skip)

    def random_point(self, seed: int, bound: int = 3) -> tuple:
        """A reproducible small-integer point (not all zero), coordinates in [-bound, bound]."""
        import random

        from exact_khk.parsing import check_count

        check_count(bound, "bound", 1, 10 ** 18)
        if not isinstance(seed, (int, str)) or isinstance(seed, bool):
            raise InputError(f"seed: expected an integer, got {seed!r}"[:200])

        rng = random.Random(f"x0-{seed}")
        while True:
            x = tuple(Fraction(rng.randint(-bound, bound)) for _ in range(self.dim))
            if any(x):
                return x
