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
