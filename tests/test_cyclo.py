"""cyclo:N — exact arithmetic in Q(ζ_N), involutions over Q(ω), Liouville integrability."""

import re
from fractions import Fraction

import pytest

from exact_khk import InputError, KahanMap, LiePoissonSystem, NotRationalError, get_arith
from .conftest import EXACT
from exact_khk.arith.cyclotomic import CycloNumber, cyclotomic_field
from exact_khk.systems.lie_poisson.invariants import grad_Htilde
from exact_khk.certification.identities import integral_patterns, involution_patterns
from exact_khk.certification.lie_poisson import liouville
from exact_khk.systems.lie_poisson.invariants import Htilde
from exact_khk.systems.lie_poisson.system import (DEFAULT_X0, default_system, involution_circulant,
                               involution_circulant_cyclotomic, rational_sign_patterns, random_point)

# --- the field ---------------------------------------------------------------


@pytest.mark.parametrize("N", [1, 2, 3, 4, 5, 6, 8, 12])
def test_zeta_is_a_primitive_root_of_unity(N):
    K = get_arith(f"cyclo:{N}")
    z = K.gen
    assert z ** N == 1
    assert all(z ** k != 1 for k in range(1, N))
    assert sum((z ** k for k in range(N)), K.zero) == (1 if N == 1 else 0)


def test_field_arithmetic_and_printing():
    K = get_arith("cyclo:3")
    z = K.gen
    assert K.format(z * z) == "-1 - z" and K.format(K(Fraction(1, 3)) - 2 * z / 3) == "1/3 - 2/3*z"
    assert K.format(K.zero) == "0" and K.format(-z) == "-z" and str(z ** 2 * 3) == "-3 - 3*z"
    a = (2 - z) / 7
    assert a * (1 / a) == 1 and (a / a) == K.one and a - a == 0
    assert K(Fraction(3, 4)) == Fraction(3, 4) and hash(K(Fraction(3, 4))) == hash(Fraction(3, 4))
    assert len({K(2), K(2) + 0 * z, 2 * K.one}) == 1
    i = get_arith("cyclo:4").gen
    assert i * i == -1 and 1 / i == -i
    with pytest.raises(ZeroDivisionError):
        a / K.zero
    with pytest.raises(ZeroDivisionError):
        1 / (z - z)
    with pytest.raises(TypeError):
        K.to_fraction(z)
    assert K.exact and K.is_zero(K.zero) and not K.is_zero(z)


def test_embedding_between_cyclotomic_fields():
    z3, K6 = get_arith("cyclo:3").gen, get_arith("cyclo:6")
    assert K6(z3) == K6.gen ** 2                   # ζ_3 = ζ_6²
    assert K6(z3) * K6.gen == K6.gen ** 3 == -1
    assert z3 * K6.gen == K6.gen * z3 == -1 and z3 == K6.gen ** 2 and 1 / z3 - K6.gen ** 4 == 0
    with pytest.raises(TypeError, match="cannot mix"):
        z3 + get_arith("cyclo:4").gen
    with pytest.raises(InputError, match="multiple of 3"):
        get_arith("cyclo:4")(z3)
    with pytest.raises(InputError, match="N >= 1"):
        get_arith("cyclo:0")


def test_non_rational_numbers_are_refused_by_rational_arithmetics():
    z = get_arith("cyclo:5").gen
    for name in ("fraction", "flint", "gmpy2", "float", "mp:64"):
        with pytest.raises(NotRationalError, match="not rational"):
            get_arith(name)(z + 1)
        assert get_arith(name)(z - z + Fraction(1, 2)) == get_arith(name)(Fraction(1, 2))


# --- involutions over Q(ω) ------------------------------------------------------------


@pytest.mark.parametrize("n", range(2, 9))
def test_every_sign_pattern_gives_an_involution_with_its_eigenvalues(n):
    K = cyclotomic_field(n)
    w = K.zeta_power(1)
    rational = set(rational_sign_patterns(n))
    for s in involution_patterns(n) + ["+" * n, "-" * n]:
        alpha = involution_circulant_cyclotomic(n, s)
        B = [[alpha[(j - i) % n] for j in range(n)] for i in range(n)]   # Σ α_k P^k
        B2 = [[sum((B[i][k] * B[k][j] for k in range(n)), K.zero) for j in range(n)]
              for i in range(n)]
        assert all(B2[i][j] == int(i == j) for i in range(n) for j in range(n)), s
        for j, sj in enumerate(1 if c == "+" else -1 for c in s):   # B v_j = s_j v_j
            v = [w ** (j * k) for k in range(n)]
            assert all(sum((B[r][k] * v[k] for k in range(n)), 0 * w) == sj * v[r] for r in range(n)), (s, j)
        if s in rational:
            assert alpha == involution_circulant(n, s)
        else:
            assert any(not a.is_rational() for a in alpha)


def test_non_rational_field_needs_the_cyclotomic_flag():
    s = LiePoissonSystem.random(5, 1)
    with pytest.raises(NotRationalError):
        s.field("g", "-+-++")
    g = s.field("g", "-+-++", cyclotomic=True)
    assert any(isinstance(t, CycloNumber) for row in g.hessian for t in row)
    assert s.field("g", "-++++", cyclotomic=True) is s.field("g", "-++++")   # rational: unchanged
    with pytest.raises(NotRationalError):
        KahanMap(g, "1/10", "flint").step(random_point(5, 1))


# --- exact regressions against an independent solver (SymPy's algebraic fields) -------


def _sympy_step(system, signs, x, eps, N):
    """Φ_g(x) by SymPy: B = Σ_j s_j Π_j built from its definition, g'(x) = J(x)M +
    [J(e_k) y, 0] (docs/conventions.md), and DomainMatrix.lu_solve over QQ<exp(2πi/N)>."""
    from sympy import I, QQ, exp, pi
    from sympy.polys.matrices import DomainMatrix

    n = system.n
    K = QQ.algebraic_field(exp(2 * pi * I / N))
    z = K.from_sympy(exp(2 * pi * I / N))
    w = z ** (N // n)
    q = lambda t: K.from_sympy(t) if not isinstance(t, Fraction) else K(t.numerator) / K(t.denominator)  # noqa: E731
    sg = [1 if c == "+" else -1 for c in signs]
    Pc = [[sum((K(sg[j]) * w ** ((-j * ((c - r) % n)) % n) for j in range(n)), K.zero) / K(n)
           for c in range(n)] for r in range(n)]
    B = [[Pc[r % n][c % n] if (r < n) == (c < n) else K.zero for c in range(2 * n)] for r in range(2 * n)]
    Hs = [[q(t) for t in row] for row in system.hessian]
    M = (DomainMatrix(B, (2 * n, 2 * n), K) * DomainMatrix(Hs, (2 * n, 2 * n), K)).to_list()
    X = [q(t) for t in x]
    J = lambda v: [[v[(i + j) % n] if (i < n and j >= n) else (-v[(i + j) % n] if (i >= n and j < n) else K.zero)  # noqa: E731
                    for j in range(2 * n)] for i in range(2 * n)]
    Jx = DomainMatrix(J(X), (2 * n, 2 * n), K)
    Md = DomainMatrix(M, (2 * n, 2 * n), K)
    y = (Md * DomainMatrix([[t] for t in X], (2 * n, 1), K)).to_list()
    D = (Jx * Md).to_list()
    for k in range(n):
        e = [K.one if i == k else K.zero for i in range(2 * n)]
        col = (DomainMatrix(J(e), (2 * n, 2 * n), K) * DomainMatrix(y, (2 * n, 1), K)).to_list()
        for i in range(2 * n):
            D[i][k] += col[i][0]
    L = [[(K.one if i == j else K.zero) - q(eps) * D[i][j] for j in range(2 * n)] for i in range(2 * n)]
    sol = DomainMatrix(L, (2 * n, 2 * n), K).lu_solve(DomainMatrix([[t] for t in X], (2 * n, 1), K))
    return [list(reversed([Fraction(int(c.numerator), int(c.denominator)) for c in sol[i, 0].element.to_list()]))
            for i in range(2 * n)]


@pytest.mark.parametrize("n, signs, N", [(3, "+-+", 3), (4, "+-++", 4), (5, "-+-++", 5), (3, "++-", 6)])
def test_step_matches_sympy_algebraic_field(n, signs, N):
    system = default_system() if n == 3 else LiePoissonSystem.random(n, seed=n)
    x = DEFAULT_X0 if n == 3 else random_point(n, 2)
    x = [Fraction(t) for t in x]
    ar = get_arith(f"cyclo:{N}")
    y = KahanMap(system.field("g", signs, cyclotomic=True), "1/10", ar).step(x)
    expected = _sympy_step(system, signs, x, Fraction(1, 10), N)
    got = [[Fraction(int(c.p), int(c.q)) for c in t.p.coeffs()] for t in y]
    assert got == expected
    assert any(len(c) > 1 for c in got)        # genuinely not rational


def test_regression_values_in_q_zeta3():
    # a fixed value (from the SymPy cross-check above), kept as an exact string
    ar = get_arith("cyclo:3")
    y = KahanMap(default_system().field("g", "+-+", cyclotomic=True), "1/10", ar).step(DEFAULT_X0)
    assert ar.format(y[0]) == "8923780/9706347 - 1413800/1078483*z"


# --- gradients: closed form against SymPy differentiation ------------------------------


@pytest.mark.parametrize("n", [2, 3])
def test_grad_htilde_matches_symbolic_derivative(n):
    import sympy as sp

    system = LiePoissonSystem.random(n, seed=10 + n)
    x = [Fraction(t) for t in random_point(n, 3)]
    eps = Fraction(1, 3)
    t = sp.Symbol("t")
    Hs = sp.Matrix(system.hessian).applyfunc(sp.nsimplify)
    expected = []
    for k in range(2 * n):     # d/dt H̃(x + t e_k) at t = 0, one symbol only
        pt = [sp.nsimplify(v) + (t if i == k else 0) for i, v in enumerate(x)]
        J = sp.Matrix(system.J(pt))
        R = sp.eye(2 * n) - sp.nsimplify(eps) ** 2 * (Hs * J) ** 2
        H = (sp.Matrix(pt).T * R.LUsolve(Hs * sp.Matrix(pt)))[0]
        expected.append(Fraction(str(sp.diff(H, t).subs(t, 0))))
    assert grad_Htilde(system.field("f"), x, eps, "fraction") == expected


# --- complete Liouville integrability, exact in Q(ζ_N) --------------------------------


def _check(records, n=None, patterns=None, pairs="all"):
    """Every claim holds and the family's four controls fail; the claims cover conservation of every
    integral by every map, commutation (of every pair of maps), ∇K~ = B∇H~ and the brackets of every
    pair of the n + 1 integrals (H~ and the n K~_j), and the rank."""
    for r in records:
        assert r.passed, r
    names = [r.name.removeprefix("identity: ") for r in records]
    controls = [r for r in records if not r.expected]
    assert [r.holds for r in controls] == [False] * 4 and all(r.residual != "0" for r in controls)
    if n is not None:
        maps = 1 + len(involution_patterns(n) if patterns is None else patterns)
        integrals = 1 + len([s for s in integral_patterns(n) if s != "+" * n])
        assert sum(x.startswith("integral ") and " conserved by Phi_" in x for x in names) == integrals * maps
        assert sum(x.startswith("commutation ") for x in names) == (maps * (maps - 1) // 2 if pairs == "all"
                                                                    else maps - 1)
        assert sum(x.startswith("involution {") for x in names) == integrals * (integrals - 1)
        assert any(x.startswith("rank of integral gradients") for x in names)


def test_paper_6d_example_with_b0_b1_b2():
    """2n = 6: the three involutions B_0, B_1, B_2 (sign patterns; the printed 𝓑_1
    block is the misprinted B_2 = B_{n-1}, docs/conventions.md, misprint 4) in Q(ζ_3) and Q(ζ_6)."""
    system = default_system()
    assert integral_patterns(3) == ["-++", "+-+", "++-"]
    for N in (3, 6):
        recs = liouville(system, DEFAULT_X0, "1/10", f"cyclo:{N}", steps=3, patterns=integral_patterns(3))
        _check(recs, 3, integral_patterns(3))
        assert recs[0].evidence == f"exact in Q(zeta_{N})" and recs[0].detail == "checked at 3 orbit points"
        rank = next(r for r in recs if r.name.startswith("rank of integral gradients (H~"))
        assert rank.residual == "rank 3" and rank.detail == "rank 3 at 4 of 4 points"


@pytest.mark.parametrize("n, pairs, steps", [(2, "all", 1), (3, "all", 1), (4, "all", 1), (5, "f", 1)])
def test_liouville_exact_all_involutions(n, pairs, steps):
    system = LiePoissonSystem.random(n, seed=n)
    _check(liouville(system, random_point(n, 1), "1/7", f"cyclo:{n}", steps=steps, pairs=pairs), n, pairs=pairs)


def test_liouville_at_a_singular_step_is_inconclusive_and_names_it(capsys):
    """At x0 = (0, -3, 2, 3, 3, 0, 2, 3) Phi_f is singular at Phi_g[++-+](x_0): the commutation of
    the two maps is undecided there (certify's rule: a point where a side is undefined is skipped
    and listed), so liouville ends INCONCLUSIVE (exit 4); the singular step is re-checked directly."""
    from exact_khk.cli.main import main
    from exact_khk.errors import SingularStepError

    given = "0,-3,2,3,3,0,2,3"
    assert main(["liouville", "--n", "4", "--seed", "1", "--x0", given, "--quiet"]) == 4
    out = capsys.readouterr().out
    assert "??   commutation Phi_f o Phi_g[++-+]" in out and "Kahan step undefined" in out
    system, ar = LiePoissonSystem.random(4, 1), get_arith("cyclo:4")
    x0 = [Fraction(t) for t in given.split(",")]
    y = KahanMap(system.field_for_signs("++-+"), "1/10", ar).step(x0)
    with pytest.raises(SingularStepError):
        KahanMap(system.field("f"), "1/10", ar).step(y)
    KahanMap(system.field("f"), "1/10", ar).step(x0)  # x_0 itself is regular for Phi_f


def test_liouville_pole_is_skipped_and_listed(capsys):
    """exact-khk liouville --n 4 --seed 6 meets a pole of H~ at x_2 = Phi_f(x_1): the point is
    skipped and listed by each check that needs it (the others decide), and the pole is re-checked
    directly."""
    from exact_khk.cli.main import main
    from exact_khk.errors import PoleError

    assert main(["liouville", "--n", "4", "--seed", "6", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "skipped k = [2], where undefined (first: H~ has a pole at x = " in out
    system = LiePoissonSystem.random(4, 6)
    x2 = KahanMap(system.field("f"), "1/10", "fraction").orbit(random_point(4, 6, system=system), 2)[2]
    with pytest.raises(PoleError):
        Htilde(system.field("f"), x2, "1/10", "fraction")


@pytest.mark.slow
@pytest.mark.parametrize("n", [5, 6, 7, 8])
def test_liouville_exact_all_involutions_large_n(n):
    system = LiePoissonSystem.random(n, seed=n)
    pairs = "all" if n <= 6 else "f"
    _check(liouville(system, random_point(n, 1), "1/7", f"cyclo:{n}", steps=1, pairs=pairs), n, pairs=pairs)


def test_rational_arithmetic_keeps_rational_involutions():
    # n = 4 in Q: only rational patterns; the full set of integrals needs cyclo:4
    system = LiePoissonSystem.random(4, seed=4)
    pats = [p for p in rational_sign_patterns(4) if p not in ("++++", "----")]
    with pytest.raises(InputError, match="not a rational involution"):
        liouville(system, random_point(4, 1), "1/7", "flint", steps=1, patterns=pats)


def test_integrals_are_exact_in_every_field_containing_omega():
    system = default_system()
    g = system.field("g", "+-+", cyclotomic=True)
    vals = {N: Htilde(g, [get_arith(f"cyclo:{N}")(Fraction(t)) for t in DEFAULT_X0], "1/10", f"cyclo:{N}")
            for N in (3, 6, 12)}
    assert get_arith("cyclo:12")(vals[3]) == get_arith("cyclo:12")(vals[6]) == vals[12]


@pytest.mark.parametrize("name", EXACT + ["cyclo:2", "cyclo:4", "gf:1000003"])
def test_n2_liouville_in_every_exact_arithmetic(name):
    """n = 2: all involutions are rational, so every exact arithmetic certifies the
    claims, and the controls fail in each of them."""
    system = LiePoissonSystem.random(2, seed=7)
    _check(liouville(system, random_point(2, 3), "1/5", name, steps=2), 2)


# --- command line -----------------------------------------------------------------------


def test_cli_liouville_cyclo(capsys):
    import json

    from exact_khk.cli.main import main

    assert main(["liouville", "--arith", "cyclo:3", "--involutions", "basis", "--steps", "1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["ok"] and out["status"] == "VALID" and out["involutions"] == ["-++", "+-+", "++-"]
    holds = {r["name"]: r["holds"] for r in out["records"]}
    assert holds["control: commutation with non-associated field"] is False
    assert holds["involution {K~[-++],K~[++-]}_Pi"] is True
    assert all(r["evidence"] == "exact in Q(zeta_3)" for r in out["records"])
    assert main(["liouville", "--arith", "flint", "--steps", "1"]) == 2
    assert "is not a rational involution" in capsys.readouterr().err


def test_liouville_reports_progress_by_check():
    """``progress(name)`` hears each check before it runs, at points and over F_P."""
    system = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")
    seen = []
    recs = liouville(system, arith=f"gf:{4611686018420360881}", trials=1, seed=1, progress=seen.append)
    assert all(r.passed for r in recs) and seen[0] == "integral H~ conserved by Phi_f"
    assert [r.name for r in recs] == [f"identity: {name}" for name in seen]
    seen.clear()
    recs = liouville(system, DEFAULT_X0, "1/10", "cyclo:3", steps=1, progress=seen.append)
    assert [r.name for r in recs] == seen


@pytest.mark.parametrize("n", range(2, 13))
def test_expresses_omega_is_whether_every_entry_of_an_involution_converts(n):
    """The one-conversion probe (ζ_n) agrees with converting every entry of the involution
    with s_1 = −1 alone (the definition), over rational, cyclotomic and finite-field arithmetics."""
    from exact_khk.systems.lie_poisson.system import expresses_omega

    probe = "+-" + "+" * (n - 2)
    entries = involution_circulant_cyclotomic(n, probe)
    for name in ("flint", "fraction", f"cyclo:{n}", f"cyclo:{2 * n}", f"cyclo:{n + 1}", "gf:13", "gf:101",
                 "gf:1009", "gf:2521"):
        ar = get_arith(name)
        try:
            for t in entries:
                ar.convert(t)
            every = True
        except (TypeError, ValueError, ArithmeticError):
            every = False
        assert expresses_omega(ar, n) is every, (n, name)


@pytest.mark.parametrize("N", [1, 2, 3, 4, 5, 7, 12])
def test_native_solve_over_q_zeta(N):
    # the rational system of φ(N) times the size solves M X = B: checked by the residual
    # M X - B = 0 over Q(ζ_N) and against elimination over Q(ζ_N) itself
    import random

    import flint

    from exact_khk.linalg import dense
    ar, rng = get_arith(f"cyclo:{N}"), random.Random(N)
    K = ar.K

    def rnd():
        return K.element(flint.fmpq_poly([flint.fmpq(rng.randint(-9, 9), rng.randint(1, 9))
                                          for _ in range(K.degree)]))

    M = [[rnd() for _ in range(4)] for _ in range(4)]
    B = [[rnd(), Fraction(-1, 3)] for _ in range(4)]              # a rational column too
    X = ar.native_solve(M, B)
    assert all(sum((M[i][k] * X[k][j] for k in range(4)), K.zero) == B[i][j] for i in range(4) for j in range(2))
    LU, perm = dense.lu_factor(ar, M)
    assert X == dense.lu_solve(LU, perm, B)


def test_native_solve_refuses_a_matrix_singular_over_q_zeta_only():
    from exact_khk.errors import SingularMatrix
    from exact_khk.linalg import dense
    ar = get_arith("cyclo:5")
    z = ar.gen
    with pytest.raises(SingularMatrix):                            # det = ζ·ζ − ζ²·1 = 0
        dense.solve(ar, [[z, z * z], [1, z]], [[1], [2]])
    X, _ = dense.solve(ar, [[z, z * z], [1, z + 1]], [[1], [2]])      # det = ζ: x_2 = 2 − ζ⁻¹
    assert X[1][0] == 2 - 1 / z and X[0][0] == (1 - z * z * X[1][0]) / z


@pytest.mark.parametrize("n, signs, N", [(3, "+-+", 3), (4, "+-++", 8), (5, "-+-++", 5)])
def test_jacobian_by_linear_forms_is_the_generic_one(n, signs, N, monkeypatch):
    # f'(x) of a field with coefficients in Q(ω) at a point of Q(ζ_N) \\ Q: the fmpq_mat
    # products of CycloArith.apply_forms against the loops over CycloNumbers
    from exact_khk.arith.cyclotomic import CycloArith
    ar = get_arith(f"cyclo:{N}")
    system = default_system() if n == 3 else LiePoissonSystem.random(n, seed=n)
    fld = system.field("g", signs, cyclotomic=True)
    z = ar.gen
    x = [ar.convert(Fraction(k + 1, 3)) + (k - 2) * z ** (k % N) / 7 for k in range(2 * n)]
    fast = fld.jacobian(ar, x)
    eps = [ar.convert(Fraction(1, 10)), ar.convert(Fraction(-1, 10)), Fraction(1, 3) - z / 5]
    steps = [fld.step_matrix(ar, x, e) for e in eps]   # I − e f'(x) as affine forms per e
    monkeypatch.setattr(CycloArith, "linear_forms", None)
    slow = fld.jacobian(ar, x)
    assert fast == slow and any(not t.is_rational() for row in fast for t in row)
    N2 = 2 * n
    for e, M in zip(eps, steps):
        assert M == [[(1 if i == j else 0) - e * slow[i][j] for j in range(N2)] for i in range(N2)]
        assert M == fld.step_matrix(ar, x, e)                      # the generic route, forms off


@pytest.mark.parametrize("N", [1, 2, 3, 5, 8, 12])
def test_native_matmul_is_the_generic_product(N):
    import random

    import flint

    from exact_khk.linalg import dense
    ar, rng = get_arith(f"cyclo:{N}"), random.Random(N)

    def rnd():
        return ar.K.element(flint.fmpq_poly([flint.fmpq(rng.randint(-9, 9), rng.randint(1, 9))
                                             for _ in range(ar.K.degree)]))

    A = [[rnd() for _ in range(3)] for _ in range(2)]
    B = [[rnd(), 0, Fraction(1, 2), rnd()] for _ in range(3)]           # plain rationals mixed in
    assert dense.matmul(A, B, ar) == dense.matmul(A, [[ar.convert(t) for t in row] for row in B])


def test_coefficient_linear_algebra_within_its_memory_bounds(monkeypatch):
    # a rational M is solved over Q; beyond the bounds of linalg.dense the generic loops and
    # elimination run (orbit --arith cyclo:10000: φ = 4000, a 24 000-square system otherwise)
    from exact_khk.linalg import dense
    ar = get_arith("cyclo:7")
    z = ar.gen
    M = [[Fraction(2), Fraction(1, 3)], [Fraction(-1), Fraction(5)]]
    B = [[z + 1], [z * z / 3]]
    X = ar.native_solve(M, B)
    assert all(sum((M[i][k] * X[k][0] for k in range(2)), ar.zero) == B[i][0] for i in range(2))
    assert dense.coefficients_native(ar, 2) and not dense.coefficients_native(get_arith("cyclo:10000"))
    assert not dense.coefficients_native(ar, dense.CYCLO_REGULAR_MAX_SIZE // 6 + 1)
    monkeypatch.setattr(dense, "CYCLO_REGULAR_MAX_SIZE", 0)          # every solve by elimination
    monkeypatch.setattr(type(ar), "native_solve", lambda *a: pytest.fail("native_solve past its bound"))
    M2 = [[z, ar.convert(1)], [ar.convert(2), z * z]]
    X2, _ = dense.solve(ar, M2, B)
    assert all(sum((M2[i][k] * X2[k][0] for k in range(2)), ar.zero) == B[i][0] for i in range(2))


@pytest.mark.parametrize("name", ["lotka-volterra", "euler-top", "cmoq-cubic"])
def test_step_matrix_forms_with_linear_terms(name, monkeypatch):
    # fields with linear parts (lotka-volterra, cmoq-cubic) and without: the affine forms of
    # I − ε f'(x) against the entrywise route, at a point and a step size of Q(ζ_3) \\ Q
    from exact_khk.arith.cyclotomic import CycloArith
    from exact_khk.systems.catalogue import resolve

    ar = get_arith("cyclo:3")
    fld, z = resolve(name).field("f"), ar.gen
    x = [ar.convert(Fraction(k + 2, 5)) - k * z / 3 for k in range(fld.dim)]
    e = Fraction(1, 7) + z / 2
    fast = fld.step_matrix(ar, x, e)
    monkeypatch.setattr(CycloArith, "linear_forms", None)
    J = fld.jacobian(ar, x)
    assert fast == [[(1 if i == j else 0) - e * J[i][j] for j in range(fld.dim)] for i in range(fld.dim)]


def test_dft_is_the_sum_over_powers_of_omega():
    """CycloArith.dft against the defining sums Σ_i w_i ω^(±ij), ω = ζ_N^(N/n), for every
    n | N (random elements of Q(ζ_12)); an n not dividing N is refused."""
    import random

    ar = get_arith("cyclo:12")
    rng = random.Random(3)
    for n in (1, 2, 3, 4, 6, 12):
        omega = ar.K.zeta_power(12 // n)
        rows = [[ar(Fraction(rng.randint(-5, 5), rng.randint(1, 4))) + ar.gen ** rng.randint(0, 11) * rng.randint(-3, 3)
                 for _ in range(n)] for _ in range(2)]
        for sign in (1, -1):
            want = [[sum((w[i] * omega ** (sign * i * j) for i in range(n)), ar.zero) for j in range(n)] for w in rows]
            assert ar.dft(rows, n, sign) == want, (n, sign)
    with pytest.raises(InputError, match="n must divide 12"):
        ar.dft([[1] * 5], 5)
