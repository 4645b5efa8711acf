"""The negative controls of the Lie–Poisson certificate and where they cannot fail.

:func:`negative_controls` declares the four controls of the paper's certificate
(:meth:`LiePoissonSystem.negative_controls`; the engine evaluates them, see
:class:`~exact_khk.systems.base.Control`): commutation with the non-associated control
field, H̃ under the control map, H̃ for a non-admissible Hessian, and H̃ at a point
perturbed by 2^-60 (relative).  A control that did not fail at a point of a degenerate set
is recorded as *inapplicable*, never as a failure; :class:`ControlDegeneracy` decides these
sets exactly, in Fractions, independently of the arithmetic of the checks; the certificate,
``liouville`` (identities) and ``prove`` (proofs) all ask it.
"""

from __future__ import annotations

from fractions import Fraction

from exact_khk.arith import get_arith
from exact_khk.errors import PoleError
from exact_khk.linalg.dense import matvec
from exact_khk.systems.base import Control
from exact_khk.systems.lie_poisson.invariants import Htilde, HtildeIntegral


def non_admissible_hessian(system):
    """Hs with its (0, 0) entry raised by 1: the block X(a) is no longer cyclic Hankel.

    For n = 2 the entries (0, 2) and (2, 0) are raised instead (the block X(b)):
    a 2×2 block with a raised diagonal entry keeps H~ conserved for about 4 % of
    small random systems and points, the raised off-diagonal block for under 0.2 %.
    """
    M = [list(r) for r in system.hessian]
    if system.n == 2:
        M[0][2] += 1
        M[2][0] += 1
    else:
        M[0][0] += 1
    return M


class ControlDegeneracy:
    """Where a negative control of the Lie–Poisson certificate cannot fail, decided exactly
    (in Fractions, independently of the checks' arithmetic); each method returns
    the reason, or None.  A control that did not fail at a point of these sets is
    recorded as inapplicable (``run_check(..., degenerate=...)``), never as a
    failure.  The sets (x0 = (u, v); frequencies: DFT index j, ω = e^{2πi/n}):

    * J(x0) singular, i.e. X(u0) singular: some û_j = Σ u_i ω^{ij} vanishes
      (u = 0, u with equal coordinates, Σu = 0, Σ(−1)^i u_i = 0 for even n, …);
      an invariant set of every Kahan map of the family, on which h(x, x̃) is
      undefined (all controls);
    * equilibria: Hs x0 = 0 (then f, every g and the control field vanish at x0
      when J(x0) is regular; every map fixes x0), or M' x0 = 0 for the
      non-admissible Hessian M' (all controls, respectively the third);
    * n = 2, controls 1 and 2: for n = 2 the frequencies j = 0, 1 decouple, the
      control field equals f on j = 1 and 3f on j = 0, so the control map is
      (Φ_{f_0}(3ε), Φ_{f_1}(ε)) with f_0 the planar field
      U' = U(βU + γV), V' = −U(αU + βV) of (U, V) = (Σu, Σv), (α, β, γ) =
      (Σa, Σb, Σc).  Kahan maps of f_0 with different steps commute (and conserve
      each other's H~) when β² = αγ (f_0 = U·K w with K nilpotent) or when
      (U, V) lies on an eigenline of K, i.e. αU² + 2βUV + γV² = 0 (an invariant
      line, on which the maps are commuting Möbius maps);
    * n ≥ 3, controls 1 and 2: b and c carry only the frequencies 0 and n/2
      (b_(i+2) = b_i, c_(i+2) = c_i; constant for odd n), control 3: b and c
      constant — systems whose u moves only within those frequencies; the
      controls held on every random example of them (found in a survey of
      1000 random systems, then confirmed on 100 more);
    * poles: H~ (or H~ of M') undefined at x0, at the perturbed point or at x_K
      (controls 2 to 4: the control has nothing to compare);
    * the fourth control: H~ constant along the line through x0 in the
      perturbed coordinate (checked at three further points of the line).
    """

    def __init__(self, system, x0=None, eps=None):
        """``x0`` None: no point (the symbolic proofs, see :meth:`everywhere`)."""
        self.system, self.x0 = system, None if x0 is None else tuple(Fraction(t) for t in x0)
        self.eps = None if eps is None else Fraction(eps)
        self._ar = get_arith("fraction")
        self._cache = {}

    def _memo(self, key, fn):
        if key not in self._cache:
            self._cache[key] = fn()
        return self._cache[key]

    def common(self):
        """Reasons shared by every control: J(x0) singular, x0 an equilibrium."""
        def reason():
            x = self.x0
            if x is None:  # no point (x generic): only the system's own reasons
                return "Hs = 0: every point is an equilibrium" if not any(map(any, self.system.hessian)) else None
            if self.system.singular_J(x):
                return ("J(x0) is singular (X(u0) is: u0 lies on the invariant set where a DFT value "
                        "sum_i u_i w^(ij) vanishes, e.g. u = 0, equal coordinates, sum u = 0)")
            if not any(matvec(self.system.hessian, list(x))):
                return "x0 is an equilibrium (Hs x0 = 0): every map of the family fixes it"
            return None
        return self._memo("common", reason)

    def _planar(self):
        """n = 2: the degenerate frequency-0 subsystem (see the class docstring)."""
        s = self.system
        if s.n != 2:
            return None
        al, be, ga = sum(s.a), sum(s.b), sum(s.c)
        if be * be == al * ga:
            return (f"n = 2: the control map is Phi_f with step 3 eps on the frequency-0 plane, where the "
                    f"planar field is degenerate (sum b^2 = sum a * sum c = {al * ga}): its Kahan maps commute")
        if self.x0 is None:  # no point: the invariant lines below are points' properties
            return None
        U, V = sum(self.x0[:2]), sum(self.x0[2:])
        if al * U * U + 2 * be * U * V + ga * V * V == 0:
            return ("n = 2: (sum u, sum v) lies on an invariant line of the frequency-0 planar field "
                    "(sum a U^2 + 2 sum b UV + sum c V^2 = 0), where Kahan maps with different steps commute")
        return None

    def _pole(self, field, x):
        try:
            Htilde(field, list(x), self.eps, self._ar)
        except PoleError:
            return True
        return False

    def _self_paired(self, constant=False):
        """n ≥ 3 and b, c carry only the frequencies 0 and n/2 (b_(i+2) = b_i, c_(i+2) = c_i;
        with ``constant``: b and c constant), a property of the system."""
        s = self.system
        n = s.n
        if n < 3:
            return None
        step = 1 if constant else 2
        if all(w[(i + step) % n] == w[i] for w in (s.b, s.c) for i in range(n)):
            what = "equal coordinates" if constant or n % 2 else "period 2 (only the frequencies 0 and n/2)"
            return (f"b and c have {what}: u then moves only within those frequencies, and the controls "
                    f"cannot tell the control field from f (they hold on every example of such systems)")
        return None

    def equilibrium(self):
        """x0 an equilibrium (Hs x0 = 0): the orbit of Φ_f is one point, where the perturbed-point
        control compares H~ near x0 with H~(x0) itself and shows nothing about the map, even when it fails."""
        if self.x0 is None:
            return self.common()
        if not any(matvec(self.system.hessian, list(self.x0))):
            return "x0 is an equilibrium (Hs x0 = 0): the orbit is one point, where every function is conserved"
        return None

    def commutation(self):
        return self.common() or self._planar() or self._self_paired()

    def everywhere(self):
        """Controls 1 and 2 as identities in x and eps (the symbolic proofs): the reasons
        that hold at every point, i.e. that depend on the system only."""
        return self._planar() or self._self_paired()

    def control_conserves(self):
        why = self.common() or self._planar() or self._self_paired()
        if not why and self.x0 is not None and self._pole(self.system.field("f"), self.x0):
            why = "H~ has a pole at x0"
        return why

    def non_admissible(self):
        why = self.common()
        if why and why.startswith("J("):
            return why
        if self._self_paired(constant=True):
            return self._self_paired(constant=True)
        if self.x0 is None:
            return why
        bad = non_admissible_hessian(self.system)
        if not any(matvec(bad, list(self.x0))):
            return "x0 is an equilibrium of the non-admissible field (Hs' x0 = 0)"
        field = self.system.field_from_hessian(bad, "non-admissible")
        if self._pole(field, self.x0):
            return "H~ of the non-admissible Hessian has a pole at x0"
        return None

    def perturbed(self, x_last, ar):
        """The fourth control; ``x_last`` is the orbit's last point (in ``ar``)."""
        why = self.common()
        if why or self.x0 is None:
            return why
        f = self.system.field("f")
        if self._pole(f, self.x0):
            return "H~ has a pole at x0 (and at the perturbed point: J does not depend on v)"
        try:
            if self._pole(f, [ar.to_fraction(t) for t in x_last] if ar.rational else x_last):
                return "H~ has a pole at the last orbit point"
        except (TypeError, ValueError, ArithmeticError):
            pass
        x, h0 = list(self.x0), Htilde(f, list(self.x0), self.eps, self._ar)
        for t in (1, 2, 3):
            y = x[:-1] + [x[-1] + t]
            if self._pole(f, y) or Htilde(f, y, self.eps, self._ar) != h0:
                return None
        return "H~ does not depend on the perturbed (last) coordinate near x0"


def negative_controls(system, x0, eps) -> list:
    """The four controls of the paper's certificate at x0 and ε, in their order (each with its
    degenerate sets from :class:`ControlDegeneracy`, which include the equilibria; the last is
    also moot at an equilibrium, where it compares H̃ near x0 with H̃(x0) even when it fails)."""
    n, degen = system.n, ControlDegeneracy(system, x0, eps)
    ctrl = system.field("control")
    bad = system.field_from_hessian(non_admissible_hessian(system), "non-admissible")
    H = system.integrals()["H~"]
    return [
        Control("commutes", "control: commutation with non-associated field",
                f"[control, must fail] Phi_f commutes with the Kahan map of the control field "
                f"({'A Hs' if n >= 3 else '(2I + A) Hs'}) at the points of the Phi_f orbit",
                field=ctrl, degenerate=lambda ar, pts: degen.commutation()),
        Control("conserved", "control: integral H~ conserved by Phi_control",
                "[control, must fail] H~ is conserved along the orbit of the control map",
                field=ctrl, function=H, degenerate=lambda ar, pts: degen.control_conserves()),
        Control("conserved", "control: integral H~ conserved for a non-admissible Hessian",
                "[control, must fail] with " + ("Hs[0][0]" if n >= 3 else "Hs[0][2] = Hs[2][0]") + " raised by 1 "
                "(block X(" + ("a" if n >= 3 else "b") + ") not cyclic Hankel), the closed "
                "form H~ is conserved by the Kahan map of J(x) Hs' x",
                field=bad, function=HtildeIntegral("H~", bad, "H~ of the non-admissible Hessian"),
                degenerate=lambda ar, pts: degen.non_admissible()),
        Control("perturbed", "control: integral H~ at a perturbed point",
                "[control, must fail] H~ at x0 with its last coordinate perturbed by {how} equals "
                "H~(x_{K}) on the orbit", function=H,
                degenerate=lambda ar, pts: degen.perturbed(pts[-1], ar), moot=degen.equilibrium)]
