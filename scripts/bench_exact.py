#!/usr/bin/env python3
"""Exact orbit steps at n = 16–256: the structured step against a bare python-flint loop.

Along the orbit of ``random_point(n, 1)`` (field f of ``LiePoissonSystem.random(n, seed=1)``,
ε = 1/10), at the first orbit points whose height reaches each target, one step is timed
three ways in interleaved rounds (medians): ``KahanMap(method="structured").step``,
``KahanMap(method="auto").step`` and a bare ``fmpz_mat.solve`` of the same 2n×2n system
with denominators cleared (built outside the timing, as in scripts/bench.py).

The floor: the time of one ``fmpz_poly`` product of two length-n polynomials whose
coefficients have h' bits, h' the height of the step's output (the largest numerator or
denominator).  Any exact step must at least form the 2×2 determinant over Q[t]/(tⁿ − 1),
a product of that kind at the input's height, and write an output of that size; the
step's time over the floor says how far it is from that.

Whole orbits (``--whole-ns``): every step of ``auto`` from the first point until the height
reaches ``--bits``, against a bare solve of each point's integer system, summed (CPU time) —
the loop a user runs, from its first step.

Usage:  python3 scripts/bench_exact.py [--bits 30000] [--ns 16,24,32] [--floor-ns 2,4,...] [--whole-ns 16,24,32]
No timing is asserted anywhere; this only measures.  Prints a Markdown section.
"""

from __future__ import annotations

import argparse
import math
import random
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench import EPS, integer_system, height, machine  # noqa: E402

import flint  # noqa: E402

from exact_khk import KahanMap, LiePoissonSystem, get_arith  # noqa: E402
from exact_khk.systems.lie_poisson.system import random_point  # noqa: E402


def medians(fns, rounds=3, budget=20.0):
    """Median time per callable over ``rounds`` interleaved rounds (rotating order);
    fewer rounds once a callable has used ``budget`` seconds."""
    times = {k: [] for k in fns}
    keys = list(fns)
    for r in range(rounds):
        for k in keys[r % len(keys):] + keys[:r % len(keys)]:
            if times[k] and sum(times[k]) > budget:
                continue
            t0 = time.perf_counter()
            fns[k]()
            times[k].append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in times.items()}


def floor_time(n, bits, rng):
    a, b = (flint.fmpz_poly([rng.getrandbits(bits) | 1 for _ in range(n)]) for _ in range(2))
    return medians({"f": lambda: a * b}, rounds=7)["f"]


def fmt(t):
    return f"{t * 1e6:.0f} µs" if t < 1e-3 else (f"{t * 1e3:.1f} ms" if t < 1 else f"{t:.2f} s")


def orbit_rows(n, targets, log):
    fld = LiePoissonSystem.random(n, seed=1).field("f")
    maps = {m: KahanMap(fld, EPS, "flint", method=m) for m in ("structured", "auto", "dense")}
    x, k, rows, rng = maps["structured"].point(random_point(n, 1)), 0, [], random.Random(n)
    for target in targets:
        while height(x) < target:
            x, k = maps["structured"].step(x), k + 1
        if rows and rows[-1][1] == k:  # two targets reached at the same point: one row
            continue
        y = maps["dense"].step(x)
        assert maps["structured"].step(x) == y == maps["auto"].step(x)
        A, B = integer_system(maps["dense"], x)
        t = medians({"structured": lambda: maps["structured"].step(x), "auto": lambda: maps["auto"].step(x),
                     "bare": lambda: A.solve(B)})
        t["floor"] = floor_time(n, height(y), rng)
        rows.append((n, k, height(x), height(y), maps["auto"].path, t))
        log(f"n={n} step {k} {height(x)}→{height(y)} bits: " + ", ".join(f"{a}={fmt(b)}" for a, b in t.items()))
    return rows


class IntegerSystems:
    """The integer systems s·(I − εf'(x)) z = q·dm·X of a homogeneous field at points x = X/dx,
    built from f'(x) = Σ_k x_k J_k (J_k = f'(e_k), from the public ``field.jacobian``) with
    fmpz_mat products: s = q·dm·dx, ε = p/q, dm the J_k's common denominator.  Much faster than
    ``integer_system`` at 10⁴ bits (no rational arithmetic), so whole orbits can be compared;
    every point's bare solution is checked against the library's step."""

    def __init__(self, fld, eps):
        assert fld.homogeneous, "f'(x) = Σ x_k f'(e_k) needs a homogeneous quadratic field"
        ar, N = get_arith("fraction"), fld.dim
        J = [fld.jacobian(ar, [ar(int(i == k)) for i in range(N)]) for k in range(N)]
        dm = math.lcm(*(t.denominator for Jk in J for row in Jk for t in row))
        self.J = [flint.fmpz_mat([[int(t * dm) for t in row] for row in Jk]) for Jk in J]
        self.dm = flint.fmpz(dm)
        self.p, self.q, self.N = eps.numerator, eps.denominator, N

    def __call__(self, x):
        dx = flint.fmpz(1)
        for t in x:
            dx = dx.lcm(t.q)
        X = [t.p * (dx // t.q) for t in x]
        JX = flint.fmpz_mat(self.N, self.N)
        for Xk, Jk in zip(X, self.J):
            if Xk:
                JX += Jk * Xk
        s = self.q * self.dm * dx
        A = flint.fmpz_mat([[s * int(i == j) for j in range(self.N)] for i in range(self.N)]) - JX * self.p
        return A, flint.fmpz_mat([[self.q * self.dm * Xi] for Xi in X])


def cumulative_rows(n, top, log):
    """Whole orbits: every step from ``random_point(n, 1)`` until the height reaches ``top``,
    CPU time of ``auto`` against a bare ``fmpz_mat.solve`` of each point's prebuilt system."""
    fld = LiePoissonSystem.random(n, seed=1).field("f")
    phi, systems = KahanMap(fld, EPS, "flint", method="auto"), IntegerSystems(fld, EPS)
    x, k, t_auto, t_bare, ratios = phi.point(random_point(n, 1)), 0, 0.0, 0.0, []
    while height(x) < top:
        A, B = systems(x)
        t0 = time.process_time()
        y = phi.step(x)
        t1 = time.process_time()
        Z = A.solve(B)
        t2 = time.process_time()
        assert [Z[i, 0] for i in range(len(x))] == list(y), "the bare system is not the step's"
        t_auto, t_bare = t_auto + t1 - t0, t_bare + t2 - t1
        ratios.append(((t2 - t1) / (t1 - t0), height(x)))
        x, k = y, k + 1
    log(f"cumulative n={n}: {k} steps to {height(x)} bits, auto {t_auto:.2f} s, bare {t_bare:.2f} s")
    return n, k, height(x), t_auto, t_bare, ratios[0][0], min(ratios[1:], default=(float("nan"), 0))


def floor_rows(ns, steps, log):
    rows, rng = [], random.Random(0)
    for n in ns:
        st = KahanMap(LiePoissonSystem.random(n, seed=1).field("f"), EPS, "flint", method="structured")
        pts = st.orbit(random_point(n, 1), steps)
        x, y = pts[-2], pts[-1]
        t = medians({"s": lambda: st.step(x)}, rounds=5)["s"]
        f = floor_time(n, height(y), rng)
        rows.append((n, height(x), height(y), t, f))
        log(f"floor n={n} {height(x)}→{height(y)} bits: step {fmt(t)} floor {fmt(f)} ({t / f:.0f}×)")
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bits", type=int, default=30_000, help="top height of the orbit table (default 30000)")
    ap.add_argument("--ns", default="16,24,32")
    ap.add_argument("--spot-ns", default="2,3,4,6,8,11,12,13,14,15")
    ap.add_argument("--floor-ns", default="2,4,8,16,32,64,128,256")
    ap.add_argument("--floor-steps", type=int, default=6, help="orbit steps before the floor point")
    ap.add_argument("--whole-ns", default="16,24,32", help="n of the whole-orbit table (empty: none)")
    args = ap.parse_args(argv)
    log = lambda s: print(s, file=sys.stderr, flush=True)  # noqa: E731
    t0 = time.perf_counter()
    targets = sorted({t for t in (0, 150, 400, 1000, 3000, 10_000) if t < args.bits} | {args.bits})
    ints = lambda text: [int(t) for t in text.split(",") if t.strip()]  # noqa: E731
    whole = [cumulative_rows(n, args.bits, log) for n in ints(args.whole_ns)]
    orbit = [r for n in ints(args.ns) for r in orbit_rows(n, targets, log)]
    spots = [r for n in ints(args.spot_ns) for r in orbit_rows(n, [0, 1000], log)]
    floors = floor_rows(ints(args.floor_ns), args.floor_steps, log)
    L = ["## Exact orbits at n = 16–256", "",
         f"Generated by `python3 scripts/bench_exact.py --bits {args.bits}` in {time.perf_counter() - t0:.0f} s "
         "on a shared, loaded 2-core machine (other jobs ran alongside; ratios of interleaved runs are "
         "meaningful, absolute times less so). One step at the first point of the orbit of "
         "`random_point(n, 1)` whose height reaches each target: the structured step, `auto`, and a bare "
         "`fmpz_mat.solve` of the same 2n×2n system with denominators cleared (built outside the timing); "
         "medians of 3 interleaved rounds. Floor: one `fmpz_poly` product of two length-n polynomials with "
         "coefficients of the output's height h' (see the script's docstring for why).", "",
         "Machine: " + ", ".join(f"{k} {v}" for k, v in machine().items()) + ".", "",
         "| n | step | h → h' (bits) | auto path | structured | auto | bare solve | bare / structured "
         "| bare / auto | structured / floor |", "|---|---|---|---|---|---|---|---|---|---|"]
    for n, k, h, h2, path, t in orbit + spots:
        L.append(f"| {n} | {k} | {h} → {h2} | {path} | {fmt(t['structured'])} | {fmt(t['auto'])} | "
                 f"{fmt(t['bare'])} | {t['bare'] / t['structured']:.1f}× | {t['bare'] / t['auto']:.1f}× | "
                 f"{t['structured'] / t['floor']:.0f}× |")
    if whole:
        L += ["", f"Whole orbits: every step of `auto` from the first point of the orbit of `random_point(n, 1)` "
              f"until the height reaches {args.bits} bits, against a bare `fmpz_mat.solve` of each point's "
              "integer system (built outside the timing from f'(x) = Σ x_k f'(e_k) in `fmpz_mat`s; each "
              "bare solution checked equal to the step); CPU time, one run, the two alternating step by step.",
              "", "| n | steps | final height (bits) | auto | bare solves | bare / auto | first step (a fresh map: "
              "with its set-up): bare / auto | slowest later step: bare / auto (at height) |",
              "|---|---|---|---|---|---|---|---|"]
        L += [f"| {n} | {k} | {h} | {ta:.2f} s | {tb:.2f} s | {tb / ta:.1f}× | {r0:.2f}× | {w:.2f}× ({wh} bits) |"
              for n, k, h, ta, tb, r0, (w, wh) in whole]
    if floors:
        L += ["", f"Structured step over the floor after {args.floor_steps - 1} orbit steps:", "",
              "| n | h → h' (bits) | structured step | floor | step / floor |", "|---|---|---|---|---|"]
        L += [f"| {n} | {h} → {h2} | {fmt(t)} | {fmt(f)} | {t / f:.0f}× |" for n, h, h2, t, f in floors]
    print("\n".join(L))


if __name__ == "__main__":
    main()
