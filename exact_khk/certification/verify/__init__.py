"""Re-derive a saved certificate by a separate, minimal code path: ``verify(data)``.

A certificate (:meth:`~exact_khk.certification.records.Certificate.to_json`,
schema version 2) records a system, x0, ε, the number of steps, the arithmetic,
the orbit x_0, …, x_K of the Kahan map Φ_f, the integrals' values on it, and one
record per claim and negative control (name, statement, claim or control, evidence,
holds, exact residual, applicable).  :func:`verify` trusts none of it: from the
certificate's own data it re-derives

* the orbit and the values (:mod:`.orbit`): every step equation by substitution,
  every step's determinant, every value recomputed at its point;
* **every record** (:mod:`.records`): the list of records the embedded system and
  options imply — refused if a record is dropped, invented, renamed or reordered,
  naming the first difference — and, for each, its statement, claim/control,
  evidence and arithmetic, and ``holds``, the exact residual and the control's
  applicability recomputed here;
* the status and the verdict line, from the re-derived records.

It does so with plain exact arithmetic written out from the formulas
(:mod:`.fields`: Q, Q(ζ_N), F_P on python-flint's numbers; its own Gaussian elimination and dual
numbers; :mod:`.maps`: the Kahan step, its derivative, the family's matrices) and
never calls the library's Kahan map, linear algebra, arithmetic contexts or
certification engines.  From the library it takes the reading of the input: the
certificate's structure (:meth:`Certificate.from_json`), rationals
(:func:`~exact_khk.parsing.parse_rational`) and the system parsing (the field's
coefficients, the integrals' reduced form where their text divides by zero); and SymPy's
rational functions for the proofs.

The records of the engine's other modes (:mod:`.modes`) are the same records at a generic
point, and must be exactly the identity / proof versions of the list above: the
Schwartz–Zippel ``identity:`` records of ``certify --identities`` are re-derived at the
verifier's own random draws over F_P (its failure bound uses the degree bounds the
records state), the symbolic ``proof:`` records of ``certify --prove`` in SymPy's
Q(x, ε) up to dimension 3 and within a time budget.  Records it cannot re-derive (proofs
beyond those) are reported **not re-checked**: the result is then ``PARTIALLY VERIFIED``
(exit status 4), never ``VERIFIED``; so is a certificate of a system file that covers
only some of the claims the system declares (a ``--claims`` selection, which the
certificate does not record).

>>> from exact_khk.certification.lie_poisson import certify
>>> data = certify(steps=2, signs=["-++"]).to_json()
>>> report = verify(data)
>>> report.ok, report.verdict()[:62]
(True, 'VERIFIED: the record of this VALID certificate is correct: re-')
>>> data["checks"][0]["evidence"] = "symbolic proof"      # an upgraded record
>>> verify(data).failures()[0][0]
'record integral H~ (closed form = definition)'
"""

from __future__ import annotations

from dataclasses import dataclass

from exact_khk.certification.verify.fields import (RATIONAL_ARITHS, Undefined, _Evaluate, _Rationals,  # noqa: F401
                                                   cyclotomic_polynomial, exact_field, _show)
from exact_khk.certification.verify.orbit import _Recheck, orbit_length
from exact_khk.certification.verify.modes import IDENTITY, PROOF, Identities, Proofs
from exact_khk.certification.verify.records import (Context, _short, _tf, differs, expected_records,
                                                    outcome_differs, rederive)
from exact_khk.errors import InputError
from exact_khk.parsing import any_int_digits

__all__ = ["verify", "VerifyReport", "SCHEMA_VERSIONS", "exact_field", "cyclotomic_polynomial", "RATIONAL_ARITHS",
           "_Evaluate", "_Rationals"]

#: the certificate schema versions this verifier reads
SCHEMA_VERSIONS = (2,)
#: top-level keys a certificate may carry that are informational: shown, not re-checked, not counted
INFORMATIONAL = ("invocation", "seconds", "versions", "height_bits", "path")
@dataclass(frozen=True)
class VerifyReport:
    """The outcome of :func:`verify`: ``results`` is a tuple of ``(name, ok, detail)``;
    ``ok`` is True iff there is at least one result and all hold (then ``partial`` says
    whether some records were not re-checked); ``checkable`` is False for a certificate
    computed in an inexact arithmetic (then ``ok`` is False); ``records`` the number of
    the certificate's records, ``rederived`` how many were re-derived; ``notes``
    informational lines (not re-checked, not counted)."""

    ok: bool
    results: tuple
    checkable: bool = True
    records: int = 0
    rederived: int = 0
    not_rechecked: tuple = ()
    notes: tuple = ()
    #: how the records of the other modes were re-derived (one phrase per mode), for the verdict
    modes: tuple = ()

    @property
    def partial(self) -> bool:
        return bool(self.not_rechecked)

    @property
    def exit_status(self) -> int:
        """0 VERIFIED, 1 NOT VERIFIED, 4 PARTIALLY VERIFIED (docs/verify.md)."""
        return 1 if not self.ok else 4 if self.partial else 0

    def failures(self) -> list:
        """The results that do not hold, in order."""
        return [r for r in self.results if not r[1]]

    def verdict(self) -> str:
        """One line: ``VERIFIED: ...``, ``PARTIALLY VERIFIED: ...`` or ``NOT VERIFIED: <first failing check>: ...``."""
        count = f"re-derived {self.rederived} of {self.records} records"
        how = f" ({'; '.join(self.modes)})" if self.modes else ""
        if self.ok and not self.partial:
            return (f"VERIFIED: the record of this {self._status} certificate is correct: {count} "
                    f"{'independently' if self.modes else 'exactly and independently'}, with its orbit, values and "
                    f"status{how}")
        if self.ok:
            what = "; ".join(self.not_rechecked[:3]) + (" ..." if len(self.not_rechecked) > 3 else "")
            return (f"PARTIALLY VERIFIED: the {self._status} certificate is correct as far as re-derived: {count}"
                    f"{how}; not re-checked: {what}")
        name, _, detail = self.failures()[0] if self.failures() else ("no results", False, "")
        more = len(self.failures()) - 1
        tail = f" (and {more} more failing check{'s' * (more != 1)})" if more > 0 else ""
        return f"NOT VERIFIED: {name}: {detail}{tail}"

    @property
    def _status(self) -> str:
        status = next((d for n, _, d in self.results if n == "status"), "")
        return status.split()[1] if status.startswith("recomputed") else "?"

    @any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
    def summary(self) -> str:
        """The results, one per line, the informational notes, then the verdict line."""
        lines = [f"  {'ok  ' if ok else 'FAIL'}  {name}: {detail}" for name, ok, detail in self.results]
        lines += [f"  info  {note}" for note in self.notes]
        return "\n".join(lines + [self.verdict()])

    @any_int_digits()
    def to_json(self) -> dict:
        return {"ok": self.ok, "checkable": self.checkable, "partial": self.partial, "verdict": self.verdict(),
                "records": self.records, "rederived": self.rederived, "not_rechecked": list(self.not_rechecked),
                "notes": list(self.notes), "modes": list(self.modes),
                "results": [{"name": n, "ok": ok, "detail": d} for n, ok, d in self.results]}


@any_int_digits()
def verify(data, seed=None, proof_budget=None) -> VerifyReport:
    """Re-derive the certificate ``data`` (the JSON dict of ``Certificate.to_json``); see
    the module docstring.  ``seed``: of the verifier's own random draws for the ``identity:``
    records (default: fresh, from the operating system; the report states it);
    ``proof_budget``: seconds for the ``proof:`` records (default :data:`~.modes.PROOF_BUDGET`).
    Malformed structures raise :class:`~exact_khk.errors.InputError` naming the field."""
    from exact_khk.certification.records import Certificate

    if not isinstance(data, dict):
        raise InputError(f"certificate: expected a JSON object, got {type(data).__name__}")
    if "schema_version" not in data:
        raise InputError("schema_version: missing key 'schema_version'")
    version = data["schema_version"]
    if type(version) is not int or version not in SCHEMA_VERSIONS:
        reads = ", ".join(map(str, SCHEMA_VERSIONS))
        return VerifyReport(False, (("schema version", False, (
            f"this verifier reads certificate schema version {reads} only (the version written by this "
            f"exact-khk, described by exact_khk/certification/certificate.schema.json); this certificate says "
            f"{str(version)[:40]!r}: re-create it with this exact-khk's certify, or verify it with the "
            f"exact-khk that wrote it")),))
    results = [("schema version", True, str(version))]
    cert = Certificate.from_json(data)  # the structure: InputError naming the field
    for key, types in (("status", str), ("valid", bool), ("verdict", str)):
        if key not in data:
            raise InputError(f"{key}: missing key {key!r}")
        if not isinstance(data[key], types):
            raise InputError(f"{key}: expected {'a string' if types is str else 'true or false'}")
    info = [key for key in data if key in INFORMATIONAL and key != "invocation"]
    notes = (("invocation (the command line and options): informational, not re-checked and not counted",)
             if "invocation" in data else ()) \
        + ((f"{', '.join(info)}: informational, not re-checked and not counted",) if info else ()) \
        + tuple(f"{key[:40]}: a key this verifier does not know, ignored" for key in data if key not in _KNOWN)
    total = len(data["checks"])
    try:
        F = exact_field(cert.arith)
    except Undefined as exc:
        F, why = None, str(exc)
    else:
        why = (f"the certificate was computed in the inexact arithmetic {cert.arith!r}: its orbit and values "
               f"are approximations and cannot be re-checked exactly (not checkable)")
    if F is None:
        results.append(("exact arithmetic", False, why))
        results += _status_results(data, data["checks"], [])
        return VerifyReport(False, tuple(results), checkable=False, records=total, notes=notes)
    results.append(("exact arithmetic", True, f"{cert.arith}: re-checked in {F.name}"))
    results.append(orbit_length(cert))  # before any point of the orbit is parsed
    if not results[-1][1]:
        return VerifyReport(False, tuple(results), records=total, notes=notes)
    results += _Recheck(cert, data, F).run()
    orbit_ok = all(ok for _, ok, _ in results)
    try:
        derived, skipped, record_results = _records(cert, data, F, orbit_ok, seed, proof_budget)
    except Undefined as exc:  # e.g. x0 with a denominator divisible by P in a gf:P certificate
        derived, skipped, record_results = data["checks"], [], [("records", False, f"cannot be re-derived: {exc}")]
    results += record_results
    results += _status_results(data, derived, skipped)
    ok = all(ok for _, ok, _ in results)
    rederived = sum(1 for d in derived if d.get("_rederived"))
    modes = []
    for prefix, how in ((IDENTITY, "as identities at the verifier's own random draws over F_P, "
                                   "each with its failure bound"),
                        (PROOF, "as identities of rational functions in SymPy")):
        k = sum(1 for d in derived if d.get("_rederived") and d["name"].startswith(prefix))
        if k:
            modes.append(f"{k} of them {how}")
    return VerifyReport(ok, tuple(results), True, total, rederived, tuple(skipped), notes, tuple(modes))


_KNOWN = set(INFORMATIONAL) | {"schema_version", "system", "x0", "eps", "steps", "arith", "signs", "status", "valid",
                               "verdict", "orbit", "values", "checks"}


def _records(cert, data, F, orbit_ok, seed=None, proof_budget=None):
    """Re-derive every record; returns (the checks with re-derived fields, the names not re-checked,
    results)."""
    checks = data["checks"]
    recorded = [c["name"] for c in checks]
    ctx = Context(cert, data, F, {c.name: c for c in cert.checks})
    expected, selection = expected_records(ctx)
    want = [r.name for r in expected]
    out, skipped, modes = [], [], {}
    # the other modes: their records are there iff certify ran them (--identities, --prove)
    first = next((c for c in checks if c["name"].startswith(IDENTITY)), {})
    budget = {} if proof_budget is None else {"budget": proof_budget}
    for prefix, make in ((IDENTITY, lambda: Identities(cert, data, ctx.chosen, first["arith"], seed)),
                         (PROOF, lambda: Proofs(cert, data, ctx.chosen, **budget))):
        if any(n.startswith(prefix) for n in recorded):
            try:
                modes[prefix] = make()
                want += modes[prefix].names
            except Undefined as exc:
                modes[prefix] = None
                out.append((f"{prefix[:-2]} records", False, f"cannot be re-derived: {exc}"))
    # coverage: exactly the implied records, in order (those of a mode that cannot be listed left out)
    listed = [n for n in recorded if not any(n.startswith(p) and modes[p] is None for p in modes)]
    diff = _first_difference(want, listed)
    if diff:
        out.insert(0, ("records cover the claims", False, diff))
    elif all(modes.values()):
        parts = [f"{len(want) - sum(1 for n in want if n.startswith((IDENTITY, PROOF)))} exact"] + \
            [f"{sum(1 for n in want if n.startswith(p))} {p[:-2]}" for p in modes]
        out.insert(0, ("records cover the claims", True, f"the {len(want)} records the system and options imply "
                       f"({', '.join(parts)}), in order"))
    if selection:
        out.append(("claim selection", True, selection + ": not re-checked"))
        skipped.append("the claims the certificate leaves out")
    proofs = modes.get(PROOF)
    if proofs and proofs.why:
        out.append(("proof records", True, f"not re-checked: {proofs.why}"))
    derived = []
    by_name = {r.name: r for r in expected}
    cache_key = data_key(data)
    counts = _identity_counts(checks)
    for c in checks:
        name = c["name"]
        mode = next((p for p in modes if name.startswith(p)), None)
        if mode is not None:
            engine = modes[mode]
            if engine is None or not engine.rederives(name):
                if engine is not None and engine.why and name in engine.names:
                    skipped.append(name)
                derived.append(dict(c))
                continue
            d, problem, detail = engine.check(c, counts)
            derived.append(d)
            out.append((f"record {name}", problem is None, problem or detail))
            continue
        rec = by_name.pop(name, None)
        if rec is None:
            derived.append(dict(c))
            continue
        d, problem = _one_record(rec, c, cert, F, orbit_ok, cache_key)
        derived.append(d)
        if problem is None:
            out.append((f"record {name}", True, _describe(d)))
        else:
            out.append((f"record {name}", False, problem))
    return derived, skipped, out


def _identity_counts(checks) -> tuple:
    """(identity claim records whose evidence states a degree bound, identity claim records other than
    rank): the range of S, the number of checks with a bound, in the engine's failure bound."""
    claims = [c for c in checks if c["name"].startswith(IDENTITY) and c["expected"]]
    return (sum(1 for c in claims if str(c.get("evidence", "")).startswith("probabilistic")),
            sum(1 for c in claims if not c["name"].startswith(IDENTITY + "rank ")))


def _first_difference(want, got) -> str | None:
    for i, (w, g) in enumerate(zip(want, got)):
        if w != g:
            if g not in want:
                return f"record {i}: {g[:80]!r} is not a record the system and options imply (invented or renamed; " \
                       f"expected {w[:80]!r})"
            if w not in got:
                return f"record {i}: {w[:80]!r} is missing (dropped; found {g[:80]!r} in its place)"
            return f"record {i}: expected {w[:80]!r}, found {g[:80]!r} (records reordered or duplicated)"
    if len(got) < len(want):
        return f"record {len(got)}: {want[len(got)][:80]!r} is missing (dropped; {len(want)} records implied, " \
               f"{len(got)} recorded)"
    if len(got) > len(want):
        return f"record {len(want)}: {got[len(want)][:80]!r} is not a record the system and options imply (invented)"
    return None


#: re-derived (holds, residual, applicable) by (the certificate's data without its records, name, statement,
#: claim or control): a pure function of these, kept for the last few certificates of at most
#: CACHE_CHARS characters (re-checking many variants of one certificate, as the tests do)
_DERIVED: dict = {}
CACHE_CHARS, CACHE_RECORDS = 1_000_000, 5_000


def data_key(data):
    """The certificate's data that the records are derived from, as one string (None if large)."""
    import json

    kept = {k: v for k, v in data.items() if k not in _RECORD_KEYS}
    text = json.dumps(kept, sort_keys=True)
    if len(text) > CACHE_CHARS:
        return None
    if len(_DERIVED) > CACHE_RECORDS:
        _DERIVED.clear()
    return text


_RECORD_KEYS = {"checks", "status", "valid", "verdict", "seconds", "versions", "invocation", "height_bits", "path"}


def _one_record(rec, c, cert, F, orbit_ok, cache_key=None):
    """(the record with re-derived holds/residual/applicable, the first difference or None)."""
    d = dict(c)
    problem = differs((("claim", rec.claim, c["claim"]), ("expected", rec.expected, c["expected"]),
                       ("evidence", F.evidence, c.get("evidence", "exact in Q")), ("arith", cert.arith, c["arith"])),
                      " from the certificate's data")
    if problem:
        return d, problem
    if not orbit_ok:
        return d, "not re-derived: the recorded orbit or values are wrong (see above)"
    key = (cache_key, rec.name, rec.claim, rec.expected)
    try:
        holds, residual, applicable = _DERIVED[key] if key in _DERIVED else rederive(rec)
    except Undefined as exc:
        return d, f"cannot be re-derived: {exc}"
    if cache_key is not None:
        _DERIVED[key] = (holds, residual, applicable)
    d.update(holds=holds, applicable=applicable, _rederived=True)
    if isinstance(residual, str):
        same, shown = c["residual"] == residual, residual
    else:
        try:
            same = F.parse(c["residual"], "residual") == residual
        except InputError:
            same = False
        shown = _show(residual)
    return d, outcome_differs(c, holds, same, f"residual {_short(shown)}", applicable)


def _describe(d) -> str:
    kind = "claim" if d["expected"] else "control"
    if not d.get("applicable", True):
        return f"{kind}, re-derived: inapplicable (cannot fail here), as recorded"
    return f"{kind}, re-derived: holds = {_tf(d['holds'])}, residual {_short(d['residual'])}, as recorded"


def _status_results(data, checks, skipped) -> list:
    """The status recomputed from the re-derived records, and the verdict line's consistency."""
    passed = [(not c.get("applicable", True)) or (c["holds"] is not None and c["holds"] == c["expected"])
              for c in checks]
    wrong = [c["expected"] and c["holds"] is False for c in checks]
    controls = sum(1 for c in checks if not c["expected"] and c.get("applicable", True))
    valid = bool(checks) and all(passed) and controls > 0
    status = "VALID" if valid else "INVALID" if any(wrong) else "INCONCLUSIVE"
    out = []
    basis = f"{len(checks)} records" + (f" ({len(skipped)} of them as recorded, not re-checked)" if skipped else "")
    if data["status"] != status or data["valid"] != valid:
        bad = next((c["name"] for c, p in zip(checks, passed) if not p), None)
        why = (f" (record {bad!r} is {'wrong' if wrong[passed.index(False)] else 'not passed'})" if bad else
               " (no negative control is applicable)" if checks and not controls else "")
        out.append(("status", False, f"recorded status {str(data['status'])[:20]!r} (valid = "
                    f"{str(data['valid']).lower()}), but the records give {status}{why}"))
    else:
        out.append(("status", True, f"recomputed {status} from {basis}, as recorded"))
    claims = sum(1 for c in checks if c["expected"])
    idle = sum(1 for c in checks if not c.get("applicable", True))
    head = {"VALID": f"VALID: all {claims} claims hold and all {controls} negative controls fail"
                     + (f"; {idle} inapplicable" if idle else ""),
            "INVALID": f"INVALID: {sum(wrong)} claim(s) are false: "
                       + "; ".join(c["name"] for c, w in zip(checks, wrong) if w) + " ("}.get(status, f"{status}:")
    if data["verdict"].startswith(head + " (" if status == "VALID" else head):
        out.append(("verdict", True, f"the verdict line states {status}"
                    + (f" with the counts of the {len(checks)} records" if status != "INCONCLUSIVE" else "")))
    else:
        out.append(("verdict", False, f"the verdict line {data['verdict'][:60]!r} does not state {head!r}"))
    return out
