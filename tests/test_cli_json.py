"""One output convention: ``--json [PATH]`` in every command that writes one JSON document
(stdout with no PATH or ``-``, instead of the table; a file written atomically otherwise, with
the table still printed), ``--out DIR`` for the commands that write several files."""

from __future__ import annotations

import json

import pytest

from exact_khk.cli.main import build_parser, main

#: (command line, a key of its JSON document): cheap runs of every command with --json
COMMANDS = [
    (["orbit", "--steps", "2"], "orbit"),
    (["certify", "--steps", "1", "--signs", "-++"], "checks"),
    (["integrals", "--steps", "1"], "Htilde"),
    (["systems"], "families"),
    (["degrees", "--system", "lotka-volterra", "--steps", "5", "--no-heights"], "degrees"),
    (["find-integrals", "--system", "euler-top", "--degree", "1"], "system"),
    (["liouville", "--n", "2", "--seed", "1", "--steps", "1"], "records"),
    # the commands that write several files with --out DIR also give their main document by --json
    (["scale", "--steps", "3", "--ariths", "float", "--no-diagnostics"], "runs"),
    (["enclose", "--steps", "3", "--methods", "naive"], "runs"),
    (["hard", "--only", "long", "--long-steps", "5", "--no-precision", "--ariths", "float"], "cases"),
]


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def _keys(doc):
    """The document's keys (its values may hold timings, which vary from run to run)."""
    return sorted(doc) if isinstance(doc, dict) else doc


def _check(doc, key):
    assert isinstance(doc, list) if key is None else key in doc


@pytest.mark.parametrize("argv, key", COMMANDS, ids=[a[0] for a, _ in COMMANDS])
def test_json_stdout_and_file_give_the_same_document(capsys, tmp_path, argv, key):
    code, out, _ = run(capsys, *argv, "--json")
    assert code == 0
    bare = json.loads(out)  # stdout holds the document alone, no table
    _check(bare, key)
    code, out, _ = run(capsys, *argv, "--json", "-")
    assert code == 0 and _keys(json.loads(out)) == _keys(bare)
    path = tmp_path / "out.json"
    code, out, err = run(capsys, *argv, "--json", str(path))
    assert code == 0
    doc = json.loads(path.read_text())
    # the same document but for what varies from run to run (timings, versions)
    assert _keys(doc) == _keys(bare)
    assert out.strip() and not out.lstrip().startswith(("{", "["))  # the table, as without --json
    assert not list(tmp_path.glob("*.tmp*"))  # written atomically: no temporary left


@pytest.mark.parametrize("argv", [a for a, _ in COMMANDS] + [["verify", "CERT"], ["prove"]],
                         ids=[a[0] for a, _ in COMMANDS] + ["verify", "prove"])
def test_every_json_option_takes_an_optional_path(argv):
    """One spelling everywhere: ``--json [PATH]`` (nargs '?', stdout by default)."""
    parser = build_parser([argv[0]])
    sub = next(a for a in parser._actions if a.dest == "command").choices[argv[0]]
    action = next(a for a in sub._actions if "--json" in a.option_strings)
    assert action.nargs == "?" and action.const == "-" and action.default is None and action.metavar == "PATH"


def test_an_unwritable_json_path_is_refused_before_the_work(capsys, tmp_path):
    code, out, err = run(capsys, "orbit", "--steps", "2", "--json", str(tmp_path / "missing" / "o.json"))
    assert code == 5 and "--json" in err and not out


def test_verify_old_spelling_still_works_with_a_note(capsys, tmp_path):
    cert = tmp_path / "cert.json"
    assert run(capsys, "certify", "--steps", "1", "--json", str(cert))[0] == 0
    code, out, err = run(capsys, "verify", "--json", str(cert))  # the spelling of the flag --json
    assert code == 0 and json.loads(out)["ok"] is True
    assert err.count("\n") == 1 and "deprecated" in err and f"verify {cert} --json" in err
    report = tmp_path / "report.json"
    code, out, err = run(capsys, "verify", str(cert), "--json", str(report))
    assert code == 0 and json.loads(report.read_text())["ok"] is True and "VERIFIED" in out and not err
    code, _, err = run(capsys, "verify", "--json")
    assert code == 2 and "CERT.json" in err
