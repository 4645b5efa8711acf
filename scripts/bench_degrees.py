#!/usr/bin/env python3
"""Degree growth on a line over F_p: the two routes of ``diagnostics.degrees`` side by side.

For each case, one random line over the prime 2^61.3 (``GOOD`` of the tests), ``--steps``
iterates (20 by default): ``polynomial_line_degrees`` (Bareiss over ``nmod_poly``) and
``valued_line_degrees`` (orbits of points of the line, Cauchy interpolation), and
``line_degrees``, the rule (values from dimension 8, handing over to polynomial arithmetic
once the degrees grow geometrically); CPU time
(``time.process_time``), the three alternating for ``--rounds`` rounds (medians); each
call is cut at ``--budget`` seconds of CPU by running it in a child process (a route
past the budget is reported as "> budget").  The degrees of the two routes are compared
(they must be equal; a route cut by ``max_degree`` reports one term fewer from values).
Cases: the Lie–Poisson family ``LiePoissonSystem.random(n, 1)``, field f (dimension 2n,
linear growth), and the cyclic quadratic fields of dimension N (exponential growth N^k,
cut at the default ``max_degree`` 20 000).

Then the whole command ``exact-khk degrees --n N --seed 1 --no-heights --quiet`` once per
tree (this one, and ``--tree OLD`` if given, alternating), CPU time of the child.

Usage:  python3 scripts/bench_degrees.py [--ns 2,3,4,5,6,8,16] [--cyclic 6,8,12,16] [--steps 20]
        [--rounds 2] [--budget 120] [--commands 4,8] [--tree OLD_TREE]
No timing is asserted anywhere; this only measures.  Prints a Markdown section.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
from pathlib import Path

from script_io import child_cpu

ROOT = Path(__file__).resolve().parent.parent

CHILD = r"""
import json, random, sys, time
from fractions import Fraction
from exact_khk import LiePoissonSystem
from exact_khk.diagnostics.degrees import line_run, polynomial_line_degrees, valued_line_degrees, resolve_field
from exact_khk.systems.expressions import ExpressionSystem
kind, size, steps, route = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
if kind == "lp":
    system = LiePoissonSystem.random(size, 1)
else:
    xs = [f"x{i}" for i in range(size)]
    system = ExpressionSystem.from_expressions(xs, field=[
        f"{xs[(i + 1) % size]}*{xs[(i + 2) % size]} - {xs[i]} + {i + 1}*{xs[(i + 3) % size]}**2"
        for i in range(size)], name=f"cyclic-{size}")
_, fld = resolve_field(system, "f")
fn = {"values": valued_line_degrees, "polynomials": polynomial_line_degrees,
      "rule": lambda *a: line_run(*a)[0]}[route]
t = time.process_time()
degs = fn(fld, Fraction(1, 10), 2749534618746033473, steps, random.Random(1), 20_000)
print(json.dumps({"cpu": time.process_time() - t, "degrees": degs}))
"""


def run_route(kind, size, steps, route, budget):
    try:
        out = subprocess.run([sys.executable, "-c", CHILD, kind, str(size), str(steps), route],
                             capture_output=True, text=True, timeout=budget, cwd=ROOT,
                             env={**os.environ, "PYTHONPATH": str(ROOT)})
    except subprocess.TimeoutExpired:
        return None, None
    if out.returncode:
        sys.exit(f"bench_degrees: the child failed: {out.stderr.strip().splitlines()[-1:]}")
    res = json.loads(out.stdout)
    return res["cpu"], res["degrees"]


def run_command(tree, n, steps):
    before = child_cpu()
    subprocess.run([sys.executable, "-m", "exact_khk", "degrees", "--n", str(n), "--seed", "1", "--steps",
                    str(steps), "--no-heights", "--quiet"], check=True, capture_output=True, cwd=tree,
                   env={**os.environ, "PYTHONPATH": str(tree)})
    return child_cpu() - before


def fmt(t, budget):
    return f"> {budget:.0f} s" if t is None else (f"{t * 1e3:.0f} ms" if t < 1 else f"{t:.2f} s")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ns", default="2,3,4,5,6,8,16", help="Lie–Poisson n (dimension 2n)")
    ap.add_argument("--cyclic", default="6,8,12,16", help="dimensions of the cyclic fields (exponential growth)")
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--budget", type=float, default=120.0, help="seconds of one route's call before it is cut")
    ap.add_argument("--commands", default="4,8", help="n of the whole `exact-khk degrees` commands")
    ap.add_argument("--tree", type=Path, help="an older source tree for the whole commands")
    args = ap.parse_args(argv)
    cases = [("lp", int(n)) for n in args.ns.split(",") if n] + [("cyclic", int(N)) for N in args.cyclic.split(",") if N]
    print(f"One random line, {args.steps} steps, CPU time, medians of {args.rounds} alternating rounds "
          f"(a call cut at {args.budget:.0f} s).\n")
    print("| case | dimension | d_k reached | polynomial arithmetic | values | the rule | "
          "polynomials / values | polynomials / the rule |")
    print("|---|---|---|---|---|---|---|---|")
    for kind, size in cases:
        times = {"polynomials": [], "values": [], "rule": []}
        degs = {}
        order = ["polynomials", "values", "rule"]
        for r in range(args.rounds):
            for route in order[r % 3:] + order[:r % 3]:
                t, d = run_route(kind, size, args.steps, route, args.budget)
                times[route].append(t)
                degs[route] = d or degs.get(route)
        dp, dv, drule = degs["polynomials"], degs["values"], degs["rule"]
        for d in (dv, drule):
            if dp is not None and d is not None and d != dp[:len(d)]:
                sys.exit(f"bench_degrees: the routes disagree for {kind} {size}: {dp} against {d}")
        med = {k: (None if None in v else statistics.median(v)) for k, v in times.items()}
        reach = (dv or dp or [None])[-1]
        def ratio(other):
            if med["polynomials"] is not None and med[other] is not None:
                return f"{med['polynomials'] / med[other]:.1f}×"
            return f"> {args.budget / med[other]:.0f}×" if med[other] is not None else "—"
        name = f"Lie–Poisson n = {size}, f" if kind == "lp" else f"cyclic field, N = {size}"
        dim = 2 * size if kind == "lp" else size
        extra = "" if dp is None or len(dp) == len(dv or dp) else f" (polynomials: {dp[-1]})"
        print(f"| {name} | {dim} | d_{len(dv or dp) - 1} = {reach}{extra} | {fmt(med['polynomials'], args.budget)} "
              f"| {fmt(med['values'], args.budget)} | {fmt(med['rule'], args.budget)} | {ratio('values')} "
              f"| {ratio('rule')} |", flush=True)
    trees = [("this tree", ROOT)] + ([("--tree", args.tree.resolve())] if args.tree else [])
    print(f"\nWhole command `exact-khk degrees --n N --seed 1 --steps {args.steps} --no-heights --quiet` "
          "(two runs over F_p), CPU time of the child, trees alternating:\n")
    print("| n | " + " | ".join(name for name, _ in trees) + (" | old / new |" if args.tree else " |"))
    print("|---|" + "---|" * len(trees) + ("---|" if args.tree else ""))
    for n in (int(n) for n in args.commands.split(",") if n):
        t = {name: run_command(tree, n, args.steps) for name, tree in (trees if n % 2 else trees[::-1])}
        row = " | ".join(f"{t[name]:.2f} s" for name, _ in trees)
        print(f"| {n} | {row} |" + (f" {t['--tree'] / t['this tree']:.1f}× |" if args.tree else ""), flush=True)
    print(f"\nMachine: {os.cpu_count()} cores, {platform.platform()}, python {platform.python_version()}; "
          f"load average {os.getloadavg()[0]:.2f} at the end.")


if __name__ == "__main__":
    main()
