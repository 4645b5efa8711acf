"""Sweeps and bad input: every problem is refused up front with one line naming it and
exit status 2 (an InputError from the API), never a raw exception from inside."""

import json
import pathlib

import pytest

from exact_khk.cli.main import main
from exact_khk.errors import InputError
from exact_khk.sweep import ResultStore, parse_spec, run_sweep

PROBE = 'task = "probe"\ntimeout = 30\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = "0-1"\n'
CERTIFY = PROBE.replace('"probe"', '"certify"')
YEAR = "31,536,000"


def write_spec(tmp_path, text, name="spec.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def verdicts(out_dir):
    text = (pathlib.Path(out_dir) / "results.jsonl").read_text(encoding="utf-8")
    return [json.loads(line)["verdict"] for line in text.splitlines() if line.strip()]


# --- 1. the time limit: one check, from 0 to a year ------------------------------------


@pytest.mark.parametrize("value", ["inf", "1e400", "99999999999999999999999", "nan", "-1", "31536001"])
@pytest.mark.parametrize("dry_run", [False, True])
def test_cli_timeout_beyond_a_year_is_refused(tmp_path, capsys, value, dry_run):
    spec = write_spec(tmp_path, PROBE)
    out = tmp_path / "out"
    code, _, err = run(capsys, "sweep", spec, "--out", out, "--workers", "0", f"--timeout={value}",
                       *(["--dry-run"] if dry_run else []))
    assert code == 2, err
    assert err.startswith("exact-khk: error: --timeout: expected a number of seconds from 0 to ")
    assert YEAR in err and "(a year)" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()  # nothing ran


@pytest.mark.parametrize("value", ["99999999999999999999999", "inf", "nan", "1e400", "-1", "10" + "0" * 400])
def test_spec_timeout_beyond_a_year_is_refused_by_dry_run(tmp_path, capsys, value):
    spec = write_spec(tmp_path, PROBE.replace("timeout = 30", f"timeout = {value}"))
    code, _, err = run(capsys, "sweep", spec, "--out", tmp_path / "out", "--dry-run")
    assert code == 2, err
    assert f"spec.toml: timeout: expected a number of seconds from 0 to {YEAR} (a year)" in err


def test_the_largest_timeout_runs(tmp_path, capsys):
    spec = write_spec(tmp_path, PROBE.replace("timeout = 30", "timeout = 31536000"))
    code, _, err = run(capsys, "sweep", spec, "--out", tmp_path / "out", "--workers", "0", "--no-plots",
                       "--timeout", "31536000")
    assert code == 0, err
    assert verdicts(tmp_path / "out") == ["OK", "OK"]


def test_api_timeout_beyond_a_year_is_an_input_error(tmp_path):
    spec = parse_spec(PROBE, origin="probe.toml")
    with pytest.raises(InputError, match=r"^timeout: expected a number of seconds from 0 to 31,536,000"):
        run_sweep(spec, tmp_path / "out", workers=0, timeout=float("inf"), plots=False)
    assert not (tmp_path / "out").exists()
    with pytest.raises(InputError, match=r"^probe\.toml: timeout: .* 31,536,000"):
        parse_spec(PROBE.replace("timeout = 30", "timeout = 99999999999999999999999"), origin="probe.toml")


def test_probe_sleep_beyond_a_year_is_refused():
    with pytest.raises(InputError, match=r"^p\.toml: options\.sleep: expected a number of seconds from 0 to "
                                         r"31,536,000 \(a year\), got 1e\+300"):
        parse_spec(PROBE + "[options]\nsleep = 1e300\n", origin="p.toml")


# --- 2. a results file that no sweep wrote, a spec nested too deeply --------------------


GARBAGE = bytes(range(256)) * 12  # line 1: bytes 0-10 (UTF-8, not JSON); line 2 has 0x80


@pytest.mark.parametrize("mode", [[], ["--summary"], ["--dry-run"]])
def test_binary_results_file_is_refused_and_kept(tmp_path, capsys, mode):
    spec = write_spec(tmp_path, PROBE)
    out = tmp_path / "d"
    out.mkdir()
    (out / "results.jsonl").write_bytes(GARBAGE)
    code, _, err = run(capsys, "sweep", spec, "--out", out, "--workers", "0", "--no-plots", *mode)
    assert code == 2, err
    assert err == (f"exact-khk: error: --out: {str(out / 'results.jsonl')!r} is not the results file of a sweep: "
                   "line 2 is not UTF-8 text\n")
    assert (out / "results.jsonl").read_bytes() == GARBAGE  # left alone


def test_deeply_nested_results_line_names_file_and_line(tmp_path, capsys):
    spec = write_spec(tmp_path, PROBE)
    out = tmp_path / "e"
    out.mkdir()
    (out / "results.jsonl").write_text('{"not": "a record"}\n' + "[" * 100000 + "\n", encoding="utf-8")
    code, _, err = run(capsys, "sweep", spec, "--out", out, "--workers", "0", "--no-plots")
    assert code == 2, err
    assert "is not the results file of a sweep: line 2 nests JSON too deeply" in err
    assert str(out / "results.jsonl") in err and "recursion" not in err
    with pytest.raises(InputError, match="line 2 nests JSON too deeply"):
        ResultStore(out).read()


def test_last_line_cut_inside_a_character_is_still_dropped(tmp_path, capsys):
    """A crash may cut the last line inside a multi-byte character: that line is skipped
    (and cut off), as any line cut short, not taken for a foreign file."""
    spec = write_spec(tmp_path, PROBE)
    out = tmp_path / "out"
    assert run(capsys, "sweep", spec, "--out", out, "--workers", "0", "--no-plots")[0] == 0
    good = (out / "results.jsonl").read_bytes()
    cut = '{"key": "x", "detail": "Lie–'.encode()[:-1]  # the last of the 3 bytes of '–' is missing
    (out / "results.jsonl").write_bytes(good + cut)
    code, stdout, err = run(capsys, "sweep", spec, "--out", out, "--workers", "0", "--no-plots")
    assert code == 0, err
    assert "2 already done; 0 to run" in stdout and "1 unreadable lines" in stdout
    assert (out / "results.jsonl").read_bytes() == good


def test_deeply_nested_sweep_json_is_rewritten(tmp_path, capsys):
    spec = write_spec(tmp_path, PROBE)
    out = tmp_path / "out"
    out.mkdir()
    (out / "sweep.json").write_text("[" * 100000, encoding="utf-8")
    code, _, err = run(capsys, "sweep", spec, "--out", out, "--workers", "0", "--no-plots")
    assert code == 0, err
    assert json.loads((out / "sweep.json").read_text(encoding="utf-8"))["tasks"] == 2


@pytest.mark.parametrize("nested", ["[" * 10000 + "]" * 10000, "{a = " * 10000 + "1" + "}" * 10000])
def test_spec_nested_too_deeply_is_refused(tmp_path, capsys, nested):
    spec = write_spec(tmp_path, f"x = {nested}\n" + PROBE, name="deep.toml")
    code, _, err = run(capsys, "sweep", spec, "--out", tmp_path / "out", "--dry-run")
    assert code == 2, err
    assert err == f"exact-khk: error: {spec}: arrays or tables nested too deeply for a sweep spec\n"


# --- 3. option values that name arithmetics --------------------------------------------


@pytest.mark.parametrize("value, message", [
    ("gf:4", "options.identities: arith: gf:4: P must be a prime"),
    ("flint", "options.identities: expected a gf:P arithmetic (P prime), got 'flint'"),
    ("gf:x", "options.identities: arith: 'gf:x': the parameter after ':' must be an integer"),
])
def test_identities_is_checked_before_anything_runs(tmp_path, capsys, value, message):
    spec = write_spec(tmp_path, CERTIFY + f'[options]\nidentities = "{value}"\n')
    code, _, err = run(capsys, "sweep", spec, "--out", tmp_path / "out", "--dry-run")
    assert code == 2, err
    assert err.startswith(f"exact-khk: error: {spec}: {message}")


def test_identities_gf_prime_is_accepted():
    spec = parse_spec(CERTIFY + '[options]\nidentities = "gf:7"\n', origin="c.toml")
    assert spec.options == {"identities": "gf:7"}


# --- 4. an empty --out ---------------------------------------------------------------------


@pytest.mark.parametrize("mode", [[], ["--dry-run"], ["--summary"]])
def test_empty_out_is_refused(tmp_path, capsys, monkeypatch, mode):
    spec = write_spec(tmp_path, PROBE)
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    code, _, err = run(capsys, "sweep", spec, "--out", "", "--workers", "0", "--no-plots", *mode)
    assert code == 2, err
    assert err == "exact-khk: error: sweep: argument --out: expected a file or folder name, got an empty string\n"
    assert list(here.iterdir()) == []
    with pytest.raises(InputError, match="--out: expected a folder"):
        run_sweep(parse_spec(PROBE), "", workers=0, plots=False)
