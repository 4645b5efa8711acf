"""``exact-khk systems``: the catalogue of classic KHK systems shipped with the package."""

from __future__ import annotations

from exact_khk.cli.options import write_json


def register(sub):
    p = sub.add_parser("systems", help="list the catalogue of classic KHK systems (use one with --system NAME)",
                       description="List the system files shipped with exact_khk. Any of them is used by name "
                       "with --system NAME in certify, orbit and integrals; --system also takes a path to your "
                       "own system file (docs/system-files.md).")
    p.add_argument("--json", action="store_true", help="print the list as JSON")
    p.set_defaults(func=cmd_systems)


def cmd_systems(args):
    from exact_khk.systems.catalogue import summary

    rows = summary()
    if args.json:
        write_json([{"name": n, "title": t, "dim": d, "known": k} for n, t, d, k in rows], "-")
        return 0
    w = max((len(n) for n, *_ in rows), default=4)
    print(f"{'name':<{w}}  dim  title; what is known")
    for name, title, dim, known in rows:
        print(f"{name:<{w}}  {dim:>3}  {title}; {known}")
    print("use one with: exact-khk certify --system NAME  (or --system path/to/file.toml)")
    return 0
