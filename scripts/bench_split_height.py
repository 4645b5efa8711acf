#!/usr/bin/env python3
"""The split step against the structured one high up exact orbits (n < 16), as a Markdown table.

Where ``method='auto'`` splits (n ≤ ``systems.lie_poisson.paths.AUTO_SPLIT_MAX_N``), the split step
should stay faster than the structured one up to the heights users reach.  Along the orbit of ``random_point(n, 1)`` (field f of
``LiePoissonSystem.random(n, seed=1)``, ε = 1/10), at the first point whose height reaches
each target, one step of each method is timed ``--rounds`` times, the two alternating
(medians; the split system is built before the timing).  Nothing is asserted.

    python3 scripts/bench_split_height.py [--ns 5,6,8,9,10,12] [--bits 3000,10000,20000] [--rounds 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench import EPS, height  # noqa: E402

from exact_khk import KahanMap, LiePoissonSystem  # noqa: E402
from exact_khk.systems.lie_poisson.system import random_point  # noqa: E402


def ints(text):
    return [int(t) for t in text.split(",")]


def fmt(t):
    return f"{t * 1e3:.2f} ms"


def rows(n, targets, rounds):
    fld = LiePoissonSystem.random(n, seed=1).field("f")
    split, struct = (KahanMap(fld, EPS, "flint", method=m) for m in ("split", "structured"))
    x, k = struct.point(random_point(n, 1)), 0
    split.step(x)
    for target in targets:
        while height(x) < target:
            x, k = struct.step(x), k + 1
        times = {"split": [], "structured": []}
        for r in range(rounds):
            for name, m in (("split", split), ("structured", struct))[::1 if r % 2 else -1]:
                t0 = time.perf_counter()
                m.step(x)
                times[name].append(time.perf_counter() - t0)
        a, b = (statistics.median(times[name]) for name in ("split", "structured"))
        yield f"| {n} | {k} | {height(x)} | {fmt(a)} | {fmt(b)} | {a / b:.2f} |"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ns", type=ints, default=ints("5,6,8,9,10,12"))
    ap.add_argument("--bits", type=ints, default=ints("3000,10000,20000"))
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args(argv)
    print("| n | step | height (bits) | split | structured | split / structured |")
    print("|---|---|---|---|---|---|")
    for n in args.ns:
        for line in rows(n, args.bits, args.rounds):
            print(line, flush=True)


if __name__ == "__main__":
    main()
