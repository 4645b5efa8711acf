"""The records of the engine's other modes, re-derived by the verifier's own code.

``certify --identities [gf:P]`` appends ``identity: ...`` records (each claim and control as an
identity in (x, ε), Schwartz–Zippel over F_P at the engine's random draws, one step) and
``certify --prove`` ``proof: ...`` records (the same as identities of rational functions).
Both are the records the certificate's system and options imply (:func:`~.records.expected_records`),
evaluated at a generic point instead of the orbit:

* :class:`Identities`: this verifier draws its **own** points (x0 in F_P^N, ε in F_P ∖ {0}; a
  draw where a step or a claim is undefined is redrawn) and evaluates every record there, one
  step, in its own F_P (:mod:`.fields`).  A claim must vanish at each draw; a control must be
  refuted (a nonzero residual refutes exactly); rank r at a draw proves generic rank r.  Its
  failure bound is (d/(P − S·D1 − 1))^k for its k draws, with the degree bound d and S, D1 as
  the record states them (the engine's ``Deg`` of the claim: read, not re-derived); the bound
  the record states is recomputed from the same numbers.  Residuals of controls come from
  other draws: compared as "nonzero mod P", not by value.
* :class:`Proofs`: the records evaluated over Q(x_0, …, x_{N−1}, ε) in SymPy's field of rational
  functions (``sympy.polys.fields``; independent of the engine's python-flint
  ``RationalFunctionArith``), where ``==`` decides the identity; residuals are compared as
  rational functions.  Up to :data:`PROOF_MAX_DIM` and within a time budget; beyond, the
  records are *not re-checked* (then the result is at best PARTIALLY VERIFIED).
"""

from __future__ import annotations

import random
import re
import secrets
import time

from exact_khk.certification.verify.fields import Undefined, _PrimeField, exact_field
from exact_khk.certification.verify.records import (UNDEFINED, Context, _short, _tf, differs,
                                                    expected_records, family, identity_signs, outcome_differs,
                                                    rederive)
from exact_khk.errors import InputError

__all__ = ["IDENTITY", "PROOF", "Identities", "Proofs", "identity_signs", "stated_bound"]

IDENTITY, PROOF = "identity: ", "proof: "
#: the draws the verifier makes (``certify --identities`` makes 2), and the most it tries for them
DRAWS, MAX_ATTEMPTS = 2, 20
#: the largest dimension whose ``proof:`` records are re-derived in SymPy (measured on a loaded
#: 2-core machine: the Euler top's 19 proof records, N = 3, in 2.5 s, its whole ``verify`` in 2.8 s;
#: the engine's own proofs reach N = 4, where the family's n = 2 takes it 6 s with python-flint),
#: and the time budget for all of them (seconds; checked between records and at each constant of
#: the field)
PROOF_MAX_DIM, PROOF_BUDGET = 3, 60.0
#: the longest recorded residual of a proof record parsed (the engine abbreviates beyond 300 characters)
RESIDUAL_CHARS = 10_000
#: the prime of the random point at which the proof records are listed (their names do not depend on it)
NAMES_PRIME = 4611686018420360881


def identity_claim(statement: str, N: int) -> str:
    return f"{statement} [as an identity in (x, eps): x0 random in F_P^{N}, one step]"


def proof_claim(statement: str) -> str:
    return f"{statement} [as an identity of rational functions in (x, eps), one step]"


def _is_rank(rec) -> bool:
    return rec.name.startswith("rank ")


# --- identities over F_P ----------------------------------------------------------------------

_PROBABILISTIC = re.compile(
    r"probabilistic over F_(\d+) with failure bound <= (\S+); (\d+) random points in F_P\^(\d+), cleared numerator "
    r"degree <= (\d+) in \(x, eps\), bound \(d/\(P - S\*D1 - 1\)\)\^k with S = (\d+) checks, D1 = (\d+) \(the degree "
    r"of the denominators one check divides by\)")
_NOTE = r"(; \d+ singular draw\(s\) redrawn \(first: .*\))?"


def stated_bound(d, S, D1, P, k) -> float:
    """(d/(P − S·D1 − 1))^k, 1 where the slack is not positive (no guarantee)."""
    slack = P - S * D1 - 1
    return min(1.0, d / slack) ** k if slack > 0 else 1.0


class Identities:
    """The ``identity:`` records re-derived at the verifier's own draws over F_P (``arith`` = gf:P,
    read from the certificate's first identity record)."""

    def __init__(self, cert, data, chosen, arith, seed=None):
        self.cert, self.data, self.chosen, self.arith = cert, data, chosen, arith
        try:
            F = exact_field(arith)
        except (InputError, Undefined) as exc:
            raise Undefined(f"arith {str(arith)[:60]!r}: {exc}") from None
        if not isinstance(F, _PrimeField):
            raise Undefined(f"arith {str(arith)[:60]!r} is not gf:P (identity records are over F_P)")
        self.F, self.P, self.N = F, F.P, cert.system.dim
        self.signs = family(data).generic_signs(cert.system, F)
        self.seed = secrets.randbits(64) if seed is None else seed
        self.draws, self.singular = [], []
        rng = random.Random(self.seed)
        while len(self.draws) < DRAWS:
            if len(self.draws) + len(self.singular) >= MAX_ATTEMPTS:
                raise Undefined(f"only {len(self.draws)} of {DRAWS} draws over F_{self.P} were regular in "
                                f"{MAX_ATTEMPTS} (first singular: {self.singular[0][:100]})")
            x, e = [F.of(rng.randrange(self.P)) for _ in range(self.N)], F.of(rng.randrange(self.P))
            if e == 0:
                self.singular.append("eps = 0")
                continue
            try:
                ctx = Context(cert, data, F, point=(x, e), arith=arith, signs=self.signs)
                recs, _ = expected_records(ctx, chosen)
            except UNDEFINED as exc:
                self.singular.append(f"a step or a statement is undefined: {exc}")
                continue
            results = [rederive(r) for r in recs]
            bad = next((r.name for r, (h, _, _) in zip(recs, results) if r.expected and not _is_rank(r) and h is None),
                       None)
            if bad is not None:
                self.singular.append(f"{bad} is undefined")
                continue
            self.draws.append((recs, results))
        self.records = {IDENTITY + r.name: i for i, r in enumerate(self.draws[0][0])}
        self.names, self.why = list(self.records), None

    def rederives(self, name) -> bool:
        return name in self.records

    def about(self) -> str:
        redrawn = f", {len(self.singular)} singular draw(s) redrawn" if self.singular else ""
        return f"{DRAWS} fresh draws of its own over F_{self.P} (seed {self.seed}{redrawn})"

    def merged(self, i):
        """(holds, residual, applicable, the draw that decided) of record i over the draws; for a
        claim, holds True means zero at every draw (the bound decides it later)."""
        rec = self.draws[0][0][i]
        at = [results[i] for _, results in self.draws]
        false = next((j for j, (h, _, a) in enumerate(at) if h is False and a), None)
        if _is_rank(rec):
            j = next((j for j, (h, _, _) in enumerate(at) if h is True), 0)
            return (*at[j], j)
        if false is not None:
            return (*at[false], false)
        if not rec.expected:
            return (*at[0], 0)
        return (True if all(h for h, _, _ in at) else None, "0", True, 0)

    def check(self, c, counts):
        """(re-derived record, problem or None, detail) of the recorded identity record ``c``;
        ``counts``: (claim records with a bound, non-rank claim records) of the certificate."""
        i = self.records[c["name"]]
        rec = self.draws[0][0][i]
        d = dict(c)
        problem = differs((("claim", identity_claim(rec.claim, self.N), c["claim"]),
                           ("expected", rec.expected, c["expected"]), ("arith", self.arith, c["arith"])), "")
        if problem:
            return d, problem, None
        holds, residual, applicable, j = self.merged(i)
        evidence, P = c.get("evidence", ""), self.P
        if holds is False and c["holds"] is not False and applicable:  # a refutation is exact: said first
            return d, (f"recorded holds = {_tf(c['holds'])}, re-derived holds = false (refuted at draw {j}: a "
                       f"nonzero residual {residual} mod P)"), None
        note = ""
        if _is_rank(rec):
            pattern = (rf"exact over F_{P}: rank r at a random point proves generic rank r over Q \(a nonzero r x r "
                       rf"minor mod P\){_NOTE}")
            how = f"{residual} at draw {j}: generic rank (a nonzero minor mod P is one over Q)"
        elif holds is False:
            pattern = rf"exact refutation over F_{P}: nonzero residual at a regular point \(draw \d+\){_NOTE}"
            how = f"refuted at draw {j} (a nonzero residual refutes exactly)"
        elif not rec.expected:
            pattern = rf"exact over F_{P}: held at the {DRAWS} random points \(x, eps\){_NOTE}"
            how = "held at every draw" if holds else "undefined at every draw"
        elif evidence.startswith("not available in the identity mode"):
            pattern = r"not available in the identity mode: no degree bound stated for this check"
            holds, residual = None, "n/a"
            how = "no degree bound stated (undecided, as the engine decides it); zero at every draw"
        else:
            m = _PROBABILISTIC.match(evidence)
            if m is None or not re.fullmatch(_NOTE, evidence[m.end():]):
                return d, f"evidence is {_short(evidence)}, but re-derived it is the Schwartz–Zippel bound " \
                          f"'probabilistic over F_{P} with failure bound <= ...'", None
            shown = m.group(2)
            p, k, dims, deg, S, D1 = (int(m.group(g)) for g in (1, 3, 4, 5, 6, 7))
            low, high = counts
            if (p, k, dims) != (P, DRAWS, self.N + 1) or not low <= S <= high:
                S_range = f"S = {low}" if low == high else f"S from {low} to {high}"
                return d, (f"evidence states P = {p}, {k} random points in F_P^{dims}, S = {S} checks; re-derived: "
                           f"P = {P}, {DRAWS} points in F_P^{self.N + 1}, {S_range}"), None
            if shown != f"{stated_bound(deg, S, D1, P, k):.4g}":
                return d, (f"evidence states failure bound <= {shown}, but (d/(P - S*D1 - 1))^k with its own d = "
                           f"{deg}, S = {S}, D1 = {D1}, k = {k} is {stated_bound(deg, S, D1, P, k):.4g}"), None
            mine = stated_bound(deg, S, D1, P, DRAWS)
            if holds and mine >= 1.0:
                holds, how = None, "zero at every draw, but P is too small for a bound below 1: undecided"
            else:
                how = "zero at every draw" if holds else "undefined"
            note = (f"; failure bound <= {mine:.4g} = (d/(P - S*D1 - 1))^{DRAWS} with the record's degree bound "
                    f"d = {deg}, S = {S}, D1 = {D1} (the engine's Deg of the claim: read, not re-derived)")
            pattern = None
        if pattern is not None and not re.fullmatch(pattern, evidence):
            return d, f"evidence is {_short(evidence)}, but re-derived it is {_short(_readable(pattern))}", None
        d.update(holds=holds, applicable=applicable, _rederived=True)
        if holds is False:  # a residual of another draw: nonzero mod P, not the same value
            try:
                same = self.F.parse(c["residual"], "residual") != 0
            except InputError:
                same = False
            shown = "a nonzero residue mod P"
        else:  # '0', 'n/a' or 'rank r'
            same, shown = c["residual"] == residual, repr(residual)
        problem = outcome_differs(c, holds, same, shown, applicable, how=f" ({how})")
        if problem:
            return d, problem, None
        kind = "claim" if rec.expected else "control"
        if not applicable:
            how = "inapplicable (cannot fail for this system)"
        return d, None, f"identity {kind}, re-derived at {self.about()}: {how}{note}; as recorded"


# --- symbolic proofs, in SymPy ------------------------------------------------------------------


class OverBudget(Exception):
    """The proof records' time budget is spent."""


class _SymPyField:
    """Q(x_0, …, x_{N−1}, ε): SymPy's field of rational functions (``sympy.polys.fields``)."""

    def __init__(self, names, deadline):
        from sympy import QQ
        from sympy.polys.fields import field

        self.K, *self.gens = field(",".join(names), QQ)
        self.names, self.deadline = names, deadline
        self.name = f"Q({', '.join(names)})"
        self.one, self.zero = self.K.one, self.K.zero

    def of(self, q):
        from fractions import Fraction

        from sympy import QQ

        if time.monotonic() > self.deadline:
            raise OverBudget()
        q = Fraction(q)
        return self.K(QQ(q.numerator, q.denominator))

    def root_of_unity(self, n):
        if n <= 2:
            return self.of(-1 if n == 2 else 1)
        raise Undefined(f"Q(x, eps) has no primitive {n}-th root of unity")

    def parse(self, text: str):
        """A rational function as python-flint prints it ('(x0^2 - 1/2*eps)/(x1)'), or None if
        it is not one (e.g. abbreviated)."""
        from sympy import Symbol
        from sympy.parsing.sympy_parser import parse_expr

        # only numbers, the symbols and + - * / ^ ( ): nothing else reaches SymPy's parser (which evaluates)
        if len(text) > RESIDUAL_CHARS or not re.fullmatch(r"[0-9a-z_^*/+\- ()]+", text) or \
                not set(re.findall(r"[a-z_]\w*", text)) <= set(self.names):
            return None
        try:
            expr = parse_expr(text.replace("^", "**"), local_dict={s: Symbol(s) for s in self.names},
                              evaluate=True)
            return self.K.from_expr(expr)
        except Exception:  # noqa: BLE001 - not a rational function in these symbols
            return None


class Proofs:
    """The ``proof:`` records re-derived over SymPy's Q(x, ε), up to :data:`PROOF_MAX_DIM` and
    within ``budget`` seconds; :attr:`why` says why not (then they are not re-checked)."""

    def __init__(self, cert, data, chosen, budget=PROOF_BUDGET):
        self.cert, self.data, self.chosen = cert, data, chosen
        N = cert.system.dim
        self.N, self.why, self.results = N, None, {}
        self.arith = "qfunc[" + ",".join([f"x{i}" for i in range(N)] + ["eps"]) + "]"
        self.signs = family(data).generic_signs(cert.system, _PrimeField(2))  # the rational involutions
        t0 = time.monotonic()
        # the list of records (names and statements) at a point of F_P: it does not depend on the point
        F, rng = _PrimeField(NAMES_PRIME), random.Random(0)
        for _ in range(MAX_ATTEMPTS):
            try:
                point = [F.of(rng.randrange(F.P)) for _ in range(N)], F.of(rng.randrange(1, F.P))
                ctx = Context(cert, data, F, point=point, arith=self.arith, signs=self.signs)
                self.names = [PROOF + r.name for r in expected_records(ctx, chosen)[0]]
                break
            except UNDEFINED:
                continue
        else:  # not met: a step or a statement undefined at 20 random points of F_P
            raise Undefined(f"the proof records cannot be listed: undefined at {MAX_ATTEMPTS} random points")
        if N > PROOF_MAX_DIM:
            self.why = (f"a symbolic proof in dimension {N}: this verifier re-derives proofs up to dimension "
                        f"{PROOF_MAX_DIM} (PROOF_MAX_DIM)")
            return
        try:
            K = _SymPyField([f"x{i}" for i in range(N)] + ["eps"], t0 + budget)
            ctx = Context(cert, data, K, point=(K.gens[:N], K.gens[N]), arith=self.arith, signs=self.signs)
            recs, _ = expected_records(ctx, chosen)
            for r in recs:
                if time.monotonic() > t0 + budget:
                    raise OverBudget()
                self.results[PROOF + r.name] = (r, rederive(r))
        except OverBudget:
            self.why = f"a symbolic proof beyond the verifier's time budget of {budget:g} s (PROOF_BUDGET)"
        self.K, self.seconds = (K if self.why is None else None), time.monotonic() - t0

    def rederives(self, name) -> bool:
        return self.why is None and name in self.results

    def check(self, c, counts=None):
        """(re-derived record, problem or None, detail) of the recorded proof record ``c``."""
        rec, (holds, residual, applicable) = self.results[c["name"]]
        d = dict(c)
        ring = f"Q({', '.join(self.K.names)})"
        if _is_rank(rec):
            evidence = f"symbolic proof: rank over {ring}"
        elif holds is None:
            evidence = f"symbolic: not decided in {ring}"
        else:
            evidence = (f"symbolic proof: identity in {ring}" if holds else
                        f"symbolic disproof: a nonzero difference in {ring}")
        problem = differs((("claim", proof_claim(rec.claim), c["claim"]), ("expected", rec.expected, c["expected"]),
                           ("arith", self.arith, c["arith"]), ("evidence", evidence, c.get("evidence"))), " in SymPy")
        if problem:
            return d, problem, None
        d.update(holds=holds, applicable=applicable, _rederived=True)
        recorded, how = c["residual"], "equal"
        if isinstance(residual, str):
            same = recorded == residual
        else:
            value = self.K.parse(recorded)
            if value is None and holds is False and re.search(r"\.\.\. \(\d+ characters\)$", recorded):
                same, how = True, "nonzero (the recorded one is abbreviated: not compared by value)"
            else:
                same = value is not None and value - residual == 0
        problem = outcome_differs(c, holds, same, _short(str(residual)), applicable, " in SymPy")
        if problem:
            return d, problem, None
        kind = "claim" if rec.expected else "control"
        state = "inapplicable" if not applicable else f"holds = {_tf(holds)}, residual {how}"
        return d, None, f"proof {kind}, re-derived in SymPy's {ring}: {state}; as recorded"


def _readable(pattern: str) -> str:
    """An evidence pattern as text: 'draw k' for a number, without the optional redraw note."""
    return pattern.replace(_NOTE, "").replace(r"\d+", "k").replace("\\", "")
