"""The summary of a sweep: counts by verdict, tables along the sweep's axes, the
slowest and the failed tasks, and plots.

The *axes* of a task are the parameters that vary across the sweep (``n``,
``seed``, ``point``, ``eps``, ``arith``, ``steps``, ``system``).  For every
axis with at most :data:`MAX_LEVELS` values the summary has a table: tasks,
verdict counts, time per task and the mean of every numeric figure; for the
first two axes (``seed`` and ``point`` are replicates, never the second) a
grid of the share of tasks with the task's success verdict (e.g. VALID)
against both — e.g. verdict against n and ε.

Files written to DIR (:func:`write_summary`): ``summary.txt`` (what is
printed), ``summary.json``, ``tasks.csv`` (one row per task: axes, verdict,
time, every scalar figure — named ``figure:NAME`` where NAME is also a column
of the axes) and, with matplotlib, ``verdicts.png`` (verdict
counts against the first axis, one panel per value of the second),
``time.png`` (time per task against the first axis) and ``figures.png``
(mean of each main figure that varies against the first axis; the constant ones are named
in its title).
"""

from __future__ import annotations

import csv
import io
import json
import math
import statistics
from collections import Counter
from dataclasses import dataclass, field, fields
from fractions import Fraction
from pathlib import Path

from exact_khk.studies.output import write_atomic
from exact_khk.sweep.tasks import FAILED, TASKS, VERDICTS

#: order in which axes are chosen for tables and plots
AXIS_ORDER = ("n", "system", "eps", "steps", "arith", "seed", "point")
#: axes that are replicates (never the second axis of a grid or plot)
REPLICATES = ("seed", "point")
#: axes whose values are ordered quantities: their figures are drawn as lines (on the
#: others — systems, arithmetics, points, seeds — as unconnected markers)
ORDERED_AXES = ("n", "eps", "steps")
#: largest number of distinct values of an axis that gets a table
MAX_LEVELS = 40
#: numeric figures shown in the printed tables (all are in the JSON and CSV)
MAX_FIGURE_COLUMNS = 6
#: the tasks' verdicts, then MISSING (a task without a record)
VERDICT_ORDER = VERDICTS + ("MISSING",)
COLORS = {"VALID": "#2a9d3f", "OK": "#2a9d3f", "FOUND": "#2a9d3f", "NONE": "#a8c6a0", "INCONCLUSIVE": "#f4a261",
          "WARNED": "#f4a261", "UNDETERMINED": "#e9c46a", "INVALID": "#d62828", "SINGULAR": "#7b8cde",
          "UNDEFINED": "#9d7bde", "UNDECIDED": "#b0b0b0", "TIMEOUT": "#8d5524", "ERROR": "#222222",
          "MISSING": "#ffffff"}


@dataclass
class Summary:
    """See the module docstring; :meth:`text` is what is printed."""

    name: str
    task: str
    ok: str
    total: int
    done: int
    counts: dict
    axes: list
    by_axis: dict
    grid: dict | None
    slowest: list
    failures: list
    figures: list
    shown: list
    task_seconds: float
    rows: list = field(default_factory=list, repr=False)

    def to_json(self) -> dict:
        # not dataclasses.asdict: it would deep-copy every row first (a third of a no-op sweep's time)
        return _jsonable({f.name: getattr(self, f.name) for f in fields(self) if f.name != "rows"})

    def text(self) -> str:
        return summary_text(self)


def _sort_key(value):
    if isinstance(value, bool):
        return (2, str(value))
    if isinstance(value, (int, float)):
        return (0, value)
    try:
        return (0, Fraction(str(value)))
    except (ValueError, ZeroDivisionError):
        return (1, str(value))


def _verdict_sort(v):
    return (VERDICT_ORDER.index(v) if v in VERDICT_ORDER else len(VERDICT_ORDER), v)


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _jsonable(obj):
    if isinstance(obj, float) and not math.isfinite(obj):
        return str(obj)
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, Fraction):
        return str(obj)
    return obj


def summarise(spec, tasks, records: dict) -> Summary:
    """The summary of ``tasks`` given ``records`` (key -> latest record); tasks
    without a record count as MISSING."""
    kind = TASKS.get(spec.task)
    rows = []
    for t in tasks:
        rec = records.get(t.key)
        row = {"key": t.key, "axes": t.axes, "verdict": rec["verdict"] if rec else "MISSING",
               "seconds": rec.get("seconds") if rec else None, "error": rec.get("error") if rec else None,
               "detail": rec.get("detail", "") if rec else "",
               "figures": {k: v for k, v in (rec.get("figures") or {}).items()
                           if v is None or isinstance(v, (int, float, str, bool))} if rec else {}}
        rows.append(row)
    counts = Counter(r["verdict"] for r in rows)
    axes = [a for a in AXIS_ORDER if any(a in t.axes for t in tasks)]
    axes += sorted({a for t in tasks for a in t.axes} - set(axes))
    figures = sorted({k for r in rows for k, v in r["figures"].items() if _number(v)})
    varying = [f for f in figures if len({r["figures"].get(f) for r in rows if _number(r["figures"].get(f))}) > 1]
    first = [f for f in (kind.figures if kind else ()) if f in figures]
    shown = (first + [f for f in varying if f not in first])[:MAX_FIGURE_COLUMNS]
    by_axis = {}
    for a in axes:
        levels = sorted({r["axes"].get(a) for r in rows}, key=_sort_key)
        if len(levels) > MAX_LEVELS:
            continue
        by_axis[a] = [_group(level, [r for r in rows if r["axes"].get(a) == level], figures) for level in levels]
    grid = None
    first, second = _plot_axes(axes)
    if first and second and first in by_axis and second in by_axis:
        ok = kind.ok if kind else "OK"
        cells = {}
        for r in rows:
            c = cells.setdefault((r["axes"].get(first), r["axes"].get(second)), [0, 0])
            c[0] += r["verdict"] == ok
            c[1] += 1
        grid = {"rows": first, "columns": second, "verdict": ok,
                "row_values": [lv["value"] for lv in by_axis[first]],
                "column_values": [lv["value"] for lv in by_axis[second]],
                "cells": [[cells.get((rv["value"], cv["value"]), [0, 0]) for cv in by_axis[second]]
                          for rv in by_axis[first]]}
    timed = [r for r in rows if _number(r["seconds"])]
    slowest = [{"key": r["key"], "axes": r["axes"], "verdict": r["verdict"], "seconds": r["seconds"]}
               for r in sorted(timed, key=lambda r: -r["seconds"])[:10]]
    failures = [{"key": r["key"], "axes": r["axes"], "verdict": r["verdict"], "error": r["error"]}
                for r in rows if r["verdict"] in FAILED][:50]
    return Summary(spec.name, spec.task, kind.ok if kind else "OK", len(tasks), len(tasks) - counts["MISSING"],
                   dict(sorted(counts.items(), key=lambda kv: _verdict_sort(kv[0]))), axes, by_axis, grid,
                   slowest, failures, figures, shown, sum(r["seconds"] for r in timed), rows)


def _group(level, rows, figures) -> dict:
    secs = [r["seconds"] for r in rows if _number(r["seconds"])]
    out = {"value": level, "tasks": len(rows),
           "verdicts": dict(sorted(Counter(r["verdict"] for r in rows).items(), key=lambda kv: _verdict_sort(kv[0]))),
           "seconds_mean": statistics.fmean(secs) if secs else None,
           "seconds_median": statistics.median(secs) if secs else None,
           "seconds_max": max(secs) if secs else None, "figures": {}}
    for f in figures:
        vals = [r["figures"][f] for r in rows if _number(r["figures"].get(f))]
        if vals:
            out["figures"][f] = {"mean": statistics.fmean(vals), "min": min(vals), "max": max(vals),
                                 "median": statistics.median(vals), "count": len(vals)}
    return out


def _plot_axes(axes):
    """(first, second): the first axis, and the first non-replicate axis after it."""
    if not axes:
        return None, None
    first = next((a for a in axes if a not in REPLICATES), axes[0])
    second = next((a for a in axes if a != first and a not in REPLICATES), None)
    return first, second


def _fmt(v, digits=4) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.{digits}g}" if v == 0 or 1e-3 <= abs(v) < 1e5 else f"{v:.2e}"
    return str(v)


def _table(head, rows) -> list:
    widths = [max(len(str(h)), *(len(str(r[i])) for r in rows)) if rows else len(str(h)) for i, h in enumerate(head)]
    line = lambda cells: "  ".join(str(c).rjust(w) for c, w in zip(cells, widths)).rstrip()  # noqa: E731
    return [line(head)] + [line(r) for r in rows]


def summary_text(s: Summary) -> str:
    """The printed summary."""
    out = [f"sweep {s.name}: {s.done} of {s.total} {s.task} tasks done"
           + (f" ({s.total - s.done} missing)" if s.done < s.total else "")
           + f"; {s.task_seconds:.1f} s of task time"]
    out.append("verdicts: " + ", ".join(f"{v} {c}" for v, c in s.counts.items()))
    verdicts = [v for v in s.counts]
    shown = s.shown
    for a, levels in s.by_axis.items():
        if len(levels) < 2 or (a in REPLICATES and len(s.by_axis) > 1):
            continue
        head = [a, "tasks"] + verdicts + ["mean s", "max s"] + shown
        rows = [[lv["value"], lv["tasks"]] + [lv["verdicts"].get(v, 0) for v in verdicts]
                + [_fmt(lv["seconds_mean"]), _fmt(lv["seconds_max"])]
                + [_fmt(lv["figures"].get(f, {}).get("mean")) for f in shown] for lv in levels]
        out += ["", f"by {a}" + (" (figures: means)" if shown else "") + ":"] + ["  " + r for r in _table(head, rows)]
    rest = [f for f in s.figures if f not in shown]
    if rest and any(len(lv) > 1 for lv in s.by_axis.values()):
        out.append(f"  (further figures in summary.json and tasks.csv: {', '.join(rest)})")
    if s.grid:
        g = s.grid
        head = [f"{g['rows']} \\ {g['columns']}"] + [str(v) for v in g["column_values"]]
        rows = [[rv] + [f"{c[0]}/{c[1]}" if c[1] else "-" for c in cells]
                for rv, cells in zip(g["row_values"], g["cells"])]
        out += ["", f"{g['verdict']} tasks against {g['rows']} and {g['columns']}:"] + ["  " + r for r in _table(head, rows)]
    if s.slowest:
        out += ["", "slowest tasks:"]
        out += ["  " + r for r in _table(["seconds", "verdict", "task", "key"],
                                         [[f"{t['seconds']:.3f}", t["verdict"], _axes_text(t["axes"]), t["key"]]
                                          for t in s.slowest[:5]])]
    if s.failures:
        out += ["", f"failed tasks ({sum(s.counts.get(v, 0) for v in FAILED)}; rerun them with --only failed):"]
        for t in s.failures[:10]:
            out.append(f"  {t['verdict']} {_axes_text(t['axes'])} [{t['key']}]: {t['error']}")
    return "\n".join(out)


def _axes_text(axes: dict) -> str:
    return " ".join(f"{k}={v}" for k, v in axes.items()) or "(the only task)"


# --- files ----------------------------------------------------------------------------------


def write_summary(s: Summary, out_dir, plots=True) -> list:
    """Write the summary files (see the module docstring); returns their paths.
    Plots are skipped (with a line in summary.txt) when matplotlib is missing."""
    out = Path(out_dir)
    paths = []
    text = s.text()
    if plots:
        try:
            paths += plot_summary(s, out)
        except ImportError:
            text += "\n(plots skipped: matplotlib is not installed)"
    write_atomic(out / "summary.txt", text + "\n", "--out")
    write_atomic(out / "summary.json", json.dumps(s.to_json(), indent=1, ensure_ascii=False) + "\n", "--out")
    write_atomic(out / "tasks.csv", _csv(s), "--out")
    return [out / "summary.txt", out / "summary.json", out / "tasks.csv"] + paths


def _csv(s: Summary) -> str:
    axes = s.axes
    figs = sorted({k for r in s.rows for k in r["figures"]})
    buf = io.StringIO()
    w = csv.writer(buf)
    fixed = {"key", "verdict", "seconds", "error", "detail", *axes}
    w.writerow(["key"] + axes + ["verdict", "seconds"] + [f"figure:{f}" if f in fixed else f for f in figs]
               + ["error", "detail"])
    for r in s.rows:
        w.writerow([r["key"]] + [r["axes"].get(a, "") for a in axes] + [r["verdict"], _cell(r["seconds"])]
                   + [_cell(r["figures"].get(f)) for f in figs] + [r["error"] or "", r["detail"] or ""])
    return buf.getvalue()


def _cell(v):
    return "" if v is None else v


def _save(fig, path: Path) -> Path:
    """Save a figure atomically (a temporary file renamed into place)."""
    write_atomic(path, lambda fh: fig.savefig(fh, format="png", dpi=110), "--out")
    return path


def plot_summary(s: Summary, out_dir) -> list:
    """verdicts.png, time.png, figures.png (matplotlib, Agg); nothing for a sweep
    without a varying axis."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    first, second = _plot_axes([a for a in s.axes if a in s.by_axis])
    if first is None:
        return []
    out = Path(out_dir)
    levels = [lv["value"] for lv in s.by_axis[first]]
    pos = {v: i for i, v in enumerate(levels)}
    seconds = [lv["value"] for lv in s.by_axis[second]][:6] if second else [None]
    paths = []

    # verdicts against the first axis, one panel per value of the second
    fig, axs = plt.subplots(1, len(seconds), figsize=(max(4.5, 3.2 * len(seconds)), 3.6), sharey=True,
                            squeeze=False)
    verdicts = list(s.counts)
    for ax, sv in zip(axs[0], seconds):
        rows = [r for r in s.rows if sv is None or r["axes"].get(second) == sv]
        bottom = [0] * len(levels)
        for v in verdicts:
            h = [sum(1 for r in rows if r["verdict"] == v and r["axes"].get(first) == lv) for lv in levels]
            ax.bar(range(len(levels)), h, bottom=bottom, color=COLORS.get(v, "#888888"), edgecolor="#444444",
                   linewidth=0.4, label=v)
            bottom = [b + x for b, x in zip(bottom, h)]
        ax.set_xticks(range(len(levels)), [str(v) for v in levels], rotation=45 if len(levels) > 8 else 0)
        ax.set_xlabel(first)
        if sv is not None:
            ax.set_title(f"{second} = {sv}", fontsize=9)
    axs[0][0].set_ylabel("tasks")
    handles, labels = axs[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=7, loc="center right")
    fig.suptitle(f"{s.name}: verdicts ({s.task})", fontsize=10)
    fig.tight_layout(rect=(0, 0, 0.86 if len(seconds) == 1 else 0.92, 1))
    paths.append(_save(fig, out / "verdicts.png"))
    plt.close(fig)

    # time per task against the first axis
    timed = [r for r in s.rows if _number(r["seconds"]) and r["seconds"] > 0]
    if timed:
        fig, ax = plt.subplots(figsize=(5.5, 3.6))
        for v in sorted({r["verdict"] for r in timed}, key=_verdict_sort):  # one colour per verdict, in the legend
            pts = [(pos[r["axes"].get(first)] + ((i * 0.618034) % 1 - 0.5) * 0.3, r["seconds"])
                   for i, r in enumerate(timed) if r["verdict"] == v]
            ax.plot(*zip(*pts), "o", ms=4, alpha=0.7, color=COLORS.get(v, "#888888"), mec="#444444", mew=0.3,
                    ls="none", label=f"{v} ({len(pts)})")
        med = [s.by_axis[first][i]["seconds_median"] for i in range(len(levels))]
        ax.plot([i for i, m in enumerate(med) if m], [m for m in med if m], "k-" if first in ORDERED_AXES else "k_",
                ms=12, lw=1.2, label="median")
        secs = [r["seconds"] for r in timed]
        if max(secs) / min(secs) > 20:
            ax.set_yscale("log")
        ax.set_xticks(range(len(levels)), [str(v) for v in levels], rotation=45 if len(levels) > 8 else 0)
        ax.set_xlabel(first)
        ax.set_ylabel("seconds per task" + (" (log scale)" if ax.get_yscale() == "log" else ""))
        ax.legend(fontsize=7, title="verdict (tasks)", title_fontsize=7, loc="center left",
                  bbox_to_anchor=(1.01, 0.5), frameon=False)
        ax.set_title(f"{s.name}: time per task", fontsize=10)
        fig.tight_layout()
        paths.append(_save(fig, out / "time.png"))
        plt.close(fig)

    # numeric figures against the first axis (means; one line per value of the second); a figure
    # with one value in every task is named in the title, not drawn (its panel would be a flat line)
    figs, constant = [], []
    for f in (f for f in s.shown if f not in ("n", "seed")):
        vals = {r["figures"][f] for r in s.rows if _number(r["figures"].get(f))}
        (figs if len(vals) > 1 else constant).append(f if len(vals) > 1 else f"{f} = {_fmt(next(iter(vals)))}")
    figs = figs[:6]
    if figs:
        cols = min(3, len(figs))
        nrows = math.ceil(len(figs) / cols)
        fig, axs = plt.subplots(nrows, cols, figsize=(3.6 * cols, 2.9 * nrows), squeeze=False)
        for ax, f in zip(axs.flat, figs):
            for sv in seconds:
                xs, ys = [], []
                for lv in levels:
                    vals = [r["figures"][f] for r in s.rows if r["axes"].get(first) == lv
                            and (sv is None or r["axes"].get(second) == sv) and _number(r["figures"].get(f))]
                    if vals:
                        xs.append(pos[lv])
                        ys.append(statistics.fmean(vals))
                if xs:
                    ax.plot(xs, ys, "o-" if first in ORDERED_AXES else "o", ms=3, lw=1,
                            label=None if sv is None else str(sv))
            ax.set_title(f, fontsize=9)
            ax.set_ylabel(f"mean {f} per task", fontsize=8)
            ax.set_xticks(range(len(levels)), [str(v) for v in levels], fontsize=7,
                          rotation=45 if len(levels) > 8 else 0)
            ax.set_xlabel(first, fontsize=8)
            ax.grid(True, alpha=0.3)
        for ax in list(axs.flat)[len(figs):]:
            ax.axis("off")
        handles, labels = axs[0][0].get_legend_handles_labels()
        width = 3.6 * cols + (1.4 if second else 0)
        fig.set_size_inches(width, 2.9 * nrows + 0.4)
        if second:
            fig.legend(handles, labels, fontsize=7, loc="center right", frameon=False, title=second, title_fontsize=7)
        fig.suptitle(f"{s.name}: figures (means over the tasks of each {first})"
                     + (f"\nthe same in every task: {', '.join(constant)}" if constant else ""), fontsize=10)
        fig.tight_layout(rect=(0, 0, 1 - (1.4 / width if second else 0), 1))
        paths.append(_save(fig, out / "figures.png"))
        plt.close(fig)
    return paths
