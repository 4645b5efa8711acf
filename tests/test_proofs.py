"""Symbolic proofs: identities in the field of rational functions Q(x, ε)."""

from fractions import Fraction

import pytest
from hypothesis import given, settings, strategies as st

from exact_khk import KahanMap, LiePoissonSystem, get_arith
from exact_khk.certification.engine import symbolic_checks
from exact_khk.certification.proofs import RationalFunctionArith, prove_jacobi

S2 = LiePoissonSystem.from_vectors("1,2", "0,1", "3,1")


def test_rational_function_arithmetic():
    ar = RationalFunctionArith(["x", "y"])
    x, y = ar.gens()
    r = (x * x - y * y) / (x - y)
    assert r == x + y and r.den == ar.one.den             # reduced by the gcd
    assert (1 / x) * x == 1 and x / (2 * x) == Fraction(1, 2)
    assert ar.is_zero(r - x - y) and not ar.is_zero(r)
    with pytest.raises(ZeroDivisionError):
        x / (y - y)
    assert ar.format(1 / (2 * x + 2)) == "(1/2)/(x + 1)"
    # Henrici's sum: the common factor x + 1 of the denominators cancels with the sum
    s = 1 / (x * (x + 1)) + 1 / (x + 1)
    assert s.den == x.num and s.num == ar.one.num and s == 1 / x
    assert 3 / (x - y) - 3 / (x - y) == 0 and (3 / (x - y) - 3 / (x - y)).den == ar.one.den


_FACTORS = [lambda x, y: x, lambda x, y: y, lambda x, y: x + 1, lambda x, y: x - y,
            lambda x, y: 2 * x * y + 3, lambda x, y: y * y + x, lambda x, y: x + y + 1]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.lists(st.integers(0, 6), max_size=3), st.lists(st.integers(0, 6), max_size=3),
                          st.integers(-3, 3).filter(bool)), min_size=2, max_size=2),
       st.sampled_from("+-*/"))
def test_rational_function_operations_stay_canonical(parts, op):
    """Henrici's sums and products (gcds of parts only) give the canonical form:
    lowest terms, monic denominator, 0 as 0/1, and the same value as the
    unreduced cross-multiplied result (checked as a polynomial identity)."""
    from exact_khk.certification.proofs import RatFunc

    ar = RationalFunctionArith(["x", "y"])
    x, y = ar.ctx.gens()
    one = ar.one.num

    def poly(idx):
        p = one
        for i in idx:
            p = p * _FACTORS[i](x, y)
        return RatFunc(p, one, reduce=False)

    (n1, d1, c1), (n2, d2, c2) = parts
    u, v = ar.one * c1 * poly(n1) / poly(d1), ar.one * c2 * poly(n2) / poly(d2)
    if op == "/" and ar.is_zero(v):
        return
    r = {"+": lambda: u + v, "-": lambda: u - v, "*": lambda: u * v, "/": lambda: u / v}[op]()
    assert r.den.leading_coefficient() == 1
    assert r.num.gcd(r.den).is_one() or r.num.is_zero() and r.den.is_one()
    num, den = {"+": (u.num * v.den + v.num * u.den, u.den * v.den),
                "-": (u.num * v.den - v.num * u.den, u.den * v.den),
                "*": (u.num * v.num, u.den * v.den), "/": (u.num * v.den, u.den * v.num)}[op]
    assert r.num * den == num * r.den


def test_kahan_step_over_rational_functions_specialises_to_the_rational_step():
    """The symbolic step at x = (1, 0, 0, 1), ε = 1/3 equals the exact rational step."""
    ar = RationalFunctionArith(["x0", "x1", "x2", "x3", "eps"])
    *x, eps = ar.gens()
    y = KahanMap(S2.field("f"), eps, ar, method="dense").step(x)
    point = [1, 0, 0, 1, Fraction(1, 3)]
    spec = [ar.evaluate(t, point) for t in y]
    assert spec == list(KahanMap(S2.field("f"), "1/3", "fraction").step([1, 0, 0, 1]))


def test_n2_proofs():
    """Every claim of the registry proved for the family's n = 2 (the engine's symbolic mode), each
    negative control disproved."""
    recs = symbolic_checks(S2.with_involutions(["+-", "-+"]))
    names = [r.name for r in recs]
    for name in ("integral H~ conserved by Phi_f", "integral K~[+-] conserved by Phi_g[-+]",
                 "commutation Phi_f o Phi_g[+-]", "Poisson tensor Pi Jacobi identity", "involution {H~,K~[-+]}_Pi",
                 "control: commutation with non-associated field", "control: integral H~ conserved by Phi_control"):
        assert f"proof: {name}" in names, name
    for r in recs:
        assert r.passed and r.holds is r.expected, r
        assert (r.residual == "0") is r.expected or r.name.startswith("proof: rank")
        assert r.evidence.startswith("symbolic proof: " if r.expected else "symbolic disproof: ")
    assert "Q(x0, x1, x2, x3, eps)" in recs[0].evidence and len([r for r in recs if not r.expected]) == 4


@pytest.mark.parametrize("n", [2, 3])
def test_jacobi_identity_for_every_admissible_hessian(n):
    system = LiePoissonSystem.random(n, seed=1)
    for eps_zero in (True, False):
        r = prove_jacobi(system, symbolic_hessian=True, eps_zero=eps_zero)
        assert r.passed and r.holds is True, r
        assert "every admissible Hessian" in r.evidence


def test_jacobi_negative_control():
    """A perturbed tensor J + ε² (x_0 · constant antisymmetric) is not Poisson."""
    from exact_khk.certification.proofs import jacobi_residual

    ok, res, _ = jacobi_residual(S2, perturb=True)
    assert not ok and res != "0"


def test_prove_is_for_n2_and_refuses_big_coefficients_at_once():
    """n = 3 (dimension 6: H~ conserved by Phi_f alone takes 1.5 CPU minutes, and the registry has
    dozens of such claims) is refused, as is a 5000-digit coefficient (SymPy ran for minutes)."""
    from exact_khk import InputError
    from exact_khk.certification.lie_poisson import PROVE_MAX_BITS, prove_limits

    with pytest.raises(InputError, match="dimension 4"):
        prove_limits(LiePoissonSystem.random(3, seed=1))
    big = LiePoissonSystem.from_vectors([2 ** PROVE_MAX_BITS, 1], "0,1", "3,1")
    with pytest.raises(InputError, match=rf"a coefficient of {PROVE_MAX_BITS + 1} bits is beyond the "
                                         rf"{PROVE_MAX_BITS} bits"):
        prove_limits(big)


def test_symbolic_results_agree_with_exact_arithmetic_at_a_point():
    """The symbolic H̃ specialised at a rational point equals H̃ computed in Q."""
    from exact_khk.systems.lie_poisson.invariants import Htilde

    ar = RationalFunctionArith(["x0", "x1", "x2", "x3", "eps"])
    *x, eps = ar.gens()
    h = Htilde(S2.field("f"), x, eps, ar)
    Q = get_arith("fraction")
    assert ar.evaluate(h, [2, -1, 1, 3, Fraction(1, 5)]) == Htilde(S2.field("f"), [Q(t) for t in (2, -1, 1, 3)], "1/5", Q)


@pytest.mark.slow
def test_cli_prove_takes_a_system_by_its_vectors_without_a_point(capsys):
    """--a/--b/--c name a system; prove needs no --x0 (and refuses one): it used to demand
    it, so a system given by its vectors could not be proved at all."""
    from exact_khk.cli.main import main

    assert main(["prove", "--a", "1,0", "--b", "2,1", "--c", "1,3"]) == 0
    out = capsys.readouterr().out
    assert "a=(1, 0), b=(2, 1), c=(1, 3)" in out and "VALID" in out and "FAIL" not in out
    assert main(["orbit", "--a", "1,0", "--b", "2,1", "--c", "1,3"]) == 2   # a point command still needs --x0
    assert "--x0 is required" in capsys.readouterr().err


def test_evidence_doc_examples_run(capsys):
    """The Python examples of docs/evidence.md run and print what they claim."""
    import pathlib
    import re

    text = (pathlib.Path(__file__).parent.parent / "docs" / "evidence.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) == 2
    for b in blocks:
        exec(compile(b, "docs/evidence.md", "exec"), {})
    out = capsys.readouterr().out
    assert "control: commutation with non-associated field False exact in Q(zeta_3)" in out
    assert "involution {K~[-++],K~[++-]}_Pi True exact in Q(zeta_3)" in out and "None" not in out
    assert "proof: Poisson map Phi_f True symbolic proof: identity in Q(x0, x1, x2, eps)" in out
    assert "for every admissible Hessian" in out


def test_cli_prove_without_options_proves_the_documented_n2_system(capsys):
    """`exact-khk prove` alone proves the n = 2 system of docs/evidence.md: every claim of the
    registry proved, the four negative controls disproved."""
    from exact_khk.cli.main import main

    assert main(["prove"]) == 0
    out = capsys.readouterr().out
    assert "a=(1, 2), b=(0, 1), c=(3, 1)" in out and "FAIL" not in out and out.rstrip().endswith("VALID")
    assert out.count("symbolic disproof") == 4 and out.count("holds=False") == 4


@pytest.mark.parametrize("option", [["--eps", "1/3"], ["--x0", "1,0,0,1"]])
def test_cli_prove_refuses_a_point_or_step_size(option, capsys):
    """x and eps are symbols in the proofs: a given --x0 or --eps was silently ignored."""
    from exact_khk.cli.main import main

    assert main(["prove", "--n", "2", "--seed", "1", *option]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and option[0] + ": prove works with rational functions" in err
