"""Figures of the precision studies (matplotlib, Agg backend), one function per figure.

Every arithmetic keeps one colour and one marker in every figure
(:func:`style`), labels sit in legends outside the data (never annotations that
may overlap), and every title names the system, ε and the number of steps.

* :func:`work_precision` — correct bits at the last step against CPU time per step (log
  axis); ball and Lohner enclosures by their certified radius; arithmetics of more
  than :data:`FEW_BITS` bits in a panel of their own; the exact arithmetic's time as a
  vertical line;
* :func:`bits_lost` — bits lost against the step, relative to each precision P:
  P + log2(relative error), so that float's and mp:53's drift of a few bits is
  visible next to mp:4096;
* :func:`drift` — the integrals' drift against the step (one panel per integral);
* :func:`enclosure_radius` — log2 of the relative enclosure radius against the
  step (log step axis), naive balls beside the Lohner enclosure.
"""

from __future__ import annotations

import math

_COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf",
           "#bcbd22", "#7f7f7f", "#000000", "#aec7e8", "#98df8a", "#ff9896", "#c5b0d5", "#c49c94"]
_LINES = ["-", "--", "-.", ":"]
_MARKERS = ["o", "s", "^", "v", "D", "P", "X", "<", ">", "h", "*", "p", "d", "8", "H", "+"]


def style(names):
    """{name: (colour, marker)}: distinct for up to 16 names, assigned in order."""
    return {n: (_COLORS[i % len(_COLORS)], _MARKERS[i % len(_MARKERS)]) for i, n in enumerate(names)}


def _pick(styles, names):
    """The styles of ``names``: from ``styles`` (keyed by arithmetic; a label is looked
    up by its first word) when given, so that one arithmetic looks the same in every figure."""
    own = style(names)
    if not styles:
        return own
    return {n: styles.get(n, styles.get(n.split(" ")[0].rstrip(","), own[n])) for n in names}


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path, legend_axes=(), rect=None):
    """Finish a figure: the legend of each of ``legend_axes`` outside its data on the right,
    the layout (within ``rect``), the PNG written atomically, the figure closed."""
    from exact_khk.studies.output import write_atomic

    for ax in legend_axes:
        ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)
    fig.tight_layout(**({"rect": rect} if rect else {}))
    write_atomic(path, lambda fh: fig.savefig(fh, format="png"), "--out")
    _plt().close(fig)


def _curve(ax, styles, name, i, pts):
    """One series against the step in its arithmetic's colour and marker (the first
    series drawn thick, so that one lying under the others stays visible)."""
    color, marker = styles[name]
    ks, ys = zip(*pts)
    ax.plot(ks, ys, color=color, marker=marker, markevery=max(1, len(ks) // 8), ms=8 if i == 0 else 5,
            lw=3.0 if i == 0 else 1.2, ls=_LINES[i % 2], label=name)


#: the work-precision diagram puts arithmetics carrying more bits than this in a panel of their
#: own (mp:4096's 4 000 correct bits would squeeze float's 50 and mp:256's 240 into one cluster)
FEW_BITS = 256


def work_precision(points, title, exact_seconds, path, styles=None, repeats=1):
    """``points``: [(label, precision P or None, CPU seconds per step, correct bits at step K, kind)]
    with kind ``'error'`` (bits = −log2 of the relative error), ``'radius'`` (−log2 of the
    certified relative radius: certified correct bits) or ``'stopped'`` (no point at step K:
    drawn hollow at 0 bits).  Arithmetics with P > :data:`FEW_BITS` go in a second panel
    with its own bit scale; the time axis (log) is shared, the exact orbit's time a dashed
    line in each panel."""
    plt = _plt()
    st = _pick(styles, [p[0] for p in points])
    drawn = [p for p in points if p[2] is not None]
    groups = [(f"P ≤ {FEW_BITS} bits", [p for p in drawn if (p[1] or 53) <= FEW_BITS]),
              (f"P > {FEW_BITS} bits", [p for p in drawn if (p[1] or 53) > FEW_BITS])]
    groups = [(head, g) for head, g in groups if g] or [("", [])]
    fig, axes = plt.subplots(1, len(groups), figsize=(4.6 * len(groups) + 2.8, 4.8), dpi=110, sharex=True,
                             squeeze=False)
    from matplotlib.ticker import NullFormatter

    for ax, (head, group) in zip(axes[0], groups):
        for label, prec, sec, bits, kind in group:
            color, marker = st[label]
            if kind == "stopped":
                ax.plot(sec, 0.0, marker=marker, color=color, mfc="none", mew=1.6, ms=9, ls="none", label=label)
            else:
                ax.plot(sec, bits, marker=marker, color=color, ms=8, ls="none", label=label)
        if exact_seconds:
            ax.axvline(exact_seconds, color="gray", ls="--", lw=1.2,
                       label=f"exact (flint), every bit: {exact_seconds * 1e3:.3g} ms/step")
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("CPU time per step [s] (log scale)" + (f", least of {repeats} runs" if repeats > 1 else ""))
        ax.set_ylabel("correct bits at step K = −log2(relative error)")
        ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]) - 0.03 * ax.get_ylim()[1])
        ax.set_title(head, fontsize=9)
        ax.grid(True, which="major", alpha=0.3)
    handles = {}  # the points in the order given, the exact orbit's line last
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    order = [p[0] for p in drawn] + [lab for lab in handles if lab.startswith("exact")]
    handles = {lab: handles[lab] for lab in order if lab in handles}
    width = 4.6 * len(groups) + 2.8
    fig.legend(list(handles.values()), list(handles), fontsize=8, loc="center right", frameon=False)
    fig.suptitle(title + "\nfilled: error against the exact orbit; balls/Lohner: certified radius; "
                 "hollow at 0: no certified bit at step K", fontsize=9)
    _save(fig, path, rect=(0, 0, 1 - 2.8 / width, 1))


def bits_lost(series, title, path, styles=None):
    """``series``: [(name, precision P, [(k, log10 relative error)])]: plots P + log2(error),
    the bits lost of the P carried (clipped at 0 for an error below 2^-P).  Floating
    arithmetics (a few bits over hundreds of steps) and certified radii (names ending in
    '(radius)': often bits per step) go in separate panels, each on its own scale, so
    that float's and mp:53's drift is visible."""
    plt = _plt()
    st = _pick(styles, [s[0] for s in series])
    groups = [("computed points (error against the exact orbit)",
               [s for s in series if not s[0].endswith("(radius)")]),
              ("enclosures (certified radius)", [s for s in series if s[0].endswith("(radius)")])]
    groups = [(head, g) for head, g in groups if g]
    fig, axes = plt.subplots(1, len(groups), figsize=(6.4 * len(groups) + 1.6, 4.8), dpi=110, squeeze=False)
    for ax, (head, group) in zip(axes[0], groups):
        for i, (name, prec, pts) in enumerate(group):
            pts = [(k, max(0.0, prec + e / math.log10(2))) for k, e in pts if e is not None and prec]
            if not pts:
                continue
            _curve(ax, st, name, i, pts)
        ax.set_xlabel("step k")
        ax.set_ylabel("bits lost = P + log2(relative error)")
        ax.set_title(head, fontsize=9)
        ax.grid(True, alpha=0.3)
    fig.suptitle(title, fontsize=10)
    _save(fig, path, legend_axes=axes[0])


def drift(series, integrals, title, path, styles=None):
    """``series``: [(name, [(k, {integral: log10 relative drift})])]; one panel per integral."""
    plt = _plt()
    st = _pick(styles, [s[0] for s in series])
    n = max(1, len(integrals))
    width = 4.2 * n + 1.7
    fig, axes = plt.subplots(1, n, figsize=(width, 4.4), dpi=110, squeeze=False)
    for ax, integral in zip(axes[0], integrals or ["-"]):
        for i, (name, rows) in enumerate(series):
            pts = [(k, d[integral]) for k, d in rows if d.get(integral) is not None]
            if not pts:
                continue
            _curve(ax, st, name, i, pts)
        ax.set_xlabel("step k")
        ax.set_ylabel(f"log10 |{integral}(x_k) - {integral}(x_0)| / |{integral}(x_0)|")
        ax.grid(True, alpha=0.3)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="center right", frameon=False)
    fig.suptitle(title + " — integral drift (exactly 0 for the exact orbit)", fontsize=10)
    _save(fig, path, rect=(0, 0, 1 - 1.6 / width, 1))


def enclosure_radius(series, title, path, target_bits=None, styles=None):
    """``series``: [(label, [(k, log2 relative radius)])]; step axis logarithmic (k ≥ 1);
    ``target_bits``: a dotted line at −target (e.g. 100 correct bits)."""
    plt = _plt()
    st = _pick(styles, [s[0] for s in series])
    fig, ax = plt.subplots(figsize=(7.6, 4.8), dpi=110)
    for i, (label, pts) in enumerate(series):
        pts = [(k, y) for k, y in pts if k >= 1 and y is not None]
        if not pts:
            continue
        color, marker = st[label]
        ks, ys = zip(*pts)
        idx = sorted({int(round(10 ** (j / 6 * math.log10(len(ks))))) - 1 for j in range(7)} | {len(ks) - 1})
        ax.plot(ks, ys, color=color, marker=marker, markevery=[i for i in idx if 0 <= i < len(ks)], ms=6,
                lw=2.6 if i == 0 else 1.4, ls=_LINES[i % len(_LINES)], label=label)
    if target_bits:
        ax.axhline(-target_bits, color="gray", ls=":", lw=1.2, label=f"{target_bits} correct bits")
    ax.axhline(0, color="black", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("step k")
    ax.set_ylabel("log2(max radius / max |x_k|)  (−correct bits)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.25)
    _save(fig, path, legend_axes=[ax])
