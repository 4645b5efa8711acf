"""The API refuses hostile input with typed errors (exact_khk.errors), never a raw error
from deep inside, and never passes a NaN on as a measured or exact value.

Rows from a hostile sweep of the public API (each raised a raw TypeError, ValueError,
AttributeError, ZeroDivisionError or MemoryError, hung, or gave a wrong answer before
it was mended); each must now raise the typed error named.
"""

from __future__ import annotations

import contextlib
import math
import sys
from fractions import Fraction

import flint
import gmpy2
import pytest

import exact_khk.testing as T
from exact_khk import InputError, KahanMap, LiePoissonSystem, System, certify, rational_sign_patterns, verify
from exact_khk.errors import NumericalError
from exact_khk.certification.records import Check
from exact_khk.diagnostics import degree_sequence, find_integrals, height_growth
from exact_khk.diagnostics.classify import classify
from exact_khk.diagnostics.map_degrees import MapDegrees, map_degrees
from exact_khk.diagnostics.measures import find_measure
from exact_khk.diagnostics.poisson import find_poisson
from exact_khk.systems.expressions import ExpressionSystem
from exact_khk.systems.lie_poisson.system import b0_signs

S3 = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")
F3 = S3.field("f")
X3 = ["1", "2", "-1", "1/2", "0", "1"]
TOP = "euler-top"

ROWS = [
    # fields: a non-integer power used to give the zero field (the identity map) silently
    ("power 1.5", lambda: S3.field("f", power=1.5)),
    ("power nan", lambda: S3.field("f", power=float("nan"))),
    ("power None", lambda: S3.field("f", power=None)),
    ("power True", lambda: S3.field("f", power=True)),
    # sign patterns: floats were truncated (1.9 -> +1), strings and None raised raw errors
    ("signs None", lambda: S3.field("g", signs=5)),
    ("signs chars", lambda: S3.field("g", signs=["+", "-", "+"])),
    ("signs float", lambda: S3.field("g", signs=[1.9, 1, 1])),
    ("signs nan", lambda: S3.field("g", signs=[1, -1, float("nan")])),
    ("signs str ints", lambda: S3.field("g", signs=["-1", "1", "1"])),
    ("involution None", lambda: S3.involution(None)),
    # a system or nothing where a field is expected
    ("map of a system", lambda: KahanMap(S3, "1/10")),
    ("map of None", lambda: KahanMap(None, "1/10")),
    ("certify an int", lambda: certify(5)),
    ("certify a field", lambda: certify(F3, steps=2)),
    ("LP option, other system", lambda: certify(System.load(TOP), steps=2, signs="-++")),
    # eps: non-finite elements of the arithmetic, and with_eps reads like the constructor
    ("eps nan float", lambda: KahanMap(F3, float("nan"), "float")),
    ("eps inf float", lambda: KahanMap(F3, float("inf"), "float")),
    ("eps mpfr nan", lambda: KahanMap(F3, gmpy2.mpfr("nan"), "mp:64")),
    ("eps mpfr inf", lambda: KahanMap(F3, gmpy2.mpfr("inf"), "mp:64")),
    ("with_eps 0", lambda: KahanMap(F3, "1/10", "fraction").with_eps(0)),
    ("with_eps None", lambda: KahanMap(F3, "1/10").with_eps(None)),
    ("with_eps nan", lambda: KahanMap(F3, "1/10", "float").with_eps(float("nan"))),
    ("system_matrix short", lambda: KahanMap(F3, "1/10").system_matrix([1, 2])),
    # sizes beyond the limits the command line has: refused at once
    ("orbit 10^12 steps", lambda: KahanMap(F3, "1/10").orbit([0] * 6, 10 ** 12)),
    ("orbit progress 5", lambda: KahanMap(F3, "1/10").orbit(X3, 2, progress=5)),
    ("orbit True steps", lambda: KahanMap(F3, "1/10").orbit(X3, True)),
    ("certify True steps", lambda: certify(steps=True)),
    ("a dict as a point", lambda: KahanMap(F3, "1/10").step(dict(enumerate(X3)))),
    ("a set as a point", lambda: KahanMap(F3, "1/10").step({1, 2, 3, 4, 5, 6})),
    ("certify 10^12 steps", lambda: certify(steps=10 ** 12)),
    ("random n 10^9", lambda: LiePoissonSystem.random(10 ** 9, 1)),
    ("orbit 5000-digit steps", lambda: KahanMap(F3, "1/10").orbit(X3, 10 ** 5000)),
    ("random 5000-digit n", lambda: LiePoissonSystem.random(10 ** 5000, 1)),
    ("sign patterns 5000-digit n", lambda: rational_sign_patterns(10 ** 5000)),
    ("power 5000 digits", lambda: S3.field("f", power=10 ** 5000)),
    ("random bound -1", lambda: LiePoissonSystem.random(3, 1, bound=-1)),
    ("random bound None", lambda: LiePoissonSystem.random(3, 1, bound=None)),
    ("random seed list", lambda: LiePoissonSystem.random(3, [1])),
    ("sign patterns 720720", lambda: rational_sign_patterns(720720)),
    ("sign patterns 0", lambda: rational_sign_patterns(0)),
    ("b0 signs 0", lambda: b0_signs(0)),
    # find_integrals reads x0 like every other entry point (floats refused, not taken as exact)
    ("integrals x0 nan", lambda: find_integrals(System.load(TOP), degree=2, x0=[float("nan"), 1, 2])),
    ("integrals x0 1/0", lambda: find_integrals(System.load(TOP), degree=2, x0=["1/0", 1, 2])),
    ("integrals x0 0.5", lambda: find_integrals(System.load(TOP), degree=2, x0=[0.5, 1, 2])),
    ("integrals seed list", lambda: find_integrals(System.load(TOP), degree=2, seed=[1])),
    ("integrals max_primes 0", lambda: find_integrals(System.load(TOP), degree=2, max_primes=0)),
    # files that are not regular text files
    ("load /dev/zero", lambda: System.load("/dev/zero")),
    ("load NUL byte", lambda: System.load("/tmp/x\x00y.toml")),
    # a comparison of differently shaped sides
    ("poisson shapes", lambda: T.assert_poisson_map(KahanMap(F3, "1/10"), lambda x: [[0]], X3, 2)),
    # the testing helpers and the records name what is wrong
    ("helper without tol", lambda: T.assert_reversible(KahanMap(F3, "1/10", "float"), X3, 3)),
    ("helper tol 'x'", lambda: T.assert_reversible(KahanMap(F3, "1/10", "float"), X3, 3, tol="x")),
    ("helper of a field", lambda: T.assert_reversible(F3, X3, 3)),
    ("helper float integral", lambda: T.assert_conserved(KahanMap(F3, "1/10"), lambda x: 0.5, X3, 3)),
    ("helper None integral", lambda: T.assert_conserved(KahanMap(F3, "1/10"), lambda x: None, X3, 3)),
    ("helper no certificate", lambda: T.assert_certificate_valid(None)),
    ("check of no name", lambda: certify(steps=2).check("nope")),
    ("Check.from_json None", lambda: Check.from_json(None)),
    ("Check.from_json {}", lambda: Check.from_json({})),
    # diagnostics' parameters
    ("heights in gf:101", lambda: height_growth(F3, X3, "1/10", arith="gf:101")),
    ("heights in float", lambda: height_growth(F3, X3, "1/10", arith="float")),
    ("heights max_bits None", lambda: height_growth(F3, X3, "1/10", max_bits=None)),
    ("degrees confirm -1", lambda: degree_sequence(S3, steps=5, confirm=-1)),
    ("degrees exact_terms -1", lambda: degree_sequence(S3, steps=5, exact_terms=-1)),
    # arithmetic names: int() takes other scripts' digits, '_' and spaces; the names do not
    ("arith mp:Arabic-Indic 53", lambda: KahanMap(F3, "1/10", "mp:\u0665\u0663")),
    ("arith mp:5_3", lambda: KahanMap(F3, "1/10", "mp:5_3")),
    ("arith gf:full-width 7", lambda: KahanMap(F3, "1/10", "gf:\uff17")),
]


# from a hostile review of the discovery entry points (each raised a raw error from deep inside,
# or took a float as exact, or searched forever)
ROWS += [
    ("map variables not ASCII", lambda: MapDegrees(["Z**2", "X*Y", "Y**2"], ["\u03b1", "\u03b2", "\u03b3"])),
    ("map components None", lambda: MapDegrees(None, ["X", "Y", "Z"])),
    ("map variables None", lambda: MapDegrees(["Z**2", "X*Y", "Y**2"], None)),
    ("map confirm 0", lambda: MapDegrees(["Z**2", "X*Y", "Y**2"], ["X", "Y", "Z"], confirm=0)),
    ("measure x0 nan", lambda: find_measure(TOP, x0=[float("nan"), 1, 2])),
    ("measure x0 0.5", lambda: find_measure(TOP, x0=[0.5, 1, 2])),
    ("measure x0 of 2", lambda: find_measure(TOP, x0=[1, 2])),
    ("measure seed None", lambda: find_measure(TOP, seed=None)),
    ("measure seed 'abc'", lambda: find_measure(TOP, seed="abc")),
    ("poisson x0 '1,2'", lambda: find_poisson(TOP, x0="1,2")),
    ("poisson measure_degree None", lambda: find_poisson(TOP, measure_degree=None)),
    ("poisson in dimension 1", lambda: find_poisson(ExpressionSystem.from_expressions(["x"], field=["x**2"]))),
    ("classify discover None", lambda: classify(TOP, steps=8, discover=None)),
    ("classify discover 5", lambda: classify(TOP, steps=8, discover=5)),
    # a progress callback that is not a function, a monomial list that is not a list: raw TypeErrors before
    ("measure progress 5", lambda: find_measure(TOP, progress=5)),
    ("poisson progress 5", lambda: find_poisson(TOP, progress=5)),
    ("integrals progress 5", lambda: find_integrals(TOP, degree=2, progress=5)),
    ("classify progress 5", lambda: classify(TOP, steps=8, progress=5)),
    ("symbolic progress 5", lambda: __import__("exact_khk.diagnostics.parametric", fromlist=["x"]).symbolic_integrals(
        TOP, ["eps"], degree=2, progress=5)),
    ("integrals monomials 5", lambda: find_integrals(TOP, monomials_list=5)),
    ("integrals monomials 'x1'", lambda: find_integrals(TOP, monomials_list="x1,x2")),
]
BIG_INT_ROWS = [
    ("degree_sequence seed 10^5000", lambda: degree_sequence(TOP, steps=6, seed=10 ** 5000)),
    ("classify seed 10^5000", lambda: classify(TOP, steps=8, seed=10 ** 5000)),
    ("measure seed 10^5000", lambda: find_measure(TOP, seed=10 ** 5000)),
    ("poisson seed 10^5000", lambda: find_poisson(TOP, seed=10 ** 5000)),
    ("map seed 10^5000", lambda: map_degrees(["Z**2", "X*Y", "Y**2"], ["X", "Y", "Z"], seed=10 ** 5000)),
    ("integrals primes 10^5000", lambda: find_integrals(TOP, degree=2, primes=10 ** 5000)),
    ("integrals primes [10^5000]", lambda: find_integrals(TOP, degree=2, primes=[10 ** 5000])),
]


@contextlib.contextmanager
def python_digit_limit():
    """Python's default 4300-digit int<->str limit (the command line, run in-process by other
    tests, lifts it for the whole process)."""
    old = sys.get_int_max_str_digits()
    sys.set_int_max_str_digits(4300)
    try:
        yield
    finally:
        sys.set_int_max_str_digits(old)


@pytest.mark.parametrize("name, call", BIG_INT_ROWS, ids=[r[0] for r in BIG_INT_ROWS])
def test_huge_integers_are_refused_under_pythons_digit_limit(name, call):
    with python_digit_limit(), pytest.raises(InputError):
        call()


def test_polynomial_texts_print_coefficients_beyond_pythons_digit_limit():
    from exact_khk.diagnostics.kernels import poly_text as mpoly_text
    from exact_khk.parsing import poly_text

    big = Fraction(10 ** 5000 + 1, 3)
    with python_digit_limit():
        text, text1 = mpoly_text({(1, 0): big}, ["x", "y"]), poly_text([0, big], "k")
    expected = str(flint.fmpq(10 ** 5000 + 1, 3))  # FLINT's printer: no digit limit
    assert text == expected + "*x" and text1 == expected + "*k"


def test_map_degrees_stop_before_an_iterate_past_the_degree_limit():
    res = MapDegrees(["(X+Y)**64", "Y**64", "Z**64"], ["X", "Y", "Z"], steps=8, primes=1)
    # d_k <= 64^k; 4096 * 64 > MAX_DEGREE = 100000: the third step is not taken, and the summary says so
    assert len(res.degrees) == 3 and max(res.degrees) <= 64 ** 2
    assert "stopped after k = 2 of 8" in res.summary()


@pytest.mark.parametrize("name, call", ROWS, ids=[r[0] for r in ROWS])
def test_hostile_api_row(name, call):
    with pytest.raises(InputError):
        call()


def test_verify_refuses_eps_zero_and_unsupported_cyclotomic_fields():
    d = certify(steps=2).to_json()
    with pytest.raises(InputError, match="eps"):
        verify(dict(d, eps="0"))
    for N in ("100000", "1000000000"):  # beyond cyclo:N's limit: "not checkable", at once
        report = verify(dict(d, arith=f"cyclo:{N}"))
        assert not report.ok and not report.checkable
    assert verify(d).ok  # the control: the untampered certificate verifies


def test_float_step_of_a_field_without_quadratic_terms():
    """An affine field (x' = y, y' = -x) in binary64: numpy's bincount of no terms is int64;
    the step must still be the binary64 solve, within a few ulps of the exact step."""
    f = System.from_expressions(["x", "y"], field=["y", "-x"]).field("f")
    exact = KahanMap(f, "1/10", "fraction").step([1, 1])
    assert exact == (Fraction(119, 101), Fraction(79, 101))  # (I - εL)⁻¹(I + εL) x by hand
    z = KahanMap(f, "1/10", "float").step([1, 1])
    # a 2×2 solve of a matrix with κ ≈ 1: each coordinate within 8 ulp of the exact value
    assert all(abs(Fraction(a) - b) <= 8 * math.ulp(float(b)) for a, b in zip(z, exact))


def test_a_nan_residual_is_never_conserved():
    phi = KahanMap(F3, "1/10", "float")
    with pytest.raises(AssertionError, match="nan"):
        T.assert_conserved(phi, lambda x: float("nan"), X3, 3, tol=1e-9)
    T.assert_conserved(phi, lambda x: 0.0, X3, 3, tol=1e-9)  # the control: a constant is conserved


def test_system_matrix_overflow_is_a_numerical_error():
    with pytest.raises(NumericalError):
        KahanMap(F3, "1/10", "float").system_matrix([1, 2, 3, 4, 5, 1e308])
    assert KahanMap(F3, "1/10", "float").system_matrix([1, 2, 3, 4, 5, 1])[0][0] == pytest.approx(-1.2)


def test_certify_takes_a_catalogue_name():
    assert certify(TOP, steps=2).status == certify(System.load(TOP), steps=2).status == "VALID"


@pytest.mark.parametrize("eps, arith, match", [
    ("101", "gf:101", "eps: '101' is 0 in gf:101"),            # said 'underflows', as if rounded
    ("-202", "gf:101", "eps: '-202' is 0 in gf:101"),
    ("1/10" + "0" * 400, "float", "underflows to 0 in float"),  # a rounding arithmetic: it does
])
def test_a_step_size_that_is_zero_in_the_arithmetic_is_named(eps, arith, match):
    with pytest.raises(InputError, match=match):
        KahanMap(F3, eps, arith)
    KahanMap(F3, "1/10", arith)  # control: a nonzero step size in the same arithmetic


@pytest.mark.parametrize("bad", ["1G", math.nan, 1.5, 0, True])
def test_find_integrals_memory_limit_is_an_integer_of_bytes(bad):
    """max_bytes NaN would switch the memory plan off (every comparison with NaN is false); a text
    was a raw TypeError: both InputError naming max_bytes."""
    with pytest.raises(InputError, match="max_bytes"):
        find_integrals("euler-top", degree=2, max_bytes=bad)


BIG_EPS = Fraction(1, 10 ** 5000)


def _big_eps_records():
    """One record of each discovery and certification result class, its eps (or a fixed parameter)
    replaced by a 5000-digit rational: summary() and to_json() print it under Python's 4300-digit limit."""
    import dataclasses

    from exact_khk.diagnostics.parametric import ParametricSearch

    top = System.load(TOP)
    res = find_integrals(top, degree=2)  # its numbers: the independence certificate's point
    yield dataclasses.replace(res, certificate=((BIG_EPS,) * 3,) + tuple(res.certificate[1:]))
    yield dataclasses.replace(find_measure(top, degree=1), eps=BIG_EPS)
    yield dataclasses.replace(find_poisson(top, degree=1), eps=BIG_EPS)
    yield dataclasses.replace(classify(top, steps=6, discover=()), eps=BIG_EPS)
    yield ParametricSearch("euler-top f", ("a",), (("eps", BIG_EPS),), (), 0, 0, 0, (), 0.0)


def test_results_print_an_eps_beyond_pythons_digit_limit():
    for res in _big_eps_records():
        with python_digit_limit():
            text, data = res.summary(), res.to_json()
        assert str(flint.fmpq(1, 10 ** 5000)) in text + str(data), type(res).__name__


def test_discovery_and_certification_run_at_an_eps_beyond_pythons_digit_limit():
    """find_poisson computed texts of a 5000-digit eps (the orbit check) before it printed them; certify's
    record printed them: both gave ValueError 'Exceeds the limit (4300 digits)'."""
    with python_digit_limit():
        res = find_poisson(TOP, degree=1, eps=BIG_EPS)
        cert = certify(TOP, steps=1, eps=BIG_EPS)
        texts = [res.summary(), str(res.to_json()), cert.summary(), str(cert.to_json())]
        assert sys.get_int_max_str_digits() == 4300  # the caller's limit is restored
    assert all(str(flint.fmpq(1, 10 ** 5000)) in t for t in texts)
    assert cert.status == "VALID"


def test_exact_orbit_checks_refuse_a_point_beyond_their_height_limit():
    """find-measure's exact orbit from an x0 of 10^4 digits used Fractions (minutes); in fmpq it takes
    seconds, and a start too high for the steps asked is refused naming x0 (command line: exit 2)."""
    from exact_khk.diagnostics import darboux

    x0 = [10 ** 700 + 1, 2, 3]  # 2326 bits; 3x per step: past 2^12 bits at the first step
    with python_digit_limit(), contextlib.ExitStack() as stack:
        stack.enter_context(pytest.MonkeyPatch.context()).setattr(darboux, "MAX_ORBIT_BITS", 4096)
        with pytest.raises(InputError, match="x0: .* beyond the limit of 4096"):
            find_measure(TOP, x0=x0, verify_steps=3)
        res = find_measure(TOP, x0=x0, verify_steps=1)  # the control: one step is within it
    assert any(c.name == "exact orbit" and c.holds is True for d in res.densities for c in d.checks)


def test_classify_survives_a_discovery_that_cannot_decide(monkeypatch):
    """classify at eps = 1e400 stopped with exit 4 and nothing else when the measure search's lift was
    not confirmed (UndecidedError): the verdict and the other evidence were lost.  That search now reads
    'could not run: ...' and classify goes on."""
    import exact_khk.diagnostics.measures as measures
    from exact_khk.errors import UndecidedError

    def undecided(*args, **kw):
        raise UndecidedError("the rational reconstruction of the kernel was not confirmed with 12 primes")

    monkeypatch.setattr(measures, "find_measure", undecided)
    res = classify(TOP, steps=6, degree=2, exact=0, discover=("measure",))
    assert res.discoveries["measure"].startswith("could not run: the rational reconstruction")
    assert res.verdict in ("integrable", "non-integrable", "undetermined") and "could not run" in res.summary()
