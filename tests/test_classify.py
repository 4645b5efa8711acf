"""classify: verdicts with their evidence; the recurrence fit's honesty on maps that are not Kahan
maps (Sage's doctest maps); the degrees of general homogeneous polynomial maps."""

from __future__ import annotations

import json

import pytest
import sympy

from exact_khk.cli.main import main
from exact_khk.diagnostics.classify import classify, lambda_upper_bound
from exact_khk.diagnostics.map_degrees import map_degrees
from exact_khk.diagnostics.recurrence import fit_recurrence
from exact_khk.errors import InputError

#: Sage's doctest of DynamicalSystem_projective.degree_sequence for [Z^2, X*Y, Y^2]
SAGE_DEGREES = (2, 3, 5, 8, 11, 17, 24, 31, 45, 56, 68, 91, 93, 184, 275)


def monomial_degrees(A, count):
    """d_k of the monomial map with exponent matrix A, independently: the exponents of the k-th
    iterate are A^k, and the common monomial factor removes sum_j min_i (A^k)_ij."""
    M = sympy.eye(len(A))
    A = sympy.Matrix(A)
    out = []
    for _ in range(count):
        out.append(int(sum(M.row(0))) - sum(min(M[i, j] for i in range(M.rows)) for j in range(M.cols)))
        M = M * A
    return out


def test_map_degrees_agree_with_sage_and_with_the_closed_form():
    closed = monomial_degrees([[0, 0, 2], [1, 1, 0], [0, 2, 0]], 16)
    assert tuple(closed[1:]) == SAGE_DEGREES
    assert map_degrees(["Z**2", "X*Y", "Y**2"], ["X", "Y", "Z"], steps=15) == tuple(closed)


def test_the_fit_is_not_forced_onto_a_sequence_without_a_short_recurrence():
    # lambda = sqrt(2) for this map; Berlekamp-Massey finds an order-14 recurrence on the first 28 terms
    # predicting the next 7 with lambda ~ 1.41457: a growth class needs as many confirmations as the order
    seq = monomial_degrees([[0, 0, 2], [1, 1, 0], [0, 2, 0]], 35)
    fit = fit_recurrence(seq)
    assert fit.order == 14 and fit.confirmed_on == 7
    assert fit.growth == "undetermined" and "need 14" in fit.reason
    # Sage's own 15 terms: nothing is claimed either
    assert fit_recurrence((1,) + SAGE_DEGREES).growth == "undetermined"


def test_linear_degree_growth_gives_lambda_one():
    # Sage's dynamical_degree(N=5) prints 6^(1/5) = 1.43 for this map; its degrees are k + 1
    degs = map_degrees(["X*Y", "Y*Z + Z**2", "Z**2"], ["X", "Y", "Z"], steps=12)
    assert degs == tuple(range(1, 14))
    fit = fit_recurrence(degs)
    assert fit.growth == "polynomial" and fit.polynomial_degree == 1
    assert fit.dynamical_degree.minimal_polynomial == "x - 1"


@pytest.mark.parametrize("components, variables, message", [
    (["X*Y + X", "Y**2"], ["X", "Y"], "is not homogeneous"),
    (["X*Y", "Y**3"], ["X", "Y"], "share one degree"),
    (["X/Y", "Y"], ["X", "Y"], "not a polynomial"),
    (["X"], ["X", "Y"], "1 component(s) for 2"),
    (["1", "1"], ["X", "Y"], "constant"),
    (["X**2", "Q"], ["X", "Y"], "unknown name"),
])
def test_map_degrees_refuses_what_is_not_a_map_of_projective_space(components, variables, message):
    with pytest.raises(InputError) as exc:
        map_degrees(components, variables, steps=3)
    assert message in str(exc.value)


def test_lambda_upper_bound_is_rounded_up():
    k, dk, b = lambda_upper_bound([1, 2, 4, 8])
    assert (k, dk, b) == (1, 2, "2.000000")
    k, dk, b = lambda_upper_bound([1, 3, 9, 19])
    assert (k, dk) == (3, 19)
    assert sympy.Rational(b) ** 3 >= 19 > (sympy.Rational(b) - sympy.Rational(1, 10 ** 6)) ** 3


def _kahan_degree_sympy(field, xs, eps, k):
    """deg Phi^k on a line, by SymPy from the formula x~ = x + 2 eps (I - eps f'(x))^-1 f(x): the
    composite restricted to x = a + t b (a, b fixed rationals, generic here) as rational functions of
    t over Q, put on a common denominator in lowest terms; its degree is d_k for a generic line."""
    t = sympy.Symbol("t")
    x = sympy.Matrix(xs)
    f = sympy.Matrix(field)
    J = f.jacobian(x)
    step = x + 2 * eps * (sympy.eye(len(xs)) - eps * J).inv() * f
    a = [sympy.Rational(3, 7), sympy.Rational(-5, 11), sympy.Rational(2, 13)][:len(xs)]
    b = [sympy.Rational(1, 3), sympy.Rational(4, 5), sympy.Rational(-7, 9)][:len(xs)]
    cur = [ai + bi * t for ai, bi in zip(a, b)]
    for _ in range(k):
        cur = [sympy.cancel(c.subs(dict(zip(xs, cur)), simultaneous=True)) for c in step]
    nums, dens = zip(*(sympy.fraction(c) for c in cur))
    den = sympy.lcm(list(dens))
    polys = [sympy.Poly(sympy.cancel(n * den / d), t) for n, d in zip(nums, dens)] + [sympy.Poly(den, t)]
    g = polys[0]
    for q in polys[1:]:
        g = sympy.gcd(g, q)
    return max(sympy.quo(q, g).degree() for q in polys)


def _field_of(name):
    """The catalogue entry's field and variables as SymPy expressions, read from its own text."""
    from exact_khk.systems.base import System

    d = System.load(name).to_json()
    xs = sympy.symbols(d["variables"])
    params = {sympy.Symbol(k): sympy.Rational(v) for k, v in d.get("parameters", {}).items()}
    return [sympy.sympify(d["field"][v]).subs(params) for v in d["variables"]], list(xs)


def test_euler_top_is_integrable_with_its_evidence():
    c = classify("euler-top", steps=12, discover=())
    assert c.verdict == "integrable"
    # an independent route: the degree of Phi^2 by SymPy from the formula
    assert c.degrees.degrees[2] == _kahan_degree_sympy(*_field_of("euler-top"), sympy.Rational(str(c.eps)), 2) == 9
    assert c.independent_integrals == 2
    kinds = {e.standing for e in c.evidence}
    assert {"proven", "probable", "conjecture", "exact at orbit points"} <= kinds


def test_kahan_lotka_volterra_is_non_integrable():
    c = classify("lotka-volterra", steps=10, discover=())
    assert c.verdict == "non-integrable"
    assert c.degrees.degrees[3] == _kahan_degree_sympy(*_field_of("lotka-volterra"), sympy.Rational(str(c.eps)), 3) == 8
    assert c.independent_integrals == 0
    # the proven bound and the fitted value agree here: lambda = 2
    assert c.lambda_upper[2] == "2.000000"


def test_undetermined_says_what_would_decide_it(capsys):
    # the CMOQ cubic's integrals are modified cubic energies: degree 2 finds none
    assert main(["classify", "cmoq-cubic", "--degree", "2", "--no-discover"]) == 4
    out = capsys.readouterr().out
    assert "verdict: UNDETERMINED" in out and "--degree 3" in out


def test_json_has_the_documented_keys(tmp_path, capsys):
    path = tmp_path / "c.json"
    assert main(["classify", "euler-top", "--steps", "10", "--no-discover", "--json", str(path)]) == 0
    d = json.loads(path.read_text())
    for key in ("verdict", "degrees", "growth", "dynamical_degree", "integrals", "measure", "poisson", "evidence"):
        assert key in d
    assert d["verdict"] == "integrable"
    assert d["dynamical_degree"]["fitted_standing"].startswith("conjecture")
    assert d["dynamical_degree"]["upper_bound"]["standing"].startswith("proven")


@pytest.mark.parametrize("argv, message", [
    (["classify", "euler-top", "--steps", "2"], "--steps"),
    (["classify", "euler-top", "--system", "lagrange-top"], "two systems"),
    (["classify", "no-such-system"], "no-such-system"),
    (["classify", "euler-top", "--degree", "0"], "--degree"),
])
def test_bad_input_is_one_line_and_exit_2(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def sympy_map_degrees(components, variables, count):
    """d_0..d_count of a map of P^N by SymPy composition, the common factor divided out (independent of
    map_degrees: no prime, no line)."""
    xs = sympy.symbols(variables)
    F = [sympy.sympify(c, locals=dict(zip(variables, xs))) for c in components]
    cur, out = list(xs), [1]
    for _ in range(count):
        cur = [sympy.expand(f.subs(dict(zip(xs, cur)), simultaneous=True)) for f in F]
        g = cur[0]
        for c in cur[1:]:
            g = sympy.gcd(g, c)
        cur = [sympy.cancel(c / g) for c in cur]
        out.append(max(sympy.Poly(c, *xs).total_degree() for c in cur))
    return tuple(out)


def test_degrees_map_command_matches_sympy_composition(capsys):
    comps = ["X*Y", "Y*Z + Z**2", "Z**2"]
    golden = sympy_map_degrees(comps, ["X", "Y", "Z"], 5)
    assert golden == (1, 2, 3, 4, 5, 6)
    assert main(["degrees", "--map", ", ".join(comps), "--variables", "X,Y,Z", "--steps", "12", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert tuple(data["degrees"][:6]) == golden
    assert data["fit"]["growth"] == "polynomial"
    # Sage's monomial map: the command prints the 15 doctest degrees and classifies nothing
    assert main(["degrees", "--map", "Z**2, X*Y, Y**2", "--variables", "X,Y,Z", "--steps", "15"]) == 0
    out = capsys.readouterr().out
    assert ", ".join(map(str, SAGE_DEGREES)) in out and "growth: not classified" in out


@pytest.mark.parametrize("extra, message", [
    (["--system", "euler-top"], "--system does not apply"),
    ([], "--variables"),
])
def test_degrees_map_bad_input_exits_2(extra, message, capsys):
    args = ["degrees", "--map", "X*Y, Y**2"] + (["--variables", "X,Y"] if extra else []) + extra
    assert main(args) == 2
    assert message in capsys.readouterr().err
