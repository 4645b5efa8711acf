"""exact-khk atlas: a two-system atlas on a tmp folder (--quick, in-process), its rows, findings,
resume, and bad input."""

import shutil
from pathlib import Path

import pytest

from exact_khk.cli.main import main

CAT = Path(__file__).parent.parent / "exact_khk" / "systems" / "catalogue"


@pytest.fixture
def folder(tmp_path):
    d = tmp_path / "systems"
    d.mkdir()
    for name in ("euler-top", "lotka-volterra"):
        shutil.copy(CAT / f"{name}.toml", d / f"{name}.toml")
    return d


def test_two_system_atlas_rows_findings_resume(folder, tmp_path):
    md, out = tmp_path / "atlas.md", tmp_path / "out"
    args = ["atlas", "--quick", "--systems", str(folder), "--out", str(out), "--workers", "0", "--markdown", str(md)]
    assert main(args) == 0
    text = md.read_text()
    rows = [ln for ln in text.splitlines() if ln.startswith("| ") and "euler-top" in ln or "lotka-volterra" in ln
            and ln.startswith("| ")]
    assert len([ln for ln in rows if "evidence" not in ln and "seconds" not in ln and "|---" not in ln]) >= 2
    assert "## Findings" in text and "## Rules" in text and "## Times" in text
    assert (tmp_path / "figures" / "atlas_degrees.png").stat().st_size > 0
    lines = sum(len(p.read_text().splitlines()) for p in out.glob("*/results.jsonl"))
    assert lines == 4  # two systems, two step sizes
    assert main(args) == 0  # resumed: nothing rerun
    assert sum(len(p.read_text().splitlines()) for p in out.glob("*/results.jsonl")) == lines


def test_bad_folder_exits_2(tmp_path, capsys):
    assert main(["atlas", "--systems", str(tmp_path / "missing"), "--out", str(tmp_path / "o"),
                 "--markdown", str(tmp_path / "a.md")]) == 2
    err = capsys.readouterr().err
    assert "--systems" in err and "Traceback" not in err


def test_default_report_outside_the_repository_is_refused_before_work(tmp_path, monkeypatch, capsys):
    """Run where there is no docs/ folder: the default report path is refused up front, naming --markdown."""
    monkeypatch.chdir(tmp_path)
    assert main(["atlas", "--out", str(tmp_path / "o"), "--quick"]) == 2
    err = capsys.readouterr().err
    assert "--markdown PATH" in err and "Traceback" not in err and not (tmp_path / "o").exists()


def test_figure_is_checked_before_the_sweeps_and_its_new_folder_removed_on_failure(folder, tmp_path, capsys):
    """--figure in a new folder is prepared before the work; when the run then fails (here --out
    cannot be created), the empty folder is removed and no report or figure is left."""
    md, fig = tmp_path / "a.md", tmp_path / "new" / "sub" / "f.png"
    assert main(["atlas", "--quick", "--systems", str(folder), "--markdown", str(md), "--figure", str(fig),
                 "--out", "/proc/x"]) == 5
    err = capsys.readouterr().err
    assert "--out" in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "new").exists() and not md.exists()
    assert main(["atlas", "--quick", "--systems", str(folder), "--markdown", str(md), "--figure",
                 str(tmp_path / "f.jpg"), "--out", str(tmp_path / "o")]) == 2  # not a figure format: before any work
    assert "--figure" in capsys.readouterr().err and not (tmp_path / "o").exists()


def test_a_system_that_cannot_be_classified_is_a_finding_with_its_error(tmp_path, capsys):
    """A folder's system beyond classify's dimension limit (64): its row and its finding give the
    task's error, not 'ERROR ... no result' counted as going beyond the literature."""
    d = tmp_path / "systems"
    d.mkdir()
    v = [f"x{i}" for i in range(70)]
    (d / "big.toml").write_text('format = 1\nname = "big"\nvariables = [' + ", ".join(f'"{x}"' for x in v)
                                + "]\n[field]\n" + "".join(f'{v[i]} = "{v[(i + 1) % 70]}*{v[(i + 2) % 70]}"\n'
                                                            for i in range(70)))
    md = tmp_path / "a.md"
    assert main(["atlas", "--quick", "--systems", str(d), "--out", str(tmp_path / "o"), "--workers", "0",
                 "--markdown", str(md)]) == 0
    findings = md.read_text().split("## Findings")[1].split("## Times")[0]
    assert "- **big**: not classified: InputError: system: dimension 70 exceeds 64" in findings
    assert "goes beyond" not in findings


def test_two_files_naming_one_system_are_refused_before_work(folder, tmp_path, capsys):
    """A second file named 'euler-top' would have replaced the first's row without a word."""
    shutil.copy(CAT / "euler-top.toml", folder / "copy.toml")
    assert main(["atlas", "--quick", "--systems", str(folder), "--out", str(tmp_path / "o"),
                 "--markdown", str(tmp_path / "a.md")]) == 2
    err = capsys.readouterr().err
    assert "'euler-top'" in err and "copy.toml" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


ROOT = Path(__file__).parent.parent
ATLAS = ROOT / "docs" / "atlas.md"
#: the documented command that writes docs/atlas.md (docs/atlas.md's header names it)
ATLAS_ARGS = ["atlas", "--out", "out/atlas"]


def _rows(text):
    """{system: (literature, default-eps verdict, second-eps verdict)} from the Verdicts table."""
    table = text.split("## Verdicts")[1].split("## Rules")[0]
    out = {}
    for ln in table.splitlines():
        cells = [c.strip() for c in ln.strip().strip("|").split("|")]
        if len(cells) < 6 or cells[0] in ("system", "---"):
            continue
        out[cells[0]] = (cells[2].split(" ")[0], cells[3].split(" ")[0], cells[4].split(" ")[0])
    return out


def test_committed_atlas_covers_the_catalogue_and_agrees_or_lists_a_finding():
    from exact_khk.systems.catalogue import load, names

    text = ATLAS.read_text()
    assert "--quick" not in text.split("## Verdicts")[0], "docs/atlas.md must come from the full atlas"
    rows = _rows(text)
    assert set(rows) == set(names())
    findings = text.split("## Findings")[1].split("## Times")[0]
    for name, (lit, va, vb) in rows.items():
        # the literature column is what the catalogue says, and a verdict that differs from a stated
        # claim (or one that goes beyond an unknown) is listed under Findings
        assert lit == str((load(name).literature or {}).get("integrable", "unknown"))
        expect = {"yes": "integrable", "no": "non-integrable"}.get(lit)
        disagrees = expect is not None and (va != expect or vb != expect)
        beyond = expect is None and (va != "undetermined" or vb != "undetermined")
        if disagrees or beyond:
            assert f"**{name}**" in findings, name
        assert va in ("integrable", "non-integrable", "undetermined") and vb in (
            "integrable", "non-integrable", "undetermined"), name


@pytest.mark.slow
def test_committed_atlas_is_what_the_documented_command_writes(tmp_path, monkeypatch):
    from exact_khk.sweep.atlas import mask_times

    monkeypatch.chdir(tmp_path)
    (tmp_path / "docs").mkdir()  # the documented command runs from the project's root, beside docs/
    assert main(ATLAS_ARGS) == 0
    assert mask_times((tmp_path / "docs" / "atlas.md").read_text()) == mask_times(ATLAS.read_text())
