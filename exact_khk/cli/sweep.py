"""``exact-khk sweep SPEC --out DIR``: one task over a family of systems, points, step
sizes and arithmetics, locally or on a Dask cluster (a thin view of
:mod:`exact_khk.sweep`; docs/sweeps.md).

Exit status 0 when every selected task has run (whatever the verdicts: they
are in DIR/results.jsonl and the summary), 2 for a malformed spec or option or a
DIR/results.jsonl that is not a sweep's results file, 5 when DIR cannot be
written, 130 when interrupted (what finished is kept; the same command resumes).
"""

from __future__ import annotations

import sys

from exact_khk.cli.options import shows_progress
from exact_khk.errors import InputError


def register(sub):
    p = sub.add_parser(
        "sweep", help="run one task over many systems, points and step sizes (locally or on Dask)",
        description="Run the task of a sweep spec (TOML: the systems, points, step sizes, arithmetics "
                    "and the task: certify, orbit, scale, degrees, find-integrals, classify, probe) on every "
                    "combination. One JSON line per task is appended to DIR/results.jsonl as tasks "
                    "finish; rerunning the same command skips the tasks already done. A summary (counts "
                    "by verdict, tables, the slowest tasks, plots) is written to DIR and printed. See "
                    "docs/sweeps.md.")
    p.add_argument("spec", metavar="SPEC", help="the sweep spec file (TOML; see docs/sweeps.md)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="folder for results.jsonl, sweep.json and the summary (created if missing)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="local worker processes (default: every core; 0: run in this process); with "
                        "--dask local: the LocalCluster's worker processes")
    p.add_argument("--dask", metavar="ADDRESS",
                   help="run on a Dask distributed cluster: the scheduler's address (e.g. tcp://host:8786; "
                        "start one with 'dask scheduler' and 'dask worker ADDRESS --nthreads 1'), or "
                        "'local' for a LocalCluster on this machine; needs the 'distributed' package")
    p.add_argument("--only", metavar="VERDICTS",
                   help="rerun only the tasks whose recorded verdict is one of these, comma-separated "
                        "(failed = ERROR and TIMEOUT; e.g. 'failed,inconclusive')")
    p.add_argument("--timeout", type=float, metavar="SECONDS",
                   help="time limit per task, at most a year (default: the spec's 'timeout', else 600; 0: none)")
    p.add_argument("--dry-run", action="store_true",
                   help="check the spec and print how many tasks there are, are done and would run")
    p.add_argument("--summary", action="store_true", help="run nothing; rewrite and print the summary of DIR")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plots of the summary")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar (it is off anyway when stderr is not a terminal)")
    p.set_defaults(func=cmd_sweep)


def cmd_sweep(args):
    from exact_khk.sweep.run import ResultStore, parse_only, run_sweep, select
    from exact_khk.sweep.spec import load_spec
    from exact_khk.sweep.tasks import checked_timeout

    checked_timeout(args.timeout, "--timeout")  # refused with --dry-run too
    if args.dask is not None and args.dask != "local" and args.workers is not None:
        raise InputError("--workers: a Dask cluster has its own workers; use --workers only with --dask local")
    if args.dask == "local" and args.workers == 0:
        raise InputError("--workers: --dask local needs at least one worker")
    if args.summary and (args.only is not None or args.dry_run):
        raise InputError("--summary runs nothing; it cannot be combined with --only or --dry-run")
    spec = load_spec(args.spec)
    only = parse_only(args.only, spec.task)
    if args.dry_run:
        tasks = spec.tasks()
        latest = ResultStore(args.out).latest()
        done = sum(1 for t in tasks if t.key in latest)
        todo = select(tasks, latest, only)
        print(f"sweep {spec.name}: {len(tasks)} {spec.task} tasks, {done} done, {len(todo)} would run"
              + (f" (--only {','.join(sorted(only))})" if only is not None else ""))
        return 0
    try:
        result = run_sweep(spec, args.out, workers=args.workers, dask=args.dask,
                           only=frozenset() if args.summary else only,
                           timeout="spec" if args.timeout is None else args.timeout,
                           progress=shows_progress(args), plots=not args.no_plots,
                           echo=None if args.summary else print)
    except KeyboardInterrupt:  # one line, as for any command, saying what is kept
        print(f"exact-khk: interrupted: stopped by the user (Ctrl-C); finished tasks are kept in "
              f"{args.out}/results.jsonl and the same command resumes", file=sys.stderr)
        return 130
    if result.ran:
        over = result.overhead_per_task
        print(f"ran {result.ran} tasks in {result.wall_seconds:.1f} s on {result.engine}: "
              f"{result.ran / result.wall_seconds:.2f} tasks/s; engine overhead "
              f"{over * 1e3:.1f} ms per task" if over is not None and result.wall_seconds > 0 else "")
    print()
    print(result.summary.text())
    print(f"\nwritten to {args.out}: results.jsonl, sweep.json, "
          + ", ".join(p.name for p in result.files))
    return 0
