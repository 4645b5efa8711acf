"""``exact-khk systems``: the catalogue of classic KHK systems shipped with the package."""

from __future__ import annotations

from exact_khk.cli.options import add_json_option, check_output, write_json


def register(sub):
    p = sub.add_parser("systems", help="list the catalogue of classic KHK systems (use one with --system NAME)",
                       description="List the system files shipped with exact_khk and the families of systems "
                       "with a size or a parameter (named NAME:K=V[,K=V], e.g. volterra-periodic:N=5). Any of "
                       "them is used by name with --system NAME in certify, orbit and integrals; --system also "
                       "takes a path to your own system file (docs/system-files.md). The last column is what "
                       "the literature claims about the Kahan map (docs/catalogue.md).")
    add_json_option(p, "the list")
    p.set_defaults(func=cmd_systems)


def cmd_systems(args):
    from exact_khk.systems.catalogue import family_summary, load, names

    systems = [load(n) for n in names()]
    families = family_summary()
    check_output(args.json)
    if args.json is not None:
        write_json({"systems": [{"name": s.name, "title": s.title, "dim": s.dim, "known": s.known(),
                                 "literature": s.literature} for s in systems],
                    "families": [{"family": f, "parameters": p, "description": d} for f, p, d in families]}, args.json)
        if args.json == "-":
            return 0
    w = max((len(s.name) for s in systems), default=4)
    print(f"{'name':<{w}}  dim  title; what the file declares; literature on the Kahan map")
    for s in systems:
        lit = s.literature
        claim = f"integrable: {lit.get('integrable', 'unknown')}, integrals: {lit.get('integrals', 'unknown')}"
        print(f"{s.name:<{w}}  {s.dim:>3}  {s.title}; {s.known()}; {claim}")
    print("\nfamilies (any member in range: NAME:K=V[,K=V]):")
    for f, params, desc in families:
        print(f"  {f}: {params}; {desc}")
    print("use one with: exact-khk certify --system NAME  (or --system path/to/file.toml)")
    return 0
