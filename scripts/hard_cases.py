#!/usr/bin/env python3
"""Run the hard-case catalogue and write the README table (public API only).

    python3 scripts/hard_cases.py --out docs/figures

Writes hard_cases.md (markdown table) and prints it.
"""

import argparse
import pathlib

from exact_khk.studies.output import write_atomic
from exact_khk.studies.hard import DEFAULT_ARITHS, catalogue, markdown_table, run_catalogue


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ariths", default=",".join(DEFAULT_ARITHS))
    ap.add_argument("--long-steps", type=int, default=1000)
    ap.add_argument("--digits", type=int, default=10)
    ap.add_argument("--out", default="hard-out")
    args = ap.parse_args()
    results = run_catalogue(catalogue(args.long_steps), args.ariths.split(","), args.digits)
    table = markdown_table(results)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_atomic(out / "hard_cases.md", table + "\n")
    print(table)
    silent = [(r.case.name, o.arith) for r in results for o in r.outcomes if o.silent_failure]
    print("silent failures:", silent or "none")


if __name__ == "__main__":
    main()
