#!/usr/bin/env python3
"""Benchmarks of the Kahan step: dense vs structured, against reference solvers.

Measures side by side in one run and writes docs/benchmarks.md:

* exact step (Lie–Poisson field f, n = 2..8, heights 64..100 000 bits): the
  library's dense integer step, its structured and split steps, a bare python-flint
  ``fmpz_mat.solve`` on the same (pre-built) integer system, gmpy2 Bareiss,
  Fraction elimination and SymPy ``Matrix.LUsolve``;
* exact orbit steps: ``KahanMap.orbit`` per step against a bare
  ``fmpz_mat.solve`` loop over the systems of the same orbit points;
* the split step against the dense one, flint and gmpy2;
* structured against dense along an orbit at n = 32, and H̃ both ways;
* cost against n at fixed height, with the fitted log–log exponent;
* the exact orbit length reachable in a time budget for n = 2, 3, 8, 32, 256.

Only public names are used (``KahanMap``, ``Htilde``, and for n in the
thousands, where the 2n×2n field itself is too large to build, the structure
from the vectors: ``structure_from_system`` with ``exact_step``; floating steps are
measured by scripts/bench_float.py); the bare systems are built from ``KahanMap.system_matrix``
with python-flint's own ``fmpq_mat.numer_denom``.

Usage:  python3 scripts/bench.py [--budget SECONDS] [--quick] [--out PATH]
        python3 scripts/bench.py --section orbit|crossover --ns 9,10 [--heights 0,500] [--steps 1]
        (one table, printed; the file is left as it is)
No timing is asserted anywhere; this only measures.
"""

from __future__ import annotations

import argparse
import gc
import math
import os
import platform
import random
import sys
import time
from fractions import Fraction
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import flint  # noqa: E402
import gmpy2  # noqa: E402
import mpmath  # noqa: E402
import sympy  # noqa: E402

from exact_khk import Htilde, KahanMap, LiePoissonSystem, get_arith  # noqa: E402
from exact_khk.systems.lie_poisson.circulant import exact_step  # noqa: E402
from exact_khk.systems.lie_poisson.system import structure_from_system  # noqa: E402
from exact_khk.studies.output import write_atomic  # noqa: E402
from exact_khk.systems.lie_poisson.paths import AUTO_SPLIT_MAX_N, SPLIT_N  # noqa: E402
from exact_khk.systems.lie_poisson.system import random_point  # noqa: E402

EPS = Fraction(1, 10)
SLOW = 0.5  # seconds: a reference solver slower than this is not run at larger sizes


def timed(fn, min_total=0.3, max_reps=50):
    """Best time of fn() over repetitions totalling about ``min_total`` seconds."""
    t0 = time.perf_counter()
    fn()
    best = time.perf_counter() - t0
    total, reps = best, 1
    while total < min_total and reps < max_reps:
        t0 = time.perf_counter()
        fn()
        dt = time.perf_counter() - t0
        best, total, reps = min(best, dt), total + dt, reps + 1
    return best


def timed_together(fns, min_total=0.5, max_reps=30, batch=0.005):
    """Best times per call of several callables, run in interleaved rounds (so that
    load on the machine hits them alike, in rotating order) until ``min_total``
    seconds in all, and at least one round per callable.  Each
    round times a batch of calls lasting about ``batch`` seconds, so that calls of
    microseconds are not timed one by one, cold after the other callables."""
    number = {}
    gc.collect()
    gc.disable()  # as timeit does: a collection triggered by one callable's garbage must not land on another
    try:
        return _rounds(fns, number, min_total, max_reps, batch)
    finally:
        gc.enable()


def _rounds(fns, number, min_total, max_reps, batch):
    for k, fn in fns.items():
        fn()  # warm-up: the first call may build caches (e.g. the integer system)
        t0 = time.perf_counter()
        fn()
        number[k] = max(1, int(batch / max(time.perf_counter() - t0, 1e-7)))
    best = {k: math.inf for k in fns}
    total, reps = 0.0, 0
    keys = list(fns)
    while reps < len(keys) or (total < min_total and reps < max_reps):
        # the order rotates each round, so that no callable always runs after the same other
        for k in keys[reps % len(keys):] + keys[:reps % len(keys)]:
            fn = fns[k]
            t0 = time.perf_counter()
            for _ in range(number[k]):
                fn()
            dt = time.perf_counter() - t0
            best[k], total = min(best[k], dt / number[k]), total + dt
        reps += 1
    return best


def point_of_height(n, bits, rng):
    """A point x = xi/d with a common bits-bit denominator (as along orbits)."""
    d = rng.getrandbits(bits) | 1 | (1 << (bits - 1))
    return [Fraction(rng.getrandbits(bits) - (1 << (bits - 1)), d) for _ in range(2 * n)]


def fmt(t):
    if t is None:
        return "—"
    return f"{t * 1e6:.0f} µs" if t < 1e-3 else (f"{t * 1e3:.2f} ms" if t < 1 else f"{t:.2f} s")


def ratio(a, b):
    return "—" if a is None or b is None else f"{a / b:.1f}×"


def integer_system(phi, x):
    """(I − εf'(x)) z = x with one common denominator cleared, as fmpz_mats
    (built from the public ``system_matrix``, outside any timing)."""
    N = len(x)
    M = phi.system_matrix(x)
    aug = flint.fmpq_mat(N, N + 1, [t for i in range(N) for t in list(M[i]) + [x[i]]])
    num, _ = aug.numer_denom()
    rows = num.tolist()
    return flint.fmpz_mat([r[:N] for r in rows]), flint.fmpz_mat([r[N:] for r in rows])


def height(x):
    """Bits of the largest numerator or denominator (python-flint fmpq or gmpy2 mpq)."""
    return max(max(int(t.numerator).bit_length(), int(t.denominator).bit_length()) for t in x)


def exact_table(ns, heights, log):
    rows, skip = [], {}
    for n in ns:
        fld = LiePoissonSystem.random(n, seed=1).field("f")
        for bits in heights:
            if n * bits > 4 * 10 ** 5:  # n = 8 at 100 000 bits: minutes per solver
                continue
            x = point_of_height(n, bits, random.Random(bits * 100 + n))
            maps = {m: KahanMap(fld, EPS, "flint", method=m) for m in ("auto", "dense", "structured", "split")
                    if m != "split" or n in SPLIT_N}
            xp = maps["dense"].point(x)
            Mz, Bz = integer_system(maps["dense"], xp)
            gm = KahanMap(fld, EPS, "gmpy2", method="dense")
            xg = gm.point(x)
            fns = {m: (lambda p=p: p.step(xp)) for m, p in maps.items()}
            fns.update(bare=lambda: Mz.solve(Bz), gmpy2=lambda: gm.step(xg))
            r = timed_together(fns, min_total=1.0)
            fr = KahanMap(fld, EPS, "fraction")
            if not skip.get(("fraction", n)):
                r["fraction"] = timed(lambda: fr.step(x), min_total=0)
                skip[("fraction", n)] = r["fraction"] > SLOW
            if not skip.get(("sympy", n)):
                Ms = sympy.Matrix(fr.system_matrix(x)).applyfunc(sympy.Rational)
                bs = sympy.Matrix([sympy.Rational(t) for t in x])
                r["sympy"] = timed(lambda: Ms.LUsolve(bs), min_total=0)
                skip[("sympy", n)] = r["sympy"] > SLOW
            r["n"], r["bits"] = n, bits
            rows.append(r)
            log(f"exact n={n} bits={bits}: " + ", ".join(f"{k}={fmt(v)}" for k, v in r.items()
                                                          if isinstance(v, float)))
    return rows


def advance(phi, x, bits):
    """Follow the orbit of x until its height reaches ``bits``."""
    while height(x) < bits:
        x = phi.step(x)
    return x


def orbit_timing(auto, dense, x, steps, **timing):
    """Per-step times of ``steps`` steps of ``auto.orbit`` and ``dense.orbit`` from x
    (checked equal) and of a bare ``fmpz_mat.solve`` loop over the systems of the
    same orbit points, timed together (``timing``: options of :func:`timed_together`)."""
    pts = dense.orbit(x, steps)
    assert auto.orbit(x, steps) == pts
    systems = [integer_system(dense, p) for p in pts[:-1]]

    def bare():
        for A, B in systems:
            A.solve(B)

    best = timed_together({"auto": lambda: auto.orbit(x, steps), "dense": lambda: dense.orbit(x, steps),
                           "bare": bare}, **timing)
    return {k: t / steps for k, t in best.items()}


def orbit_steps(ns, heights, log, steps=16):
    """Per-step cost of ``KahanMap.orbit`` (auto and dense) over ``steps`` steps
    against a bare ``fmpz_mat.solve`` loop over the systems of the same orbit points."""
    rows = []
    for n in ns:
        fld = LiePoissonSystem.random(n, seed=1).field("f")
        auto, dense = (KahanMap(fld, EPS, "flint", method=m) for m in ("auto", "dense"))
        x = auto.point(random_point(n, 1))
        for bits in heights:
            x = advance(auto, x, bits)
            r = {"n": n, "bits": height(x), "steps": steps, "path": auto.path}
            r.update(orbit_timing(auto, dense, x, steps, min_total=1.0, max_reps=20))
            rows.append(r)
            log(f"orbit steps n={n} from {r['bits']} bits: auto={fmt(r['auto'])} "
                f"dense={fmt(r['dense'])} bare={fmt(r['bare'])}")
    return rows


def crossover(ns, heights, log, steps=4):
    """dense / structured and split / structured time of ``steps`` orbit steps from
    points of one exact orbit, by height: where ``method='auto'`` should switch to the
    structured step (the rules in :mod:`exact_khk.kahan.map` and :mod:`exact_khk.systems.lie_poisson.split`)."""
    rows = []
    for n in ns:
        fld = LiePoissonSystem.random(n, seed=1).field("f")
        maps = {m: KahanMap(fld, EPS, "flint", method=m) for m in ("structured", "dense", "split")}
        x, cells = maps["dense"].point(random_point(n, 1)), []
        for target in heights:
            x = advance(maps["structured"], x, target)
            r = timed_together({m: (lambda p=p: p.orbit(x, steps)) for m, p in maps.items()}, min_total=0.3)
            cells.append((target, height(x), r["dense"] / r["structured"], r["split"] / r["structured"]))
        rows.append((n, cells))
        log(f"crossover n={n}: " + ", ".join(f"{h} bits {a:.2f}/{b:.2f}" for _, h, a, b in cells))
    return rows


def split_crossover(cases, orbit_heights, random_heights, log):
    """dense / split time by height, for 8 steps along the orbit of ``random_point(n, 1)``
    and for one step at random points, for the (arith, ns) in ``cases`` (``method='auto'``
    splits at these n from the start)."""
    rows = []
    for arith, ns in cases:
        for n in ns:
            fld = LiePoissonSystem.random(n, seed=1).field("f")
            sp, de = (KahanMap(fld, EPS, arith, method=m) for m in ("split", "dense"))
            x, orbit = sp.point(random_point(n, 1)), []
            for target in orbit_heights:
                while height(x) < target:
                    x = sp.step(x)
                r = timed_together({"split": lambda: sp.orbit(x, 8), "dense": lambda: de.orbit(x, 8)},
                                   min_total=0.3)
                orbit.append((height(x), r["dense"] / r["split"]))
            rand = []
            for bits in random_heights:
                xr = sp.point(point_of_height(n, bits, random.Random(bits * 100 + n)))
                r = timed_together({"split": lambda: sp.step(xr), "dense": lambda: de.step(xr)}, min_total=0.3)
                rand.append((bits, r["dense"] / r["split"]))
            rows.append((arith, n, orbit, rand))
            log(f"split crossover {arith} n={n}: orbit " + ", ".join(f"{h}b {q:.2f}" for h, q in orbit)
                + "; random " + ", ".join(f"{h}b {q:.2f}" for h, q in rand))
    return rows


def structured_along_orbit(n, stops, log):
    """One step of each method at points of one exact orbit (structured vs dense)."""
    fld = LiePoissonSystem.random(n, seed=1).field("f")
    st, de = (KahanMap(fld, EPS, "flint", method=m) for m in ("structured", "dense"))
    x, done, rows = st.point(random_point(n, 1)), 0, []
    for k in stops:
        for _ in range(k - done):
            x = st.step(x)
        done = k
        t_st = timed(lambda: st.step(x), min_total=0, max_reps=3)
        t0 = time.perf_counter()
        y = de.step(x)
        t_de = time.perf_counter() - t0
        assert y == st.step(x)
        rows.append((n, k, height(x), t_st, t_de))
        log(f"n={n} step {k} ({height(x)} bits): structured {fmt(t_st)}, dense {fmt(t_de)}")
    return rows


def htilde_table(cases, log):
    """H̃ at orbit points: the dense 2n×2n solve against the 2×2-over-circulants one."""
    rows = []
    for n, k in cases:
        fld = LiePoissonSystem.random(n, seed=1).field("f")
        phi = KahanMap(fld, EPS, "flint")
        x = phi.orbit(random_point(n, 1), k)[-1]
        t_st = timed(lambda: Htilde(fld, x, phi.eps, phi.arith), min_total=0.2, max_reps=5)
        t0 = time.perf_counter()
        value = Htilde(fld, x, phi.eps, phi.arith, method="dense")
        t_de = time.perf_counter() - t0
        assert value == Htilde(fld, x, phi.eps, phi.arith)
        rows.append((n, k, height(x), t_st, t_de))
        log(f"H~ n={n} after {k} steps: structured {fmt(t_st)}, dense {fmt(t_de)}")
    return rows


def fit_exponent(pts):
    """Least-squares slope of log t against log n."""
    xs, ys = [math.log(n) for n, _ in pts], [math.log(t) for _, t in pts]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((a - mx) * (b - my) for a, b in zip(xs, ys)) / sum((a - mx) ** 2 for a in xs)


def scaling(ns_struct, ns_dense, bits, log):
    out = {"structured": [], "dense": []}
    for n in ns_struct:
        st = structure_from_system(LiePoissonSystem.random(n, seed=1), "f")
        ar = get_arith("flint")
        x = [ar(t) for t in point_of_height(n, bits, random.Random(n))]
        out["structured"].append((n, timed(lambda: exact_step(st, x, ar(EPS), ar), max_reps=10)))
        log(f"scaling structured n={n}: {fmt(out['structured'][-1][1])}")
    for n in ns_dense:
        phi = KahanMap(LiePoissonSystem.random(n, seed=1).field("f"), EPS, "flint", method="dense")
        x = phi.point(point_of_height(n, bits, random.Random(n)))
        out["dense"].append((n, timed(lambda: phi.step(x), max_reps=10)))
        log(f"scaling dense n={n}: {fmt(out['dense'][-1][1])}")
    return out


def orbit_reach(ns, budget, log):
    rows = []
    for n in ns:
        fld = LiePoissonSystem.random(n, seed=1).field("f")
        for method in ("auto", "dense") if n <= 32 else ("auto",):  # dense n = 256: minutes per step
            phi = KahanMap(fld, EPS, "flint", method=method)
            if method == "dense" and rows and rows[-1][:1] == (n,) and rows[-1][2] == "dense":
                rows.append((n, method, rows[-1][2], rows[-1][3], rows[-1][4]))
                continue
            x = phi.point(random_point(n, 1))
            steps, t0 = 0, time.perf_counter()
            while time.perf_counter() - t0 < budget:
                x = phi.step(x)
                steps += 1
            rows.append((n, method, phi.path, steps, height(x)))
            log(f"orbit n={n} {method}: {steps} steps in {budget} s, final height {rows[-1][4]} bits")
    return rows


def machine():
    return {
        "cores": os.cpu_count(), "platform": platform.platform(), "cpu": platform.processor() or "?",
        "python": platform.python_version(), "python-flint": flint.__version__,
        "gmpy2": gmpy2.version(), "mpmath": mpmath.__version__, "sympy": sympy.__version__,
    }


#: docs/benchmarks.md: what follows this line comes from scripts/bench_float.py, bench_startup.py,
#: bench_exact.py, bench_certify.py and bench_compare.py, and is kept when this script rewrites the rest
MARKER = "<!-- The sections below are written by the other scripts/bench_*.py; bench.py keeps them. -->"
#: docs/benchmarks.md: what precedes this line (the title, the headline table, the method) is
#: written by hand, and kept when this script writes the tables between it and MARKER
BEGIN = "<!-- From here to the next marker, the tables are written by scripts/bench.py. -->"


def orbit_table(orbit):
    """The rows of :func:`orbit_steps` as a markdown table (no header), and the note of steps
    more than 1.3× the bare solve."""
    L = [f"| {r['n']} | {r['bits']} | {r['steps']} | {r['path']} | {fmt(r['auto'])} | {fmt(r['dense'])} | "
         f"{fmt(r['bare'])} | {ratio(r['auto'], r['bare'])} | {ratio(r['dense'], r['bare'])} |" for r in orbit]
    over = [f"n = {r['n']} from {r['bits']} bits ({ratio(r['auto'], r['bare'])})" for r in orbit
            if r["auto"] > 1.3 * r["bare"]]
    return L + ["", "Orbit steps (auto) more than 1.3× the bare solve: " + ("; ".join(over) if over else "none") + "."]


def crossover_table(rows):
    """The rows of :func:`crossover` as a markdown table with its header."""
    return (["| n | " + " | ".join(f"from ≥ {t} bits" for t, *_ in rows[0][1]) + " |",
             "|---|" + "---|" * len(rows[0][1])]
            + [f"| {n} | " + " | ".join(f"{a:.2f} / {b:.2f} ({h} bits)" for _, h, a, b in cells) + " |"
               for n, cells in rows])


ORBIT_HEADER = ["| n | start height (bits) | steps | auto path | auto | dense | bare | auto / bare | dense / bare |",
                "|---|---|---|---|---|---|---|---|---|"]


def write(path, info, args, res, elapsed):
    exact, orbit, along, htil = res["exact"], res["orbit"], res["along"], res["htilde"]
    scal, reach = res["scaling"], res["reach"]
    L = [BEGIN, "",
         f"Generated by `python3 scripts/bench.py{' --quick' if args.quick else ''} --budget {args.budget:g}` "
         f"in {elapsed:.0f} s. Times are the best of repeated runs on a shared machine "
         "(two runs of this script differed by up to 50 % in single timings); ratios are measured side by side "
         "in the same run, and in the two exact-step tables the compared methods run in interleaved rounds.", "",
         "Machine: " + ", ".join(f"{k} {v}" for k, v in info.items()) + ".", "",
         "System: `LiePoissonSystem.random(n, seed=1)`, field f, ε = 1/10. Height h: the point is "
         "xi/d with h-bit integers xi and a common h-bit denominator d (orbit points share one). "
         "\"bare\" is python-flint `fmpz_mat.solve` alone on the already-built integer system "
         "(I − εf'(x)) z = x of the same point, denominators cleared; the library also builds that "
         "system and converts the point.", "",
         "### Exact orbit steps (python-flint)", "",
         "`KahanMap.orbit` from a point of the orbit of `random_point(n, 1)` with the given height, "
         "per step, against a bare `fmpz_mat.solve` loop over the systems of the same orbit points.", "",
         *ORBIT_HEADER]
    L += orbit_table(orbit)
    L += ["", "### Exact step at random points (python-flint unless stated)", "",
          "| n | h (bits) | library auto | dense (fmpz_mat) | structured | split | bare `fmpz_mat.solve` "
          "| auto / bare | gmpy2 Bareiss | Fraction elim. | SymPy LUsolve | Fraction / dense | SymPy / dense "
          "| dense / structured |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in exact:
        L.append(f"| {r['n']} | {r['bits']} | {fmt(r['auto'])} | {fmt(r['dense'])} | {fmt(r['structured'])} | "
                 f"{fmt(r.get('split'))} | {fmt(r['bare'])} | {ratio(r['auto'], r['bare'])} | {fmt(r['gmpy2'])} | "
                 f"{fmt(r.get('fraction'))} | {fmt(r.get('sympy'))} | {ratio(r.get('fraction'), r['dense'])} | "
                 f"{ratio(r.get('sympy'), r['dense'])} | {ratio(r['dense'], r['structured'])} |")
    over = [f"n = {r['n']}, {r['bits']} bits ({ratio(r['auto'], r['bare'])})" for r in exact
            if r["auto"] > 1.3 * r["bare"]]
    L += ["", "Library steps (auto) more than 1.3× the bare solve: " + ("; ".join(over) if over else "none") + "."]
    L += ["", "\"library auto\" is the method `KahanMap` picks (exact flint steps are split for "
          f"n ≤ {AUTO_SPLIT_MAX_N} and structured for every larger n). \"split\": one 2×2 system per cyclotomic factor "
          "of tⁿ − 1. Random points of height h have no special structure, so "
          "the exact solution is as large as Cramer's rule allows (about 2n·h bits). "
          "\"—\": not run (a smaller case already took more than "
          f"{SLOW:g} s).", "",
          "### The split step against the dense one", "",
          "dense / split time (above 1: split faster) for 8 steps of `KahanMap.orbit` from points of the orbit "
          "of `random_point(n, 1)` (by the start point's height), and for one step at random points of height h "
          "(answers of Cramer size). `auto` takes the split step from the start at "
          f"n ≤ {AUTO_SPLIT_MAX_N}, with flint and gmpy2 (whose dense step is Bareiss elimination).", "",
          "| arith | n | along the orbit | random points |", "|---|---|---|---|"]
    L += [f"| {a} | {n} | " + ", ".join(f"{h} bits: {q:.2f}" for h, q in orbit) + " | "
          + ", ".join(f"{h} bits: {q:.2f}" for h, q in rand) + " |" for a, n, orbit, rand in res["split"]]
    L += ["", "### Where the structured step overtakes the dense and the split one (exact orbits)", "",
          "dense / structured and split / structured time (above 1: structured faster) of 4 steps of "
          "`KahanMap.orbit` from points of the orbit of `random_point(n, 1)`, by the start point's height, "
          "for n = 7..15 except 8 (`auto` takes the structured step there from the first point). "
          "The dense map solves output-sensitively "
          "once its answers are known to be small; the timed calls repeat one orbit, so after the warm-up "
          "call it does so from the first step.", "",
          *crossover_table(res["crossover"])]
    L += ["", "### Structured against dense along one exact orbit", "",
          "| n | step | height (bits) | structured | dense | dense / structured |", "|---|---|---|---|---|---|"]
    L += [f"| {n} | {k} | {h} | {fmt(a)} | {fmt(b)} | {ratio(b, a)} |" for n, k, h, a, b in along]
    L += ["", "### H̃ at orbit points (exact, python-flint)", "",
          "| n | after steps | height (bits) | structured (auto) | dense | dense / structured |",
          "|---|---|---|---|---|---|"]
    L += [f"| {n} | {k} | {h} | {fmt(a)} | {fmt(b)} | {ratio(b, a)} |" for n, k, h, a, b in htil]
    L += ["", f"### Cost against n at fixed height ({args.scale_bits}-bit random point)", "",
          "| n | " + " | ".join(str(n) for n, _ in scal["structured"]) + " |",
          "|---|" + "---|" * len(scal["structured"]),
          "| structured | " + " | ".join(fmt(t) for _, t in scal["structured"]) + " |",
          "| dense | " + " | ".join(fmt(dict(scal["dense"]).get(n)) for n, _ in scal["structured"]) + " |", ""]
    for k in ("structured", "dense"):
        pts = [(n, t) for n, t in scal[k] if n >= 8]
        if len(pts) >= 2:
            L.append(f"- {k}: fitted log–log exponent {fit_exponent(pts):.2f} (n ≥ 8)")
    L += ["", "The answer itself has 2n coordinates of about 2n·h bits (Cramer), so n² is the size of "
          "the output: an exponent near 2 means a step costs about as much as its output is large "
          "(the dense one is fitted on n = 8..32 only).", "",
          f"### Exact orbit length reachable in {args.budget:g} s (python-flint)", "",
          "| n | method | path | steps | final height (bits) |", "|---|---|---|---|---|"]
    L += [f"| {n} | {m} | {p} | {s} | {h} |" for n, m, p, s, h in reach]
    L += ["", f"Budget per run: {args.budget:g} s (`--budget`); start point `random_point(n, 1)`.", ""]
    # the sections after the marker are written by the other benchmark scripts: keep them
    old = Path(path).read_text() if Path(path).exists() else ""
    head = old[:old.index(BEGIN)] if BEGIN in old else "# Benchmarks\n\n## Exact steps (python-flint)\n\n"
    tail = old[old.index(MARKER):] if MARKER in old else MARKER + "\n"
    write_atomic(path, head + "\n".join(L) + "\n" + tail)


def print_section(ap, args):
    """``--section``: one table for the given n and heights, printed."""
    if not args.ns or min(args.ns) < 2:
        ap.error("--section needs --ns, integers >= 2")
    log = lambda s: print(s, file=sys.stderr, flush=True)  # noqa: E731
    if args.section == "orbit":
        heights = args.heights or (0, 64, 1000)
        if args.steps < 1:
            ap.error("--steps must be at least 1")
        lines = ORBIT_HEADER + orbit_table(orbit_steps(args.ns, heights, log, args.steps))
    else:
        heights = args.heights or (0, 250, 500, 1000, 1500, 2000, 3000, 4500, 6000)
        lines = crossover_table(crossover(args.ns, heights, log))
    print("\n".join(lines))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--budget", type=float, default=10.0, help="seconds per orbit-length run (default 10)")
    ap.add_argument("--quick", action="store_true", help="fewer sizes and heights")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent.parent / "docs" / "benchmarks.md"))
    ap.add_argument("--section", choices=("orbit", "crossover"),
                    help="run only this table for --ns and print it; docs/benchmarks.md is left as it is")
    ap.add_argument("--ns", type=lambda s: [int(t) for t in s.split(",")], help="n of --section (comma-separated)")
    ap.add_argument("--heights", type=lambda s: [int(t) for t in s.split(",")],
                    help="start heights in bits of --section (comma-separated)")
    ap.add_argument("--steps", type=int, default=16, help="steps per timing of --section orbit (default 16)")
    args = ap.parse_args(argv)
    if args.section:
        return print_section(ap, args)
    args.scale_bits = 64
    log = lambda s: print(s, flush=True)  # noqa: E731
    t0 = time.perf_counter()
    quick = args.quick
    res = {
        "orbit": orbit_steps((2, 3, 4, 8) if quick else range(2, 9), (0, 64, 1000) if quick else (0, 64, 1000, 10000),
                             log),
        "exact": exact_table((2, 3, 4, 8) if quick else range(2, 9),
                             (64, 10000) if quick else (64, 1000, 10000, 100000), log),
        "split": split_crossover((("flint", (2, 3, 9)), ("gmpy2", (2, 11))) if quick else
                                 (("flint", (2, 3, 4, 5, 6, 8, 9, 10, 12)), ("gmpy2", (2, 3, 4, 5, 6, 7, 8, 11, 15))),
                                 (0, 50, 100, 200, 400),
                                 (16, 64, 128, 256, 512), log),
        "crossover": crossover((7, 11) if quick else (7, 9, 10, 11, 12, 13, 14, 15),
                               (0, 250, 500, 1000, 1500, 2000, 3000, 4500, 6000),
                               log),
        "along": structured_along_orbit(32, (0, 24) if quick else (0, 24, 50), log),
        "htilde": htilde_table(((3, 50), (8, 20)) if quick else ((3, 50), (8, 20), (16, 10)), log),
        "scaling": scaling((4, 8, 16, 32, 64, 128) if quick else (4, 8, 16, 32, 64, 128, 256),
                           (4, 8, 16) if quick else (4, 8, 16, 32), args.scale_bits, log),
        "reach": orbit_reach((2, 3, 8, 32) if quick else (2, 3, 8, 32, 256), args.budget, log),
    }
    write(args.out, machine(), args, res, time.perf_counter() - t0)
    log(f"wrote {args.out}")


if __name__ == "__main__":
    main()
