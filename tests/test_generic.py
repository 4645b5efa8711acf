"""The generic certificate of any quadratic system (exact_khk.certification.engine).

Golden facts are derived by hand or by SymPy here, never by the code under test:
the CMOQ modified energy and Sanz-Serna's Poisson structure of Kahan's
Lotka–Volterra map are checked against their published statements; a wrong
integral must make the certificate INVALID; degenerate points make controls
inapplicable, never failures.
"""

from fractions import Fraction

import pytest
import sympy as sp

from exact_khk import InputError, KahanMap, certify, get_arith
from exact_khk.certification.claims import CLAIMS, modified_energy
from exact_khk.certification.engine import certify_system
from exact_khk.cli.main import main
from exact_khk.systems.expressions import ExpressionSystem

LV = dict(variables=["u", "v"], field={"u": "u*(1-v)", "v": "v*(u-1)"},
          poisson=[["0", "u*v"], ["-u*v", "0"]], controls={"naive": "u*v"}, x0=["1/2", "3"], eps="1/10",
          name="lv")
CUBIC = dict(variables=["q", "p"], hamiltonian={"K": [["0", "1"], ["-1", "0"]], "H": "p**2/2 + q**3/3 - q**2/2"},
             x0=["1/3", "1/2"], eps="1/10", name="cubic")


def lv():
    return ExpressionSystem.from_expressions(**LV)


def cubic():
    return ExpressionSystem.from_expressions(**CUBIC)


@pytest.mark.parametrize("arith", ["fraction", "gmpy2", "flint"])
def test_lotka_volterra_is_poisson_and_the_naive_invariant_is_not_conserved(arith):
    cert = certify(lv(), steps=6, arith=arith)
    assert cert.status == "VALID", cert.table()
    assert cert.check("Poisson map Phi_f").holds is True
    assert cert.check("control: naive conserved by Phi_f").holds is False
    jac = cert.check("control: Jacobi identity of Pi + W")
    assert not jac.applicable and "dimension 2" in jac.detail  # cannot fail in 2D: inapplicable, not FAILED


def test_exact_arithmetics_agree_on_orbit_and_values():
    certs = [certify(cubic(), steps=5, arith=a) for a in ("fraction", "gmpy2", "flint")]
    assert certs[0].orbit == certs[1].orbit == certs[2].orbit
    assert len(certs[0].orbit) == 6


def test_cmoq_modified_energy_against_sympy():
    """H~ = H + (2 eps/3) grad H^T (I - eps f')^{-1} f (CMOQ with h = 2 eps), from SymPy directly."""
    q, p, e = sp.symbols("q p e")
    H = p ** 2 / 2 + q ** 3 / 3 - q ** 2 / 2
    f = sp.Matrix([sp.diff(H, p), -sp.diff(H, q)])
    J = f.jacobian([q, p])
    expr = H + sp.Rational(2, 3) * e * (sp.Matrix([[sp.diff(H, q), sp.diff(H, p)]]) * (sp.eye(2) - e * J).inv() * f)[0]
    x, eps = (Fraction(1, 3), Fraction(1, 2)), Fraction(1, 10)
    want = sp.Rational(expr.subs({q: sp.Rational(1, 3), p: sp.Rational(1, 2), e: sp.Rational(1, 10)}))
    sys_ = cubic()
    ar = get_arith("fraction")
    got = modified_energy(ar, sys_.field("f"), sys_.hamiltonian_form()[1], [ar.convert(t) for t in x], ar.convert(eps))
    assert got == Fraction(int(want.p), int(want.q))
    cert = certify(sys_, steps=8)
    assert cert.status == "VALID" and cert.check("CMOQ modified energy conserved").holds is True
    assert cert.check("CMOQ invariant measure").holds is True
    assert cert.check("control: H conserved").holds is False


def test_a_wrong_integral_makes_the_certificate_invalid():
    wrong = ExpressionSystem.from_expressions(**{**LV, "integrals": {"I": "u + v"}})
    cert = certify(wrong, steps=4, claims=["integrals"])
    assert cert.status == "INVALID" and cert.check("integral I conserved by Phi_f").holds is False


def test_equilibrium_makes_controls_inapplicable_not_failed():
    """At the equilibrium (1, 1) of Lotka–Volterra every Kahan step returns the point."""
    cert = certify(lv(), x0=["1", "1"], steps=3, claims=["reversibility", "jacobian", "poisson"])
    assert cert.status != "INVALID"
    twice = cert.check("control: Phi_f applied twice returns")
    assert not twice.applicable and "2-periodic" in twice.detail
    assert all(c.holds for c in cert.checks if c.expected)


def test_no_applicable_control_is_inconclusive_not_valid():
    """A field with nothing declared, at its equilibrium 0: reversibility and the Jacobian
    hold, and neither control can fail there (Φ(x) = x, f'(Φ(x)) = f'(x)); nothing shows
    that the checks can fail."""
    field_only = ExpressionSystem.from_expressions(["x", "y"], ["x*y", "x - y**2"])
    cert = certify(field_only, x0=["0", "0"], steps=3)
    assert [c.holds for c in cert.checks if c.expected] == [True, True]
    assert [c.applicable for c in cert.checks if not c.expected] == [False, False]
    assert cert.status == "INCONCLUSIVE" and "no negative control can fail at this point" in cert.verdict()


def _expressions(field, names):
    """The components of a QuadraticField as expression strings (for a system file)."""
    return {names[i]: " + ".join(f"({c})*{names[j]}*{names[k]}" for (j, k), c in terms) or "0"
            for i, terms in enumerate(field.terms())}


def test_commutation_of_the_paper_fields_written_as_a_system_file():
    """f and the associated g of a Lie–Poisson system (Petrera–Suris: their Kahan maps commute at
    equal eps), handed in as expressions: the generic certificate confirms it, and the control
    (g at 2 eps) fails."""
    from exact_khk import LiePoissonSystem

    lp = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3")
    names = ["u0", "u1", "v0", "v1"]
    s = ExpressionSystem.from_expressions(names, field=_expressions(lp.field("f"), names),
                                          fields={"g": _expressions(lp.field("g", "-+"), names)},
                                          x0=["2", "1", "1", "-1"], eps="1/7")
    cert = certify(s, steps=4, claims=["commutation", "reversibility"])
    assert cert.status == "VALID", cert.table()
    assert cert.check("commutation Phi_f o Phi_g").holds is True
    assert cert.check("control: commutation with Phi_g at 2 eps").holds is False
    assert cert.check("reversibility Phi_g").holds is True
    # the same orbit as the Lie–Poisson map, exactly
    assert cert.orbit[-1] == tuple(str(t) for t in KahanMap(lp.field("f"), "1/7").orbit(["2", "1", "1", "-1"], 4)[-1])


def test_claims_are_validated():
    with pytest.raises(InputError, match="unknown claim"):
        certify_system(lv(), claims=["nonsense"])
    with pytest.raises(InputError, match="declares nothing"):
        certify_system(lv(), claims=["cmoq"])
    assert set(CLAIMS) >= {"reversibility", "integrals", "poisson", "commutation", "jacobian", "cmoq"}


def test_floating_certificate_is_inconclusive_never_invalid():
    cert = certify(cubic(), steps=4, arith="mp:80")
    assert cert.status == "INCONCLUSIVE" and all(c.holds is None for c in cert.checks if c.applicable)


def test_certificate_json_carries_the_orbit_and_values():
    cert = certify(cubic(), steps=3)
    data = cert.to_json()
    assert data["schema_version"] >= 2 and len(data["orbit"]) == 4 and data["orbit"][0] == ["1/3", "1/2"]
    assert data["system"]["name"] == "cubic" and data["path"]
    assert ExpressionSystem.from_json(data["system"]).field("f").quad == cubic().field("f").quad


def test_cli_certify_system_file(tmp_path, capsys):
    path = tmp_path / "cubic.toml"
    path.write_text('name = "cubic"\nvariables = ["q", "p"]\n[hamiltonian]\nK = [["0", "1"], ["-1", "0"]]\n'
                    'H = "p**2/2 + q**3/3 - q**2/2"\n[defaults]\nx0 = ["1/3", "1/2"]\neps = "1/10"\n')
    assert main(["certify", "--system", str(path), "--steps", "5"]) == 0
    out = capsys.readouterr().out
    assert out.strip().splitlines()[-1].startswith("VALID") and "CMOQ modified energy" in out
    assert main(["certify", "--system", str(path), "--steps", "3", "--claims", "cmoq"]) == 0
    assert main(["certify", "--system", str(path), "--signs", "-++"]) == 2
    assert main(["orbit", "--system", str(path), "--steps", "2"]) == 0
    out = capsys.readouterr().out
    assert "q" in out.splitlines()[2] or "q" in out
    assert main(["integrals", "--system", str(path)]) == 0
    assert main(["certify", "--system", str(tmp_path / "missing.toml")]) == 2
    assert main(["certify", "--system", str(path), "--a", "1,2"]) == 2
