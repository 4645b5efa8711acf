"""Invariant measures of a Kahan map from discrete Darboux polynomials.

A density m is preserved when m(x̃)·det dΦ(x) = m(x) (x̃ = Φ(x); the measure m dx).
With P a *Darboux polynomial* of cofactor C, P(x̃) = C(x)·P(x) (Celledoni, Evripidou,
McLaren, Owren, Quispel, Tapley, arXiv:1902.04685), a product Π P_i^(n_i) whose
cofactors multiply to det dΦ gives the density 1/Π P_i^(n_i).  Over Q (dimension ≤ 4,
:mod:`.darboux`) det dΦ = κ·Π F_i^(k_i) is factored, the F_i being the irreducible
factors of A = det(I − εf′) (the map's denominator) and of the numerator, and the
cofactors tried are

* det dΦ itself (densities 1/P) and 1/det dΦ (densities P) — in every dimension;
* every c·Π F_i^(e_i) with e_i ∈ [−2, 0] for the factors of A and [0, 2] for the others
  (a Darboux polynomial of degree d has P(x̃) = P^h(Ñ, A)/A^d): the constant c is found
  over F_p as a generalized eigenvalue (:func:`cofactor_candidates`) and lifted to Q.

For a fixed cofactor the condition is linear in P's coefficients over all monomials of
degree ≤ D; its kernel at random points of F_p^N is lifted to Q
(:func:`~.darboux.lifted_kernel`).  The irreducible Darboux polynomials are then
combined: the small integer vectors n with Σ n_i e_i = k and Π c_i^(n_i) = κ give the
densities 1/Π P_i^(n_i).  Every Darboux polynomial is factored over Q and the cofactor
of each factor is computed exactly and written over the F_i.

**Verification** of each density m = U/V (U, V polynomials of degrees u, v):

* exactly, m(x̃)·det dΦ(x) = m(x) at the points of a fresh exact orbit (exact rationals;
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

import flint

from exact_khk.diagnostics.darboux import (MARGIN, ModMap, _Evaluator, cofactor, eval_poly, exact_orbit, fresh_point,
                                           lifted_kernel, mpoly_dict, mpoly_text, primitive, rows_of_points,
                                           symbolic_map)
from exact_khk.diagnostics.degrees import eps_of, random_primes, resolve_field
from exact_khk.diagnostics.kernels import monomials, poly_text, rational_reconstruction
from exact_khk.errors import InputError
from exact_khk.parsing import any_int_digits, check_progress, check_count, parse_vector

#: random points of the identity check over F_p
SZ_POINTS = 8
#: the most candidate monomials for the search over all cofactors c·Π F_i^k_i (one m × m
#: characteristic polynomial per exponent vector, 3^r vectors for r factors)
GENERAL_MAX_UNKNOWNS = 200


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

    @any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
    def to_json(self):
        return {"name": self.name, "holds": self.holds, "detail": self.detail}


def verified(checks) -> bool:
    """The exact orbit check held, no other check failed, and every applicable control failed."""
    return any(c.name == "exact orbit" and c.holds is True for c in checks) \
        and all(c.holds is not False for c in checks if not c.name.startswith("control")) \
        and all(c.holds is not True for c in checks if c.name.startswith("control"))


@dataclass(frozen=True)
class Darboux:
    """A Darboux polynomial P(x̃) = C(x)·P(x)."""

    polynomial: str
    cofactor: str
    factors: tuple   # ((factor text, its cofactor text), ...)
    polys: tuple = ()  # P and its irreducible factors as ((exponents, Fraction), ...) tuples

    @any_int_digits()
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
        return verified(self.checks)

    @any_int_digits()
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
    integrals: tuple = ()  # ((text, conserved on a fresh exact orbit: True/False/None), ...)

    @any_int_digits()
    def to_json(self):
        return {"field": self.label, "eps": str(self.eps), "degree": self.degree, "factors": list(self.factors),
                "det_dPhi": self.det_text,
                "searches": [{"cofactor": c, "kernel_dim": k} for c, k in self.searches],
                "darboux": [d.to_json() for d in self.darboux],
                "densities": [d.to_json() for d in self.densities],
                "integrals": [{"integral": t, "conserved_on_fresh_orbit": ok} for t, ok in self.integrals],
                "primes": list(self.primes),
                "notes": list(self.notes), "seconds": self.seconds}

    @any_int_digits()
    def toml(self) -> str:
        """A ``[measure]`` block of a system file (the first verified density), or a comment."""
        good = [d for d in self.densities if d.verified]
        if not good:
            return f"# no preserved density found at degree <= {self.degree}\n"
        return f'[measure]\n# found by exact-khk find-measure at eps = {self.eps}\ndensity = "{good[0].text}"\n'

    @any_int_digits()
    def summary(self) -> str:
        out = [f"measure search for {self.label} at eps = {self.eps}: Darboux polynomials of degree <= {self.degree}"]
        if self.factors:
            out.append("  factors over Q of A = det(I - eps f') and det dPhi:")
            out += [f"    F{i} = {t}" for i, t in enumerate(self.factors, 1)]
            out.append(f"  det dPhi = {self.det_text}")
        for c, k in self.searches:
            kind = "" if c.endswith("det dPhi") else " (irreducible)"
            out.append(f"  cofactor {c}: {k} Darboux polynomial(s){kind}")
        for d in self.darboux:
            out.append(f"  Darboux polynomial {d.polynomial}")
            out.append(f"    cofactor {d.cofactor}")
            if len(d.factors) > 1 or (d.factors and d.factors[0][0] != d.polynomial):
                out += [f"    factor {a}: cofactor {b}" for a, b in d.factors]
        for t, ok in self.integrals:
            out.append(f"  integral {t} (Darboux polynomials of one cofactor; conserved on a fresh exact orbit: "
                       f"{ {True: 'yes', False: 'NO', None: 'not checked (poles)'}[ok]})")
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


@any_int_digits()
def find_measure(system, degree=2, field="f", eps=None, seed=0, verify_steps=4, x0=None,
                 progress=None) -> MeasureSearch:
    """Darboux polynomials and preserved densities of the Kahan map (module docstring); ``x0``:
    the start of the exact orbit check (default a fresh reproducible point)."""
    t0 = time.perf_counter()
    stage = check_progress(progress) or (lambda name: None)
    sysobj, fld = resolve_field(system, field)
    eps = eps_of(sysobj, eps)
    N = fld.dim
    check_count(degree, "degree", 1, 12)
    check_count(verify_steps, "verify_steps", 1, 100)
    seed = check_count(seed, "seed", -2 ** 63, 2 ** 63)
    x0 = None if x0 is None else parse_vector(x0, "x0", N)  # exact rationals only, as everywhere
    variables = _variables(sysobj, N)
    exps = monomials(N, degree)
    m = len(exps)
    if m > 3000:
        raise InputError(f"degree: {m} candidate monomials of degree <= {degree} in {N} variables exceed 3000")
    notes, primes = [], set()
    stage("det dPhi over Q")
    sym = symbolic_map(fld, eps)
    factor_texts, det_text, kappa, ks = (), "", None, None
    cands = [("det dPhi", None, 1)]
    if sym is None:
        notes.append(f"dimension {N} > 4: det dPhi is not factored over Q; only the cofactors det dPhi^(+-1) are tried")
    else:
        factor_texts = tuple(mpoly_text(g, variables) for g in sym.factors)
        const, ks = sym.express(sym.det_num, sym.det_den)
        kappa = Fraction(int(const.p), int(const.q))
        det_text = _over_factors(kappa, ks)
        stage("cofactors (eigenvalues over F_p)")
        found = cofactor_candidates(fld, eps, sym, exps, seed)
        if found is None:
            notes.append(f"{m} unknowns: beyond {GENERAL_MAX_UNKNOWNS} (GENERAL_MAX_UNKNOWNS) only the cofactors "
                         "det dPhi^(+-1) are tried")
        for c, kk in sorted(found or (), key=lambda t: (sum(map(abs, t[1].values())), sorted(t[1].items()))):
            if (c, kk) != (kappa, ks):
                cands.append((_over_factors(c, kk), (c, kk), 1))
    cands.append(("1/det dPhi", None, -1))
    ev = _Evaluator(exps)
    one = {(0,) * N: Fraction(1)}
    searches, darboux, densities, items, integrals = [], [], [], [], []
    for text, root, power in cands:
        cof = _cofactor_mod(sym, root, power)

        def make_rows(p, rng, cof=cof):
            mm = ModMap(fld, eps, p)
            return rows_of_points(N, m + MARGIN, mm, lambda at: _row(ev, at, cof, p), rng)

        stage(f"Darboux polynomials, cofactor {text}")
        basis, used = lifted_kernel(make_rows, m, seed, progress=progress)
        primes.update(used)
        polys = [primitive({e: c for e, c in zip(exps, v) if c}) for v in basis]
        if root is not None:  # products and powers of irreducible ones are formed below, not listed
            polys = [P for P in polys if _irreducible(sym, P)]
            if not polys:
                continue
        if not polys:
            searches.append((text, 0))
            continue
        searches.append((text, len(polys)))
        for P in polys:
            darboux.append(_darboux(sym, P, text, variables, N))
        if len(polys) > 1:
            notes.append(f"cofactor {text}: {len(polys)} independent Darboux polynomials; their ratios are conserved "
                         f"(integrals), so a density built from them is determined up to such a factor")
        if root is not None:
            items.append((polys, root))
            for P in polys[1:]:
                integrals.append((f"{_paren(expr(P, variables))}/{_paren(expr(polys[0], variables))}",
                                  _conserved_ratio(fld, eps, P, polys[0], seed, verify_steps, x0)))
            continue
        num, den = (polys[0], one) if power == -1 else (one, polys[0])
        if not any(_same_ratio(num, den, d) for d in densities):
            stage("verify the density")
            densities.append(_verify(fld, eps, num, den, variables, seed, verify_steps, primes, None, x0))
    for num, den, shown in _products(items, kappa, ks, N):
        if not any(_same_ratio(num, den, d) for d in densities):
            stage("verify the density")
            densities.append(_verify(fld, eps, num, den, variables, seed, verify_steps, primes,
                                     shown(variables), x0))
    if not densities:
        notes.append("nothing found: no product of Darboux polynomials of degree <= "
                     f"{degree} with the cofactors tried gives a density (a kernel 0 modulo a prime proves that none "
                     "exists over Q for that cofactor; try a higher --degree)")
    label = f"{sysobj.name if sysobj is not None else 'field'} {fld.label}"
    return MeasureSearch(label, eps, degree, tuple(variables), factor_texts, det_text, tuple(searches),
                         tuple(darboux), tuple(densities), tuple(sorted(primes)), tuple(notes),
                         time.perf_counter() - t0, tuple(integrals))


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


def cofactor_candidates(fld, eps, sym, exps, seed, max_exp=2):
    """The cofactors c·Π F_i^k_i of Darboux polynomials in the span of ``exps``, as (c, {i: k_i})
    over Q, or None beyond :data:`GENERAL_MAX_UNKNOWNS`.  Exponents: −max_exp..0 for the factors
    of A (the map's denominator), 0..max_exp for the others.  For each exponent vector the
    constant c is a generalized eigenvalue of the pencil (U, V), U = [φ_j(x̃_k)],
    V = [C₀(x_k)φ_j(x_k)], at random points over F_p: the roots in F_p of the characteristic
    polynomial of (RV)⁻¹RU (R a random projection), kept when U − cV has a kernel, and lifted by
    rational reconstruction (the exact search that follows confirms or drops it)."""
    import itertools

    import flint

    m, N = len(exps), fld.dim
    if m > GENERAL_MAX_UNKNOWNS:
        return None
    p = random_primes(1, seed + 104729)[0]
    in_A = [divmod(sym.A, F)[1].is_zero() for F in sym.factors]
    ranges = [range(-max_exp, 1) if a else range(0, max_exp + 1) for a in in_A]
    rng = random.Random(f"cofactors-{seed}")
    mm = ModMap(fld, eps, p)
    fpolys = [{e: c.numerator * pow(c.denominator, -1, p) % p for e, c in mpoly_dict(F).items()} for F in sym.factors]
    ev = _Evaluator(exps)
    pts, tries = [], 0
    while len(pts) < m + MARGIN and tries < 20 * (m + MARGIN):
        tries += 1
        at = mm.at([rng.randrange(p) for _ in range(N)])
        if at is None:
            continue
        fv = [eval_poly(fp, at[0]) % p for fp in fpolys]
        if 0 not in fv:
            pts.append((ev(at[1], 1, p), ev(at[0], 1, p), fv))
    s = len(pts)
    if s < m + MARGIN:
        return []
    U = flint.nmod_mat(s, m, [v for t, _, _ in pts for v in t], p)
    R = flint.nmod_mat(m, s, [rng.randrange(p) for _ in range(m * s)], p)
    RU = R * U
    out = []
    for kk in itertools.product(*ranges):
        c0 = [_prod_pow(fv, kk, p) for _, _, fv in pts]
        V = flint.nmod_mat(s, m, [c * v for (_, b, _), c in zip(pts, c0) for v in b], p)
        try:
            Ti = (R * V).inv()
        except ZeroDivisionError:
            continue
        for root, _ in (Ti * RU).charpoly().roots():
            c = int(root)
            if c and (U - V * c).rank() < m:
                cq = rational_reconstruction(c, p)
                if cq is not None:
                    out.append((cq, {i: k for i, k in enumerate(kk) if k}))
    return out


def _irreducible(sym, P) -> bool:
    """Whether P is a non-constant polynomial irreducible over Q."""
    from exact_khk.diagnostics.darboux import _q

    poly = sym.ctx.from_dict({e: _q(c) for e, c in P.items()})
    if poly.is_constant():
        return False
    facs = poly.factor()[1]
    return len(facs) == 1 and facs[0][1] == 1


def _prod_pow(values, exps, p):
    out = 1
    for v, k in zip(values, exps):
        if k:
            out = out * pow(v, k, p) % p
    return out


def _products(items, kappa, ks, N, bound=2, limit=3):
    """Densities 1/Π P_i^n_i from Darboux polynomials with cofactors (c_i, k_i): the small integer
    vectors n (|n_i| ≤ bound) with Σ n_i k_i = the exponents of det dΦ and Π c_i^n_i = κ, fewest
    factors first; ``limit`` of them, as (num, den, text maker).  A repeated exponent uses the
    item's further Darboux polynomials when it has several (1/(P_1 P_2) rather than 1/P_1²)."""
    import itertools

    if kappa is None or not items:
        return []
    items = items[:6]
    sols = []
    for n in itertools.product(range(-bound, bound + 1), repeat=len(items)):
        if not any(n):
            continue
        total, const = {}, Fraction(1)
        for ni, (_, (c, kk)) in zip(n, items):
            for k, e in kk.items():
                total[k] = total.get(k, 0) + ni * e
            const *= Fraction(c) ** ni
        if {k: e for k, e in total.items() if e} == ks and const == kappa:
            sols.append(n)
    sols.sort(key=lambda n: (sum(map(abs, n)), [-t for t in n]))
    out = []
    for n in sols[:limit]:
        num, den = {(0,) * N: Fraction(1)}, {(0,) * N: Fraction(1)}
        nums, dens = [], []
        for ni, (polys, _) in zip(n, items):
            chosen = [polys[j % len(polys)] for j in range(abs(ni))]
            for P in chosen:
                if ni > 0:
                    den = _mul(den, P)
                    dens.append(P)
                else:
                    num = _mul(num, P)
                    nums.append(P)

        def shown(variables, nums=nums, dens=dens):
            top = "*".join(_paren(expr(P, variables), " +-/") for P in nums) or "1"
            bottom = "*".join(_paren(expr(P, variables), " +-/") for P in dens)
            if not bottom:
                return top
            return f"{top}/({bottom})" if len(dens) > 1 or any(c in bottom for c in " +-*") else f"{top}/{bottom}"
        out.append((num, den, shown))
    return out


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
    """Whether num/den is a constant multiple of the density ``d``."""
    a, b = _mul(num, dict(d.den)), _mul(dict(d.num), den)
    return primitive(a) == primitive(b)


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
                            f"m(x~) det dPhi(x) = m(x) exactly (fmpq) at {len(data)} points of the orbit of "
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


def _conserved_ratio(fld, eps, num, den, seed, steps, x0):
    """Whether num/den takes one value along a fresh exact orbit (None: no orbit avoids its poles)."""
    orbit = _fresh_orbit(fld, eps, seed, steps, num, den, x0)
    if orbit is None:
        return None
    _, data = orbit
    pts = [x for x, *_ in data] + [data[-1][1]]
    return len({flint.fmpq(eval_poly(num, x)) / eval_poly(den, x) for x in pts}) == 1


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
