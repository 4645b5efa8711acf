"""The catalogue of classic KHK systems (exact_khk/systems/catalogue/*.toml).

Golden data (tests/data/golden_catalogue.json) is produced by
scripts/generate_catalogue_golden.py with SymPy alone, straight from the formula
x~ = x + 2 eps (I - eps f'(x))^{-1} f(x) and SymPy's LUsolve — not by this
library — and every exact arithmetic must reproduce it with ==.
"""

import json
import pathlib

import pytest

from exact_khk import KahanMap, certify
from exact_khk.cli.main import main
from exact_khk.systems.catalogue import load, names, resolve

GOLDEN = json.loads((pathlib.Path(__file__).parent / "data" / "golden_catalogue.json").read_text())
EXACT = ("fraction", "gmpy2", "flint")


def test_the_catalogue_has_the_classic_systems():
    assert {"euler-top", "lotka-volterra", "lagrange-top", "cmoq-cubic"} <= set(names())
    for name in names():
        s = load(name)
        assert s.source, f"{name}: cite the source"
        assert resolve(name) is s


@pytest.mark.parametrize("name", sorted(GOLDEN))
@pytest.mark.parametrize("arith", EXACT)
def test_orbits_equal_the_sympy_golden_orbits(name, arith):
    gold = GOLDEN[name]
    s = load(name)
    steps = min(len(gold["orbit"]) - 1, 12 if name == "lotka-volterra" else 60)
    phi = KahanMap(s.field("f"), gold["eps"], arith)
    ar = phi.arith
    pts = phi.orbit(gold["x0"], steps)
    assert [[ar.format(t) for t in p] for p in pts] == gold["orbit"][:steps + 1]
    e = ar.convert(phi.eps_exact)
    for iname, values in gold.get("integrals", {}).items():
        fn = s.integrals()[iname]
        assert [ar.format(fn(ar, p, e)) for p in pts] == values[:steps + 1]


@pytest.mark.parametrize("arith", EXACT)
def test_euler_top_integrals_conserved_for_50_steps(arith):
    s = load("euler-top")
    cert = certify(s, steps=50, arith=arith, claims=["integrals"])
    assert cert.status == "VALID", cert.table()
    assert len(s.integrals()) >= 2
    for name in s.integrals():
        assert cert.check(f"integral {name} conserved by Phi_f").holds is True


def test_lotka_volterra_is_poisson_and_its_naive_invariant_fails():
    s = load("lotka-volterra")
    cert = certify(s, steps=8, claims=["poisson", "reversibility"])
    assert cert.status == "VALID", cert.table()
    assert cert.check("Poisson map Phi_f").holds is True
    controls = [c for c in cert.checks if not c.expected and c.name.startswith("control:") and "conserved" in c.name]
    assert controls and all(c.holds is False for c in controls)


def test_cmoq_modified_energy_conserved_exactly():
    cert = certify(load("cmoq-cubic"), steps=8, claims=["cmoq"])
    assert cert.status == "VALID", cert.table()
    assert cert.check("CMOQ modified energy conserved").holds is True
    assert cert.check("CMOQ invariant measure").holds is True
    assert cert.check("control: H conserved").holds is False


@pytest.mark.parametrize("name", ["euler-top", "lagrange-top", "cmoq-cubic", "lotka-volterra"])
def test_every_catalogue_system_certifies_from_the_command_line(name, capsys):
    steps = "6" if name == "lotka-volterra" else "10"
    assert main(["certify", "--system", name, "--steps", steps]) == 0
    assert capsys.readouterr().out.strip().splitlines()[-1].startswith("VALID")


def test_systems_command_lists_the_catalogue(capsys):
    assert main(["systems"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in names())
