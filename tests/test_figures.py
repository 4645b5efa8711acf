"""What the figures draw (read from the matplotlib figure before it is closed, not from pixels):
the work-precision diagram, the height-growth plot, the sweep summary's plots."""

import math

import pytest

pytest.importorskip("matplotlib")


@pytest.fixture
def drawn(monkeypatch):
    """The figures closed while the test runs (every plotting function closes its figure)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figs, real = [], plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: (figs.append(fig), real(fig)))
    return figs


def _points(ax):
    """{legend label: (x, y)} of the single-point series of an axes."""
    return {ln.get_label(): (ln.get_xdata()[0], ln.get_ydata()[0]) for ln in ax.lines if len(ln.get_xdata()) == 1}


def test_work_precision_correct_bits_against_cpu_time(tmp_path, drawn):
    from exact_khk.studies.scaling import LOG10_2, plot_study, scaling_study
    from exact_khk.systems.lie_poisson import DEFAULT_X0, default_system

    st = scaling_study(default_system(), DEFAULT_X0, "1/10", 6, ["float", "mp:113", "mp:1024", "ball:64"],
                       progress=False, repeats=2)
    assert st.repeats == 2 and all(r.seconds_per_step > 0 for r in st.runs)
    plot_study(st, tmp_path)
    fig = next(f for f in drawn if f._suptitle is not None and "work-precision" in f._suptitle.get_text())
    few, many = [ax for ax in fig.axes if ax.lines]
    assert "least of 2 runs" in few.get_xlabel() and "CPU" in few.get_xlabel() and few.get_xscale() == "log"
    assert set(_points(few)) == {"float", "mp:113", "ball:64 (certified radius)"}
    assert set(_points(many)) == {"mp:1024"}               # more than 256 bits: a panel of its own
    for run in st.runs:                                    # y = −log2 of the error (balls: of the radius)
        label = run.arith + (" (certified radius)" if run.arith.startswith("ball") else "")
        x, y = {**_points(few), **_points(many)}[label]
        last = run.rows[-1].radius_log10 if run.arith.startswith("ball") else run.rows[-1].error_log10
        assert x == run.seconds_per_step and math.isclose(y, max(0.0, -last / LOG10_2))
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels[:4] == ["float", "mp:113", "mp:1024", "ball:64 (certified radius)"] and "exact" in labels[-1]


def test_growth_plot_draws_no_rejected_fit(tmp_path, drawn):
    from exact_khk.systems.catalogue import load
    from exact_khk.diagnostics import height_growth, plot_growth

    lv = load("lotka-volterra")
    g = height_growth(lv.field("f"), ["2", "1"], "1/10", steps=12)
    assert g.growth == "exponential"
    plot_growth(tmp_path / "g.png", heights=g)
    ax = drawn[-1].axes[0]
    fits = [ln for ln in ax.lines if "fit" in ln.get_label() and len(ln.get_xdata())]
    assert [ln.get_label().split(" ")[0] for ln in fits] == ["exponential"]
    assert all(v > 0 for v in fits[0].get_ydata())
    assert any(ln.get_label().startswith("rejected fits (not drawn)") for ln in ax.lines)


def test_sweep_figures_have_labels_and_no_flat_panel(tmp_path, drawn):
    """certify's main figures include ``false`` and ``open`` (0 in every task here: no claim is
    false): they are named in the title, not drawn as flat panels."""
    from exact_khk.sweep import parse_spec, run_sweep

    spec = parse_spec('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = "2-3"\nseeds = "0-2"\n'
                      '[grid]\neps = ["1/10", "1/3"]\nsteps = 3\n[options]\nsigns = "b0"\npoisson_points = 1\n',
                      origin="certify.toml")
    res = run_sweep(spec, tmp_path, workers=0)
    assert "false" in res.summary.shown and all(r["figures"].get("false") == 0 for r in res.summary.rows
                                                  if r["figures"])
    fig = next(f for f in drawn if f._suptitle is not None and "figures (means" in f._suptitle.get_text())
    assert "false = 0" in fig._suptitle.get_text()
    panels = [ax for ax in fig.axes if ax.lines]
    assert panels and all(ax.get_ylabel() for ax in panels) and "false" not in [ax.get_title() for ax in panels]
    for ax in panels:  # every drawn figure varies
        assert len({y for ln in ax.lines for y in ln.get_ydata()}) > 1, ax.get_title()
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["1/10", "1/3"]
    time_ax = next(f.axes[0] for f in drawn if f.axes[0].get_ylabel().startswith("seconds per task"))
    legend = [t.get_text() for t in time_ax.get_legend().get_texts()]
    assert legend == [f"{v} ({c})" for v, c in res.summary.counts.items()] + ["median"]
