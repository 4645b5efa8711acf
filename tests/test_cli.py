"""The ``exact-khk orbit`` command."""

import json

import pytest

from exact_khk import KahanMap, LiePoissonSystem
from exact_khk.cli.main import main


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_orbit_json_matches_library(capsys):
    code, out, _ = run(capsys, "orbit", "--n", "3", "--a", "1,0,2", "--b", "0,1,0", "--c", "3,1,1",
                       "--x0", "1,2,-1,1/2,0,1", "--eps", "1/10", "--steps", "4", "--field", "g",
                       "--signs", "-++", "--arith", "gmpy2", "--json")
    assert code == 0
    data = json.loads(out)
    assert len(data["orbit"]) == 5 and all(len(p) == 6 for p in data["orbit"])
    sys3 = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")
    phi = KahanMap(sys3.field("g", "-++"), "1/10", "fraction")
    assert data["orbit"] == [[phi.arith.format(t) for t in p] for p in phi.orbit(["1", "2", "-1", "1/2", "0", "1"], 4)]
    assert data["orbit"][0] == ["1", "2", "-1", "1/2", "0", "1"]


def test_orbit_default_readable(capsys):
    code, out, _ = run(capsys, "orbit", "--steps", "3")
    assert code == 0
    assert "Lie–Poisson system n=3" in out and "exact" in out
    assert len([l for l in out.splitlines() if l.strip()[:1].isdigit()]) == 4


def test_orbit_float_json_has_all_digits(capsys):
    code, out, _ = run(capsys, "orbit", "--steps", "2", "--arith", "mp:200", "--json")
    assert code == 0
    val = json.loads(out)["orbit"][2][0]
    assert len(val.replace("-", "").replace(".", "")) >= 55  # 200 bits ≈ 60 digits


def test_seed_draws_system_and_point(capsys):
    code, out, _ = run(capsys, "orbit", "--n", "4", "--seed", "3", "--steps", "2", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["system"]["n"] == 4 and len(data["orbit"][0]) == 8


@pytest.mark.parametrize("argv, fragment", [
    (["orbit", "--a", "1,2", "--b", "1", "--c", "1,1", "--x0", "1,1,1,1"], "--b: expected 2 entries"),
    (["orbit", "--a", "1,2", "--b", "1,1", "--c", "1,1", "--x0", "1,1,1,x"], "--x0[3]"),
    (["orbit", "--a", "1", "--b", "1", "--c", "1", "--x0", "1,1"], "n >= 2"),
    (["orbit", "--n", "1", "--seed", "2"], "n >= 2"),
    (["orbit", "--eps", "0"], "--eps"),
    (["orbit", "--eps", "1/0"], "--eps"),
    (["orbit", "--arith", "quad"], "unknown arithmetic"),
    (["orbit", "--steps", "many"], "--steps"),
    (["orbit", "--field", "g", "--signs", "+-+"], "not rational"),
])
def test_malformed_input_exit_2(capsys, argv, fragment):
    if argv[-1] == "+-+":  # n = 3: '+-+' splits the class {1, 2}
        pass
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert fragment in err and len(err.strip().splitlines()) == 1
    assert out == ""


def test_singular_step_exit_3(capsys):
    # a point and ε with det(I − ε f'(x)) = 0 (see test_core._rational_singular_eps)
    from .test_core import _rational_singular_eps

    s = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3")
    eps = _rational_singular_eps(s, ["1", "0", "2", "1"])
    code, out, err = run(capsys, "orbit", "--a", "1,2", "--b", "0,1", "--c", "-1,3", "--x0", "1,0,2,1",
                         "--eps", str(eps), "--steps", "3")
    assert code == 3
    assert "step 1" in err and str(eps) in err and len(err.strip().splitlines()) == 1


def test_orbit_method_choice(capsys):
    """--method picks how steps are solved; every exact method prints the same orbit, and
    the output says which path ran."""
    orbits = {}
    for method in ("auto", "dense", "structured", "split"):
        code, out, _ = run(capsys, "orbit", "--steps", "6", "--method", method, "--json")
        assert code == 0
        data = json.loads(out)
        assert data["method"] == method
        orbits[method] = data["orbit"]
        assert data["path"] == {"auto": "split", "dense": "dense",
                                "structured": "structured", "split": "split"}[method]
    assert orbits["auto"] == orbits["dense"] == orbits["structured"] == orbits["split"]
    code, out, _ = run(capsys, "orbit", "--steps", "1", "--method", "split")
    assert code == 0 and "method split: split" in out


def test_orbit_method_refused_exit_2(capsys):
    code, out, err = run(capsys, "orbit", "--steps", "1", "--method", "split", "--arith", "float")
    assert code == 2 and out == ""
    assert "'split' needs" in err and len(err.strip().splitlines()) == 1
    code, out, err = run(capsys, "orbit", "--method", "fastest")
    assert code == 2 and "--method" in err


def test_liouville_default_runs_on_the_built_in_system(capsys):
    """`exact-khk liouville` with no options takes cyclo:n (n = 3): every involution needs
    Q(omega); flint is refused with the arithmetic named."""
    from exact_khk.cli.main import main

    assert main(["liouville"]) == 0
    out = capsys.readouterr().out
    assert "exact in Q(zeta_3)" in out and "control: integral H~ conserved by Phi_control" in out
    assert main(["liouville", "--arith", "flint"]) == 2
    assert "cyclo:3" in capsys.readouterr().err


def test_a_failed_or_interrupted_command_leaves_no_new_empty_folder(capsys, tmp_path, monkeypatch):
    new = tmp_path / "new" / "deeper"
    code, _, err = run(capsys, "hard", "--out", str(new), "--long-steps", "0")  # refused after the folder
    assert code == 2 and "--long-steps" in err
    assert not (tmp_path / "new").exists()
    kept = tmp_path / "kept"  # control: a folder that was there before stays, empty or not
    kept.mkdir()
    code, _, _ = run(capsys, "hard", "--out", str(kept), "--long-steps", "0")
    assert code == 2 and kept.is_dir()
    from exact_khk.studies import scaling

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt
    monkeypatch.setattr(scaling, "scaling_study", interrupted)
    code, _, err = run(capsys, "scale", "--steps", "2", "--ariths", "float", "--out", str(new))
    assert code == 130 and "Ctrl-C" in err and not (tmp_path / "new").exists()
    monkeypatch.undo()
    # control: a command that succeeds keeps its new folder (and what it wrote)
    code, _, _ = run(capsys, "scale", "--steps", "2", "--ariths", "float", "--out", str(new))
    assert code == 0 and any(new.iterdir())


def test_a_singular_orbit_from_a_seeded_point_says_where_the_point_came_from(capsys):
    """n = 2, seed 4 (c = 0): the orbit of the seed's point reaches det(I − εf′(x)) = 0 at
    step 5, exactly. The one-line error (exit 3) says the point was drawn for the seed and
    how to get another; with the same point given by --x0 it does not."""
    from exact_khk.cli.main import main

    assert main(["orbit", "--n", "2", "--seed", "4", "--steps", "6"]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "step 5" in err and "drawn for --seed 4" in err
    assert main(["orbit", "--n", "2", "--seed", "4", "--steps", "6", "--x0", "-3,2,3,-3"]) == 3
    err = capsys.readouterr().err
    assert "step 5" in err and "--seed" not in err


def test_orbit_table_in_gmpy2_equals_flint(capsys):
    """The table shows gmpy2's mpz rationals as it shows flint's (a seeded n = 8 orbit has an entry
    below the float range: shown by the leading digits, which took only fmpz)."""
    tables = []
    for arith in ("gmpy2", "flint"):
        assert main(["orbit", "--n", "8", "--seed", "1", "--arith", arith, "--steps", "2"]) == 0
        out = capsys.readouterr().out
        tables.append([ln for ln in out.splitlines() if ln.strip()[:1].isdigit()])
    assert tables[0] == tables[1] and len(tables[0]) == 3
