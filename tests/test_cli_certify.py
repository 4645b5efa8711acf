"""The ``exact-khk certify`` and ``exact-khk integrals`` commands."""

import json
from fractions import Fraction as F

from exact_khk import LiePoissonSystem, get_arith
from exact_khk.cli.main import main
from exact_khk.systems.lie_poisson.invariants import Htilde
from exact_khk.systems.lie_poisson.system import DEFAULT_EPS, DEFAULT_X0, default_system, random_point


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_certify_default_is_valid_and_readable(capsys):
    code, out, _ = run(capsys, "certify")
    assert code == 0
    lines = out.splitlines()
    assert lines[0].startswith("Lie–Poisson system n=3")
    assert lines[2].split() == ["check", "expect", "holds", "residual", "time"]
    assert lines[-1].startswith("VALID: all 31 claims hold and all 4 negative controls fail "
                                "(flint arithmetic, n = 3, 20 steps")
    assert any(l.startswith("commutation Phi_f o Phi_g[-++]") and " true " in l for l in lines)
    assert any(l.startswith("control: commutation with non-associated field") and " false " in l for l in lines)


def test_certify_table_stays_narrow_when_a_name_is_long(capsys):
    """At n = 6 the rank check names all 15 integrals (199 characters): it gets a line of
    its own instead of widening every row of the table (at n = 12: 1 000 characters)."""
    code, out, _ = run(capsys, "certify", "--n", "6", "--seed", "2", "--steps", "2", "--quiet")
    assert code == 0
    lines = out.splitlines()
    at = next(i for i, l in enumerate(lines) if l.startswith("rank of integral gradients (H~, K~["))
    assert len(lines[at]) > 150 and lines[at + 1].split()[:3] == ["true", "true", "rank"]
    rows = [l for l in lines[2:] if not l.startswith("    ") and l != lines[at] and not l.startswith("evidence")]
    assert max(len(l) for l in rows[:-1]) <= 64 + 60, max(rows[:-1], key=len)


def test_certify_json_stdout_and_file(capsys, tmp_path):
    code, out, _ = run(capsys, "certify", "--steps", "3", "--signs", "-++", "--json", "-")
    assert code == 0
    data = json.loads(out)  # nothing but JSON on stdout
    assert data["valid"] is True and data["signs"] == ["-++"] and data["steps"] == 3
    assert {k["name"] for k in data["checks"]} >= {"commutation Phi_f o Phi_g[-++]", "reversibility Phi_f"}
    path = tmp_path / "cert.json"
    code, out, _ = run(capsys, "certify", "--steps", "2", "--n", "4", "--seed", "1", "--eps", "-1/8",
                       "--signs", "-+++", "--signs", "++-+", "--json", str(path))
    assert code == 0 and out.splitlines()[-1].startswith("VALID")
    data = json.loads(path.read_text())
    assert data["eps"] == "-1/8" and data["system"]["n"] == 4 and data["signs"] == ["-+++", "++-+"]


def test_certify_exit_statuses(capsys):
    code, out, _ = run(capsys, "certify", "--steps", "2", "--arith", "float")
    assert code == 4 and out.splitlines()[-1].startswith("INCONCLUSIVE")
    code, _, err = run(capsys, "certify", "--signs", "+-+")
    assert code == 2 and "not a rational involution" in err and "cyclo:3" in err
    assert len(err.strip().splitlines()) == 1
    code, _, err = run(capsys, "certify", "--steps", "0")
    assert code == 2 and "--steps" in err
    code, _, err = run(capsys, "certify", "--poisson-points", "0")
    assert code == 2 and "--poisson-points" in err
    # det(I - eps f'(x0)) vanishes at eps = 1/5 for this n = 2 system and point
    code, _, err = run(capsys, "certify", "--a", "1,2", "--b", "0,1", "--c", "-1,3", "--x0", "1,0,2,1", "--eps", "1/5")
    assert code == 3 and "step 1" in err


def test_integrals_text_and_json(capsys):
    s = default_system()
    ar = get_arith("fraction")
    x = [ar(F(t)) for t in DEFAULT_X0]
    want_H = ar.format(Htilde(s.field("f"), x, DEFAULT_EPS, ar))
    want_K = {sg: ar.format(Htilde(s.field("g", sg), x, DEFAULT_EPS, ar)) for sg in ("+--", "-++")}
    code, out, _ = run(capsys, "integrals")
    assert code == 0
    assert f"H~ = {want_H}" in out and f"K~[-++] = {want_K['-++']}" in out
    code, out, _ = run(capsys, "integrals", "--json", "--arith", "gmpy2")
    data = json.loads(out)
    assert code == 0 and data["Htilde"] == want_H and data["Ktilde"] == want_K
    # after steps of Phi_f the values are the same (conservation), at another point
    code, out, _ = run(capsys, "integrals", "--json", "--steps", "4")
    later = json.loads(out)
    assert later["Htilde"] == want_H and later["Ktilde"] == want_K and later["x"] != data["x"]
    code, out, _ = run(capsys, "integrals", "--n", "2", "--seed", "3", "--json")
    data = json.loads(out)
    assert set(data["Ktilde"]) == {"+-", "-+"}
    s2 = LiePoissonSystem.random(2, 3)
    x2 = [ar(t) for t in random_point(2, 3)]
    assert data["Ktilde"]["+-"] == ar.format(Htilde(s2.field("g", "+-"), x2, DEFAULT_EPS, ar))


def test_a_drawn_point_whose_orbit_meets_a_singular_step_is_redrawn(capsys):
    """certify --n 2 --seed 4: the seed's first point meets a singular step at step 5 (exit 3 when given as
    --x0); the tool drew it, so it takes the seed's next draw and says so; the certificate is VALID there."""
    system = LiePoissonSystem.random(2, 4)
    first = random_point(2, 4, system=system, eps=DEFAULT_EPS)
    second = random_point(2, 4, system=system, eps=DEFAULT_EPS, skip=1)
    assert first != second
    x0 = ",".join(str(t) for t in first)
    assert main(["certify", "--n", "2", "--seed", "4", "--x0", x0]) == 3       # the user's point: no redraw
    capsys.readouterr()
    assert main(["certify", "--n", "2", "--seed", "4"]) == 0
    out, err = capsys.readouterr()
    assert "draw 2 is used" in err and "singular step at step 5" in err and "VALID" in out
    assert f"x0 = ({', '.join(str(t) for t in second)})" in out
