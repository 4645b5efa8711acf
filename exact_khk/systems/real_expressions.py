"""System files with real parameters: ``exact-khk enclose --system FILE --param NAME=REAL``.

A system file's ``[parameters]`` are exact rationals substituted at parse time
(:mod:`.expressions`).  :class:`RealExpressionSystem` overrides some of them by reals
(:func:`~exact_khk.arith.reals.parse_real` syntax: ``sqrt(2)``, ``[1.9,2.1]``,
``2+-1e-6``) read as arb balls at P bits, and re-reads the field's components with
the overridden parameters p as extra polynomial generators: each component is
num(x, p)/den(p), and the coefficient of each monomial x^m is a polynomial c_m(p)
divided by den(p) (rationals; a denominator that involves x, or a term of degree
above 2 in x for symbolic p, is refused).  Evaluated in arb over the parameter
balls, each coefficient ball contains c_m(p)/den(p) for every p in the boxes; a
denominator whose ball may be 0 is refused (InputError).

The components come from the file's ``[field]``, or, for a file that gives its field by
``[hamiltonian]`` only, from its K and H, re-read the same way: H = h(x, p)/d(p) and
K_ij = k_ij(p)/e_ij(p), and f_i = Σ_j K_ij (∂h/∂x_j)/d (the numerator differentiated in
the ring), one num/den per component.  Refused there too (one-line InputError): an entry
of K or a denominator of H that involves x, and a K that is skew at the file's values
only (K_ij + K_ji must vanish for every p).  From the components on, both sources take
the same path.

:meth:`~RealExpressionSystem.parameter_fields` gives the field at the midpoints
(exact rationals: c(m)/den(m)) and ∂f/∂p_j, whose coefficients
(∂c·den − c·∂den)/den² are evaluated in balls over the boxes (exact rationals
when f is affine in p), so the Lohner enclosure carries the parameters of nonzero
radius as coordinates (:mod:`exact_khk.studies.enclosure`).

Integrals: those whose text does not mention an overridden parameter are kept
(their values do not depend on it); the others are skipped, with the reason in
:attr:`~RealExpressionSystem.skipped` and in :meth:`describe` (the file claims them
for its own parameter values only, and an integral is never evaluated at other
values).  Poisson tensors, other fields and controls are not carried over: this
system serves ``enclose`` only.

>>> from exact_khk.systems.catalogue import resolve
>>> s = RealExpressionSystem.from_assignments(resolve("euler-top"), ["a3=[2.9,3.1]"], 64)
>>> s.field("f").terms()[2]
(((0, 1), [3e+0 +/- 0.101]),)
>>> sorted(s.integrals()), sorted(s.skipped)
(['H12'], ['H23', 'H31'])
>>> s = RealExpressionSystem.from_assignments(resolve("cmoq-cubic"), ["a=[0.9,1.1]"], 64)  # [hamiltonian] only
>>> s.field("f").terms()[3]  # p2' = -dH/dq2 = -q2 - a q1^2 - a q2^2
(((0, 0), [-1e+0 +/- 0.101]), ((1, 1), [-1e+0 +/- 0.101]))
"""

from __future__ import annotations

import re
from fractions import Fraction

import flint

from ..arith import check_precision, get_arith
from ..errors import InputError
from .base import System
from .expression_parser import Parser, cancel, frac, ring, short, terms, text_of
from .expressions import EPS, ExpressionSystem, quadratic_field_from_terms
from .quadratic import ParameterFields, certainly_zero

_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class RealExpressionSystem(System):
    """A system file's system with some parameters real (arb balls at ``prec`` bits); build
    it with :meth:`from_assignments`.  Only the field ``'f'`` (ball coefficients) and the
    integrals that do not mention an overridden parameter."""

    kind = "expressions-real"

    def __init__(self, base: ExpressionSystem, values: dict, prec: int = 256):
        self.prec = check_precision("ball", prec)
        self.base, self.values = base, dict(values)
        self.name, self.variables, self.dim = base.name, base.variables, base.dim
        self.default_x0, self.default_eps = base.default_x0, base.default_eps
        self.default_steps = base.default_steps
        spec = base.to_json()
        self._ring_and_table()
        self._rows = (self._read(spec["field"]) if "field" in spec else
                      self._read_hamiltonian(spec["hamiltonian"]))
        with flint.ctx.workprec(self.prec):
            self._field = self._ball_field()
        self._integrals, self.skipped = {}, {}
        for name, fn in base.integrals().items():
            used = sorted(set(_WORD.findall(spec.get("integrals", {}).get(name, ""))) & set(values))
            if used:
                self.skipped[name] = (f"mentions the real parameter{'s' * (len(used) > 1)} {', '.join(used)} "
                                      f"(claimed for the file's values only)")
            else:
                self._integrals[name] = fn

    @classmethod
    def from_assignments(cls, base, assignments, prec: int = 256, option: str = "--param"):
        """From ``['NAME=REAL', ...]``: each NAME a declared parameter of ``base``, given once."""
        from exact_khk.arith.reals import parse_real

        if not isinstance(base, ExpressionSystem):
            raise InputError(f"{option}: needs a system file (--system FILE or a catalogue name); the Lie–Poisson "
                             f"blocks take reals in --a/--b/--c")
        declared = ", ".join(base.parameters) or "none"
        values = {}
        for item in assignments:
            name, eq, text = str(item).partition("=")
            name = name.strip()
            if not eq or not name or not text.strip():
                raise InputError(f"{option}: expected NAME=REAL, got {str(item)[:80]!r}")
            if name not in base.parameters:
                raise InputError(f"{option}: {base.name} has no parameter {name!r} (declared: {declared})")
            if name in values:
                raise InputError(f"{option}: {name} is given twice")
            values[name] = parse_real(text, prec, f"{option} {name}")
        if not values:
            raise InputError(f"{option}: expected at least one NAME=REAL")
        return cls(base, values, prec)

    # --- the field, re-read with the overridden parameters as generators -------------

    def _ring_and_table(self):
        """The ring Q[x, ε, p] of the re-read texts (the overridden parameters p as generators),
        the names a text may use (x, p, and the other parameters at their rational values) and
        the refused ones (ε)."""
        N = self.dim
        self._R = ring((*self.variables, EPS, *self.values))
        gens = self._R.gens()
        self._table = dict(zip(self.variables, gens[:N]), **dict(zip(self.values, gens[N + 1:])))
        self._table.update({p: self._R.constant(flint.fmpq(q.numerator, q.denominator))
                            for p, q in self.base.parameters.items() if p not in self.values})
        self._refused = {EPS: "eps is not allowed here: it is the step size, and a vector field does not depend "
                              "on it"}

    def _parse(self, text, where):
        """(num, den) of ``text`` in the ring, in lowest terms."""
        return Parser(text, where, self._R, self._table, self._refused, "a name of the file").value

    def _free_of_x(self, poly, where, what):
        """Refuse a ring polynomial (a denominator, or an entry of K) that involves x."""
        if any(any(m[:self.dim + 1]) for m, _ in terms(poly)):
            raise InputError(f"{where}: with real {', '.join(self.values)}, {what} {text_of(poly)} depends on "
                             f"the variables")

    def _row(self, num, den, where):
        """One component num(x, p)/den(p) as ({x-exponents: coefficient c_m(p)}, den(p))."""
        N, R = self.dim, self._R
        self._free_of_x(den, where, "the denominator")
        coefs = {}
        for m, c in terms(num):
            if sum(m[:N]) > 2:
                raise InputError(f"{where}: with real {', '.join(self.values)}, the field has a term of degree "
                                 f"{sum(m[:N])} in the variables (the file's values cancel it)")
            coefs[m[:N]] = coefs.get(m[:N], R.from_dict({})) + R.from_dict({(0,) * (N + 1) + m[N + 1:]: c})
        return coefs, den

    def _read(self, texts):
        """Per component of a [field]: ({x-exponents: coefficient c_m(p)}, den(p)) as ring
        polynomials in the parameters (the ring's generators are x, ε, p)."""
        return [self._row(*self._parse(texts[v], f"{self.name}: field {v}"), f"{self.name}: field {v}")
                for v in self.variables]

    def _read_hamiltonian(self, spec):
        """The rows of f = K∇H from a [hamiltonian] (``{"K": matrix of texts, "H": text}``):
        H = h(x, p)/d(p) and K_ij = k_ij(p)/e_ij(p), so f_i = Σ_j K_ij (∂h/∂x_j)/d; the
        denominators d and e_ij, and K, must not involve x, and K must be skew for every p."""
        N, R, at = self.dim, self._R, f"{self.name}: hamiltonian"
        h, d = self._parse(spec["H"], f"{at} H")
        self._free_of_x(d, f"{at} H", "the denominator")
        K = [[self._parse(e, f"{at} K[{i}][{j}]") for j, e in enumerate(row)] for i, row in enumerate(spec["K"])]
        for i, row in enumerate(K):
            for j, (k, e) in enumerate(row):
                self._free_of_x(k, f"{at} K[{i}][{j}]", "the numerator")
                self._free_of_x(e, f"{at} K[{i}][{j}]", "the denominator")
                if j >= i and (k * K[j][i][1] + K[j][i][0] * e):
                    raise InputError(f"{at} K: K[{j}][{i}] = {short(spec['K'][j][i])} is not minus K[{i}][{j}] = "
                                     f"{short(spec['K'][i][j])} for every {', '.join(self.values)} (K must be "
                                     f"skew-symmetric)")
        grad = [h.derivative(i) for i in range(N)]
        rows = []
        for v, row in zip(self.variables, K):
            num, den = R.from_dict({}), R.constant(1)  # Σ_j k_ij/e_ij ∂h/∂x_j over a common denominator
            for (k, e), g in zip(row, grad):
                if k and g:
                    num, den = cancel(num * e + k * g * den, den * e)
            rows.append(self._row(*cancel(num, den * d), f"{self.name}: field {v} = (K grad H)_{v}"))
        return rows

    def _evaluate(self, poly, point, convert):
        """poly(p) at the point (arb balls or Fractions; ``convert`` maps a rational coefficient)."""
        out = convert(Fraction(0))
        for m, c in terms(poly):
            term = convert(frac(c))
            for t, k in zip(point, m[self.dim + 1:]):
                for _ in range(k):  # not t ** k: arb's power of a ball with negative points is nan
                    term = term * t
            out = out + term
        return out

    def _fields(self, rule, label):
        """The QuadraticField whose coefficient of x^m in component v is rule(v, den_v)(c_m),
        without the exactly zero ones (e.g. ∂c/∂p_j of a c free of p_j): ``rule`` does the work
        that depends on the component's denominator once."""
        rows = []
        for v, (coefs, den) in zip(self.variables, self._rows):
            coefficient = rule(v, den)
            rows.append([(m, t) for m, t in ((m, coefficient(c)) for m, c in coefs.items()) if not certainly_zero(t)])
        return quadratic_field_from_terms(rows, label)

    def _ball_field(self):
        balls, ball = list(self.values.values()), get_arith(f"ball:{self.prec}").convert

        def rule(v, den):
            d = self._evaluate(den, balls, ball)
            if d.contains(0):
                raise InputError(f"--param: field {v}: its denominator {text_of(den)} may be 0 for the given "
                                 f"{', '.join(self.values)} (it lies in {d.str(5, radius=True)})")
            return lambda c: self._evaluate(c, balls, ball) / d

        return self._fields(rule, "f")

    def parameter_fields(self, kind: str = "f"):
        """f as a :class:`~exact_khk.systems.quadratic.ParameterFields` in the overridden
        parameters of nonzero radius (None when every one is a point): the field at the
        midpoints (exact), and for each parameter ∂f/∂p_j = (∂c·den − c·∂den)/den² in balls
        over the boxes (None if such a ball is not finite: the box is too wide for
        midpoint-radius arithmetic, e.g. den² over s ∈ [1/2, 3/2])."""
        from exact_khk.arith.ball import ball_mid

        free = [j for j, b in enumerate(self.values.values()) if not b.rad().is_zero()]
        if kind != "f" or not free:
            return None
        balls, ball = list(self.values.values()), get_arith(f"ball:{self.prec}").convert
        mids = [Fraction(int(q.p), int(q.q)) for q in map(ball_mid, balls)]
        with flint.ctx.workprec(self.prec):
            def at_mids(_, den):
                d = self._evaluate(den, mids, Fraction)
                return lambda c: self._evaluate(c, mids, Fraction) / d

            mid = self._fields(at_mids, "f")

            def derivative(g):  # g: the index of the parameter's generator in the ring
                def rule(_, den):  # (∂c·den − c·∂den)/den², the denominator's parts once per component
                    dg, square = den.derivative(g), self._evaluate(den ** 2, balls, ball)
                    return lambda c: self._evaluate(c.derivative(g) * den - c * dg, balls, ball) / square
                return rule

            units = tuple(self._fields(derivative(self.dim + 1 + j), f"df/d{list(self.values)[j]}") for j in free)
        if not all(c.is_finite() for u in units for terms in u.terms() for _, c in terms):
            return None  # a box so wide that a derivative is unbounded in balls: the ball field alone
        return ParameterFields(mid, units, tuple(flint.arb(balls[j].rad()) for j in free),
                               tuple(list(self.values)[j] for j in free))

    # --- the System interface -------------------------------------------------------------

    def field(self, name: str = "f"):
        if name != "f":
            raise InputError(f"{self.name}: with real parameters only the field 'f' is available")
        return self._field

    def integrals(self) -> dict:
        return dict(self._integrals)

    def random_point(self, seed: int, bound: int = 3) -> tuple:
        return self.base.random_point(seed, bound)

    def describe(self) -> str:
        real = ", ".join(f"{k} = {v.str(10, radius=True)}" for k, v in self.values.items())
        kept = ", ".join(self._integrals) or "none"
        skipped = "".join(f"; integral {k} skipped: it {why}" for k, why in self.skipped.items())
        return (f"{self.name}: {self.base.title or 'quadratic system'} (dimension {self.dim}) with real parameters "
                f"(arb balls at {self.prec} bits) {real}; integrals kept: {kept}{skipped}")

    def to_json(self) -> dict:
        return dict(self.base.to_json(), real_parameters={k: v.str(30, radius=True) for k, v in self.values.items()},
                    prec=self.prec, skipped_integrals=dict(self.skipped))
