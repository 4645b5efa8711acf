"""find-integrals on the Kouloukas–Quispel–Vanhaecke generalized Lotka–Volterra chain.

x_i' = x_i (Σ_{j>i} x_j − Σ_{j<i} x_j), i = 1..N (T. E. Kouloukas, G. R. W. Quispel and P. Vanhaecke,
"Liouville integrability and superintegrability of a generalized Lotka–Volterra system and its Kahan
discretization", J. Phys. A 49 (2016) 225201, arXiv:1601.06957): its Kahan map has N − 1 independent
integrals.  For each N: ``find_integrals`` at ``--degree`` (wall time, CPU time, peak resident memory of
this process), the number found and independent (exact Jacobian rank), then ``exact-khk certify`` of the
system file ``--toml`` would write (the found integrals conserved exactly along an orbit, with the
negative controls).  Prints a Markdown table; nothing is asserted.

    python scripts/bench_discovery.py [--n 4,6,10] [--degree 2]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import resource
import tempfile
import time
from pathlib import Path


def chain(N):
    from exact_khk.systems.expressions import ExpressionSystem

    vs = [f"x{i}" for i in range(1, N + 1)]
    field = []
    for i, v in enumerate(vs):
        up = " + ".join(vs[i + 1:]) or "0"
        down = " + ".join(vs[:i]) or "0"
        field.append(f"{v}*(({up}) - ({down}))")
    return ExpressionSystem.from_expressions(vs, field=field, name=f"kqv-lv-{N}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", default="4,6,10", help="chain lengths (comma-separated)")
    ap.add_argument("--degree", type=int, default=2)
    args = ap.parse_args(argv)
    from exact_khk.cli.main import main as cli
    from exact_khk.diagnostics import find_integrals
    from exact_khk.diagnostics.integrals import system_file

    print("| N | candidates | kernel | shows | extracted | independent | certify | wall s | CPU s | peak RSS MB |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for N in (int(t) for t in args.n.split(",")):
        s = chain(N)
        t0, c0 = time.perf_counter(), time.process_time()
        res = find_integrals(s, degree=args.degree, eps="1/10")
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "found.toml"
            path.write_text(system_file(s, res, "1/10"))
            with contextlib.redirect_stdout(io.StringIO()):
                rc = cli(["certify", "--system", str(path), "--quiet", "--steps", "5"])
        print(f"| {N} | {len(res.candidates)} | {res.kernel_dim} | {res.visible} | {len(res.integrals)} | "
              f"{res.independent} | {'VALID' if rc == 0 else f'exit {rc}'} | {wall:.1f} | {cpu:.1f} | {rss:.0f} |",
              flush=True)


if __name__ == "__main__":
    main()
