"""The claim registry's verdicts: controls that cannot fail are inapplicable, a certificate
with no applicable control is INCONCLUSIVE, and the claim 'measure' (added in one module,
exact_khk/certification/claims.py) certifies Kahan's Lotka–Volterra measure dx dy/(xy)."""

from __future__ import annotations

from fractions import Fraction

import sympy as sp

from exact_khk.certification.claims import CLAIMS, REGISTRY
from exact_khk.certification.engine import certify_system
from exact_khk.certification.lie_poisson import certify
from exact_khk.systems.expressions import ExpressionSystem
from exact_khk.systems.lie_poisson.system import LiePoissonSystem, random_point

LV = {"x": "x*(1 - y)", "y": "y*(x - 1)"}


def test_published_hirota_kimura_integrals_of_the_euler_top_certify_valid():
    """(1 - eps^2 a2 a3 x1^2)/(1 - eps^2 a3 a1 x2^2) -> 1 as eps -> 0: that control cannot fail."""
    a1, a2, a3 = 1, -2, 3
    top = ExpressionSystem.from_expressions(
        ["x1", "x2", "x3"], field={"x1": f"{a1}*x2*x3", "x2": f"{a2}*x3*x1", "x3": f"{a3}*x1*x2"},
        integrals={"C1": f"(1 - eps**2*({a2})*({a3})*x1**2)/(1 - eps**2*({a3})*({a1})*x2**2)",
                   "C2": f"(1 - eps**2*({a3})*({a1})*x2**2)/(1 - eps**2*({a1})*({a2})*x3**2)"},
        x0=["1", "2", "-1"], eps="1/5")
    cert = certify_system(top, steps=5)
    assert cert.status == "VALID"
    limit = cert.check("control: C1 at eps = 0 conserved")
    assert not limit.applicable and "is a constant" in limit.detail
    assert cert.check("control: C1 at a perturbed point").holds is False  # an applicable control fails


def test_an_equilibrium_is_inconclusive():
    eq = ExpressionSystem.from_expressions(["x", "y"], field={"x": "x*y", "y": "-x*y"}, integrals={"I": "x + y"},
                                           x0=["0", "0"], eps="1/10")
    cert = certify_system(eq, steps=5)
    assert cert.status == "INCONCLUSIVE"
    controls = [c for c in cert.checks if not c.expected]
    assert controls and all(not c.applicable for c in controls)
    # the perturbed-point control fails (I is not constant), but at a fixed point that shows nothing
    moved = cert.check("control: I at a perturbed point")
    assert moved.holds is False and "fixed point" in moved.detail
    # the same system off the equilibrium: VALID (x + y is conserved: f1 + f2 = 0)
    assert certify_system(eq, x0=["1", "2"], steps=5).status == "VALID"


def test_a_seeded_point_avoids_every_map_the_certificate_steps():
    s = LiePoissonSystem.random(4, 1)
    x0 = random_point(4, 1, system=s, eps="1/10")
    cert = certify(s, x0, "1/10", 20)
    assert cert.status == "VALID", [c.name for c in cert.checks if not c.passed]


def _kahan_lv_step(x, y, eps):
    """Kahan's step of x' = x(1 - y), y' = y(x - 1), from its defining equations, by Cramer's rule:
    (X - x)/(2 eps) = (X + x)/2 - (X y + x Y)/2,  (Y - y)/(2 eps) = (X y + x Y)/2 - (Y + y)/2."""
    h = 1 / (2 * eps)
    a11, a12, b1 = h - Fraction(1, 2) + y / 2, x / 2, h * x + x / 2
    a21, a22, b2 = -y / 2, h + Fraction(1, 2) - x / 2, h * y - y / 2
    d = a11 * a22 - a12 * a21
    return (b1 * a22 - a12 * b2) / d, (a11 * b2 - a21 * b1) / d


def test_kahan_lotka_volterra_preserves_dx_dy_over_xy():
    assert "measure" in CLAIMS and REGISTRY["measure"].declared(ExpressionSystem.from_expressions(
        ["x", "y"], field=LV, measure="1/(x*y)"))
    eps, x0 = Fraction(1, 10), (Fraction(1, 2), Fraction(3))
    lv = ExpressionSystem.from_expressions(["x", "y"], field=LV, measure="1/(x*y)", x0=list(map(str, x0)), eps="1/10")
    cert = certify_system(lv, steps=6)
    assert cert.status == "VALID"
    assert cert.check("invariant measure").holds is True
    assert cert.check("control: measure with density 1 preserved").holds is False
    # the orbit, independently (Fractions from the defining equations)
    p = x0
    for k in range(1, 7):
        p = _kahan_lv_step(*p, eps)
        assert tuple(Fraction(t) for t in cert.orbit[k]) == p
    # the claim itself, independently (SymPy): m(Phi(x)) det dPhi(x) = m(x) identically
    x, y, e = sp.symbols("x y e")
    X, Y = sp.symbols("X Y")
    sol = sp.solve([(X - x) - e * ((X + x) - (X * y + x * Y)), (Y - y) - e * ((X * y + x * Y) - (Y + y))], [X, Y])
    Phi = sp.Matrix([sol[X], sol[Y]])
    det = Phi.jacobian([x, y]).det()
    assert sp.simplify(det / (Phi[0] * Phi[1]) - 1 / (x * y)) == 0
    # and a wrong density is refused: the claim can fail
    wrong = ExpressionSystem.from_expressions(["x", "y"], field=LV, measure="1/(x*y**2)", x0=["1/2", "3"], eps="1/10")
    assert certify_system(wrong, steps=3, claims=["measure"]).status == "INVALID"


def test_a_system_file_declares_a_measure():
    text = ('format = 1\nname = "lv"\nvariables = ["x", "y"]\n[field]\nx = "x*(1 - y)"\ny = "y*(x - 1)"\n'
            '[measure]\ndensity = "1/(x*y)"\n[defaults]\nx0 = ["1/2", "3"]\neps = "1/10"\n')
    s = ExpressionSystem.from_toml(text)
    assert s.claims == ("reversibility", "jacobian", "measure") and "invariant measure" in s.known()
    assert ExpressionSystem.from_json(s.to_json()).measure().text == "1/(x*y)"
    assert certify_system(s, steps=3).status == "VALID"


EQ_FILE = 'name = "eq"\nvariables = ["x", "y"]\n[field]\nx = "x*y"\ny = "-x*y"\n[integrals]\nI = "x + y"\n'


def test_a_drawn_point_of_a_system_file_is_no_equilibrium(tmp_path):
    s = ExpressionSystem.from_toml(EQ_FILE)
    plain = [s.random_point(seed) for seed in range(30)]
    assert any(x == 0 or y == 0 for x, y in plain)  # the plain draws do hit equilibria (x = 0 or y = 0) ...
    drawn = [s.seeded_point(seed) for seed in range(30)] + [s.default_x0]
    assert all(x != 0 and y != 0 for x, y in drawn)  # ... the points the tool draws never do
    assert certify_system(s, x0=s.seeded_point(0), steps=3).status == "VALID"


def test_a_degenerate_user_point_is_named_with_the_way_out(tmp_path, capsys):
    from exact_khk.cli.main import main

    path = tmp_path / "eq.toml"
    path.write_text(EQ_FILE + '[defaults]\nx0 = ["0", "0"]\n', encoding="utf-8")
    assert main(["certify", "--system", str(path), "--steps", "3"]) == 4
    err = capsys.readouterr().err
    assert "x0 is degenerate for this system" in err and "fixed point" in err and "--seed" in err
    # a point on the singular set of the family: every check of H~ is undefined there
    assert main(["certify", "--a", "1,0,2", "--b", "0,1,0", "--c", "3,1,1", "--x0", "1,1,1,0,1,2", "--steps", "3"]) == 4
    err = capsys.readouterr().err
    assert "x0 is degenerate for this system" in err and "undefined at every point" in err
    assert main(["certify", "--system", str(path), "--steps", "3", "--seed", "0"]) == 0
    assert "degenerate" not in capsys.readouterr().err


def test_the_perturbed_point_control_of_the_family_is_moot_at_an_equilibrium():
    """Hs x0 = 0 (a = b = 0, X(c) v0 = 0, X(u0) regular): H~ near x0 differs from H~(x0) = 0, a
    failure that says nothing about the map; the non-admissible field still moves x0 and is judged."""
    s = LiePoissonSystem.from_vectors("0,0", "0,0", "1,1")
    cert = certify(s, ["1", "0", "1", "-1"], "1/10", 3)
    moved = cert.check("control: integral H~ at a perturbed point")
    assert moved.holds is False and not moved.applicable and "equilibrium" in moved.detail
    assert cert.check("control: integral H~ conserved for a non-admissible Hessian").applicable


def test_system_files_name_the_registry_claims():
    """systems/ sits below certification/, so system files keep their own list of claim names: the same."""
    from exact_khk.systems import expressions

    assert expressions.CLAIMS == CLAIMS


def test_any_system_may_declare_the_certificate_behaviours_of_the_family():
    """claims_on_every_orbit and own_controls_only are declared on System, not tied to the family: an
    expression system declaring them has its integrals and Poisson map checked per map along every
    map's orbit (the Poisson checks at the poisson_points subset) and its own controls alone."""
    top = ExpressionSystem.from_expressions(
        ["x1", "x2", "x3"], field={"x1": "x2*x3", "x2": "-2*x3*x1", "x3": "3*x1*x2"},
        fields={"g": {"x1": "2*x2*x3", "x2": "-4*x3*x1", "x3": "6*x1*x2"}},
        integrals={"C1": "(1 + 6*eps**2*x1**2)/(1 - 3*eps**2*x2**2)"},
        poisson=[["0", "x3", "-x2"], ["-x3", "0", "x1"], ["x2", "-x1", "0"]],
        controls={"naive": "x1**2 + x2**2 + x3**2"}, x0=["1", "2", "3"], eps="1/10")
    claims = ["integrals", "commutation", "poisson"]
    plain = certify_system(top, steps=5, claims=claims)
    assert plain.check("integral C1 conserved by Phi_g").claim == "C1(y_k) = C1(y_0) along the Phi_g orbit of x0"
    assert "control: C1 at a perturbed point" in [c.name for c in plain.checks]
    top.claims_on_every_orbit = top.own_controls_only = True
    declared = certify_system(top, steps=5, claims=claims, poisson_points=2)
    conserved = declared.check("integral C1 conserved by Phi_g")
    assert conserved.claim == "C1(x_k) = C1(x_0) for k = 1..5 along the Phi_g orbit"
    for name, holds in (("integral C1 conserved by Phi_f", True), ("integral C1 conserved by Phi_g", False)):
        # Phi_g is Phi_f at 2 eps, whose integral C1 is not (it is of step eps): both routes say so alike
        assert declared.check(name).holds is plain.check(name).holds is holds
        assert declared.check(name).residual == plain.check(name).residual
    assert "Poisson map Phi_g" in [c.name for c in declared.checks]
    jacobi = next(c for c in declared.checks if c.name.endswith("Jacobi identity"))
    assert "at 2 of the 5 points (k = [0, 4]) of the Phi_f orbit" in jacobi.claim
    assert [c.name for c in declared.checks if not c.expected] == ["control: naive conserved by Phi_f"]
