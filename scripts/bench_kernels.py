"""find-integrals: K ∩ span(columns) over F_p, the loop it replaced against one product.

``exact_khk.diagnostics.kernels._restricted`` (99c1d6f) combines the nullspace X with the
kernel basis as one ``nmod_mat`` product; before, a Python loop wrote out
Σ_r X[r, k]·basis[r][c] for every k and c (``loop`` below, kept only to measure it; both share the nullspace, which is timed with each).
For ``find_integrals(LiePoissonSystem.random(3, 1), degree=D)`` every call the search makes
is captured, then the first ``--calls`` of them are timed both ways, alternating call by
call, ``--rounds`` times (the answers compared with ``==``).  Prints a Markdown table.
Nothing is asserted.

    python scripts/bench_kernels.py [--degrees 2,3,4] [--calls 40] [--rounds 3]
"""

from __future__ import annotations

import argparse
import time

from exact_khk import LiePoissonSystem
from exact_khk.diagnostics import find_integrals, kernels


def loop(X, nul, basis, p):
    """The replaced combination: Σ_r X[r, k]·basis[r][c] written out in Python."""
    d, m = len(basis), len(basis[0])
    return [[sum(int(X[r, k]) * basis[r][c] for r in range(d)) % p for c in range(m)] for k in range(nul)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--degrees", default="2,3,4", help="candidate degrees D (n = 3: 28, 84, 210 monomials)")
    ap.add_argument("--calls", type=int, default=40, help="calls timed per degree (the first ones)")
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args(argv)
    product = kernels._restricted
    calls = []

    def spy(basis, keep, p, combine=None):
        calls.append((basis, keep, p))
        return product(basis, keep, p, combine)

    print("| D | candidates | kernel dim | calls timed | loop | product | loop / product |")
    print("|---|---|---|---|---|---|---|")
    kernels._restricted = spy
    try:
        for D in map(int, args.degrees.split(",")):
            calls.clear()
            find_integrals(LiePoissonSystem.random(3, 1), degree=D)
            sample = calls[:args.calls]
            t_loop = t_product = 0.0
            for _ in range(args.rounds):
                for call in sample:
                    t0 = time.perf_counter()
                    a = product(*call, combine=loop)
                    t1 = time.perf_counter()
                    b = product(*call)
                    t2 = time.perf_counter()
                    assert a == b, "the product differs from the loop"
                    t_loop, t_product = t_loop + t1 - t0, t_product + t2 - t1
            basis = sample[0][0]
            print(f"| {D} | {len(basis[0])} | {len(basis)} | {len(sample)} × {args.rounds} | "
                  f"{t_loop * 1e3:.1f} ms | {t_product * 1e3:.1f} ms | {t_loop / t_product:.1f}× |")
    finally:
        kernels._restricted = product


if __name__ == "__main__":
    main()
