"""Systems written as expressions: system files (TOML) and the Python equivalent.

A system file (see ``docs/system-files.md``) gives a quadratic vector field f on
Q^N componentwise, f_i = Σ_{j≤k} q_ijk x_j x_k + Σ_j l_ij x_j + c_i, together with
claimed integrals I(x, ε), a Poisson tensor Π(x, ε), commuting fields, a
Hamiltonian form f = K∇H and negative controls.  Everything is exact: decimal
literals are rationals (0.1 = 1/10) and parameters are substituted as rationals.

Expressions are read by the safe parser of :mod:`.expression_parser` (never by
``eval``): only the declared names, ``eps``, numbers, ``+ - * / **`` and
parentheses, with bounded exponents and a bounded amount of work.

>>> s = ExpressionSystem.from_expressions(["x1", "x2"], field=["x1*x2", "-x1*x2 + x2"],
...                                       integrals={"I": "x1 + x2 - log_x2"})
Traceback (most recent call last):
...
exact_khk.errors.InputError: integrals I: unknown name 'log_x2' at position 10 (allowed: variables x1, x2; eps)
>>> s = ExpressionSystem.from_expressions(["x", "y"], field=["y", "-x"], integrals={"H": "x**2 + y**2"})
>>> s.field("f").evaluate(get_arith("fraction"), [Fraction(1), Fraction(2)])
[Fraction(2, 1), Fraction(-1, 1)]
>>> s.integrals()["H"](get_arith("fraction"), [Fraction(1), Fraction(2)], Fraction(1, 10))
Fraction(5, 1)
>>> ExpressionSystem.from_json(s.to_json()).to_json() == s.to_json()
True
"""

from __future__ import annotations

import re
from decimal import Decimal
from fractions import Fraction

import flint

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from ..arith import _as_fraction, get_arith
from ..errors import InputError
from ..parsing import read_text_file
from .base import System
from .expression_parser import (CONSTANTS, Parser, checked_polynomial, frac, lc, number_text, ring, short, terms,
                                text_of, to_polynomial)
from .functions import PolynomialTensor, RationalFunction
from .quadratic import QuadraticField

MAX_FILE = 10_000_000     # bytes in a system file
#: variables in a system file: the polynomial ring of N variables holds N² exponents (10 000: about
#: 0.1 GB and a second; 100 000 exhausts FLINT's memory, which aborts the process), and each step
#: solves N×N systems (the commands refuse beyond a few hundred variables at 4 GB)
MAX_VARIABLES = 10_000
EPS = "eps"
CLAIMS = ("reversibility", "integrals", "poisson", "commutation", "jacobian", "cmoq", "measure")
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_SYSTEM_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._:=,-]*\Z")  # ':', '=', ',' name a family member


def _quadratic_field(polys, label: str) -> QuadraticField:
    """The QuadraticField with f_i = polys[i] (ring polynomials of degree <= 2, no ε)."""
    return quadratic_field_from_terms([[(m[:-1], frac(c)) for m, c in terms(p)] for p in polys], label)


def quadratic_field_from_terms(rows, label: str) -> QuadraticField:
    """The QuadraticField with f_i = Σ c x^m over the (exponent tuple m, coefficient c) pairs
    of rows[i] (total degree <= 2; coefficients exact rationals or arb balls)."""
    quad, lin, const = [], [], []
    for row in rows:
        q, l, c = [], [], Fraction(0)
        for m, coef in row:
            idx = tuple(i for i, k in enumerate(m) for _ in range(k))
            if len(idx) == 2:
                q.append((idx, coef))
            elif len(idx) == 1:
                l.append((idx[0], coef))
            else:
                c = coef
        quad.append(tuple(sorted(q, key=lambda t: t[0])))
        lin.append(tuple(sorted(l, key=lambda t: t[0])))
        const.append(c)
    return QuadraticField(len(rows), tuple(quad), tuple(lin), tuple(const), label)


def _fmpq(q) -> flint.fmpq:
    """An exact rational (int or Fraction) as a flint fmpq."""
    q = Fraction(q)
    return flint.fmpq(q.numerator, q.denominator)


def _rational(value, where: str) -> Fraction:
    """An exact rational from an int, Fraction, TOML decimal or a constant expression string."""
    if isinstance(value, (int, Fraction)) and not isinstance(value, bool):
        return Fraction(value)
    if isinstance(value, Decimal):
        if not value.is_finite():
            raise InputError(f"{where}: {value} is not a rational number")
        return Fraction(value)
    if isinstance(value, str):
        num, den = Parser(value, where, CONSTANTS, {}, {}, "a rational number is expected here").value
        return frac(lc(num)) / frac(lc(den))
    if isinstance(value, float):
        raise InputError(f"{where}: {value!r} is a binary float; write it as a string such as '1/10'")
    raise InputError(f"{where}: expected a rational number (a string such as '1/3'), got {value!r}")


def _spec_value(value, where: str):
    """A number or expression as stored in the JSON form: a string."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        raise InputError(f"{where}: expected a string, got {value!r}")
    if isinstance(value, Decimal):
        return number_text(_rational(value, where))
    if isinstance(value, (int, Fraction)) or hasattr(value, "numerator") or hasattr(value, "p"):
        return number_text(_as_fraction(value))  # also gmpy2 mpq, flint fmpq
    raise InputError(f"{where}: expected a string, got {value!r} ({type(value).__name__})")


def _table(value, where: str) -> dict:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise InputError(f"{where}: expected a table (name = value), got {type(value).__name__}")
    return value


def _matrix(value, N: int, where: str) -> list:
    if not isinstance(value, (list, tuple)) or len(value) != N or any(
            not isinstance(row, (list, tuple)) or len(row) != N for row in value):
        raise InputError(f"{where}: expected a {N}x{N} matrix (a list of {N} rows of {N} entries)")
    return [[_spec_value(e, f"{where}[{i}][{j}]") for j, e in enumerate(row)] for i, row in enumerate(value)]


def _components(value, variables, where: str) -> dict:
    """A field given as {variable: expression} or as a list in variable order."""
    if isinstance(value, (list, tuple)):
        if len(value) != len(variables):
            raise InputError(f"{where}: expected {len(variables)} components (one per variable), got {len(value)}")
        value = dict(zip(variables, value))
    value = _table(value, where)
    missing = [v for v in variables if v not in value]
    known = set(variables)
    extra = [k for k in value if k not in known]
    if missing or extra:
        raise InputError(f"{where}: " + "; ".join(
            ([f"missing component(s) {', '.join(missing)}"] if missing else []) +
            ([f"unknown component(s) {', '.join(map(str, extra))}"] if extra else [])) +
            f" (one component per variable: {', '.join(variables)})")
    return {v: _spec_value(value[v], f"{where} {v}") for v in variables}


def _read_literature(table, where: str) -> dict:
    """The [literature] table: strings under :data:`LITERATURE_KEYS`; ``integrable`` is
    "yes", "no" or "unknown", ``integrals`` a count (an integer >= 0) or "unknown"."""
    table = _table(table, where)
    extra = [k for k in table if k not in LITERATURE_KEYS]
    if extra:
        raise InputError(f"{where}: unknown key(s) {', '.join(map(repr, extra))} (known: {', '.join(LITERATURE_KEYS)})")
    for k, v in table.items():
        ok = (v in ("yes", "no", "unknown") if k == "integrable" else
              (v == "unknown" or isinstance(v, int) and not isinstance(v, bool) and v >= 0) if k == "integrals" else
              isinstance(v, str))
        if not ok:
            want = {"integrable": "'yes', 'no' or 'unknown'",
                    "integrals": "a count (an integer >= 0) or 'unknown'"}.get(k, "a string")
            raise InputError(f"{where} {k}: expected {want}, got {v!r}"[:300])
    return dict(table)


# --- the system ----------------------------------------------------------------------

_KEYS = ("format", "kind", "name", "title", "source", "variables", "parameters", "field", "fields",
         "integrals", "poisson", "hamiltonian", "controls", "measure", "defaults", "claims", "literature")
#: [literature]: what the literature claims about the Kahan map (not the ODE); text, never checked
LITERATURE_KEYS = ("reference", "integrable", "integrals", "measure", "poisson", "notes")
_NEEDS = {"integrals": "integrals", "poisson": "poisson", "commutation": "fields", "cmoq": "hamiltonian",
          "measure": "measure"}


class ExpressionSystem(System):
    """A quadratic system given by expressions (a system file, or Python strings).

    Build it with :meth:`from_expressions`, :meth:`from_toml`, :meth:`from_json`
    or :func:`load_system`; every input error is an :class:`InputError` naming
    the key at fault.  :meth:`to_json` keeps the original strings, so
    ``from_json(to_json())`` rebuilds the same system.
    """

    kind = "expressions"

    def __init__(self, table: dict, origin: str = ""):
        at = (lambda key: f"{origin}: {key}") if origin else (lambda key: key)
        t = _table(table, origin or "system")
        unknown = [k for k in t if k not in _KEYS]
        if unknown:
            raise InputError(at(f"unknown key(s) {', '.join(map(repr, unknown))}; known keys: {', '.join(_KEYS)}"))
        if t.get("format", 1) != 1 or t.get("kind", self.kind) != self.kind:
            raise InputError(at(f"format {t.get('format')!r} / kind {t.get('kind')!r}: this reader "
                                f"knows format 1, kind 'expressions'"))
        for key in ("name", "variables"):
            if key not in t:
                raise InputError(at(f"missing required key {key!r}"))
        for key in ("name", "title", "source"):
            if not isinstance(t.get(key, ""), str):
                raise InputError(at(f"{key}: expected a string, got {t[key]!r}"))
        if not _SYSTEM_NAME.match(t["name"]):
            raise InputError(at(f"name: {t['name']!r} must be letters, digits, '.', '_', '-', ':', '=' or ','"))
        self.name, self.title, self.source = t["name"], t.get("title", ""), t.get("source", "")
        variables = t["variables"]
        if not isinstance(variables, (list, tuple)) or not variables:
            raise InputError(at("variables: expected a non-empty list of names"))
        if len(variables) > MAX_VARIABLES:
            raise InputError(at(f"variables: {len(variables)} variables, beyond the limit of {MAX_VARIABLES:,} "
                                f"(MAX_VARIABLES; every step solves dense N x N systems)"))
        for i, v in enumerate(variables):
            if not isinstance(v, str):
                raise InputError(at(f"variables[{i}]: expected a name (a string), got {v!r}"))
        seen = set()  # not variables.count(v): N² for N variables
        for v in variables:
            if not _NAME.match(v) or v == EPS or v in seen:
                raise InputError(at(f"variables: {v!r} is " + ("used twice" if v in seen else
                                    "reserved for the step size" if v == EPS else "not a valid name")))
            seen.add(v)
        self.variables, self.dim = tuple(variables), len(variables)
        spec = {"format": 1, "kind": self.kind, "name": self.name, "title": self.title,
                "source": self.source, "variables": list(variables)}
        self._spec, self._at = spec, at

        params = _table(t.get("parameters"), at("parameters"))
        for p in params:
            if not isinstance(p, str) or not _NAME.match(p) or p == EPS or p in variables:
                raise InputError(at(f"parameters: {p!r} is " + ("the name of a variable" if p in variables else
                                    "reserved for the step size" if p == EPS else "not a valid name")))
        self.parameters = {p: _rational(v, at(f"parameters {p}")) for p, v in params.items()}
        if params:
            spec["parameters"] = {p: _spec_value(v, at(f"parameters {p}")) for p, v in params.items()}
        self._ring = ring((*variables, EPS))
        gens = self._ring.gens()
        self._eps = gens[-1]
        self._values = {p: self._ring.constant(flint.fmpq(q.numerator, q.denominator))
                        for p, q in self.parameters.items()}
        self._names = dict(zip(variables, gens), **self._values)
        self._scopes = {}

        self._fields, self._hamiltonian = {}, None
        f = self._read_hamiltonian(t.get("hamiltonian"))
        if "field" in t:
            spec["field"] = _components(t["field"], variables, at("field"))
            exprs = self._read_field(spec["field"], "field")
            for i, v in enumerate(variables):
                if f is not None and exprs[i] != f[i]:
                    raise InputError(at(f"hamiltonian: field {v} = {short(spec['field'][v])} differs "
                                        f"from (K grad H)_{v} = {text_of(f[i])}"))
            f = exprs
        elif f is None:
            raise InputError(at("missing required key 'field' (or give [hamiltonian] with K and H)"))
        self._fields["f"] = _quadratic_field(f, "f")
        others = _table(t.get("fields"), at("fields"))
        for g, comps in others.items():
            if g == "f" or not isinstance(g, str) or not _NAME.match(g):
                raise InputError(at(f"fields: {g!r} is not a valid name for another field ('f' is the main one)"))
            spec.setdefault("fields", {})[g] = _components(comps, variables, at(f"fields.{g}"))
            self._fields[g] = _quadratic_field(self._read_field(spec["fields"][g], f"fields.{g}"), g)

        self._integrals, self._controls = (self._read_functions(t.get(key), key) for key in ("integrals", "controls"))
        self._poisson = self._read_poisson(t.get("poisson"))
        self._measure = self._read_measure(t.get("measure"))
        self._read_defaults(_table(t.get("defaults"), at("defaults")))
        self._read_claims(t.get("claims"))
        self.literature = _read_literature(t.get("literature"), at("literature"))
        if self.literature:
            spec["literature"] = dict(self.literature)

    # --- readers (each records the original strings in self._spec) ----------

    def _parse(self, text, where, eps=True, constant=False):
        """Parse ``text``: variables, parameters and (if ``eps``) ε allowed; only
        parameters if ``constant``."""
        return Parser(text, self._at(where), self._ring, *self._scope(eps and not constant, constant))

    def _scope(self, eps, constant):
        """(names, refused, allowed) for :meth:`_parse`, built once per kind of entry: they
        list every variable, and a file of N components must not cost N² to read."""
        if (eps, constant) not in self._scopes:
            names = dict(self._values) if constant else dict(self._names, **({EPS: self._eps} if eps else {}))
            refused = {v: f"{v} is a variable, and this entry must be constant" for v in self.variables}
            refused[EPS] = ("eps is not allowed here: it is the step size, and a vector field does not "
                            "depend on it" if not constant else "eps is not allowed in a constant")
            allowed = "; ".join(s for s in ("" if constant else "variables " + ", ".join(self.variables),
                                            "parameters " + ", ".join(self._values) if self._values else "",
                                            EPS if eps else "") if s)
            self._scopes[eps, constant] = (names, refused, "allowed: " + (allowed or "numbers only"))
        return self._scopes[eps, constant]

    def _read_field(self, comps, key):
        return [checked_polynomial(self._parse(comps[v], f"{key} {v}", eps=False), self.variables, 2,
                                    self._at(f"{key} {v}"), "a Kahan map needs a quadratic field")
                for v in self.variables]

    def _function(self, text, where, name):
        num, den = self._parse(text, where).value
        return RationalFunction(to_polynomial(num, self.dim), to_polynomial(den, self.dim), name=name, text=text)

    def _read_functions(self, table, key):
        out = {}
        for name, text in _table(table, self._at(key)).items():
            text = _spec_value(text, self._at(f"{key} {name}"))
            self._spec.setdefault(key, {})[name] = text
            out[name] = self._function(text, f"{key} {name}", name)
        return out

    def _read_poisson(self, table):
        if table is None:
            return None
        table = _table(table, self._at("poisson"))
        if set(table) != {"matrix"}:
            raise InputError(self._at("poisson: expected exactly one key, 'matrix'"))
        M = _matrix(table["matrix"], self.dim, self._at("poisson matrix"))
        self._spec["poisson"] = {"matrix": M}
        entries = [[self._function(e, f"poisson matrix[{i}][{j}]", f"Pi[{i}][{j}]") for j, e in enumerate(row)]
                   for i, row in enumerate(M)]
        return PolynomialTensor(entries, name=self._at("poisson matrix"), text=str(M))

    def _read_measure(self, table):
        """``[measure] density = "m(x, eps)"``: the density of a measure m(x) dx claimed invariant."""
        if table is None:
            return None
        table = _table(table, self._at("measure"))
        if set(table) != {"density"}:
            raise InputError(self._at("measure: expected exactly one key, 'density'"))
        text = _spec_value(table["density"], self._at("measure density"))
        self._spec["measure"] = {"density": text}
        if self._parse(text, "measure density").value[0].is_zero():  # m = 0 would "hold" at every point
            raise InputError(self._at("measure density: 0 is not the density of a measure (a nonzero function is "
                                      "needed)"))
        return self._function(text, "measure density", "m")

    def _read_hamiltonian(self, table):
        """K∇H as ring polynomials (None without [hamiltonian]); sets self._hamiltonian."""
        if table is None:
            return None
        table = _table(table, self._at("hamiltonian"))
        if set(table) != {"K", "H"}:
            raise InputError(self._at("hamiltonian: expected exactly the keys 'K' and 'H'"))
        Ks = _matrix(table["K"], self.dim, self._at("hamiltonian K"))
        Htext = _spec_value(table["H"], self._at("hamiltonian H"))
        self._spec["hamiltonian"] = {"K": Ks, "H": Htext}
        K = [[self._parse(e, f"hamiltonian K[{i}][{j}]", constant=True).value for j, e in enumerate(row)]
             for i, row in enumerate(Ks)]
        K = [[frac(lc(num)) / frac(lc(den)) for num, den in row] for row in K]
        for i in range(self.dim):
            for j in range(i, self.dim):
                if K[i][j] + K[j][i] != 0:
                    raise InputError(self._at(f"hamiltonian K: K[{j}][{i}] = {short(Ks[j][i])} is not minus "
                                              f"K[{i}][{j}] = {short(Ks[i][j])} (K must be skew-symmetric)"))
        H = checked_polynomial(self._parse(Htext, "hamiltonian H", eps=False), self.variables, 3,
                                self._at("hamiltonian H"), "H must be a polynomial of degree <= 3")
        self._hamiltonian = (tuple(map(tuple, K)),
                             RationalFunction(to_polynomial(H, self.dim), name="H", text=Htext))
        grad = [H.derivative(i) for i in range(self.dim)]
        return [sum((grad[j] * flint.fmpq(k.numerator, k.denominator) for j, k in enumerate(row)),
                    self._ring.from_dict({}))
                for row in K]

    def _read_defaults(self, table):
        extra = [k for k in table if k not in ("x0", "eps", "steps")]
        if extra:
            raise InputError(self._at(f"defaults: unknown key(s) {', '.join(map(repr, extra))} (known: x0, eps, steps)"))
        spec = {}
        self.default_eps = Fraction(1, 10)
        if "steps" in table:
            steps = table["steps"]
            if not isinstance(steps, int) or isinstance(steps, bool) or not 1 <= steps <= 10 ** 6:
                raise InputError(self._at(f"defaults steps: expected an integer from 1 to 10^6, got {steps!r}"))
            spec["steps"] = self.default_steps = steps
        if "eps" in table:
            spec["eps"] = _spec_value(table["eps"], self._at("defaults eps"))
            self.default_eps = _rational(table["eps"], self._at("defaults eps"))
            if self.default_eps == 0:
                raise InputError(self._at("defaults eps: the step size must be nonzero"))
        if "x0" in table:
            x0 = table["x0"]
            if not isinstance(x0, (list, tuple)) or len(x0) != self.dim:
                raise InputError(self._at(f"defaults x0: expected a list of {self.dim} numbers (one per "
                                          f"variable), got {x0!r}"[:200]))
            spec["x0"] = [_spec_value(v, self._at(f"defaults x0[{i}]")) for i, v in enumerate(x0)]
            self._default_x0 = tuple(_rational(v, self._at(f"defaults x0[{i}]")) for i, v in enumerate(x0))
        else:  # searched when first asked for (:attr:`default_x0`): N³ work, after the size limits
            self._default_x0 = None
        if spec:
            self._spec["defaults"] = spec

    def _read_claims(self, claims):
        present = {"integrals": self._integrals, "poisson": self._poisson,
                   "fields": len(self._fields) > 1, "hamiltonian": self._hamiltonian, "measure": self._measure}
        if claims is None:
            self.claims = tuple(c for c in CLAIMS if c not in _NEEDS or present[_NEEDS[c]])
            return
        if not isinstance(claims, (list, tuple)) or not all(isinstance(c, str) for c in claims):
            raise InputError(self._at(f"claims: expected a list of names among {', '.join(CLAIMS)}"))
        for c in claims:
            if c not in CLAIMS:
                raise InputError(self._at(f"claims: unknown claim {c!r}; known: {', '.join(CLAIMS)}"))
            if c in _NEEDS and not present[_NEEDS[c]]:
                raise InputError(self._at(f"claims: {c!r} needs a [{_NEEDS[c]}] section"))
        self.claims = tuple(dict.fromkeys(claims))
        self._spec["claims"] = list(self.claims)

    @property
    def default_x0(self) -> tuple:
        """``[defaults] x0``, else the first small random point where every declared function
        is finite and every step matrix invertible (:meth:`_regular_point`: a determinant of
        size N per field and draw, so searched only when first asked for, not while the file
        is read: a command checks the file's size first)."""
        if self._default_x0 is None:
            self._default_x0 = self._regular_point(self.default_eps)
        return self._default_x0

    def seeded_point(self, seed: int, eps=None, skip: int = 0) -> tuple:
        """The point drawn for ``--seed``: the first regular point (:meth:`_regular_point`) from ``seed`` on
        (``skip``: regular points passed over first)."""
        return self._regular_point(self.default_eps if eps is None else eps, seed, skip)

    def _regular_point(self, eps, start=0, skip=0):
        """The first small random point (seeds ``start``, ``start`` + 1, …) where every declared
        function is finite, f(x) ≠ 0 (no equilibrium: there no control can fail) and
        I − ε g'(x) is invertible for every field g (reproducible)."""
        fr = get_arith("fraction")
        fns = list(self._integrals.values()) + list(self._controls.values()) + (
            [e for row in self._poisson.entries for e in row] if self._poisson else []) + (
            [self._measure] if self._measure else [])
        for seed in range(start, start + 200):
            x = self.random_point(seed)
            if any(self._fields["f"].evaluate(fr, x)) and all(
                    not fn.den.evaluate(fr, x, eps) == 0 for fn in fns) and all(
                    flint.fmpq_mat([[_fmpq(int(i == j) - eps * t) for j, t in enumerate(row)]
                                    for i, row in enumerate(g.jacobian(fr, x))]).det() != 0
                    for g in self._fields.values()):
                if not skip:
                    return x
                skip -= 1
        return self.random_point(start)

    # --- constructors -------------------------------------------------------------

    @classmethod
    def from_expressions(cls, variables, field=None, parameters=None, integrals=None, poisson=None,
                         fields=None, hamiltonian=None, controls=None, x0=None, eps=None, claims=None,
                         name="user", title="", source="", measure=None):
        """A system from Python values: ``variables`` a list of names (or ``"x, y"``),
        ``field`` a list of expression strings in variable order (or a dict),
        ``parameters`` name -> rational, ``integrals``/``controls`` name -> expression,
        ``poisson`` an N×N matrix of expressions, ``fields`` name -> field,
        ``hamiltonian`` ``{"K": matrix, "H": expression}``, ``x0``/``eps`` rationals,
        ``claims`` a list of claim names, ``measure`` the density of an invariant measure (an expression)."""
        if isinstance(variables, str):
            variables = [v for v in re.split(r"[\s,]+", variables) if v]
        t = {"name": name, "title": title, "source": source, "variables": variables}
        for key, value in (("field", field), ("parameters", parameters), ("integrals", integrals),
                           ("fields", fields), ("hamiltonian", hamiltonian), ("controls", controls),
                           ("claims", claims)):
            if value is not None:
                t[key] = value
        if poisson is not None:
            t["poisson"] = poisson if isinstance(poisson, dict) else {"matrix": poisson}
        if measure is not None:
            t["measure"] = measure if isinstance(measure, dict) else {"density": measure}
        defaults = {k: v for k, v in (("x0", x0), ("eps", eps)) if v is not None}
        if defaults:
            t["defaults"] = defaults
        return cls(t)

    @classmethod
    def from_toml(cls, text, origin: str = "<string>"):
        """A system from the text of a system file (``origin`` names it in errors)."""
        if isinstance(text, bytes):
            text = text.decode("utf-8")
        try:
            table = tomllib.loads(text, parse_float=Decimal)
        except (tomllib.TOMLDecodeError, ValueError) as exc:
            raise InputError(f"{origin}: not valid TOML: {exc}") from None
        except RecursionError:  # tomllib reads nested arrays and tables recursively
            raise InputError(f"{origin}: arrays or tables nested too deeply to read") from None
        return cls(table, origin)

    @classmethod
    def from_json(cls, d: dict):
        """The inverse of :meth:`to_json`."""
        return cls(d)

    # --- the System interface -------------------------------------------------------

    def to_json(self) -> dict:
        """The system as a JSON-compatible dict of the original strings (see :meth:`from_json`)."""
        import copy
        return copy.deepcopy(self._spec)

    def field(self, name: str = "f") -> QuadraticField:
        if name not in self._fields:
            raise InputError(f"{self.name}: unknown field {name!r}; known: {', '.join(self._fields)}")
        return self._fields[name]

    def field_names(self) -> tuple:
        return tuple(self._fields)

    def integrals(self) -> dict:
        return dict(self._integrals)

    def controls(self) -> dict:
        return dict(self._controls)

    def poisson(self):
        return self._poisson

    def hamiltonian_form(self):
        return self._hamiltonian

    def measure(self):
        return self._measure

    def known(self) -> str:
        """What the file claims, in a few words."""
        n, others = len(self._integrals), [g for g in self._fields if g != "f"]
        return ", ".join(s for s in (
            f"{n} integral{'s' * (n != 1)}" if n else "",
            "Poisson tensor" if self._poisson else "",
            f"commuting field{'s' * (len(others) != 1)} {', '.join(others)}" if others else "",
            "Hamiltonian form f = K grad H" if self._hamiltonian else "",
            "invariant measure" if self._measure else "",
            f"{len(self._controls)} control{'s' * (len(self._controls) != 1)}" if self._controls else "") if s) or "the field only"

    def describe(self) -> str:
        return f"{self.name}: {self.title or 'quadratic system'} (dimension {self.dim}; {self.known()})"

    def __repr__(self):
        return f"<ExpressionSystem {self.describe()}>"


def load_system(path) -> ExpressionSystem:
    """Read a system file (TOML); every problem is an InputError naming the file."""
    text = read_text_file(path, "system file", MAX_FILE)
    return ExpressionSystem.from_toml(text, origin=str(path))
