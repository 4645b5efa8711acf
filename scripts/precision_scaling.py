#!/usr/bin/env python3
"""Precision-scaling study of the Kahan orbit (public API only).

Produces the README's work-precision figure:

    python3 scripts/precision_scaling.py --steps 200 --out docs/figures

Compares float, mp:P and ball:P orbits of the built-in n = 3 system with the exact
orbit, writes scaling.csv / scaling.json / work_precision.png / error_vs_step.png,
and fits the precision rule bits = D*log2(10) + c*K + const for D digits.
"""

import argparse

from exact_khk.studies.scaling import DEFAULT_ARITHS, precision_rule, scaling_study, write_study
from exact_khk.systems.lie_poisson.system import DEFAULT_EPS, DEFAULT_X0, default_system


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--ariths", default=",".join(DEFAULT_ARITHS))
    ap.add_argument("--digits", type=int, default=30)
    ap.add_argument("--out", default="scaling-out")
    ap.add_argument("--repeats", type=int, default=5, help="CPU time per step: the least of this many runs")
    args = ap.parse_args()
    system = default_system()
    study = scaling_study(system, DEFAULT_X0, DEFAULT_EPS, args.steps, args.ariths.split(","), repeats=args.repeats)
    for path in write_study(study, args.out):
        print("wrote", path)
    print(f"exact (flint): {study.exact_seconds_per_step * 1e3:.3f} CPU ms/step (least of {args.repeats} runs)")
    for run in study.runs:
        print(f"{run.arith:>10}: {run.status:<9} bits left {run.bits_left or 0:7.1f}, "
              f"lost/step {run.loss_rate or 0:6.3f}, {(run.seconds_per_step or 0) * 1e3:7.3f} ms/step")
    for kind in ("mp", "ball"):
        rule = precision_rule(system, DEFAULT_X0, DEFAULT_EPS, args.steps, args.digits, kind)
        found = ", ".join(f"K={r.steps}: {r.bits}" for r in rule.results)
        print(f"{kind}: {args.digits} digits need {found} bits; "
              f"fit bits = D*log2(10) + {rule.c:.3f}*K + {rule.const:.1f}")


if __name__ == "__main__":
    main()
