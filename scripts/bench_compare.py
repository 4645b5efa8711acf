#!/usr/bin/env python3
"""Before/after benchmark: the same cases timed on two source trees, side by side.

Each case is a short snippet that uses only the public API both trees share; it
runs in a fresh subprocess with ``PYTHONPATH`` set to one tree, and reports the
best of several repetitions of its timed part (imports and set-up excluded,
except in the cases that time them on purpose).  Trees alternate round by
round (old, new, old, new, …) so that a change of machine load hits both; the
table keeps each tree's best time and the ratio new/old.

Usage:  python3 scripts/bench_compare.py OLD_TREE [NEW_TREE] [--rounds R] [--only TEXT] [--out PATH]
(OLD_TREE e.g. a ``git worktree`` of the previous commit).  No timing is
asserted anywhere; this only measures.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

PRELUDE = """
import time
from fractions import Fraction
from exact_khk import KahanMap, LiePoissonSystem, Htilde, get_arith
try:
    from exact_khk.systems.lie_poisson import random_point
except ImportError:  # the tree before the package layout
    from exact_khk.systems import random_point
def best(fn, reps=5):
    out = []
    for _ in range(reps):
        t0 = time.perf_counter(); fn(); out.append(time.perf_counter() - t0)
    return min(out)
def orbit_case(n, arith, steps, method="auto"):
    f = LiePoissonSystem.random(n, seed=1).field("f")
    phi = KahanMap(f, Fraction(1, 10), arith, method=method)
    x = random_point(n, 1)
    phi.orbit(x, 1)
    return best(lambda: phi.orbit(x, steps)) / steps
"""

#: (name, snippet printing one float: seconds)
CASES = [
    *[(f"exact orbit step, flint auto, n = {n} ({k} steps)", f"print(orbit_case({n}, 'flint', {k}))")
      for n, k in ((2, 60), (3, 40), (4, 30), (6, 20), (8, 16), (12, 10), (16, 6), (32, 4))],
    *[(f"exact orbit step, flint auto, n = 9 ({k} steps)", f"print(orbit_case(9, 'flint', {k}))") for k in (20, 200)],
    *[(f"exact orbit step, gmpy2 auto, n = {n}", f"print(orbit_case({n}, 'gmpy2', 16))") for n in (3, 8)],
    ("exact orbit step, flint dense, n = 5", "print(orbit_case(5, 'flint', 16, 'dense'))"),
    *[(f"float orbit step (dense), n = {n}", f"print(orbit_case({n}, 'float', 50))") for n in (3, 8)],
    ("mp:256 orbit step (dense), n = 4", "print(orbit_case(4, 'mp:256', 20))"),
    *[(f"H~ at an orbit point, flint, n = {n}",
       f"f = LiePoissonSystem.random({n}, seed=1).field('f'); ar = get_arith('flint')\n"
       f"x = KahanMap(f, Fraction(1, 10), ar).orbit(random_point({n}, 1), 5)[-1]\n"
       f"print(best(lambda: Htilde(f, x, Fraction(1, 10), ar)))") for n in (3, 8, 16)],
    ("certify, the default certificate (n = 3, 20 steps)",
     "from exact_khk import certify\nprint(best(lambda: certify(), reps=3))"),
    *[(f"default point, random_point(n, 1, system) of a new system, n = {n}",
       f"print(best(lambda: random_point({n}, 1, system=LiePoissonSystem.random({n}, seed=1))))")
      for n in (4, 8, 14)],
    *[(f"default point, whole command exact-khk {cmd}",
       "import subprocess, sys\ndef run():\n"
       f"    subprocess.run([sys.executable, '-m', 'exact_khk', *{cmd.split()!r}], check=True, capture_output=True)\n"
       "print(best(run, reps=3))") for cmd in ("orbit --n 14 --seed 1 --steps 5", "integrals --n 12 --seed 1")],
    ("import exact_khk (whole process start, 1 rep)",
     "import subprocess, sys\nt0 = time.perf_counter()\n"
     "subprocess.run([sys.executable, '-c', 'import exact_khk'], check=True)\nprint(time.perf_counter() - t0)"),
]


def run_case(tree: Path, snippet: str) -> float:
    env = dict(os.environ, PYTHONPATH=str(tree))
    out = subprocess.run([sys.executable, "-c", PRELUDE + snippet], env=env, capture_output=True, text=True,
                         timeout=600, cwd=str(tree))
    if out.returncode:
        raise RuntimeError(f"case failed in {tree}: {out.stderr.strip().splitlines()[-1:]}")
    return float(out.stdout.strip().splitlines()[-1])


def fmt(t: float) -> str:
    return f"{t * 1e6:.1f} µs" if t < 1e-3 else (f"{t * 1e3:.2f} ms" if t < 1 else f"{t:.2f} s")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path, nargs="?", default=Path(__file__).resolve().parent.parent)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--only", help="only the cases whose name contains this text")
    ap.add_argument("--out", type=Path, help="write the markdown table here")
    args = ap.parse_args()
    cases = [c for c in CASES if args.only is None or args.only in c[0]]
    if not cases:
        ap.error(f"no case's name contains {args.only!r}")
    best = {tree: {} for tree in ("old", "new")}
    for r in range(args.rounds):
        for name, snippet in cases:
            for tree in ("old", "new"):
                t = run_case(getattr(args, tree), snippet)
                best[tree][name] = min(t, best[tree].get(name, t))
            print(f"round {r + 1}: {name}: old {fmt(best['old'][name])}, new {fmt(best['new'][name])}",
                  file=sys.stderr)
    lines = [f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python "
             f"{platform.python_version()}; best of 5 repetitions × {args.rounds} alternating rounds.", "",
             "| case | before | after | after / before |", "|---|---|---|---|"]
    for name, _ in cases:
        o, n = best["old"][name], best["new"][name]
        lines.append(f"| {name} | {fmt(o)} | {fmt(n)} | {n / o:.2f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        from exact_khk.studies.output import write_atomic
        write_atomic(args.out, text)
    json.dump(best, sys.stderr)


if __name__ == "__main__":
    main()
