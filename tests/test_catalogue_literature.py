"""The literature catalogue: every entry certifies, records the literature's claim on its Kahan
map, and every declared integral is conserved by the Kahan step computed here with SymPy alone,
straight from x~ = x + 2 eps (I - eps f'(x))^{-1} f(x) (never with this library's map).  Fields of
the generated families are rebuilt here from the papers' formulas and compared with the entries."""

import random

import pytest
import sympy as sp

from exact_khk import certify
from exact_khk.cli.main import main
from exact_khk.errors import InputError
from exact_khk.systems.catalogue import families, load, names
from exact_khk.systems.expressions import ExpressionSystem

ISSUE_42 = ("euler-top", "lagrange-top", "clebsch", "euler-poisson", "kahan-lotka-volterra", "cmoq-cubic",
            "lotka-volterra-3d", "nambu-homogeneous", "nambu-inhomogeneous")


def _sympy(system):
    """(variables, field, {integral: expr}, {control: expr}) parsed by SymPy from the entry's strings."""
    spec = system.to_json()
    xs = sp.symbols(list(system.variables))
    loc = {v: s for v, s in zip(system.variables, xs)}
    loc.update({p: sp.Rational(v) for p, v in spec.get("parameters", {}).items()})
    loc["eps"] = sp.Symbol("eps")
    if "field" in spec:
        f = [sp.sympify(spec["field"][v], locals=loc) for v in system.variables]
    else:   # f = K grad H
        K = sp.Matrix([[sp.sympify(e, locals=loc) for e in row] for row in spec["hamiltonian"]["K"]])
        H = sp.sympify(spec["hamiltonian"]["H"], locals=loc)
        f = list(K * sp.Matrix([sp.diff(H, v) for v in xs]))
    read = lambda key: {k: sp.sympify(t, locals=loc) for k, t in spec.get(key, {}).items()}
    return xs, f, read("integrals"), read("controls"), loc["eps"]


def _kahan_step(xs, f, point, e):
    """x~ = x + 2 e (I - e f'(x))^{-1} f(x) at a rational point, in SymPy rationals."""
    sub = dict(zip(xs, point))
    J = sp.Matrix(f).jacobian(xs).subs(sub)
    A = sp.eye(len(xs)) - e * J
    assert A.det() != 0
    return list(sp.Matrix(point) + 2 * e * A.LUsolve(sp.Matrix(f).subs(sub)))


def test_there_are_at_least_16_entries_each_with_its_literature_claim():
    assert len(names()) >= 16
    assert set(ISSUE_42) <= set(names())
    for family in ("volterra-periodic", "volterra-open", "kqv-lotka-volterra", "henon-heiles", "planar-cubic",
                   "zhukovsky-volterra", "kirchhoff"):
        assert any(n.startswith(family + ":") for n in names())
    for name in names():
        s = load(name)
        assert s.name == name and s.source, name
        lit = s.literature
        assert lit["reference"] and lit["integrable"] in ("yes", "no", "unknown"), name
        assert lit["integrals"] == "unknown" or isinstance(lit["integrals"], int), name
        assert lit.get("notes") or lit["integrable"] == "yes", f"{name}: say what was read"
        assert ExpressionSystem.from_json(s.to_json()).literature == lit


@pytest.mark.parametrize("name", names())
def test_every_entry_certifies_and_its_integrals_hold_by_sympy(name):
    s = load(name)
    cert = certify(s, steps=3)
    assert cert.status == "VALID", cert.table()
    xs, f, integrals, controls, eps = _sympy(s)
    e = sp.Rational(s.default_eps)
    random.seed(name)
    points = [[sp.Rational(v) for v in s.default_x0]] + [
        [sp.Rational(random.randint(-7, 7), random.randint(1, 4)) for _ in xs] for _ in range(2)]
    for p in points:
        q = _kahan_step(xs, f, p, e)
        at = lambda fn, pt: fn.subs(eps, e).subs(dict(zip(xs, pt)))
        for iname, fn in integrals.items():
            assert sp.nsimplify(at(fn, q) - at(fn, p)) == 0, (name, iname, p)
    # a negative control: some declared control changes along the first step
    if controls:
        p, q = points[0], _kahan_step(xs, f, points[0], e)
        assert any(sp.simplify(fn.subs(dict(zip(xs, q))) - fn.subs(dict(zip(xs, p)))) != 0
                   for fn in controls.values()), name


def _chain_field(kind, N):
    x = sp.symbols(f"x1:{N + 1}")
    get = lambda k: x[k % N] if kind == "periodic" else (x[k] if 0 <= k < N else 0)
    if kind == "kqv":
        return x, [x[i] * (sum(x[i + 1:]) - sum(x[:i])) for i in range(N)]
    return x, [x[k] * (get(k + 1) - get(k - 1)) for k in range(N)]


@pytest.mark.parametrize("family, kind", [("volterra-periodic", "periodic"), ("volterra-open", "open"),
                                          ("kqv-lotka-volterra", "kqv")])
@pytest.mark.parametrize("N", [3, 5, 8])
def test_chains_are_the_papers_equations(family, kind, N):
    s = load(f"{family}:N={N}")
    xs, f, integrals, _, _ = _sympy(s)
    x, g = _chain_field(kind, N)
    assert [sp.expand(a - b.subs(dict(zip(x, xs)))) for a, b in zip(f, g)] == [0] * N


def test_henon_heiles_and_planar_cubic_are_the_stated_fields():
    q1, q2, p1, p2 = sp.symbols("q1 q2 p1 p2")
    for sigma in (-1, -6, -16, 1, 3):
        B = 16 if sigma == -16 else 1
        H = (p1 ** 2 + p2 ** 2) / 2 + (q1 ** 2 + B * q2 ** 2) / 2 + q1 ** 2 * q2 - sp.Rational(sigma, 3) * q2 ** 3
        _, f, _, _, _ = _sympy(load(f"henon-heiles:sigma={sigma}"))
        want = [sp.diff(H, p1), sp.diff(H, p2), -sp.diff(H, q1), -sp.diff(H, q2)]
        assert [sp.expand(a - b) for a, b in zip(f, want)] == [0] * 4
    x, y = sp.symbols("x y")
    l = (x, y, x + y)
    for g in [(1, 1, 1), (1, 1, 2), (1, 2, 3), (2, 3, 5)]:
        H = l[0] ** g[0] * l[1] ** g[1] * l[2] ** g[2]
        pre = l[0] ** (1 - g[0]) * l[1] ** (1 - g[1]) * l[2] ** (1 - g[2])
        want = [sp.cancel(pre * sp.diff(H, y)), sp.cancel(-pre * sp.diff(H, x))]   # J = [[0, 1], [-1, 0]]
        assert all(sp.Poly(w, x, y).total_degree() == 2 for w in want)       # quadratic for every gamma
        _, f, _, _, _ = _sympy(load("planar-cubic:g1={},g2={},g3={}".format(*g)))
        assert [sp.expand(a - b) for a, b in zip(f, want)] == [0, 0]


def test_kirchhoff_field_is_the_kirchhoff_equations():
    m = sp.Matrix(sp.symbols("m1 m2 m3")); p = sp.Matrix(sp.symbols("p1 p2 p3"))
    for b1, b3 in [(0, 0), (1, 1), (1, 2)]:
        A, B, C = sp.diag(1, 1, 2), sp.diag(b1, b1, b3), sp.diag(1, 1, 3)
        want = list(m.cross(A * m + B * p) + p.cross(B * m + C * p)) + list(p.cross(A * m + B * p))
        xs, f, _, _, _ = _sympy(load(f"kirchhoff:b1={b1},b3={b3}"))
        sub = dict(zip(list(m) + list(p), xs))
        assert [sp.expand(a - b.subs(sub)) for a, b in zip(f, want)] == [0] * 6
    # B = b I: the field is that of B = 0 (docs/catalogue.md)
    (_, f1, *_), (_, f0, *_) = _sympy(load("kirchhoff:b1=1,b3=1")), _sympy(load("kirchhoff:b1=0,b3=0"))
    assert [sp.expand(a - b) for a, b in zip(f1, f0)] == [0] * 6


@pytest.mark.parametrize("spec, message", [
    ("volterra-periodic:N=2", "N=2 is outside 3..40"),
    ("volterra-periodic:N=x", "N='x' is not an integer"),
    ("volterra-periodic", "missing N"),
    ("volterra-periodic:M=3", "'M=3' is not a parameter"),
    ("henon-heiles:sigma=1,sigma=2", "sigma is given twice"),
    ("planar-cubic:g1=0,g2=1,g3=1", "g1=0 is outside 1..6"),
    ("no-family:N=3", "unknown catalogue system"),
])
def test_bad_family_members_are_input_errors_naming_the_range(spec, message):
    with pytest.raises(InputError, match=message):
        load(spec)


def test_bad_member_on_the_command_line_is_one_line_and_exit_2(capsys):
    assert main(["certify", "--system", "kqv-lotka-volterra:N=41", "--steps", "2"]) == 2
    err = capsys.readouterr().err
    assert "N=41 is outside 2..40" in err and "Traceback" not in err


def test_literature_table_is_validated():
    base = dict(name="t", variables=["x"], field={"x": "x**2"})
    for bad, msg in [({"integrable": "maybe"}, "'yes', 'no' or 'unknown'"), ({"integrals": -1}, "a count"),
                     ({"bogus": "1"}, "unknown key"), ({"notes": 3}, "a string")]:
        with pytest.raises(InputError, match=msg):
            ExpressionSystem(dict(base, literature=bad))
    assert ExpressionSystem(base).literature == {}


def test_systems_command_lists_every_entry_with_its_claim(capsys):
    assert main(["systems"]) == 0
    out = capsys.readouterr().out
    for name in names():
        assert name in out
    for family in families.FAMILIES:
        assert f"{family}: " in out
    assert "integrable: yes" in out and "integrable: unknown" in out


def test_docs_catalogue_table_lists_exactly_the_entries_with_their_claims():
    import pathlib
    import re

    text = (pathlib.Path(__file__).parents[1] / "docs" / "catalogue.md").read_text()
    rows = re.findall(r"^\| `([^`]+)` \| (\d+) \| [^|]* \| (\w+) / (\w+) \| ([^|]*) \|", text, re.M)
    assert sorted(r[0] for r in rows) == names()
    for name, dim, integrable, integrals, declared in rows:
        s = load(name)
        assert (int(dim), integrable, integrals, declared) == (
            s.dim, s.literature["integrable"], str(s.literature["integrals"]), s.known())


def test_the_integral_checks_are_not_vacuous():
    """Most entries declare integrals or a Hamiltonian form, and a wrong integral is rejected."""
    declared = [n for n in names() if load(n).integrals()]
    assert len(declared) >= 12, declared
    s = load("nambu-homogeneous")
    xs, f, integrals, _, eps = _sympy(s)
    p = [sp.Rational(v) for v in s.default_x0]
    q = _kahan_step(xs, f, p, sp.Rational(1, 10))
    wrong = integrals["H12"].subs(eps, 2 * eps)          # the eps convention off by a factor 2
    at = lambda fn, pt: fn.subs(eps, sp.Rational(1, 10)).subs(dict(zip(xs, pt)))
    assert at(wrong, q) != at(wrong, p) and at(integrals["H12"], q) == at(integrals["H12"], p)
