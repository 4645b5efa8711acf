#!/usr/bin/env python3
"""The sweep engine's own cost, side by side with a plain ``concurrent.futures`` loop.

Every engine runs the same ``--tasks`` no-op ``probe`` tasks (the sweep task that does no
mathematics: a small system is built, a record made) through ``exact_khk.sweep.run_task``:

* ``loop``: a plain ``ProcessPoolExecutor(N).map(run_task, payloads)`` (forkserver, the same
  preloaded modules), results kept in a list — nothing written, nothing resumable;
* ``local``: ``run_sweep(..., workers=N, plots=False)`` into a fresh folder: the results file
  (synced in batches), the lock, sweep.json and the summary files;
* ``inline``: ``run_sweep(..., workers=0)`` (this process), and ``loop-inline``: a plain
  ``for`` loop over ``run_task`` in this process;
* ``dask`` (``--dask``): ``run_sweep(..., dask="local", workers=N)`` — a LocalCluster.

Every variant includes starting its pool.  The variants run interleaved, ``--rounds`` times;
the table gives the minimum wall time of each and its ratio to ``loop`` (or ``loop-inline``),
the parent's CPU time, and the load average.  Markdown on stdout:

    python scripts/bench_sweep.py [--tasks 1000] [--workers 2] [--rounds 3] [--dask]
    python scripts/bench_sweep.py --spec SPEC.toml --dask     # real tasks instead of no-ops
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from exact_khk.sweep import parse_spec, run_sweep, run_task  # noqa: E402
from exact_khk.sweep.run import PRELOAD, RESULTS  # noqa: E402


def spec(tasks):
    return parse_spec(f'task = "probe"\ntimeout = 60\n[system]\nfamily = "lie-poisson"\nn = 2\n'
                      f'seeds = "0-{tasks - 1}"\n', origin="bench-sweep.toml")


def loop(payloads, workers):
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(PRELOAD)
    with ProcessPoolExecutor(workers, mp_context=ctx) as ex:
        return list(ex.map(run_task, payloads))


def timed(fn):
    t, c = time.perf_counter(), time.process_time()
    n = fn()
    return time.perf_counter() - t, time.process_time() - c, n


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--dask", action="store_true", help="also a Dask LocalCluster (needs distributed)")
    ap.add_argument("--spec", help="a sweep spec file to run instead of the no-op probes (--tasks ignored)")
    args = ap.parse_args()
    if args.spec:
        from exact_khk.sweep import load_spec

        sp = load_spec(args.spec)
        args.tasks = sp.count()
    else:
        sp = spec(args.tasks)
    payloads = [t.payload(60) for t in sp.tasks()]
    tmp = Path(tempfile.mkdtemp(prefix="bench-sweep-"))
    runs = {"loop": [], "local": [], "loop-inline": [], "inline": []}
    if args.dask:
        runs["dask"] = []

    def sweep(name, r, **kw):
        out = tmp / f"{name}-{r}"
        res = run_sweep(sp, out, plots=False, **kw)
        assert res.ran == args.tasks and sum(1 for _ in open(out / RESULTS)) == args.tasks
        return res.ran

    for r in range(args.rounds):
        variants = {"loop": lambda: len(loop(payloads, args.workers)),
                    "local": lambda: sweep("local", r, workers=args.workers),
                    "loop-inline": lambda: len([run_task(dict(p, engine="inline")) for p in payloads]),
                    "inline": lambda: sweep("inline", r, workers=0)}
        if args.dask:
            variants["dask"] = lambda: sweep("dask", r, dask="local", workers=args.workers)
        for name, fn in variants.items():
            wall, cpu, n = timed(fn)
            assert n == args.tasks
            runs[name].append((wall, cpu))
            print(f"round {r + 1}: {name:<12} {wall:7.3f} s wall, {cpu:6.3f} s parent CPU", file=sys.stderr)
    base = {"local": "loop", "dask": "loop", "inline": "loop-inline", "loop": "loop", "loop-inline": "loop-inline"}
    best = {k: min(v) for k, v in runs.items()}
    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    what = f"{sp.task} tasks of {args.spec}" if args.spec else "no-op probe tasks"
    print(f"{args.tasks} {what}, {args.workers} workers, best of {args.rounds} interleaved rounds; "
          f"{os.cpu_count()} cores, Python {platform.python_version()}"
          + (f", load average {load[0]:.1f} at the end" if load else "") + "\n")
    print("| engine | wall s (min) | tasks/s | per task | × plain loop | parent CPU s |")
    print("|---|---|---|---|---|---|")
    for name, (wall, cpu) in best.items():
        print(f"| `{name}` | {wall:.3f} | {args.tasks / wall:,.0f} | {wall / args.tasks * 1e3:.2f} ms | "
              f"{wall / best[base[name]][0]:.2f}× (`{base[name]}`) | {cpu:.2f} |")


if __name__ == "__main__":
    main()
