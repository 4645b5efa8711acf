"""``exact-khk atlas``: classify every catalogue system (and every system file of a folder) as a
sweep at two step sizes, and write the Markdown report docs/atlas.md with its degree figure
(a thin view of :mod:`exact_khk.sweep.atlas`)."""

from __future__ import annotations

import sys

HELP = "classify every catalogue system (and a folder's system files) as a sweep; write docs/atlas.md"


def register(sub):
    p = sub.add_parser("atlas", help=HELP,
                       description="Runs the classify task over the catalogue (and --systems DIR) at each "
                       "system's default eps and a fixed second eps, resumable in --out, and writes the report.")
    p.add_argument("--systems", metavar="DIR", default=None, help="also classify every *.toml system file in DIR")
    p.add_argument("--out", metavar="DIR", default="atlas-results", help="results folder (resumable; default "
                   "atlas-results)")
    p.add_argument("--workers", type=int, default=None, help="local processes (default: every core)")
    p.add_argument("--dask", metavar="ADDRESS", default=None, help="run on a Dask scheduler")
    p.add_argument("--markdown", metavar="PATH", default="docs/atlas.md", help="report (default docs/atlas.md)")
    p.add_argument("--figure", metavar="PATH", default=None,
                   help="degree figure (default: figures/atlas_degrees.png beside the report)")
    p.add_argument("--quick", action="store_true", help="8 steps, 3 exact degrees, no measure/Poisson search; "
                   "with --systems only the folder's files")
    p.set_defaults(func=cmd_atlas)


def cmd_atlas(args):
    from pathlib import Path

    from exact_khk.cli.options import check_output
    from exact_khk.diagnostics.heights import plot_format
    from exact_khk.errors import InputError
    from exact_khk.studies.output import prepare_folder
    from exact_khk.sweep.atlas import run_atlas, write_report

    if args.markdown == "docs/atlas.md" and not Path("docs").is_dir():
        raise InputError("--markdown: the default report docs/atlas.md needs a docs/ folder in the current "
                         "directory (the repository's); pass --markdown PATH elsewhere")
    if args.markdown == "-":  # check_output takes '-' for stdout; the report is a file beside its figure
        raise InputError("--markdown: expected a file name ('-' for stdout is not supported)")
    check_output(args.markdown, "--markdown")
    figure = args.figure or str(Path(args.markdown).parent / "figures" / "atlas_degrees.png")
    # the figure, like the report, is refused before the sweeps: its format, then its folder
    # (created now; removed again if the command fails while it is empty)
    plot_format(figure, "--figure")
    prepare_folder(Path(figure).absolute().parent, "--figure")
    check_output(figure, "--figure")
    rows, timing, opts = run_atlas(args.out, args.systems, args.quick, args.workers, args.dask,
                                    echo=lambda line: print(line, file=sys.stderr))
    given = [("--systems", args.systems, None), ("--out", args.out, "atlas-results"), ("--workers", args.workers, None),
             ("--dask", args.dask, None), ("--markdown", args.markdown, "docs/atlas.md"), ("--figure", args.figure, None)]
    command = " ".join(["exact-khk atlas"] + (["--quick"] if args.quick else [])
                       + [f"{k} {v}" for k, v, default in given if v != default])
    findings = write_report(rows, timing, opts, args.markdown, figure, command, args.quick)
    print(f"atlas: {len(rows)} systems in {timing['wall']:.0f} s wall, {timing['cpu']:.0f} s CPU, {len(findings)} "
          f"findings; written to {args.markdown} "
          f"and {figure}")
    return 0
