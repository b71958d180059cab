"""A campaign figure is laid out without the tight layout and drawn once: its title, its
legend beside the axes and its labels lie inside the PNG, which holds the title as its
"Title"; a legend too wide for the fixed margins falls back to the tight layout."""

import numpy as np
from matplotlib.figure import Figure
from PIL import Image

from agilesat.orchestration.campaign import report
from agilesat.orchestration.output import plots


def counted_draws(monkeypatch) -> list:
    """The (figure, renderer) of each drawing from now on."""
    drawn = []
    original = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda fig, r: drawn.append((fig, r)) or original(fig, r))
    return drawn


def inside(drawn, ax) -> bool:
    """The title, axis labels and legend of ``ax`` inside its figure as last drawn."""
    fig, renderer = drawn[-1]
    fig.set_dpi(renderer.dpi)  # as drawn (pyplot's close gives it back its own)
    edge = fig.bbox.padded(1.0)
    texts = [ax.title, ax.xaxis.label, ax.yaxis.label, ax.get_legend()]
    boxes = [t.get_window_extent(renderer) for t in texts]
    return all(
        edge.x0 <= b.x0 and b.x1 <= edge.x1 and edge.y0 <= b.y0 and b.y1 <= edge.y1 for b in boxes
    )


def histogram(label: str):
    from agilesat.orchestration.output.plots import plt

    fig, ax = plt.subplots(figsize=(7.5, 3.6))
    ax.hist(np.random.default_rng(0).normal(size=500), bins=20)
    ax.axvline(1.0, color="tab:red", linestyle="--", label=label)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_xlabel("m [°]")
    ax.set_ylabel("runs")
    ax.set_title("A metric's description\nover two lines\n500 runs", fontsize=10)
    return fig, ax


def test_a_histogram_with_its_legend_beside_is_drawn_once_and_fits(tmp_path, monkeypatch):
    drawn = counted_draws(monkeypatch)
    fig, ax = histogram("requirement (upper)")
    path = report._save(fig, ax, tmp_path / "hist_m.png")
    assert len(drawn) == 1 and inside(drawn, ax)
    image = Image.open(path)
    assert image.text["Title"] == "A metric's description\nover two lines\n500 runs"
    assert image.size == (1500, 720)


def test_a_legend_too_wide_for_the_margins_is_laid_out_tight(tmp_path, monkeypatch):
    monkeypatch.setattr(plots, "DPI", 50)  # a smaller PNG: the layout is in inches
    drawn = counted_draws(monkeypatch)
    fig, ax = histogram("a requirement with a long label " * 2)
    report._save(fig, ax, tmp_path / "hist_m.png")
    assert len(drawn) == 2 and inside(drawn, ax)


def test_a_histogram_is_one_outline_of_the_counts(tmp_path, monkeypatch):
    """The bars drawn as one filled outline (one patch, not a rectangle per bin), whose
    tops are numpy's counts of the values in the bins."""
    drawn = []
    monkeypatch.setattr(report, "_save", lambda fig, ax, path: drawn.append(ax) or path)
    values = np.random.default_rng(3).normal(size=100)
    array = np.array([(x,) for x in values], dtype=[("m", float)])
    report.histograms(array, {"metrics": {"m": {"unit": "1"}}}, tmp_path)
    [ax] = drawn
    [outline] = ax.patches
    counts, edges = np.histogram(values, bins=10)  # √100 bins
    x, y = outline.get_xy().T
    for count, low, high in zip(counts, edges, edges[1:]):
        assert np.any((x == low) & (y == count)) and np.any((x == high) & (y == count))


def test_an_envelope_draws_the_median_of_the_runs_with_or_without_a_stopped_one(
    tmp_path, monkeypatch
):
    """The median line: numpy's median over the runs at each time; a run that stopped
    early (NaN from then on) counts only while it ran."""
    drawn = []
    monkeypatch.setattr(report, "_save", lambda fig, ax, path: drawn.append(ax) or path)
    t = np.arange(20) * 0.5
    signals = np.random.default_rng(4).normal(size=(9, 2, 20))
    signals[3, 1, 12:] = np.nan
    report.envelopes(signals, ["a", "b"], {}, t, tmp_path)
    full, stopped = (ax.lines[0].get_ydata() for ax in drawn)
    close = np.testing.assert_allclose  # the mean of the middle two, or interpolated
    close(full, np.median(signals[:, 0], axis=0), rtol=1e-12)
    close(stopped[:12], np.median(signals[:, 1, :12], axis=0), rtol=1e-12)
    close(stopped[12:], np.median(np.delete(signals[:, 1, 12:], 3, 0), axis=0), rtol=1e-12)
