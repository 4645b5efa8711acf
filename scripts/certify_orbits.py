#!/usr/bin/env python3
"""Certify many random rational orbits and print a summary table.

For every n in --n, seed in --seeds and eps in --eps: the system
LiePoissonSystem.random(n, seed), the point random_point(n, seed), and
``exact_khk.certify`` with --steps steps.  A singular Kahan step is counted
separately (the theorems say nothing there), and so is a certificate with
undecided checks but no wrong result (e.g. the definition h(x, x~) is undefined
on orbits in the invariant hyperplane sum(u) = 0, where J is singular); any
certificate with a wrong result is printed in full.  Exit status 0 iff no
certificate failed.

    python3 scripts/certify_orbits.py --n 2-4 --seeds 0-4 --eps 1/10,1/7 --steps 10
"""

from __future__ import annotations

import argparse
import sys
import time

from tqdm import tqdm

from exact_khk import InputError, LiePoissonSystem, SingularStepError, certify, parse_rational
from exact_khk.systems.lie_poisson.system import random_point


def int_range(text: str) -> list[int]:
    """'2-4' -> [2, 3, 4]; '2,5' -> [2, 5]."""
    out = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        out.extend(range(int(lo), int(hi or lo) + 1))
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", default="2-4", help="values of n, e.g. '2-4' or '2,3,5' (default 2-4)")
    p.add_argument("--seeds", default="0-4", help="random seeds, e.g. '0-9' (default 0-4)")
    p.add_argument("--eps", default="1/10,1/7", help="comma-separated step sizes (default 1/10,1/7)")
    p.add_argument("--steps", type=int, default=10, help="steps per orbit (default 10)")
    p.add_argument("--arith", default=None, help="arithmetic (default: fastest exact)")
    p.add_argument("--poisson-points", type=int, default=None, help="Poisson-map checks at K points only")
    args = p.parse_args(argv)
    try:
        ns, seeds = int_range(args.n), int_range(args.seeds)
        epss = [parse_rational(e, "--eps") for e in args.eps.split(",")]
    except (ValueError, InputError) as exc:
        print(f"certify_orbits: error: {exc}", file=sys.stderr)
        return 2
    cases = [(n, seed, eps) for n in ns for seed in seeds for eps in epss]
    rows = {n: {"cases": 0, "valid": 0, "undecided": 0, "singular": 0, "steps": 0, "height": 0, "seconds": 0.0}
            for n in ns}
    failures, undecided = [], []
    for n, seed, eps in tqdm(cases, desc="certifying", unit="orbit"):
        r = rows[n]
        r["cases"] += 1
        t0 = time.perf_counter()
        try:
            cert = certify(LiePoissonSystem.random(n, seed), random_point(n, seed), eps, args.steps,
                           args.arith, poisson_points=args.poisson_points)
        except SingularStepError as exc:
            r["singular"] += 1
            tqdm.write(f"n={n} seed={seed} eps={eps}: singular step, skipped ({exc})")
            continue
        finally:
            r["seconds"] += time.perf_counter() - t0
        if cert.valid:
            r["valid"] += 1
            r["steps"] += cert.steps
        elif all(c.passed or c.holds is None for c in cert.checks):
            r["undecided"] += 1
            undecided.append((n, seed, eps, cert))
        else:
            failures.append((n, seed, eps, cert))
        r["height"] = max(r["height"], cert.height_bits or 0)
    head = ("n", "cases", "valid", "undecided", "singular", "failed", "steps certified", "max height (bits)",
            "time (s)")
    print("\n" + "  ".join(f"{h:>{max(len(h), 5)}}" for h in head))
    keys = ("cases", "valid", "undecided", "singular", "failed", "steps", "height", "seconds")
    total = dict.fromkeys(keys, 0)
    for n, r in list(rows.items()) + [("all", total)]:
        if n != "all":
            r["failed"] = r["cases"] - r["valid"] - r["undecided"] - r["singular"]
            for k in keys:
                total[k] = max(total[k], r[k]) if k == "height" else total[k] + r[k]
        vals = [n] + [f"{r[k]:.2f}" if k == "seconds" else r[k] for k in keys]
        print("  ".join(f"{v:>{max(len(h), 5)}}" for v, h in zip(vals, head)))
    for n, seed, eps, cert in undecided:
        print(f"\nundecided: n={n} seed={seed} eps={eps}: " + "; ".join(
            f"{c.name}: {c.detail}" for c in cert.checks if c.holds is None))
    for n, seed, eps, cert in failures:
        print(f"\nFAILED: n={n} seed={seed} eps={eps}\n{cert.system.describe()}\n{cert.table()}\n{cert.verdict()}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
