"""find-integrals extracts every independent integral its kernel shows (issue 41, items 1, 2, 5).

Every found integral is checked here by a route independent of the code under test: the Kahan
step is recomputed with SymPy straight from its definition x~ = x + 2 eps (I - eps f'(x))^-1 f(x)
at random rational points (not orbit points), and I(x~) == I(x) exactly; functional independence
is the rank of the Jacobian computed by SymPy at a rational point.
"""

import functools
import random
from fractions import Fraction as F

import pytest
import sympy

from exact_khk import LiePoissonSystem
from exact_khk.cli.main import main
from exact_khk.diagnostics import find_integrals
from exact_khk.diagnostics.degrees import resolve_field
from exact_khk.systems.expressions import ExpressionSystem

EULER = ExpressionSystem.from_expressions(["x", "y", "z"], field=["y*z", "-2*x*z", "x*y"], name="euler")
VOLTERRA = ExpressionSystem.from_expressions(["x", "y", "z"], field=["x*(y - z)", "y*(z - x)", "z*(x - y)"],
                                             name="volterra3")
KAHAN_LV = ExpressionSystem.from_expressions(["x", "y"], field=["x*(1 - y)", "y*(x - 1)"], name="kahan-lv")


def sympy_field(system, field="f"):
    """(symbols, components) of the field as SymPy expressions, from its quadratic, linear and
    constant coefficients."""
    _, fld = resolve_field(system, field)
    xs = sympy.symbols(f"x0:{fld.dim}")
    comps = []
    for k in range(fld.dim):
        e = sum(sympy.Rational(str(c)) * xs[i] * xs[j] for (i, j), c in fld.terms()[k])
        e += sum(sympy.Rational(str(c)) * xs[j] for j, c in fld.linear[k])
        comps.append(e + sympy.Rational(str(fld.const[k])))
    return xs, comps


def kahan_step(xs, comps, eps, point):
    """x~ = x + 2 eps (I - eps f'(x))^-1 f(x), by SymPy at a rational point."""
    at = dict(zip(xs, point))
    J = sympy.Matrix([[sympy.diff(c, v) for v in xs] for c in comps]).subs(at)
    f = sympy.Matrix([c.subs(at) for c in comps])
    return list(sympy.Matrix(point) + 2 * eps * (sympy.eye(len(xs)) - eps * J).LUsolve(f))


def as_sympy(integral, xs):
    num, den = integral.polynomials()
    poly = lambda d: sum(sympy.Rational(c.numerator, c.denominator) * sympy.Mul(*[v ** k for v, k in zip(xs, e)])
                         for e, c in d.items())  # noqa: E731
    return poly(num) / poly(den)


def value(integral, x):
    """num(x)/den(x) from the integral's coefficients, by Fractions (None at a pole)."""
    num, den = integral.polynomials()
    ev = lambda d: sum(c * _mono(e, x) for e, c in d.items())  # noqa: E731
    d = ev(den)
    return None if d == 0 else ev(num) / d


def _mono(e, x):
    out = F(1)
    for t, k in zip(x, e):
        out *= t ** k
    return out


def check_found(system, res, eps, field="f", points=3, seed=1):
    """Every found integral is conserved at random rational points (SymPy's Kahan step, values by
    Fractions) and their SymPy Jacobian has full rank at a rational point: returns that rank."""
    xs, comps = sympy_field(system, field)
    eps = sympy.Rational(str(eps))
    rng = random.Random(seed)
    checked = 0
    while checked < points:
        x = [sympy.Rational(rng.randint(-9, 9), rng.randint(1, 5)) for _ in xs]
        try:
            y = kahan_step(xs, comps, eps, x)
        except (ValueError, ZeroDivisionError):
            continue
        xf, yf = ([F(int(t.p), int(t.q)) for t in pt] for pt in (x, y))
        vals = [(value(f, xf), value(f, yf)) for f in res.integrals]
        if any(v is None or w is None for v, w in vals):
            continue
        assert all(v == w for v, w in vals)
        checked += 1
    x = [F(rng.randint(-9, 9), rng.randint(1, 5)) for _ in xs]
    rows = [gradient(f, x) for f in res.integrals]
    return sympy.Matrix([[sympy.Rational(t.numerator, t.denominator) for t in r] for r in rows]).rank() \
        if rows else 0


def gradient(integral, x):
    """d(num/den)/dx_j at x, by differentiating the coefficient dicts with Fractions (quotient rule)."""
    num, den = integral.polynomials()

    def ev(d, j=None):
        total = F(0)
        for e, c in d.items():
            if j is not None:
                if not e[j]:
                    continue
                c, e = c * e[j], e[:j] + (e[j] - 1,) + e[j + 1:]
            total += c * _mono(e, x)
        return total

    n0, d0 = ev(num), ev(den)
    return [(ev(num, j) * d0 - n0 * ev(den, j)) / d0 ** 2 for j in range(len(x))]


def test_euler_top_two():
    res = find_integrals(EULER, degree=2, eps="1/10")
    assert (res.kernel_dim, len(res.integrals), res.independent, res.visible) == (2, 2, 2, 2)
    assert check_found(EULER, res, "1/10") == 2
    assert "kernel 2, extracted 2, independent 2" in res.summary()
    # the certificate: the exact Jacobian rank at the stated point
    point, rank = res.certificate
    assert rank == 2 and len(point) == 3


def test_volterra_chain_linear_and_modified_cubic_never_a_power():
    """x' = x(y - z) cyclic: x + y + z and a modified cubic; 1/(x + y + z)^3 is not a new integral."""
    res = find_integrals(VOLTERRA, degree=3, eps="1/10")
    assert res.visible == 2 and len(res.integrals) == 2 and res.independent == 2
    assert check_found(VOLTERRA, res, "1/10") == 2
    x, y, z = sympy.symbols("x0:3")
    first = as_sympy(res.integrals[0], (x, y, z))
    assert sympy.simplify(sympy.diff(first, x) - sympy.diff(first, y)) == 0     # a function of x + y + z
    assert any("is a function of the integrals kept" in n for n in res.notes)  # the power, named and dropped
    assert any("on the level sets x + y + z = c" in n for n in res.notes)       # the cubic: level-set pencil
    # the second is not a function of the linear one, and tends to a function of xyz and x + y + z
    assert sympy.Matrix([[sympy.diff(as_sympy(f, (x, y, z)), v).subs({x: 1, y: 2, z: 5}) for v in (x, y, z)]
                         for f in res.integrals]).rank() == 2


@pytest.mark.parametrize("n", [2, 3])
def test_lie_poisson_default_options_n_each(n):
    """n = 3: the built-in system of the README (a, b, c below); n = 2: a random one."""
    s = LiePoissonSystem.random(2, 1) if n == 2 else LiePoissonSystem.from_vectors([1, 0, 2], [0, 1, 0], [3, 1, 1])
    res = find_integrals(s, degree=2)
    assert len(res.integrals) == n and res.independent == n and res.visible == n
    assert check_found(s, res, "1/10", points=2) == n


def test_degenerate_orbits_are_replaced():
    """An orbit on a smaller invariant set (the fixed point 0) has a larger kernel: flagged, replaced,
    and the integrals are still all extracted."""
    res = find_integrals(EULER, degree=2, eps="1/10", x0=["0", "0", "0"])
    assert any("periodic" in w for w in res.warnings)
    assert len(res.integrals) == 2 and res.independent == 2


@pytest.mark.parametrize("degree", [2, 3, 4])
def test_kahan_lotka_volterra_has_none(degree):
    """x' = x(1 - y), y' = y(x - 1): measure-preserving, not integrable: nothing, and said."""
    res = find_integrals(KAHAN_LV, degree=degree, eps="1/10")
    assert res.kernel_dim == 0 and res.integrals == () and res.independent == 0
    assert "kernel 0, extracted 0, independent 0" in res.summary()
    assert "no integral with numerator and denominator in the span" in res.summary()


def test_random_quadratic_field_has_none():
    rng = random.Random(5)
    terms = ["x*x", "x*y", "y*y", "x*z", "y*z", "z*z", "x", "y", "z"]
    comps = [" + ".join(f"{rng.randint(-3, 3)}*{t}" for t in terms) for _ in range(3)]
    s = ExpressionSystem.from_expressions(["x", "y", "z"], field=comps, name="random")
    res = find_integrals(s, degree=2, eps="1/10")
    assert res.kernel_dim == 0 and res.integrals == ()
    assert "no integral with numerator and denominator in the span" in res.summary()


def test_toml_round_trip_certifies_valid(tmp_path, capsys):
    """find-integrals --toml writes a system file; certify of it is VALID (exit 0); with a found
    integral altered it is not (exit 1)."""
    out = tmp_path / "found.toml"
    assert main(["find-integrals", "--system", "euler-top", "--toml", str(out), "--quiet"]) == 0
    text = out.read_text()
    found = [t for t in text.splitlines() if t.startswith("found_I")]
    assert len(found) == 2 and not any("^" in t for t in found)
    capsys.readouterr()
    assert main(["certify", "--system", str(out), "--quiet"]) == 0
    assert "VALID" in capsys.readouterr().out
    bad = tmp_path / "bad.toml"
    line = next(t for t in text.splitlines() if t.startswith("found_I1 = "))
    bad.write_text(text.replace(line, line.replace(")/(", " + x1)/(", 1)))
    assert main(["certify", "--system", str(bad), "--quiet"]) == 1


def test_toml_of_a_lie_poisson_field_writes_the_field(tmp_path, capsys):
    out = tmp_path / "lp.toml"
    assert main(["find-integrals", "--n", "2", "--seed", "1", "--toml", str(out), "--quiet"]) == 0
    assert "[field]" in out.read_text()
    capsys.readouterr()
    assert main(["certify", "--system", str(out), "--quiet"]) == 0


def test_found_integrals_print_in_system_file_syntax():
    res = find_integrals(EULER, degree=2, eps="1/10")
    assert all("^" not in f.numerator + f.denominator for f in res.integrals)
    ExpressionSystem.from_expressions(["x", "y", "z"], field=["y*z", "-2*x*z", "x*y"],
                                      integrals={f"I{i}": f"({f.numerator})/({f.denominator})"
                                                 for i, f in enumerate(res.integrals)})


@functools.lru_cache(maxsize=None)
def lagrange_top():
    return find_integrals("lagrange-top", degree=2)


@pytest.mark.slow
def test_lagrange_top_what_is_extracted_is_right():
    """The kernel at degree <= 2 shows 4.  m3; the two pencils of the kernel on the level sets m3 = c
    (candidates free of m3) interpolated in c: Hirota-Kimura's J and the modified energy; and a ratio of
    degree 8/6 of the HK basis {1, p3, m1^2, m2^2, p3^2} (hkbases.py; the catalogue's K is quadratic in
    the catalogue's J, but the J found is a Moebius transform of it with coefficients depending on m3, so
    K is of higher degree in it).  Nothing is left unextracted."""
    res = lagrange_top()
    assert res.visible == 4 and len(res.integrals) == 4 and res.independent == 4
    assert sum("on the level sets m3 = c" in n for n in res.notes) == 2
    assert sum("of the HK basis" in n for n in res.notes) == 1
    assert "kernel 10, extracted 4, independent 4 (the kernel shows 4" in res.summary()
    assert not any("the kernel shows 4 independent integrals" in w for w in res.warnings)


@pytest.mark.slow
def test_lagrange_top_four():
    """All 4, each conserved by SymPy's Kahan step at rational points (not the code under test), the rank
    of their gradients (by Fractions and SymPy) equal to their number."""
    res = lagrange_top()
    assert res.visible == 4 and len(res.integrals) == 4 and res.independent == 4
    assert check_found("lagrange-top", res, "1/10", points=2) == 4


CLEBSCH = ExpressionSystem.from_expressions(  # m' = p × Ωp, p' = p × m, Ω = diag(1, 2, 5)
    ["m1", "m2", "m3", "p1", "p2", "p3"],
    field=["3*p2*p3", "-4*p1*p3", "p1*p2", "p2*m3 - p3*m2", "p3*m1 - p1*m3", "p1*m2 - p2*m1"], name="clebsch")


@functools.lru_cache(maxsize=None)
def clebsch():
    return find_integrals(CLEBSCH, degree=2, eps="1/10")


@pytest.mark.slow
def test_clebsch_what_is_extracted_is_right():
    res = clebsch()
    assert res.visible == 4 and len(res.integrals) >= 3
    assert check_found(CLEBSCH, res, "1/10", points=2) == len(res.integrals) == res.independent


@pytest.mark.slow
def test_clebsch_four():
    """All 4: I1 from the HK basis {1, p_k^2}, I2 and I3 fitted from circuits inside {1, p_k^2, m_k p_k}, and
    the fourth from the HK-basis route (hkbases.py): a ratio of degree 10/8 on a circuit with two m_k^2
    (scripts/check_clebsch_integrals.py: no ratio of lower degree raises the rank to 4)."""
    res = clebsch()
    assert res.visible == 4 and len(res.integrals) == 4 and res.independent == 4
    assert check_found(CLEBSCH, res, "1/10", points=2) == 4


def test_memory_is_planned_and_refused_up_front(monkeypatch, capsys):
    """The evaluation matrices' memory is estimated before any work; beyond EXACT_KHK_MAX_MEMORY the
    command exits 2 with one line naming the limit (84 candidates × 101 points × 20 bytes > 100 kB)."""
    monkeypatch.setenv("EXACT_KHK_MAX_MEMORY", "100K")
    assert main(["find-integrals", "--system", "lagrange-top", "--degree", "3", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "EXACT_KHK_MAX_MEMORY" in err and "Traceback" not in err
    monkeypatch.setenv("EXACT_KHK_MAX_MEMORY", "1G")
    assert main(["find-integrals", "--system", "euler-top", "--quiet"]) == 0


def test_lie_poisson_with_degenerate_orbits_and_a_mixed_kernel():
    """n = 2, seed 4: one default orbit lies on a smaller invariant set (kernel 10 > 8) and the span
    is of no single shape (main extracted 0); all 3 integrals the kernel shows are extracted."""
    s = LiePoissonSystem.random(2, 4)
    res = find_integrals(s, degree=2)
    assert any("smaller invariant set" in w for w in res.warnings)
    assert res.visible == 3 and len(res.integrals) == 3 and res.independent == 3
    assert check_found(s, res, "1/10", points=2) == 3


def test_cmoq_cubic_modified_energy():
    """A cubic Hamiltonian with constant Poisson matrix (Celledoni, McLachlan, Owren, Quispel 2013):
    the Kahan map with step h = 2 eps preserves H~ = H + (h/3) grad H^T (I - (h/2) f'(x))^-1 f(x).
    The integral found at degree 3 is a function of H~: their gradients are parallel (SymPy)."""
    system = "docs/examples/cubic.toml"
    res = find_integrals(system, degree=3, eps="1/10")
    assert (len(res.integrals), res.independent) == (1, 1)
    assert check_found(system, res, "1/10") == 1
    q, p = xs = sympy.symbols("q p")
    eps = sympy.Rational(1, 10)
    H = p ** 2 / 2 + q ** 3 / 3 - q ** 2 / 2
    grad = sympy.Matrix([H.diff(q), H.diff(p)])
    f = sympy.Matrix([[0, 1], [-1, 0]]) * grad
    modified = H + (2 * eps / 3) * (grad.T * (sympy.eye(2) - eps * f.jacobian(xs)).LUsolve(f))[0]
    found = as_sympy(res.integrals[0], xs)
    assert not sympy.cancel(found.diff(q)).is_zero                       # not a constant
    assert sympy.cancel(found.diff(q) * modified.diff(p) - found.diff(p) * modified.diff(q)) == 0
    # the negative control: the unmodified energy H is not a function of the found integral
    assert sympy.cancel(found.diff(q) * H.diff(p) - found.diff(p) * H.diff(q)) != 0
