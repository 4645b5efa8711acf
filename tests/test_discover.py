"""find-measure and find-poisson against an independent route: SymPy builds the Kahan map
straight from x~ = x + 2 eps (I - eps f'(x))^-1 f(x), its Jacobian by differentiation, and
substitutes the discovered density / tensor (exactly, symbolically or at rational points)."""

from __future__ import annotations

import json
import random
from fractions import Fraction

import pytest
import sympy as sp

from exact_khk.cli.main import main
from exact_khk.diagnostics.measures import find_measure
from exact_khk.diagnostics.poisson import find_poisson
from exact_khk.errors import InputError
from exact_khk.systems.expressions import ExpressionSystem

LV = (["x", "y"], ["x - x*y", "x*y - y"])
# the catalogue's Euler top (a1, a2, a3) = (1, -2, 3) at its default eps = 1/5
EULER = (["x1", "x2", "x3"], ["x2*x3", "-2*x3*x1", "3*x1*x2"])
CUBIC = (["q", "p"], ["p", "q - q**2"])  # K grad H, H = p^2/2 + q^3/3 - q^2/2, K = [[0, 1], [-1, 0]]


def kahan_sympy(names, field, eps):
    """(symbols, x~ as a Matrix of rational functions, dPhi) from the formulas, SymPy only."""
    xs = sp.symbols(names)
    f = sp.Matrix([sp.sympify(c, locals=dict(zip(names, xs))) for c in field])
    J = f.jacobian(xs)
    e = sp.Rational(eps)
    xt = sp.Matrix(xs) + 2 * e * (sp.eye(len(xs)) - e * J).LUsolve(f)
    xt = xt.applyfunc(sp.cancel)
    return xs, xt, xt.jacobian(xs)


def read(text, xs):
    return sp.sympify(text.replace("^", "**"), locals={str(s): s for s in xs})


def points(n, count, seed=1):
    rng = random.Random(seed)
    return [[sp.Rational(rng.randint(-9, 9), rng.randint(1, 5)) for _ in range(n)] for _ in range(count)]


def density_preserved(xs, xt, det, m):
    """m(x~) det dPhi(x) - m(x) == 0 as a rational function (SymPy; dimension 2)."""
    return sp.cancel(m.subs(dict(zip(xs, xt)), simultaneous=True) * sp.cancel(det.det()) - m) == 0


def test_lotka_volterra_measure_and_poisson():
    sysobj = ExpressionSystem.from_expressions(LV[0], field=LV[1])
    res = find_measure(sysobj, degree=2, eps="1/10")
    xs, xt, D = kahan_sympy(*LV, "1/10")
    x, y = xs
    assert len(res.densities) == 1
    d = res.densities[0]
    m = read(d.text, xs)
    assert sp.cancel(m * x * y).is_constant()          # the density 1/(xy) of Sanz-Serna
    assert density_preserved(xs, xt, D, m)
    assert d.verified and [c.holds for c in d.checks] == [True, False, True]   # control fails
    assert not density_preserved(xs, xt, D, m * (1 + x))                    # the control, independently
    # the Darboux polynomial xy is reported with its factors x, y and their cofactors
    assert any(dp.polynomial == "x*y" and {a for a, _ in dp.factors} == {"x", "y"} for dp in res.darboux)
    assert res.toml().splitlines()[-1] == 'density = "1/(x*y)"'

    pres = find_poisson(sysobj, degree=2, eps="1/10")
    assert pres.kernel_dim == 1 and len(pres.tensors) == 1
    pi12 = read(pres.tensors[0].entries[0][1], xs)
    assert sp.cancel(pi12 / (x * y)).is_constant()
    P = sp.Matrix([[0, pi12], [-pi12, 0]])
    lhs = (D * P * D.T).applyfunc(sp.cancel)
    assert sp.cancel(lhs[0, 1] - pi12.subs(dict(zip(xs, xt)), simultaneous=True)) == 0
    assert [c.holds for c in pres.tensors[0].checks] == [True, True, False, True]


def test_euler_top_measure():
    res = find_measure("euler-top", degree=2)
    xs, xt, D = kahan_sympy(*EULER, "1/5")
    x1, x2, x3 = xs
    eps = sp.Rational(1, 5)
    expected = 1 / ((1 - eps ** 2 * (-6) * x1 ** 2) * (1 - eps ** 2 * 3 * x2 ** 2))   # a2 a3 = -6, a3 a1 = 3
    good = [d for d in res.densities if d.verified]
    assert good
    m = read(good[0].text, xs)
    ratio = sp.cancel(m / expected)
    sub = dict(zip(xs, xt))
    for pt in points(3, 3):  # found = expected times an integral (here a constant), checked at points
        at = dict(zip(xs, pt))
        at_t = {s: v.subs(at) for s, v in sub.items()}
        assert m.subs(at_t) * D.subs(at).det() == m.subs(at)
        assert ratio.subs(at_t) == ratio.subs(at)
    assert all(c.holds is False for d in res.densities for c in d.checks if c.name.startswith("control"))
    # Darboux polynomials of one cofactor: their ratios, the Hirota-Kimura integrals, conserved by the SymPy map
    assert len(res.integrals) == 2 and all(ok for _, ok in res.integrals)
    for text, _ in res.integrals:
        I = read(text, xs)
        for pt in points(3, 2, seed=9):
            at = dict(zip(xs, pt))
            assert I.subs({s: v.subs(at) for s, v in sub.items()}) == I.subs(at)


def test_euler_top_poisson_with_casimir():
    res = find_poisson("euler-top", degree=3)
    xs, xt, D = kahan_sympy(*EULER, "1/5")
    sub = dict(zip(xs, xt))
    assert res.tensors
    t = res.tensors[0]
    P = sp.Matrix(3, 3, lambda i, j: read(t.entries[i][j], xs))
    # Jacobi identity (SymPy, symbolically)
    for i, j, k in [(0, 1, 2)]:
        jac = sum(P[a, s] * sp.diff(P[b, c], xs[s]) for a, b, c in ((i, j, k), (j, k, i), (k, i, j)) for s in range(3))
        assert sp.expand(jac) == 0
    for pt in points(3, 2):
        at = dict(zip(xs, pt))
        Dp = D.subs(at)
        assert (Dp * P.subs(at) * Dp.T - P.subs({s: v.subs(at) for s, v in sub.items()})).applyfunc(sp.simplify) \
            == sp.zeros(3, 3)
    # a Casimir that is a Hirota-Kimura integral: pi grad C = 0 and C conserved by the SymPy map
    assert t.casimirs
    C = read(t.casimirs[0].text, xs)
    grad = sp.Matrix([sp.diff(C, s) for s in xs])
    assert (P * grad).applyfunc(sp.cancel) == sp.zeros(3, 1)
    hk = [(1 + sp.Rational(6, 25) * xs[0] ** 2), (1 - sp.Rational(3, 25) * xs[1] ** 2),
          (1 + sp.Rational(2, 25) * xs[2] ** 2)]
    num, den = sp.fraction(sp.cancel(C))
    assert any(sp.cancel(num / a).is_constant() for a in hk) and any(sp.cancel(den / a).is_constant() for a in hk)
    for pt in points(3, 2, seed=5):
        at = dict(zip(xs, pt))
        assert C.subs(at) == C.subs({s: v.subs(at) for s, v in sub.items()})
    assert t.verified and any(c.name.startswith("control") and c.holds is False for c in t.checks)


def test_cmoq_cubic_measure():
    res = find_measure("docs/examples/cubic.toml", degree=2)
    xs, xt, det = kahan_sympy(*CUBIC, "1/10")
    f = sp.Matrix([read(c, xs) for c in CUBIC[1]])
    A = (sp.eye(2) - sp.Rational(1, 10) * f.jacobian(xs)).det()   # CMOQ: density 1/det(I - eps f'(x))
    m = read(res.densities[0].text, xs)
    assert sp.cancel(m * A).is_constant()
    assert density_preserved(xs, xt, det, m)


def test_random_quadratic_field_nothing_found():
    rng = random.Random(3)
    terms = ["1", "x", "y", "x**2", "x*y", "y**2"]
    field = [" + ".join(f"({rng.randint(-5, 5) or 1})*{t}" for t in terms) for _ in range(2)]
    sysobj = ExpressionSystem.from_expressions(["x", "y"], field=field)
    res = find_measure(sysobj, degree=2, eps="1/7")
    assert res.densities == () and "nothing found" in res.summary()
    pres = find_poisson(sysobj, degree=2, eps="1/7")
    assert pres.tensors == () and "nothing found" in pres.summary()


def test_cli_toml_json_and_errors(tmp_path, capsys):
    assert main(["find-poisson", "lotka-volterra", "--toml"]) == 0
    block = capsys.readouterr().out
    assert block.startswith("[poisson]") and "u*v" in block
    src = open("exact_khk/systems/catalogue/lotka-volterra.toml").read()
    head = src.split("[poisson]")[0]
    tail = src.split("[controls]")[1]
    path = tmp_path / "lv.toml"
    path.write_text(head + block + "\n[controls]" + tail)
    assert main(["certify", "--system", str(path), "--steps", "3", "--quiet"]) == 0   # pasted back: VALID
    out = tmp_path / "m.json"
    assert main(["find-measure", "--system", "lotka-volterra", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["densities"][0]["density"] == "1/(u*v)" and data["densities"][0]["verified"]
    capsys.readouterr()
    assert main(["find-measure", "euler-top", "--system", "lotka-volterra"]) == 2
    assert "differ" in capsys.readouterr().err
    assert main(["find-measure", "euler-top", "--degree", "99"]) == 2
    assert "--degree" in capsys.readouterr().err


def test_fraction_recheck_of_lv_density():
    """The density 1/(uv) of the catalogue's Lotka-Volterra map, recomputed with Fractions from the
    defining equation (x~ - x)/(2 eps) = B(x, x~) + L(x + x~)/2 (a 2x2 linear solve by Cramer's rule)."""
    res = find_measure("lotka-volterra", degree=2)
    assert res.densities[0].text == "1/(u*v)"
    e = Fraction(1, 10)

    def step(u, v):  # u' = u(2 - v), v' = v(u - 1): linear in (U, V) = x~
        # (U - u)/(2e) = (u + U) - (u V + U v)/2, (V - v)/(2e) = (u V + U v)/2 - (v + V)/2
        a11, a12, r1 = 1 - 2 * e + e * v, e * u, u * (1 + 2 * e)
        a21, a22, r2 = -e * v, 1 + e - e * u, v * (1 - e)
        det = a11 * a22 - a12 * a21
        return (r1 * a22 - a12 * r2) / det, (a11 * r2 - a21 * r1) / det

    def jac(u, v):  # det dPhi: differentiate M(x) X = r(x), M dX = dr - dM X
        U, V = step(u, v)
        a11, a12 = 1 - 2 * e + e * v, e * u
        a21, a22 = -e * v, 1 + e - e * u
        det = a11 * a22 - a12 * a21
        cols = []
        for dr1, dr2, dM in (((1 + 2 * e), 0, ((0, e), (0, -e))), (0, (1 - e), ((e, 0), (-e, 0)))):
            b1 = dr1 - (dM[0][0] * U + dM[0][1] * V)
            b2 = dr2 - (dM[1][0] * U + dM[1][1] * V)
            cols.append(((b1 * a22 - a12 * b2) / det, (a11 * b2 - a21 * b1) / det))
        return cols[0][0] * cols[1][1] - cols[0][1] * cols[1][0]

    u, v = Fraction(3, 2), Fraction(1, 3)
    for _ in range(4):
        U, V = step(u, v)
        assert 1 / (U * V) * jac(u, v) == 1 / (u * v)
        u, v = U, V


def test_cli_x0_at_a_pole_and_inapplicable_control(capsys):
    """At the fixed point (0, 0) on the poles of 1/(uv): the exact check cannot run, so the
    density is not called verified; the tensor's control is inapplicable, never 'failed'."""
    assert main(["find-measure", "lotka-volterra", "--x0", "0,0"]) == 0
    out = capsys.readouterr().out
    assert "exact orbit: inapplicable" in out and "NOT verified" in out
    assert main(["find-poisson", "lotka-volterra", "--x0", "0,0"]) == 0
    out = capsys.readouterr().out
    assert "control: (1 + x_j) pi: inapplicable" in out and "[VERIFIED]" in out


def test_darboux_cofactors_against_sympy():
    """Each reported Darboux polynomial P of Kahan's Lotka-Volterra map has P(x~)/P(x) equal to its
    reported cofactor, written over the reported factors F_i (SymPy substitution)."""
    sysobj = ExpressionSystem.from_expressions(LV[0], field=LV[1])
    res = find_measure(sysobj, degree=1, eps="1/10")
    xs, xt, _ = kahan_sympy(*LV, "1/10")
    F = {f"F{i}": read(t, xs) for i, t in enumerate(res.factors, 1)}
    found = {d.polynomial: d.cofactor for d in res.darboux}
    assert set(found) == {"x", "y"}             # degree 1: the two coordinate lines
    for P, cof in found.items():
        p = read(P, xs)
        ratio = sp.cancel(p.subs(dict(zip(xs, xt)), simultaneous=True) / p)
        assert sp.cancel(ratio - sp.sympify(cof, locals=F)) == 0
    # at degree 1 the density 1/(xy) comes from multiplying them
    assert [d.text for d in res.densities] == ["1/(x*y)"] and res.densities[0].verified


def test_euler_top_poisson_block_certifies(tmp_path, capsys):
    """The --toml block of find-poisson replaces the catalogue's [poisson] section: certify is VALID."""
    assert main(["find-poisson", "euler-top", "--degree", "3", "--toml"]) == 0
    block = capsys.readouterr().out
    src = open("exact_khk/systems/catalogue/euler-top.toml").read()
    head, rest = src.split("[poisson]")
    path = tmp_path / "euler.toml"
    path.write_text(head + block + "\n[controls]" + rest.split("[controls]")[1])
    assert main(["certify", "--system", str(path), "--steps", "3", "--quiet"]) == 0
    assert "VALID" in capsys.readouterr().out


def test_bad_input_one_line_no_traceback(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 'x'\nvariables = ['x']\n[field]\nx = 'x**3'\n")
    for argv in (["find-measure", str(bad)], ["find-poisson", "euler-top", "--x0", "a,b,c"],
                 ["find-poisson", "euler-top", "--casimir-degree", "0"], ["find-measure", "no-such-system"],
                 ["find-measure", "euler-top", "--degree", "13"]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "Traceback" not in err, (argv, err)
    for call in (lambda: find_measure("euler-top", degree=0), lambda: find_poisson("euler-top", degree=-1),
                 lambda: find_measure("euler-top", eps=0)):
        with pytest.raises(InputError):
            call()


def kahan_at(names, field, eps, pt):
    """(x~, dPhi) at a rational point by SymPy from the formulas: x~ = x + 2 eps (I - eps f'(x))^-1 f(x),
    dPhi = (I - eps f'(x))^-1 (I + eps f'(x~))."""
    xs = sp.symbols(names)
    f = sp.Matrix([sp.sympify(c, locals=dict(zip(names, xs))) for c in field])
    J, e = f.jacobian(xs), sp.Rational(eps)
    at = dict(zip(xs, pt))
    M = sp.eye(len(xs)) - e * J.subs(at)
    xt = sp.Matrix(pt) + 2 * e * M.LUsolve(f.subs(at))
    return list(xt), M.LUsolve(sp.eye(len(xs)) + e * J.subs(dict(zip(xs, xt))))


def test_volterra_chain_measure_and_poisson():
    """The 3-species Volterra chain x' = x(y - z) (cyclic): the density 1/(xyz) and a preserved Poisson
    tensor with the Casimir x + y + z, checked with the SymPy map at rational points."""
    names, field = ["x", "y", "z"], ["x*(y - z)", "y*(z - x)", "z*(x - y)"]
    sysobj = ExpressionSystem.from_expressions(names, field=field)
    res = find_measure(sysobj, degree=2, eps="1/10")
    xs = sp.symbols(names)
    texts = [d.text for d in res.densities if d.verified]
    assert "1/(x*y*z)" in texts
    pts = points(3, 2, seed=4)
    for text in texts:
        m = read(text, xs)
        for pt in pts:
            xt, D = kahan_at(names, field, "1/10", pt)
            assert m.subs(dict(zip(xs, xt))) * D.det() == m.subs(dict(zip(xs, pt)))
    pres = find_poisson(sysobj, degree=2, eps="1/10")
    t = pres.tensors[0]
    P = sp.Matrix(3, 3, lambda i, j: read(t.entries[i][j], xs))
    for pt in pts:
        xt, D = kahan_at(names, field, "1/10", pt)
        assert D * P.subs(dict(zip(xs, pt))) * D.T == P.subs(dict(zip(xs, xt)))
    assert [c.text for c in t.casimirs] == ["x + y + z"]
    assert (P * sp.Matrix([1, 1, 1])).applyfunc(sp.expand) == sp.zeros(3, 1)
