#!/usr/bin/env python3
"""Floating Kahan steps against the obvious alternatives, as interleaved ratios.

For Lie–Poisson systems ``LiePoissonSystem.random(n, seed=1)`` (dimension N = 2n),
ε = 1/(10n) and a random point, one step Φ_f(x, ε) from a point of the arithmetic:

* ``float``: the library step (``KahanMap(f, eps, "float")``, method auto →
  dense) against a bare ``numpy.linalg.solve(M, x)`` of the same prebuilt system
  M = I − εf'(x) plus the condition estimate the library promises,
  ``numpy.linalg.cond(M, 1)``;
* ``mp:P``: the library step against a naive ``ctx.lu_solve(ctx.matrix(M),
  ctx.matrix(x))`` of the same prebuilt M (a private mpmath context at P bits;
  mpmath itself works at P + 10 bits inside ``lu_solve``, and gives no κ);
* the structured (DFT) ``mp:P`` step (``method="structured"``) against the
  library's dense ``mp:P`` step.

The candidates of one ratio alternate (A, B, A, B, …); each sample times a
loop of calls lasting at least ``--sample`` seconds, and the ratio is
median(A)/median(B), so a change of load hits both.  Prints a Markdown table.
No timing is asserted anywhere; this only measures.

Usage:  python scripts/bench_float.py [--ns 2,3,4,8,...] [--prec 128] [--rounds 7]
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings
from fractions import Fraction

import mpmath
import numpy

from exact_khk import KahanMap, LiePoissonSystem, get_arith
from exact_khk.systems.lie_poisson.system import random_point

#: beyond these n a candidate is skipped (reason printed with the table)
MP_DENSE_MAX_N = 64  # 2n×2n elimination in mpf: (2n)³/3 operations, 1 s per step at n = 64
FLOAT_ROUNDS_BIG = 512  # from this n, fewer rounds (one step is seconds)


def sample(fn, seconds):
    """Seconds per call of ``fn``: a loop lasting at least ``seconds``."""
    k, t = 1, 0.0
    while True:
        t0 = time.perf_counter()
        for _ in range(k):
            fn()
        t = time.perf_counter() - t0
        if t >= seconds or k >= 1 << 20:
            return t / k
        k = max(2 * k, int(k * 1.2 * seconds / max(t, 1e-9)))


def ratio(a, b, rounds, seconds):
    """(median time of a, median time of b) over ``rounds`` alternations."""
    sa, sb = [], []
    for _ in range(rounds):
        sa.append(sample(a, seconds))
        sb.append(sample(b, seconds))
    return statistics.median(sa), statistics.median(sb)


def fmt(t):
    return f"{t * 1e6:.0f} µs" if t < 1e-3 else (f"{t * 1e3:.2f} ms" if t < 1 else f"{t:.2f} s")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ns", default="2,3,4,8,16,32,64,128,256,512,1024,2048,4096")
    ap.add_argument("--prec", type=int, default=128)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--sample", type=float, default=0.05)
    ap.add_argument("--float-only", action="store_true", help="only the float column")
    args = ap.parse_args()
    warnings.simplefilter("ignore")  # conditioning warnings do not change the cost
    fl, mp = get_arith("float"), get_arith(f"mp:{args.prec}")
    rows = []
    for n in map(int, args.ns.split(",")):
        system = LiePoissonSystem.random(n, seed=1)
        f = system.field("f")
        eps = Fraction(1, 10 * n)
        x = random_point(n, 1)
        rounds = args.rounds if n < FLOAT_ROUNDS_BIG else max(1, args.rounds // 3)
        phi = KahanMap(f, eps, fl)
        xf = phi.step(x)
        M, b = numpy.array(phi.system_matrix(xf)), numpy.array(xf)
        lib, base = ratio(lambda: phi.step(xf), lambda: (numpy.linalg.solve(M, b), numpy.linalg.cond(M, 1)),
                          rounds, args.sample)
        row = {"n": n, "float": fmt(lib), "numpy": fmt(base), "r_float": lib / base}
        if args.float_only:
            rows.append(row)
            print(row, flush=True)
            continue
        psi = KahanMap(f, eps, mp, method="structured")
        xm = psi.step(x)
        if n <= MP_DENSE_MAX_N:
            dense = KahanMap(f, eps, mp, method="dense")
            Mm = dense.system_matrix(xm)
            ctx = mpmath.MPContext()
            ctx.prec = args.prec
            lib, base = ratio(lambda: dense.step(xm), lambda: ctx.lu_solve(ctx.matrix(Mm), ctx.matrix(list(xm))),
                              rounds, args.sample)
            row.update({"mp": fmt(lib), "mpmath": fmt(base), "r_mp": lib / base})
            dft, lib = ratio(lambda: psi.step(xm), lambda: dense.step(xm), rounds, args.sample)
            row.update({"dft": fmt(dft), "r_dft": lib / dft})
        else:
            row["dft"] = fmt(statistics.median(sample(lambda: psi.step(xm), args.sample) for _ in range(rounds)))
        rows.append(row)
        print(row, flush=True)
    p = args.prec
    print(f"\n| n | float step | numpy solve + cond | float / numpy | mp:{p} dense step | mpmath lu_solve "
          f"| mp / mpmath | mp:{p} DFT step | dense / DFT |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        mpcols = ("— | — | — | — | —" if "dft" not in r else
                  f"{r['mp']} | {r['mpmath']} | {r['r_mp']:.2f} | {r['dft']} | {r['r_dft']:.0f}×" if "mp" in r
                  else f"— | — | — | {r['dft']} | —")
        print(f"| {r['n']} | {r['float']} | {r['numpy']} | {r['r_float']:.2f} | {mpcols} |")
    print(f"\n— : skipped for n > {MP_DENSE_MAX_N}: a dense mp step is (2n)³/3 mpf operations "
          f"(seconds to hours per step), for the library and mpmath alike.")


if __name__ == "__main__":
    main()
