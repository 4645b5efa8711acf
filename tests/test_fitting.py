"""The fits of kernel entries (exact_khk/diagnostics/fitting.py): the linear system is filled straight
into an ``nmod_mat`` (memory planned first, refused beyond the limit), solved mod word-size primes and
lifted by CRT and rational reconstruction; a fit is restricted to the variables the entry depends on,
and fits that cannot equal the entry on a random line over F_p are not tried.

Golden values come from SymPy (the Kahan step recomputed from its definition), never from the code
under test."""

import random
from fractions import Fraction as F

import pytest
import sympy

from exact_khk.cli.main import main
from exact_khk.diagnostics import find_integrals
from exact_khk.diagnostics.degrees import random_primes, resolve_field
from exact_khk.diagnostics.fitting import EntryFitter, EntryLine, FitTooLarge, entry_jacobian, entry_line, fit_bytes
from exact_khk.diagnostics.kernels import monomials
from exact_khk.errors import InputError
from .test_find_integrals import check_found, kahan_step, sympy_field


def chain(N):
    """The Kouloukas-Quispel-Vanhaecke chain x_i' = x_i (sum_{j>i} x_j - sum_{j<i} x_j)."""
    return f"kqv-lotka-volterra:N={N}"


def kqv_integral(N, k):
    """x_{k-1} x_{k+1} (x_{k-2} + x_{k-1}) / (x_{k-2} x_k (x_k + x_{k+1})) (1-based indices), a modified
    integral of the chain's Kahan map: checked here by SymPy's Kahan step before it is used as golden."""
    xs = sympy.symbols(f"x0:{N}")
    a, b, c, d = xs[k - 3], xs[k - 2], xs[k - 1], xs[k]
    return xs, b * d * (a + b) / (a * c * (c + d))


def conserved_by_sympy(I, xs, comps, seed, den_max, eps=sympy.Rational(1, 10), points=2):
    """I(x~) == I(x) at ``points`` random rational points, x~ by SymPy's Kahan step (not the code under test)."""
    rng = random.Random(seed)
    for _ in range(points):
        x = [sympy.Rational(rng.randint(1, 9), rng.randint(1, den_max)) for _ in xs]
        y = kahan_step(xs, comps, eps, x)
        assert sympy.simplify(I.subs(dict(zip(xs, y))) - I.subs(dict(zip(xs, x)))) == 0
    return rng


def sympy_poly(d, xs):
    """The polynomial of a {exponents: coefficient} dict, in SymPy."""
    return sum(sympy.Rational(c.numerator, c.denominator) * sympy.Mul(*[v ** k for v, k in zip(xs, e)])
               for e, c in d.items())


def test_the_golden_kqv_integral_is_conserved():
    xs, comps = sympy_field(chain(6))
    _, I = kqv_integral(6, 4)
    conserved_by_sympy(I, xs, comps, seed=3, den_max=4)


def _fitter_of(system, sub_texts, known=(), max_bytes=None, seed=0):
    """(fitter, key, gradient, pivots, fld) of the kernel of one sparse candidate set along a random orbit."""
    from exact_khk.diagnostics.kernels import _point, parse_monomials

    sysobj, fld = resolve_field(system, "f")
    sub = parse_monomials(sub_texts, [f"x{i}" for i in range(fld.dim)])
    steps, margin, p = len(sub) + 16, 8, random_primes(1, seed)[0]
    x0 = _point(random.Random(seed), fld.dim)
    data = entry_jacobian(fld, F(1, 10), x0, sub, steps, p, seed)
    assert data is not None and len(data[1]) == 1
    key, grad = sorted(data[3].items())[0]
    fitter = EntryFitter(fld, F(1, 10), sub, steps, data[0], seed, margin, known, max_bytes=max_bytes)
    return fitter, key, grad, data[0], fld, sub, steps, p


def test_fit_in_the_entrys_own_variables_recovers_a_golden_integral():
    """KQV N = 6: the kernel vector supported on x1*x3, x1*x4, x2*x4 (0-based names) has entries that
    depend on 4 of the 6 variables only; the fit in those variables at degree 3 (70 unknowns, against
    168 in all 6) is a function of the golden integral of x0..x3 (the same level sets), conserved by
    SymPy's Kahan step."""
    fitter, key, grad, _, fld, *_ = _fitter_of(chain(6), ["x0*x2", "x0*x3", "x1*x3"])
    p = random_primes(1, 0)[0]
    own = [l for l in range(6) if grad[l] % p]
    assert own == [0, 1, 2, 3]
    primes = random_primes(4, 1)
    assert fitter.fit(key, 2, primes, 0, own) is None  # degree 3 is needed
    num, den = fitter.fit(key, 3, primes, 0, own)
    assert all(not e[4] and not e[5] for e in list(num) + list(den))
    xs, comps = sympy_field(chain(6))
    fitted = sympy_poly(num, xs) / sympy_poly(den, xs)
    _, golden = kqv_integral(6, 3)
    rng = conserved_by_sympy(fitted, xs, comps, seed=5, den_max=4)
    # functionally dependent on the golden integral: their gradients are parallel at a point
    x = {v: sympy.Rational(rng.randint(1, 9), rng.randint(1, 4)) for v in xs}
    J = sympy.Matrix([[sympy.diff(f, v).subs(x) for v in xs] for f in (fitted, golden)])
    assert J.rank() == 1


def test_line_restriction_prunes_fits_that_cannot_succeed():
    """The entry on a random line over F_p has the degree of the fitted N/D (3); fits of lower degree are
    refused by the line (no pair beyond the vanishing ones), the right one admitted; a degree bound
    below it says so (A = None)."""
    fitter, key, grad, pivots, fld, sub, steps, p = _fitter_of(chain(6), ["x0*x2", "x0*x3", "x1*x3"])
    line = entry_line(fld, F(1, 10), sub, steps, pivots, key, p, random.Random(2), 8)
    assert line.degree == 3
    assert not line.admits([], 2, 0) and line.admits([], 3, 0)
    low = entry_line(fld, F(1, 10), sub, steps, pivots, key, p, random.Random(2), 2)
    assert low.A is None and low.degree is None
    # with the sum L = x0 + ... + x5 known (degree 1 on the line): degree 1 with coefficients of degree 1
    # in L reaches only degree 2 on the line: refused; degree 2 with J = 1 reaches 3 and is admitted (the
    # line is a necessary condition: one variable t cannot tell x from L)
    L = line.restrict({tuple(int(i == j) for i in range(6)): F(1) for j in range(6)})
    one = line.restrict({(0,) * 6: F(1)})
    assert not line.admits([(L, one)], 1, 1)
    assert line.admits([(L, one)], 2, 1)


def test_restrict_is_evaluation_on_the_line():
    p = random_primes(1, 0)[0]
    line = EntryLine(p, [3, 5], [7, 11])
    f = line.restrict({(2, 0): F(1, 2), (1, 1): F(-3), (0, 0): F(4)})
    for t in (0, 1, 17):
        x, y = 3 + 7 * t, 5 + 11 * t
        assert int(f(t)) == (x * x * pow(2, -1, p) - 3 * x * y + 4) % p


def test_fit_memory_is_planned_and_refused_before_any_work():
    fitter, key, grad, *_ = _fitter_of(chain(6), ["x0*x2", "x0*x3", "x1*x3"], max_bytes=10_000)
    with pytest.raises(FitTooLarge, match="EXACT_KHK_MAX_MEMORY") as exc:
        fitter.fit(key, 3, random_primes(3, 1), 0)
    assert isinstance(exc.value, InputError)
    assert fitter.starts == []  # refused before any orbit was drawn
    assert fit_bytes(70, 78) == 160 * 70 * 78


def test_search_with_fits_beyond_the_memory_limit_says_so(monkeypatch, capsys):
    """Kernels fit in 100 kB (their bases 79 kB), the fits do not (70 unknowns at degree 3 in 4 variables:
    874 kB planned): the search goes on without them and says so; exit 0."""
    res = find_integrals(chain(5), degree=2, eps="1/10", max_bytes=100_000)
    assert any("EXACT_KHK_MAX_MEMORY" in w for w in res.warnings)
    assert check_found(chain(5), res, "1/10", points=1) == len(res.integrals) == res.independent
    monkeypatch.setenv("EXACT_KHK_MAX_MEMORY", "100K")
    assert main(["find-integrals", "--system", chain(5), "--quiet"]) == 0
    assert "Traceback" not in capsys.readouterr().err


def test_kqv_chain_every_integral():
    """KQV N = 6: the kernel shows 5; all 5 are extracted, each conserved by SymPy's Kahan step, their
    SymPy Jacobian of rank 5."""
    res = find_integrals(chain(6), degree=2, eps="1/10")
    assert res.visible == 5 and len(res.integrals) == 5 and res.independent == 5
    assert check_found(chain(6), res, "1/10", points=1) == 5


def test_fits_in_few_variables_have_few_unknowns():
    from exact_khk.diagnostics.integrals import fit_shapes

    assert fit_shapes(20, 0, 3, {(): 4}) == [((), 1, 0), ((), 2, 0), ((), 3, 0)]
    assert len(monomials(4, 3)) == 35


@pytest.mark.slow
def test_kqv_chain_n10_every_integral_certified(tmp_path, capsys):
    """KQV N = 10: the kernel shows 9; all 9 extracted, conserved by SymPy's Kahan step, SymPy Jacobian rank 9,
    and `certify` of the system file --toml writes is VALID (exit 0)."""
    out = tmp_path / "kqv10.toml"
    assert main(["find-integrals", "--system", chain(10), "--toml", str(out), "--quiet"]) == 0
    res = find_integrals(chain(10), degree=2, eps="1/10")
    assert res.visible == 9 and len(res.integrals) == 9 and res.independent == 9
    assert check_found(chain(10), res, "1/10", points=1) == 9
    capsys.readouterr()
    assert main(["certify", "--system", str(out), "--quiet"]) == 0
    assert "VALID" in capsys.readouterr().out


def test_solve_with_numerator_and_denominator_over_different_monomials():
    """EntryFitter.solve, as the HK-basis route calls it: on the Euler top's circuit {x², z², 1} the entry
    c_{x²}/c_1 is fitted with N over {1, z²} and D over the even monomials of degree <= 2; the pair is
    conserved by SymPy's Kahan step.  Negative control: with D over {1, x²}, which cannot hold the
    denominator, no pair is returned."""
    euler = "euler-top"
    _, fld = resolve_field(euler, "f")
    sub = [(2, 0, 0), (0, 0, 2), (0, 0, 0)]
    primes = list(random_primes(4, 1))
    fitter = EntryFitter(fld, F(1, 10), sub, 12, (0, 1), 0, 4)
    even = [e for e in monomials(3, 2) if not any(k % 2 for k in e)]
    num, den = fitter.solve((0, 2), [(0, 0, 0), (0, 0, 2)], even, primes)
    assert set(num) <= {(0, 0, 0), (0, 0, 2)} and set(den) <= set(even) and len(den) > 1
    xs, comps = sympy_field(euler)
    # the entry depends on the map's ε, the one the fitter was given (1/10)
    conserved_by_sympy(sympy_poly(num, xs) / sympy_poly(den, xs), xs, comps, seed=2, den_max=5)
    assert fitter.solve((0, 2), [(0, 0, 0), (0, 0, 2)], [(0, 0, 0), (2, 0, 0)], primes) is None


def test_supports_are_fitted_in_order_of_their_entries_variables(monkeypatch):
    """KQV N = 8: the sparse kernel vectors are taken by the fewest variables a non-constant entry depends on
    (its gradient mod p), not by the variables of their candidates: the first ones have an entry in at most
    4 variables, and the support x1*x3, x1*x4, x2*x4 (entries in x1..x4 only, as the golden integral of
    test_fit_in_the_entrys_own_variables_recovers_a_golden_integral) comes before every support whose
    entries all depend on all 8 variables, among them supports of 3 candidates in fewer variables.  The
    gradients computed from one shared orbit equal those computed alone."""
    from exact_khk.diagnostics import integrals
    from exact_khk.diagnostics.kernels import monomial_text

    seen = {}

    def capture(self, ref, found, fit_degree, plist, seed, *rest):
        seen["subs"] = self.ordered_supports([], ref, plist[0], seed)
        seen["args"] = (self.fld, self.eps, ref.x0, self.steps, plist[0], seed)
        return (), 0, None, None

    monkeypatch.setattr(integrals._Job, "complete", capture)
    find_integrals(chain(8), degree=2, eps="1/10")
    own = [min(sum(1 for g in grad if g) for grad in data[3].values() if any(grad)) for _, data in seen["subs"]]
    assert own == sorted(own) and own[0] <= 4
    names = [sorted(monomial_text(e, [f"x{i}" for i in range(1, 9)]) for e in sub) for sub, _ in seen["subs"]]
    first = names.index(["x1*x3", "x1*x4", "x2*x4"])
    assert own[first] == 4
    full = [i for i, (sub, data) in enumerate(seen["subs"]) if all(sum(1 for g in grad if g) == 8
                                                                   for grad in data[3].values() if any(grad))]
    assert full and first < min(full)
    assert any(len(seen["subs"][i][0]) == 3 for i in full)  # 3 candidates, entries in all 8 variables
    fld, eps, x0, steps, p, seed = seen["args"]
    for sub, data in seen["subs"][:5] + seen["subs"][-5:]:
        assert entry_jacobian(fld, eps, x0, sub, steps, p, seed) == data
