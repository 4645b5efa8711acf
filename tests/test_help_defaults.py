"""The defaults the help texts state agree with the parser's real defaults and with the docs.

Each statement is read from the text (``--help`` or README.md / docs/*.md) and compared with the
value the code uses (the parser's default, or the library constant a ``None`` default resolves to),
so a default changed in one place and not in the other fails here.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import re
from fractions import Fraction

import pytest

from exact_khk.cli import main as cli_main

ROOT = pathlib.Path(__file__).resolve().parent.parent


def _subparsers():
    parser = cli_main.build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices


SUBPARSERS = _subparsers()


def _help(action):
    text = " ".join((action.help or "").split())
    return text % {"default": action.default} if "%(default)" in text else text


def _resolved_defaults(command):
    """What an option whose parser default is None resolves to in the command (from the library's
    constants, not from the help texts)."""
    from exact_khk.arith import get_arith
    from exact_khk.systems.base import System
    from exact_khk.systems.lie_poisson.system import DEFAULT_EPS

    out = {"--eps": str(DEFAULT_EPS), "--arith": get_arith(None).name, "--steps": str(System.default_steps)}
    if command == "find-integrals":
        out["--degree"] = "2"  # exact_khk/cli/diagnostics.py: kw["degree"] = 2 if args.degree is None
    return out


#: a stated default that is a value (a number, a rational, an arithmetic, a list of them)
STATED = re.compile(r"[(;] ?default:? ([-\w/.:,+]+)")


def _is_value(text) -> bool:
    """Whether a stated default is a value (a number, a rational, an arithmetic name) rather than words."""
    from exact_khk.arith import arith_names

    return bool(re.fullmatch(r"-?\d+(/\d+)?", text)) or text in arith_names()


def stated_defaults():
    """[(command, option, stated value, parser default)] of every option whose help states a value."""
    out = []
    for name, sub in SUBPARSERS.items():
        for action in sub._actions:
            m = STATED.search(_help(action))
            if m and action.option_strings:
                out.append((name, action.option_strings[-1], m.group(1).rstrip(",.;:"), action.default))
    return out


def test_stated_defaults_were_found():
    found = {(c, o) for c, o, _, _ in stated_defaults()}
    assert {("certify", "--eps"), ("certify", "--arith"), ("orbit", "--steps"), ("hard", "--long-steps"),
            ("scale", "--ariths"), ("liouville", "--trials")} <= found, found


@pytest.mark.parametrize("command, option, stated, default", stated_defaults(),
                         ids=[f"{c} {o}" for c, o, _, _ in stated_defaults()])
def test_stated_default_is_the_parsers(command, option, stated, default):
    """A value the help states as the default is the parser's default, or what None resolves to."""
    if default is None:
        resolved = _resolved_defaults(command)
        if not _is_value(stated):  # "(default: the system's)", "(default: every core; ...)": words
            return
        assert option in resolved, f"{command} {option}: the help states default {stated}, the parser has None"
        default = resolved[option]
    assert str(default) == stated, f"{command} {option}: the help says default {stated}, the parser's is {default}"


def test_every_eps_help_says_one_step_is_time_two_eps():
    """The first thing a Kahan or CMOQ user gets wrong: one step approximates the time-2ε flow."""
    seen = 0
    for name, sub in SUBPARSERS.items():
        for action in sub._actions:
            if "--eps" in action.option_strings:
                seen += 1
                assert re.search(r"time 2\*?\s?eps", _help(action)) and "h = 2 eps" in _help(action), \
                    f"{name} --eps: {_help(action)}"
    assert seen >= 10


def test_the_system_default_is_stated_once_per_command():
    """The system group names the built-in n = 3 system unless the description names another; a
    command whose default system differs (prove) names it in its description."""
    from exact_khk.cli.liouville import PROVE_DEFAULT_VECTORS

    for name, sub in SUBPARSERS.items():
        for group in sub._action_groups:
            if group.title and group.title.startswith("system"):
                assert "unless the description above names another" in group.title, (name, group.title)
    desc = " ".join(SUBPARSERS["prove"].description.split())
    assert "n = 2 system a = %s, b = %s, c = %s" % PROVE_DEFAULT_VECTORS in desc
    evidence = (ROOT / "docs" / "evidence.md").read_text(encoding="utf-8")
    m = re.search(r'LiePoissonSystem\.from_vectors\("([^"]+)", "([^"]+)", "([^"]+)"\)\n'
                  r'(?:.*\n)*?.*by default for this n = 2 system', evidence)
    assert m and m.groups() == PROVE_DEFAULT_VECTORS, "docs/evidence.md names another default system for prove"


def _vector(text):
    return [Fraction(t.strip().replace("−", "-")) for t in text.split(",")]


def test_the_builtin_system_in_the_docs_is_the_codes():
    """README's and certify --help's statement of the built-in system: n, a, b, c, x0, ε, steps."""
    from exact_khk.systems.base import System
    from exact_khk.systems.lie_poisson.system import DEFAULT_EPS, DEFAULT_VECTORS, DEFAULT_X0

    readme = " ".join((ROOT / "README.md").read_text(encoding="utf-8").split())
    m = re.search(r"built-in system \(n = (\d+), a = \(([^)]*)\), b = \(([^)]*)\), c = \(([^)]*)\), "
                  r"x0 = \(([^)]*)\), ε = ([\d/]+), (\d+) steps\)", readme)
    assert m, "README no longer states the built-in system"
    n, a, b, c, x0, eps, steps = m.groups()
    assert [_vector(a), _vector(b), _vector(c)] == [_vector(v) for v in DEFAULT_VECTORS]
    assert int(n) == len(_vector(DEFAULT_VECTORS[0]))
    assert _vector(x0) == [Fraction(t) for t in DEFAULT_X0]
    assert Fraction(eps) == Fraction(str(DEFAULT_EPS))
    assert int(steps) == System.default_steps
    certify_desc = " ".join(SUBPARSERS["certify"].description.split())
    m = re.search(r"built-in n = (\d+) system, x0 and eps = ([\d/]+), (\d+) steps", certify_desc)
    assert m and (int(m.group(1)), Fraction(m.group(2)), int(m.group(3))) == \
        (int(n), Fraction(str(DEFAULT_EPS)), System.default_steps)
    certify_md = (ROOT / "docs" / "certify.md").read_text(encoding="utf-8")
    m = re.search(r"exact-khk certify\s+# built-in n = (\d+) system, x0, eps = ([\d/]+), (\d+) steps", certify_md)
    assert m and (int(m.group(1)), Fraction(m.group(2)), int(m.group(3))) == \
        (int(n), Fraction(str(DEFAULT_EPS)), System.default_steps)


#: defaults the docs state, by (file, pattern capturing the value, command, option)
DOC_DEFAULTS = [
    ("docs/precision.md", r"exact-khk scale\s+# built-in n = 3 system, (\d+) steps", "scale", "--steps"),
    ("docs/evidence.md", r"default prime (\d+)", "certify", "--identities"),
]


@pytest.mark.parametrize("path, pattern, command, option", DOC_DEFAULTS,
                         ids=[f"{p} {o}" for p, _, _, o in DOC_DEFAULTS])
def test_docs_state_the_parsers_defaults(path, pattern, command, option):
    m = re.search(pattern, (ROOT / path).read_text(encoding="utf-8"))
    assert m, f"{path}: the statement of the {command} {option} default is gone: {pattern}"
    action = next(a for a in SUBPARSERS[command]._actions if option in a.option_strings)
    value = action.const if action.nargs == "?" else action.default
    assert str(value).removeprefix("gf:") == m.group(1), f"{path} says {m.group(1)}, {command} {option} has {value}"


def test_certify_help_and_readme_list_every_exit_status():
    """certify --help names every exit status the command line can end with, and so does the
    README's table (cli.main.EXIT is the one list)."""
    desc = " ".join(SUBPARSERS["certify"].description.split())
    statuses = sorted(set(cli_main.EXIT.values()))
    listed = [int(s) for s in re.findall(r"(?:^|,) (\d+) ", desc.partition("Exit status")[2])]
    assert listed == statuses, (listed, desc)
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert sorted(int(s) for s in re.findall(r"^\| (\d+) \|", readme, re.M)) == statuses


def test_sweep_help_and_docs_name_every_task():
    from exact_khk.sweep.tasks import TASKS

    desc = " ".join(SUBPARSERS["sweep"].description.split())
    m = re.search(r"the task: ([\w, -]+)\)", desc)
    assert m and sorted(t.strip() for t in m.group(1).split(",")) == sorted(TASKS), desc
    sweeps = (ROOT / "docs" / "sweeps.md").read_text(encoding="utf-8")
    row = next(line for line in sweeps.splitlines() if line.startswith("| `task` |"))
    assert sorted(re.findall(r"`([\w-]+)`", row.split("|")[3])) == sorted(TASKS), row


def test_liouville_default_arithmetic_is_the_one_its_help_states(capsys):
    """liouville --help: cyclo:n for n >= 3, flint for n = 2 (what the run records)."""
    desc = " ".join(SUBPARSERS["liouville"].description.split())
    assert "default cyclo:n for n >= 3" in desc and "flint for n = 2" in desc
    assert cli_main.main(["liouville", "--steps", "1", "--involutions", "basis", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["arith"] == "cyclo:3"
    assert cli_main.main(["liouville", "--a", "1,2", "--b", "0,1", "--c", "3,1", "--x0", "1,2,-1,1/2",
                          "--steps", "1", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["arith"] == "flint"


def test_the_stated_default_check_can_fail():
    """Negative control: a help stating another default than the parser's is caught."""
    parser = argparse.ArgumentParser()
    action = parser.add_argument("--steps", type=int, default=20, help="number of steps (default 30)")
    m = STATED.search(_help(action))
    assert m and m.group(1) != str(action.default)
