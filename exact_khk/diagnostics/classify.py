"""Is the Kahan map of a system integrable?  One verdict, with its evidence and how each
piece was obtained (docs/diagnostics.md, "classify").

The evidence:

* **degrees** d_k of Φ^k over F_p on random lines (:func:`~exact_khk.diagnostics.degrees.degree_sequence`).
  *Proven*: each reported d_k is a lower bound of the true degree (the computation never
  overcounts).  *Probable*: equality, with the stated Schwartz–Zippel bound on an undercount.
* **exact degrees** over Q for the first iterates, where affordable.  *Proven*: they are the
  degrees; and since d_{k+m} ≤ d_k·d_m, the dynamical degree λ = lim d_k^{1/k} = inf_k d_k^{1/k}
  (Fekete), so λ ≤ d_k^{1/k} for every exactly known d_k (:func:`lambda_upper_bound`).
* **the fitted recurrence** and λ as an algebraic number (:mod:`~exact_khk.diagnostics.recurrence`):
  a *conjecture* — a recurrence fitted on finitely many terms and confirmed on a few more;
  maps in dimension ≥ 3 can have dynamical degrees that no recurrence describes.
* **integrals** (:func:`~exact_khk.diagnostics.integrals.find_integrals`): each verified exactly
  on a fresh orbit; their functional independence is the exact rank of their Jacobian at a
  rational point.
* **invariant measure** and **Poisson structure**, where the discovery modules are installed
  (:data:`DISCOVERIES`): each verified as its module states.

The rules (:data:`RULES`): ``integrable`` needs at least one verified integral *and* bounded or
polynomial growth confirmed on terms beyond the fit; ``non-integrable`` needs exponential growth
confirmed beyond the fit; anything else is ``undetermined``, with what more would decide it.
Both verdicts rest on a fitted recurrence, so both are stated as evidence, not as theorems.

>>> c = classify("euler-top", steps=12)
>>> c.verdict, c.degrees.fit.growth, len(c.integrals.integrals)
('integrable', 'polynomial', 2)
"""

from __future__ import annotations

import importlib
import math
import time
from dataclasses import dataclass, field as dc_field
from fractions import Fraction

from exact_khk.errors import InputError, UndecidedError
from exact_khk.parsing import any_int_digits, check_progress, check_count

#: the verdict rules, as stated in the output and in docs/diagnostics.md
RULES = {
    "integrable": "at least one integral verified exactly on a fresh orbit, and bounded or polynomial degree "
                  "growth confirmed on terms beyond the fitted recurrence",
    "non-integrable": "exponential degree growth (dynamical degree > 1) confirmed on terms beyond the fitted "
                      "recurrence",
    "undetermined": "neither of the above",
}

#: the discoveries: key → (module, function, attribute listing what was found); each function takes
#: (system, eps=..., field=...) and returns a record with ``to_json()`` and that attribute, a tuple of
#: found objects each with ``verified`` (exact on a fresh orbit) and ``to_json()``
DISCOVERIES = {
    "measure": ("exact_khk.diagnostics.measures", "find_measure", "densities"),
    "poisson": ("exact_khk.diagnostics.poisson", "find_poisson", "tensors"),
}


def verified_found(key, result) -> tuple:
    """What the discovery ``key`` found and verified exactly on a fresh orbit."""
    return tuple(x for x in getattr(result, DISCOVERIES[key][2]) if x.verified)


def found_text(key, item) -> str:
    """One line for a found density or tensor."""
    if key == "measure":
        return f"density {item.text}"
    N = len(item.entries)
    pairs = [f"pi[{a}][{b}] = {item.entries[a][b]}" for a in range(N) for b in range(a + 1, N)
             if item.entries[a][b] != "0"]
    return f"tensor of rank {item.rank}: " + ", ".join(pairs)


@dataclass(frozen=True)
class Evidence:
    """One piece of evidence: what it says, how it was obtained, and its standing
    (``proven``, ``probable`` with a stated bound, ``exact at orbit points`` or ``conjecture``)."""

    what: str
    how: str
    standing: str

    @any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
    def to_json(self) -> dict:
        return {"what": self.what, "how": self.how, "standing": self.standing}


@dataclass(frozen=True)
class Classification:
    """The verdict of :func:`classify` and everything it rests on."""

    label: str
    dim: int
    eps: Fraction
    verdict: str
    reason: str
    degrees: object                 # DegreeSequence
    lambda_upper: tuple | None      # (k, d_k, upper bound as a decimal string) or None
    integrals: object | None        # IntegralSearch or None when the search could not run
    integrals_note: str
    degree: int                     # the integral search's degree bound
    discoveries: dict               # key → result or a string saying why it did not run
    evidence: tuple
    decide: tuple                   # what more would decide an undetermined verdict
    seconds: float = 0.0
    notes: tuple = dc_field(default=())

    @property
    def independent_integrals(self) -> int:
        return 0 if self.integrals is None else int(getattr(self.integrals, "independent", 0) or 0)

    def _discovery_json(self, key):
        r = self.discoveries.get(key)
        if r is None or isinstance(r, str):
            return {"status": "not run", "reason": r or "not asked"}
        return {"status": "found" if verified_found(key, r) else "nothing found",
                "verified": [found_text(key, x) for x in verified_found(key, r)], **r.to_json()}

    @any_int_digits()
    def to_json(self) -> dict:
        fit = self.degrees.fit
        dd = fit.dynamical_degree
        return {
            "system": self.label, "dim": self.dim, "eps": str(self.eps),
            "verdict": self.verdict, "reason": self.reason, "rules": dict(RULES),
            "degrees": {"sequence": list(self.degrees.degrees), "exact_over_Q": [int(d) for d in self.degrees.exact],
                        "undercount_bound": self.degrees.undercount_bound,
                        "runs": len(self.degrees.runs)},
            "growth": {"class": fit.growth, "polynomial_degree": fit.polynomial_degree,
                       "polynomial": fit.polynomial, "recurrence": fit.to_json(),
                       "standing": "conjecture: a recurrence fitted on "
                                   f"{fit.fitted_on} terms and confirmed on {fit.confirmed_on} more"},
            "dynamical_degree": {
                "fitted": dd.to_json() if dd is not None else None,
                "fitted_standing": "conjecture (from the fitted recurrence)",
                "upper_bound": ({"k": self.lambda_upper[0], "d_k": self.lambda_upper[1],
                                 "bound": self.lambda_upper[2],
                                 "standing": "proven: lambda <= d_k^(1/k) for exact d_k (submultiplicativity)"}
                                if self.lambda_upper else None)},
            "integrals": (self.integrals.to_json() | {"independent": self.independent_integrals,
                                                       "of_dimension": self.dim}
                          if self.integrals is not None else {"status": "not run", "reason": self.integrals_note}),
            "measure": self._discovery_json("measure"),
            "poisson": self._discovery_json("poisson"),
            "evidence": [e.to_json() for e in self.evidence],
            "decide": list(self.decide), "seconds": self.seconds, "notes": list(self.notes),
        }

    @any_int_digits()
    def summary(self) -> str:
        d = self.degrees
        fit = d.fit
        out = [f"verdict: {self.verdict.upper()} — {self.reason}",
               f"  degrees d_0..d_{len(d.degrees) - 1}: {', '.join(map(str, d.degrees))}"]
        if fit.determined and fit.growth != "undetermined":
            g = fit.growth + (f" of degree {fit.polynomial_degree}" if fit.growth == "polynomial" else "")
            dd = fit.dynamical_degree
            lam = (f"; lambda: root of {dd.minimal_polynomial} in [{dd.enclosure[0]}, {dd.enclosure[1]}]"
                   if dd is not None else "")
            out.append(f"  growth: {g}{lam} (fitted on {fit.fitted_on} terms, confirmed on {fit.confirmed_on})")
        else:
            out.append(f"  growth: not classified ({fit.reason})")
        if self.lambda_upper:
            k, dk, b = self.lambda_upper
            out.append(f"  lambda <= d_{k}^(1/{k}) = {dk}^(1/{k}) <= {b} (exact d_{k} over Q)")
        if self.integrals is not None:
            found = len(self.integrals.integrals)
            out.append(f"  integrals at degree <= {self.degree}: {found} found, "
                       f"{self.independent_integrals} functionally independent (dimension {self.dim})")
            for i, it in enumerate(self.integrals.integrals, 1):
                text = integral_text(it)
                out.append(f"    I{i} = " + (text if len(text) <= 200 else
                                             f"{text[:200]}... ({len(text)} characters: --json has it whole)"))
        else:
            out.append(f"  integrals: not searched ({self.integrals_note})")
        for key in DISCOVERIES:
            r = self.discoveries.get(key)
            if r is None or isinstance(r, str):
                out.append(f"  {key}: not run ({r or 'not asked'})")
            else:
                found = verified_found(key, r)
                out.append(f"  {key}: " + ("; ".join(found_text(key, x) for x in found) + " (verified exactly on a "
                                           "fresh orbit; find-" + key + " has the checks)" if found else
                                           f"nothing found at degree <= {r.degree}"))
        out.append("  evidence:")
        out += [f"    [{e.standing}] {e.what} — {e.how}" for e in self.evidence]
        out += [f"  to decide: {t}" for t in self.decide]
        out += [f"  note: {n}" for n in self.notes]
        out.append(f"  time {self.seconds:.2f} s")
        return "\n".join(out)


def integral_text(it) -> str:
    """A found integral as num/den text."""
    den = it.denominator.strip()
    return f"({it.numerator})" + ("" if den in ("1", "") else f" / ({den})")


def lambda_upper_bound(exact_degrees) -> tuple | None:
    """(k, d_k, bound): the smallest d_k^{1/k} over the exactly known degrees (k ≥ 1), rounded up
    to 6 decimals — a proven upper bound of the dynamical degree (d_{k+m} ≤ d_k d_m, Fekete).

    >>> lambda_upper_bound([1, 3, 9, 19])
    (3, 19, '2.668402')
    """
    best = None
    for k, dk in enumerate(int(d) for d in exact_degrees):
        if k == 0 or dk < 1:
            continue
        # the smallest 6-decimal q with q^k >= dk, found exactly
        lo = math.floor(dk ** (1.0 / k) * 10 ** 6) - 2
        q = max(lo, 0)
        while Fraction(q, 10 ** 6) ** k < dk:
            q += 1
        if best is None or q < best[0]:
            best = (q, k, dk)
    if best is None:
        return None
    q, k, dk = best
    return k, dk, f"{q // 10 ** 6}.{q % 10 ** 6:06d}"


def _discover(key, system, eps, field, progress=None):
    module, name, _ = DISCOVERIES[key]
    try:
        fn = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError):
        return "not available in this installation"
    try:
        return fn(system, eps=eps, field=field, progress=progress)
    except (InputError, UndecidedError) as exc:  # e.g. a lift not confirmed at an eps of 400 digits
        return f"could not run: {exc}"


#: the integral search's default degree: the largest d <= 4 whose candidates number at most this.
#: Measured (CPU of find_integrals with its default fit, shared 2-core machine): dimension 5 at
#: degree 4 (126 candidates) 18-26 s for the Volterra chains, dimension 6 at degree 4 (210) over 90 s
#: for clebsch, lagrange-top, kirchhoff; at 70 candidates (dimension 5: degree 3, 6: degree 2) every
#: catalogue system takes at most about 14 s and the integrable ones still show a verified integral
MAX_DEFAULT_CANDIDATES = 70
#: from this dimension the default fit degree of the integral entries is the search degree, not twice
#: it: dimension 6 at degree 2 took over 45 s (lagrange-top) with fit degree 4, 6-14 s with fit degree 2
CAPPED_FIT_DIM = 6


def default_degree(dim: int) -> int:
    """The largest degree d <= 4 with C(dim + d, d) <= MAX_DEFAULT_CANDIDATES candidate monomials (at least 1).

    >>> default_degree(3), default_degree(5), default_degree(6), default_degree(40)
    (4, 3, 2, 1)
    """
    return max([1] + [d for d in range(1, 5) if math.comb(dim + d, d) <= MAX_DEFAULT_CANDIDATES])


def default_fit_degree(dim: int, degree: int) -> int:
    """The degree bound of the fitted integral entries: 2·degree (find_integrals' own default), capped at
    ``degree`` from dimension :data:`CAPPED_FIT_DIM` (the measurement above).

    >>> default_fit_degree(3, 4), default_fit_degree(6, 2)
    (8, 2)
    """
    return degree if dim >= CAPPED_FIT_DIM else 2 * degree


@any_int_digits()
def classify(system, eps=None, steps=20, degree=None, field="f", seed=0, exact=6, confirm=3,
             discover=("measure", "poisson"), progress=None, fit_degree=None) -> Classification:
    """Classify the Kahan map of ``system`` (a System, catalogue name or system file) at step
    ``eps``: degrees d_0..d_steps over F_p, the first ``exact`` exactly over Q (where affordable),
    integrals of degree ≤ ``degree`` (default :func:`default_degree`), and the discoveries named in ``discover``
    (module docstring for the rules).  ``progress(stage)``: called with the name of each stage and, during the
    degree stage, with ``'degrees over F_p: step k'`` (k counts the steps of all lines)."""
    from exact_khk.diagnostics.degrees import degree_sequence, eps_of, resolve_field
    from exact_khk.diagnostics.integrals import find_integrals

    t0 = time.perf_counter()
    check_count(steps, "steps", 4, 400)
    if degree is not None:
        check_count(degree, "degree", 1, 12)
    if fit_degree is not None:
        check_count(fit_degree, "fit_degree", 0, 12)
    check_count(exact, "exact", 0, 50)
    seed = check_count(seed, "seed", -2 ** 63, 2 ** 63)
    if isinstance(discover, str) or not isinstance(discover, (list, tuple, set, frozenset)):
        raise InputError(f"discover: expected a list of discoveries ({', '.join(DISCOVERIES)}), got {discover!r}"[:300])
    unknown = set(discover) - set(DISCOVERIES)
    if unknown:
        raise InputError(f"discover: unknown discovery {sorted(unknown)[0]!r} (known: {', '.join(DISCOVERIES)})")
    sysobj, fld = resolve_field(system, field)
    eps = eps_of(sysobj, eps)
    auto = degree is None and fit_degree is None
    degree = default_degree(fld.dim) if degree is None else degree
    fit_degree = default_fit_degree(fld.dim, degree) if fit_degree is None else fit_degree
    stage = check_progress(progress) or (lambda s: None)
    stage("degrees over F_p")
    degs = degree_sequence(sysobj if sysobj is not None else fld, steps=steps, eps=eps, field=field, seed=seed,
                           exact=exact, confirm=confirm,
                           progress=None if progress is None else lambda k: progress(f"degrees over F_p: step {k}"))
    notes = list(degs.notes)
    if auto and (math.comb(fld.dim + 4, 4) > MAX_DEFAULT_CANDIDATES or fit_degree < 2 * degree):
        notes.append(f"integral search capped: degree {degree}, fitted entries of degree <= {fit_degree} (defaults "
                     f"for dimension {fld.dim}, chosen by measured cost; --degree and --fit-degree search further)")
    integrals, inote = None, ""
    stage(f"integrals of degree <= {degree}")
    try:
        integrals = find_integrals(sysobj if sysobj is not None else fld, degree=degree, field=field, eps=eps,
                                   seed=seed, fit_degree=fit_degree, progress=progress)
    except InputError as exc:
        inote = str(exc)
    discoveries = {}
    for key in discover:
        stage(f"{key} search")
        discoveries[key] = _discover(key, sysobj if sysobj is not None else fld, eps, field, progress)
    fit = degs.fit
    upper = lambda_upper_bound(degs.exact) if degs.exact else None
    verified = 0 if integrals is None else sum(1 for it in integrals.integrals if it.verified)
    indep = 0 if integrals is None else int(getattr(integrals, "independent", 0) or 0)
    confirmed = fit.determined and fit.growth != "undetermined" and fit.confirmed_on >= confirm
    slow = confirmed and fit.growth in ("bounded", "polynomial")
    fast = confirmed and fit.growth == "exponential"
    if fast and upper is not None and fit.dynamical_degree is not None:
        if float(upper[2]) < fit.dynamical_degree.value - 1e-6:
            notes.append("the fitted dynamical degree exceeds the proven upper bound: the fit is wrong")
            fast = False
    decide = []
    if slow and verified:
        verdict = "integrable"
        reason = (f"{indep} independent integral(s) verified exactly, and {fit.growth} degree growth "
                  f"confirmed on {fit.confirmed_on} terms beyond the fit")
    elif fast:
        verdict = "non-integrable"
        reason = (f"exponential degree growth, lambda ~ {fit.dynamical_degree.value:.6g}, confirmed on "
                  f"{fit.confirmed_on} terms beyond the fit")
    else:
        verdict = "undetermined"
        if not confirmed:
            reason = f"degree growth not classified ({fit.reason})"
            decide.append(f"more iterates (--steps {2 * steps})")
        else:
            reason = f"{fit.growth} degree growth, but no integral of degree <= {degree} was found"
            decide.append(f"a higher integral degree (--degree {degree + 1})")
    evidence = [
        Evidence(f"d_k >= {list(degs.degrees)} for k = 0..{len(degs.degrees) - 1}",
                 f"iterates restricted to {len(degs.runs)} random line(s) over F_p (never an overcount)", "proven"),
        Evidence("d_k equal to these values",
                 f"P(undercount) <= {degs.undercount_bound:.3g} at good primes (Schwartz–Zippel)", "probable"),
    ]
    if degs.exact:
        evidence.append(Evidence(f"d_k = {[int(d) for d in degs.exact]} for k = 0..{len(degs.exact) - 1}",
                                 "composition of the map over Q (fmpz_mpoly, gcds removed)", "proven"))
    if upper:
        evidence.append(Evidence(f"lambda <= {upper[2]}", f"lambda = inf d_k^(1/k) <= d_{upper[0]}^(1/{upper[0]}) "
                                 f"with d_{upper[0]} = {upper[1]} exact", "proven"))
    if fit.determined and fit.order:
        dd = fit.dynamical_degree
        evidence.append(Evidence(f"d_k satisfies chi(x) = {fit.characteristic_text()}"
                                 + (f"; lambda = root of {dd.minimal_polynomial} in [{dd.enclosure[0]}, "
                                    f"{dd.enclosure[1]}]" if dd is not None else ""),
                                 f"shortest recurrence fitted on {fit.fitted_on} terms, confirmed on "
                                 f"{fit.confirmed_on} more", "conjecture"))
    if integrals is not None:
        for it in integrals.integrals:
            if not it.verified:
                continue
            evidence.append(Evidence(f"{integral_text(it)} is conserved",
                                     "found from orbits (modular kernels), verified exactly on a fresh orbit",
                                     "exact at orbit points"))
        if integrals.integrals:
            evidence.append(Evidence(f"{indep} of the integrals are functionally independent",
                                     "exact rank of their Jacobian at a rational point", "proven"))
    for key in discover:
        r = discoveries[key]
        if not isinstance(r, str):
            for x in verified_found(key, r):
                evidence.append(Evidence(f"{key}: {found_text(key, x)}",
                                         "found by modular linear algebra; verified exactly on a fresh orbit and "
                                         "as an identity over F_p with its Schwartz–Zippel bound (find-" + key + ")",
                                         "exact at orbit points; identity over F_p with a stated bound"))
    return Classification(degs.label, degs.dim, eps, verdict, reason, degs, upper, integrals, inote, degree, discoveries,
                          tuple(evidence), tuple(decide), time.perf_counter() - t0, tuple(notes))
