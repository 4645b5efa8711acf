#!/usr/bin/env python3
"""Whole commands, as a user waits for them: ``exact-khk ARGS`` in this tree and in an older one.

Each command runs as a child process (``python -m exact_khk ARGS``, the tree on PYTHONPATH,
output discarded) in this tree and, with ``--tree OLD``, in that one, the two alternating
in every round; the time is the child's CPU time (``resource.getrusage``), the median over
the rounds.  A command that fails in either tree stops the script with its last line.

Usage:  python3 scripts/bench_commands.py [--tree OLD_TREE] [--rounds 2] ["hard" "orbit --n 8" ...]
No timing is asserted anywhere; this only measures.  Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import os
import shlex
import statistics
import subprocess
import sys
from pathlib import Path

from script_io import child_cpu

ROOT = Path(__file__).resolve().parent.parent


def run(tree: Path, args: list) -> float:
    """CPU seconds of ``exact-khk args`` run from ``tree``."""
    before = child_cpu()
    out = subprocess.run([sys.executable, "-m", "exact_khk", *args], capture_output=True, text=True,
                         cwd=tree, env={**os.environ, "PYTHONPATH": str(tree)})
    if out.returncode != 0:
        last = (out.stderr.strip().splitlines() or ["(no message)"])[-1]
        sys.exit(f"bench_commands: 'exact-khk {shlex.join(args)}' failed in {tree} "
                 f"(exit {out.returncode}): {last}")
    return child_cpu() - before


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("commands", nargs="*", default=["hard"], help="argument strings of exact-khk (default: hard)")
    ap.add_argument("--tree", type=Path, help="an older source tree to compare with")
    ap.add_argument("--rounds", type=int, default=2, help="alternating rounds per command (default 2)")
    args = ap.parse_args(argv)
    if args.rounds < 1:
        ap.error("--rounds: expected a positive integer")
    if args.tree is not None and not (args.tree / "exact_khk").is_dir():
        ap.error(f"--tree: {args.tree} holds no exact_khk package")
    trees = [("this tree", ROOT)] + ([("--tree", args.tree.resolve())] if args.tree else [])
    print("| command | " + " | ".join(name for name, _ in trees) + (" | old / new |" if args.tree else " |"))
    print("|---|" + "---|" * len(trees) + ("---|" if args.tree else ""))
    for command in args.commands:
        argv_ = shlex.split(command)
        times = {name: [] for name, _ in trees}
        for r in range(args.rounds):
            for name, tree in (trees if r % 2 else trees[::-1]):
                times[name].append(run(tree, argv_))
        t = {name: statistics.median(v) for name, v in times.items()}
        row = " | ".join(f"{t[name]:.2f} s" for name, _ in trees)
        ratio = f" {t['--tree'] / t['this tree']:.2f}× |" if args.tree else ""
        print(f"| `exact-khk {command}` | {row} |{ratio}", flush=True)


if __name__ == "__main__":
    main()
