#!/usr/bin/env python3
"""Benchmark of ``exact-khk certify`` (default checks): the certificate of the
Lie–Poisson family for n = 3 (the built-in system) and n = 4, 8, 16 (``--seed``
systems), 20 steps, flint arithmetic.

For each n it reports

* the in-process call of the public API ``exact_khk.certify(system, x0, steps=…)``
  in a fresh interpreter (imports excluded): the median wall time and CPU time
  (``time.process_time``) of ``--reps`` calls, after one warm-up call with 2 steps;
* the whole command ``python -m exact_khk certify … --quiet`` once: wall time and
  the CPU time of the child process (start-up and imports included);

and the verdict with its number of claims, as a Markdown table.  CPU time is the
figure to compare on a shared machine (wall time includes waiting for a core).
``--tree`` runs another source tree (e.g. an export of the previous commit) for a
before/after comparison; no timing is asserted anywhere.

Usage:  python scripts/bench_certify.py [--sizes 3,4,8,16] [--steps 20] [--reps 3]
        [--seed 1] [--tree PATH] [--no-cli]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

SNIPPET = """
import json, statistics, sys, time
from fractions import Fraction
from exact_khk import certify, LiePoissonSystem
from exact_khk.systems.lie_poisson import random_point
n, steps, reps, seed = {n}, {steps}, {reps}, {seed}
if n == 3:
    system, x0 = None, None
else:
    system = LiePoissonSystem.random(n, seed)
    x0 = random_point(n, seed, system=system, eps=Fraction(1, 10))
certify(system, x0, steps=2)  # warm-up: lazy imports, caches of the process
walls, cpus = [], []
for _ in range(reps):
    w, c = time.perf_counter(), time.process_time()
    cert = certify(system, x0, steps=steps)
    cpus.append(time.process_time() - c)
    walls.append(time.perf_counter() - w)
claims = sum(1 for ch in cert.checks if ch.expected)
print(json.dumps({{"wall": statistics.median(walls), "cpu": statistics.median(cpus),
                  "status": cert.status, "claims": claims, "checks": len(cert.checks)}}))
"""


def _env(tree: Path):
    """The environment of a run of ``tree`` (which is also its working directory: the
    interpreter puts the working directory first on ``sys.path``)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(tree) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def in_process(tree, n, steps, reps, seed):
    code = SNIPPET.format(n=n, steps=steps, reps=reps, seed=seed)
    out = subprocess.run([sys.executable, "-c", code], env=_env(tree), cwd=tree, capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def cli(tree, n, steps, seed):
    args = [sys.executable, "-m", "exact_khk", "certify", "--steps", str(steps), "--quiet"]
    if n != 3:
        args += ["--n", str(n), "--seed", str(seed)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(args, env=_env(tree), cwd=tree, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    verdict = next((w for w in ("VALID", "INVALID", "INCONCLUSIVE")
                    if proc.stdout.strip().splitlines() and
                    proc.stdout.strip().splitlines()[-1].startswith(w)), f"exit {proc.returncode}")
    return {"wall": wall, "cpu": cpu, "status": proc.returncode, "verdict": verdict}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="3,4,8,16", help="comma-separated n (default 3,4,8,16)")
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--reps", type=int, default=3, help="in-process calls per n (median; default 3)")
    ap.add_argument("--seed", type=int, default=1, help="--seed of the systems for n != 3 (default 1)")
    ap.add_argument("--tree", type=Path, default=ROOT, help="source tree to run (default: this one)")
    ap.add_argument("--no-cli", action="store_true", help="skip the whole-command timing")
    args = ap.parse_args(argv)
    sizes = [int(t) for t in args.sizes.split(",")]
    print(f"tree {args.tree}, {args.steps} steps, flint, seed {args.seed} (n = 3: the built-in system); "
          f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores\n")
    print("| n | certify() wall (s) | certify() CPU (s) | CLI wall (s) | CLI CPU (s) | verdict (claims) |")
    print("|---|---|---|---|---|---|")
    for n in sizes:
        reps = args.reps if n <= 8 else 1
        r = in_process(args.tree, n, args.steps, reps, args.seed)
        c = None if args.no_cli else cli(args.tree, n, args.steps, args.seed)
        verdict = f"{r['status']} ({r['claims']})"
        cw = "–" if c is None else f"{c['wall']:.2f}"
        cc = "–" if c is None else f"{c['cpu']:.2f}"
        print(f"| {n} | {r['wall']:.2f} | {r['cpu']:.2f} | {cw} | {cc} | {verdict} |", flush=True)


if __name__ == "__main__":
    main()
