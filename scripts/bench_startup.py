"""Start-up and set-up times of exact_khk, as Markdown tables (docs/benchmarks.md, "Start-up and set-up").

Start-up: the median wall time (and CPU time) of fresh interpreters running ``exact-khk --help``,
``exact-khk orbit --steps 1``, ``exact-khk certify`` (default options) and ``python -c "import
exact_khk"``, against ``python -c pass``; the commands run interleaved, ``--runs`` rounds
(``exact-khk`` is run as ``python -m exact_khk``, which is what the console script does).

Set-up: for each n a fresh interpreter builds ``LiePoissonSystem.random(n, 1)``, the field f (and g
of B_0), and the maps ``KahanMap(field, "1/10", "flint")`` and ``KahanMap(field, "1/10", "float",
method="structured")``; times are medians over ``--repeats`` fresh systems.  It then takes one
float structured step (and, for n ≤ ``--exact-step-max-n``, one exact step) and reports the peak
RSS of the process (``resource.getrusage``) and above the interpreter with exact_khk imported.

    python scripts/bench_startup.py [--tree PATH] [--runs 10] [--sizes 256,1024,4096,20000]

``--tree`` is the source tree measured (default: this script's), put first on PYTHONPATH; run it
twice (e.g. with ``--tree`` an older checkout) for a before/after comparison.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

SETUP_CHILD = r"""
import json, resource, statistics, sys, time
n, repeats, exact_step = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3] == "1"
t0 = time.perf_counter()
from exact_khk import KahanMap, LiePoissonSystem
from exact_khk.systems.lie_poisson.system import random_point
import exact_khk.arith.cyclotomic, exact_khk.systems.lie_poisson.circulant  # imports are not set-up
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
out = {"n": n, "import": time.perf_counter() - t0}
times = {"system": [], "f": [], "g": []}
for seed in range(1, repeats + 1):
    t = time.perf_counter()
    system = LiePoissonSystem.random(n, seed)
    times["system"].append(time.perf_counter() - t)
    for kind in ("f", "g"):
        t = time.perf_counter()
        fld = system.field(kind)
        maps = (KahanMap(fld, "1/10", "flint"), KahanMap(fld, "1/10", "float", method="structured"))
        times[kind].append(time.perf_counter() - t)
        assert all(m.path == "structured" for m in maps) or n < 16, [m.path for m in maps]
out.update({k: statistics.median(v) for k, v in times.items()})
system = LiePoissonSystem.random(n, 1)
fld = system.field("f")
x0 = random_point(n, 1)
out["setup_rss"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 - base
t = time.perf_counter()
KahanMap(fld, "1/10", "float", method="structured").step(x0)
out["float_step"] = time.perf_counter() - t
out["float_rss"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
if exact_step:
    t = time.perf_counter()
    KahanMap(fld, "1/10", "flint").step(x0)
    out["exact_step"] = time.perf_counter() - t
    out["exact_rss"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
out["base_rss"] = base
print(json.dumps(out))
"""


def _env(tree):
    return dict(os.environ, PYTHONPATH=os.pathsep.join([str(tree)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))


def startup(tree, runs):
    """{label: (median wall, median cpu)} over ``runs`` interleaved rounds."""
    py = sys.executable
    cmds = {
        "`python -c pass`": [py, "-c", "pass"],
        "`python -c \"import exact_khk\"`": [py, "-c", "import exact_khk"],
        "`exact-khk --help`": [py, "-m", "exact_khk", "--help"],
        "`exact-khk orbit --steps 1`": [py, "-m", "exact_khk", "orbit", "--steps", "1"],
        "`exact-khk certify`": [py, "-m", "exact_khk", "certify"],
    }
    wall = {k: [] for k in cmds}
    cpu = {k: [] for k in cmds}
    env = _env(tree)
    for _ in range(runs):
        for label, cmd in cmds.items():
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            t = time.perf_counter()
            res = subprocess.run(cmd, env=env, cwd=tree, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            wall[label].append(time.perf_counter() - t)
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu[label].append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)
            if res.returncode not in (0,):
                raise SystemExit(f"{cmd} ended with {res.returncode}: {res.stderr.decode()[-500:]}")
    return {k: (statistics.median(wall[k]), statistics.median(cpu[k])) for k in cmds}


def setup(tree, n, repeats, exact_step):
    res = subprocess.run([sys.executable, "-c", SETUP_CHILD, str(n), str(repeats), "1" if exact_step else "0"],
                         env=_env(tree), cwd=tree, capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"set-up at n = {n} failed: {res.stderr[-1000:]}")
    return json.loads(res.stdout.strip().splitlines()[-1])


def _t(s):
    return "—" if s is None else (f"{s * 1000:.1f} ms" if s < 1 else f"{s:.2f} s")


def _mb(b):
    return "—" if b is None else f"{b / 2 ** 20:.0f} MB"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tree", default=str(Path(__file__).resolve().parent.parent),
                    help="source tree to measure (put first on PYTHONPATH)")
    ap.add_argument("--runs", type=int, default=10, help="interleaved rounds of the start-up commands")
    ap.add_argument("--sizes", default="256,1024,4096,20000", help="n of the set-up table")
    ap.add_argument("--repeats", type=int, default=3, help="fresh systems per n (median)")
    ap.add_argument("--exact-step-max-n", type=int, default=1024, help="one exact step only up to this n")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    load0 = os.getloadavg()

    rows = startup(args.tree, args.runs)
    base_wall, base_cpu = rows["`python -c pass`"]
    print(f"Start-up (median of {args.runs} interleaved runs; tree {args.tree}):\n")
    print("| command | wall | CPU | wall − `python -c pass` | CPU − `python -c pass` |")
    print("|---|---|---|---|---|")
    for label, (w, c) in rows.items():
        print(f"| {label} | {_t(w)} | {_t(c)} | {_t(w - base_wall)} | {_t(c - base_cpu)} |")

    print("\nSet-up of the Lie–Poisson family (field + maps `KahanMap(fld, \"1/10\", \"flint\")` and "
          "`KahanMap(fld, \"1/10\", \"float\", method=\"structured\")`; median of "
          f"{args.repeats} systems) and one step:\n")
    print("| n | system | field f + 2 maps | field g + 2 maps | set-up RSS | float structured step | "
          "peak RSS after it | exact step | peak RSS after it |")
    print("|---|---|---|---|---|---|---|---|---|")
    for n in (int(t) for t in args.sizes.split(",")):
        r = setup(args.tree, n, args.repeats, n <= args.exact_step_max_n)
        print(f"| {n} | {_t(r['system'])} | {_t(r['f'])} | {_t(r['g'])} | +{_mb(r['setup_rss'])} | "
              f"{_t(r['float_step'])} | {_mb(r['float_rss'])} | {_t(r.get('exact_step'))} | "
              f"{_mb(r.get('exact_rss'))} |")
    load1 = os.getloadavg()
    print(f"\nMachine: {os.cpu_count()} cores, {platform.platform()}, python {platform.python_version()}; "
          f"load average {load0[0]:.1f} at the start, {load1[0]:.1f} at the end; "
          f"{time.perf_counter() - t_start:.0f} s in all.")


if __name__ == "__main__":
    main()
