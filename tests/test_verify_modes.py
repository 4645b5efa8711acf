"""``verify`` re-derives the records of the engine's other modes: ``identity:`` records (at its
own random draws over F_P) and ``proof:`` records (in SymPy's Q(x, ε)).

Certificates made by the library's ``certify --identities`` for the paper's family (n = 2), a
catalogue system (euler-top) and a system file (docs/examples/cubic.toml, also ``--prove``)
VERIFY (exit 0); each kind of tampering of an identity or proof record — holds or expected
flipped, dropped, invented, statement edited, evidence upgraded, the prime changed — is refused,
naming the record; a false identity claim passed off as holding is refused (holds is recomputed
at the verifier's own draws, never read).
"""

import copy
import json
import pathlib
import re

import pytest

from exact_khk.arith.cyclotomic import DEFAULT_PRIME
from exact_khk.certification import certify
from exact_khk.certification.records import Certificate
from exact_khk.certification.verify import verify
from exact_khk.certification.verify.modes import identity_signs, stated_bound
from exact_khk.certification.verify.fields import _PrimeField
from exact_khk.cli.main import main
from exact_khk.systems.lie_poisson.system import LiePoissonSystem, default_involutions
from tests.test_verify_tamper import example_toml

DOCS = pathlib.Path(__file__).parent.parent / "docs"
GF = f"gf:{DEFAULT_PRIME}"
SEED = 20261128  # the verifier's own draws, fixed for reproducible messages


@pytest.fixture(scope="module")
def certs(tmp_path_factory):
    lp2 = LiePoissonSystem.from_vectors("1,2", "0,1", "3,1")
    made = {"lp2": certify(lp2, x0=["1", "3", "1/2", "2"], steps=2, identities=GF),
            "euler-top": certify("euler-top", steps=2, identities=GF),
            "cubic": certify(DOCS / "examples" / "cubic.toml", steps=2, identities=GF, prove=True),
            "example": certify(example_toml(tmp_path_factory), steps=2, identities=GF)}
    return {k: json.loads(json.dumps(c.to_json())) for k, c in made.items()}


def consistent(d):
    """``d`` with status, valid and verdict rewritten to agree with its (tampered) records."""
    cert = Certificate.from_json(d)
    d.update(status=cert.status, valid=cert.valid, verdict=cert.verdict())
    return d


def refused(d, naming=None):
    report = verify(d, seed=SEED)
    assert not report.ok and report.exit_status == 1, report.summary()
    if naming is not None:
        assert naming in report.verdict(), report.verdict()
    return report


def mode_records(d, prefix):
    return [i for i, c in enumerate(d["checks"]) if c["name"].startswith(prefix)]


@pytest.mark.parametrize("which", ["lp2", "euler-top", "cubic", "example"])
def test_certificates_with_other_modes_are_verified(certs, which):
    d = certs[which]
    report = verify(d, seed=SEED)
    assert report.ok and report.exit_status == 0, report.summary()
    n, k = len(d["checks"]), len(mode_records(d, "identity: "))
    assert k and report.records == report.rederived == n
    assert report.verdict().startswith(f"VERIFIED: the record of this {d['status']} certificate is correct: "
                                       f"re-derived {n} of {n} records independently, with its orbit, values and "
                                       f"status ({k} of them as identities at the verifier's own random draws")
    assert f"seed {SEED}" in report.summary() and "(the engine's Deg of the claim: read, not re-derived)" in \
        report.summary()
    if which == "cubic":
        assert f"; {len(mode_records(d, 'proof: '))} of them as identities of rational functions in SymPy)" \
            in report.verdict()


def test_fresh_draws_by_default(certs):
    a, b = verify(certs["euler-top"]), verify(certs["euler-top"])
    assert a.exit_status == b.exit_status == 0
    seed = lambda r: re.search(r"seed (\d+)", r.summary()).group(1)  # noqa: E731
    assert seed(a) != seed(b)  # 64 random bits each


def test_the_family_identity_records_cover_the_involutions_gf_p_holds():
    # P = 1 mod 3: every involution of n = 3; P = 2 mod 3 (P = 1000037): the rational ones only
    for P in (DEFAULT_PRIME, 1000037):
        assert identity_signs(3, _PrimeField(P)) == default_involutions(3, f"gf:{P}")
    assert identity_signs(2, _PrimeField(DEFAULT_PRIME)) == default_involutions(2, GF)
    assert stated_bound(31, 7, 42, DEFAULT_PRIME, 2) == (31 / (DEFAULT_PRIME - 7 * 42 - 1)) ** 2


# --- each kind of tampering of an identity record ------------------------------------------------


def first_claim(d, prefix="identity: "):
    return next(i for i in mode_records(d, prefix) if d["checks"][i]["expected"] and d["checks"][i]["holds"]
                and "rank" not in d["checks"][i]["name"])


def first_control(d, prefix="identity: "):
    return next(i for i in mode_records(d, prefix) if not d["checks"][i]["expected"])


def tamper_record(d, i, **fields):
    d["checks"][i].update(fields)
    return d["checks"][i]["name"]


TAMPER = {
    "holds flipped": lambda d, i: tamper_record(d, i, holds=False),
    "control holds flipped": lambda d, i: tamper_record(d, first_control(d), holds=True, residual="0"),
    "expected flipped": lambda d, i: tamper_record(d, i, expected=False),
    "claim text edited": lambda d, i: tamper_record(d, i, claim=d["checks"][i]["claim"] + " for every x"),
    "evidence upgraded": lambda d, i: tamper_record(d, i, evidence="symbolic proof: identity in Q(x, eps)"),
    "failure bound lowered": lambda d, i: tamper_record(
        d, i, evidence=re.sub(r"failure bound <= \S+;", "failure bound <= 1e-99;", d["checks"][i]["evidence"])),
    "control evidence upgraded": lambda d, i: tamper_record(d, first_control(d), evidence="symbolic disproof"),
    "control made inapplicable": lambda d, i: tamper_record(d, first_control(d), applicable=False),
    "prime changed in arith": lambda d, i: tamper_record(d, i, arith="gf:1000003"),
    "arith not a prime": lambda d, i: tamper_record(d, i, arith="gf:1000001"),
}


@pytest.mark.parametrize("which", ["lp2", "euler-top", "cubic"])
@pytest.mark.parametrize("what", sorted(TAMPER))
def test_each_tampering_of_an_identity_record_is_refused(certs, which, what):
    d = copy.deepcopy(certs[which])
    name = TAMPER[what](d, first_claim(d))
    report = refused(consistent(d))
    failing = report.failures()[0][0]
    assert failing in (f"record {name}", "identity records"), report.summary()
    assert name in report.verdict() or failing == "identity records"


@pytest.mark.parametrize("which", ["lp2", "euler-top", "cubic"])
def test_identity_records_dropped_invented_or_reordered(certs, which):
    d = copy.deepcopy(certs[which])
    i = first_control(d)
    name = d["checks"].pop(i)["name"]
    refused(consistent(d), f"{name!r} is missing (dropped")
    d = copy.deepcopy(certs[which])
    invented = dict(d["checks"][first_claim(d)], name="identity: integral Q conserved by Phi_f")
    d["checks"].insert(first_claim(d) + 1, invented)
    refused(consistent(d), "'identity: integral Q conserved by Phi_f' is not a record the system and options imply")
    d = copy.deepcopy(certs[which])
    ids = mode_records(d, "identity: ")
    d["checks"][ids[0]], d["checks"][ids[1]] = d["checks"][ids[1]], d["checks"][ids[0]]
    refused(d, "records reordered")


def test_the_family_rank_records_are_rederived(certs):
    d = copy.deepcopy(certs["lp2"])
    c = next(c for c in d["checks"] if c["name"].startswith("identity: rank of integral gradients ("))
    assert c["residual"] == "rank 2"
    c["residual"] = "rank 3"
    refused(d, f"record {c['name']}: recorded residual 'rank 3', re-derived 'rank 2'")


def test_every_identity_record_with_the_prime_changed_is_refused(certs):
    d = copy.deepcopy(certs["euler-top"])
    for i in mode_records(d, "identity: "):
        d["checks"][i]["arith"] = "gf:1000003"
    report = refused(d)
    assert f"evidence states P = {DEFAULT_PRIME}, 2 random points in F_P^4, S = 7 checks; re-derived: P = 1000003" \
        in report.verdict()


def test_a_false_identity_passed_off_as_holding_is_refused(certs):
    d = copy.deepcopy(certs["example"])  # the INVALID example: some identities are refuted
    assert verify(d, seed=SEED).exit_status == 0
    false = next(c for c in d["checks"] if c["name"].startswith("identity: ") and c["expected"]
                 and c["holds"] is False)
    model = next(c for c in d["checks"] if c["name"].startswith("identity: ") and c["holds"] is True
                 and c["evidence"].startswith("probabilistic"))
    false.update(holds=True, residual="0", evidence=model["evidence"])
    refused(consistent(d), f"record {false['name']}: recorded holds = true, re-derived holds = false (refuted at draw")


def test_an_identity_claim_undecided_for_a_tiny_prime_is_rederived_so():
    """Over F_101 the bound (d/(P - S D1 - 1))^2 is 1 (S D1 = 128 > P): the engine leaves the claims
    undecided; the verifier re-derives that and refuses them recorded as holding."""
    d = json.loads(json.dumps(certify(DOCS / "examples" / "cubic.toml", steps=2, identities="gf:101").to_json()))
    claims = [c for c in d["checks"] if c["name"].startswith("identity: ") and c["expected"]
              and c["evidence"].startswith("probabilistic")]
    assert claims and all(c["holds"] is None for c in claims)
    assert verify(d, seed=SEED).exit_status == 0
    claims[0]["holds"] = True
    refused(consistent(d), "P is too small for a bound below 1: undecided")


# --- proof records ------------------------------------------------------------------------------


PROOF_TAMPER = {
    "holds flipped": lambda d, i: tamper_record(d, i, holds=False),
    "expected flipped": lambda d, i: tamper_record(d, i, expected=False),
    "claim text edited": lambda d, i: tamper_record(d, i, claim=d["checks"][i]["claim"] + " for every x"),
    "evidence changed": lambda d, i: tamper_record(d, i, evidence="symbolic proof: identity in Q(x0, eps)"),
    "residual of a claim": lambda d, i: tamper_record(d, i, residual="x0 - 1"),
    "residual of a control": lambda d, i: tamper_record(d, first_control(d, "proof: "), residual="x0 - 1"),
    "residual not a rational function": lambda d, i: tamper_record(d, first_control(d, "proof: "), residual="exit()"),
    "arith": lambda d, i: tamper_record(d, i, arith="qfunc[x0,x1,eps,t]"),
    "dropped": lambda d, i: d["checks"].pop(i)["name"],
    "invented": lambda d, i: d["checks"].insert(i, dict(d["checks"][i], name="proof: integral Q conserved"))
    or "proof: integral Q conserved",
}


def _proof_tampering_refused(d0, what):
    d = copy.deepcopy(d0)
    name = PROOF_TAMPER[what](d, first_claim(d, "proof: "))
    report = refused(consistent(d))
    assert name in report.verdict(), report.verdict()


@pytest.mark.parametrize("what", sorted(PROOF_TAMPER))
def test_each_tampering_of_a_proof_record_is_refused(certs, what):
    _proof_tampering_refused(certs["cubic"], what)


def test_proofs_beyond_the_budget_are_not_rechecked(certs, tmp_path, capsys):
    d = certs["cubic"]
    report = verify(d, seed=SEED, proof_budget=0)
    proofs = len(mode_records(d, "proof: "))
    assert report.ok and report.partial and report.exit_status == 4, report.summary()
    assert report.rederived == len(d["checks"]) - proofs
    assert "not re-checked: a symbolic proof beyond the verifier's time budget of 0 s" in report.summary()
    path = tmp_path / "cubic.json"
    path.write_text(json.dumps(d))
    assert main(["verify", str(path)]) == 0
    assert capsys.readouterr().out.splitlines()[-1].startswith("VERIFIED: ")


@pytest.mark.slow
def test_euler_top_proofs_are_rederived_and_tampering_refused():
    d = json.loads(json.dumps(certify("euler-top", steps=2, prove=True).to_json()))
    report = verify(d)
    n = len(d["checks"])
    assert report.exit_status == 0 and report.rederived == n, report.summary()
    for what in PROOF_TAMPER:
        _proof_tampering_refused(d, what)


@pytest.mark.slow
def test_family_proofs_in_dimension_4_are_not_rechecked_but_covered():
    lp2 = LiePoissonSystem.from_vectors("1,2", "0,1", "3,1")
    d = json.loads(json.dumps(certify(lp2, x0=["1", "3", "1/2", "2"], steps=2, prove=True).to_json()))
    report = verify(d)
    proofs = len(mode_records(d, "proof: "))
    assert report.exit_status == 4 and report.rederived == len(d["checks"]) - proofs, report.summary()
    assert "a symbolic proof in dimension 4" in report.summary()
    d["checks"].pop(mode_records(d, "proof: ")[3])
    assert verify(consistent(d)).exit_status == 1  # the names are still covered
