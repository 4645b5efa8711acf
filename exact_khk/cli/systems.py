"""``exact-khk systems``: the catalogue of classic KHK systems shipped with the package."""

from __future__ import annotations

from exact_khk.cli.options import add_json_option, check_output, write_json


def register(sub):
    p = sub.add_parser("systems", help="list the catalogue of classic KHK systems (use one with --system NAME)",
                       description="List the system files shipped with exact_khk. Any of them is used by name "
                       "with --system NAME in certify, orbit and integrals; --system also takes a path to your "
                       "own system file (docs/system-files.md).")
    add_json_option(p, "the list")
    p.set_defaults(func=cmd_systems)


def cmd_systems(args):
    from exact_khk.systems.catalogue import summary

    check_output(args.json)
    rows = summary()
    if args.json is not None:
        write_json([{"name": n, "title": t, "dim": d, "known": k} for n, t, d, k in rows], args.json)
        if args.json == "-":
            return 0
    w = max((len(n) for n, *_ in rows), default=4)
    print(f"{'name':<{w}}  dim  title; what is known")
    for name, title, dim, known in rows:
        print(f"{name:<{w}}  {dim:>3}  {title}; {known}")
    print("use one with: exact-khk certify --system NAME  (or --system path/to/file.toml)")
    return 0
