"""The integrability atlas: classify every catalogue system and every system file of a folder
as two sweeps (each system's default eps, and the fixed second eps :data:`SECOND_EPS`), then
write a Markdown report and a figure of all degree sequences (docs/atlas.md).

Timings are kept out of the table: they sit in the "Times" section only, so that a
regenerated report can be compared with the committed one with that section masked
(:func:`mask_times`).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from exact_khk.errors import InputError

#: the second step size of every system: a fixed rational, never tuned to agree with anything
SECOND_EPS = "2/21"
#: options of the full and the quick atlas (stated in the report)
FULL = {"steps": 20, "exact": 6, "no_discover": False}
QUICK = {"steps": 8, "exact": 3, "no_discover": True}
TIMES_HEADING = "## Times"
TIME_PREFIX = "Time of this run:"


def _toml_list(items) -> str:
    return "[" + ", ".join(json.dumps(str(i)) for i in items) + "]"


def atlas_specs(systems_dir=None, quick=False):
    """The two sweep specs (default eps, second eps) over the catalogue and the folder's files."""
    from exact_khk.sweep.spec import parse_spec
    from exact_khk.systems.catalogue import names

    files = []
    if systems_dir is not None:
        d = Path(systems_dir)
        if not d.is_dir():
            raise InputError(f"--systems: {systems_dir!r} is not a folder")
        files = sorted(str(p.resolve()) for p in d.iterdir() if p.suffix == ".toml")
        if not files:
            raise InputError(f"--systems: no system file (*.toml) in {systems_dir!r}")
    cat = [] if systems_dir is not None and quick else names()
    opts = QUICK if quick else FULL
    specs = []
    for tag, eps in (("default-eps", None), ("second-eps", SECOND_EPS)):
        parts = []
        for kind, items in (("catalogue", cat), ("file", files)):
            if not items:
                continue
            text = (f'name = "atlas-{tag}-{kind}"\ntask = "classify"\n[system]\n{kind} = {_toml_list(items)}\n'
                    f"[grid]\nsteps = {opts['steps']}\n" + (f'eps = ["{eps}"]\n' if eps else "")
                    + f"[options]\nexact = {opts['exact']}\nno_discover = {str(opts['no_discover']).lower()}\n")
            parts.append((f"{tag}-{kind}", parse_spec(text, origin=f"atlas ({tag}, {kind})")))
        specs += parts
    _distinct_names(files, cat)
    return specs, opts


def _distinct_names(files, catalogue):
    """InputError when two system files, or a file and a catalogue entry, share a name: the report
    has one row per name, and one of them would be dropped without a word."""
    from exact_khk.systems.catalogue import resolve

    seen = {name: f"the catalogue entry {name!r}" for name in catalogue}
    for path in files:
        name = resolve(path).name
        if name in seen:
            raise InputError(f"--systems: {path!r} names its system {name!r}, as does {seen[name]}: the atlas has "
                             "one row per name (give the files distinct names)")
        seen[name] = repr(path)


def run_atlas(out_dir, systems_dir=None, quick=False, workers=None, dask=None, echo=None):
    """Run (or resume) the atlas sweeps into ``out_dir``; returns (rows, timing, options): timing holds the
    wall and CPU seconds of this run (CPU of this process plus the cpu_seconds of every task it computed; a
    resumed run counts only what it computed) and the load average (1, 5, 15 min) before and after."""
    from exact_khk.sweep.run import ResultStore, run_sweep

    import os
    import resource

    specs, opts = atlas_specs(systems_dir, quick)
    t0 = time.perf_counter()
    load0 = os.getloadavg()
    cpu0 = resource.getrusage(resource.RUSAGE_SELF).ru_utime + resource.getrusage(resource.RUSAGE_SELF).ru_stime
    rows: dict = {}
    task_cpu = 0.0
    for tag, spec in specs:
        sub = Path(out_dir) / tag
        before = set(ResultStore(sub).latest()) if sub.exists() else set()
        run_sweep(spec, sub, workers=workers, dask=dask, plots=False, echo=echo)
        keys = {t.key for t in spec.tasks()}
        for key, rec in ResultStore(sub).latest().items():
            if key not in before:  # computed by this run: its worker's CPU time
                task_cpu += float(rec.get("cpu_seconds") or 0.0)
            if key not in keys:
                continue
            name = rec["params"]["system"].get("name") or rec["params"]["system"].get("file") or key
            rows.setdefault(name, {})["default" if tag.startswith("default") else "second"] = rec
    # the workers are not this process's children (forkserver): their CPU is the tasks' own cpu_seconds
    cpu = resource.getrusage(resource.RUSAGE_SELF).ru_utime + resource.getrusage(resource.RUSAGE_SELF).ru_stime \
        - cpu0 + task_cpu
    return rows, _add_timing(out_dir, time.perf_counter() - t0, cpu, load0, os.getloadavg()), opts


def _add_timing(out_dir, wall, cpu, load0, load1) -> dict:
    """The time of every run into ``out_dir`` so far (a resumed run adds only what it computed):
    kept in ``out_dir``/timing.json, so a report written from resumed results states the whole cost."""
    import os

    from exact_khk.studies.output import write_atomic

    path = Path(out_dir) / "timing.json"
    old = json.loads(path.read_text()) if path.exists() else None
    t = {"wall": wall, "cpu": cpu, "load_before": list(load0), "load_after": list(load1), "cores": os.cpu_count(),
         "runs": 1}
    if old:
        t.update(wall=old["wall"] + wall, cpu=old["cpu"] + cpu, load_before=old["load_before"], runs=old["runs"] + 1)
    write_atomic(path, json.dumps(t).encode(), "--out")
    return t


def _cls(rec):
    if rec is None:
        return None
    f = rec.get("figures") or {}
    return json.loads(f["json"]) if f.get("json") else None


def _summary(c) -> str:
    if c is None:
        return "no result"
    seq = c["degrees"]["sequence"][:8]
    dd = c["dynamical_degree"]
    lam = ""
    if dd.get("fitted"):
        lam = f"; λ fitted (conjecture) {dd['fitted'].get('enclosure', dd['fitted'].get('value'))}"
    if dd.get("upper_bound"):
        lam += f"; λ ≤ {dd['upper_bound']['bound']} (proven)"
    ints = c["integrals"]
    n_int = ints.get("independent", "not run") if isinstance(ints, dict) else "?"
    found = {k: ("yes" if isinstance(c[k], dict) and c[k].get("status") == "found" else
                 "not run" if isinstance(c[k], dict) and c[k].get("status") == "not run" else "no")
             for k in ("measure", "poisson")}
    return (f"degrees {', '.join(map(str, seq))}…; growth {c['growth']['class']}{lam}; "
            f"integrals {n_int}/{c['dim']}; measure {found['measure']}; Poisson {found['poisson']}")


def _literature(name):
    from exact_khk.systems.catalogue import load

    try:
        lit = getattr(load(name), "literature", None) or {}
    except Exception:  # a system file, not a catalogue name
        return "unknown", "—"
    return str(lit.get("integrable", "unknown")), str(lit.get("reference", "—"))


def timing_line(timing) -> str:
    """The report's one timing line (written by the command, masked when a regenerated report is compared)."""
    la, lb = timing["load_before"], timing["load_after"]
    runs = timing.get("runs", 1)
    return (f"{TIME_PREFIX} {timing['wall']:.0f} s wall, {timing['cpu']:.0f} s CPU (the command and the CPU time "
            f"of its tasks{f', summed over {runs} resumed runs' if runs > 1 else ''}) on {timing['cores']} cores; "
            "load average (1, 5, 15 min) before "
            f"{la[0]:.2f}, {la[1]:.2f}, {la[2]:.2f}, after {lb[0]:.2f}, {lb[1]:.2f}, {lb[2]:.2f} "
            "(the machine is shared: other work inflates the wall time).")


def _literature_notes(name) -> str:
    from exact_khk.systems.catalogue import load

    try:
        return str((getattr(load(name), "literature", None) or {}).get("notes", ""))
    except Exception:  # a system file, not a catalogue name
        return ""


def write_report(rows, timing, opts, markdown, figure, command, quick=False):
    """Write the Markdown report and the degree figure; returns the findings (list of strings)."""
    from exact_khk.diagnostics.classify import RULES
    from exact_khk.systems.catalogue.families import FAMILIES
    from exact_khk.studies.output import write_atomic

    fams = "; ".join(f"{f} at " + ", ".join("(" + ", ".join(f"{k}={v}" for k, v in p.items()) + ")" for p in m)
                     for f, (_, _, m, _) in FAMILIES.items())
    lines = ["# Integrability atlas", "",
             f"Generated by `{command}` (do not edit by hand). Each system is classified at its default ε and "
             f"at the fixed second ε = {SECOND_EPS}; options: steps {opts['steps']}, exact degrees over Q for the "
             f"first {opts['exact']} iterates, integral search at classify's default degree, measure/Poisson "
             f"searches {'skipped' if opts['no_discover'] else 'run'}. Every parameterized family is classified "
             f"at more than one parameter point, one row each (fixed before any run, never tuned): {fams}.", "",
             timing_line(timing), "",
             "![degree sequences](figures/atlas_degrees.png)", "", "## Verdicts", "",
             "| system | dim | literature (reference) | verdict (default ε) | verdict (ε = " + SECOND_EPS
             + ") | evidence (default ε) |", "|---|---|---|---|---|---|"]
    findings, times, curves = [], [], []
    for name in sorted(rows):
        a, b = _cls(rows[name].get("default")), _cls(rows[name].get("second"))
        lit, ref = _literature(name)
        va = a["verdict"] if a else rows[name].get("default", {}).get("verdict", "missing")
        vb = b["verdict"] if b else rows[name].get("second", {}).get("verdict", "missing")
        dim = a["dim"] if a else "?"
        errors = [r.get("error") for r in (rows[name].get("default"), rows[name].get("second")) if r and r.get("error")]
        evidence = _summary(a) if a or not errors else f"no result: {errors[0]}".replace("|", "/")
        lines.append(f"| {name} | {dim} | {lit} ({ref}) | {va} (ε = {a['eps'] if a else '?'}) | {vb} | "
                     f"{evidence} |")
        if errors:  # a task that failed says nothing about integrability: its error is the finding
            findings.append(f"- **{name}**: not classified: {errors[0]}")
        elif a and b and va != vb:
            findings.append(f"- **{name}**: the verdict differs between ε = {a['eps'] if a else '?'} ({va}) and "
                            f"ε = {SECOND_EPS} ({vb}).")
        expect = {"yes": "integrable", "no": "non-integrable"}.get(lit)
        notes = _literature_notes(name)
        both = f"{va} (default ε), {vb} (ε = {SECOND_EPS}): {_summary(a)}."
        if errors:
            pass  # its finding is the error, above
        elif expect and (va != expect or vb != expect):
            findings.append(f"- **{name}**: literature says {lit} ({ref}); the tool says {both}"
                            + (f" Literature notes: {notes}" if notes else ""))
        elif not expect and (va != "undetermined" or vb not in ("undetermined", "missing")):
            findings.append(f"- **{name}**: literature {lit}; the tool goes beyond it: {both}"
                            + (f" Literature notes: {notes}" if notes else ""))
        if a:
            curves.append((name, va, a["degrees"]["sequence"]))
            times.append(f"| {name} | {a.get('seconds', 0):.1f} | {(b or {}).get('seconds', 0):.1f} |")
    lines += ["", "## Rules", ""] + [f"- **{k}**: {v}" for k, v in RULES.items()] + [
        "", "Proven: degrees over F_p on a line are lower bounds of the degrees d_k; exact degrees over Q give "
        "the upper bound λ ≤ d_k^(1/k). Conjecture: λ from a fitted recurrence (confirmed on further terms, "
        "not proven); in dimension ≥ 3 a dynamical degree need not satisfy any recurrence.",
        "", "## Findings", ""] + (findings or ["- none: every verdict agrees with the literature where it "
                                               "states one, at both step sizes."])
    lines += ["", TIMES_HEADING, "", timing_line(timing), "",
              "| system | seconds (default ε) | seconds (second ε) |", "|---|---|---|"] + times
    write_atomic(markdown, ("\n".join(lines) + "\n").encode(), "--markdown")
    _figure(curves, figure)
    return findings


def _figure(curves, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from exact_khk.diagnostics.heights import plot_format
    from exact_khk.studies.output import write_atomic

    colours = {"integrable": "tab:blue", "non-integrable": "tab:red", "undetermined": "tab:gray"}
    fig, ax = plt.subplots(figsize=(9, 6), dpi=110)
    seen = set()
    for name, verdict, seq in curves:
        ax.semilogy(range(len(seq)), [max(d, 1) for d in seq], "-o", ms=3, lw=1, alpha=0.8,
                    color=colours.get(verdict, "black"), label=None if verdict in seen else verdict)
        seen.add(verdict)
    ax.set_xlabel("iterate k")
    ax.set_ylabel("degree d_k (log scale)")
    ax.set_title("Degree sequences of the Kahan maps of the atlas (colour: verdict)")
    if curves:  # no curve (every system failed): no legend to draw
        ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, lambda fh: fig.savefig(fh, format=plot_format(path, "--figure")), "--figure")
    plt.close(fig)


def mask_times(text: str) -> str:
    """The report without its timing line and "Times" section (for comparing a regenerated report)."""
    return "\n".join(line for line in text.split(TIMES_HEADING)[0].split("\n") if not line.startswith(TIME_PREFIX))
