"""Quadratic vector fields f(x) = Q(x) + L x + c with exact coefficients.

The Kahan machinery (:mod:`exact_khk.kahan.map`) accepts any
:class:`QuadraticField`; the Lie–Poisson family (:mod:`exact_khk.systems`) is
one source of them.  Coefficients are exact (``Fraction``, or any value the
arithmetic's ``convert`` accepts, e.g. arb balls that enclose real coefficients in
``ball:P``); they are converted into an arithmetic once and cached.  A term is
dropped only when its coefficient is certainly 0 (:func:`certainly_zero`): a ball
that merely contains 0 stands for coefficients that may be nonzero.

>>> from fractions import Fraction as F
>>> from exact_khk.arith import get_arith
>>> # Lotka–Volterra-like field on Q^2: f(x) = (x0*x1, -x0*x1 + x1)
>>> fld = QuadraticField.from_tensor(
...     [[[0, F(1, 2)], [F(1, 2), 0]], [[0, F(-1, 2)], [F(-1, 2), 0]]],
...     linear=[[0, 0], [0, 1]])
>>> ar = get_arith("fraction")
>>> fld.evaluate(ar, [ar(2), ar(3)])
[Fraction(6, 1), Fraction(-3, 1)]
>>> fld.jacobian(ar, [ar(2), ar(3)])
[[Fraction(3, 1), Fraction(2, 1)], [Fraction(-3, 1), Fraction(-1, 1)]]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from math import lcm

from ..arith import _as_fraction
from ..errors import InputError
from ..parsing import _short
from ..linalg.dense import coefficients_native


def certainly_zero(c) -> bool:
    """Whether the coefficient ``c`` is exactly 0.  ``c == 0`` is exact for rationals and,
    for arb balls, true only for the exact ball 0 — unlike ``c != 0``, which is false for
    every ball that contains 0 and would drop a term whose coefficient may be nonzero."""
    return bool(c == 0)


@dataclass(frozen=True)
class ParameterFields:
    """A field f(x; p) whose real parameters p_j are known only to lie in balls [m_j ± r_j]:
    ``mid`` = f(·; m) at the (dyadic) midpoints, with exact rational coefficients, and
    ``units[j]`` ⊇ ∂f/∂p_j(·; p) for every p in the boxes (a :class:`QuadraticField` whose
    coefficients are exact rationals when f is affine in p — e.g. the unit fields of the
    Lie–Poisson blocks — and arb balls over the boxes otherwise); ``radii[j]`` = r_j > 0
    (an exact arb); ``names[j]`` names p_j (``'a_2'``).  The Lohner enclosure
    (:mod:`exact_khk.studies.enclosure`) carries δ_j = p_j − m_j as coordinates."""

    mid: "QuadraticField"
    units: tuple
    radii: tuple
    names: tuple


@dataclass(frozen=True, eq=False)
class QuadraticField:
    """A quadratic vector field on K^dim.

    ``quad[i]``: tuple of ``((j, k), coef)`` with ``j <= k`` meaning
    ``f_i += coef * x_j * x_k``; ``linear[i]``: tuple of ``(j, coef)``;
    ``const[i]``: the constant term.  ``label`` is a short human name.
    """

    dim: int
    quad: tuple
    linear: tuple
    const: tuple
    label: str = "f"
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def from_tensor(cls, T, linear=None, const=None, label="f"):
        """From ``T[i][j][k]`` = coefficient of ``x_j x_k`` in ``f_i`` (need not be symmetric)."""
        N = len(T)
        quad = []
        for i in range(N):
            if len(T[i]) != N or any(len(row) != N for row in T[i]):
                raise InputError(f"tensor: component {i} is not {N}x{N}")
            terms = {}
            for j in range(N):
                for k in range(N):
                    c = T[i][j][k]
                    if not certainly_zero(c):
                        key = (min(j, k), max(j, k))
                        terms[key] = terms.get(key, 0) + c
            quad.append(tuple((key, c) for key, c in sorted(terms.items()) if not certainly_zero(c)))
        lin = tuple(tuple((j, c) for j, c in enumerate(row) if not certainly_zero(c)) for row in linear) \
            if linear is not None else tuple(() for _ in range(N))
        cst = tuple(const) if const is not None else tuple(0 for _ in range(N))
        if len(lin) != N or len(cst) != N:
            raise InputError("field: linear part and constant must have the dimension of the tensor")
        return cls(N, tuple(quad), lin, cst, label)

    def terms(self) -> tuple:
        """The quadratic terms ``quad`` (subclasses may build them on demand)."""
        return self.quad

    def circulant_structure(self, cyclotomic=False):
        """The :class:`~exact_khk.systems.lie_poisson.circulant.CirculantStructure` of a field whose
        step's four n×n blocks are circulant (declared by the field), or None;
        ``cyclotomic``: blocks with entries in Q(ζ) count too."""
        return None

    def structured_steps(self, ar, method, eps):
        """What a :class:`~exact_khk.kahan.map.KahanMap` solves its steps by besides the dense
        solve, for ``method`` 'auto', 'structured' or 'split' and ε = ``eps`` (an element of
        ``ar``): an object with ``split``, ``structure``, ``step(x, eps, ar)``
        and ``split_system(kernel, p, q)`` (a family's fast steps, e.g.
        :class:`~exact_khk.systems.lie_poisson.steps.CirculantSteps`), or None: every step
        dense.  A field without such steps (this default) refuses 'structured' and 'split'."""
        if method in ("structured", "split"):
            raise InputError(f"method: {method!r} needs a field whose Jacobian blocks are circulant "
                             f"(Lie–Poisson fields); this field's steps are solved densely ('auto', 'dense')")
        return None

    @property
    def homogeneous(self) -> bool:
        """True when f is a homogeneous quadratic (no linear or constant part)."""
        return all(not row for row in self.linear) and all(certainly_zero(c) for c in self.const)

    def _converted(self, ar):
        """Coefficients in ``ar``: f-terms, Jacobian linear forms, linear part, constants."""
        hit = self._cache.get(ar.name)
        if hit is not None:
            return hit
        conv = ar.convert
        with ar.local():  # ball coefficients are summed at the arithmetic's precision
            fterms = [[(j, k, conv(c)) for (j, k), c in terms] for terms in self.terms()]
            jac = [[{} for _ in range(self.dim)] for _ in range(self.dim)]
            for i, terms in enumerate(self.terms()):
                for (j, k), c in terms:  # d/dx_j (c x_j x_k) = c x_k, and symmetrically
                    jac[i][j][k] = jac[i][j].get(k, 0) + c
                    jac[i][k][j] = jac[i][k].get(j, 0) + c
            jterms = [[[(k, conv(c)) for k, c in sorted(d.items()) if not certainly_zero(c)] for d in row]
                      for row in jac]
            lin = [[(j, conv(c)) for j, c in row] for row in self.linear]
            cst = [conv(c) for c in self.const]
        out = (fterms, jterms, lin, cst)
        self._cache[ar.name] = out
        return out

    def evaluate(self, ar, x):
        """f(x) as a list of elements of ``ar`` (x: a sequence of ``dim`` of them)."""
        if not hasattr(x, "__len__") or len(x) != self.dim:
            got = f"{len(x)}" if hasattr(x, "__len__") else _short(x)
            raise InputError(f"x: expected {self.dim} coordinates, got {got}")
        fterms, _, lin, cst = self._converted(ar)
        out = []
        for i in range(self.dim):
            s = cst[i]
            for j, k, c in fterms[i]:
                s = s + c * x[j] * x[k]
            for j, c in lin[i]:
                s = s + c * x[j]
            out.append(s)
        return out

    def _forms(self, ar, x, e=None):
        """The N² affine forms of f'(x) (``e`` None) or of I − e·f'(x), evaluated at x by the
        arithmetic's ``linear_forms``/``apply_forms`` (prepared once per e, cached), as rows."""
        N = self.dim
        key = ("affine forms", ar.name, None if e is None else ar.format(e))
        if key not in self._cache:
            _, jterms, lin, _ = self._converted(ar)
            scale = (lambda c: c) if e is None else (lambda c: -e * c)
            consts = [[ar.zero if e is None or i != j else ar.one for j in range(N)] for i in range(N)]
            for i in range(N):
                for j, c in lin[i]:
                    consts[i][j] = consts[i][j] + scale(c)
            self._cache[key] = ar.linear_forms([[(k, scale(c)) for k, c in jterms[i][j]]
                                                for i in range(N) for j in range(N)],
                                               [c for row in consts for c in row], N)
        vals = ar.apply_forms(self._cache[key], x)
        return [vals[i * N:(i + 1) * N] for i in range(N)]

    def jacobian(self, ar, x):
        """f'(x) as a list of rows of elements of ``ar`` (N² linear forms in x, all at once
        where the arithmetic offers ``linear_forms``: e.g. integer matrix products for ``cyclo:N``)."""
        if ar.linear_forms is not None and coefficients_native(ar):
            return self._forms(ar, x)
        _, jterms, lin, _ = self._converted(ar)
        rows = []
        for i in range(self.dim):
            row = []
            for j in range(self.dim):
                s = ar.zero
                for k, c in jterms[i][j]:
                    s = s + c * x[k]
                row.append(s)
            for j, c in lin[i]:
                row[j] = row[j] + c
            rows.append(row)
        return rows

    def step_matrix(self, ar, x, e):
        """I − e·f'(x), the matrix of a Kahan step with step size e (an element of ``ar``):
        N² affine forms in x, all at once where the arithmetic offers ``linear_forms``
        (prepared once per e), else from :meth:`jacobian` entry by entry."""
        if ar.linear_forms is not None and coefficients_native(ar):
            return self._forms(ar, x, e)
        N, Jf = self.dim, self.jacobian(ar, x)
        return [[(ar.one if i == j else ar.zero) - e * Jf[i][j] for j in range(N)] for i in range(N)]

    def _rational_jacobian(self):
        """(H, L, c, den): H[i][j][k] = ∂²f_i/∂x_j∂x_k, L, c as Fractions, and den
        the common denominator of H and L (cached)."""
        hit = self._cache.get("ratjac")
        if hit is None:
            N = self.dim
            H = [[[Fraction(0)] * N for _ in range(N)] for _ in range(N)]
            for i, terms in enumerate(self.terms()):
                for (j, k), c in terms:
                    H[i][j][k] += _as_fraction(c)
                    H[i][k][j] += _as_fraction(c)
            L = [[Fraction(0)] * N for _ in range(N)]
            for i, row in enumerate(self.linear):
                for j, c in row:
                    L[i][j] += _as_fraction(c)
            den = lcm(1, *(t.denominator for plane in H for row in plane for t in row),
                      *(t.denominator for row in L for t in row))
            hit = self._cache["ratjac"] = (H, L, [_as_fraction(c) for c in self.const], den)
        return hit

    def integer_system(self, kernel, p, q):
        """``(V, R)``: the Kahan system at ε = p/q as two integer tensors in ``kernel``'s form.

        For x = xi/dx (integers) and v = [xi, dx], with D = q·den·dx
        (den: the common denominator of f's coefficients),

        * ``V · v`` is vec(D·(I − ε f'(x))), row-major (N² rows; ``V`` is
          stored by :meth:`~exact_khk.arith.IntegerKernel.square_tensor` and
          ``kernel.square(V, v)`` gives the N×N matrix);
        * ``R · v`` is D·((I + εL)x + 2εc) (N rows),

        so the Kahan step x̃ = (I − εf'(x))^{-1}((I + εL)x + 2εc) — equal to
        x + 2ε(I − εf'(x))^{-1} f(x), since f'(x)x = 2Q(x) + Lx — is one
        integer solve.  For homogeneous f, R · v = q·den·xi.  Cached for the
        last few (kernel, ε).  The rows are :meth:`integer_tensor_rows` (a field that
        knows a cheaper form of them overrides that).
        """
        def build(p, q):
            V, R = self.integer_tensor_rows(p, q)
            return kernel.square_tensor(V), kernel.tensor(R)

        return self.cached_system(("intsys", kernel.name), int(p), int(q), build)

    def integer_tensor_rows(self, p, q):
        """``(V, R)`` of :meth:`integer_system` as integer rows over [xi, dx] (N² and N rows,
        up to one common factor): :meth:`integer_rows`, the O(n³) rational Jacobian."""
        return self.integer_rows(p, q)

    def integer_rows(self, p, q):
        """(V, R) of :meth:`integer_system` as plain lists of integer rows (N² and N
        rows of N + 1 integers, acting on [xi, dx])."""
        def build(p, q):
            H, L, c, den = self._rational_jacobian()
            den = lcm(den, *(t.denominator for t in c))
            N = self.dim
            V = [[int(-p * den * t) for t in H[i][j]] + [int(den * (q * (i == j) - p * L[i][j]))]
                 for i in range(N) for j in range(N)]
            R = [[int(den * (q * (i == k) + p * L[i][k])) for k in range(N)] + [int(2 * p * den * c[i])]
                 for i in range(N)]
            return V, R

        return self.cached_system("introws", int(p), int(q), build)

    def cached_system(self, key, p, q, build):
        """``build(p, q)`` for ε = p/q, cached under ``key`` for the last few ε (a
        scan over many ε must not grow the cache without bound)."""
        systems = self._cache.setdefault(key, {})
        hit = systems.get((p, q))
        if hit is None:
            if len(systems) >= 8:
                systems.pop(next(iter(systems)))
            hit = systems[(p, q)] = build(p, q)
        return hit
