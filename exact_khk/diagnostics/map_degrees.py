"""Degrees of the iterates of a homogeneous polynomial map of projective space, over F_p on a line.

A map F = [F_0 : … : F_N] of P^N given by homogeneous polynomials of one degree (Sage's
``DynamicalSystem_projective``; for instance [Z², XY, Y²]) is iterated on a random line
ℓ(t) = a + t·b of F_p^{N+1}: each component becomes a polynomial in t (``nmod_poly``), the
gcd of the N + 1 components is divided out after every step, and the degree of what
remains is d_k, the degree of Φ^k restricted to the line.  As for Kahan maps
(:mod:`~exact_khk.diagnostics.degrees`), this never overcounts d_k = deg F^{∘k} (after
removing common factors), and undercounts with probability at most 2·d_k(d_k + 1)/p
per line at a good prime; the reported sequence is the maximum over the runs.

This is for maps that are not Kahan maps — the honesty tests of the recurrence fit use
two of Sage's doctest maps — and for users who have a map rather than a vector field.

>>> r = map_degrees(["Z**2", "X*Y", "Y**2"], ["X", "Y", "Z"], steps=6)
>>> r[:7]
(1, 2, 3, 5, 8, 11, 17)
"""

from __future__ import annotations

import math
import random
import re

import flint

from exact_khk.diagnostics.degrees import check_primes
from exact_khk.errors import InputError
from exact_khk.parsing import any_int_digits, check_count

MAX_STEPS = 10_000
#: the largest degree of an iterate on a line (nmod_poly of 10^5 terms: seconds per step)
MAX_DEGREE = 100_000


def parse_map(components, variables) -> list:
    """The components as lists of (exponent tuple, integer coefficient), all of one degree ≥ 1.
    Rational coefficients are scaled to integers per component only if every component is
    scaled alike (a common factor does not change the projective map)."""
    from exact_khk.systems.expression_parser import Parser, ring

    variables = [str(v).strip() for v in _sequence(variables, "variables")]
    if len(variables) < 2 or len(set(variables)) != len(variables):
        raise InputError(f"variables: expected at least two distinct names, got {variables!r}"[:300])
    bad = [v for v in variables if not _NAME.match(v)]
    if bad:  # the names of a FLINT ring: ASCII identifiers
        raise InputError(f"variables: {bad[0]!r} is not a name (a letter or '_', then letters, digits or '_')"[:300])
    comps = [str(c) for c in _sequence(components, "map")]
    if len(comps) != len(variables):
        raise InputError(f"map: {len(comps)} component(s) for {len(variables)} variable(s): a map of P^N "
                         f"has one component per homogeneous coordinate")
    R = ring(variables)
    gens = dict(zip(variables, R.gens()))
    polys, degree = [], None
    for i, text in enumerate(comps):
        num, den = Parser(text, f"map component {i + 1}", R, gens, {}, ", ".join(variables)).value
        if not den.is_constant():
            raise InputError(f"map component {i + 1}: {text!r} is not a polynomial (clear denominators: a "
                             f"rational map of P^N is given by polynomials of one degree)")
        poly = num / den
        terms = [(tuple(int(e) for e in exps), flint.fmpq(c)) for exps, c in zip(poly.monoms(), poly.coeffs())]
        if not terms:
            raise InputError(f"map component {i + 1}: the zero polynomial")
        degs = {sum(e) for e, _ in terms}
        if len(degs) != 1:
            raise InputError(f"map component {i + 1}: {text!r} is not homogeneous (degrees {sorted(degs)})")
        d = degs.pop()
        if degree is not None and d != degree:
            raise InputError(f"map component {i + 1}: degree {d}, but component 1 has degree {degree}: the "
                             f"components of a map of P^N share one degree")
        degree = d
        polys.append(terms)
    if degree < 1:
        raise InputError("map: constant components do not define a map of P^N")
    den = math.lcm(*(int(c.q) for terms in polys for _, c in terms))
    return [[(e, int(c * den)) for e, c in terms] for terms in polys]


#: a variable name: an ASCII identifier (the rule of system files, exact_khk/systems/expressions.py)
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def _sequence(value, name) -> list:
    """A list or tuple of texts, or a comma-separated text (InputError naming ``name`` otherwise)."""
    if isinstance(value, str):
        return value.split(",")
    if not isinstance(value, (list, tuple)):
        raise InputError(f"{name}: expected a list of texts, got {type(value).__name__}")
    return list(value)


def _apply(polys, vec, p):
    ctx_zero = flint.nmod_poly([], p)
    out = []
    for terms in polys:
        acc = ctx_zero
        for exps, c in terms:
            term = flint.nmod_poly([c % p], p)
            for v, e in zip(vec, exps):
                if e:
                    term *= v ** e
            acc += term
        out.append(acc)
    return out


def _reduce(vec):
    g = None
    for v in vec:
        if v != 0:
            g = v if g is None else g.gcd(v)
    if g is None:
        return None
    return [v // g for v in vec] if g.degree() > 0 else vec


def map_degrees(components, variables, steps=10, primes=2, seed=0, max_degree=MAX_DEGREE) -> tuple:
    """d_0..d_steps of the iterates of the homogeneous polynomial map (module docstring), the
    maximum over one random line per prime; stops before a step whose iterate, before its common
    factor is removed, could exceed degree ``max_degree`` (d_k times the degree of the map)."""
    check_count(steps, "steps", 1, MAX_STEPS)
    check_count(max_degree, "max_degree", 1, 10 ** 7)
    seed = check_count(seed, "seed", -2 ** 63, 2 ** 63)
    polys = parse_map(components, variables)
    degree = sum(polys[0][0][0])
    primes = check_primes(primes, seed=seed)
    runs = []
    for p in primes:
        rng = random.Random(f"map-line-{seed}-{p}")
        for _attempt in range(5):
            vec = [flint.nmod_poly([rng.randrange(p), rng.randrange(p)], p) for _ in polys]
            degs = [max(v.degree() for v in vec)]
            for _ in range(steps):
                if degs[-1] * degree > max_degree:  # the next iterate is computed at up to this degree
                    break
                vec = _reduce(_apply(polys, vec, p))
                if vec is None:
                    break
                degs.append(max(v.degree() for v in vec))
                if degs[-1] > max_degree:
                    break
            if vec is not None:
                runs.append(degs)
                break
    if not runs:
        raise InputError("primes: the map sent every line tried to zero (choose other primes)")
    length = min(len(r) for r in runs)
    return tuple(max(r[k] for r in runs) for k in range(length))


class MapDegrees:
    """:func:`map_degrees` with the recurrence fit (:func:`~exact_khk.diagnostics.recurrence.fit_recurrence`),
    for ``exact-khk degrees --map``.

    >>> r = MapDegrees(["X*Y", "Y*Z + Z**2", "Z**2"], ["X", "Y", "Z"], steps=10)
    >>> r.degrees[:5], r.fit.growth, r.fit.polynomial
    ((1, 2, 3, 4, 5), 'polynomial', 'k + 1')
    """

    def __init__(self, components, variables, steps=20, primes=2, seed=0, confirm=3):
        from exact_khk.diagnostics.degrees import MIN_CONFIRM
        from exact_khk.diagnostics.recurrence import fit_recurrence, too_short

        check_count(confirm, "confirm", MIN_CONFIRM, 1000)  # as for Kahan maps (degree_sequence)
        self.components = [str(c).strip() for c in _sequence(components, "map")]
        self.variables = [str(v).strip() for v in _sequence(variables, "variables")]
        self.primes = check_primes(primes, seed=seed)
        self.degrees = map_degrees(self.components, self.variables, steps=steps, primes=list(self.primes), seed=seed,
                                   max_degree=MAX_DEGREE)
        self.steps = steps
        # as for Kahan maps (degrees.py): 2 d (d + 1)/p per line at a good prime, one line per prime
        self.undercount_bound = max(math.prod(min(1.0, 2 * d * (d + 1) / p) for p in self.primes)
                                    for d in self.degrees)
        try:
            self.fit = fit_recurrence(self.degrees, confirm=confirm)
        except InputError as exc:
            self.fit = too_short(self.degrees, str(exc))

    @any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
    def to_json(self) -> dict:
        return {"map": self.components, "variables": self.variables, "degrees": list(self.degrees),
                "degree_kind": "degree of F^k on P^N after removing the common factor of its components",
                "undercount_bound": self.undercount_bound, "fit": self.fit.to_json()}

    @any_int_digits()
    def summary(self) -> str:
        N = len(self.variables) - 1
        return "\n".join([
            f"degrees of F^k for F = [{' : '.join(self.components)}] on P^{N} "
            f"([{' : '.join(self.variables)}]), k = 0..{len(self.degrees) - 1}:",
            "  " + ", ".join(map(str, self.degrees)),
            f"  over F_p on random lines (never an overcount); P(undercount) <= {self.undercount_bound:.3g} at good "
            "primes (Schwartz-Zippel, 2d(d+1)/p per run)",
            "  " + self.fit.summary().replace("\n", "\n  ")]
            + ([f"  note: stopped after k = {len(self.degrees) - 1} of {self.steps}: the next iterate could pass "
                f"degree {MAX_DEGREE} (MAX_DEGREE)"] if len(self.degrees) <= self.steps else []))
