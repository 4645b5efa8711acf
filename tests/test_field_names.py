"""One resolution of field names (System.named_field), as the command
line, the sweep tasks and the diagnostics take them."""

import json

import pytest

from exact_khk.arith import get_arith
from exact_khk.cli.main import main
from exact_khk.diagnostics.degrees import resolve_field
from exact_khk.errors import InputError, NotRationalError
from exact_khk.kahan.map import KahanMap
from exact_khk.sweep.tasks import run_task
from exact_khk.systems.expressions import ExpressionSystem
from exact_khk.systems.lie_poisson.system import LiePoissonSystem, b0_signs

LP = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")  # n = 3: '-++', '+--' rational, '+-+' not
EULER = ExpressionSystem.from_expressions(["x", "y", "z"], field=["y*z", "-2*x*z", "x*y"],
                                          fields={"g": ["y*z", "-x*z", "0"]}, name="euler-g")


def same(a, b):
    return a.label == b.label and a.terms() == b.terms()


@pytest.mark.parametrize("name, kind, signs", [
    ("f", "f", None), ("control", "control", None),
    ("g", "g", b0_signs(3)), ("b0", "g", b0_signs(3)),  # B_0 = '-++'
    ("+--", "g", "+--"), ("g[+--]", "g", "+--"), ("-++", "g", "-++"), ("g[-++]", "g", "-++"),
])
def test_lie_poisson_names(name, kind, signs):
    assert same(LP.named_field(name), LP.field(kind, signs=signs))
    assert same(resolve_field(LP, name)[1], LP.field(kind, signs=signs))


def test_non_rational_pattern_needs_omega_and_omega_is_asked_only_for_patterns():
    for name in ("+-+", "g[+-+]"):
        with pytest.raises(NotRationalError):
            LP.named_field(name)
        assert same(LP.named_field(name, cyclotomic=True), LP.field("g", "+-+", cyclotomic=True))
        assert LP.named_field(name, cyclotomic=lambda: True).label == "g[+-+]"
    asked = []
    for name in ("f", "g", "b0", "control"):
        LP.named_field(name, cyclotomic=lambda: asked.append(name))
    assert asked == []
    LP.named_field("-++", cyclotomic=lambda: asked.append("-++"))
    assert asked == ["-++"]


def test_file_field_names():
    assert same(EULER.named_field("f"), EULER.field("f"))
    assert same(EULER.named_field("g"), EULER.field("g"))
    assert EULER.named_field("g").quad != EULER.named_field("f").quad
    for name in ("b0", "-++", "g[-++]", "h"):  # the family's forms are not names of a file's fields
        with pytest.raises(InputError, match=rf"unknown field {name!r}".replace("[", r"\[").replace("+", r"\+")):
            EULER.named_field(name)


@pytest.mark.parametrize("name, message", [
    ("g[", r"^field: expected f, g, b0, g\[SIGNS\], a sign pattern SIGNS or control .*, got 'g\['$"),
    ("g[-++", r"got 'g\[-\+\+'$"),
    ("h", r"^field: expected f, g, b0, .* for the Lie–Poisson family, got 'h'$"),
    ("", r"got ''$"),
    ("f[-++]", r"got 'f\[-\+\+\]'$"),
    ("g[]", r"^signs: '' must be 3 characters"),
    ("g[-+]", r"^signs: '-\+' must be 3 characters"),
    ("-+++", r"^signs: '-\+\+\+' must be 3 characters"),
    ("g[abc]", r"^signs: 'abc' must be 3 characters, each '\+' or '-'"),
    (3, r"^field: expected a field name, got 3$"),
])
def test_bad_names_are_one_typed_line(name, message):
    with pytest.raises(InputError, match=message) as info:
        LP.named_field(name, cyclotomic=lambda: pytest.fail("omega asked for a bad name"))
    assert "\n" not in str(info.value)


def test_the_callers_agree(capsys):
    """The orbit command, the sweep's orbit task and the degrees task take every form."""
    x0 = ["1", "2", "-1", "1/2", "0", "1"]
    want = KahanMap(LP.field("g", "+--"), "1/10", "fraction").orbit(x0, 3)
    ar = get_arith("fraction")
    for argv in (["--field", "g", "--signs", "+--"], ["--field", "g[+--]"], ["--field", "+--"]):
        assert main(["orbit", "--a", "1,0,2", "--b", "0,1,0", "--c", "3,1,1", "--x0", ",".join(x0), "--eps",
                     "1/10", "--steps", "3", "--arith", "fraction", "--json", *argv]) == 0
        assert json.loads(capsys.readouterr().out)["orbit"] == [[ar.format(t) for t in p] for p in want]
    seen = {"orbit": set(), "degrees": set()}
    for name in ("g", "b0", "-++", "g[-++]"):
        for task, figure in (("orbit", "heights"), ("degrees", "degrees")):
            rec = run_task({"key": "k", "params": {
                "task": task, "system": {"family": "lie-poisson", "n": 3, "seed": 1}, "point": {"seed": 1},
                "eps": "1/10", "arith": "flint", "steps": 4, "options": {"field": name}}})
            assert rec["error"] is None and rec["verdict"] in ("OK", "UNDETERMINED"), rec
            seen[task].add(tuple(rec["figures"][figure]))
    assert [len(v) for v in seen.values()] == [1, 1]
    for argv, message in ((["--field", "f", "--signs", "-++"], "--signs applies only to --field g"),
                          (["--system", "euler-top", "--field", "g", "--signs", "-++"], "--signs applies only"),
                          (["--field", "g["], "got 'g['")):
        for cmd in ("orbit", "degrees"):
            assert main([cmd, "--steps", "4", *argv]) == 2
            err = capsys.readouterr().err
            assert message in err and len(err.strip().splitlines()) == 1
