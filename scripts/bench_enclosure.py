"""Benchmark of certified long orbits: naive balls against the Lohner enclosure.

For the default n = 3 Lie–Poisson orbit (what ``exact-khk certify`` uses) and the
catalogue's Euler top, enclose K steps at P bits by

* ``ball:P``  — the library's ball arithmetic step (what ``scale`` runs as ball:P),
* ``naive``   — the ball step of :mod:`exact_khk.studies.enclosure` (arb_mat solves),
* ``lohner``  — the mean-value enclosure with Lohner's QR basis,

check every enclosure against the exact orbit where it is affordable (up to
``--exact-bits`` of height), and write ``enclosure_benchmark.json`` and one
``enclosure_radius_<system>.png`` per system into ``--out``.

    PYTHONPATH=. python scripts/bench_enclosure.py --steps 10000 --prec 256 --out docs/figures

Timings are wall-clock on a shared machine; only the radius figures are the
result.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import time

from exact_khk.studies import enclosure, plots, scaling
from exact_khk.studies.output import write_atomic
from exact_khk.systems.catalogue import resolve
from exact_khk.systems.lie_poisson import DEFAULT_EPS, DEFAULT_X0, default_system


def cases():
    et = resolve("euler-top")
    return [("lie-poisson-n3", default_system(), [str(t) for t in DEFAULT_X0], str(DEFAULT_EPS)),
            ("euler-top", et, [str(t) for t in et.default_x0], str(et.default_eps))]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=10_000)
    ap.add_argument("--prec", type=int, default=256)
    ap.add_argument("--exact-bits", type=int, default=1 << 17, help="check against the exact orbit while its "
                    "height stays below this many bits")
    ap.add_argument("--out", default="docs/figures")
    a = ap.parse_args()
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    report = {"command": f"PYTHONPATH=. python scripts/bench_enclosure.py --steps {a.steps} --prec {a.prec} "
                         f"--exact-bits {a.exact_bits} --out {a.out}", "steps": a.steps, "prec": a.prec, "systems": {}}
    for name, system, x0, eps in cases():
        fld = system.field("f")
        t = time.perf_counter()
        exact, exact_sec, _ = scaling.exact_prefix(fld, x0, eps, a.steps, a.exact_bits)
        t_exact = time.perf_counter() - t
        ball = scaling.run_orbit(system, x0, eps, len(exact) - 1, f"ball:{a.prec}", exact, diagnostics=False)
        runs = {}
        for m in ("naive", "lohner"):
            t = time.perf_counter()
            runs[m] = enclosure.enclose(system, x0, eps, a.steps, a.prec, m, exact, scaling.declared(system)[0])
            runs[m + "_seconds"] = time.perf_counter() - t
        lo = runs["lohner"]
        ks = [r.step for r in lo.rows if r.step >= 1 and r.rad_log2 is not None]
        logk_slope = scaling._slope([math.log2(k) for k in ks], [r.rad_log2 for r in lo.rows
                                                                   if r.step >= 1 and r.rad_log2 is not None])
        rec = {
            "x0": x0, "eps": eps, "exact_steps_checked": len(exact) - 1, "exact_seconds": t_exact,
            "ball": {"arith": ball.arith, "status": ball.status, "steps_done": ball.steps_done,
                     "failed_step": ball.failed_step, "radius_rate_bits_per_step": ball.radius_rate,
                     "useless_step": ball.useless_step, "encloses": ball.encloses},
            "naive": dict(runs["naive"].summary(), seconds=runs["naive_seconds"]),
            "lohner": dict(lo.summary(), seconds=runs["lohner_seconds"],
                           log2_radius_vs_log2_k_slope=logk_slope,
                           correct_bits_at={str(k): lo.rows[k].correct_bits for k in (1, 10, 100, 1000, 10000)
                                            if k < len(lo.rows)}),
        }
        report["systems"][name] = rec
        print(name, json.dumps(rec, indent=1))
        LOG2_10 = math.log2(10)
        series = [(f"ball:{a.prec} (library ball step), {ball.radius_rate:.2f} bits/step",
                   [(r.step, r.radius_log10 * LOG2_10) for r in ball.rows if r.radius_log10 is not None]),
                  (f"naive arb_mat balls, {runs['naive'].radius_rate:.2f} bits/step",
                   [(r.step, r.rad_log2) for r in runs["naive"].rows]),
                  (f"Lohner (QR) enclosure, {lo.radius_rate:.5f} bits/step",
                   [(r.step, r.rad_log2) for r in lo.rows])]
        plots.enclosure_radius(series, f"{system.name}, eps={eps}, x0=({', '.join(x0)})\n"
                               f"certified enclosure radius at {a.prec} bits, K={a.steps} steps", out / f"enclosure_radius_{name}.png",
                               target_bits=100)
    write_atomic(out / "enclosure_benchmark.json", json.dumps(report, indent=1) + "\n")


if __name__ == "__main__":
    main()
