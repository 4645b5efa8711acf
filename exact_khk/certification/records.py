"""Records of certification: a :class:`Check` per statement, a :class:`Certificate`
per orbit — frozen dataclasses with a JSON view; printing is a view too.

A check is a **claim** (``expected=True``: it must hold) or a **negative
control** (``expected=False``: a statement that is false for the system, so
that the check is seen to be able to fail).  ``holds`` is True/False, or None
when undecided.  A control that cannot fail at the chosen point (a degenerate
point: an equilibrium, a critical point of the integral, …) is recorded with
``applicable=False`` and the reason in ``detail``; it never makes a
certificate fail.

The verdict of a certificate:

* ``VALID`` — every claim holds, every applicable control fails, and at least
  one control is applicable;
* ``INVALID`` — some claim is decided false (the only verdict that says a
  statement about the system is wrong);
* ``INCONCLUSIVE`` — no claim is false, but a check is undecided, or a control
  did not fail (the check did not show that it can fail at this point), or no
  control is applicable at all (e.g. at an equilibrium).
"""

from __future__ import annotations

import sys
from dataclasses import asdict, dataclass, field
from fractions import Fraction

from exact_khk.errors import InputError
from exact_khk.parsing import any_int_digits

#: version of the certificate JSON (``Certificate.to_json``)
SCHEMA_VERSION = 2
#: the widest check name that sets the width of :meth:`Certificate.table`'s first column;
#: a longer name (at large n the rank check lists dozens of integrals) gets a line of its own
TABLE_NAME_WIDTH = 64


@dataclass(frozen=True)
class Check:
    """One certified statement.

    ``expected`` is True for a claim and False for a negative control;
    ``holds`` is True/False, or None when undecided; ``residual`` is the exact
    first nonzero residual ('0' if none) for exact evidence, else the measured
    largest |difference|; ``detail`` says where it was evaluated or failed;
    ``applicable`` is False for a control that cannot fail here (see module
    docstring).
    """

    name: str
    claim: str
    expected: bool
    holds: bool | None
    residual: str
    arith: str
    seconds: float
    evidence: str = "exact in Q"
    detail: str = ""
    applicable: bool = True

    @property
    def passed(self) -> bool:
        """A claim that holds, or a control that fails (decided either way); an
        inapplicable control counts as passed (it says nothing)."""
        if not self.applicable:
            return True
        return self.holds is not None and self.holds == self.expected

    @property
    def wrong(self) -> bool:
        """A claim decided false: the statement is wrong."""
        return self.expected and self.holds is False

    @property
    def status(self) -> str:
        """'ok', 'WRONG', 'UNDECIDED', 'DID NOT FAIL' or 'inapplicable'."""
        if not self.applicable:
            return "inapplicable"
        if self.passed:
            return "ok"
        if self.holds is None:
            return "UNDECIDED"
        return "WRONG" if self.expected else "DID NOT FAIL"

    @any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
    def to_json(self) -> dict:
        return asdict(self)

    @classmethod
    def from_json(cls, d: dict) -> "Check":
        """The check of :meth:`to_json`; malformed input raises InputError naming the key."""
        return _check_from_json(d, "check")


def status_of(checks) -> str:
    """``'VALID'`` when every claim of ``checks`` holds, every applicable control fails and
    at least one control is applicable; else ``'INVALID'`` if a claim is decided false, else
    ``'INCONCLUSIVE'`` (see the module docstring)."""
    if checks and all(c.passed for c in checks) and any(not c.expected and c.applicable for c in checks):
        return "VALID"
    return "INVALID" if any(c.wrong for c in checks) else "INCONCLUSIVE"


@dataclass(frozen=True)
class Certificate:
    """All checks on one orbit: the system, x0, ε, steps, arithmetic, versions.

    ``system`` is any :class:`~exact_khk.systems.base.System` (its ``to_json``
    and ``describe`` are used); ``signs`` the involutions of a Lie–Poisson
    certificate (empty otherwise); ``orbit`` the orbit points as exact strings
    and ``values`` the integrals' values on them (name -> list of strings),
    when recorded; ``path`` how the steps were solved.
    """

    system: object
    x0: tuple
    eps: Fraction
    steps: int
    arith: str
    signs: tuple
    checks: tuple
    versions: dict = field(default_factory=dict)
    seconds: float = 0.0
    height_bits: int | None = None
    orbit: tuple = ()
    values: dict = field(default_factory=dict)
    path: str = ""

    @property
    def valid(self) -> bool:
        """True iff every claim holds, every applicable control fails, and at least one
        control is applicable (otherwise nothing shows that the checks can fail here)."""
        return self.status == "VALID"

    @property
    def status(self) -> str:
        """``'VALID'``, ``'INVALID'`` or ``'INCONCLUSIVE'`` (:func:`status_of` its checks)."""
        return status_of(self.checks)

    def check(self, name: str) -> Check:
        """The check called ``name``."""
        for c in self.checks:
            if c.name == name:
                return c
        raise InputError(f"check: no check named {abbreviate(repr(name), 60)} in this certificate "
                         f"({len(self.checks)} checks; see Certificate.checks)")

    def __repr__(self):
        return (f"<Certificate {self.status}: {getattr(self.system, 'name', '?')}, {len(self.checks)} checks, "
                f"{self.steps} steps, {self.arith}>")

    def verdict(self) -> str:
        """One line: VALID / INVALID / INCONCLUSIVE, and why."""
        claims = [c for c in self.checks if c.expected]
        controls = [c for c in self.checks if not c.expected and c.applicable]
        idle = [c for c in self.checks if not c.applicable]
        where = f"{self.arith} arithmetic, {_short(self.system)}, {self.steps} steps, {self.seconds:.2f} s"
        if self.status == "VALID":
            extra = f"; {len(idle)} inapplicable" if idle else ""
            return (f"VALID: all {len(claims)} claims hold and all {len(controls)} negative controls "
                    f"fail{extra} ({where})")
        if self.status == "INVALID":
            bad = [c.name for c in self.checks if c.wrong]
            return f"INVALID: {len(bad)} claim(s) are false: {'; '.join(bad)} ({where})"
        open_ = [c.name for c in self.checks if not c.passed]
        if not self.checks:
            return f"INCONCLUSIVE: the certificate has no checks ({where})"
        if not open_:
            return (f"INCONCLUSIVE: all {len(claims)} claims hold, but no negative control can fail at this "
                    f"point ({len(idle)} inapplicable), so nothing shows that the checks can fail here ({where})")
        return (f"INCONCLUSIVE: no claim is false, but {len(open_)} check(s) are undecided or did not fail, "
                f"e.g. {open_[0]!r} ({where})")

    @any_int_digits()
    def summary(self) -> str:
        """A few lines: the system, the orbit, the verdict."""
        return "\n".join([self.system.describe(),
                          f"x0 = ({', '.join(str(t) for t in self.x0)}), eps = {self.eps}, {self.steps} steps, "
                          f"arithmetic {self.arith}" + (f", path {self.path}" if self.path else ""),
                          self.verdict()])

    def table(self) -> str:
        """A readable table: check, expected, holds, abbreviated residual, time; the claim below."""
        w = min(max(len(c.name) for c in self.checks), TABLE_NAME_WIDTH)
        kinds = [c.evidence for c in self.checks]
        common = max(set(kinds), key=kinds.count)
        lines = [f"{'check':<{w}}  {'expect':<6}  {'holds':<9}  {'residual':<24}  {'time':>7}"]
        for c in self.checks:
            holds = {True: "true", False: "false", None: "undecided"}[c.holds]
            mark = "" if c.status == "ok" else f"  <-- {c.status}"
            name = c.name
            if len(name) > w:  # a long name (e.g. the rank check listing every integral at large n)
                lines.append(name)  # on a line of its own, so that it does not widen every row
                name = ""
            lines.append(f"{name:<{w}}  {str(c.expected).lower():<6}  {holds:<9}  "
                         f"{abbreviate(c.residual):<24}  {c.seconds:>6.3f}s{mark}")
            lines.append(f"    {c.claim}" + (f" [{c.detail}]" if c.detail else "")
                         + (f" (evidence: {c.evidence})" if c.evidence != common else ""))
        lines.append(f"evidence, unless stated: {common}")
        return "\n".join(lines)

    @classmethod
    def from_json(cls, d: dict) -> "Certificate":
        """The certificate of :meth:`to_json` (schema version 2), rebuilt: the system by
        ``LiePoissonSystem.from_json`` (a ``"family"`` key) or ``ExpressionSystem.from_json``,
        the checks by :meth:`Check.from_json`.  The derived keys (``status``, ``valid``,
        ``verdict``) are not read: they follow from the checks (re-checking them is the
        business of :func:`exact_khk.certification.verify.verify`).  Malformed input
        raises :class:`~exact_khk.errors.InputError` naming the key.

        >>> from exact_khk.certification.lie_poisson import certify
        >>> cert = certify(steps=2, signs=["-++"])
        >>> again = Certificate.from_json(cert.to_json())
        >>> again.to_json() == cert.to_json()
        True
        >>> Certificate.from_json({"schema_version": 2, "system": {"family": "lie-poisson"}})
        Traceback (most recent call last):
        ...
        exact_khk.errors.InputError: system: a Lie–Poisson system needs the vectors 'a', 'b', 'c'
        """
        from exact_khk.parsing import parse_rational, parse_signs, parse_vector

        d = _json_object(d, "certificate")
        version = _json_key(d, "schema_version", int)
        if version != SCHEMA_VERSION:
            raise InputError(f"schema_version: this reader knows version {SCHEMA_VERSION}, got {version!r}")
        system = system_from_json(_json_key(d, "system", dict))
        x0 = parse_vector(_json_key(d, "x0", list), "x0", system.dim)
        eps = parse_rational(_json_key(d, "eps", str), "eps")
        if eps == 0:
            raise InputError("eps: the step size must be nonzero")
        steps = _json_key(d, "steps", int)
        if steps < 1:
            raise InputError(f"steps: expected a positive integer, got {steps}")
        signs = _json_key(d, "signs", list)
        for i, s in enumerate(signs):
            if not isinstance(s, str):
                raise InputError(f"signs[{i}]: expected a string such as '-++', got {_kind(s)}")
            if "signs" in system.certificate_options:
                parse_signs(s, system.n)
        if signs and "signs" not in system.certificate_options:
            raise InputError("signs: only a Lie–Poisson certificate has involutions")
        checks = tuple(_check_from_json(c, f"checks[{i}]")
                       for i, c in enumerate(_json_key(d, "checks", list)))
        versions = _json_key(d, "versions", dict, {})
        for k, v in versions.items():
            if v is not None and not isinstance(v, str):
                raise InputError(f"versions.{k}: expected a string or null, got {_kind(v)}")
        height = _json_key(d, "height_bits", int, None, nullable=True)
        orbit = []
        for k, p in enumerate(_json_key(d, "orbit", list, [])):
            if not isinstance(p, list) or len(p) != system.dim:
                raise InputError(f"orbit[{k}]: expected a list of {system.dim} coordinates (strings)")
            for i, t in enumerate(p):
                if not isinstance(t, str):
                    raise InputError(f"orbit[{k}][{i}]: expected a string, got {_kind(t)}")
            orbit.append(tuple(p))
        values = _json_key(d, "values", dict, {})
        for name, vs in values.items():
            if vs is None:
                continue
            if not isinstance(vs, list):
                raise InputError(f"values.{name}: expected a list of strings or null, got {_kind(vs)}")
            for k, t in enumerate(vs):
                if not isinstance(t, str):
                    raise InputError(f"values.{name}[{k}]: expected a string, got {_kind(t)}")
        return cls(system, x0, eps, steps, _json_key(d, "arith", str), tuple(signs), checks,
                   dict(versions), float(_json_key(d, "seconds", (int, float), 0.0)), height,
                   tuple(orbit), {k: (None if v is None else list(v)) for k, v in values.items()},
                   _json_key(d, "path", str, ""))

    @any_int_digits()
    def to_json(self) -> dict:
        return {"schema_version": SCHEMA_VERSION, "system": self.system.to_json(),
                "x0": [str(t) for t in self.x0], "eps": str(self.eps), "steps": self.steps,
                "arith": self.arith, "path": self.path, "signs": list(self.signs),
                "status": self.status, "valid": self.valid, "verdict": self.verdict(),
                "seconds": self.seconds, "height_bits": self.height_bits, "versions": self.versions,
                "orbit": [list(p) for p in self.orbit], "values": self.values,
                "checks": [c.to_json() for c in self.checks]}


def system_from_json(d: dict):
    """The system of a certificate's ``"system"`` JSON (:func:`exact_khk.systems.catalogue.from_json`:
    a family's system when the dict has a ``"family"`` key, else a system file's); InputError if malformed."""
    from exact_khk.systems.catalogue import from_json

    return from_json(_json_object(d, "system"))


#: the fields of a check in its JSON: (type(s), required)
_CHECK_FIELDS = {"name": (str, True), "claim": (str, True), "expected": (bool, True),
                 "holds": ((bool, type(None)), True), "residual": (str, True), "arith": (str, True),
                 "seconds": ((int, float), True), "evidence": (str, False), "detail": (str, False),
                 "applicable": (bool, False)}


def _check_from_json(d, where: str) -> Check:
    d = _json_object(d, where)
    for key, (types, required) in _CHECK_FIELDS.items():
        if key not in d:
            if required:
                raise InputError(f"{where}: missing key {key!r}")
            continue
        v = d[key]
        if not isinstance(v, types) or (isinstance(v, bool) and bool not in _as_tuple(types)):
            raise InputError(f"{where}.{key}: expected {_type_names(types)}, got {_kind(v)}")
    return Check(**{k: d[k] for k in Check.__dataclass_fields__ if k in d})


def _json_object(d, where: str) -> dict:
    if not isinstance(d, dict):
        raise InputError(f"{where}: expected a JSON object, got {_kind(d)}")
    return d


def _json_key(d: dict, key: str, types, default=..., nullable=False):
    """``d[key]`` checked to be of ``types`` (bool is not an int here); ``default`` if
    absent and a default is given, else InputError naming the key."""
    if key not in d:
        if default is ...:
            raise InputError(f"{key}: missing key {key!r}")
        return default
    v = d[key]
    if v is None and nullable:
        return None
    if not isinstance(v, types) or (isinstance(v, bool) and bool not in _as_tuple(types)):
        raise InputError(f"{key}: expected {_type_names(types)}{' or null' if nullable else ''}, got {_kind(v)}")
    return v


def _as_tuple(types) -> tuple:
    return types if isinstance(types, tuple) else (types,)


def _type_names(types) -> str:
    names = {str: "a string", int: "an integer", float: "a number", bool: "true or false",
             dict: "an object", list: "a list", type(None): "null"}
    return " or ".join(dict.fromkeys(names.get(t, t.__name__) for t in _as_tuple(types)))


def _kind(v) -> str:
    """A value for a message: its JSON type, and the value itself when short."""
    kind = {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "a list",
            dict: "an object", type(None): "null"}.get(type(v), type(v).__name__)
    text = repr(v) if isinstance(v, (bool, float, type(None))) or (isinstance(v, str) and len(v) <= 40) else ""
    return f"{kind} {text}".strip() if text and kind != "null" else kind


def _short(system) -> str:
    return system.short_name


def abbreviate(text: str, width: int = 24) -> str:
    """``text`` cut to ``width`` characters, saying how long it was."""
    if len(text) <= width:
        return text
    tail = f"…({len(text)} ch)"
    return text[:width - len(tail)] + tail


def library_versions() -> dict:
    """Versions of exact_khk, Python and the numeric libraries (for records)."""
    import importlib.metadata as md

    from exact_khk import __version__

    out = {"exact_khk": __version__, "python": sys.version.split()[0]}
    for dist in ("python-flint", "gmpy2", "mpmath", "sympy"):
        try:
            out[dist] = md.version(dist)
        except md.PackageNotFoundError:
            out[dist] = None
    return out
