"""find-integrals on the Kouloukas–Quispel–Vanhaecke generalized Lotka–Volterra chain.

x_i' = x_i (Σ_{j>i} x_j − Σ_{j<i} x_j), i = 1..N (T. E. Kouloukas, G. R. W. Quispel and P. Vanhaecke,
"Liouville integrability and superintegrability of a generalized Lotka–Volterra system and its Kahan
discretization", J. Phys. A 49 (2016) 225201, arXiv:1601.06957): its Kahan map has N − 1 independent
integrals.  For each N: ``find_integrals`` at ``--degree`` (wall time, CPU time, peak resident memory of
this process), the number found and independent (exact Jacobian rank), then ``exact-khk certify`` of the
system file ``--toml`` would write (the found integrals conserved exactly along an orbit, with the
negative controls).  Prints a Markdown table; nothing is asserted.  With ``--log FILE`` each stage
and each fit (entry, degree, outcome, seconds, peak RSS) is appended to FILE as it happens, so a run
stopped early says how far it got.

``--kernel N,D`` instead measures one orbit kernel (:func:`orbit_kernel_mod`) of a random quadratic
field in N variables (integer coefficients in [-3, 3], seed 5) at degree <= D, as ``find-integrals``
computes it: wall, CPU, peak RSS, kernel dimension.

    python scripts/bench_discovery.py [--n 4,6,10,20] [--degree 2] [--log FILE]
    python scripts/bench_discovery.py --kernel 20,4
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


def rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def kernel(N, D):
    """One orbit kernel of a random quadratic field in N variables at degree <= D."""
    import random
    from fractions import Fraction

    from exact_khk.diagnostics.degrees import random_primes, resolve_field
    from exact_khk.diagnostics.kernels import _point, monomials, orbit_kernel_mod
    from exact_khk.systems.expressions import ExpressionSystem

    rng = random.Random(5)
    vs = [f"x{i}" for i in range(N)]
    quad = [f"{a}*{b}" for i, a in enumerate(vs) for b in vs[i:]] + vs
    field = [" + ".join(f"({rng.randint(-3, 3)})*{t}" for t in quad) for _ in vs]
    _, fld = resolve_field(ExpressionSystem.from_expressions(vs, field=field, name=f"random{N}"), "f")
    exps = monomials(N, D)
    m = len(exps)
    margin = max(8, m // 10)
    steps = m + 2 * margin
    r0 = rss_mb()
    t0, c0 = time.perf_counter(), time.process_time()
    k = orbit_kernel_mod(fld, Fraction(1, 10), _point(random.Random(1), N), exps, steps, random_primes(1, 0)[0],
                         margin, progress=lambda t: print(f"  {time.perf_counter() - t0:.0f} s: {t}", flush=True))
    print(f"| {N} | {D} | {m} | {steps + 1} | {k.dim} | {'yes' if k.stable else 'no'} | "
          f"{time.perf_counter() - t0:.0f} | {time.process_time() - c0:.0f} | {r0:.0f} | {rss_mb():.0f} |")


def logged(path):
    """A progress callback appending each stage to ``path``, and each fit (by wrapping EntryFitter.fit)."""
    from exact_khk.diagnostics import fitting

    t0 = time.perf_counter()

    def log(text):
        with open(path, "a") as fh:
            fh.write(f"{time.perf_counter() - t0:8.1f} s  CPU {time.process_time():8.1f} s  "
                     f"peak {rss_mb():6.0f} MB  {text}\n")

    fit = fitting.EntryFitter.fit

    def traced(self, key, delta, primes, J=0, variables=None):
        t = time.perf_counter()
        out = fit(self, key, delta, primes, J, variables)
        log(f"fit of entry {key} at degree {delta}, J = {J}, {len(self.known)} known, "
            f"{self.fld.dim if variables is None else len(variables)} variables: "
            f"{'found' if out is not None else 'none'} ({time.perf_counter() - t:.1f} s)")
        return out

    fitting.EntryFitter.fit = traced
    return log


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", default="4,6,10,20", help="chain lengths (comma-separated)")
    ap.add_argument("--degree", type=int, default=2)
    ap.add_argument("--log", help="append stages and fits to this file as they happen")
    ap.add_argument("--kernel", help="N,D: one orbit kernel of a random quadratic field instead")
    args = ap.parse_args(argv)
    if args.kernel:
        print("| variables | degree | candidates | points | kernel | stable | wall s | CPU s | RSS before MB | "
              "peak RSS MB |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        kernel(*(int(t) for t in args.kernel.split(",")))
        return
    from exact_khk.cli.main import main as cli
    from exact_khk.diagnostics import find_integrals
    from exact_khk.diagnostics.integrals import system_file

    log = logged(args.log) if args.log else None

    print("| N | candidates | kernel | shows | extracted | independent | certify | wall s | CPU s | peak RSS MB |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for N in (int(t) for t in args.n.split(",")):
        s = chain(N)
        t0, c0 = time.perf_counter(), time.process_time()
        if log:
            log(f"N = {N}")
        res = find_integrals(s, degree=args.degree, eps="1/10", progress=log)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        rss = rss_mb()
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
