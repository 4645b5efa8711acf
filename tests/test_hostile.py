"""No traceback, ever, from the command line; absurd requests refused at once.

A table of hostile invocations of every subcommand.  Each row asserts: no
"Traceback" anywhere, the documented exit status (0 ok, 1 invalid, 2 bad input
or a request beyond a documented limit, 3 singular step / pole / no trustworthy
bit, 4 inconclusive, 5 output, 70 internal error, 130 interrupted), at most one
line on stderr when the command fails, and no partial output file.  Most rows
call :func:`exact_khk.cli.main.main` in-process; subprocesses are used for an
ASCII-only stdout, for SIGINT at a random moment of a long run and for a few
end-to-end rows.

Rows of ``scale``/``hard``/``enclose`` are ordinary rows: their limits
(MAX_STUDY_DIM, MAX_DIGITS, MAX_LONG_STEPS, MAX_ENCLOSURE_STEPS in cli/study.py and
exact_khk/studies/enclosure.py) are checked before the work.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time

import pytest

from exact_khk.cli.main import main

BIG = "7" * 5000                                     # a 5000-digit number
HUGE_X0 = ",".join(["1" + "3" * 10000, "2", "-1", "1/2", "0", "1"])  # a 10^4-digit entry
SING = ["--a", "1,2", "--b", "0,1", "--c", "-1,3", "--x0", "1,0,2,1", "--eps", "1/5"]  # det(I - eps f'(x0)) = 0
FAR = "1e160,2e160,-1e160,1e160,0,1e160"
FARTHER = "1e200,2e200,-1e200,1e200,0,1e200"

#: malformed (and two well-formed) system files, written to the test's folder
TOMLS = {
    "empty": "",
    "syntax": 'name = "x"\nvariables = [\n',
    "badformat": 'format = 999\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "y*x"\ny = "-x*y"\n',
    "missing_field": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "y"\n',
    "bigexp": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "y**99999999"\ny = "x"\n',
    "cubic": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "y*y*y"\ny = "x"\n',
    "unknown": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "z"\ny = "x"\n',
    "divzero": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "y/0"\ny = "x"\n',
    "dupvar": 'format = 1\nname = "x"\nvariables = ["x","x"]\n[field]\nx = "x"\n',
    "inject": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "__import__(\'os\')"\ny = "x"\n',
    "badint": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "y*x"\ny = "-x*y"\n'
              '[integrals]\nI = "1/(x-x)"\n',
    "deep": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "' + "(" * 500 + "y" + ")" * 500
            + '"\ny = "x"\n',
    "badx0": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "y*x"\ny = "-x*y"\n[defaults]\nx0 = ["1"]\n',
    "badpoisson": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "y*x"\ny = "-x*y"\n'
                  '[poisson]\nmatrix = [["0"]]\n',
    "ok": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "y*x"\ny = "-x*y"\n',
    "onevar": 'format = 1\nname = "x"\nvariables = ["x"]\n[field]\nx = "x*x"\n',
    "zerodensity": 'format = 1\nname = "x"\nvariables = ["x","y"]\n[field]\nx = "y*x"\ny = "-x*y"\n'
                   '[measure]\ndensity = "x - x"\n',
}
GARBAGE = bytes(random.Random(0).randrange(256) for _ in range(3000))

def row(argv, code, *marks, id=None, nonan=False):
    marks = list(marks)
    return pytest.param(list(argv), code, nonan, marks=marks, id=id or " ".join(a[:24] for a in argv)[:80])


BAD_EPS = ["1/0", "abc", "nan", "inf", "", " ", "1e99999", "0", "-0", "0/7", "1//2", "0x10", "1/-3", "--1",
           "1" + "0" * 1_000_001]
COMMANDS_WITH_SYSTEM = ["orbit", "certify", "integrals", "liouville", "scale", "prove"]

ROWS = []
# bad rationals: every command that reads --eps / --x0
for cmd in COMMANDS_WITH_SYSTEM:
    for eps in BAD_EPS[:10] if cmd != "orbit" else BAD_EPS:
        ROWS.append(row([cmd, "--eps", eps], 2, id=f"{cmd} --eps {eps[:12]!r}"))
    for x0 in ["1,2,3", "1,,2,3,4,5", "a,b,c,d,e,f", "1/0,1,1,1,1,1", "nan,1,1,1,1,1", "1e10001,1,1,1,1,1",
               "1,2,3,4,5,6,7", ";;;"]:
        ROWS.append(row([cmd, "--x0", x0], 2, id=f"{cmd} --x0 {x0[:14]!r}"))
# wrong lengths, inconsistent options
ROWS += [
    row(["orbit", "--a", "1,2", "--b", "1,2,3", "--c", "1,1", "--x0", "1,1,1,1"], 2),
    row(["orbit", "--a", "1", "--b", "1", "--c", "1", "--x0", "1,1"], 2),
    row(["orbit", "--a", "1,2", "--b", "1,2", "--c", "1,2"], 2, id="orbit --a/--b/--c without --x0"),
    row(["orbit", "--a", "1,2", "--b", "1,2"], 2, id="orbit --a --b without --c"),
    row(["orbit", "--a", "1,2", "--b", "1,2", "--c", "1,2", "--x0", "1,1,1,1", "--seed", "1"], 2),
    row(["orbit", "--seed", "3"], 2, id="orbit --seed without --n"),
    row(["orbit", "--n", "4"], 2, id="orbit --n 4 without a system"),
    row(["orbit", "--a", ",".join(["1"] * 200_001), "--b", "1", "--c", "1", "--x0", "1"], 2, id="orbit --a of 200001"),
    row(["certify", "--signs", "++"], 2), row(["certify", "--signs", "+++"], 2), row(["certify", "--signs", "+-+"], 2),
    row(["certify", "--signs", "abc"], 2), row(["orbit", "--field", "g", "--signs", "+-+"], 2),
    row(["orbit", "--field", "h"], 2), row(["orbit", "--signs", "-++"], 2, id="orbit --signs without --field g"),
    row(["orbit", "--method", "split", "--arith", "float"], 2), row(["orbit", "--method", "fast"], 2),
    row(["orbit", "--method", "structured", "--arith", "gf:11"], 2, id="structured in gf:11 (3 does not divide 10)"),
    row(["orbit", "--n", "20", "--arith", "cyclo:10000", "--seed", "1", "--steps", "1"], 0,
        id="cyclo:10000 at n = 20: no (80000)^2 DFT transform"),
    row(["orbit", "--method", "structured", "--arith", "ball:64"], 2),
    row(["liouville", "--involutions", "+++"], 2), row(["liouville", "--involutions", "+-"], 2),
    row(["liouville", "--involutions", "x,y"], 2), row(["liouville", "--arith", "float"], 2),
    row(["liouville", "--arith", "flint"], 2, id="liouville flint cannot hold omega"),
    row(["prove", "--n", "4", "--seed", "1"], 2, id="prove n = 4"), row(["certify", "--claims", "integrals"], 2),
    row(["certify", "--prove", "--n", "4", "--seed", "1"], 2, id="certify --prove at n = 4"),
    row(["integrals", "--signs", "+-"], 2),
]
# absurd sizes: refused at once, naming the limit
ROWS += [
    row(["orbit", "--steps", str(10 ** 9)], 2), row(["orbit", "--steps", str(10 ** 30)], 2),
    row(["certify", "--steps", str(10 ** 9)], 2), row(["integrals", "--steps", str(10 ** 9)], 2),
    row(["liouville", "--steps", str(10 ** 9)], 2), row(["scale", "--steps", str(10 ** 9)], 2),
    row(["orbit", "--steps", "100000"], 2, id="orbit --steps 1e5 exact (memory estimate)"),
    row(["certify", "--steps", "100000"], 2, id="certify --steps 1e5 (memory estimate)"),
    row(["orbit", "--steps", "-1"], 2), row(["certify", "--steps", "0"], 2), row(["orbit", "--steps", "many"], 2),
    row(["orbit", "--n", "20000", "--seed", "1", "--method", "dense"], 2),
    row(["orbit", "--n", "20000", "--seed", "1", "--arith", "float"], 2),
    row(["orbit", "--n", "20000", "--seed", "1", "--arith", "mp:64"], 2),
    row(["orbit", "--n", "20000", "--seed", "1", "--arith", "ball:64"], 2),
    row(["orbit", "--n", "20000", "--seed", "1", "--arith", "gmpy2"], 2),
    row(["orbit", "--n", "20000", "--seed", "1", "--method", "split"], 2),
    row(["certify", "--n", "20000", "--seed", "1"], 2), row(["integrals", "--n", "20000", "--seed", "1"], 2),
    row(["integrals", "--n", "20000", "--seed", "1", "--arith", "float"], 2),
    row(["liouville", "--n", "20000", "--seed", "1", "--involutions", "basis"], 2),
    row(["liouville", "--n", "40", "--seed", "1"], 2, id="liouville 2^40 involutions"),
    row(["certify", "--n", "60", "--seed", "1"], 2, id="certify 4094 involutions x 20 steps"),
    row(["prove", "--n", "20000", "--seed", "1"], 2),
    row(["orbit", "--n", str(10 ** 30), "--seed", "1"], 2), row(["orbit", "--n", "0", "--seed", "1"], 2),
    row(["orbit", "--n", "-5", "--seed", "1"], 2),
    row(["certify", "--poisson-points", "0"], 2),
    row(["liouville", "--arith", "gf:1000003", "--trials", str(10 ** 9)], 2),
    row(["liouville", "--arith", "gf:1000003", "--trials", "0"], 2),
    row(["scale", "--digits", "0"], 2), row(["hard", "--digits", "0"], 2), row(["hard", "--long-steps", "0"], 2),
    row(["hard", "--only", "no-such-case"], 2),
    row(["scale", "--n", "20000", "--seed", "1", "--steps", "1"], 2),
    row(["scale", "--digits", "100000", "--steps", "2", "--ariths", "float"], 2),
    row(["hard", "--long-steps", str(10 ** 9), "--only", "long"], 2),
    row(["hard", "--digits", "100000", "--only", "near-root"], 2),
    row(["scale", "--ariths", "lohner:0"], 2), row(["scale", "--ariths", "lohner:abc"], 2),
    row(["scale", "--ariths", "lohner:99999999"], 2), row(["hard", "--ariths", "lohner:64"], 2),
]
# enclose: real input and its limits
for x0 in ["[1,2", "[2,1],1,1,1,1,1", "1+-(-1),1,1,1,1,1", "1+-,1,1,1,1,1", "sqrt(,1,1,1,1,1", "log(0),1,1,1,1,1",
           "__import__('os'),1,1,1,1,1", "[1;2],1,1,1,1,1", "1/0,1,1,1,1,1", "2^9999999,1,1,1,1,1", "x" * 20000]:
    ROWS.append(row(["enclose", "--x0", x0], 2, id=f"enclose --x0 {x0[:16]!r}"))
ROWS += [row(["enclose", "--eps", e], 2) for e in ("[-1,1]", "0", "0+-1/10", "[1/10,1/20]", "abc")]
ROWS += [row(["enclose", "--prec", p], 2) for p in ("0", "1", "-5", "99999999", "abc")]
ROWS += [row(["enclose", "--steps", s], 2) for s in ("0", "-1", str(10 ** 9), str(10 ** 7))]
ROWS += [row(["enclose", "--methods", m], 2) for m in ("taylor", "", "naive,naive")]
ROWS += [row(["enclose", "--arith", "float"], 2), row(["enclose", "--n", "20000", "--seed", "1"], 2),
         row(["enclose", "--x0", "sqrt(2),1,1,1,1,1", "--check-exact"], 2),
         row(["enclose", "--system", "euler-top", "--x0", "1,2"], 2)]
# arithmetics beyond their bounds
for cmd in ("orbit", "certify", "integrals"):
    for name in ("mp:999999999999999999999999999999", "cyclo:1000000007", "gf:4", "ball:0", "gf:2", "gf:3",
                 "mp:1", "mp:-5", "mp:abc", "mp", "gf:", "quad", "cyclo:0", "ball:99999999", "gf:" + "9" * 40,
                 "gf:18446744073709551629", "mp:1000001"):
        ROWS.append(row([cmd, "--arith", name], 2, id=f"{cmd} --arith {name[:20]}"))
ROWS += [row(["scale", "--ariths", "mp:99999999999"], 2), row(["scale", "--ariths", "flint"], 2),
         row(["scale", "--ariths", ","], 2), row(["hard", "--ariths", "cyclo:1000000007"], 2),
         row(["scale", "--arith", "float"], 2)]
# bad paths: checked before the work, never a partial file
ROWS += [
    row(["certify", "--json", "{tmp}/missing/x.json"], 5), row(["certify", "--json", "{tmp}"], 5),
    row(["certify", "--steps", "1", "--json", "/dev/full"], 5, id="certify --json /dev/full"),
    row(["liouville", "--json", "{tmp}/missing/x.json"], 5), row(["prove", "--json", "{tmp}/missing/x.json"], 5),
    row(["liouville", "--json", "{tmp}"], 5),
    row(["orbit", "--system", "{tmp}/missing.toml"], 2), row(["orbit", "--system", "{tmp}"], 2),
    row(["orbit", "--system", "/dev/zero"], 2), row(["orbit", "--system", "/dev/null"], 2),
    row(["orbit", "--system", "no-such-system"], 2),
    row(["orbit", "--system", "euler-top", "--n", "3"], 2),
]
# from a hostile sweep of the command line (each was a hang, a memory blow-up, an internal
# error, a late failure or a silent misreading before it was mended)
ROWS += [
    row(["verify", "/dev/zero"], 2), row(["sweep", "/dev/zero", "--out", "{tmp}/o", "--dry-run"], 2),
    row(["hard", "--system", "/dev/zero"], 2),
    row(["liouville", "--system", "euler-top", "--steps", "1"], 2), row(["prove", "--system", "euler-top"], 2),
    row(["certify", "--system", "euler-top", "--claims", "", "--steps", "2"], 2, id="certify --claims ''"),
    row(["certify", "--steps", "2", "--json", "/proc/x.json"], 5, id="certify --json /proc/x.json"),
    row(["degrees", "--steps", "3", "--plot", "{tmp}/out.txt"], 2, id="degrees --plot out.txt"),
    row(["degrees", "--steps", "3", "--arith", "float"], 2), row(["find-integrals", "--arith", "float"], 2),
    row(["prove", "--arith", "gf:7"], 2), row(["prove", "--n", "2", "--seed", "1", "--steps", "5"], 2),
    row(["degrees", "--steps", "6", "--max-bits", "-1"], 2), row(["degrees", "--steps", "6", "--max-bits", "5"], 2),
    row(["find-integrals", "--system", "euler-top", "--monomials", "x1^99999999"], 2),
    row(["find-integrals", "--system", "euler-top", "--monomials", "x1^45,x2"], 2, id="find-integrals degree 45"),
    row(["find-integrals", "--system", "euler-top", "--monomials", "x1^" + BIG], 2),
    row(["orbit", "--eps", "1 0", "--steps", "1"], 2, id="orbit --eps '1 0'"),
    row(["orbit", "--eps", "\u0661/\u0661\u0660".encode().decode("unicode_escape"), "--steps", "1"], 2,
        id="orbit --eps in Arabic-Indic digits"),
    row(["orbit", "--eps", "1 / 10", "--steps", "1"], 0, id="orbit --eps '1 / 10'"),
    row(["certify", "--steps", "1", "--arith", "cyclo:3", "--signs", "--+"], 0, id="certify --signs --+"),
]
# from a hostile review of the discovery and atlas commands (each was an internal error, a hang,
# a misleading message, a silently ignored option or a late failure before it was mended)
ROWS += [
    row(["degrees", "--map", "\u03b1*\u03b2,\u03b2*\u03b3,\u03b3*\u03b1", "--variables", "\u03b1,\u03b2,\u03b3"], 2,
        id="degrees --map with non-ASCII variable names"),
    row(["degrees", "--map", "(X+Y)**64, Y**64, Z**64", "--variables", "X,Y,Z", "--steps", "8"], 0,
        id="degrees --map of degree 64 stops before degree 262144"),
    row(["degrees", "--map", "X*Y,Y*Z,Z*X", "--variables", "X,Y,Z", "--confirm", "0"], 2),
    row(["find-poisson", "TOML:onevar"], 2, id="find-poisson in dimension 1"),
    row(["find-integrals", "--system", "euler-top", "--line-seed", BIG], 2, id="find-integrals 5000-digit --line-seed"),
    row(["classify", "--system", "euler-top", "--line-seed", BIG], 2, id="classify 5000-digit --line-seed"),
    row(["classify", "euler-top", "--x0", "1,2,3"], 2, id="classify --x0 (read and ignored before)"),
    row(["find-integrals", "euler-top", "--degree", "2"], 0, id="find-integrals SYSTEM (as find-measure takes it)"),
    row(["find-integrals", "euler-top", "--system", "clebsch"], 2, id="find-integrals SYSTEM and another --system"),
    row(["find-measure", "euler-top", "--x0", "1" + "3" * 10000 + ",2,3", "--steps", "6"], 2,
        id="find-measure 10^4-digit --x0, 6 steps: past MAX_ORBIT_BITS"),
    row(["find-poisson", "euler-top", "--degree", "1", "--eps", "1/1" + "0" * 5000], 0,
        id="find-poisson at an eps of 5000 digits"),
    row(["find-measure", "--system", "euler-top", "--line-seed", BIG], 2, id="find-measure 5000-digit --line-seed"),
    row(["find-integrals", "--system", "euler-top", "--toml", ""], 2, id="find-integrals --toml ''"),
    row(["find-integrals", "--system", "euler-top", "--toml", "-"], 2, id="find-integrals --toml - (no file named '-')"),
    row(["find-integrals", "--system", "euler-top", "--monomials", "x1^4*x2^4"], 2,
        id="find-integrals: the default --fit-degree beyond its limit is named as a default"),
    row(["atlas", "--quick", "--systems", "{tmp}", "--markdown", "{tmp}/a.md", "--figure", ""], 2,
        id="atlas --figure ''"),
    row(["atlas", "--quick", "--systems", "{tmp}", "--markdown", "-"], 2, id="atlas --markdown - (no file named '-')"),
    row(["atlas", "--quick", "--systems", "{tmp}", "--markdown", "{tmp}/a.md", "--figure", "{tmp}/f.txt"], 2,
        id="atlas --figure of no image format"),
    row(["atlas", "--quick", "--systems", "{tmp}", "--markdown", "{tmp}/a.md", "--figure", "/proc/x.png"], 5,
        id="atlas --figure /proc/x.png"),
]
# malformed system files
for name in TOMLS:
    if name not in ("ok", "onevar"):
        ROWS.append(row(["certify", "--system", f"TOML:{name}", "--steps", "2"], 2, id=f"--system {name}.toml"))
ROWS += [row(["orbit", "--system", "TOML:garbage"], 2, id="--system garbage bytes"),
         row(["certify", "--system", "TOML:ok", "--steps", "2"], 0),
         row(["orbit", "--system", "TOML:ok", "--x0", "1,2,3"], 2),
         row(["orbit", "--system", "TOML:ok", "--signs", "+-"], 2),
         row(["integrals", "--system", "TOML:ok", "--x0", "1,2"], 0)]
# huge but valid numbers; floating results never pass nan/inf on as data
ROWS += [
    row(["orbit", "--eps", "1/" + BIG, "--steps", "2"], 0, id="orbit 5000-digit eps"),
    row(["orbit", "--eps", "1/" + BIG, "--steps", "2", "--arith", "mp:53"], 0, id="orbit 5000-digit eps mp:53"),
    row(["orbit", "--eps", "1/" + BIG, "--steps", "2", "--arith", "float"], 2, id="orbit 5000-digit eps float"),
    row(["orbit", "--eps", "1" + "0" * 5000, "--arith", "float"], 2, id="orbit eps 1e5000 float"),
    row(["orbit", "--eps", "1" + "0" * 5000, "--arith", "mp:53"], 3, id="orbit eps 1e5000 mp:53"),
    row(["orbit", "--x0", HUGE_X0, "--steps", "2"], 0, id="orbit 10^4-digit x0"),
    row(["orbit", "--x0", HUGE_X0, "--steps", "2", "--json"], 0, id="orbit 10^4-digit x0 json"),
    row(["orbit", "--x0", HUGE_X0, "--steps", "2", "--arith", "float"], 2, id="orbit 10^4-digit x0 float"),
    row(["orbit", "--x0", HUGE_X0, "--steps", "2", "--arith", "ball:64"], 0, id="orbit 10^4-digit x0 ball"),
    row(["integrals", "--x0", HUGE_X0], 0, id="integrals 10^4-digit x0"),
    row(["integrals", "--x0", HUGE_X0, "--arith", "mp:64"], 0, id="integrals 10^4-digit x0 mp:64", nonan=True),
    row(["integrals", "--arith", "float", "--x0", FAR], 0, id="integrals float at 1e160", nonan=True),
    row(["integrals", "--arith", "mp:53", "--x0", FARTHER], 0, id="integrals mp:53 at 1e200", nonan=True),
    row(["integrals", "--arith", "float", "--x0", "1e300,2e300,-1e300,1e300,0,1e300"], 0, nonan=True),
    row(["integrals", "--arith", "float", "--x0", "1e-320,2e-320,-1e-320,1e-320,0,1e-320"], 0, nonan=True),
    row(["integrals", "--arith", "ball:64", "--x0", FARTHER], 0, nonan=True),
    row(["orbit", "--arith", "float", "--x0", FAR, "--steps", "3"], 0, nonan=True),
    row(["orbit", "--arith", "float", "--x0", "1e300,2e300,-1e300,1e300,0,1e300", "--steps", "3"], 0, nonan=True),
    row(["orbit", "--arith", "float", "--x0", FAR, "--steps", "3", "--json"], 0, nonan=True),
    row(["orbit", "--arith", "float", *SING], 3, id="orbit float exactly singular step"),
    row(["orbit", "--arith", "mp:80", *SING], 3, id="orbit mp:80 exactly singular step"),
    row(["orbit", *SING], 3, id="orbit exact singular step"),
    row(["orbit", "--arith", "float", "--method", "structured", *SING], 3, id="orbit float structured singular"),
    row(["orbit", "--arith", "ball:64", *SING], 4, id="orbit ball singular: undecided"),
    row(["integrals", "--arith", "float", *SING], 0, nonan=True),
    row(["certify", "--steps", "2", "--arith", "float"], 4), row(["certify", "--steps", "2", "--arith", "gf:7"], 3),
    row(["certify", "--steps", "2", "--arith", "gf:5"], 2, id="certify gf:5 bad reduction of eps"),
    row(["orbit", "--steps", "1", "--arith", "FLINT"], 0), row(["orbit", "--arith", "cyclo:10000", "--steps", "1"], 0),
    row(["integrals", "--arith", "gf:7"], 0), row(["orbit", "--seed", str(10 ** 30), "--n", "3", "--steps", "1"], 0),
    row(["orbit", "--x0", "-1,2,3,4,5,6", "--steps", "1"], 0, id="orbit negative x0 value"),
    row(["orbit", "--eps", "-1/7", "--steps", "1"], 0, id="orbit negative eps value"),
]
# help, version, unknown commands and options
ROWS += [row(["--version"], 0), row(["--help"], 0), row([], 2, id="no command")] + [
    row([cmd, "--help"], 0) for cmd in ("orbit", "certify", "integrals", "systems", "liouville", "prove", "scale",
                                        "hard", "enclose")] + [
    row(["bogus"], 2), row(["orbit", "--bogus"], 2), row(["orbit", "--steps"], 2),
    row(["orbit", "--eps", "--steps", "3"], 2), row(["systems", "extra"], 2), row(["systems"], 0),
    row(["systems", "--json"], 0), row(["certify", "--steps", "1", "--json"], 0, id="certify --json without PATH: stdout"),
]


def _argv(argv, tmp):
    out = []
    for a in argv:
        if a.startswith("TOML:"):
            name = a[5:]
            path = tmp / f"{name}.toml"
            if name == "garbage":
                path.write_bytes(GARBAGE)
            else:
                path.write_text(TOMLS[name])
            a = str(path)
        out.append(a.replace("{tmp}", str(tmp)))
    return out


def _check(code, out, err, expected, nonan, before, tmp):
    assert "Traceback" not in err and "Traceback" not in out
    assert code == expected, (code, err[:500])
    if code != 0:
        lines = err.strip().splitlines()
        assert len(lines) <= 1, err[:2000]
        assert all(line.startswith("exact-khk: ") for line in lines), err[:500]
    if nonan:  # no nan/inf printed as a value
        words = [t.strip("(),[]\"':=") for t in out.lower().split()]
        assert not [w for w in words if w.lstrip("+-") in ("nan", "inf", "infinity")], out[:500]
    after = set(os.listdir(tmp))
    assert not [f for f in after if f.startswith(".tmp-")], after      # no temporary left behind
    if code != 0:
        assert after <= before, after - before                         # no partial output


@pytest.mark.parametrize("argv, code, nonan", ROWS)
def test_hostile_row(argv, code, nonan, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = _argv(argv, tmp_path)
    before = set(os.listdir(tmp_path))
    got = main(argv)
    out, err = capsys.readouterr()
    _check(got, out, err, code, nonan, before, tmp_path)


def test_table_is_large():
    assert len(ROWS) >= 150
    commands = {p.values[0][0] if p.values[0] else "" for p in ROWS}
    assert {"orbit", "certify", "integrals", "systems", "liouville", "prove", "scale", "hard", "--help",
            "--version"} <= commands


def test_limits_are_named(capsys):
    """The refusals name the limit they hit."""
    for argv, words in [(["orbit", "--arith", "mp:9999999"], "1000000 bits"),
                        (["orbit", "--arith", "cyclo:1000000007"], "limit of 10000"),
                        (["orbit", "--arith", "gf:4"], "not a prime"),
                        (["orbit", "--steps", str(10 ** 9)], "MAX_STEPS"),
                        (["orbit", "--n", "20000", "--seed", "1", "--method", "dense"], "EXACT_KHK_MAX_MEMORY"),
                        (["certify", "--steps", "100000"], "memory limit"),
                        (["orbit", "--n", str(10 ** 6), "--seed", "1"], "MAX_N")]:
        assert main(argv) == 2
        assert words in capsys.readouterr().err


def test_structured_path_stays_allowed_at_large_n(capsys):
    """O(n) memory: the structured float step at n = 20000 is not refused."""
    assert main(["orbit", "--n", "20000", "--seed", "1", "--arith", "float", "--method", "structured",
                 "--steps", "1", "--json"]) == 0
    assert '"orbit"' in capsys.readouterr().out


def test_memory_limit_is_configurable(capsys, monkeypatch):
    monkeypatch.setenv("EXACT_KHK_MAX_MEMORY", "1M")
    assert main(["orbit", "--n", "40", "--seed", "1", "--arith", "float", "--steps", "1"]) == 2
    assert "1.05 MB" in capsys.readouterr().err
    monkeypatch.setenv("EXACT_KHK_MAX_MEMORY", "lots")
    assert main(["orbit", "--steps", "1"]) == 2
    assert "EXACT_KHK_MAX_MEMORY" in capsys.readouterr().err


def test_warnings_are_one_line(capsys):
    """A near-singular floating step warns in one line on stderr, not a raw Python warning."""
    from fractions import Fraction

    eps = Fraction(1, 5) + Fraction(1, 10 ** 12)  # near the singular step of SING
    code = main(["orbit", "--arith", "float", "--steps", "1", *SING[:-2], "--eps", str(eps)])
    err = capsys.readouterr().err
    assert code == 0 and len(err.strip().splitlines()) == 1
    assert err.startswith("exact-khk: warning: NearSingularWarning")


# --- subprocesses: encoding, SIGINT, end to end ------------------------------------

def _run(args, env=None, **kw):
    full_env = dict(os.environ, **(env or {}))
    return subprocess.run([sys.executable, "-m", "exact_khk", *args], capture_output=True, text=True,
                          env=full_env, timeout=120, **kw)


@pytest.mark.parametrize("args", [["orbit", "--steps", "2"], ["--help"], ["certify", "--steps", "1"],
                                  ["orbit", "--eps", "1/0"], ["systems"]])
def test_ascii_only_stdout(args, tmp_path):
    res = _run(args, env={"PYTHONIOENCODING": "ascii"}, cwd=tmp_path)
    assert "Traceback" not in res.stderr
    assert res.returncode in (0, 2)
    if args[0] == "orbit" and res.returncode == 0:
        assert "\\u2013" in res.stdout  # 'Lie–Poisson', escaped
    assert len(res.stderr.strip().splitlines()) <= 1


@pytest.mark.parametrize("args, code", [(["--version"], 0), (["certify", "--eps", "1/0"], 2),
                                        (["orbit", "--arith", "gf:4"], 2), (["certify", "--steps", "1"], 0)])
def test_end_to_end(args, code, tmp_path):
    res = _run(args, cwd=tmp_path)
    assert "Traceback" not in res.stderr and res.returncode == code
    if code:
        assert len(res.stderr.strip().splitlines()) == 1


def test_sigint_at_a_random_moment(tmp_path):
    """Ctrl-C during a long certificate: exactly one line on stderr, exit 130, no output file."""
    t0 = time.perf_counter()
    assert _run(["--version"]).returncode == 0  # warm the caches; the start-up time bounds the delay
    startup = time.perf_counter() - t0
    delay = 2 * startup + random.uniform(0.2, 2.0)
    proc = subprocess.Popen([sys.executable, "-m", "exact_khk", "certify", "--steps", "3000", "--json", "out.json"],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(delay)
    assert proc.poll() is None, "the run ended before the signal"
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, (proc.returncode, err)
    assert err.strip().splitlines() == ["exact-khk: interrupted: stopped by the user (Ctrl-C)"], err
    assert "Traceback" not in err and out == ""
    assert os.listdir(tmp_path) == []  # neither out.json nor a temporary


def test_sigint_while_the_command_line_is_imported():
    """Ctrl-C while the console script imports the command line (the slowest part of
    start-up): one line and exit 130, no traceback.  (An interrupt during Python's own
    start-up, while site-packages' .pth files run, is Python's to report.)"""
    code = ("import builtins\n"
            "real = builtins.__import__\n"
            "def interrupted(name, *args, **kw):\n"
            "    if name == 'exact_khk.cli.main':\n"
            "        raise KeyboardInterrupt\n"
            "    return real(name, *args, **kw)\n"
            "builtins.__import__ = interrupted\n"
            "from exact_khk.__main__ import run\n"
            "run()\n")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert res.returncode == 130 and res.stdout == ""
    assert res.stderr.strip().splitlines() == ["exact-khk: interrupted: stopped by the user (Ctrl-C)"], res.stderr


@pytest.mark.slow
@pytest.mark.parametrize("args", [["scale", "--n", "20000", "--seed", "1", "--steps", "1"],
                                  ["scale", "--digits", "100000", "--steps", "2", "--ariths", "float"],
                                  ["hard", "--long-steps", str(10 ** 9), "--only", "long"],
                                  ["hard", "--digits", "100000", "--only", "near-root"]])
def test_study_limits(args, tmp_path):
    """scale/hard requests that would run for hours must be refused at once (reported)."""
    res = subprocess.run([sys.executable, "-m", "exact_khk", *args, "--quiet"], capture_output=True, text=True,
                         cwd=tmp_path, timeout=30)
    assert res.returncode == 2 and "Traceback" not in res.stderr


# --- the API contract: numbers are read as the map reads them -----------------------

def _lp():
    from exact_khk.systems.lie_poisson import default_system

    return default_system()


@pytest.mark.parametrize("arith", ["flint", "gmpy2", "fraction"])
def test_public_functions_read_points_like_the_map(arith):
    from fractions import Fraction

    import flint
    import gmpy2

    from exact_khk import get_arith
    from exact_khk.arith import to_fraction
    from exact_khk.systems.lie_poisson.invariants import Htilde, Pi, Pi_from_q, grad_Htilde, q_coefficients

    s, ar = _lp(), get_arith(arith)
    f = s.field("f")
    points = [["1", "2", "-1", "1/2", "0", "1"], [1, 2, -1, Fraction(1, 2), 0, 1],
              [flint.fmpq(1), flint.fmpq(2), flint.fmpq(-1), flint.fmpq(1, 2), flint.fmpq(0), flint.fmpq(1)],
              [gmpy2.mpq(1), 2, "-1", "0.5", gmpy2.mpq(0), "1"], [ar(t) for t in ("1", "2", "-1", "1/2", "0", "1")]]
    epss = ["1/10", Fraction(1, 10), flint.fmpq(1, 10), gmpy2.mpq(1, 10), "0.1", ar("1/10")]
    values = {to_fraction(ar, Htilde(f, x, e, ar)) for x in points for e in epss}
    from exact_khk.certification.lie_poisson import htilde_definition
    values |= {to_fraction(ar, htilde_definition(f, x, e, ar)) for x in points[:4] for e in epss[:3]}
    assert len(values) == 1
    x = points[0]
    assert to_fraction(ar, grad_Htilde(f, x, "1/10", ar)) == to_fraction(ar, grad_Htilde(f, points[1], "1/10", ar))
    assert [to_fraction(ar, r) for r in Pi(s, x, "1/10", ar)] == [to_fraction(ar, r) for r in
                                                                Pi_from_q(s, x, "1/10", ar)]
    assert len(q_coefficients(s, x, ar)) == 3


@pytest.mark.parametrize("bad", [0.5, float("nan")])
def test_floats_refused_in_exact_arithmetics(bad):
    import numpy as np

    from exact_khk import InputError, KahanMap
    from exact_khk.systems.lie_poisson.invariants import Htilde, grad_Htilde

    f = _lp().field("f")
    x = [bad, 2, -1, "1/2", 0, 1]
    for call in (lambda: Htilde(f, x, "1/10", "flint"), lambda: Htilde(f, [1, 2, -1, 1, 0, 1], bad, "fraction"),
                 lambda: grad_Htilde(f, x, "1/10", "gmpy2"), lambda: KahanMap(f, "1/10").step(x),
                 lambda: KahanMap(f, np.float64(0.1)), lambda: KahanMap(f, "1/10").step(np.array([bad, 2, -1, 0.5, 0, 1])),
                 lambda: Htilde(f, ["x", 2, -1, 1, 0, 1], "1/10"), lambda: Htilde(f, [1, 2], "1/10"),
                 lambda: Htilde(f, "123456", "1/10")):
        with pytest.raises(InputError):
            call()


def test_numpy_in_floating_arithmetics():
    import numpy as np

    from exact_khk import KahanMap
    from exact_khk.systems.lie_poisson.invariants import Htilde

    f = _lp().field("f")
    x = np.array([1.0, 2.0, -1.0, 0.5, 0.0, 1.0])
    y = KahanMap(f, "1/10", "float").step(x)
    assert all(type(t) is float for t in y)
    assert KahanMap(f, np.float64(0.1), "float").step(x) == y
    assert KahanMap(f, "1/10", "float").step(x.astype(np.float32)) == y
    z = KahanMap(f, np.float64(0.1), "mp:60").step(list(x))
    assert abs(float(z[0]) - y[0]) < 1e-12
    h = Htilde(f, x, np.float64(0.1), "float")
    assert type(h) is float and h == Htilde(f, [float(t) for t in x], 0.1, "float")


def test_float_orbit_through_an_exactly_singular_step_raises():
    import warnings

    from exact_khk import KahanMap, LiePoissonSystem, SingularStepError

    s = LiePoissonSystem.from_vectors("1,2", "0,1", "-1,3")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no raw warning either
        for method in ("dense", "structured"):
            with pytest.raises(SingularStepError, match="step 1"):
                KahanMap(s.field("f"), "1/5", "float", method=method).orbit(["1", "0", "2", "1"], 3)


def test_floating_integrals_scale_and_follow_the_conditioning_policy():
    from exact_khk import Htilde, NearSingularWarning
    from exact_khk.errors import NumericalError, PoleError

    f = _lp().field("f")
    exact = float(Htilde(f, [10 ** 160, 2 * 10 ** 160, -10 ** 160, 10 ** 160, 0, 10 ** 160], "1/10"))
    for arith, scale in (("float", 1e160), ("mp:53", 1e200), ("float", 1e300)):
        x = [scale, 2 * scale, -scale, scale, 0.0, scale]
        assert abs(float(Htilde(f, x, "1/10", arith)) - exact) < 1e-12 * abs(exact)
    # H~ of this n = 2 system has a pole at x = (1, 2, 0, 1), eps = 1/18 ((Hs J(x))^2 has eigenvalue 18^2)
    from fractions import Fraction

    from exact_khk import LiePoissonSystem

    g = LiePoissonSystem.from_vectors("-2,1", "3,3", "3,-3").field("f")
    x = ["1", "2", "0", "1"]
    with pytest.raises(PoleError) as exact:
        Htilde(g, x, "1/18", "flint")
    assert not isinstance(exact.value, NumericalError) and "has a pole" in str(exact.value)
    with pytest.raises(NumericalError, match="not a proven pole") as numeric:  # rounding hides the pole
        Htilde(g, x, "1/18", "float")
    assert numeric.value.condition >= 2 ** 53
    near = Fraction(1, 18) * (1 + Fraction(1, 10 ** 10))
    with pytest.warns(NearSingularWarning) as rec:
        value = Htilde(g, x, near, "float")
    kappa = rec[0].message.condition
    assert 2 ** 26 < kappa < 2 ** 53
    # backward-stable elimination: relative error <= c·N·u·κ (N = 4, u = 2^-53; c = 2 allowed;
    # measured 0.16·u·κ)
    assert abs(value - float(Htilde(g, x, near, "flint"))) <= 2 * len(x) * 2.0 ** -53 * kappa * abs(value)


def test_to_fraction_one_call():
    from fractions import Fraction

    from exact_khk import InputError, get_arith
    from exact_khk.arith import to_fraction

    for name in ("flint", "gmpy2", "fraction"):
        ar = get_arith(name)
        assert to_fraction(ar, ar("-3/4") * 2) == Fraction(-3, 2)
        assert to_fraction(ar, [ar(1), "1/3"]) == (Fraction(1), Fraction(1, 3))
    assert to_fraction(get_arith("float"), 0.1) == Fraction(0.1)
    assert to_fraction(get_arith("mp:80"), get_arith("mp:80")("1/4")) == Fraction(1, 4)
    K = get_arith("cyclo:3")
    assert to_fraction(K, K("2/3")) == Fraction(2, 3)
    with pytest.raises(InputError):
        to_fraction(K, K.gen)
    with pytest.raises(InputError):
        to_fraction(get_arith("gf:7"), get_arith("gf:7")(3))
    with pytest.raises(InputError):
        to_fraction(get_arith("flint"), 0.5)


def test_progress_only_on_a_terminal(monkeypatch):
    """Progress bars (studies, sweeps, orbits) only when stderr is a terminal and --quiet is absent."""
    import argparse
    import io

    from exact_khk.cli.options import shows_progress

    class Tty(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr(sys, "stderr", io.StringIO())
    assert shows_progress(argparse.Namespace(quiet=False)) is False
    monkeypatch.setattr(sys, "stderr", Tty())
    assert shows_progress(argparse.Namespace(quiet=False)) is True
    assert shows_progress(argparse.Namespace(quiet=True)) is False


def test_progress_bar_shows_while_one_long_step_reports_nothing(monkeypatch):
    """A run whose first step takes minutes (degrees at n = 30, liouville at n = 12 building
    its maps) reported nothing, so tqdm never drew the bar: a thread now redraws it after
    DELAY and every TICK, and stops with the bar."""
    import argparse
    import io
    import time

    from exact_khk.cli.options import Progress

    class Tty(io.StringIO):
        def isatty(self):
            return True

    err = Tty()
    monkeypatch.setattr(sys, "stderr", err)
    monkeypatch.setattr(Progress, "DELAY", 0.05)
    monkeypatch.setattr(Progress, "TICK", 0.05)
    with Progress(argparse.Namespace(quiet=False), 10, "slowstage") as progress:
        monkeypatch.setattr(progress.bar, "delay", 0.05)
        deadline = time.monotonic() + 30
        while "slowstage" not in err.getvalue() and time.monotonic() < deadline:
            time.sleep(0.02)  # no update: only the thread can draw the bar
        assert "slowstage" in err.getvalue() and "0/10" in err.getvalue()
    size = len(err.getvalue())
    time.sleep(0.2)
    assert len(err.getvalue()) == size  # the thread stopped with the bar


def test_real_vectors_of_unknown_length_are_limited_per_coordinate():
    """A real vector read without a known dimension (``enclose --a`` without ``--n``)
    is limited per coordinate, like one of known dimension: 300 entries ``sqrt(2)``
    are read; one entry longer than the limit is refused."""
    from exact_khk.arith.reals import MAX_REAL_CHARS, parse_real_vector
    from exact_khk.errors import InputError

    assert len(parse_real_vector(",".join(["sqrt(2)"] * 300), 64, "--a")) == 300
    with pytest.raises(InputError, match="per coordinate"):
        parse_real_vector("1" * (MAX_REAL_CHARS + 1), 64, "--a")


def test_classify_reports_progress_during_its_degree_stage(monkeypatch, capsys):
    """classify's degree stage (minutes for a long run) passed no callback: a terminal showed nothing.
    The command's progress display now hears each step over F_p and each later stage by name."""
    import exact_khk.cli.classify as cli_classify

    heard = []

    class Recording:
        def __init__(self, *args, **kw):
            pass

        def __call__(self, where):
            heard.append(where)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

    monkeypatch.setattr(cli_classify, "Progress", Recording)
    code = main(["classify", "euler-top", "--steps", "6", "--degree", "2", "--no-discover", "--exact", "0"])
    assert code == 4  # undetermined: 6 iterates do not confirm the growth
    steps = [w for w in heard if str(w).startswith("degrees over F_p: step")]
    assert [int(w.rsplit(" ", 1)[1]) for w in steps] == list(range(1, 13))  # 2 lines (primes) of 6 steps
    assert heard.index(steps[-1]) < heard.index("integrals of degree <= 2")
