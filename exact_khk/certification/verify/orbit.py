"""The recorded orbit and the integrals' recorded values, re-checked: the step equations by
substitution, the steps' determinants, every value recomputed at its point."""

from __future__ import annotations

from fractions import Fraction

from exact_khk.certification.verify.fields import Undefined, _Rationals, _eliminate, _matmul, _matvec, _show
from exact_khk.certification.verify.maps import (_expression_field, _htilde, _identity_minus, _involution, _lp_field,
                                                 _lp_hessian, h_definition)
from exact_khk.certification.verify.records import LiePoisson, evaluator, family, reduced


def orbit_length(cert) -> tuple:
    """The result line on the orbit's length (steps + 1 points), read before any point is parsed."""
    K, got = cert.steps, len(cert.orbit)
    if got != K + 1:
        return ("orbit length", False, f"{got} points recorded; {_show(Fraction(K))} steps need "
                f"{_show(Fraction(K + 1))}: nothing else is re-derived")
    return ("orbit length", True, f"{K + 1} points")


class _Recheck:
    """The orbit and the integrals of one certificate, re-checked in the field F."""

    def __init__(self, cert, data, F):
        self.cert, self.data, self.F = cert, data, F
        self.system = cert.system
        self.lp = family(data) is LiePoisson
        self.pts = [[F.parse(t, f"orbit[{k}][{i}]") for i, t in enumerate(p)] for k, p in enumerate(cert.orbit)]
        self.e = F.of(cert.eps)
        if self.lp:
            n = self.system.n
            self.n = n
            self.Hs = [[F.of(t) for t in row] for row in _lp_hessian(self.system.a, self.system.b, self.system.c)]
            self.f = _lp_field(n, self.Hs)
        else:
            self.f = _expression_field(self.system.field("f"), F)

    def run(self) -> list:
        """The re-checks of an orbit whose length :func:`orbit_length` accepted."""
        out = [self.starts_at_x0()]
        out += self.steps()
        out += self.integrals()
        return out

    def starts_at_x0(self):
        if not self.pts:
            return ("orbit starts at x0", False, "no orbit recorded")
        try:
            x0 = [self.F.of(t) for t in self.cert.x0]
        except Undefined as exc:
            return ("orbit starts at x0", False, str(exc))
        bad = [i for i, (a, b) in enumerate(zip(self.pts[0], x0)) if a != b]
        if bad:
            i = bad[0]
            return ("orbit starts at x0", False, f"x_0[{i}] = {_show(self.pts[0][i])} but x0[{i}] = {_show(x0[i])}")
        return ("orbit starts at x0", True, "x_0 = x0")

    def steps(self):
        f, e, pts = self.f, self.e, self.pts
        homogeneous = f.homogeneous
        eq_bad = det_bad = None
        for k in range(len(pts) - 1):
            x, y = pts[k], pts[k + 1]
            A = _identity_minus(e, f.jacobian(x))
            diff = [a - b for a, b in zip(_matvec(A, y), x if homogeneous else f.kahan_rhs(e, x))]
            i = next((i for i, d in enumerate(diff) if d != 0), None)
            if i is not None and eq_bad is None:
                eq_bad = (k, i, diff[i])
            det, _ = _eliminate(A)
            if det == 0 and det_bad is None:
                det_bad = k
        K = len(pts) - 1
        form = ("(I - eps f'(x_k)) x_{k+1} = x_k" if homogeneous else
                "(I - eps f'(x_k)) x_{k+1} = (I + eps L) x_k + 2 eps c")
        if eq_bad is not None:
            k, i, d = eq_bad
            first = ("Kahan step equations", False, f"{form} fails at k = {k}, row {i}: residual {_show(d)}")
        else:
            first = ("Kahan step equations", True, f"{form} holds exactly for k = 0..{K - 1}")
        if det_bad is not None:
            second = ("Kahan steps nonsingular", False, f"det(I - eps f'(x_k)) = 0 at k = {det_bad}: the step "
                      f"from x_{det_bad} is not unique")
        else:
            second = ("Kahan steps nonsingular", True, f"det(I - eps f'(x_k)) != 0 for k = 0..{K - 1}")
        return [first, second]

    # --- integrals -------------------------------------------------------------

    def integral_functions(self) -> dict:
        """name -> fn(x) (a field element; ZeroDivisionError or Undefined at a pole)."""
        F, e = self.F, self.e
        if self.lp:
            n = self.n
            fns = {"H~": lambda x: _htilde(self.Hs, x, e, n)}
            for s in self.cert.signs:
                try:
                    M = _matmul(_involution(n, s, F), self.Hs)
                except Undefined as exc:
                    fns[f"K~[{s}]"] = exc
                    continue
                fns[f"K~[{s}]"] = lambda x, M=M: _htilde(M, x, e, n)
            return fns
        spec = self.data["system"]
        expression = evaluator(spec, F)
        return {name: expression(text, f"system.integrals.{name}", e)
                for name, text in (spec.get("integrals") or {}).items()}

    def _value(self, name, fn, k):
        """(value, how) of integral ``name`` at x_k; raises Undefined at a pole."""
        x = self.pts[k]
        try:
            return fn(x), ""
        except ZeroDivisionError:
            pass
        except Undefined:
            raise
        if self.lp or not isinstance(self.F, _Rationals):
            raise Undefined("division by zero")
        return reduced(self.system.integrals()[name], self.F, x, self.cert.eps), " (reduced form)"

    def integrals(self) -> list:
        fns = self.integral_functions()
        recorded = self.cert.values
        out = []
        missing = [n for n in fns if n not in recorded]
        extra = [n for n in recorded if n not in fns]
        if missing or extra:
            out.append(("integrals recorded", False, "; ".join(
                ([f"no values recorded for {', '.join(missing)}"] if missing else []) +
                ([f"values recorded for {', '.join(extra)}, which the system does not declare"] if extra else []))))
        else:
            out.append(("integrals recorded", True, f"{', '.join(fns) or 'none declared'}"))
        checks = {c.name: c for c in self.cert.checks}
        for name, fn in fns.items():
            if name not in recorded:
                continue
            out += self._one_integral(name, fn, recorded[name], checks.get(f"integral {name} conserved by Phi_f"))
        if self.lp and "H~" in recorded and isinstance(recorded["H~"], list):
            out.append(self._definition(recorded["H~"]))
        return out

    def _one_integral(self, name, fn, recorded, check):
        label = f"values of {name}"
        if isinstance(fn, Undefined):
            return [(label, False, f"cannot be recomputed: {fn}")]
        if recorded is None:  # recorded as undefined: there must be a pole on the orbit
            for k in range(len(self.pts)):
                try:
                    self._value(name, fn, k)
                except Undefined:
                    return [(label, True, f"recorded as undefined; {name} has a pole at x_{k}")]
            return [(label, False, f"recorded as undefined, but {name} is finite at every orbit point")]
        if len(recorded) != len(self.pts):
            return [(label, False, f"{len(recorded)} values recorded for {len(self.pts)} orbit points")]
        values, notes = [], set()
        for k, text in enumerate(recorded):
            r = self.F.parse(text, f"values.{name}[{k}]")
            try:
                v, how = self._value(name, fn, k)
            except Undefined as exc:
                return [(label, False, f"recorded {_show(r)} at x_{k}, where {name} is undefined ({exc})")]
            if v != r:
                return [(label, False, f"at x_{k}: recorded {_show(r)}, recomputed {_show(v)}")]
            values.append(v)
            notes.add(how)
        result = [(label, True, f"all {len(values)} recorded values recomputed exactly{''.join(sorted(notes))}")]
        conserved = all(v == values[0] for v in values)
        k = next((k for k, v in enumerate(values) if v != values[0]), None)
        state = "equal along the orbit" if conserved else f"not equal along the orbit (x_{k} differs from x_0)"
        result.append((f"{name} conserved", True, f"values {state} (the record of the claim is re-derived below)"))
        return result

    def _definition(self, recorded):
        """H~(x_k) = (2 eps)^-1 x_k^T J(m)^-1 x_{k+1}, m = (x_k + x_{k+1})/2 (skipped where J(m) is singular)."""
        label = "H~ closed form = definition"
        pts = self.pts
        if len(recorded) != len(pts):
            return (label, False, "the values of H~ do not match the orbit")
        done, skipped = 0, []
        for k in range(len(pts) - 1):
            try:
                h = h_definition(pts[k], pts[k + 1], self.e, self.n)
            except Undefined:
                skipped.append(k)
                continue
            r = self.F.parse(recorded[k], f"values.H~[{k}]")
            if h != r:
                return (label, False, f"at x_{k}: recorded H~ = {_show(r)}, definition gives {_show(h)}")
            done += 1
        note = f"; skipped k = {skipped[:5]}{'...' if len(skipped) > 5 else ''} (J(m) singular)" if skipped else ""
        return (label, True, f"h(x_k, x_(k+1)) = H~(x_k) at {done} orbit points{note}")

