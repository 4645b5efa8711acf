#!/usr/bin/env python3
"""One Kahan step and one H̃ in ``cyclo:n`` or ``gf:P``: the exact DFT against the dense solve.

For each n, the associated field g of the sign pattern '+-+…+' (a non-rational involution
for n ≥ 3; over Q(ω)) of ``LiePoissonSystem.random(n, seed=1)``, ε = 1/10, at the third
orbit point from a small integer point: ``KahanMap(method="structured")`` (the exact DFT,
:mod:`exact_khk.systems.lie_poisson.circulant_dft`) against ``method="dense"`` (in ``cyclo:n`` FLINT on
the rational system of size 2n·φ(n); in ``gf:P``, P the default prime of
:data:`exact_khk.arith.cyclotomic.DEFAULT_PRIME` (n | P − 1 for n ≤ 12), f'(x) entry by entry
and an ``nmod_mat`` solve), and ``Htilde`` auto against ``method="dense"``; each pair
checked equal (==) first; medians of interleaved rounds.

Usage:  python3 scripts/bench_cyclo_dft.py [--arith cyclo|gf] [--ns 2,3,4,5,6,7,8,10,12] [--rounds 7]
No timing is asserted anywhere; this only measures.  Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import random
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench import machine  # noqa: E402

from exact_khk import KahanMap, LiePoissonSystem, get_arith  # noqa: E402
from exact_khk.arith.cyclotomic import DEFAULT_PRIME  # noqa: E402
from exact_khk.systems.lie_poisson.invariants import Htilde  # noqa: E402


def medians(fns, rounds):
    times = {k: [] for k in fns}
    keys = list(fns)
    for r in range(rounds):
        for k in keys[r % len(keys):] + keys[:r % len(keys)]:
            t0 = time.perf_counter()
            fns[k]()
            times[k].append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in times.items()}


def fmt(t):
    return f"{t * 1e6:.0f} µs" if t < 1e-3 else f"{t * 1e3:.2f} ms"


def row(n, rounds, arith):
    ar = get_arith(f"cyclo:{n}" if arith == "cyclo" else f"gf:{DEFAULT_PRIME}")
    g = LiePoissonSystem.random(n, seed=1).field("g", "+-" + "+" * (n - 2), cyclotomic=True)
    auto, dense = (KahanMap(g, "1/10", ar, method=m) for m in ("structured", "dense"))
    rng = random.Random(n)
    x = auto.orbit([rng.randint(-3, 3) for _ in range(2 * n)], 2)[-1]
    assert auto.step(x) == dense.step(x)
    assert Htilde(g, x, auto.eps, ar) == Htilde(g, x, auto.eps, ar, method="dense")
    t = medians({"step dft": lambda: auto.step(x), "step dense": lambda: dense.step(x),
                 "H dft": lambda: Htilde(g, x, auto.eps, ar),
                 "H dense": lambda: Htilde(g, x, auto.eps, ar, method="dense")}, rounds)
    return (f"| {n} | {fmt(t['step dft'])} | {fmt(t['step dense'])} | {t['step dense'] / t['step dft']:.1f}× "
            f"| {fmt(t['H dft'])} | {fmt(t['H dense'])} | {t['H dense'] / t['H dft']:.1f}× |")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ns", default="2,3,4,5,6,7,8,10,12")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--arith", choices=("cyclo", "gf"), default="cyclo",
                    help="cyclo: cyclo:n for each n; gf: gf:P, P the default prime")
    args = ap.parse_args(argv)
    try:
        ns = [int(t) for t in args.ns.split(",")]
    except ValueError:
        ap.error(f"--ns: expected integers separated by commas, got {args.ns!r}")
    if args.rounds < 1 or any(n < 2 or n > 64 for n in ns):
        ap.error("--rounds must be positive and each n in 2..64")
    if args.arith == "gf" and any((DEFAULT_PRIME - 1) % n for n in ns):
        ap.error(f"--ns: gf:{DEFAULT_PRIME} holds the n-th roots of unity only for n | P - 1")
    t0 = time.perf_counter()
    print("Machine: " + ", ".join(f"{k} {v}" for k, v in machine().items()) + "\n")
    print("| n | step: DFT | step: dense | dense / DFT | H̃: DFT | H̃: dense | dense / DFT |")
    print("|---|---|---|---|---|---|---|")
    for n in ns:
        print(row(n, args.rounds, args.arith), flush=True)
    print(f"\n({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
