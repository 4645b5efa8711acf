"""System files and exact functions: parsing, safety, evaluation in every arithmetic."""

import json
import random
import re
import textwrap
from fractions import Fraction as F
from pathlib import Path

import pytest
import sympy

from exact_khk.arith import get_arith
from exact_khk.errors import InputError, PoleError, UndecidedError
from exact_khk.systems import catalogue
from exact_khk.systems.expressions import ExpressionSystem, load_system
from exact_khk.systems.functions import Polynomial, PolynomialTensor, RationalFunction

V3 = ["x1", "x2", "x3"]
EULER = ["x2*x3", "-2*x3*x1", "3*x1*x2"]
SO3 = [["0", "x3", "-x2"], ["-x3", "0", "x1"], ["x2", "-x1", "0"]]
DOCS = Path(__file__).resolve().parent.parent / "docs" / "system-files.md"


def system(field=EULER, **kw):
    return ExpressionSystem.from_expressions(V3, field, **kw)


def refused(match, **kw):
    with pytest.raises(InputError, match=match):
        system(**kw)


# --- coefficient extraction against SymPy --------------------------------------------


def random_component(rng, names):
    """A random quadratic polynomial, written as products and sums (not expanded)."""
    def lin():
        return " + ".join(f"({rng.randint(-9, 9)}/{rng.randint(1, 5)})*{v}" for v in rng.sample(names, 2)) \
            + f" - {rng.randint(0, 4)}"
    parts = [f"({lin()})*({lin()})", f"{rng.randint(-3, 3)}*{rng.choice(names)}**2",
             f"-({lin()})/{rng.randint(1, 7)}", f"{rng.choice(names)}*{rng.choice(names)}/3"]
    return " + ".join(rng.sample(parts, rng.randint(1, 4)))


@pytest.mark.parametrize("seed", range(25))
def test_quadratic_coefficients_match_sympy(seed):
    rng = random.Random(seed)
    names = [f"u{i}" for i in range(rng.randint(1, 5))]
    comps = [random_component(rng, names) for _ in names] if len(names) > 1 else ["u0**2 - 1/2"]
    fld = ExpressionSystem.from_expressions(names, comps).field("f")
    syms = sympy.symbols(names)
    for i, text in enumerate(comps):
        P = sympy.Poly(sympy.sympify(text, locals=dict(zip(names, syms))), *syms)
        quad, lin = dict(fld.quad[i]), dict(fld.linear[i])
        for j in range(len(names)):
            assert lin.get(j, 0) == P.coeff_monomial(syms[j])
            for k in range(j, len(names)):
                assert quad.get((j, k), 0) == P.coeff_monomial(syms[j] * syms[k])
        assert fld.const[i] == P.coeff_monomial(1)


@pytest.mark.parametrize("text", ["-x1**2", "x1**-2*x1**3", "2**-1*x1", "1/2/3*x2", "2-3-4", "--x1",
                                  "-(x1 - x2)**2", "(x1)**(+2) / (2)**(-3)", "+-+x3*x1"])
def test_precedence_is_pythons(text):
    f = system([text, "0", "0"]).field("f")
    P = sympy.Poly(sympy.sympify(text), *sympy.symbols(V3))
    assert dict(f.quad[0]).get((0, 0), 0) == P.coeff_monomial(sympy.Symbol("x1") ** 2)
    assert f.const[0] == P.coeff_monomial(1)


def test_decimals_and_parameters_are_exact():
    s = system(["0.1*x1*x2 + .5 + 2.", "a*x1", "b*x3**2"], parameters={"a": "1.25", "b": F(-2, 3)})
    f = s.field("f")
    assert f.quad[0] == (((0, 1), F(1, 10)),) and f.const[0] == F(5, 2)
    assert f.linear[1] == ((0, F(5, 4)),) and f.quad[2] == (((2, 2), F(-2, 3)),)
    assert s.parameters == {"a": F(5, 4), "b": F(-2, 3)}


def test_scientific_literals_are_the_decimals_they_spell():
    s = system(["1e-5*x1*x2 + 2.5E3", "3.e-1*x1 + .5e1", "x3**2*1e0 + 1E+2"])
    f = s.field("f")
    assert f.quad[0] == (((0, 1), F(1, 100000)),) and f.const[0] == 2500
    assert f.linear[1] == ((0, F(3, 10)),) and f.const[1] == 5
    assert f.quad[2] == (((2, 2), F(1)),) and f.const[2] == 100
    assert system(["1e10000*x1", "0", "0"]).field("f").linear[0] == ((0, F(10) ** 10000),)


# --- refused input --------------------------------------------------------------------


@pytest.mark.parametrize("text, match", [
    ("x2**2*x3", r"field x1: term x2\*\*2\*x3 has degree 3; a Kahan map needs a quadratic field"),
    ("x2/x3", r"field x1: term x2/x3 is not a polynomial"),
    ("x2**-1", r"term x2\*\*-1 is not a polynomial"),
    ("eps*x2", r"field x1: eps is not allowed here"),
    ("y*x2", r"unknown name 'y' at position 0 \(allowed: variables x1, x2, x3\)"),
    ("__import__('os').system('true')", r"unknown name '__import__'"),
    ("(lambda: 1)()", r"unknown name 'lambda'"),
    ("x1.__class__", r"character '\.' at position 2 is not allowed"),
    ("x1[0]", r"character '\[' at position 2"),
    ("'x1'", r"character \"'\" at position 0"),
    ("x1!", r"character '!' at position 2 is not allowed; expressions use names, numbers, \+ - \* / \*\* \(or \^\)"),
    ("x1^2^3", r"chained \*\* is not allowed"),
    ("x1**10**9", r"chained \*\* is not allowed"),
    ("9**9**9", r"chained \*\* is not allowed"),
    ("x1**999", r"exponent 999 at position 4 is too large"),
    ("1e10001*x2", r"the exponent of 1e10001 at position 0 is beyond the limit of 10000"),
    ("2e-99999999999999999999*x2", r"the exponent of 2e-9+ at position 0 is beyond the limit"),
    ("x2**1e2", r"exponent '1e2' at position 4 is not an integer literal"),
    ("2e*x2", r"unknown name 'e' at position 1"),
    ("x1**99999999999999999999", r"is too large"),
    ("x1**(1/2)", r"must be an integer literal"),
    ("x1**x2", r"exponent 'x2' at position 4 is not an integer literal"),
    ("((x1 + x2 + x3 + 1)**64)**64", r"the expression is too large"),
    ("(((((9**64)**64)**64)**64)**64)", r"numbers in this expression are too large"),
    ("x" * 10 ** 6, r"has 1000000 characters \(limit 100000\)"),
    ("(" * 500 + "x1" + ")" * 500, r"nested deeper than 100"),
    ("2 x1", r"unexpected 'x1' at position 2"),
    ("x1 +", r"ends too early"),
    ("", r"empty expression"),
    ("(x1", r"missing '\)'"),
    ("x1/0", r"division by zero"),
    ("x1/(x2 - x2)", r"division by zero"),
])
def test_hostile_and_wrong_fields_are_refused(text, match):
    refused(match, field=[text, "0", "0"])


def test_caret_reads_as_power_like_sympy():
    """'^' is '**' on input (SymPy's parse_expr reads it so): the same field and integral."""
    a = system(["x2^2 - x3", "-x1*x2", "x1 - x3^2"])
    b = system(["x2**2 - x3", "-x1*x2", "x1 - x3**2"])
    fa, fb = a.field("f"), b.field("f")
    assert (fa.quad, fa.linear, fa.const) == (fb.quad, fb.linear, fb.const) and fa.quad[2] == (((2, 2), F(-1)),)
    assert str(sympy.sympify("x2^2 - x3", convert_xor=True)) == str(sympy.sympify("x2**2 - x3"))


def test_huge_integers_are_exact():
    big = 10 ** 5000 + 7                     # more digits than Python's int <-> str limit
    digits = "1" + "0" * 4996 + "0007"
    s = system([f"{digits}*x1*x2 - {digits}", "0", "0"], parameters={"a": digits + "/3"},
               integrals={"I": f"x1/{digits} + a*eps"})
    assert s.field("f").quad[0] == (((0, 1), F(big)),) and s.field("f").const[0] == -big
    assert s.parameters["a"] == F(big, 3)
    fr = get_arith("fraction")
    assert s.integrals()["I"](fr, [F(big), F(0), F(0)], F(3)) == 1 + big
    with pytest.raises(InputError, match=r"term <a 5001-digit number>\*x1\*x2\*\*2 has degree 3"):
        system([f"{digits}*x1*x2**2", "0", "0"])
    again = ExpressionSystem.from_json(json.loads(json.dumps(
        system(parameters={"b": F(big, 7)}, x0=[big, 1, 2]).to_json())))
    assert again.parameters["b"] == F(big, 7) and again.default_x0[0] == big


@pytest.mark.parametrize("kw, match", [
    (dict(field=EULER[:2]), r"field: expected 3 components \(one per variable\), got 2"),
    (dict(field={"x1": "x2", "x2": "x1", "y": "1"}), r"missing component\(s\) x3; unknown component\(s\) y"),
    (dict(parameters={"x1": 1}), r"parameters: 'x1' is the name of a variable"),
    (dict(parameters={"eps": 1}), r"parameters: 'eps' is reserved"),
    (dict(parameters={"a": "sqrt(2)"}), r"parameters a: unknown name 'sqrt'.*rational number is expected"),
    (dict(parameters={"a": "x1"}), r"parameters a: unknown name 'x1'"),
    (dict(parameters={"a": 0.5}), r"parameters a: 0.5 is a binary float"),
    (dict(parameters={"a": True}), r"parameters a: expected a rational number"),
    (dict(x0=[1, 2]), r"defaults x0: expected a list of 3 numbers"),
    (dict(eps="0"), r"defaults eps: the step size must be nonzero"),
    (dict(claims=["poisson"]), r"claims: 'poisson' needs a \[poisson\] section"),
    (dict(claims=["magic"]), r"claims: unknown claim 'magic'"),
    (dict(fields={"f": EULER}), r"fields: 'f' is not a valid name"),
    (dict(integrals={"I": "x1 + sin(x2)"}), r"integrals I: unknown name 'sin'"),
    (dict(integrals={"I": 1.5}), r"integrals I: expected a string"),
    (dict(poisson=[["0", "x3"], ["-x3", "0"]]), r"poisson matrix: expected a 3x3 matrix"),
    (dict(poisson=[["0", "x3", "-x2"], ["-x3", "0", "x1"], ["x2", "x1", "0"]]),
     r"entry \[2\]\[1\] = x1 is not minus entry \[1\]\[2\] = x1"),
    (dict(poisson=[["1", "x3", "-x2"], ["-x3", "0", "x1"], ["x2", "-x1", "0"]]),
     r"diagonal entry \[0\]\[0\] = 1 must be 0"),
])
def test_bad_system_arguments(kw, match):
    refused(match, **kw)


def test_variables_are_checked():
    for variables, match in ((["x", "x"], "'x' is used twice"), (["x", "eps"], "reserved for the step size"),
                             (["x", "2y"], "not a valid name"), ([], "non-empty list"),
                             (["x", 5], r"variables\[1\]: expected a name \(a string\), got 5")):
        with pytest.raises(InputError, match=match):
            ExpressionSystem.from_expressions(variables, ["0"] * len(variables))


# --- evaluation in every arithmetic --------------------------------------------------

INTEGRAL = "(1 - eps**2*(-2)*3*x1**2 + x3/7)/(1 - eps**2*3*x2**2 - eps*x1*x3)"
ARITHS = ["fraction", "gmpy2", "flint", "float", "mp:100", "ball:128", "gf:1000003", "cyclo:7"]


def exact_value(text, x, eps, diff=None):
    syms = sympy.symbols(V3 + ["eps"])
    e = sympy.sympify(text, locals=dict(zip(V3 + ["eps"], syms)))
    if diff is not None:
        e = sympy.diff(e, syms[diff])
    q = e.subs(dict(zip(syms, [sympy.Rational(v.numerator, v.denominator) for v in list(x) + [eps]])))
    return F(int(q.p), int(q.q))


def agrees(ar, value, exact):
    """``value`` (an element of ar) is the exact rational ``exact``, up to ar's rounding."""
    if ar.name.startswith("ball"):
        mid, rad = (F(int(m) * 2 ** int(e)) if e >= 0 else F(int(m), 2 ** -int(e))
                    for m, e in (value.mid().man_exp(), value.rad().man_exp()))
        return abs(mid - exact) <= rad
    if not ar.exact:
        return abs(ar.to_fraction(value) - exact) <= abs(exact) * 2 ** (8 - ar.prec) + F(1, 10 ** 30)
    return value == ar.convert(exact)


@pytest.mark.parametrize("name", ARITHS)
def test_rational_function_and_gradient_in_every_arithmetic(name):
    ar = get_arith(name)
    I = system(integrals={"I": INTEGRAL}).integrals()["I"]
    rng = random.Random(name)
    for _ in range(5):
        x = [F(rng.randint(-9, 9), rng.randint(1, 4)) for _ in range(3)]
        eps = F(rng.randint(1, 5), 13)
        xa, ea = [ar.convert(t) for t in x], ar.convert(eps)
        with ar.local():
            assert agrees(ar, I(ar, xa, ea), exact_value(INTEGRAL, x, eps))
            for i, g in enumerate(I.gradient(ar, xa, ea)):
                assert agrees(ar, g, exact_value(INTEGRAL, x, eps, diff=i))


def test_polynomial_basics():
    x0, eps = Polynomial.variable(2, 0), Polynomial.variable(2, 2)
    p = x0 * x0 * eps + Polynomial.constant(2, F(1, 2))
    assert p.degree_in_x() == 2 and p.depends_on_eps and not x0.depends_on_eps
    assert p.derivative(0) == x0 * eps.scale(2) and p.derivative(2) == x0 * x0
    assert Polynomial(2).degree_in_x() == -1 and (p - p).is_zero()
    with pytest.raises(InputError):
        Polynomial(2, {(1, 0): 1})


def test_at_eps_zero():
    s = system(integrals={"A": "(x1 + eps)/(1 - eps*x2)", "B": "x1/eps", "C": "eps*x1/(eps*x2 + eps**2)",
                          "D": "(eps + x1*eps**2)/eps**2"})
    fr, x = get_arith("fraction"), [F(2), F(3), F(5)]
    I = s.integrals()
    assert I["A"].at_eps_zero()(fr, x, F(7)) == 2 and not I["A"].at_eps_zero().depends_on_eps
    assert I["B"].at_eps_zero() is None and I["D"].at_eps_zero() is None
    assert I["C"].at_eps_zero()(fr, x, F(0)) == F(2, 3)


def test_poles():
    I = system(integrals={"I": "x1/(1 - 3*x2)"}).integrals()["I"]
    for name in ("fraction", "flint", "float", "mp:80", "gf:101"):
        ar = get_arith(name)
        with pytest.raises(PoleError, match=r"I has a pole at x = \(1.*\), eps = .*: its denominator vanishes"):
            I(ar, [ar.convert(F(v)) for v in (1, F(1, 3), 0)], ar.convert(F(1, 10)))
        with pytest.raises(PoleError):
            I.gradient(ar, [ar.convert(F(v)) for v in (1, F(1, 3), 0)], ar.convert(F(1, 10)))
    ball = get_arith("ball:64")
    with ball.local(), pytest.raises(UndecidedError, match="cannot decide whether the denominator of I"):
        I(ball, [ball.convert(F(1)), ball.convert(F(1, 3)), ball.zero], ball.convert(F(1, 10)))
    J = system(integrals={"J": "x1**64"}).integrals()["J"]
    fl = get_arith("float")
    with pytest.raises(PoleError, match="not finite"):
        J(fl, [1e10, 0.0, 0.0], 0.1)


# --- Poisson tensors -------------------------------------------------------------------


def sympy_jacobiator(M, point):
    syms = sympy.symbols(V3)
    P = sympy.Matrix(3, 3, lambda i, j: sympy.sympify(M[i][j], locals=dict(zip(V3, syms))))
    s = sum(P[i, m] * sympy.diff(P[j, k], syms[m]) + P[j, m] * sympy.diff(P[k, i], syms[m])
            + P[k, m] * sympy.diff(P[i, j], syms[m]) for i, j, k in [(0, 1, 2)] for m in range(3))
    q = s.subs(dict(zip(syms, point)))
    return F(int(q.p), int(q.q))


@pytest.mark.parametrize("name", ["fraction", "flint", "float", "mp:100", "gf:1000003"])
def test_jacobiator(name):
    ar = get_arith(name)
    bad = [["0", "x1", "-x3"], ["-x1", "0", "x2"], ["x3", "-x2", "0"]]   # curl-free fails: v.curl v != 0
    rng = random.Random(3)
    for _ in range(4):
        x = [F(rng.randint(-5, 5), rng.randint(1, 3)) for _ in range(3)]
        xa, ea = [ar.convert(t) for t in x], ar.convert(F(1, 10))
        Pi = system(poisson=SO3).poisson()
        assert all(ar.is_zero(t) for t in Pi.jacobiator(ar, xa, ea))
        assert ar.format(Pi.matrix(ar, xa, ea)[1][0]) == ar.format(-ar.convert(x[2]))
        (j,) = system(poisson=bad).poisson().jacobiator(ar, xa, ea)
        assert agrees(ar, j, sympy_jacobiator(bad, x))
    assert sympy_jacobiator(bad, [1, 1, 1]) != 0


def test_tensor_skew_check_is_symbolic():
    s = system(poisson=[["0", "x3/(1 - eps*x1)", "0"], ["(-x3 + eps*x1*x3)/(1 - eps*x1)**2", "0", "0"],
                        ["0", "0", "0"]])
    assert s.poisson().depends_on_eps
    one, zero = RationalFunction(Polynomial.constant(2, 1), name="one", text="1"), RationalFunction(Polynomial(2))
    with pytest.raises(InputError, match=r"Pi: entry \[1\]\[0\] = 1 is not minus entry \[0\]\[1\] = 1"):
        PolynomialTensor([[zero, one], [one, zero]])
    assert PolynomialTensor([[zero, one], [-one, zero]]).matrix(get_arith("flint"), [1, 2], 0)[1][0] == -1


# --- Hamiltonian form ----------------------------------------------------------------

HAM = {"K": [["0", "1"], ["-1", "0"]], "H": "x1**3/3 + x1*x2**2 - x2"}


def test_hamiltonian_gives_the_field():
    s = ExpressionSystem.from_expressions(["x1", "x2"], hamiltonian=HAM)
    K, H = s.hamiltonian_form()
    assert K == ((0, 1), (-1, 0)) and H.is_polynomial and H.num.degree_in_x() == 3
    f = s.field("f")     # f = K grad H = (2 x1 x2 - 1, -x1^2 - x2^2)
    assert f.quad == ((((0, 1), 2),), (((0, 0), -1), ((1, 1), -1))) and f.const == (-1, 0)
    assert "cmoq" in s.claims
    same = ExpressionSystem.from_expressions(["x1", "x2"], ["2*x1*x2 - 1", "-(x1**2 + x2**2)"], hamiltonian=HAM)
    assert same.field("f").quad == f.quad


@pytest.mark.parametrize("ham, field, match", [
    (HAM, ["2*x1*x2 - 1", "x2**2 - x1**2"], r"hamiltonian: field x2 = x2\*\*2 - x1\*\*2 differs from \(K grad H\)_x2"),
    ({"K": [["0", "1"], ["1", "0"]], "H": "x1"}, None, r"K\[1\]\[0\] = 1 is not minus K\[0\]\[1\] = 1"),
    ({"K": [["0", "x1"], ["-x1", "0"]], "H": "x1"}, None, r"K\[0\]\[1\]: x1 is a variable"),
    ({"K": [["0", "1"], ["-1", "0"]], "H": "x1**2*x2**2"}, None, r"term x1\*\*2\*x2\*\*2 has degree 4"),
    ({"K": [["0", "1"], ["-1", "0"]], "H": "eps*x1"}, None, r"hamiltonian H: eps is not allowed"),
    ({"K": [["0", "1"], ["-1", "0"]]}, None, r"exactly the keys 'K' and 'H'"),
])
def test_hamiltonian_checks(ham, field, match):
    with pytest.raises(InputError, match=match):
        ExpressionSystem.from_expressions(["x1", "x2"], field, hamiltonian=ham)


# --- the system object, JSON and TOML ------------------------------------------------

EULER_TOML = """
name = "euler"
title = "Euler top"
variables = ["x1", "x2", "x3"]
[parameters]
a1 = "1"
a2 = -2
a3 = 0.3
[field]
x1 = "a1*x2*x3"
x2 = "a2*x3*x1"
x3 = "a3*x1*x2"
[fields.g]
x1 = "2*a1*x2*x3"
x2 = "2*a2*x3*x1"
x3 = "2*a3*x1*x2"
[integrals]
I1 = "(1 - eps**2*a2*a3*x1**2)/(1 - eps**2*a1*a3*x2**2)"
[poisson]
matrix = [["0", "x3", "-x2"], ["-x3", "0", "x1"], ["x2", "-x1", "0"]]
[controls]
naive = "x1**2 + x2**2 + x3**2"
[defaults]
x0 = ["1", "2", 3]
eps = "1/10"
"""


def test_toml_system_and_json_round_trip(tmp_path):
    path = tmp_path / "euler.toml"
    path.write_text(EULER_TOML)
    s = load_system(path)
    assert (s.name, s.title, s.dim, s.kind, s.variables) == ("euler", "Euler top", 3, "expressions", tuple(V3))
    assert s.parameters["a3"] == F(3, 10) and s.default_x0 == (1, 2, 3) and s.default_eps == F(1, 10)
    assert s.field_names() == ("f", "g") and s.field("g").quad[2] == (((0, 1), F(3, 5)),)
    assert s.claims == ("reversibility", "integrals", "poisson", "commutation", "jacobian")
    assert set(s.integrals()) == {"I1"} and set(s.controls()) == {"naive"} and s.hamiltonian_form() is None
    assert "2 integrals" not in s.describe() and "1 integral" in s.describe()
    with pytest.raises(InputError, match=r"unknown field 'h'; known: f, g"):
        s.field("h")
    d = json.loads(json.dumps(s.to_json()))
    assert d["integrals"]["I1"] == "(1 - eps**2*a2*a3*x1**2)/(1 - eps**2*a1*a3*x2**2)"
    t = ExpressionSystem.from_json(d)
    assert t.to_json() == s.to_json() and t.claims == s.claims and t.default_x0 == s.default_x0
    for g in s.field_names():
        a, b = s.field(g), t.field(g)
        assert (a.quad, a.linear, a.const) == (b.quad, b.linear, b.const)
    assert t.integrals()["I1"].num == s.integrals()["I1"].num
    assert t.poisson().entries[0][1].num == s.poisson().entries[0][1].num


def test_default_point_is_regular():
    s = system(integrals={"I": "1/(x1 - 1)/(x2 + 1)"})
    x = s.default_x0
    assert len(x) == 3 and any(x) and x[0] != 1 and x[1] != -1 and s.default_eps == F(1, 10)
    assert system().default_x0 == system().default_x0


@pytest.mark.parametrize("edit, match", [
    (lambda t: t.replace('title', 'bogus = 1\ntitle'), r"unknown key\(s\) 'bogus'; known keys"),
    (lambda t: t.replace("[field]", "[field"), r"not valid TOML: .*\(at line \d+, column \d+\)"),
    (lambda t: t.replace('name = "euler"', ""), r"missing required key 'name'"),
    (lambda t: t.replace('name = "euler"', "name = 3"), r"name: expected a string"),
    (lambda t: t.replace('variables = ["x1", "x2", "x3"]', 'variables = "x1"'), r"variables: expected"),
    (lambda t: t.replace('variables = ["x1", "x2", "x3"]', 'variables = ["x1", "x1", "x3"]'),
     "variables: 'x1' is used twice"),
    (lambda t: t.replace('variables = ["x1", "x2", "x3"]', 'variables = ["x1", "a1", "x3"]'),
     r"parameters: 'a1' is the name of a variable"),
    (lambda t: t.replace('x3 = "a3*x1*x2"\n[fields', '[fields'), r"field: missing component\(s\) x3"),
    (lambda t: t.replace('a1 = "1"', 'a1 = "pi"'), r"parameters a1: unknown name 'pi'"),
    (lambda t: t.replace('a1 = "1"', "a1 = nan"), r"parameters a1: NaN is not a rational number"),
    (lambda t: t.replace('x0 = ["1", "2", 3]', 'x0 = ["1", "2"]'), r"defaults x0: expected a list of 3"),
    (lambda t: t.replace('eps = "1/10"', 'step = "1/10"'), r"defaults: unknown key\(s\) 'step'"),
    (lambda t: t.replace('I1 = "', 'I1 = "x1**99 + '), r"integrals I1: exponent 99"),
    (lambda t: t.replace("[poisson]\nmatrix", "[poisson]\nmatrx"), r"poisson: expected exactly one key"),
    (lambda t: t.replace('title = "Euler top"', 'title = "Euler top"\nclaims = "integrals"'),
     r"claims: expected a list of names"),
    (lambda t: t + "claims = ['integrals']\n", r"defaults: unknown key\(s\) 'claims'"),
])
def test_toml_errors_name_the_problem(edit, match):
    with pytest.raises(InputError, match="t.toml: " + match):
        ExpressionSystem.from_toml(edit(EULER_TOML), origin="t.toml")


def test_claims_in_toml():
    top = EULER_TOML.replace('title = "Euler top"', 'title = "Euler top"\nclaims = ["integrals", "poisson"]')
    assert ExpressionSystem.from_toml(top).claims == ("integrals", "poisson")


def test_unreadable_files(tmp_path):
    with pytest.raises(InputError, match="no such system file"):
        load_system(tmp_path / "missing.toml")
    with pytest.raises(InputError, match="is a folder, not a system file"):
        load_system(tmp_path)
    (tmp_path / "bin.toml").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(InputError, match="not a UTF-8 text file"):
        load_system(tmp_path / "bin.toml")


# --- the catalogue and the documentation ---------------------------------------------


def test_catalogue(tmp_path):
    names = catalogue.names()
    assert names == sorted(names)
    for name, title, dim, known in catalogue.summary():
        s = catalogue.load(name)
        assert (s.name, s.title, s.dim, s.known()) == (name, title, dim, known)
        assert catalogue.resolve(name) is s
        assert ExpressionSystem.from_json(s.to_json()).to_json() == s.to_json()
    with pytest.raises(InputError, match="unknown catalogue system 'nope'; available: "):
        catalogue.load("nope")
    with pytest.raises(InputError, match="neither a catalogue system"):
        catalogue.resolve("nope")
    (tmp_path / "e.toml").write_text(EULER_TOML)
    assert catalogue.resolve(tmp_path / "e.toml").name == "euler"
    assert catalogue.resolve(str(tmp_path / "e.toml")).name == "euler"


def test_catalogue_loading(tmp_path, monkeypatch):
    (tmp_path / "euler.toml").write_text(EULER_TOML)
    (tmp_path / "other.toml").write_text(EULER_TOML)           # its name key says "euler"
    monkeypatch.setattr(catalogue, "_files", lambda: {p.stem: p for p in tmp_path.glob("*.toml")})
    monkeypatch.setattr(catalogue.families, "listed", lambda: [])   # files only
    assert catalogue.names() == ["euler", "other"]
    assert catalogue.load("euler") is catalogue.resolve("euler")
    with pytest.raises(InputError, match="catalogue other.toml: its name key 'euler' differs from the file name"):
        catalogue.summary()
    (tmp_path / "other.toml").unlink()
    assert catalogue.summary() == [("euler", "Euler top", 3, "1 integral, Poisson tensor, commuting field g, "
                                                            "1 control")]


def test_documentation_examples_run(tmp_path):
    text = DOCS.read_text()
    blocks = re.findall(r"```(toml|python)\n(.*?)```", text, re.S)
    tomls = [b for kind, b in blocks if kind == "toml"]
    assert tomls and all(ExpressionSystem.from_toml(b).dim > 0 for b in tomls if "name =" in b)
    for kind, block in blocks:
        if kind == "python":
            exec(compile(textwrap.dedent(block), str(DOCS), "exec"), {"__name__": "docs"})


def test_polynomial_over_z_at_flint_points_is_the_rational_sum():
    """At python-flint rationals a polynomial is summed over Z with one denominator
    (Polynomial._evaluate_over_z): the same rational as Fraction arithmetic term by term,
    checked against SymPy's exact evaluation too; mixed denominators, ε, negative and
    zero coordinates."""
    import flint

    from exact_khk.systems.functions import Polynomial

    rng = random.Random(7)
    fl, fr = get_arith("flint"), get_arith("fraction")
    syms = sympy.symbols("x0 x1 x2 eps")
    for trial in range(40):
        terms = {tuple(rng.randint(0, 4) for _ in range(4)): F(rng.randint(-50, 50), rng.randint(1, 30))
                 for _ in range(rng.randint(2, 12))}
        p = Polynomial(3, terms)
        pt = [F(rng.randint(-10 ** 30, 10 ** 30), rng.randint(1, 10 ** 20)) for _ in range(3)]
        pt[trial % 3] = F(0) if trial % 5 == 0 else pt[trial % 3]
        eps = F(rng.randint(-9, 9) or 1, rng.randint(1, 99))
        got = p.evaluate(fl, [flint.fmpq(q.numerator, q.denominator) for q in pt],
                         flint.fmpq(eps.numerator, eps.denominator))
        assert type(got) is flint.fmpq
        want = p.evaluate(fr, pt, eps)
        expr = sum(sympy.Rational(c.numerator, c.denominator) * sympy.Mul(*(s ** k for s, k in zip(syms, e)))
                   for e, c in p.terms.items())
        gold = expr.subs(dict(zip(syms, [sympy.Rational(q.numerator, q.denominator) for q in pt + [eps]])))
        assert (int(got.p), int(got.q)) == (want.numerator, want.denominator) == (gold.p, gold.q)
