"""Invariant measures of a Kahan map from discrete Darboux polynomials.

A density m is preserved when m(x̃)·det dΦ(x) = m(x) (x̃ = Φ(x); the measure m dx).
With P a *Darboux polynomial* of cofactor C, P(x̃) = C(x)·P(x) (Celledoni, Evripidou,
McLaren, Owren, Quispel, Tapley, arXiv:1902.04685), a product of Darboux
polynomials whose cofactors multiply to det dΦ gives the density 1/Π P.  At a fixed
ε the search is linear in P's coefficients once the cofactor is fixed; the
cofactors tried are built from the factorisation of det dΦ over Q
(:mod:`.darboux`): det dΦ = κ·Π a_i^k_i, and for every g dividing all k_i with κ a
g-th power in Q, C = ±κ^(1/g)·Π a_i^(k_i/g) (the product of any g Darboux
polynomials of this cofactor is a density denominator); g = 1 gives the densities
1/P directly, and C = 1/det dΦ the polynomial densities P.  All monomials of degree
≤ D are the candidates; the kernel of P(x̃) − C(x)P(x) at random points of F_p^N is
lifted to Q (:func:`~.darboux.lifted_kernel`).  Each Darboux polynomial is factored
over Q and the cofactor of every factor is computed exactly as a rational function
and written over the factors of A = det(I − εf′) and det dΦ.

**Verification** of each density m = U/V (U, V polynomials of degrees u, v):

* exactly, m(x̃)·det dΦ(x) = m(x) at the points of a fresh exact orbit (Fractions;
  det dΦ = det(I + εf′(x̃))/det(I − εf′(x)));
* as an identity over F_p, at random points of a prime not used to find it: after
  clearing denominators the identity is G(x) = 0 with deg G ≤ (N + 1)(u + v + N),
  so a G ≢ 0 passes k points where A ≠ 0 with probability ≤ (deg G/(p − N))^k
  (Schwartz–Zippel, conditioned on A(x) ≠ 0, deg A ≤ N);
* negative control (must fail): m·(1 + x_j), j a coordinate that changes along the
  fresh orbit, is not preserved (inapplicable when every coordinate is constant
  along it, e.g. at a fixed point).

>>> from exact_khk.systems.expressions import ExpressionSystem
>>> lv = ExpressionSystem.from_expressions(["x", "y"], field=["x - x*y", "x*y - y"])
>>> res = find_measure(lv, degree=2, eps="1/10")
>>> [d.text for d in res.densities]
['1/(x*y)']
"""

from __future__ import annotations

import random
import time
from dataclasses import dataclass
from fractions import Fraction
from math import comb

from exact_khk.diagnostics.darboux import (MARGIN, ModMap, _Evaluator, cofactor, eval_poly, exact_orbit, fresh_point,
                                           lifted_kernel, mpoly_dict, mpoly_text, primitive, rows_of_points,
                                           symbolic_map)
from exact_khk.diagnostics.degrees import eps_of, random_primes, resolve_field
from exact_khk.diagnostics.kernels import monomials, poly_text
from exact_khk.errors import InputError
from exact_khk.parsing import check_count

#: random points of the identity check over F_p
SZ_POINTS = 8


def expr(poly: dict, variables) -> str:
    """A polynomial in system-file syntax (``**`` for powers)."""
    return poly_text(poly, variables).replace("^", "**")


def _paren(text, ops=" +-/"):
    return text if all(c not in text for c in ops) else f"({text})"


@dataclass(frozen=True)
class Check:
    """One verification: what was checked, whether it holds (None: inapplicable), and how."""

    name: str
    holds: object
    detail: str

    def to_json(self):
        return {"name": self.name, "holds": self.holds, "detail": self.detail}


@dataclass(frozen=True)
class Darboux:
    """A Darboux polynomial P(x̃) = C(x)·P(x)."""

    polynomial: str
    cofactor: str
    factors: tuple   # ((factor text, its cofactor text), ...)
    polys: tuple = ()  # P and its irreducible factors as ((exponents, Fraction), ...) tuples

    def to_json(self):
        return {"polynomial": self.polynomial, "cofactor": self.cofactor,
                "factors": [{"polynomial": a, "cofactor": b} for a, b in self.factors]}


@dataclass(frozen=True)
class Density:
    """A preserved density num/den and its checks."""

    text: str            # system-file syntax
    num: tuple           # ((exponents, Fraction), ...)
    den: tuple
    checks: tuple

    @property
    def verified(self) -> bool:
        """The exact orbit check held, no other check failed, and every applicable control failed."""
        return any(c.name == "exact orbit" and c.holds is True for c in self.checks) and all(c.holds is not False for c in self.checks if not c.name.startswith("control")) and \
            all(c.holds is not True for c in self.checks if c.name.startswith("control"))

    def to_json(self):
        return {"density": self.text, "verified": self.verified, "checks": [c.to_json() for c in self.checks]}


@dataclass(frozen=True)
class MeasureSearch:
    label: str
    eps: Fraction
    degree: int
    variables: tuple
    factors: tuple         # texts of the irreducible factors F1, F2, ... of A and det dΦ
    det_text: str          # det dΦ over the factors
    searches: tuple        # ((cofactor text, kernel dimension), ...)
    darboux: tuple
    densities: tuple
    primes: tuple
    notes: tuple
    seconds: float

    def to_json(self):
        return {"field": self.label, "eps": str(self.eps), "degree": self.degree, "factors": list(self.factors),
                "det_dPhi": self.det_text,
                "searches": [{"cofactor": c, "kernel_dim": k} for c, k in self.searches],
                "darboux": [d.to_json() for d in self.darboux],
                "densities": [d.to_json() for d in self.densities], "primes": list(self.primes),
                "notes": list(self.notes), "seconds": self.seconds}

    def toml(self) -> str:
        """A ``[measure]`` block of a system file (the first verified density), or a comment."""
        good = [d for d in self.densities if d.verified]
        if not good:
            return f"# no preserved density found at degree <= {self.degree}\n"
        return f'[measure]\n# found by exact-khk find-measure at eps = {self.eps}\ndensity = "{good[0].text}"\n'

    def summary(self) -> str:
        out = [f"measure search for {self.label} at eps = {self.eps}: Darboux polynomials of degree <= {self.degree}"]
        if self.factors:
            out.append("  factors over Q of A = det(I - eps f') and det dPhi:")
            out += [f"    F{i} = {t}" for i, t in enumerate(self.factors, 1)]
            out.append(f"  det dPhi = {self.det_text}")
        for c, k in self.searches:
            out.append(f"  cofactor {c}: {k} Darboux polynomial(s)")
        for d in self.darboux:
            out.append(f"  Darboux polynomial {d.polynomial}")
            out.append(f"    cofactor {d.cofactor}")
            if len(d.factors) > 1 or (d.factors and d.factors[0][0] != d.polynomial):
                out += [f"    factor {a}: cofactor {b}" for a, b in d.factors]
        if not self.densities:
            out.append(f"  no preserved density 1/P or P with P of degree <= {self.degree} (nothing found)")
        for d in self.densities:
            out.append(f"  density m = {d.text}  [{'VERIFIED' if d.verified else 'NOT verified'}]")
            for c in d.checks:
                mark = {True: "holds", False: "fails", None: "inapplicable"}[c.holds]
                out.append(f"    {c.name}: {mark} ({c.detail})")
        out += [f"  note: {n}" for n in self.notes]
        out.append(f"  primes {len(self.primes)}; time {self.seconds:.2f} s")
        return "\n".join(out)


def find_measure(system, degree=2, field="f", eps=None, seed=0, verify_steps=4, x0=None,
                 progress=None) -> MeasureSearch:
    """Darboux polynomials and preserved densities of the Kahan map (module docstring); ``x0``:
    the start of the exact orbit check (default a fresh reproducible point)."""
    t0 = time.perf_counter()
    stage = progress or (lambda name: None)
    sysobj, fld = resolve_field(system, field)
    eps = eps_of(sysobj, eps)
    N = fld.dim
    check_count(degree, "degree", 1, 12)
    check_count(verify_steps, "verify_steps", 1, 100)
    variables = _variables(sysobj, N)
    exps = monomials(N, degree)
    m = len(exps)
    if m > 3000:
        raise InputError(f"degree: {m} candidate monomials of degree <= {degree} in {N} variables exceed 3000")
    notes, primes = [], set()
    stage("det dPhi over Q")
    sym = symbolic_map(fld, eps)
    factor_texts, det_text, cands = (), "", []
    if sym is None:
        notes.append(f"dimension {N} > 4: det dPhi is not factored over Q; only the cofactors det dPhi^(+-1) are tried")
        cands = [("det dPhi", None, 1, 1), ("1/det dPhi", None, -1, 1)]
    else:
        factor_texts = tuple(mpoly_text(g, variables) for g in sym.factors)
        const, ks = sym.express(sym.det_num, sym.det_den)
        det_text = _over_factors(Fraction(int(const.p), int(const.q)), ks)
        cands = [("det dPhi", None, 1, 1)]
        for g in _root_orders(const, ks):
            for sign in ((1, -1) if g % 2 == 0 else (1,)):
                root = sign * _rational_root(Fraction(int(const.p), int(const.q)), g)
                cands.append((_over_factors(root, {k: e // g for k, e in ks.items()}),
                              (root, {k: e // g for k, e in ks.items()}), 1, g))
        cands.append(("1/det dPhi", None, -1, 1))
    ev = _Evaluator(exps)
    searches, darboux, densities = [], [], []
    for text, root, power, g in cands:
        cof = _cofactor_mod(sym, root, power)

        def make_rows(p, rng, cof=cof):
            mm = ModMap(fld, eps, p)
            return rows_of_points(N, m + MARGIN, mm, lambda at: _row(ev, at, cof, p), rng)

        stage(f"Darboux polynomials, cofactor {text}")
        basis, used = lifted_kernel(make_rows, m, seed, progress=progress)
        primes.update(used)
        searches.append((text, len(basis)))
        polys = [primitive({e: c for e, c in zip(exps, v) if c}) for v in basis]
        if not polys:
            continue
        for P in polys:
            darboux.append(_darboux(sym, P, text, variables, N))
        if power == -1:
            dens = [(P, {(0,) * N: Fraction(1)}) for P in polys[:1]]
        elif g == 1:
            dens = [({(0,) * N: Fraction(1)}, P) for P in polys[:1]]
        else:
            prod = {(0,) * N: Fraction(1)}
            chosen = (polys * g)[:g] if len(polys) < g else polys[:g]
            for P in chosen:
                prod = _mul(prod, P)
            dens = [({(0,) * N: Fraction(1)}, prod)]
        for num, den in dens:
            if any(_same_ratio(num, den, d) for d in densities):
                continue
            stage("verify the density")
            shown = None if power == -1 or g == 1 else \
                "1/(" + "*".join(_paren(expr(P, variables), " +-/") for P in chosen) + ")"
            densities.append(_verify(fld, eps, num, den, variables, seed, verify_steps, primes, shown, x0))
        if len(polys) > 1:
            notes.append(f"cofactor {text}: {len(polys)} independent Darboux polynomials; their ratios are conserved "
                         f"(integrals), so the density is determined up to such a factor")
    if not densities:
        notes.append("nothing found: no Darboux polynomial of degree <= "
                     f"{degree} with the cofactors tried gives a density (a kernel 0 modulo a prime proves that none "
                     "exists over Q for that cofactor; try a higher --degree)")
    label = f"{sysobj.name if sysobj is not None else 'field'} {fld.label}"
    return MeasureSearch(label, eps, degree, tuple(variables), factor_texts, det_text, tuple(searches),
                         tuple(darboux), tuple(densities), tuple(sorted(primes)), tuple(notes),
                         time.perf_counter() - t0)


def _variables(sysobj, N):
    variables = list(getattr(sysobj, "variables", ()) or ())
    if len(variables) != N or getattr(sysobj, "kind", "") == "lie-poisson":
        variables = [f"x{i}" for i in range(N)]
    return variables


def _row(ev, at, cof, p):
    """The row φ_j(x̃) − C(x)·φ_j(x) of P(x̃) = C(x)·P(x) (none where C has a pole)."""
    x, xt, _, A, B = at
    c = cof(x, xt, A, B, p)
    if c is None:
        return []
    return [[(a - c * b) % p for a, b in zip(ev(xt, 1, p), ev(x, 1, p))]]


def _root_orders(const, ks):
    """The g > 1 dividing every exponent with the constant a g-th power in Q."""
    from math import gcd

    G = 0
    for e in ks.values():
        G = gcd(G, e)
    c = Fraction(int(const.p), int(const.q))
    return [g for g in range(2, G + 1) if G % g == 0 and _rational_root(c, g) is not None]


def _rational_root(c: Fraction, g: int):
    """The positive g-th root of |c| in Q when it exists and c > 0 or g odd, else None."""
    if c < 0 and g % 2 == 0:
        return None

    def iroot(n):
        r = round(abs(n) ** (1.0 / g))
        for s in (r - 1, r, r + 1):
            if s >= 0 and s ** g == abs(n):
                return s
        return None
    a, b = iroot(c.numerator), iroot(c.denominator)
    if a is None or b is None:
        return None
    return Fraction(a, b) * (-1 if c < 0 else 1)


def _over_factors(const, ks) -> str:
    num = [f"F{k + 1}" + (f"**{e}" if e > 1 else "") for k, e in sorted(ks.items()) if e > 0]
    den = [f"F{k + 1}" + (f"**{-e}" if e < -1 else "") for k, e in sorted(ks.items()) if e < 0]
    text = "*".join(([str(const)] if const != 1 or not num else []) + num)
    if den:
        text += "/" + (den[0] if len(den) == 1 else "(" + "*".join(den) + ")")
    return text


def _cofactor_mod(sym, root, power):
    """The cofactor at a point mod p: (x, x̃, A, B, p) ↦ value."""
    if root is None:
        return lambda x, xt, A, B, p: (B * pow(A, -1, p)) % p if power == 1 else \
            None if B == 0 else (A * pow(B, -1, p)) % p
    const, ks = root
    polys = [(mpoly_dict(sym.factors[k]), e) for k, e in ks.items()]

    def value(x, xt, A, B, p):
        v = const.numerator * pow(const.denominator, -1, p)
        for poly, e in polys:
            w = eval_poly({k: c.numerator * pow(c.denominator, -1, p) for k, c in poly.items()}, x) % p
            if w == 0:
                return None
            v = v * pow(w, e, p)
        return v % p
    return value


def _mul(a, b):
    out = {}
    for e1, c1 in a.items():
        for e2, c2 in b.items():
            e = tuple(i + j for i, j in zip(e1, e2))
            out[e] = out.get(e, 0) + c1 * c2
    return {e: c for e, c in out.items() if c}


def _same_ratio(num, den, d):
    return dict(d.num) == num and dict(d.den) == den


def _darboux(sym, P, text, variables, N) -> Darboux:
    """P with its cofactor ``text``, and its factors over Q with their exact cofactors."""
    if sym is None:
        return Darboux(expr(P, variables), text, (), (tuple(sorted(P.items())),))
    from exact_khk.diagnostics.darboux import _q

    poly = sym.ctx.from_dict({e: _q(c) for e, c in P.items()})
    facs, polys = [], [tuple(sorted(P.items()))]
    if not poly.is_constant():
        for h, _ in poly.factor()[1]:
            hp = primitive(mpoly_dict(h))
            if tuple(sorted(hp.items())) not in polys:
                polys.append(tuple(sorted(hp.items())))
            cn, cd = cofactor(sym, h)
            ex = sym.express(cn, cd)
            ctext = _over_factors(Fraction(int(ex[0].p), int(ex[0].q)), ex[1]) if ex is not None else \
                f"({expr(mpoly_dict(cn), variables)})/({expr(mpoly_dict(cd), variables)})"
            facs.append((expr(primitive(mpoly_dict(h)), variables), ctext))
    return Darboux(expr(P, variables), text, tuple(facs), tuple(polys))


def _verify(fld, eps, num, den, variables, seed, steps, used, shown=None, x0=None) -> Density:
    """The exact orbit check, the identity over F_p and the negative control (module docstring)."""
    N = fld.dim
    u = max(sum(e) for e in num)
    v = max(sum(e) for e in den)
    ntext, dtext = expr(num, variables), expr(den, variables)
    text = shown or (ntext if dtext == "1" else f"{_paren(ntext)}/{_paren(dtext, ' +-/*')}")
    checks = []
    orbit = _fresh_orbit(fld, eps, seed, steps, num, den, x0)
    if orbit is None:
        checks.append(Check("exact orbit", None, "no orbit avoiding the poles and singular steps was found"))
    else:
        x0, data = orbit

        def holds(fn, dn):
            return all(eval_poly(fn, xt) * eval_poly(dn, x) * B == eval_poly(fn, x) * eval_poly(dn, xt) * A
                       for x, xt, A, B, _ in data)
        checks.append(Check("exact orbit", holds(num, den),
                            f"m(x~) det dPhi(x) = m(x) with Fractions at {len(data)} points of the orbit of "
                            f"({', '.join(map(str, x0))})"))
        moving = next((j for j in range(N) if any(x[j] != xt[j] for x, xt, *_ in data)), None)
        if moving is None:
            checks.append(Check("control: perturbed density", None, "every coordinate is constant along the orbit"))
        else:
            e1 = tuple(int(i == moving) for i in range(N))
            pert = dict(num)
            for e, c in num.items():  # num * (1 + x_j)
                s = tuple(a + b for a, b in zip(e, e1))
                pert[s] = pert.get(s, 0) + c
            checks.append(Check("control: perturbed density", holds(pert, den),
                                f"[must fail] m*(1 + {variables[moving]}) preserved on the same orbit"))
    p = next(q for q in random_primes(len(used) + 8, seed + 7919) if q not in used)
    mm, rng = ModMap(fld, eps, p), random.Random(f"sz-{seed}")
    nm = {e: c.numerator * pow(c.denominator, -1, p) for e, c in num.items()}
    dm = {e: c.numerator * pow(c.denominator, -1, p) for e, c in den.items()}
    ok, k = True, 0
    while k < SZ_POINTS:
        at = mm.at([rng.randrange(p) for _ in range(N)])
        if at is None:
            continue
        x, xt, _, A, B = at
        k += 1
        ok = ok and (eval_poly(nm, xt) * eval_poly(dm, x) * B - eval_poly(nm, x) * eval_poly(dm, xt) * A) % p == 0
    D = (N + 1) * (u + v + N)
    checks.append(Check("identity over F_p", ok, f"{SZ_POINTS} random points mod a fresh {p.bit_length()}-bit prime; "
                        f"deg G <= {D}, false pass <= ({D}/(p - {N}))^{SZ_POINTS} < 2^-"
                        f"{int(SZ_POINTS * (p.bit_length() - 1 - D.bit_length()))}"))
    return Density(text, tuple(sorted(num.items())), tuple(sorted(den.items())), tuple(checks))


def _fresh_orbit(fld, eps, seed, steps, num, den, start=None):
    """(x0, exact orbit data) from ``start`` if given, else the first of 20 fresh reproducible points
    whose orbit avoids singular steps and the poles of num/den (None when none does)."""
    from exact_khk.errors import SingularStepError

    for t in range(1 if start is not None else 20):
        x0 = tuple(start) if start is not None else fresh_point(f"{seed}-{t}", fld.dim)
        try:
            data = exact_orbit(fld, eps, x0, steps)
        except (SingularStepError, ZeroDivisionError, StopIteration):
            continue
        if all(eval_poly(den, x) != 0 and eval_poly(den, xt) != 0 for x, xt, *_ in data):
            return x0, data
    return None
