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

* ``VALID`` — every claim holds and every applicable control fails;
* ``INVALID`` — some claim is decided false (the only verdict that says a
  statement about the system is wrong);
* ``INCONCLUSIVE`` — no claim is false, but a check is undecided, or a control
  did not fail (the check did not show that it can fail at this point).
"""

from __future__ import annotations

import sys
from dataclasses import asdict, dataclass, field
from fractions import Fraction

#: version of the certificate JSON (``Certificate.to_json``)
SCHEMA_VERSION = 2


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

    def to_json(self) -> dict:
        return asdict(self)

    @classmethod
    def from_json(cls, d: dict) -> "Check":
        return cls(**{k: d[k] for k in cls.__dataclass_fields__ if k in d})


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
        """True iff every claim holds and every applicable control fails."""
        return bool(self.checks) and all(c.passed for c in self.checks)

    @property
    def status(self) -> str:
        """``'VALID'``, ``'INVALID'`` or ``'INCONCLUSIVE'`` (see the module docstring)."""
        if self.valid:
            return "VALID"
        return "INVALID" if any(c.wrong for c in self.checks) else "INCONCLUSIVE"

    def check(self, name: str) -> Check:
        """The check called ``name``."""
        for c in self.checks:
            if c.name == name:
                return c
        raise KeyError(name)

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
        return (f"INCONCLUSIVE: no claim is false, but {len(open_)} check(s) are undecided or did not fail, "
                f"e.g. {open_[0]!r} ({where})")

    def summary(self) -> str:
        """A few lines: the system, the orbit, the verdict."""
        return "\n".join([self.system.describe(),
                          f"x0 = ({', '.join(str(t) for t in self.x0)}), eps = {self.eps}, {self.steps} steps, "
                          f"arithmetic {self.arith}" + (f", path {self.path}" if self.path else ""),
                          self.verdict()])

    def table(self) -> str:
        """A readable table: check, expected, holds, abbreviated residual, time; the claim below."""
        w = max(len(c.name) for c in self.checks)
        kinds = [c.evidence for c in self.checks]
        common = max(set(kinds), key=kinds.count)
        lines = [f"{'check':<{w}}  {'expect':<6}  {'holds':<9}  {'residual':<24}  {'time':>7}"]
        for c in self.checks:
            holds = {True: "true", False: "false", None: "undecided"}[c.holds]
            mark = "" if c.status == "ok" else f"  <-- {c.status}"
            lines.append(f"{c.name:<{w}}  {str(c.expected).lower():<6}  {holds:<9}  "
                         f"{abbreviate(c.residual):<24}  {c.seconds:>6.3f}s{mark}")
            lines.append(f"    {c.claim}" + (f" [{c.detail}]" if c.detail else "")
                         + (f" (evidence: {c.evidence})" if c.evidence != common else ""))
        lines.append(f"evidence, unless stated: {common}")
        return "\n".join(lines)

    def to_json(self) -> dict:
        return {"schema_version": SCHEMA_VERSION, "system": self.system.to_json(),
                "x0": [str(t) for t in self.x0], "eps": str(self.eps), "steps": self.steps,
                "arith": self.arith, "path": self.path, "signs": list(self.signs),
                "status": self.status, "valid": self.valid, "verdict": self.verdict(),
                "seconds": self.seconds, "height_bits": self.height_bits, "versions": self.versions,
                "orbit": [list(p) for p in self.orbit], "values": self.values,
                "checks": [c.to_json() for c in self.checks]}


def _short(system) -> str:
    n = getattr(system, "n", None)
    return f"n = {n}" if n is not None and getattr(system, "kind", "") == "lie-poisson" else system.name


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
