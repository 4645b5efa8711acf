#!/usr/bin/env python3
"""The structured exact step's division rule of ``systems.lie_poisson.paths``, measured: its two division routes.

Divisions (``--ns``, ``--bits``): along the orbit of ``random_point(n, 1)`` (field f of
``LiePoissonSystem.random(n, seed=1)``, ε = 1/10), at the first point whose height reaches each
target, every division the step makes over a factor Z[t]/(tᵐ ∓ 1) of tⁿ − 1 is recorded and
timed both ways: Cramer's rule down the tower (``CirculantRing._solve_norm``) and the fixed-point
division (``CirculantRing.solve`` with the tower ruled out, from the hint the ring had).  H is
Cramer's bound on the answer (bits); "rule" is what ``circulant.by_norm`` picks.

Norm (``--norm-ns``, odd n only; ``--norm-bits``): where the tower ends at an odd b, the norm by
the Galois conjugates (``CirculantRing.norm``) against d⁻¹ over Q by ``fmpq_poly.xgcd`` (FLINT's
multimodular gcd, the route before it), for random d with coefficients of each height.

Times are medians of ``--rounds`` interleaved rounds (each a loop of about 2 ms of calls); both routes give the same answer (asserted).
Nothing about speed is asserted.  Prints Markdown tables.

    python3 scripts/bench_division.py [--ns 16,32,64] [--bits 0,1000,3000]
    python3 scripts/bench_division.py --ns "" --norm-ns 5,9,11,15 --norm-bits 10,100,1000
"""

from __future__ import annotations

import argparse
import random
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench import EPS, height  # noqa: E402
from bench_exact import fmt, medians  # noqa: E402

from exact_khk import LiePoissonSystem, get_arith  # noqa: E402
from exact_khk.systems.lie_poisson import circulant as C  # noqa: E402
from exact_khk.systems.lie_poisson.system import random_point  # noqa: E402


def ints(text):
    return [int(t) for t in text.split(",") if t.strip()]


def per_call(fns, rounds):
    """Median time per call of each callable over ``rounds`` interleaved rounds, each round
    a loop of about 2 ms of calls (a single call of tens of µs is mostly timer and cache
    noise)."""
    number = {}
    for k, f in fns.items():
        t0 = time.perf_counter()
        f()
        number[k] = max(1, int(2e-3 / max(time.perf_counter() - t0, 1e-7)))
    loops = {k: (lambda f=f, m=number[k]: [f() for _ in range(m)]) for k, f in fns.items()}
    return {k: t / number[k] for k, t in medians(loops, rounds=rounds).items()}


def fixed_point(ring, hint, d, rhs):
    """The fixed-point division of d by a fresh ring with the hint ``ring`` had."""
    fresh = C.CirculantRing(ring.n, ring.sign)
    fresh.height_ratio = hint
    saved = C.by_norm
    C.by_norm = lambda n, bound: False
    try:
        return fresh.solve(d, rhs)
    finally:
        C.by_norm = saved


def division_rows(n, targets, rounds):
    ar = get_arith("flint")
    st = C.circulant_structure(LiePoissonSystem.random(n, seed=1).field("f"))
    x, eps, k, done = [ar(t) for t in random_point(n, 1)], ar(EPS), 0, set()
    real = C.CirculantRing.solve
    for target in targets:
        while height(x) < target:
            x, k = C.exact_step(st, x, eps, ar), k + 1
        if k in done:
            continue
        done.add(k)
        seen = []
        C.CirculantRing.solve = lambda self, d, rhs: seen.append((self, self.height_ratio, d, rhs)) or real(self, d, rhs)
        try:
            C.exact_step(st, x, eps, ar)
        finally:
            C.CirculantRing.solve = real
        for ring, hint, d, rhs in seen:
            if ring.n == 1:
                continue  # scalar: no fixed-point division to compare
            H = C._hadamard_bits(ring.n, max(d.height_bits(), 1), max(r.height_bits() for r in rhs))
            a, b = ring._solve_norm(d, rhs), fixed_point(ring, hint, d, rhs)
            assert [w * b[1] for w in a[0]] == [w * a[1] for w in b[0]], "the two divisions differ"
            t = per_call({"norm": lambda: ring._solve_norm(d, rhs), "fixed": lambda: fixed_point(ring, hint, d, rhs)},
                        rounds=rounds)
            factor = f"t^{ring.n} {'+' if ring.sign < 0 else '-'} 1"
            yield (f"| {n} | {k} | {height(x)} | {factor} | {H} | {fmt(t['norm'])} | {fmt(t['fixed'])} | "
                   f"{t['norm'] / t['fixed']:.2f} | {'norm' if C.by_norm(ring.n, H) else 'fixed point'} |")


def norm_rows(ns, bits_list, rounds):
    """The norm at odd n (the Galois conjugates) against d⁻¹ over Q by ``fmpq_poly.xgcd``, for
    random d with coefficients of each height; both give d·A = N (asserted)."""
    import flint

    rng = random.Random(7)
    for n in ns:
        ring = C.CirculantRing(n)
        for bits in bits_list:
            d = flint.fmpz_poly([rng.randint(-2 ** bits, 2 ** bits) for _ in range(n)])
            N, A = ring.norm(d)
            assert N != 0 and ring.mul(d, A) == N, "not d·A = N"
            g, s, _ = flint.fmpq_poly(d).xgcd(ring.modulus)
            t = per_call({"galois": lambda: ring.norm(d), "xgcd": lambda: flint.fmpq_poly(d).xgcd(ring.modulus)},
                        rounds=rounds)
            yield (f"| {n} | {bits} | {fmt(t['galois'])} | {fmt(t['xgcd'])} | {t['galois'] / t['xgcd']:.2f} | "
                   f"{N.bit_length()} | {s.denom().bit_length()} |")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ns", type=ints, default=ints("16,32,64"))
    ap.add_argument("--bits", type=ints, default=ints("0,1000,3000"), help="orbit heights of the division table")
    ap.add_argument("--norm-ns", type=ints, default=[], help="odd n of the norm table (none by default)")
    ap.add_argument("--norm-bits", type=ints, default=ints("10,100,1000"), help="heights of the norm table's d")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args(argv)
    if args.ns:
        table(["n", "step", "height (bits)", "factor", "Cramer's bound H (bits)", "norm", "fixed point",
               "norm / fixed point", "rule"], (line for n in args.ns for line in division_rows(n, args.bits, args.rounds)))
    if args.norm_ns:
        if any(n % 2 == 0 or n < 3 for n in args.norm_ns):
            ap.error("--norm-ns: odd n >= 3 only (the tower's end)")
        print()
        table(["n", "height of d (bits)", "norm (Galois)", "xgcd over Q", "norm / xgcd", "bits of N",
               "bits of xgcd's denominator"], norm_rows(args.norm_ns, args.norm_bits, args.rounds))


def table(columns, lines):
    """A Markdown table, each row printed as soon as it is measured."""
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    for line in lines:
        print(line, flush=True)


if __name__ == "__main__":
    main()
