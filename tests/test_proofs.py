"""Symbolic proofs: identities in the field of rational functions Q(x, ε)."""

from fractions import Fraction

import pytest
from hypothesis import given, settings, strategies as st

from exact_khk import KahanMap, LiePoissonSystem, get_arith
from exact_khk.certification.proofs import (RationalFunctionArith, prove_all, prove_commutation, prove_conservation,
                              prove_jacobi)

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
    from exact_khk.certification.proofs import _kmap

    y = _kmap(S2.field("f"), eps, ar).step(x)
    point = [1, 0, 0, 1, Fraction(1, 3)]
    spec = [ar.evaluate(t, point) for t in y]
    assert spec == list(KahanMap(S2.field("f"), "1/3", "fraction").step([1, 0, 0, 1]))


def test_n2_proofs():
    """Each proof is followed by its negative control, which must be disproved."""
    recs = prove_all(S2)
    assert [r.name for r in recs] == ["proof:conservation", "proof:conservation:control", "proof:commutation",
                                      "proof:commutation:control", "proof:jacobi", "proof:jacobi:control"]
    for r in recs:
        control = r.name.endswith(":control")
        assert r.passed and r.expected is not control and r.holds is not control, r
        assert (r.residual == "0") is not control
        assert r.evidence.startswith("symbolic disproof: " if control else "symbolic proof: ")
    assert "Q(x0, x1, x2, x3, eps)" in recs[0].evidence


@pytest.mark.parametrize("signs", ["-+", "+-"])
def test_n2_associated_maps(signs):
    assert prove_conservation(S2, kind="g", signs=signs).holds is True
    assert prove_commutation(S2, kind="g", signs=signs).holds is True


def test_n2_negative_controls_fail_symbolically():
    for r in (prove_conservation(S2, kind="control"), prove_commutation(S2, kind="control")):
        assert r.expected is False and r.holds is False and r.passed, r
        assert r.residual != "0" and "eps" in r.residual


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


def test_prove_all_is_for_n2_and_3():
    from exact_khk import InputError

    with pytest.raises(InputError, match="n = 2"):
        prove_all(LiePoissonSystem.random(4, seed=1))


def test_prove_all_refuses_coefficients_beyond_its_bits_at_once():
    """A 5000-digit coefficient ran SymPy for minutes: refused before any proof starts."""
    from exact_khk import InputError
    from exact_khk.certification.proofs import PROVE_MAX_BITS

    big = LiePoissonSystem.from_vectors([2 ** PROVE_MAX_BITS, 1], "0,1", "3,1")
    with pytest.raises(InputError, match=rf"a coefficient of {PROVE_MAX_BITS + 1} bits is beyond the "
                                         rf"{PROVE_MAX_BITS} bits"):
        prove_all(big, progress=lambda stage: pytest.fail(f"a proof started: {stage}"))


@pytest.mark.slow
def test_n3_proofs_and_their_controls():
    """n = 3 (about 11 CPU minutes since Henrici's arithmetic; before it, conservation alone
    did not finish in 13 minutes): the three identities proved, the three controls disproved,
    with progress reported before each."""
    from exact_khk.systems.lie_poisson import default_system

    stages = []
    recs = prove_all(default_system(), stages.append)
    assert [r.holds for r in recs] == [True, False, True, False, True, False]
    assert all(r.passed for r in recs) and len(stages) == 6 and "n = 3" in recs[0].claim


def test_symbolic_results_agree_with_exact_arithmetic_at_a_point():
    """The symbolic H̃ specialised at a rational point equals H̃ computed in Q."""
    from exact_khk.systems.lie_poisson.invariants import Htilde

    ar = RationalFunctionArith(["x0", "x1", "x2", "x3", "eps"])
    *x, eps = ar.gens()
    h = Htilde(S2.field("f"), x, eps, ar)
    Q = get_arith("fraction")
    assert ar.evaluate(h, [2, -1, 1, 3, Fraction(1, 5)]) == Htilde(S2.field("f"), [Q(t) for t in (2, -1, 1, 3)], "1/5", Q)


def test_cli_prove(capsys):
    from exact_khk.cli.main import main

    assert main(["prove", "--n", "2", "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert out.count("symbolic proof") == 3 and out.count("symbolic disproof") == 3


def test_cli_prove_takes_a_system_by_its_vectors_without_a_point(capsys):
    """--a/--b/--c name a system; prove needs no --x0 (and refuses one): it used to demand
    it, so a system given by its vectors could not be proved at all."""
    from exact_khk.cli.main import main

    assert main(["prove", "--a", "1,0", "--b", "2,1", "--c", "1,3"]) == 0
    out = capsys.readouterr().out
    assert "a=(1, 0), b=(2, 1), c=(1, 3)" in out and out.count("holds=True") == 3
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
    assert out.count("exact in Q(zeta_3) at 4 orbit points") == 8
    assert "control:commutation False" in out and "proof:jacobi True" in out


def test_cli_prove_without_options_proves_the_documented_n2_system(capsys):
    """`exact-khk prove` alone refused (the built-in default has n = 3); it now proves the n = 2
    system of docs/evidence.md, with the three negative controls disproved."""
    from exact_khk.cli.main import main

    assert main(["prove"]) == 0
    out = capsys.readouterr().out
    assert "a=(1, 2), b=(0, 1), c=(3, 1)" in out and out.count("ok  ") == 6 and "FAIL" not in out
    assert out.count(":control") == 3 and out.count("holds=False") == 3


@pytest.mark.parametrize("option", [["--eps", "1/3"], ["--x0", "1,0,0,1"]])
def test_cli_prove_refuses_a_point_or_step_size(option, capsys):
    """x and eps are symbols in the proofs: a given --x0 or --eps was silently ignored."""
    from exact_khk.cli.main import main

    assert main(["prove", "--n", "2", "--seed", "1", *option]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and option[0] + ": prove works with rational functions" in err
