"""Figures laid out with fixed margins where every text fits, else tight (issue 10,
latency): never a clipped or overlapping text, and the PNG as savefig writes it."""

import numpy as np
import pytest

from agilesat.orchestration.output import figure_layout, plots

matplotlib = pytest.importorskip("matplotlib")


def _figure(n=2, sharex=True):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig, axes = plots._subplots(n, sharex=sharex)
    t = np.linspace(0.0, 150.0, 301)
    for k, ax in enumerate(axes[:, 0]):
        ax.plot(t, np.sin(t / 10) * 10**k, label="a")
        ax.plot(t, np.cos(t / 10), label="b")
        ax.legend()
        ax.set_ylabel(f"signal {k} [rad/s]")
    axes[-1, 0].set_xlabel("time [s]")
    axes[0, 0].set_title("a title")
    figure_layout.fixed(fig, axes, "a title")
    return fig, axes, FigureCanvasAgg(fig)


def _texts_inside_and_apart(fig, axes, canvas) -> bool:
    """Independent of the layout's own check: each axes' tight box (its ticks, labels and
    title) inside the figure and clear of the others'."""
    renderer = canvas.get_renderer()
    boxes = [ax.get_tightbbox(renderer) for ax in axes[:, 0]]
    edge = fig.bbox.padded(1.0)
    inside = all(
        edge.x0 <= b.x0 and b.x1 <= edge.x1 and edge.y0 <= b.y0 and b.y1 <= edge.y1 for b in boxes
    )
    return inside and not any(p.overlaps(q) for p, q in zip(boxes, boxes[1:]))


@pytest.mark.parametrize("n, sharex", [(1, True), (2, True), (3, True), (2, False)])
def test_our_stacked_axes_fit_the_fixed_margins(n, sharex):
    fig, axes, canvas = _figure(n, sharex)
    assert figure_layout.draw(fig, axes, canvas)
    assert _texts_inside_and_apart(fig, axes, canvas)


@pytest.mark.parametrize(
    "spoil",
    [
        lambda axes: axes[0, 0].set_yticks([0.0, 1.0], ["a tick label far too long", "b"]),
        lambda axes: axes[0, 0].set_xlabel("an x label\non three\nlines"),  # onto the next
        lambda axes: axes[0, 0].set_title("a title\non three\nlines"),  # title: 1 line given
        lambda axes: axes[1, 0].set_xticks([0.0, 150.0], ["0", "a last tick label past it"]),
    ],
)
def test_a_text_that_does_not_fit_is_laid_out_tight(spoil):
    fig, axes, canvas = _figure(2, sharex=False)
    spoil(axes)
    canvas.draw()
    assert not _texts_inside_and_apart(fig, axes, canvas)  # the fixed margins fail it
    assert not figure_layout.draw(fig, axes, canvas)
    assert _texts_inside_and_apart(fig, axes, canvas)


def test_the_png_is_the_one_savefig_writes(tmp_path):
    from PIL import Image

    with plots.written_as((".png",)):
        plots._save(*_figure(1)[:2], tmp_path / "ours.png", "a title", "time [s]")
    fig = _figure(1)[0]
    fig.savefig(tmp_path / "saved.png", dpi=plots.DPI)
    ours, saved = (np.asarray(Image.open(tmp_path / f)) for f in ("ours.png", "saved.png"))
    assert ours.shape == (round((1.2 + 2.6) * plots.DPI), 8 * plots.DPI, 4)
    assert np.array_equal(ours, saved)


def test_a_legend_reaching_other_axes_is_laid_out_tight():
    fig, axes, canvas = _figure(2, sharex=False)
    for k in range(20):
        axes[0, 0].plot([0.0, 150.0], [k, k], label=f"series {k}")
    axes[0, 0].legend()
    canvas.draw()
    legend = axes[0, 0].get_legend().get_window_extent(canvas.get_renderer())
    assert legend.overlaps(axes[1, 0].bbox)  # with the fixed margins
    assert not figure_layout.draw(fig, axes, canvas)


def test_the_formats_are_set_per_thread_and_checked():
    import threading

    inside, leave = threading.Event(), threading.Event()

    def png_only():
        with plots.written_as((".png",)):
            inside.set()
            leave.wait(10)

    thread = threading.Thread(target=png_only)
    thread.start()
    inside.wait(10)
    assert plots.written() == plots.FORMATS == (".png", ".svg")  # not this thread's
    leave.set()
    thread.join()
    with pytest.raises(ValueError, match=r"expected '.png' first"):
        with plots.written_as((".svg",)):
            pass


@pytest.mark.parametrize("rc", ["figure.autolayout", "figure.constrained_layout.use"])
def test_a_figure_laid_out_tight_stays_as_drawn_whatever_rcparams_say(rc):
    """After the tight fallback no layout engine is left to lay the SVG twin out anew (it
    would differ from the PNG drawn before it)."""
    from matplotlib.layout_engine import PlaceHolderLayoutEngine

    with matplotlib.rc_context({rc: True}):
        fig, axes, canvas = _figure(2, sharex=False)
        axes[0, 0].set_title("a title\non three\nlines")
        assert not figure_layout.draw(fig, axes, canvas)
        engine = fig.get_layout_engine()  # none, or matplotlib's place holder, a no-op
        assert engine is None or isinstance(engine, PlaceHolderLayoutEngine)


def _panel(values, **marks):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig, axes = plots._subplots(1)
    ax = axes[0, 0]
    t = np.linspace(0.0, 10.0, 200)
    for k, v in enumerate(values):
        ax.plot(t, v, label=f"series {k + 1}")
    plots._mark(ax, plots._span(values), **marks)
    plots._legend(ax)
    FigureCanvasAgg(fig).draw()
    return ax


def test_a_limit_far_above_an_error_makes_the_axis_logarithmic_and_shows_both():
    """video_sar's pointing error (1.5e-5°) under its 0.05° line was a flat line."""
    error = 1e-5 * (1.5 + np.sin(np.linspace(0, 3, 200)))
    ax = _panel([error], limit=((0.05,), "required"), bottom=0.0)
    assert ax.get_yscale() == "log"
    low, high = ax.get_ylim()
    assert low <= error.min() and high > 0.05
    assert [line.get_ydata()[0] for line in ax.lines[1:]] == [0.05]


def test_a_limit_far_outside_signed_data_is_said_not_drawn():
    """video_sar's gimbal rates (0.002 rad/s) against ±0.6 rad/s were flat lines."""
    rates = [0.002 * np.sin(np.linspace(0, 3, 200) + k) for k in range(6)]
    ax = _panel(rates, limit=(0.6, "limit ±0.6 rad/s"))
    assert ax.get_ylim()[1] < 0.01  # the data fill the axes
    assert "limit ±0.6 rad/s (off scale)" in ax.get_legend_handles_labels()[1]


def test_the_legend_covers_no_data_and_no_series_has_the_limits_red():
    rates = [np.sin(np.linspace(0, 6, 200) + k) for k in range(6)]
    ax = _panel(rates, limit=(1.0, "limit"))
    colours = [line.get_color() for line in ax.lines[:6]]
    assert "tab:red" not in colours and len(set(colours)) == 6
    box = ax.get_legend().get_window_extent()
    for line in ax.lines:
        points = ax.transData.transform(np.column_stack(line.get_data()))
        inside = (box.x0 < points[:, 0]) & (points[:, 0] < box.x1)
        assert not (inside & (box.y0 < points[:, 1]) & (points[:, 1] < box.y1)).any()


def test_overview_names_vector_elements_by_axis_angles_in_degrees_booleans_false_true(
    tmp_path, monkeypatch
):
    from agilesat.orchestration.output.results import Results

    t = np.linspace(0.0, 1.0, 5)
    names = ["time", "A.w[1]", "A.w[2]", "A.w[3]", "A.q_BI[1]", "A.q_BI[2]", "A.q_BI[3]"]
    names += ["A.q_BI[4]", "A.on"]
    data = np.column_stack([t, t, t, t, t, t, t, t, t > 0.5])
    units = {n: "rad" for n in names[1:4]} | {n: "1" for n in names[4:8]}
    drawn = []
    monkeypatch.setattr(plots, "_save", lambda fig, axes, *rest: drawn.append(axes) or rest[0])
    plots.overview(Results(names, data, {"units": units}), tmp_path)
    [axes] = drawn
    w, q, on = axes[:, 0]
    assert [line.get_label() for line in w.lines] == ["x", "y", "z"]
    assert w.get_ylabel() == "w [°]" and w.lines[0].get_ydata()[-1] == pytest.approx(180 / np.pi)
    assert [line.get_label() for line in q.lines] == ["w", "x", "y", "z"]
    assert [tick.get_text() for tick in on.get_yticklabels()] == ["false", "true"]
