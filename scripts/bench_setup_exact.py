"""Set-up of exact maps for n ≤ 15, as a Markdown table (docs/benchmarks.md, "Set-up of exact maps").

Users wait for a map's set-up at the first step of every command and for every map a
certificate builds (31 at n = 8).  For each n a fresh interpreter (imports done first, not
timed) builds ``LiePoissonSystem.random(n, 1)``'s field f, then times, in CPU seconds,

* ``KahanMap(f, "1/10", "flint")`` and its first step from ``random_point(n, 1)``;
* the next 19 steps of that orbit (the steps themselves, set-up paid);

and, once per n in ``--certify``, the whole command ``python -m exact_khk certify --n N
--seed 1 --quiet`` (CPU time of the child: start-up, set-up and work).  With ``--tree OLD``
every measurement also runs on that source tree, the two trees alternating round by round,
and the table gives old / new side by side.  Nothing is asserted.

    python scripts/bench_setup_exact.py [--tree OLD] [--sizes 3,5,8,11,12,13,15] [--certify 8] [--rounds 5]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

CHILD = r"""
import json, sys, time
n = int(sys.argv[1])
from exact_khk import KahanMap, LiePoissonSystem
from exact_khk.systems.lie_poisson.system import random_point
import flint
flint.fmpz_mat([[2]]).solve(flint.fmpz_mat([[1]]))  # FLINT's own first-call set-up is not the map's
fld = LiePoissonSystem.random(n, 1).field("f")
x = random_point(n, 1)
t = time.process_time()
phi = KahanMap(fld, "1/10", "flint")
x = phi.step(x)
first = time.process_time() - t
t = time.process_time()
phi.orbit(x, 19)
print(json.dumps({"first": first, "next19": time.process_time() - t, "path": phi.path}))
"""


def _env(tree):
    env = dict(os.environ)
    env["PYTHONPATH"] = str(tree) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def child(tree, n):
    out = subprocess.run([sys.executable, "-c", CHILD, str(n)], env=_env(tree), cwd=tree, capture_output=True,
                         text=True, check=True)  # cwd: '-c' and '-m' put the working folder first on sys.path
    return json.loads(out.stdout)


def certify_cpu(tree, n):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-m", "exact_khk", "certify", "--n", str(n), "--seed", "1", "--quiet"],
                   env=_env(tree), cwd=tree, capture_output=True, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _ms(s):
    return f"{s * 1e3:.1f} ms" if s < 1 else f"{s:.2f} s"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tree", default=None, help="an older source tree, measured alternately with this one")
    ap.add_argument("--sizes", default="3,5,8,11,12,13,15", help="n of the map table")
    ap.add_argument("--certify", default="8", help="n of the whole-command certify rows ('' for none)")
    ap.add_argument("--rounds", type=int, default=5, help="alternating rounds (medians)")
    args = ap.parse_args(argv)
    sizes = [int(t) for t in args.sizes.split(",") if t.strip()]
    cert = [int(t) for t in args.certify.split(",") if t.strip()]
    trees = {"new": ROOT} | ({"old": Path(args.tree).resolve()} if args.tree else {})
    maps = {(k, n): [] for k in trees for n in sizes}
    certs = {(k, n): [] for k in trees for n in cert}
    for r in range(args.rounds):
        for n in sizes:
            for k, tree in (trees.items() if r % 2 == 0 else reversed(trees.items())):
                maps[k, n].append(child(tree, n))
        for n in cert:
            for k, tree in (trees.items() if r % 2 == 0 else reversed(trees.items())):
                certs[k, n].append(certify_cpu(tree, n))
        print(f"round {r + 1} of {args.rounds} done", file=sys.stderr)

    def med(rows, key):
        return statistics.median(row[key] for row in rows)
    head = "| n | path | map + first step | next 19 steps |"
    if "old" in trees:
        head = ("| n | path | map + first step: old | new | old / new | next 19 steps: old | new | old / new |")
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    for n in sizes:
        new = maps["new", n]
        if "old" in trees:
            old = maps["old", n]
            print(f"| {n} | {new[0]['path']} | {_ms(med(old, 'first'))} | {_ms(med(new, 'first'))} | "
                  f"{med(old, 'first') / med(new, 'first'):.1f}× | {_ms(med(old, 'next19'))} | "
                  f"{_ms(med(new, 'next19'))} | {med(old, 'next19') / med(new, 'next19'):.2f}× |")
        else:
            print(f"| {n} | {new[0]['path']} | {_ms(med(new, 'first'))} | {_ms(med(new, 'next19'))} |")
    if cert:
        print()
        print("| certify (whole command, CPU) | " + (" old | new | old / new |" if "old" in trees else " new |"))
        print("|---|" + ("---|---|---|" if "old" in trees else "---|"))
        for n in cert:
            new = statistics.median(certs["new", n])
            if "old" in trees:
                old = statistics.median(certs["old", n])
                print(f"| n = {n}, 20 steps | {_ms(old)} | {_ms(new)} | {old / new:.2f}× |")
            else:
                print(f"| n = {n}, 20 steps | {_ms(new)} |")
    print(f"\n{args.rounds} rounds, medians; CPU time (time.process_time, RUSAGE_CHILDREN); python "
          f"{sys.version.split()[0]}, {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
