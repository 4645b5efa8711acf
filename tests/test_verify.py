"""``verify``: stand-alone re-checking of saved certificates, and ``exact-khk verify``."""

import copy
import json
import pathlib
import re
import sys
from contextlib import contextmanager
from fractions import Fraction

import pytest

from exact_khk.certification.engine import certify_system
from exact_khk.certification.lie_poisson import certify
from exact_khk.certification.records import Certificate
from exact_khk.certification.verify import VerifyReport, cyclotomic_polynomial, verify
from exact_khk.cli import verify as cli_verify
from exact_khk.cli.main import main
from exact_khk.errors import InputError
from exact_khk.parsing import parse_rational
from exact_khk.systems.expressions import ExpressionSystem

SCHEMA = pathlib.Path(__file__).parent.parent / "exact_khk" / "certification" / "certificate.schema.json"


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def roundtrip(cert):
    """The certificate as a reader of the file sees it."""
    return json.loads(json.dumps(cert.to_json()))


def linear_integral_system():
    """x' = xy − xz, y' = yz − yx, z' = zx − zy: the sum of the components is 0, so
    S = x + y + z is a linear integral of f, and every Kahan map conserves linear
    integrals exactly; Q = xyz is an integral of the flow, not of the Kahan map."""
    return ExpressionSystem.from_expressions(["x", "y", "z"], field=["x*y - x*z", "y*z - y*x", "z*x - z*y"],
                                             integrals={"S": "x + y + z"}, controls={"Q": "x*y*z"},
                                             x0=["1", "2", "3"], eps="1/10", name="linear-integral")


@pytest.fixture(scope="module")
def lp_cert():
    return roundtrip(certify(steps=3, signs=["-++"]))


@pytest.fixture(scope="module")
def generic_cert():
    return roundtrip(certify_system(linear_integral_system(), steps=4))


@contextmanager
def digits_limit(limit):
    """Python's int/str digit limit set to ``limit`` for the block (0: lifted, as the
    CLI's main() does for the rest of the process; 4300: Python's default)."""
    old = sys.get_int_max_str_digits() if hasattr(sys, "get_int_max_str_digits") else None
    if old is not None:
        sys.set_int_max_str_digits(limit)
    try:
        yield
    finally:
        if old is not None:
            sys.set_int_max_str_digits(old)


DEFAULT_LIMIT = 4300  # Python's default (sys.int_info.default_max_str_digits)


# --- accepted certificates -------------------------------------------------------------


def test_default_lie_poisson_certificate_is_verified():
    cert = certify()
    data = roundtrip(cert)
    assert data["orbit"] and set(data["values"]) == {"H~", "K~[+--]", "K~[-++]"} and data["path"]
    assert [Fraction(t) for t in data["orbit"][0]] == list(cert.x0)
    report = verify(data)
    assert isinstance(report, VerifyReport) and report.ok and report.checkable, report.summary()
    names = [r[0] for r in report.results]
    for name in ("schema version", "orbit length", "orbit starts at x0", "Kahan step equations",
                 "Kahan steps nonsingular", "values of H~", "H~ conserved", "values of K~[-++]",
                 "K~[-++] conserved", "H~ closed form = definition", "status", "verdict"):
        assert name in names
    assert report.summary().splitlines()[-1].startswith("VERIFIED: ")
    assert report.to_json()["ok"] is True and len(report.to_json()["results"]) == len(report.results)


def test_lie_poisson_values_are_the_memoised_integrals(lp_cert):
    # H~ is conserved: one value along the orbit, equal to the closed form at x0
    from exact_khk.systems.lie_poisson import default_system
    from exact_khk.systems.lie_poisson.invariants import Htilde
    from exact_khk import get_arith

    h0 = Htilde(default_system().field("f"), [Fraction(t) for t in lp_cert["x0"]], "1/10", get_arith("fraction"))
    assert lp_cert["values"]["H~"] == [str(h0)] * 4


def test_n2_certificate_with_signs_is_verified(capsys, tmp_path):
    path = tmp_path / "n2.json"
    code, _, _ = run(capsys, "certify", "--n", "2", "--seed", "1", "--signs", "+-", "--steps", "6",
                     "--json", str(path))
    assert code == 0
    data = json.loads(path.read_text())
    assert data["signs"] == ["+-"] and set(data["values"]) == {"H~", "K~[+-]"}
    report = verify(data)
    assert report.ok, report.summary()


def test_generic_certificate_with_a_linear_integral_is_verified(generic_cert):
    assert generic_cert["status"] == "VALID"
    assert generic_cert["values"]["S"] == ["6"] * 5  # x + y + z = 6, exactly conserved
    report = verify(generic_cert)
    assert report.ok, report.summary()
    assert ("S conserved", True, "values equal along the orbit (the record of the claim is re-derived below)") in report.results


def test_non_homogeneous_field_invalid_claim_and_pole_are_verified():
    # f has linear and constant parts; P is not conserved (an honest INVALID certificate);
    # I has a pole at x0 (recorded as undefined); R = (x**2 - 1)/(x - 1) divides by zero
    # as written where x = 1, its reduced form x + 1 does not
    system = ExpressionSystem.from_expressions(
        ["x", "y", "z"], field={"x": "y*z + 1", "y": "-2*z*x + x", "z": "x*y"},
        integrals={"I": "(x**2 + 1)/(y - 2)", "R": "(x**2 - 1)/(x - 1)"}, x0=["1", "2", "3"], eps="1/10")
    data = roundtrip(certify_system(system, steps=3))
    assert data["status"] == "INVALID" and data["values"]["I"] is None
    report = verify(data)
    assert report.ok, report.summary()
    detail = dict((n, d) for n, _, d in report.results)
    assert "(I + eps L) x_k + 2 eps c" in detail["Kahan step equations"]
    assert "pole" in detail["values of I"] and "reduced form" in detail["values of R"]
    assert "not equal along the orbit" in detail["R conserved"]
    assert report.verdict().startswith("VERIFIED: the record of this INVALID certificate")


@pytest.mark.parametrize("arith", ["fraction", "gmpy2", "cyclo:3", "gf:4611686018420360881"])
def test_other_exact_arithmetics_are_verified(arith):
    data = roundtrip(certify(steps=2, arith=arith))
    report = verify(data)
    assert report.ok, report.summary()
    if arith.startswith(("cyclo", "gf")):  # the non-rational involutions too
        assert len(data["signs"]) == 6


def test_cyclotomic_values_are_recomputed_exactly():
    data = roundtrip(certify(steps=1, arith="cyclo:3", signs=["+-+"]))
    assert "z" in data["values"]["K~[+-+]"][0]  # an element of Q(omega) that is not rational
    assert verify(data).ok
    data["values"]["K~[+-+]"][1] = data["values"]["K~[+-+]"][1].replace("z", "z^2", 1)
    assert "values of K~[+-+]" in [r[0] for r in verify(data).failures()]
    assert cyclotomic_polynomial(12) == (1, 0, -1, 0, 1)


@pytest.mark.parametrize("arith", ["float", "mp:80", "ball:128"])
def test_inexact_certificate_is_not_checkable(arith):
    data = roundtrip(certify(steps=2, arith=arith))
    assert data["orbit"] and data["values"]["H~"]  # recorded all the same
    report = verify(data)
    assert not report.ok and not report.checkable
    assert report.failures()[0][0] == "exact arithmetic" and "cannot be re-checked exactly" in report.verdict()
    assert report.verdict().startswith("NOT VERIFIED: exact arithmetic:")
    assert [r[0] for r in report.results] == ["schema version", "exact arithmetic", "status", "verdict"]


# --- tampering -------------------------------------------------------------------------


def _plus_tiny(text):
    return f"{parse_rational(text, 't') + Fraction(1, 10 ** 30)}"


def _set(path, fn):
    def mutate(d):
        *head, last = path
        for k in head:
            d = d[k]
        d[last] = fn(d[last])
    return mutate


def _drop_point(d):
    del d["orbit"][2]


def _first_claim_holds_flipped(d):
    c = next(c for c in d["checks"] if c["name"] == "reversibility Phi_f")
    c["holds"] = not c["holds"]


def _conservation_flipped(d):
    c = next(c for c in d["checks"] if c["name"].startswith("integral ") and "conserved by Phi_f" in c["name"])
    c["holds"] = False


LP_MUTATIONS = {
    "coordinate +1/10^30": (_set(["orbit", 2, 4], _plus_tiny), "Kahan step equations"),
    "last coordinate +1/10^30": (_set(["orbit", 3, 5], _plus_tiny), "Kahan step equations"),
    "eps": (_set(["eps"], lambda e: "1/11"), "Kahan step equations"),
    "x0": (_set(["x0", 1], lambda t: "3"), "orbit starts at x0"),
    "value of H~": (_set(["values", "H~", 2], _plus_tiny), "values of H~"),
    "value of K~": (_set(["values", "K~[-++]", 0], lambda t: "0"), "values of K~[-++]"),
    "a check's holds": (_first_claim_holds_flipped, "record reversibility Phi_f"),
    "a conservation check's holds": (_conservation_flipped, "record integral H~ conserved by Phi_f"),
    "status": (_set(["status"], lambda s: "INVALID"), "status"),
    "valid": (_set(["valid"], lambda s: False), "status"),
    "verdict": (_set(["verdict"], lambda s: "INVALID: " + s), "verdict"),
    "dropped orbit point": (_drop_point, "orbit length"),
    "system a": (_set(["system", "a", 0], lambda t: "2"), "Kahan step equations"),
    "steps": (_set(["steps"], lambda k: k + 1), "orbit length"),
    "signs": (_set(["signs"], lambda s: ["+--"]), "integrals recorded"),
    # cut short: the claims only (no control left, so it cannot be VALID), or with one control
    # (still VALID, but the verdict's counts are those of the whole certificate)
    "checks cut to the claims": (lambda d: d.update(checks=[c for c in d["checks"] if c["expected"]][:3]),
                                 "records cover the claims"),
    "checks cut to 3 claims and a control": (
        lambda d: d.update(checks=[c for c in d["checks"] if c["expected"]][:3]
                           + [c for c in d["checks"] if not c["expected"]][:1]), "records cover the claims"),
}


@pytest.mark.parametrize("what", sorted(LP_MUTATIONS))
def test_tampered_lie_poisson_certificate_fails_naming_the_check(lp_cert, what):
    assert verify(lp_cert).ok
    mutate, expected = LP_MUTATIONS[what]
    data = copy.deepcopy(lp_cert)
    mutate(data)
    report = verify(data)
    assert not report.ok
    failing = [r[0] for r in report.failures()]
    assert expected in failing, report.summary()
    assert report.verdict().startswith(f"NOT VERIFIED: {failing[0]}: ")


GENERIC_MUTATIONS = {
    "coordinate +1/10^30": (_set(["orbit", 1, 0], _plus_tiny), "Kahan step equations"),
    "eps": (_set(["eps"], lambda e: "-1/10"), "Kahan step equations"),
    "x0": (_set(["x0", 2], lambda t: "4"), "orbit starts at x0"),
    "value": (_set(["values", "S", 3], lambda t: "7"), "values of S"),
    "field": (_set(["system", "field", "x"], lambda t: "2*x*y - x*z"), "Kahan step equations"),
    "integral text": (_set(["system", "integrals", "S"], lambda t: "x + y"), "values of S"),
    "status": (_set(["status"], lambda s: "INCONCLUSIVE"), "status"),
    "dropped orbit point": (_drop_point, "orbit length"),
}


@pytest.mark.parametrize("what", sorted(GENERIC_MUTATIONS))
def test_tampered_generic_certificate_fails_naming_the_check(generic_cert, what):
    mutate, expected = GENERIC_MUTATIONS[what]
    data = copy.deepcopy(generic_cert)
    mutate(data)
    report = verify(data)
    assert not report.ok and expected in [r[0] for r in report.failures()], report.summary()


def test_unknown_schema_version_is_a_failing_check(lp_cert):
    data = dict(lp_cert, schema_version=3)
    report = verify(data)
    assert not report.ok and report.failures()[0][0] == "schema version"


# --- malformed input -------------------------------------------------------------------


def _del(*path):
    def mutate(d):
        for k in path[:-1]:
            d = d[k]
        del d[path[-1]]
    return mutate


MALFORMED = {
    "no orbit coordinates as strings": (_set(["orbit", 1, 0], lambda t: 1.5), "orbit[1][0]"),
    "not a rational": (_set(["orbit", 1, 0], lambda t: "one third"), "orbit[1][0]"),
    "missing x0": (_del("x0"), "x0"),
    "missing system": (_del("system"), "system"),
    "x0 too short": (_set(["x0"], lambda v: v[:2]), "x0"),
    "eps a number": (_set(["eps"], lambda e: 0.1), "eps"),
    "eps zero denominator": (_set(["eps"], lambda e: "1/0"), "eps"),
    "steps a string": (_set(["steps"], lambda k: "3"), "steps"),
    "checks not a list": (_set(["checks"], lambda c: {"a": 1}), "checks"),
    "check without holds": (_del("checks", 0, "holds"), "checks[0]"),
    "check holds a string": (_set(["checks", 1, "holds"], lambda h: "yes"), "checks[1].holds"),
    "check not an object": (_set(["checks", 2], lambda c: "ok"), "checks[2]"),
    "values not an object": (_set(["values"], lambda v: [1, 2]), "values"),
    "value not a string": (_set(["values", "H~", 1], lambda v: 3), "values.H~[1]"),
    "value not rational": (_set(["values", "H~", 1], lambda v: "x"), "values.H~[1]"),
    "point of wrong length": (_set(["orbit", 1], lambda p: p[:-1]), "orbit[1]"),
    "system vector": (_set(["system", "a"], lambda a: "1,2,3"), "system.a"),
    "system family": (_set(["system", "family"], lambda f: "toda"), "system.family"),
    "system n": (_set(["system", "n"], lambda n: 4), "system.n"),
    "signs pattern": (_set(["signs"], lambda s: ["-+"]), "signs"),
    "status type": (_set(["status"], lambda s: None), "status"),
    "missing verdict": (_del("verdict"), "verdict"),
    "missing schema version": (_del("schema_version"), "schema_version"),
}


@pytest.mark.parametrize("what", sorted(MALFORMED))
def test_malformed_certificate_raises_input_error_naming_the_field(lp_cert, what):
    mutate, field = MALFORMED[what]
    data = copy.deepcopy(lp_cert)
    mutate(data)
    with pytest.raises(InputError) as info:
        verify(data)
    assert field in str(info.value)


@pytest.mark.parametrize("bad", [None, [], "cert", 3])
def test_not_an_object_raises_input_error(bad):
    with pytest.raises(InputError, match="expected a JSON object"):
        verify(bad)


def test_malformed_expression_system_raises_input_error(generic_cert):
    data = copy.deepcopy(generic_cert)
    data["system"]["field"]["x"] = "x**3"
    with pytest.raises(InputError, match="degree"):
        verify(data)
    data = copy.deepcopy(generic_cert)
    del data["system"]["variables"]
    with pytest.raises(InputError, match="variables"):
        verify(data)


# --- Certificate.from_json ---------------------------------------------------------------


def test_certificate_from_json_round_trips(lp_cert, generic_cert):
    for data in (lp_cert, generic_cert):
        cert = Certificate.from_json(data)
        assert cert.status == data["status"] and cert.to_json() == data
        assert cert.orbit and cert.path == data["path"]


def test_certificate_from_json_refuses_malformed_input(lp_cert):
    # from_json does not read the derived keys, and keeps the orbit and values as the
    # arithmetic's strings (only verify parses them, in the certificate's arithmetic)
    unread = {"status type", "missing verdict", "not a rational", "value not rational"}
    for what, (mutate, field) in MALFORMED.items():
        if what in unread:
            continue
        data = copy.deepcopy(lp_cert)
        mutate(data)
        with pytest.raises(InputError):
            Certificate.from_json(data)


# --- the JSON schema -------------------------------------------------------------------


def _validate(instance, schema, root=None, where="$"):
    """A small validator for the subset of JSON Schema 2020-12 the certificate schema uses
    (used when the jsonschema package is not installed)."""
    root = schema if root is None else root
    if "$ref" in schema:
        ref = schema["$ref"]
        assert ref.startswith("#/$defs/"), ref
        return _validate(instance, root["$defs"][ref.split("/")[-1]], root, where)
    if "oneOf" in schema:
        ok = 0
        for sub in schema["oneOf"]:
            try:
                _validate(instance, sub, root, where)
                ok += 1
            except AssertionError:
                pass
        assert ok == 1, f"{where}: matches {ok} of the oneOf alternatives"
    if "const" in schema:
        assert instance == schema["const"] and type(instance) is type(schema["const"]), f"{where}: const"
    if "enum" in schema:
        assert instance in schema["enum"], f"{where}: {instance!r} not in enum"
    if "type" in schema:
        types = schema["type"] if isinstance(schema["type"], list) else [schema["type"]]
        check = {"object": lambda v: isinstance(v, dict), "array": lambda v: isinstance(v, list),
                 "string": lambda v: isinstance(v, str), "boolean": lambda v: isinstance(v, bool),
                 "null": lambda v: v is None,
                 "integer": lambda v: isinstance(v, int) and not isinstance(v, bool),
                 "number": lambda v: isinstance(v, (int, float)) and not isinstance(v, bool)}
        assert any(check[t](instance) for t in types), f"{where}: not of type {types}"
    if isinstance(instance, dict):
        for key in schema.get("required", []):
            assert key in instance, f"{where}: missing {key!r}"
        props = schema.get("properties", {})
        for key, value in instance.items():
            if key in props:
                _validate(value, props[key], root, f"{where}.{key}")
            elif schema.get("additionalProperties") is False:
                raise AssertionError(f"{where}: unexpected key {key!r}")
            elif isinstance(schema.get("additionalProperties"), dict):
                _validate(value, schema["additionalProperties"], root, f"{where}.{key}")
    if isinstance(instance, list):
        assert len(instance) >= schema.get("minItems", 0), f"{where}: too few items"
        for i, item in enumerate(instance):
            if "items" in schema:
                _validate(item, schema["items"], root, f"{where}[{i}]")
    if isinstance(instance, str) and "pattern" in schema:
        assert re.search(schema["pattern"], instance), f"{where}: {instance[:40]!r} does not match"
    if isinstance(instance, (int, float)) and not isinstance(instance, bool) and "minimum" in schema:
        assert instance >= schema["minimum"], f"{where}: below the minimum"


def validate(instance):
    schema = json.loads(SCHEMA.read_text())
    try:
        import jsonschema
    except ImportError:
        _validate(instance, schema)
    else:
        jsonschema.Draft202012Validator.check_schema(schema)
        jsonschema.Draft202012Validator(schema).validate(instance)


def test_schema_accepts_the_certificates_the_tool_writes(lp_cert, generic_cert, capsys, tmp_path):
    schema = json.loads(SCHEMA.read_text())
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert schema["properties"]["schema_version"] == {"const": 2}
    assert set(schema["required"]) == set(lp_cert)  # every key of version 2, and only those
    path = tmp_path / "c.json"
    assert run(capsys, "certify", "--steps", "2", "--json", str(path))[0] == 0
    catalogue = tmp_path / "euler.json"
    assert run(capsys, "certify", "--system", "euler-top", "--steps", "2", "--json", str(catalogue))[0] == 0
    assert verify(json.loads(catalogue.read_text())).ok
    for data in (lp_cert, generic_cert, json.loads(path.read_text()), json.loads(catalogue.read_text()),
                 roundtrip(certify(steps=1, arith="float")), roundtrip(certify(steps=1, arith="cyclo:3"))):
        validate(data)


def test_schema_refuses_malformed_certificates(lp_cert):
    for mutate in (_del("orbit"), _set(["schema_version"], lambda v: 3), _set(["eps"], lambda e: "0.1"),
                   _set(["checks", 0, "holds"], lambda h: "yes"), lambda d: d.__setitem__("extra", 1),
                   _set(["system", "family"], lambda f: "toda")):
        data = copy.deepcopy(lp_cert)
        mutate(data)
        with pytest.raises(Exception):
            validate(data)


# --- big integers --------------------------------------------------------------------------


def test_big_integers_round_trip_without_lifting_the_digit_limit():
    """Coordinates of more than 10^4 digits, verified with Python's default int/str
    limit in force (the verifier never converts a huge int to or from str itself)."""
    x0 = ["1/" + "7" * 5000, "2", "3"]
    with digits_limit(0):
        cert = certify_system(linear_integral_system(), x0=x0, steps=2, claims=["integrals"])
        text = json.dumps(cert.to_json())
    with digits_limit(DEFAULT_LIMIT):
        data = json.loads(text)
        assert max(len(t.split("/")[0]) for p in data["orbit"] for t in p) >= 10_000
        report = verify(data)
        assert report.ok, report.summary()
        bad = copy.deepcopy(data)
        bad["orbit"][2][1] = bad["orbit"][2][1].replace("1", "2", 1)
        report = verify(bad)
        assert not report.ok and report.failures()[0][0] == "Kahan step equations"
        assert "digits>" in report.verdict()  # the residual is abbreviated, not printed
        json.dumps(report.to_json())
        if hasattr(sys, "get_int_max_str_digits"):
            assert sys.get_int_max_str_digits() == DEFAULT_LIMIT  # not lifted by verify


def test_big_lie_poisson_certificate_round_trips():
    with digits_limit(0):
        cert = certify(x0=["1/" + "7" * 800, "2", "-1", "1/2", "0", "1"], steps=1, signs=["-++"], poisson_points=1)
        text = json.dumps(cert.to_json())
    with digits_limit(DEFAULT_LIMIT):
        data = json.loads(text)
        assert max(len(t.split("/")[-1]) for p in data["orbit"] for t in p) > DEFAULT_LIMIT
        assert max(len(t) for v in data["values"].values() for t in v) > 2 * DEFAULT_LIMIT
        assert verify(data).ok


# --- the command line ------------------------------------------------------------------


def test_cli_certify_then_verify(capsys, tmp_path):
    path = tmp_path / "cert.json"
    assert run(capsys, "certify", "--steps", "4", "--json", str(path))[0] == 0
    code, out, err = run(capsys, "verify", str(path))
    assert code == 0 and err == ""
    assert out.splitlines()[-1].startswith("VERIFIED: ")
    code, out, _ = run(capsys, "verify", str(path), "--json")
    report = json.loads(out)
    assert code == 0 and report["ok"] is True and report["verdict"].startswith("VERIFIED")


def test_cli_verify_generic_certificate(capsys, tmp_path):
    path = tmp_path / "cert.json"
    path.write_text(json.dumps(certify_system(linear_integral_system(), steps=3).to_json()))
    code, out, _ = run(capsys, "verify", str(path))
    assert code == 0 and out.splitlines()[-1].startswith("VERIFIED")


def test_cli_tampered_certificate_exits_1(capsys, tmp_path):
    path = tmp_path / "cert.json"
    assert run(capsys, "certify", "--steps", "3", "--json", str(path))[0] == 0
    data = json.loads(path.read_text())
    data["values"]["H~"][1] = "1/3"
    path.write_text(json.dumps(data))
    code, out, err = run(capsys, "verify", str(path))
    assert code == 1 and err == ""
    assert out.splitlines()[-1].startswith("NOT VERIFIED: values of H~: at x_1: recorded 1/3")


def test_cli_inexact_certificate_exits_1(capsys, tmp_path):
    path = tmp_path / "cert.json"
    run(capsys, "certify", "--steps", "2", "--arith", "float", "--json", str(path))
    code, out, _ = run(capsys, "verify", str(path))
    assert code == 1 and out.splitlines()[-1].startswith("NOT VERIFIED: exact arithmetic:")


@pytest.mark.parametrize("content, message", [
    (None, "no such certificate file"),
    ("{not json", "not valid JSON"),
    ("[1, 2]", "expected a JSON object"),
    ('{"schema_version": 2}', "missing key 'system'"),
    ('{"schema_version": 2, "system": {"family": "lie-poisson", "n": 2, "a": ["1", "2"], '
     '"b": ["0", "1"], "c": ["1", "x"]}}', "c[1]"),
    (b"\xff\xfe\x00", "not"),
])
def test_cli_malformed_file_exits_2_with_one_line(capsys, tmp_path, content, message):
    path = tmp_path / "cert.json"
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif content is not None:
        path.write_text(content)
    code, out, err = run(capsys, "verify", str(path))
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert err.startswith("exact-khk: error: ") and message in err and "cert.json" in err


def test_cli_too_large_file_exits_2(capsys, tmp_path, monkeypatch):
    path = tmp_path / "cert.json"
    path.write_text(json.dumps(roundtrip(certify(steps=1, signs=["-++"]))))
    monkeypatch.setattr(cli_verify, "MAX_CERTIFICATE", 100)
    code, _, err = run(capsys, "verify", str(path))
    assert code == 2 and "larger than 100 bytes" in err and len(err.strip().splitlines()) == 1


def test_cli_tampered_structure_exits_2(capsys, tmp_path, lp_cert):
    data = copy.deepcopy(lp_cert)
    data["checks"][0]["expected"] = "yes"
    path = tmp_path / "cert.json"
    path.write_text(json.dumps(data))
    code, _, err = run(capsys, "verify", str(path))
    assert code == 2 and "checks[0].expected" in err and len(err.strip().splitlines()) == 1


def test_verifier_gradient_closed_form_equals_dual_numbers():
    """The verifier's closed form of grad H~_M (two solves) equals its dual-number derivative
    through H~_M (one solve over dual numbers), with ==, in Q, Q(zeta_3) and F_P, for H~ and a K~."""
    from exact_khk.certification.verify.fields import _Cyclotomic, _FlintRationals, _PrimeField
    from exact_khk.certification.verify.maps import _htilde, _involution, _lp_hessian, _matmul, gradient, htilde_gradient

    a, b, c = ([Fraction(t) for t in v] for v in ((1, 0, 2), (0, 1, 0), (3, 1, 1)))
    for F in (_FlintRationals(), _Cyclotomic(3), _PrimeField(1000003)):
        Hs = [[F.of(t) for t in row] for row in _lp_hessian(a, b, c)]
        x = [F.of(Fraction(t)) for t in (1, 2, -1, Fraction(1, 2), 0, 1)]
        e = F.of(Fraction(1, 10))
        for M in (Hs, _matmul(_involution(3, "-++", F), Hs)):
            assert htilde_gradient(M, x, e, 3) == gradient(lambda y, M=M: _htilde(M, y, e, 3), x)
