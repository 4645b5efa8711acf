"""gf:P — prime fields: reduction checks, cross-checks with Q and Q(ζ), Schwartz–Zippel."""

from fractions import Fraction

import flint
import pytest

from exact_khk import InputError, KahanMap, LiePoissonSystem, SingularStepError, get_arith
from exact_khk.arith.cyclotomic import BadReductionError
from exact_khk.certification.identities import cross_check_mod_p
from exact_khk.certification.lie_poisson import liouville
from exact_khk.systems.lie_poisson.system import DEFAULT_X0, default_system, random_point

P = 4611686018420360881            # prime, P ≡ 1 (mod 720720): ω exists for n ≤ 16


def test_prime_and_parameter_checks():
    assert flint.fmpz(P).is_prime() and (P - 1) % 720720 == 0
    for bad in ("gf:1", "gf:15", "gf:1000002"):
        with pytest.raises(InputError, match="prime"):
            get_arith(bad)
    F = get_arith("gf:7")
    assert F.exact and F.format(F(Fraction(-1, 3))) == "2"        # 3 * 2 = 6 = -1
    with pytest.raises(BadReductionError, match=r"1/14 has a denominator divisible by 7"):
        F(Fraction(1, 14))
    with pytest.raises(BadReductionError, match=r"a denominator of 8423 bits is divisible by 7 \(bad") as info:
        F(Fraction(1, 7 ** 3000))  # its size, not its 2 536 digits
    assert len(str(info.value)) < 200
    with pytest.raises(ZeroDivisionError):
        F.one / F.zero
    with pytest.raises(TypeError):
        F.to_fraction(F.one)


def test_roots_of_unity_and_compatible_embeddings():
    F = get_arith("gf:13")                          # 12 = 2^2 * 3
    for m in (1, 2, 3, 4, 6, 12):
        r = F.root_of_unity(m)
        assert r ** m == 1 and all(r ** k != 1 for k in range(1, m))
    K3, K12 = get_arith("cyclo:3"), get_arith("cyclo:12")
    z3 = K3.gen
    assert F(K12(z3)) == F(z3) == F(K12.gen) ** 4  # the same prime above 13 for every N
    a = (2 - z3) / 5 + z3 * z3
    assert F(a) == (2 - F(z3)) / 5 + F(z3) ** 2    # reduction is a ring homomorphism
    with pytest.raises(InputError, match=r"P ≡ 1 \(mod 5\)"):
        F(get_arith("cyclo:5").gen)


def test_involution_needs_p_congruent_one_mod_n():
    g = default_system().field("g", "+-+", cyclotomic=True)
    with pytest.raises(InputError, match=r"choose a prime P ≡ 1 \(mod 3\)"):
        KahanMap(g, "1/10", "gf:1000037").step(DEFAULT_X0)       # 1000037 ≡ 2 (mod 3)
    assert KahanMap(g, "1/10", "gf:1000003").step(DEFAULT_X0)    # 1000003 ≡ 1 (mod 3)


def test_singular_steps_are_detected_exactly_mod_p():
    """Find ε with det(I − εf'(x)) ≡ 0 mod p by brute force; the determinant is
    computed independently over Z (fmpq_mat) and reduced."""
    p, system = 101, default_system()
    x = [Fraction(t) for t in (1, 2, -1, 3, 0, 1)]
    F, Q = get_arith(f"gf:{p}"), get_arith("flint")
    fld = system.field("f")
    singular = []
    for e in range(1, p):
        L = KahanMap(fld, e, Q).system_matrix(KahanMap(fld, e, Q).point(x))
        det = flint.fmpq_mat(L).det()
        if int(det.p) % p == 0:
            singular.append(e)
            with pytest.raises(SingularStepError):
                KahanMap(fld, e, F).step(x)
        else:
            KahanMap(fld, e, F).step(x)
    assert singular       # the polynomial det has roots mod 101 for this x


# --- cross-checks with exact results ----------------------------------------------------


def test_rational_orbits_reduce_to_gf_orbits():
    system = LiePoissonSystem.random(4, seed=4)
    rat = ["-+++", "++-+", "-+-+"]                      # rational involutions for n = 4
    r = cross_check_mod_p(system, random_point(4, 1), "1/7", "flint", f"gf:{P}", steps=3, patterns=rat,
                          integral_signs=["++++"] + rat)
    assert r.passed and r.holds, r


def test_cyclotomic_orbits_reduce_to_gf_orbits():
    r = cross_check_mod_p(default_system(), DEFAULT_X0, "1/10", "cyclo:3", "gf:1000003", steps=2)
    assert r.passed and r.holds, r
    r = cross_check_mod_p(default_system(), DEFAULT_X0, "1/10", "cyclo:6", "gf:1000039", steps=1)
    assert r.passed and r.holds, r


def test_cross_check_detects_a_mismatch(monkeypatch):
    """Negative control: a gf computation with a perturbed step size must be caught."""
    import exact_khk.certification.identities as ident

    real = ident.KahanMap

    def skewed(field, eps, arith=None):
        return real(field, Fraction(eps) + 1 if get_arith(arith).name.startswith("gf") else eps, arith)

    monkeypatch.setattr(ident, "KahanMap", skewed)
    r = cross_check_mod_p(default_system(), DEFAULT_X0, "1/10", "flint", "gf:1000003", steps=1,
                          patterns=["-++"], integral_signs=["+++", "-++"])
    assert r.holds is False and not r.passed and "f step 1 coordinate 0" in r.residual


def test_bad_reduction_is_refused_not_wrapped():
    # eps = 1/7 has no value mod 7
    with pytest.raises(BadReductionError):
        KahanMap(default_system().field("f"), "1/7", "gf:7")


# --- Schwartz–Zippel -------------------------------------------------------------------


def _check(records, n, trials):
    """Every claim holds with its failure bound stated, (d/(P - S*D1 - 1))^k from the degree d the
    claim states; the degree of H~ conserved by Phi_f is the one derived independently:
    H~ (4N - 2, 4N) at Phi(x) ((2N + 1, 2N), N = 2n) minus H~: 8N^2 + 8N - 2."""
    import re

    for r in records:
        assert r.passed, r
    byname = {r.name: r for r in records}
    N = 2 * n
    for r in records:
        if r.expected and not r.name.startswith("identity: rank"):
            m = re.search(r"failure bound <= ([0-9.e+-]+); (\d+) random .* degree <= (\d+) in \(x, eps\).*"
                          r"S = (\d+) checks, D1 = (\d+)", r.evidence)
            bound, k, d, S, D1 = float(m.group(1)), *map(int, m.groups()[1:])
            assert k == trials and f"{bound:.4g}" == f"{(d / (P - S * D1 - 1)) ** k:.4g}" and bound < 1e-14
    assert f"degree <= {8 * N * N + 8 * N - 2} in" in byname["identity: integral H~ conserved by Phi_f"].evidence
    for r in records:
        if not r.expected:
            assert r.holds is False and r.evidence.startswith("exact refutation")


@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_schwartz_zippel_all_involutions(n):
    system = LiePoissonSystem.random(n, seed=n)
    _check(liouville(system, arith=f"gf:{P}", trials=2, seed=n), n, 2)


@pytest.mark.slow
@pytest.mark.parametrize("n", [6, 7, 8])
def test_schwartz_zippel_all_involutions_large_n(n):
    system = LiePoissonSystem.random(n, seed=n)
    _check(liouville(system, arith=f"gf:{P}", trials=1, seed=n), n, 1)


def test_singular_draws_are_redrawn_and_reported():
    # tiny prime: many draws hit eps = 0 or a singular step; they are not counted
    from exact_khk.certification.engine import identity_checks

    recs = identity_checks(LiePoissonSystem.random(2, seed=2).with_involutions(["+-", "-+"]), "gf:13", trials=3,
                           seed=5, max_draws=200)
    ev = recs[0].evidence
    assert "singular draw(s) redrawn" in ev
    assert recs[0].holds is None                # zero residuals, but no bound below 1: undecided
    assert "failure bound <= 1;" in ev          # P = 13 is far too small to certify anything


def test_too_many_singular_draws_is_an_input_error():
    from exact_khk.certification.engine import identity_checks

    with pytest.raises(InputError, match="trials"):
        identity_checks(default_system().with_involutions(["-++"]), "gf:7", trials=50, seed=0, max_draws=5)


def test_schwartz_zippel_needs_a_prime_field():
    from exact_khk.certification.engine import identity_checks

    with pytest.raises(InputError, match="gf:P"):
        identity_checks(default_system(), "cyclo:3")


def test_cli_liouville_gf(capsys):
    from exact_khk.cli.main import main

    assert main(["liouville", "--n", "4", "--seed", "4", "--arith", f"gf:{P}", "--trials", "1"]) == 0
    assert "probabilistic over F_" in capsys.readouterr().out
    assert main(["liouville", "--arith", "gf:1000037", "--trials", "1"]) == 2
    assert "is not a rational involution" in capsys.readouterr().err
