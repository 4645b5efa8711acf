"""Every record of a certificate, re-derived from the certificate's own data.

From the embedded system, ε, x0, the number of steps, the arithmetic and the options
the certificate records (the involutions; the Poisson-point subset named in its
statements), :func:`expected_records` lists the records the library's ``certify`` must
have written — name, statement, claim or control — each with its re-derivation: a
function giving ``(holds, residual)`` exactly, and for a control the rule that makes
it inapplicable where it cannot fail.  :func:`rederive` runs one; the caller compares
it with the recorded one field by field.

The system's family is read from the certificate's own system JSON (its ``"family"`` key, in
:data:`FAMILIES`; none: a system given by expressions).  Each kind of claim is one function in one
table (:data:`LIE_POISSON_KINDS`, :data:`EXPRESSION_KINDS`): adding a kind is adding a function and
a line there.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from fractions import Fraction
from math import gcd

from exact_khk.certification.verify.fields import (Dual, Undefined, _Evaluate, _Rationals, _dot, _matmul, _matvec,
                                                   _FlintRationals, rank, solve, to_fraction)
from exact_khk.certification.verify.maps import (_expression_field, _htilde, _identity_minus, _involution, _lp_field,
                                                 _lp_hessian, _lp_J, determinant, dphi, dual_step, gradient, gradients,
                                                 h_definition,
                                                 htilde_gradient, jacobiator, lazy_orbit, lp_pi, lp_pi_from_q, lp_q,
                                                 lp_shift, orbit, shift_index, step, transpose)

#: relative perturbation of the "perturbed point" controls (exact arithmetics)
PERTURBATION = Fraction(1, 2 ** 60)
#: a quantity that does not exist at a point
UNDEFINED = (Undefined, ZeroDivisionError)


@dataclass
class Expect:
    """One record the certificate must hold: ``derive() -> (holds, residual)`` (None: not
    re-derived by this verifier), ``degenerate() -> reason or None`` for a control."""

    name: str
    claim: str
    expected: bool
    derive: object = None
    degenerate: object = None
    always: object = None      # a reason that makes the control inapplicable even when it fails


def claim(name, statement, derive):
    return Expect(name, statement, True, derive)


def control(name, statement, derive, degenerate=None, always=None):
    return Expect(name, statement, False, derive, degenerate, always)


def rederive(rec):
    """(holds, residual, applicable) of ``rec`` (residual: a field element, or a string
    such as 'n/a' or 'rank 2'), as ``certify`` decides them."""
    try:
        holds, residual = rec.derive()
    except UNDEFINED:
        holds, residual = None, "n/a"
    applicable = True
    if not rec.expected and rec.always is not None and rec.always():
        applicable = False
    if not rec.expected and holds is not False and rec.degenerate is not None and rec.degenerate():
        applicable = False
    return holds, residual, applicable


def differs(fields, where: str):
    """The first of ``fields`` ((key, re-derived, recorded)) that differs, as a message (None if none)."""
    for key, want, have in fields:
        if want != have:
            return (f"{key} is {_short(have)}, but {'the statement' if key == 'claim' else 'it'} re-derived{where} is "
                    f"{_short(want)}")
    return None


def outcome_differs(c, holds, same, shown, applicable, where="", how=""):
    """The first of holds, residual (``same``: as recorded; ``shown``: the re-derived one, as shown) and
    applicable in which the recorded record ``c`` differs from the re-derived one, as a message."""
    if c["holds"] != holds:
        return f"recorded holds = {_tf(c['holds'])}, re-derived{where} holds = {_tf(holds)}{how}"
    if not same:
        return f"recorded residual {_short(c['residual'])}, re-derived{where} {shown}"
    if c.get("applicable", True) != applicable:
        return (f"recorded applicable = {_tf(c.get('applicable', True))}, re-derived: the control "
                f"{'can fail' if applicable else 'cannot fail'} here, so applicable = {_tf(applicable)}")
    return None


def _tf(v) -> str:
    return {True: "true", False: "false", None: "undecided"}.get(v, repr(v))


def _short(v, width=60) -> str:
    text = v if isinstance(v, str) else repr(v)
    return repr(text if len(text) <= width else text[:width - 3] + "...")


def _flatten(v):
    if isinstance(v, (list, tuple)):
        for t in v:
            yield from _flatten(t)
    else:
        yield v


def compare(sides, ks):
    """``lhs == rhs`` for ``(lhs, rhs) = sides(k)``, k in ``ks`` (rhs None: 0): (False, first nonzero
    lhs − rhs) at the first difference, (True, '0') if all agree, (None, 'n/a') if undefined at every
    point (points where a side is undefined are skipped)."""
    done = 0
    for k in ks:
        try:
            lhs, rhs = sides(k)
        except UNDEFINED:
            continue
        done += 1
        left = list(_flatten(lhs))
        right = [0] * len(left) if rhs is None else list(_flatten(rhs))
        for a, b in zip(left, right):
            d = a - b
            if d != 0:
                return False, d
    return (True, "0") if done else (None, "n/a")


def conserved(value, pts):
    """I(x_k) = I(x_0) for k >= 1, by :func:`compare` (``pts`` may be lazy)."""
    pts = iter(pts)
    x0 = next(pts)
    return compare(lambda x: (value(x), value(x0)), pts)


def poisson_map(f, e, Pi, pts, ks):
    """dΦ(x_k) Π(x_k) dΦ(x_k)ᵀ = Π(x_{k+1}) by :func:`compare`, decided multiplied out by A = I − εf'(x_k)
    (dΦ = A⁻¹B, B = I + εf'(x_{k+1}): B Π(x_k) Bᵀ = A Π(x_{k+1}) Aᵀ, no solve; A is invertible on
    an orbit, whose steps are re-checked nonsingular or solved here); where that
    fails, the residual is that of dΦ Π dΦᵀ − Π(x_{k+1}) itself."""
    def sides(k):
        x, y = pts[k], pts[k + 1]
        A, B = _identity_minus(e, f.jacobian(x)), _identity_minus(e, f.jacobian(y), 1)
        if _matmul(_matmul(B, Pi(k)), transpose(B)) == _matmul(_matmul(A, Pi(k + 1)), transpose(A)):
            return (), ()
        D = dphi(f, e, x, y)
        return _matmul(_matmul(D, Pi(k)), transpose(D)), Pi(k + 1)
    return compare(sides, ks)


class Context:
    """What a certificate's records are derived from: the field F, ε, x0, the steps, the
    recorded orbit (re-checked by :mod:`.orbit`), the system, the arithmetic's name and the
    involutions (the family).

    With ``point`` = (x0, ε), elements of F (a random draw in F_P, or the symbols of Q(x, ε)), it is
    the context of the other modes instead: one step from x0 computed here (:class:`~.fields.Undefined`
    where it is singular), ``arith`` and ``signs`` theirs, and ``point_free``: the controls' rules that
    judge a point are off (x0 is generic)."""

    def __init__(self, cert, data, F, checks=None, point=None, arith=None, signs=None):
        self.cert, self.data, self.F, self.checks, self._memo = cert, data, F, checks or {}, {}
        self.system, self.arith, self.point_free = cert.system, arith or cert.arith, point is not None
        self.signs = list(cert.signs if signs is None else signs)
        if point is None:
            self.K, self.eps, self.e = cert.steps, Fraction(cert.eps), F.of(cert.eps)
            self.x0q, self.x0 = [Fraction(t) for t in cert.x0], [F.of(t) for t in cert.x0]
            self.pts = [[F.parse(t, f"orbit[{k}][{i}]") for i, t in enumerate(p)] for k, p in enumerate(cert.orbit)]
        else:
            self.K, self.eps, self.x0q, self.x0, self.e = 1, None, None, list(point[0]), point[1]
        self.family = family(data)(self)
        if point is not None:
            self.pts = orbit(self.family.fields["f"], self.e, self.x0, 1)

    def memo(self, key, fn):
        if key not in self._memo:
            self._memo[key] = fn()
        return self._memo[key]

    def same(self, a, b):
        return all(s == t for s, t in zip(a, b))


class Family:
    """What the records of every system share: its Kahan maps (``fields``, named ``mapname``), their
    orbits from x0, reversibility and commutation with Phi_f."""

    def orbit(self, key):
        c = self.ctx
        return c.pts if key == "f" else c.memo(("orbit", key), lambda: orbit(self.fields[key], c.e, c.x0, c.K))

    def reversibility(self):
        c, out = self.ctx, []
        for key, name in self.mapname.items():
            def derive(key=key):
                pts = self.orbit(key)
                return compare(lambda k: (step(self.fields[key], -c.e, pts[k + 1]), pts[k]), range(c.K))
            out.append(claim(f"reversibility {name}", f"{name}({name}(x, eps), -eps) = x at the {c.K} points of its "
                             f"orbit", derive))
        return out

    def commuting(self, key, e):
        """Phi_f(Phi_key(x_k, e)) = Phi_key(x_{k+1}, e) at the points of the Phi_f orbit, by :func:`compare`."""
        c, pts, f = self.ctx, self.ctx.pts, self.fields["f"]
        y = lambda k: c.memo(("step", key, e == c.e, k), lambda: step(self.fields[key], e, pts[k]))  # noqa: E731
        return compare(lambda k: (step(f, c.e, y(k)), y(k + 1)), range(c.K))

    def commutation(self, key):
        name = self.mapname[key]
        return claim(f"commutation Phi_f o {name}", f"Phi_f({name}(x)) = {name}(Phi_f(x)) at the {self.ctx.K} points "
                     f"x_k of the Phi_f orbit", lambda: self.commuting(key, self.ctx.e))

    @staticmethod
    def generic_signs(system, F):
        """The involutions of the other modes' records over F (None: the system has none)."""
        return None


# --- the Lie–Poisson family ----------------------------------------------------------------


class LiePoisson(Family):
    """The paper's certificate: the fields f and g[s], their orbits, H~ and K~[s]."""

    def __init__(self, ctx):
        self.ctx = c = ctx
        s = c.system
        self.n = n = s.n
        F = c.F
        self.Hq = _lp_hessian(s.a, s.b, s.c)
        self.Hs = [[F.of(t) for t in row] for row in self.Hq]
        self.signs = list(c.signs)
        self.keys = ["f"] + self.signs
        self.M = {"f": self.Hs}
        for sg in self.signs:
            self.M[sg] = _matmul(_involution(n, sg, F), self.Hs)
        self.fields = {k: _lp_field(n, M) for k, M in self.M.items()}
        self.integral = {"f": "H~"} | {sg: f"K~[{sg}]" for sg in self.signs}
        self.mapname = {"f": "Phi_f"} | {sg: f"Phi_g[{sg}]" for sg in self.signs}
        self.npts = c.K + 1
        self.flint = c.arith == "flint"

    def records(self, chosen=None):
        self.ctx.chosen = None
        return [r for kind in LIE_POISSON_KINDS for r in kind(self)], None

    @staticmethod
    def generic_signs(system, F):
        return identity_signs(system.n, F)

    def value(self, key, pts, k):
        return self.ctx.memo(("I", key, id(pts), k), lambda: _htilde(self.M[key], pts[k], self.ctx.e, self.n))

    def grad(self, key, k):
        c = self.ctx
        return c.memo(("grad", key, k), lambda: htilde_gradient(self.M[key], c.pts[k], c.e, self.n))

    def poisson_points(self):
        """The orbit points of the Poisson checks: all, or the subset the certificate's own
        statement names (``certify --poisson-points P``), if it is one that option makes."""
        K = self.ctx.K
        rec = self.ctx.checks.get("Poisson tensor Pi Jacobi identity")
        m = re.search(r"at (\d+) of the \d+ points", rec.claim) if rec is not None else None
        if m and 1 <= int(m.group(1)) < K:
            p = int(m.group(1))
            return sorted({round(i * (K - 1) / max(p - 1, 1)) for i in range(p)})
        return list(range(K))


def identity_signs(n: int, F) -> list:
    """The involutions ``certify --identities gf:P`` certifies for the family (F = F_P; F_2: those
    of ``certify --prove``): all 2^n − 2 when F_P holds ω = ζ_n (n ≥ 3, P ≡ 1 mod n), else the
    rational ones (constant on the classes {j : gcd(j, n) = d}) other than ±I; sorted."""
    every = [''.join("-" if (m >> j) & 1 else "+" for j in range(n)) for m in range(2 ** n)]
    if not (n >= 3 and (F.P - 1) % n == 0):
        every = [s for s in every if all(s[j] == s[k] for j in range(n) for k in range(n) if gcd(j, n) == gcd(k, n))]
    return sorted(s for s in every if s not in ("+" * n, "-" * n))


def lp_integrals(lp):
    c, K = lp.ctx, lp.ctx.K
    out = []
    for key in lp.keys:
        I, name = lp.integral[key], lp.mapname[key]

        def derive(key=key):
            pts = lp.orbit(key)
            return compare(lambda k: (lp.value(key, pts, k), h_definition(pts[k], pts[k + 1], c.e, lp.n)), range(K))
        out.append(claim(f"integral {I} (closed form = definition)",
                         f"{I}(x) by (tH 4) equals h(x, {name}(x)) = (2 eps)^-1 x^T J((x+x~)/2)^-1 x~ at the "
                         f"{K} points of the {name} orbit", derive))
    for ikey in lp.keys:
        for mkey in lp.keys:
            I, name = lp.integral[ikey], lp.mapname[mkey]

            def derive(ikey=ikey, mkey=mkey):
                pts = lp.orbit(mkey)
                return compare(lambda k: (lp.value(ikey, pts, k), lp.value(ikey, pts, 0)), range(1, lp.npts))
            out.append(claim(f"integral {I} conserved by {name}",
                             f"{I}(x_k) = {I}(x_0) for k = 1..{K} along the {name} orbit", derive))
    return out


def lp_poisson(lp):
    c, n, K = lp.ctx, lp.n, lp.ctx.K
    ks = lp.poisson_points()
    subset = "every point" if len(ks) == K else f"{len(ks)} of the {K} points (k = {ks})"
    Pi = lambda pts: (lambda k: c.memo(("Pi", id(pts), k), lambda: lp_pi(lp.Hs, pts[k], c.e, n)))  # noqa: E731
    out = [claim("Poisson tensor Pi formula",
                 f"Pi = J - eps^2 J Hs J Hs J equals (1 - eps^2 q_0) J - eps^2 sum_(l>=1) q_l A^l J at the {lp.npts} "
                 f"points of the Phi_f orbit",
                 lambda: compare(lambda k: (Pi(c.pts)(k), lp_pi_from_q(lp.Hs, c.pts[k], c.e, n)), range(lp.npts))),
           claim("Poisson tensor Pi Jacobi identity",
                 f"the cyclic sums of Pi_im d_m Pi_jk vanish at {subset} of the Phi_f orbit",
                 lambda: compare(lambda k: (jacobiator(lambda x: lp_pi(lp.Hs, x, c.e, n), c.pts[k]), None), ks))]
    for key in lp.keys:
        name = lp.mapname[key]

        def derive(key=key):
            pts = lp.orbit(key)
            return poisson_map(lp.fields[key], c.e, Pi(pts), pts, ks)
        out.append(claim(f"Poisson map {name}",
                         f"dPhi(x) Pi(x) dPhi(x)^T = Pi(Phi(x)) for {name} at {subset} of its orbit", derive))
    return out


def lp_involution(lp):
    c, n = lp.ctx, lp.n

    every = range(lp.npts)

    def q_sides(k):
        g = gradients(lambda x: lp_q(lp.Hs, x, n), c.pts[k])
        return g[1:], [[g[0][i] for i in shift_index(n, l)] for l in range(1, n)]

    def bracket(sg, P):  # grad H~^T P(x_k) grad K~[sg] = 0
        return compare(lambda k: (_dot(lp.grad("f", k), _matvec(P(c.pts[k]), lp.grad(sg, k))), None), every)
    out = [claim("gradients of q_l: grad q_l = A^l grad q_0",
                 f"the exact gradients ({'closed form' if lp.flint else 'dual numbers'}) of "
                 f"q_l = tr((A^T)^l (J Hs)^2)/(2n) satisfy grad q_l = A^l grad q_0 at the {lp.npts} points of "
                 f"the Phi_f orbit", lambda: compare(q_sides, every))]
    for sg in lp.signs:
        B = _involution(n, sg, c.F)
        out += [claim(f"integral gradients grad K~[{sg}] = B grad H~",
                      f"grad K~[{sg}] = B grad H~ (exact gradients) at the {lp.npts} points of the Phi_f orbit",
                      lambda sg=sg, B=B: compare(lambda k: (lp.grad(sg, k), _matvec(B, lp.grad("f", k))), every)),
                claim(f"involution {{H~,K~[{sg}]}}_J",
                      f"grad H~^T J grad K~[{sg}] = 0 at the {lp.npts} points of the Phi_f orbit",
                      lambda sg=sg: bracket(sg, lambda x: _lp_J(x, n))),
                claim(f"involution {{H~,K~[{sg}]}}_Pi",
                      f"grad H~^T Pi grad K~[{sg}] = 0 at the {lp.npts} points of the Phi_f orbit",
                      lambda sg=sg: bracket(sg, lambda x: lp_pi(lp.Hs, x, c.e, n)))]
    return out


def lp_rank(lp):
    from exact_khk.arith import get_arith
    from exact_khk.systems.lie_poisson.system import expresses_omega

    c, n = lp.ctx, lp.n
    signs_rows = [[Fraction(1)] * n] + [[Fraction(1 if ch == "+" else -1) for ch in sg] for sg in lp.signs]
    r_expr = rank(signs_rows)
    n_rational = len({gcd(j, n) for j in range(n)})
    over = (f"all n = {n} integrals are expressible in {c.arith}"
            if n_rational == n or expresses_omega(get_arith(c.arith), n)
            else f"over Q only {n_rational} of the n = {n} integrals are expressible (the others need Q(omega))")

    def rank_fn(rows_at, expected):
        def derive():
            ranks = {}
            for k in range(lp.npts):
                try:
                    ranks[k] = rank(rows_at(k))
                except UNDEFINED:
                    continue
            high = [k for k, r in ranks.items() if r > expected]
            if high:
                return False, f"rank {ranks[high[0]]}"
            if not any(r == expected for r in ranks.values()):
                return None, f"rank {max(ranks.values(), default=0)}"
            return True, f"rank {expected}"
        return derive
    names = ", ".join(lp.integral.values())
    return [claim(f"rank of integral gradients ({names})",
                  f"the gradients of the {len(lp.keys)} integrals expressible here have rank {r_expr} "
                  f"(the dimension of their span: functional independence, proved by one orbit point of full rank; "
                  f"the rank may drop at critical points) on the Phi_f orbit; {over}",
                  rank_fn(lambda k: [lp.grad(key, k) for key in lp.keys], r_expr)),
            claim("rank of integral gradients A^i grad H~ (i < n)",
                  f"the gradients A^i grad H~ (i = 0..{n - 1}) of the n integrals H~_i have full rank n = {n} "
                  f"(functional independence, proved by one orbit point of full rank) on the Phi_f orbit",
                  rank_fn(lambda k: [[lp.grad("f", k)[s] for s in shift_index(n, i)] for i in range(n)], n))]


class LPDegeneracy:
    """Where a control of the family cannot fail (decided in Q, as ``certify`` decides it):
    J(x0) singular, x0 an equilibrium, the planar n = 2 cases, b and c of period 1 or 2,
    poles, and H~ constant along the perturbed coordinate."""

    def __init__(self, lp):
        self.lp, c = lp, lp.ctx
        s = c.system
        self.a, self.b, self.c = list(s.a), list(s.b), list(s.c)
        Q = _FlintRationals()
        self.Hq = [[Q.of(t) for t in row] for row in lp.Hq]
        self.n, self.free = lp.n, c.point_free
        if not self.free:
            self.x0, self.eps = [Q.of(t) for t in c.x0q], Q.of(c.eps)

    def common(self):
        n = self.n
        if self.free:  # a generic x0 (the other modes): only the system's own reason
            return "Hs = 0" if not any(map(any, self.Hq)) else None
        x = self.x0
        if determinant([[x[(i + j) % n] for j in range(n)] for i in range(n)]) == 0:
            return "J(x0) is singular"
        if not any(_matvec(self.Hq, x)):
            return "x0 is an equilibrium"
        return None

    def equilibrium(self):
        """x0 an equilibrium (Hs x0 = 0): a one-point orbit shows nothing, even where a control fails."""
        if self.free:
            return self.common()
        return "x0 is an equilibrium" if not any(_matvec(self.Hq, self.x0)) else None

    def planar(self):
        if self.n != 2:
            return None
        al, be, ga = sum(self.a), sum(self.b), sum(self.c)
        if be * be == al * ga:
            return "n = 2: degenerate planar field"
        if self.free:
            return None
        U, V = sum(self.x0[:2]), sum(self.x0[2:])
        return "n = 2: invariant line" if al * U * U + 2 * be * U * V + ga * V * V == 0 else None

    def self_paired(self, constant=False):
        n = self.n
        if n < 3:
            return None
        st = 1 if constant else 2
        return "b, c periodic" if all(w[(i + st) % n] == w[i] for w in (self.b, self.c) for i in range(n)) else None

    def pole(self, M, x):
        try:
            _htilde(M, list(x), self.eps, self.n)
        except UNDEFINED:
            return True
        return False

    def commutation(self):
        return self.common() or self.planar() or self.self_paired()

    def control_conserves(self):
        return self.commutation() or (None if self.free else "pole" if self.pole(self.Hq, self.x0) else None)

    def non_admissible(self):
        why = self.common()
        if why and why.startswith("J("):
            return why
        if self.self_paired(constant=True):
            return "b, c constant"
        if self.free:
            return why
        bad = non_admissible(self.Hq, self.n)
        if not any(_matvec(bad, self.x0)):
            return "equilibrium of the non-admissible field"
        return "pole" if self.pole(bad, self.x0) else None

    def perturbed(self):
        why = self.common()
        if why or self.free:
            return why
        if self.pole(self.Hq, self.x0):
            return "pole at x0"
        last = self.lp.ctx.pts[-1]
        if isinstance(self.lp.ctx.F, _Rationals) and self.pole(self.Hq, last):
            return "pole at x_K"
        x, h0 = list(self.x0), _htilde(self.Hq, self.x0, self.eps, self.n)
        for t in (1, 2, 3):
            y = x[:-1] + [x[-1] + t]
            if self.pole(self.Hq, y) or _htilde(self.Hq, y, self.eps, self.n) != h0:
                return None
        return "H~ does not depend on the last coordinate"


def non_admissible(H, n):
    """Hs with (0, 0) raised by 1 (n = 2: (0, 2) and (2, 0))."""
    M = [list(r) for r in H]
    if n == 2:
        M[0][2] += 1
        M[2][0] += 1
    else:
        M[0][0] += 1
    return M


def lp_controls(lp):
    c, n, F, K = lp.ctx, lp.n, lp.ctx.F, lp.ctx.K
    deg = LPDegeneracy(lp)
    C = lp_shift(n) if n >= 3 else [[2 * (i == j) + t for j, t in enumerate(r)] for i, r in enumerate(lp_shift(n))]
    Mc = _matmul([[F.of(t) for t in r] for r in C], lp.Hs)
    fc, f = _lp_field(n, Mc), lp.fields["f"]
    H = lambda x: _htilde(lp.Hs, x, c.e, n)  # noqa: E731
    bad = non_admissible(lp.Hs, n)
    rel = F.of(PERTURBATION)

    def perturbed():
        x = list(c.pts[0])
        x[-1] = rel if x[-1] == 0 else x[-1] + x[-1] * rel
        return compare(lambda _: (H(x), lp.value("f", c.pts, K)), [0])
    return [
        control("control: commutation with non-associated field",
                f"[control, must fail] Phi_f commutes with the Kahan map of the control field "
                f"({'A Hs' if n >= 3 else '(2I + A) Hs'}) at the points of the Phi_f orbit",
                lambda: compare(lambda x: (step(f, c.e, step(fc, c.e, x)), step(fc, c.e, step(f, c.e, x))), c.pts),
                deg.commutation),
        control("control: integral H~ conserved by Phi_control",
                "[control, must fail] H~ is conserved along the orbit of the control map",
                lambda: conserved(H, lazy_orbit(fc, c.e, c.x0, K)), deg.control_conserves),
        control("control: integral H~ conserved for a non-admissible Hessian",
                "[control, must fail] with " + ("Hs[0][0]" if n >= 3 else "Hs[0][2] = Hs[2][0]") + " raised by 1 "
                "(block X(" + ("a" if n >= 3 else "b") + ") not cyclic Hankel), the closed "
                "form H~ is conserved by the Kahan map of J(x) Hs' x",
                lambda: conserved(lambda x: _htilde(bad, x, c.e, n),
                                          lazy_orbit(_lp_field(n, bad), c.e, c.x0, K)), deg.non_admissible),
        control("control: integral H~ at a perturbed point",
                f"[control, must fail] H~ at x0 with its last coordinate perturbed by 2^-60 relative equals "
                f"H~(x_{K}) on the orbit", perturbed, deg.perturbed, deg.equilibrium)]


#: the Lie–Poisson certificate's kinds of records, in the order ``certify`` writes them
LIE_POISSON_KINDS = (lp_integrals, lambda lp: [lp.commutation(sg) for sg in lp.signs], LiePoisson.reversibility,
                     lp_poisson, lp_involution, lp_rank, lp_controls)


# --- systems given by expressions (catalogue, system files) --------------------------------


def reduced(fn, F, x, eps):
    """Over Q, where an expression as written divides by zero at x: the value there of the library's
    rational function ``fn`` reduced to lowest terms (Undefined at a pole)."""
    from exact_khk.arith import get_arith
    from exact_khk.errors import PoleError

    try:
        return F.of(fn(get_arith("fraction"), [to_fraction(t) for t in x], eps))
    except PoleError:
        raise Undefined("pole") from None


def evaluator(spec, F):
    """(text, where, e) -> x -> the value of the system's expression ``text`` at x in F (its parameters, ε = e)."""
    params = {p: _Evaluate(t, {}, F, f"system.parameters.{p}").value for p, t in (spec.get("parameters") or {}).items()}
    variables = list(spec["variables"])
    return lambda text, where, e: lambda x: _Evaluate(text, dict(params, eps=e, **dict(zip(variables, x))), F,
                                                      where).value


class Expressions(Family):
    """A system given by expressions: its fields, integrals, controls, Π and H, evaluated
    from the system's own text by :class:`~.fields._Evaluate` (dual numbers for derivatives)."""

    def __init__(self, ctx):
        self.ctx = c = ctx
        self.spec = spec = c.data["system"]
        F = c.F
        self.expression = evaluator(spec, F)
        self.N = len(spec["variables"])
        self.field_names = ["f"] + list(spec.get("fields") or {})
        self.fields = {g: _expression_field(c.system.field(g), F) for g in self.field_names}
        self.mapname = {g: f"Phi_{g}" for g in self.field_names}
        lib = c.system
        self.lib_integrals, self.lib_controls = lib.integrals(), lib.controls()

    def fn(self, text, where, eps=None, name=None, table=None):
        """x -> the value of ``text`` at x (``eps``: another value of ε); over Q, where the text
        as written divides by zero, the library's reduced rational function ``table[name]``."""
        c = self.ctx

        def value(x):
            try:
                return self.expression(text, where, c.e if eps is None else eps)(x)
            except ZeroDivisionError:
                if table is None or not isinstance(c.F, _Rationals) or isinstance(x[0], Dual):
                    raise
            lib = table[name] if eps is None else table[name].at_eps_zero()
            return reduced(lib, c.F, x, c.eps if eps is None else 0)
        return value

    def poisson(self, x):
        """Π(x) from the system's matrix: the upper triangle evaluated, the lower one its negative."""
        M, P = self.spec["poisson"]["matrix"], [[0 * x[0]] * self.N for _ in range(self.N)]
        for i in range(self.N):
            for j in range(i + 1, self.N):
                P[i][j] = self.expression(M[i][j], f"system.poisson.matrix[{i}][{j}]", self.ctx.e)(x)
                P[j][i] = -P[i][j]
        return P

    def records(self, chosen=None):
        """See :func:`expected_records`."""
        ctx = self.ctx
        known, own = declared_claims(ctx.system)
        by_kind = {k: EXPRESSION_KINDS[k](self) for k in known}
        names = set(ctx.checks)
        if chosen is None:
            chosen = [k for k in known if any(r.name in names for r in by_kind[k])] or list(own)
        note = None
        if tuple(chosen) != own:
            note = (f"the records cover the claims {', '.join(chosen)}; the system's own list is {', '.join(own)} "
                    f"(a --claims selection, which the certificate does not record)")
        ctx.chosen = list(chosen)
        records = [r for k in chosen for r in by_kind[k]] + ex_declared_controls(self)
        # at a fixed point of Phi_f every control is inapplicable, even one that fails: the orbit is one point
        fixed = lambda: "x0 is a fixed point of Phi_f" if ctx.same(ctx.pts[1], ctx.pts[0]) else None  # noqa: E731
        return [r if r.expected else replace(r, always=fixed) for r in records], note


def ex_reversibility(ex):
    c, K, pts, f = ex.ctx, ex.ctx.K, ex.ctx.pts, ex.fields["f"]
    return ex.reversibility() + [control(
        "control: Phi_f applied twice returns",
        "[control, must fail] Phi_f(Phi_f(x, eps), eps) = x at the orbit points",
        lambda: compare(lambda k: (pts[k + 2], pts[k]), range(K - 1)) if K >= 2
        else compare(lambda _: (step(f, c.e, pts[1]), pts[0]), [0]), lambda: c.same(step(f, c.e, pts[1]), pts[0]))]


def ex_integrals(ex):
    c, K, pts, out = ex.ctx, ex.ctx.K, ex.ctx.pts, []
    for name, text in (ex.spec.get("integrals") or {}).items():
        I = ex.fn(text, f"system.integrals.{name}", name=name, table=ex.lib_integrals)
        out.append(claim(f"integral {name} conserved by Phi_f",
                         f"{name}(x_k) = {name}(x_0) for k = 1..{K} along the Phi_f orbit; {name} = {text}",
                         lambda I=I: conserved(I, pts)))
        for g in ex.field_names[1:]:
            out.append(claim(f"integral {name} conserved by Phi_{g}",
                             f"{name}(y_k) = {name}(y_0) along the Phi_{g} orbit of x0",
                             lambda I=I, g=g: conserved(I, lazy_orbit(ex.fields[g], c.e, c.x0, K))))
        out.append(_perturbed_point(ex, name, text, I))
        lib = ex.lib_integrals[name]
        if lib.depends_on_eps and lib.at_eps_zero() is not None:
            I0 = ex.fn(text, f"system.integrals.{name}", eps=0 * c.e, name=name, table=ex.lib_integrals)
            out.append(control(f"control: {name} at eps = 0 conserved",
                               f"[control, must fail] the eps -> 0 limit of {name} (the continuous-time quantity) "
                               f"is conserved along the Phi_f orbit", lambda I0=I0: conserved(I0, pts),
                               lambda lib=lib: "constant" if _constant(lib.at_eps_zero()) else None))
    return out


def _perturbed_point(ex, name, text, I):
    c, pts = ex.ctx, ex.ctx.pts
    try:
        grad = gradient(ex.fn(text, f"system.integrals.{name}"), pts[0])
    except UNDEFINED:
        grad = _library_gradient(ex, name)
    j = next((i for i, g in enumerate(grad) if g != 0), None)
    if j is None:
        return control(f"control: {name} at a perturbed point", f"[control, must fail] {name} at x0 moved along "
                       f"a coordinate differs from {name}(x_K)", lambda: (None, "n/a"), lambda: "critical point")
    moved = list(pts[0])
    rel = c.F.of(PERTURBATION)
    moved[j] = rel if moved[j] == 0 else moved[j] + moved[j] * rel
    return control(f"control: {name} at a perturbed point",
                   f"[control, must fail] {name} at x0 with x_{j} moved by 2^-60 relative (d{name}/dx_{j}(x0) != 0) "
                   f"equals {name}(x_{c.K})", lambda: compare(lambda _: (I(moved), I(pts[-1])), [0]))


def _library_gradient(ex, name):
    """Over Q, where the text as written divides by zero at x0: the reduced function's gradient."""
    from exact_khk.arith import get_arith
    from exact_khk.errors import PoleError

    c = ex.ctx
    if not isinstance(c.F, _Rationals):
        return []
    try:
        return [c.F.of(t) for t in ex.lib_integrals[name].gradient(get_arith("fraction"),
                                                                   [to_fraction(t) for t in c.pts[0]], c.eps)]
    except (PoleError, ArithmeticError):
        return []


def ex_poisson(ex):
    c, K, pts, N = ex.ctx, ex.ctx.K, ex.ctx.pts, ex.N
    f = ex.fields["f"]
    Pi = lambda k: c.memo(("Pi", k), lambda: ex.poisson(pts[k]))  # noqa: E731

    def plus_w(x):
        M = ex.poisson(x)
        M[0][1], M[1][0] = M[0][1] + 1, M[1][0] - 1
        M[1][2], M[2][1] = M[1][2] + x[1], M[2][1] - x[1]
        return M
    j = next((i for i in range(N) if pts[1][i] - pts[0][i] != 0), 0)
    scaled = lambda k: [[(1 + pts[k][j]) * t for t in row] for row in Pi(k)]  # noqa: E731
    return [
        claim("Poisson tensor Jacobi identity",
              f"the cyclic sums of Pi_im d_m Pi_jk vanish at the {K + 1} orbit points",
              lambda: compare(lambda k: (jacobiator(ex.poisson, pts[k]), None), range(K + 1))),
        claim("Poisson map Phi_f", f"dPhi(x) Pi(x) dPhi(x)^T = Pi(Phi(x)) at the {K} orbit points",
              lambda: poisson_map(f, c.e, Pi, pts, range(K))),
        control("control: Jacobi identity of Pi + W", "[control, must fail] Pi + W, W = e_0^e_1 + x_1 e_1^e_2, "
                "satisfies the Jacobi identity at the orbit points",
                lambda: compare(lambda k: (jacobiator(plus_w, pts[k]), None), range(K + 1))
                if N >= 3 else (True, "0"), lambda: N < 3),
        control(f"control: (1 + x_{j}) Pi preserved", f"[control, must fail] the Kahan map preserves (1 + x_{j}) Pi "
                f"(it would make 1 + x_{j} an integral)", lambda: poisson_map(f, c.e, scaled, pts, range(K)),
                lambda: c.same(pts[1], pts[0]))]


def ex_commutation(ex):
    c = ex.ctx
    return [r for g in ex.field_names[1:] for r in (
        ex.commutation(g),
        control(f"control: commutation with Phi_{g} at 2 eps",
                f"[control, must fail] Phi_f(., eps) commutes with Phi_{g}(., 2 eps) at the Phi_f orbit points",
                lambda g=g: ex.commuting(g, 2 * c.e), lambda: c.same(c.pts[1], c.pts[0])))]


def ex_jacobian(ex):
    c, K, pts, f = ex.ctx, ex.ctx.K, ex.ctx.pts, ex.fields["f"]
    return [
        claim("Jacobian of Phi_f", f"the derivative of the step (dual numbers through the solve) equals "
              f"(I - eps f'(x))^-1 (I + eps f'(Phi(x))) at the {K} orbit points",
              lambda: compare(lambda k: (dual_step(f, c.e, pts[k]), dphi(f, c.e, pts[k], pts[k + 1])), range(K))),
        control("control: Jacobian with f'(x) for f'(Phi(x))",
                "[control, must fail] the derivative of the step equals (I - eps f'(x))^-1 (I + eps f'(x))",
                lambda: compare(lambda k: (dual_step(f, c.e, pts[k]), dphi(f, c.e, pts[k], pts[k])), range(K)),
                lambda: all(c.same(sum(f.jacobian(pts[k + 1]), []), sum(f.jacobian(pts[k]), [])) for k in range(K)))]


def ex_cmoq(ex):
    c, K, pts, f = ex.ctx, ex.ctx.K, ex.ctx.pts, ex.fields["f"]
    H = ex.fn(ex.spec["hamiltonian"]["H"], "system.hamiltonian.H")
    kahan = lambda x: _identity_minus(c.e, f.jacobian(x))  # noqa: E731

    def modified(x):
        z = solve(kahan(x), f.evaluate(x), "I - eps f'(x) is singular")
        return H(x) + c.F.of(Fraction(2, 3)) * c.e * sum((a * b for a, b in zip(gradient(H, x), z)), 0 * x[0])

    def det_sides(k):
        D = determinant(dphi(f, c.e, pts[k], pts[k + 1]))
        return D * determinant(kahan(pts[k])), determinant(kahan(pts[k + 1]))
    return [
        claim("CMOQ modified energy conserved", f"H~(x) = H(x) + (2 eps/3) grad H(x)^T (I - eps f'(x))^-1 f(x) "
              f"is conserved along the Phi_f orbit (k = 1..{K})", lambda: conserved(modified, pts)),
        claim("CMOQ invariant measure", "det dPhi(x) det(I - eps f'(x)) = det(I - eps f'(Phi(x))): the measure "
              f"dx / det(I - eps f'(x)) is preserved at the {K} orbit points",
              lambda: compare(det_sides, range(K))),
        control("control: H conserved", "[control, must fail] the Hamiltonian H itself is conserved along the "
                "Phi_f orbit", lambda: conserved(H, pts)),
        control("control: Phi_f preserves volume", "[control, must fail] det dPhi(x) = 1 at the orbit points",
                lambda: compare(lambda k: (determinant(dphi(f, c.e, pts[k], pts[k + 1])), 1), range(K)),
                lambda: c.same(pts[1], pts[0]))]


def _constant(fn) -> bool:
    """Whether the library's reduced rational function num/den is free of x (every partial of num/den is 0)."""
    dnum, dden = fn.partials()
    return all((fn.den * a - fn.num * b).is_zero() for a, b in zip(dnum, dden))


def ex_measure(ex):
    c, K, pts, f = ex.ctx, ex.ctx.K, ex.ctx.pts, ex.fields["f"]
    text = ex.spec["measure"]["density"]
    m = ex.fn(text, "system.measure.density")
    det = lambda k: c.memo(("det dPhi", k), lambda: determinant(dphi(f, c.e, pts[k], pts[k + 1])))  # noqa: E731
    lib = ex.ctx.system.measure()
    return [
        claim("invariant measure", f"m(Phi(x)) det dPhi(x) = m(x), m = {text}: the measure m(x) dx is preserved "
              f"at the {K} orbit points", lambda: compare(lambda k: (m(pts[k + 1]) * det(k), m(pts[k])), range(K))),
        control("control: measure with density 1 preserved", "[control, must fail] det dPhi(x) = 1 at the orbit "
                "points (the density 1 in place of m)", lambda: compare(lambda k: (det(k), 1), range(K)),
                lambda: "constant density" if hasattr(lib, "partials") and _constant(lib) else None)]


def ex_declared_controls(ex):
    pts = ex.ctx.pts
    return [control(f"control: {name} conserved by Phi_f",
                    f"[control, must fail] {name} = {text} is conserved along the Phi_f orbit",
                    lambda fn=ex.fn(text, f"system.controls.{name}", name=name, table=ex.lib_controls):
                    conserved(fn, pts))
            for name, text in (ex.spec.get("controls") or {}).items()]


#: the claims of a system given by expressions, in the order ``certify`` writes them: name ->
#: the function listing its records (the declared controls come after, always)
EXPRESSION_KINDS = {"reversibility": ex_reversibility, "integrals": ex_integrals, "poisson": ex_poisson,
                    "commutation": ex_commutation, "jacobian": ex_jacobian, "cmoq": ex_cmoq, "measure": ex_measure}


def declared_claims(system) -> tuple:
    """The claims the system declares something for, in :data:`EXPRESSION_KINDS` order, and its own
    list (the file's ``claims``, else all of them): what ``certify`` runs without ``--claims``."""
    has = {"reversibility": True, "jacobian": True, "integrals": bool(system.integrals()),
           "poisson": system.poisson() is not None, "commutation": len(system.field_names()) > 1,
           "cmoq": system.hamiltonian_form() is not None, "measure": system.measure() is not None}
    known = tuple(k for k in EXPRESSION_KINDS if has[k])
    own = getattr(system, "claims", None) or known
    return known, tuple(k for k in EXPRESSION_KINDS if k in own)


#: the record builders of a certificate's system, by its JSON's "family" key (a system without one is given
#: by expressions)
FAMILIES = {"lie-poisson": LiePoisson}


def family(data):
    return FAMILIES.get(data["system"].get("family"), Expressions)


def expected_records(ctx, chosen=None) -> tuple:
    """(the records the certificate's system and options imply, a note on the claim selection or None);
    ``chosen``: the claims of a system given by expressions (default: those the records in
    ``ctx.checks`` cover, else the system's own list)."""
    return ctx.family.records(chosen)
