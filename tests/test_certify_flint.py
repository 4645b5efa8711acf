"""The flint route of the Lie–Poisson certificate (systems/lie_poisson/flint_forms.py,
linalg/flintmat.py, the flint branch of grad_Htilde): every quantity equals (``==``)
its generic counterpart — lists of rows, dual-number derivatives, the dense H̃ — at
random rational points, and certificates are the same check for check."""

import random
from fractions import Fraction as F

import flint
import pytest

from exact_khk import KahanMap, LiePoissonSystem, certify, get_arith
from exact_khk.linalg.dual import jacobian
from exact_khk.certification.checks import jacobiator
from exact_khk.systems.lie_poisson.flint_forms import FlintForms
from exact_khk.linalg.dense import matmul, transpose
from exact_khk.systems.lie_poisson.dihedral import BlockMatrix, Mixed
from exact_khk.certification.lie_poisson import htilde_definition
from exact_khk.linalg.flintmat import rank, rows, uses_flint
from exact_khk.systems.lie_poisson.invariants import (Htilde, Pi, Pi_from_q, grad_Htilde, grad_Htilde_dual,
                                                      q_coefficients)
from exact_khk.systems.lie_poisson.system import random_point, rational_sign_patterns

FL, FR = get_arith("flint"), get_arith("fraction")


def _case(n, seed):
    rng = random.Random(seed)
    s = LiePoissonSystem.random(n, seed)
    x = [FL(F(rng.randint(-9, 9), rng.randint(1, 7))) for _ in range(2 * n)]
    return s, x, FL(F(1, rng.randint(2, 20)))


def _involutions(s):
    n = s.n
    signs = [p for p in rational_sign_patterns(n) if p not in ("+" * n, "-" * n)]
    return {"f": (s.field("f"), None)} | {p: (s.field("g", p), s.involution(p)) for p in signs}


def test_uses_flint_only_for_fmpq_elements():
    assert uses_flint(FL)
    assert not any(uses_flint(get_arith(a)) for a in ("fraction", "gmpy2", "float", "mp:64", "cyclo:3"))


@pytest.mark.parametrize("n,seed", [(2, 1), (3, 2), (4, 3), (5, 4), (6, 5)])
def test_poisson_forms_equal_the_generic_ones(n, seed):
    s, x, e = _case(n, seed)
    fm = FlintForms(s, e)
    assert rows(fm.Pi(x)) == Pi(s, x, e, FL)
    assert rows(fm.Pi_from_q(x)) == Pi_from_q(s, x, e, FL)
    assert fm.Pi_sides(x) == ((), ())  # the formula holds
    assert fm.q(x) == q_coefficients(s, x, FL)
    # derivatives: closed forms against dual numbers
    N = 2 * n
    g = jacobian(FL, lambda d, xd: [t for row in Pi(s, xd, e, d) for t in row], x)[1]
    D, c = fm._dPi_int(x)  # what the dense Jacobi tensor uses: c ∂_mΠ, integer, for m < n
    assert [rows(flint.fmpq_mat(Dm) / c) for Dm in D] == [[[g[i * N + j][m] for j in range(N)] for i in range(N)]
                                                          for m in range(n)]
    assert all(g[i][m] == 0 for i in range(N * N) for m in range(n, N))  # Π does not depend on v
    assert fm.jacobiator(x) == jacobiator(FL, lambda d, xd: Pi(s, xd, e, d), x)
    assert fm.q_gradients(x) == jacobian(FL, lambda d, xd: q_coefficients(s, xd, d), x)[1]


@pytest.mark.parametrize("n,seed", [(2, 6), (3, 7), (4, 8), (5, 9)])
def test_kahan_jacobian_and_poisson_map_decision(n, seed):
    s, x, e = _case(n, seed)
    fm = FlintForms(s, e)
    for kind in ("f", "g", "control"):
        field = s.field(kind)
        assert rows(fm.field_jacobian(field, x)) == field.jacobian(FL, x)
        phi = KahanMap(field, e, FL)
        y = phi.step(x)
        D = phi.jacobian(x)
        assert rows(fm.dPhi(phi, x, y)) == D
        holds = matmul(matmul(D, Pi(s, x, e, FL)), transpose(D)) == Pi(s, y, e, FL)
        assert holds is (kind != "control")  # the control map is not Poisson for Pi
        assert fm.poisson_map_cleared(phi, x, y, fm.Pi_int(x), fm.Pi_int(y)) is holds
        # a false instance: Π(y) replaced by Π(x)
        assert fm.poisson_map_cleared(phi, x, y, fm.Pi_int(x), fm.Pi_int(x)) is False


def test_pi_sides_report_the_rational_residual_when_they_differ():
    s, x, e = _case(3, 10)

    class Broken(FlintForms):  # Π with one entry off by 1
        def Pi_int(self, x):
            Pz, c = super().Pi_int(x)
            Pz[0, 1] += c
            return Pz, c

    left, right = Broken(s, e).Pi_sides(x)
    diff = [a - b for a, b in zip(left, right)]
    assert diff[1] == 1 and all(d == 0 for i, d in enumerate(diff) if i != 1)
    assert left == [t for r in Pi(s, x, e, FL) for t in r][:1] + [Pi(s, x, e, FL)[0][1] + 1] + \
        [t for r in Pi(s, x, e, FL) for t in r][2:]


@pytest.mark.parametrize("n,seed", [(2, 11), (3, 12), (4, 13), (6, 14)])
def test_shared_integrals_and_gradients(n, seed):
    s, x, e = _case(n, seed)
    fm = FlintForms(s, e)
    inv = _involutions(s)
    assert fm.share_matrices(inv) == set(inv)  # the hypotheses are checked, and hold
    values = fm.integral_values(x)
    w = fm.htilde_adjoint(x)
    xq = [F(int(t.p), int(t.q)) for t in x]
    for key, (field, _) in inv.items():
        assert values[key] == Htilde(field, x, e, FL, method="dense")
        y = KahanMap(field, e, FL).step(x)
        assert fm.htilde_definition(x, y) == htilde_definition(field, x, e, FL, y)
        grad = fm.gradient(field, x, fm.htilde_solution(x, field), w)
        assert grad == grad_Htilde_dual(field, x, e, FL)  # dual numbers
        assert [F(int(t.p), int(t.q)) for t in grad] == grad_Htilde(field, xq, F(int(e.p), int(e.q)), FR)


def test_sharing_refused_for_a_matrix_that_does_not_commute():
    s, x, e = _case(3, 15)
    fm = FlintForms(s, e)
    not_involution = [[F(int(i == j)) for j in range(6)] for i in range(6)]
    not_involution[0][1] = F(1)
    assert fm.share_matrices({"f": (s.field("f"), None), "x": (s.field("g"), not_involution)}) == {"f"}


@pytest.mark.parametrize("n,seed", [(2, 1), (3, 3), (4, 2), (5, 1)])
def test_flint_grad_htilde_equals_dual_numbers(n, seed):
    s, x, e = _case(n, seed)
    for kind in ("f", "g", "control"):
        field = s.field(kind)
        assert grad_Htilde(field, x, e, FL) == grad_Htilde_dual(field, x, e, FL)


@pytest.mark.parametrize("n", [2, 4])
def test_flint_and_fraction_certificates_agree_check_for_check(n):
    s = LiePoissonSystem.random(n, seed=n)
    x0 = random_point(n, n)
    fast, plain = (certify(s, x0, "1/9", steps=3, arith=a) for a in ("flint", "fraction"))
    key = lambda c: [(k.name, k.holds, k.residual, k.applicable, k.detail) for k in c.checks]  # noqa: E731
    assert key(fast) == key(plain)
    assert fast.values == plain.values and fast.orbit == plain.orbit


@pytest.mark.parametrize("n,seed", [(2, 16), (3, 17), (4, 18), (6, 19)])
def test_circulant_hankel_blocks_equal_the_dense_integer_forms(n, seed):
    s, x, e = _case(n, seed)
    fm = FlintForms(s, e)
    Pb, c = fm.Pi_blocks(x)
    Pz, c2 = fm.Pi_int(x)
    assert c == c2 and Pb.dense() == Pz
    assert fm._jacobi_tensor_blocks(x) == fm._jacobi_tensor_dense(x)
    for kind in ("f", "g", "control"):
        field = s.field(kind)
        Mb = fm._hessian_blocks(field)
        assert Mb is not None and Mb.dense() == fm._hessian_int(field)[0]
        Fb, den = fm._field_jacobian_blocks(field, Mb, x)
        Fz, den2 = fm._field_jacobian_int(field, x)
        assert den == den2 and Fb.dense() == Fz
        phi = KahanMap(field, e, FL)
        y = phi.step(x)
        assert fm.poisson_map_blocks(phi, x, y, fm.Pi_blocks(x), fm.Pi_blocks(y)) is (kind != "control")
        assert fm.poisson_map_blocks(phi, x, y, fm.Pi_blocks(x), fm.Pi_blocks(x)) is False


def test_block_algebra_rules():
    """Products, sums and transposes of circulant/Hankel block matrices equal the dense ones."""
    rng = random.Random(7)
    for n in (2, 3, 5):
        def block(kind):
            return None if rng.random() < 0.2 else (kind, flint.fmpz_poly([rng.randint(-5, 5) for _ in range(n)]))
        for kinds in (("C", "X", "X", "C"), ("X", "C", "C", "X")):
            bs = [block(k) for k in kinds]
            M = BlockMatrix(n, [bs[:2], bs[2:]])
            for other in (M, M.T()):
                try:
                    prod = M * other
                except Mixed:  # a circulant plus a Hankel block has no such form
                    continue
                assert prod.dense() == M.dense() * other.dense()
            assert M.T().dense() == M.dense().transpose()
            assert (M + M).dense() == M.dense() * 2 and (M - M).dense() == M.dense() * 0


def test_certified_rank_equals_the_exact_rank():
    rng = random.Random(2)
    for _ in range(200):
        m, N = rng.randint(1, 7), rng.randint(1, 7)
        r = rng.randint(0, min(m, N))
        A = [[F(rng.randint(-5, 5), rng.randint(1, 4)) for _ in range(N)] for _ in range(r)]
        C = [[F(rng.randint(-3, 3), rng.randint(1, 3)) for _ in range(r)] for _ in range(m)]
        M = [[FL(sum((C[i][k] * A[k][j] for k in range(r)), F(0))) for j in range(N)] for i in range(m)]
        assert rank(M) == flint.fmpq_mat(m, N, [t for row in M for t in row]).rank()
    # a row independent over Q but dependent modulo the prime: the exact fallback
    from exact_khk.linalg.flintmat import RANK_PRIME
    assert rank([[1, 0], [2, 2 * RANK_PRIME]]) == 2 and rank([[1, 1], [RANK_PRIME + 1, 1]]) == 2


@pytest.mark.parametrize("n", [2, 3, 4])
def test_fast_forms_behind_the_claims_equal_the_generic_route(n):
    """In one arithmetic (flint), every record of the certificate with the family's fast forms
    (System.fast_forms) equals the record by the generic route (fast_forms None): the same exact
    residuals, verdicts and details; only the wording of how the q_l gradients were taken differs."""
    from exact_khk.certification.engine import certify_system

    class Generic(LiePoissonSystem):
        def fast_forms(self, ar, eps):
            return None

    s = LiePoissonSystem.random(n, seed=n)
    g = Generic(s.a, s.b, s.c)
    x0 = s.random_point(1)
    fast, plain = (certify_system(t.with_involutions(t.involutions(FL)), x0, "1/9", 4, "flint", poisson_points=3)
                   for t in (s, g))
    key = lambda c: [(k.name, k.claim.replace("closed form", "dual numbers"), k.holds, k.residual,  # noqa: E731
                      k.applicable, k.detail) for k in c.checks]
    assert key(fast) == key(plain) and len(fast.checks) > 20
    assert any("closed form" in k.claim for k in fast.checks)
    assert fast.values == plain.values and fast.orbit == plain.orbit


def test_a_wrong_fast_form_behind_the_claims_makes_the_certificate_invalid():
    """The claims decide with what the fast forms return: the integer Π (Pi_int) off by one
    antisymmetric pair fails the Π formula and the Π brackets, and nothing else (the Poisson-map
    claim takes Π by circulant blocks, Pi_blocks, here)."""
    from exact_khk.certification.engine import certify_system

    class Broken(FlintForms):
        def Pi_int(self, x):
            Pz, c = super().Pi_int(x)
            Pz[0, 1] += c
            Pz[1, 0] -= c
            return Pz, c

    class System(LiePoissonSystem):
        def fast_forms(self, ar, eps):
            return Broken(self, eps)

    s = LiePoissonSystem.random(3, seed=3)
    cert = certify_system(System(s.a, s.b, s.c), s.random_point(1), "1/9", 3, "flint")
    assert cert.status == "INVALID"
    failed = {k.name for k in cert.checks if k.expected and k.holds is False}
    assert failed == {"Poisson tensor Pi formula", "involution {H~,K~[+--]}_Pi", "involution {H~,K~[-++]}_Pi"}
