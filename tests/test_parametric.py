"""find-integrals --symbolic: integrals as rational functions of eps and parameters, compared
with the Hirota-Kimura closed forms typed in from the literature (SymPy, not the code under test):
each reconstructed integral must be a function of the published ones (the Jacobian of it together
with two published integrals has determinant 0 in Q(x, eps, a)), and the reconstructed ones must be
independent."""

from __future__ import annotations

import json
from fractions import Fraction

import pytest
import sympy as sp

from exact_khk.cli.main import main
from exact_khk.diagnostics.parametric import EPS, prove_identity, kahan_image, reconstruct, symbolic_integrals
from exact_khk.errors import InputError
from exact_khk.systems.catalogue import load

X = sp.symbols("x1 x2 x3")
EPS_S, A1, A2, A3 = sp.symbols("eps a1 a2 a3")
NAMES = {"x1": X[0], "x2": X[1], "x3": X[2], "eps": EPS_S, "a1": A1, "a2": A2, "a3": A3}


def published(a1=A1, a2=A2, a3=A3):
    """Hirota-Kimura (J. Phys. Soc. Japan 69, 2000; Petrera-Pfadler-Suris 2011): the Euler top's
    Kahan map (h = 2 eps) conserves H_ij = (a_j x_i^2 - a_i x_j^2)/(1 - eps^2 a_i a_j x_k^2)."""
    x1, x2, x3 = X
    return [(a2 * x1**2 - a1 * x2**2) / (1 - EPS_S**2 * a1 * a2 * x3**2),
            (a3 * x2**2 - a2 * x3**2) / (1 - EPS_S**2 * a2 * a3 * x1**2)]


def as_sympy(f):
    return sp.sympify(f.numerator, locals=NAMES) / sp.sympify(f.denominator, locals=NAMES)


#: rational points where the Jacobian determinants are evaluated, eps (and parameters left) symbolic
POINTS = [dict(zip(X + (A1, A2, A3), map(sp.Rational, v)))
          for v in (("1/2", "-3", "5/7", "5/3", "-2/7", "4"), ("-4/3", "2/9", "11/5", "7/2", "3", "-1/6"))]


def jacobian_det(fs):
    """det d(f1, f2, f3)/dx at POINTS (x and the parameters left symbolic), as rational functions
    of eps (a determinant that vanishes identically vanishes there; one that does not, almost never)."""
    J = sp.Matrix([[sp.diff(f, x) for x in X] for f in fs])
    return [sp.cancel(sp.together(J.subs(pt)).det()) for pt in POINTS]


def check_against_literature(res, **values):
    H = published(**values)
    assert len(res.integrals) == 2 and all(f.proven for f in res.integrals)
    Is = [as_sympy(f).subs(values_symbols(values)) for f in res.integrals]
    for I in Is:
        assert jacobian_det([I] + H) == [0, 0]         # a function of the published integrals
    assert 0 not in jacobian_det(Is + [X[0]])         # and the two are independent


def values_symbols(values):
    return {NAMES[k]: v for k, v in values.items()}


def test_euler_top_eps_symbolic_matches_hirota_kimura():
    res = symbolic_integrals(load("euler-top"), ["eps"], degree=2)
    assert res.symbols == ("eps",) and dict(res.fixed) == {"a1": 1, "a2": -2, "a3": 3}
    assert any("eps" in f.numerator + f.denominator for f in res.integrals)
    check_against_literature(res, a1=1, a2=-2, a3=3)
    assert "proven exactly" in res.integrals[0].proof and "PROVEN" in res.summary()


def test_euler_top_eps_and_a1_symbolic():
    res = symbolic_integrals(load("euler-top"), "eps,a1", degree=2)
    check_against_literature(res, a2=-2, a3=3)


@pytest.mark.slow
def test_euler_top_all_parameters_symbolic():
    res = symbolic_integrals(load("euler-top"), ["a1", "a2", "a3", "eps"], degree=2)
    assert res.symbols == ("eps", "a1", "a2", "a3") and res.fixed == ()
    check_against_literature(res)


def test_negative_controls():
    # a perturbed coefficient fails the proof
    res = symbolic_integrals(load("euler-top"), ["eps"], degree=2, perturb=Fraction(1, 7))
    assert not res.integrals[0].proven and "FAILS" in res.integrals[0].proof and res.integrals[1].proven
    # the same over F_p (Schwartz-Zippel), with its failure bound stated
    res = symbolic_integrals(load("euler-top"), ["eps"], degree=2, perturb=Fraction(1, 7), proof="sz")
    assert not res.integrals[0].proven and "FAILS at a point of F_" in res.integrals[0].proof
    assert res.integrals[1].proven and "failure probability <= " in res.integrals[1].proof
    # a degree bound too low: no reconstruction, refused
    with pytest.raises(InputError, match="degree <= 1"):
        symbolic_integrals(load("euler-top"), ["eps"], degree=2, max_degree=1)
    # the proof itself fails on a function that is not an integral: x1^2 + x2^2 + x3^2
    import flint
    R = flint.fmpq_mpoly_ctx.get(("x1", "x2", "x3", "eps"), "degrevlex")
    x1, x2, x3, e = R.gens()
    f = [x2 * x3, -2 * x3 * x1, 3 * x1 * x2]
    y, q = kahan_image(f, R, 3, e)
    assert not prove_identity(x1**2 + x2**2 + x3**2, R.constant(1), y, q, 3)
    assert prove_identity(3 * x1**2 - x3**2, 2 * x1**2 + x2**2, y, q, 3)   # (a3 x1^2 - a1 x3^2)/(-(a2 x1^2 - a1 x2^2))


def test_reconstruct_against_fractions():
    import random
    rng = random.Random(1)
    pts = [(Fraction(rng.randint(-50, 50), rng.randint(1, 9)), Fraction(rng.randint(-50, 50), rng.randint(1, 9)))
           for _ in range(40)]
    c = [(1 + s * t) / (s - 2 * t * t) for s, t in pts]
    P, Q = reconstruct(pts, c, 2)
    for s, t in [(Fraction(5, 3), Fraction(-7, 2)), (Fraction(1, 9), Fraction(4))]:
        val = sum(v * s**e[0] * t**e[1] for e, v in P.items()) / sum(v * s**e[0] * t**e[1] for e, v in Q.items())
        assert val == (1 + s * t) / (s - 2 * t * t)
    assert reconstruct(pts, c, 1) is None          # degree 1 cannot fit: the confirming samples refuse it


def test_bad_input():
    with pytest.raises(InputError, match="not a parameter"):
        symbolic_integrals(load("euler-top"), ["b7"], degree=2)
    with pytest.raises(InputError, match="named twice"):
        symbolic_integrals(load("euler-top"), ["eps", "eps"], degree=2)
    with pytest.raises(InputError, match="not a parameter"):
        symbolic_integrals("lotka-volterra", ["a1"], degree=2)
    for bad in (123, [1, 2], None):
        with pytest.raises(InputError, match="symbolic"):
            symbolic_integrals(load("euler-top"), bad, degree=2)
    with pytest.raises(InputError, match="proof"):
        symbolic_integrals(load("euler-top"), EPS, degree=2, proof="maybe")


def test_cli(tmp_path, capsys):
    out = tmp_path / "e.toml"
    assert main(["find-integrals", "--system", "euler-top", "--symbolic", "eps", "--toml", str(out)]) == 0
    text = capsys.readouterr().out
    assert "PROVEN" in text and "**" in text and "^" not in text.split("I1 =")[1].split("\n")[0]
    assert main(["certify", "--system", str(out), "--quiet"]) == 0         # pasted back: VALID
    js = tmp_path / "e.json"
    assert main(["find-integrals", "--system", "euler-top", "--symbolic", "eps", "--symbolic", "a1",
                 "--json", str(js)]) == 0
    data = json.loads(js.read_text())
    assert data["symbols"] == ["eps", "a1"] and all(f["proven"] for f in data["integrals"])
    capsys.readouterr()
    for argv in (["--symbolic", "b7"], ["--symbolic", "eps", "--symbolic-degree", "1"],
                 ["--symbolic", "eps", "--symbolic-degree", "99"], ["--symbolic-degree", "2"]):
        assert main(["find-integrals", "--system", "euler-top", *argv]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "--symbolic" in err and "Traceback" not in err


def check_measure(symbols, values):
    """The issue's target (catalogue [literature]): dx/((1 - eps^2 a2 a3 x1^2)(1 - eps^2 a3 a1 x2^2)),
    up to a factor free of x (a density times a constant is preserved)."""
    from exact_khk.diagnostics.parametric import symbolic_measures

    res = symbolic_measures(load("euler-top"), symbols, degree=2)
    assert res.kind == "measure" and len(res.integrals) == 1 and res.integrals[0].proven
    m = as_sympy(res.integrals[0]).subs(values)
    published = 1 / ((1 - EPS_S**2 * A2 * A3 * X[0]**2) * (1 - EPS_S**2 * A3 * A1 * X[1]**2))
    ratio = sp.cancel(m / published.subs(values))
    assert ratio != 0 and not ratio.free_symbols & set(X)


@pytest.mark.slow
def test_euler_top_measure_in_eps_and_a1():
    check_measure("eps,a1", {A2: -2, A3: 3})


@pytest.mark.slow
def test_euler_top_measure_all_symbolic():
    check_measure("eps,a1,a2,a3", {})


def test_euler_top_measure_matches_the_published_density():
    from exact_khk.diagnostics.parametric import symbolic_measures

    check_measure("eps", {A1: 1, A2: -2, A3: 3})
    # negative control: a perturbed density fails the proof, exactly and over F_p
    for proof in ("exact", "sz"):
        bad = symbolic_measures(load("euler-top"), ["eps"], degree=2, perturb=Fraction(1, 3), proof=proof)
        assert not bad.integrals[0].proven and "FAILS" in bad.integrals[0].proof


def test_cli_measure(capsys):
    assert main(["find-measure", "euler-top", "--symbolic", "eps", "--toml"]) == 0
    block = capsys.readouterr().out
    assert block.startswith("[measure]") and "eps**2" in block
    assert main(["find-measure", "euler-top", "--symbolic", "zz"]) == 2
    assert "--symbolic" in capsys.readouterr().err


@pytest.mark.slow
def test_euler_top_poisson_tensors_preserved_and_casimir():
    """Each tensor reconstructed in eps is preserved at a rational eps and x (SymPy builds the Kahan map
    and dPhi by differentiation, tests/test_discover.py), and one has the Hirota-Kimura integral
    (1 - eps^2 a2 a3 x1^2)/(1 - eps^2 a3 a1 x2^2) as a Casimir (the issue's target)."""
    from exact_khk.diagnostics.parametric import symbolic_tensors
    from tests.test_discover import EULER, kahan_sympy

    res = symbolic_tensors(load("euler-top"), ["eps"], degree=3)
    assert res.kind == "poisson" and res.integrals and all(t.proven for t in res.integrals)
    pis = [sp.Matrix([[sp.sympify(e, locals=NAMES) for e in row] for row in t.entries]) for t in res.integrals]
    for eps in ("-2/7",):
        xs, xt, D = kahan_sympy(*EULER, eps)
        at = {EPS_S: sp.Rational(eps)}
        for pt in POINTS[:1]:
            subs = {x: pt[x] for x in X}
            xt_pt, D_pt = xt.subs(subs), D.subs(subs)
            for pi in pis:
                lhs = D_pt * pi.subs(at).subs(subs) * D_pt.T
                rhs = pi.subs(at).subs(dict(zip(X, xt_pt)), simultaneous=True)
                assert (lhs - rhs).applyfunc(sp.cancel) == sp.zeros(3, 3)
    C = (1 - EPS_S**2 * A2 * A3 * X[0]**2) / (1 - EPS_S**2 * A3 * A1 * X[1]**2)
    grad = sp.Matrix([sp.diff(C.subs({A1: 1, A2: -2, A3: 3}), x) for x in X])
    assert any((pi * grad).applyfunc(sp.cancel) == sp.zeros(3, 1) for pi in pis)
    # negative control: a perturbed tensor fails (preservation and Jacobi)
    bad = symbolic_tensors(load("euler-top"), ["eps"], degree=3, perturb=Fraction(1, 3), proof="sz")
    assert not bad.integrals[0].proven and "FAILS" in bad.integrals[0].proof


def test_lotka_volterra_tensor_with_parameters():
    """u' = u(a - b v), v' = v(c u - d): the tensor u*v, the same for every eps and a;
    a perturbed one fails, exactly."""
    from exact_khk.diagnostics.parametric import symbolic_tensors

    res = symbolic_tensors("lotka-volterra", "eps,a", degree=2, proof="exact")
    assert [t.entries for t in res.integrals] == [(("0", "u*v"), ("-u*v", "0"))] and res.integrals[0].proven
    assert "proven exactly" in res.integrals[0].proof and "Jacobi identity proven" in res.integrals[0].proof
    bad = symbolic_tensors("lotka-volterra", "eps,a", degree=2, proof="exact", perturb=Fraction(1, 2))
    assert not bad.integrals[0].proven and "FAILS" in bad.integrals[0].proof


def test_cli_poisson(capsys):
    assert main(["find-poisson", "lotka-volterra", "--symbolic", "eps,a", "--toml"]) == 0
    assert capsys.readouterr().out.startswith("[poisson]")
    assert main(["find-poisson", "euler-top", "--symbolic", "eps", "--symbolic-degree", "99"]) == 2
    assert "--symbolic-degree" in capsys.readouterr().err


def test_samples_of_another_shape_are_dropped_or_refused(monkeypatch):
    """The normal form must be the same at every sample: a minority of samples whose search finds
    something else is dropped (and said), a split is refused."""
    import exact_khk.diagnostics.parametric as par

    real, calls = par._sample, []

    def odd_one_out(every):
        def sample(*args, **kw):
            calls.append(1)
            shape, coeffs, head = real(*args, **kw)
            return (shape[:1], coeffs[:1], head) if len(calls) % every == 0 else (shape, coeffs, head)
        return sample
    monkeypatch.setattr(par, "_sample", odd_one_out(5))
    res = symbolic_integrals(load("euler-top"), ["eps"], degree=2)
    assert res.dropped >= 1 and any("dropped" in n for n in res.notes) and all(f.proven for f in res.integrals)
    calls.clear()
    monkeypatch.setattr(par, "_sample", odd_one_out(2))
    with pytest.raises(InputError, match="differ between the samples"):
        symbolic_integrals(load("euler-top"), ["eps"], degree=2)
