"""One orbit kernel: this tree's :func:`orbit_kernel_mod` against another tree's, side by side.

The other tree's ``exact_khk/diagnostics/kernels.py`` (e.g. ``git show 9d7d353:exact_khk/diagnostics/kernels.py
> /tmp/old_kernels.py``) is loaded as a module; both compute the kernel of the same orbit mod the same
prime (the orbit is computed once and handed to both), in interleaved rounds; CPU time per kernel, the
ratio, and that the two results (canonical basis, dimension, stability) are equal with ==.  Systems: the
KQV chain at (N, degree).

    python scripts/bench_kernel_route.py --old /tmp/old_kernels.py [--cases 4:2,10:2,20:2,10:3,5:6]
"""

from __future__ import annotations

import argparse
import importlib.util
import random
import sys
import time
from fractions import Fraction
from pathlib import Path


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", required=True, help="path of the other tree's kernels.py")
    ap.add_argument("--cases", default="4:2,10:2,20:2,10:3,5:6", help="N:degree pairs (comma-separated)")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).parent))
    from bench_discovery import chain

    from exact_khk.diagnostics import kernels as new
    from exact_khk.diagnostics.degrees import random_primes, resolve_field

    spec = importlib.util.spec_from_file_location("old_kernels", args.old)
    old = importlib.util.module_from_spec(spec)
    sys.modules["old_kernels"] = old
    spec.loader.exec_module(old)
    p = random_primes(1, 0)[0]
    orbit = new._orbit_mod
    print("| N | degree | candidates | points | kernel | other tree ms | this tree ms | other / this |")
    print("|---|---|---|---|---|---|---|---|")
    for N, D in (tuple(int(t) for t in c.split(":")) for c in args.cases.split(",")):
        _, fld = resolve_field(chain(N), "f")
        exps = new.monomials(N, D)
        m = len(exps)
        margin = max(8, m // 10)
        steps = m + 2 * margin
        x0 = new._point(random.Random(1), N)
        pts = orbit(fld, Fraction(1, 10), x0, steps, p)
        new._orbit_mod = old._orbit_mod = lambda *a, pts=pts: pts  # noqa: E731  (the same orbit for both)
        t_old = t_new = 0.0
        for _ in range(args.rounds):
            t = time.process_time()
            a = old.orbit_kernel_mod(fld, Fraction(1, 10), x0, exps, steps, p, margin)
            t_old += time.process_time() - t
            t = time.process_time()
            b = new.orbit_kernel_mod(fld, Fraction(1, 10), x0, exps, steps, p, margin)
            t_new += time.process_time() - t
            if (a.basis, a.dim, a.stable) != (b.basis, b.dim, b.stable):
                raise SystemExit(f"N = {N}, degree {D}: the two kernels differ")
        print(f"| {N} | {D} | {m} | {steps + 1} | {a.dim} | {t_old / args.rounds * 1e3:.1f} | "
              f"{t_new / args.rounds * 1e3:.1f} | {t_old / t_new:.2f}× |", flush=True)
        new._orbit_mod = orbit


if __name__ == "__main__":
    main()
