"""Figures with matplotlib (non-interactive backend), fit for a report: every figure as a
200-dpi PNG and an SVG beside it (:data:`FORMATS`; :func:`written_as` chooses: ``agilesat
run`` writes the SVG only with ``--svg``), limits and requirements drawn where they exist.

A row of :func:`panels` is ``(x, {label: values}, ylabel)`` or ``(x, series, ylabel,
marks)`` with ``marks`` any of ``limit=(value, label)`` (dashed red lines at ±value, or at
the values of a pair), ``band=(low, high, label)`` (a shaded band), ``paper=(value, label)``
(a dotted line: the paper's value beside ours), ``statistic=(value, label)`` (a dash-dotted
black line: the statistic a requirement compares), ``bottom=y`` (the axis starts there),
``log=True`` (a logarithmic axis: an error of 100° and of 0.001° on one panel),
``at=(x, label)`` (a solid black vertical line: an instant a metric gives, such as a
settling time), ``paper_at=(x, label)`` (a dotted vertical line: the paper's instant),
``events=(xs, label)`` (thin grey vertical lines: payload reversals, say),
``empty=(x0, x1, label)`` (a light grey span where the quantity has no value: before a
windowed index's first full window).
``panels(..., phases=[(name, start, end), ...])`` marks the phases of a maneuver on every
axes (dotted grey lines at their boundaries) and names them above the top axes.
Axes that do not share x each get the x label.  The overview of a run leaves out Euler rates
within :data:`GIMBAL_LOCK_MARGIN` of gimbal lock (shaded, and the legend says so).
Later series are drawn thinner, so that lines lying on top of each other stay visible;
"planned …" and "reference …" series are dashed.

matplotlib is imported by the first figure drawn, not with this module (a run without
figures never loads it).
"""

from __future__ import annotations

import contextlib
import math
import textwrap
from contextvars import ContextVar
from pathlib import Path

from ..system.units import label as unit_label
from ..system.units import to_degrees
from . import figure_layout
from .recorder import atomically

DPI = 200
#: the formats a figure can be written in: the PNG (the path given) and its vector twin
FORMATS = (".png", ".svg")
#: those figures are written in now: all, or as :func:`written_as` sets them (per thread)
_written: ContextVar[tuple[str, ...]] = ContextVar("agilesat_figure_formats", default=FORMATS)
_STYLES = ("-", "--", "-.", ":")
#: the series' colours: matplotlib's tab10 without its red, which is the limits'
SERIES_COLOURS = (
    "tab:blue",
    "tab:orange",
    "tab:green",
    "tab:purple",
    "tab:brown",
    "tab:pink",
    "tab:gray",
    "tab:olive",
    "tab:cyan",
)


@contextlib.contextmanager
def written_as(formats):
    """Figures made inside (in this thread) are written in ``formats``: ".png" first, then
    any of the others of :data:`FORMATS`."""
    formats = tuple(formats)
    if formats[:1] != (".png",) or not set(formats) <= set(FORMATS):
        raise ValueError(f"figure formats {formats}: expected '.png' first, then of {FORMATS}")
    token = _written.set(formats)
    try:
        yield
    finally:
        _written.reset(token)


#: (figures written so far, called before each is drawn) while :func:`drawing` (per thread)
_drawing: ContextVar[tuple[list, object] | None] = ContextVar("agilesat_drawing", default=None)


@contextlib.contextmanager
def drawing(before=None):
    """Figures made inside (in this thread) are listed, as they are written, in the list
    yielded; ``before(paths)`` is called before each one is written, with the files it
    is written as (it may raise: a run stopped by a signal then says which figures were
    written)."""
    drawn: list[Path] = []
    token = _drawing.set((drawn, before))
    try:
        yield drawn
    finally:
        _drawing.reset(token)


#: {file name: Figure} of each figure written while :func:`figure_objects` (per thread)
_figure_objects: ContextVar[dict | None] = ContextVar("agilesat_figure_objects", default=None)


@contextlib.contextmanager
def figure_objects():
    """Figures made inside (in this thread) are collected, as {file name: matplotlib
    Figure} in the dict yielded: what they show can be asked of their axes (the tests do)."""
    figures: dict = {}
    token = _figure_objects.set(figures)
    try:
        yield figures
    finally:
        _figure_objects.reset(token)


def written() -> tuple[str, ...]:
    """The formats figures are written in now."""
    return _written.get()


def formats(path) -> list[Path]:
    """Every file a figure is written as (the PNG path given, then its vector twin)."""
    return [Path(path).with_suffix(suffix) for suffix in written()]


def lines(
    path: Path,
    title: str,
    t,
    series: dict,
    ylabel: str,
    xlabel: str = "time [s]",
    phases=(),
    title_size=None,
    **marks,
) -> Path:
    """One axes: each named series against time (or ``xlabel``)."""
    return panels(path, title, [(t, series, ylabel, marks)], xlabel, phases, title_size)


def panels(
    path: Path, title: str, rows, xlabel: str = "time [s]", phases=(), title_size=None
) -> Path:
    """Stacked axes sharing x, one per row (see the module docstring); ``title_size``:
    the title's font size (default matplotlib's)."""
    shared = len({id(r[0]) for r in rows}) == 1
    fig, axes = _subplots(len(rows), sharex=shared)
    for ax, row in zip(axes[:, 0], rows):
        t, series, ylabel = row[:3]
        for k, (name, values) in enumerate(series.items()):
            ax.plot(
                t,
                values,
                label=name,
                linewidth=_width(k, len(series)),
                linestyle="--" if name.startswith(("planned", "reference")) else "-",
            )
        _mark(ax, _span(series.values()), **(row[3] if len(row) > 3 else {}))
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        _legend(ax)
        if not shared:
            ax.set_xlabel(xlabel)
    _phases(axes[:, 0], phases)
    pad = 14.0 if phases else None
    return _save(fig, axes, path, title, xlabel, title_pad=pad, title_size=title_size)


def _phases(axes, phases) -> None:
    """The phases [(name, start, end), ...] of a maneuver: dotted grey lines at their
    boundaries on every axes, each phase's name above the top axes, centred on it."""
    if not phases:
        return
    from matplotlib.transforms import blended_transform_factory

    boundaries = sorted({end for _, _, end in phases[:-1]})  # between phases
    for ax in axes:
        low, high = ax.get_xlim()
        for x in boundaries:
            if low < x < high:
                ax.axvline(x, color="0.6", linestyle=(0, (2, 4)), linewidth=0.9, zorder=0.5)
    top = axes[0]
    low, high = top.get_xlim()
    on_x = blended_transform_factory(top.transData, top.transAxes)
    for name, start, end in phases:
        start, end = max(start, low), min(end, high)
        if start < end:
            top.text(
                (start + end) / 2,
                1.01,
                name,
                transform=on_x,
                ha="center",
                va="bottom",
                fontsize=7,
                color="0.35",
            )


def _legend(ax) -> None:
    """The legend (of two entries or more) in headroom of its own above the data and the
    limits, so that it covers neither."""
    labels = ax.get_legend_handles_labels()[1]
    if len(labels) < 2:
        return
    columns = min(3, len(labels))
    share = 0.09 * -(-len(labels) // columns) + 0.05  # of the axes' height
    low, high = ax.get_ylim()
    if ax.get_yscale() == "log":
        ax.set_ylim(low, high * (high / low) ** (share / (1 - share)))
    else:
        ax.set_ylim(low, high + (high - low) * share / (1 - share))
    ax.legend(fontsize=8, ncol=columns, loc="upper right")


def _width(k: int, n: int) -> float:
    """Line widths falling from 2.2 to 0.9 over the series: a line lying exactly on an
    earlier one still shows that one's colour at its edges."""
    return 2.2 - 1.3 * k / max(n - 1, 1)


def _span(series) -> float:
    """The largest |value| of the series (0 if none is finite)."""
    import numpy as np

    finite = [np.abs(v)[np.isfinite(v)] for v in map(np.asarray, series)]
    return max((float(v.max()) for v in finite if v.size), default=0.0)


#: a limit this many times the data's largest |value| would flatten it into a line
FAR = 20.0


def _mark(
    ax,
    span: float,
    limit=None,
    band=None,
    paper=None,
    statistic=None,
    bottom=None,
    log=False,
    at=None,
    paper_at=None,
    events=None,
    empty=None,
) -> None:
    """The marks of a panel (module docstring) whose series reach ``span`` at most.  A
    limit far above the data (:data:`FAR` times) would flatten it: on a non-negative
    quantity (``bottom=0``, an error) the axis turns logarithmic and shows both; a signed
    one keeps its scale, and the legend says the limit, off scale."""
    if band is not None:
        low, high, text = band
        ax.axhspan(low, high, color="tab:green", alpha=0.15, label=text)
    if limit is not None:
        value, text = limit
        values = value if isinstance(value, (tuple, list)) else (-value, value)
        far = 0 < span and min(abs(y) for y in values if y) > FAR * span
        if far and bottom == 0.0:  # three decades below the data's peak, and the limit
            log, bottom = True, span / 1e3
            values = [y for y in values if y > 0]
        elif far:
            ax.plot(
                [], [], color="tab:red", linestyle="--", linewidth=1, label=f"{text} (off scale)"
            )
            values = []
        for k, y in enumerate(values):
            ax.axhline(
                y, color="tab:red", linestyle="--", linewidth=1, label=text if k == 0 else None
            )
    if paper is not None:
        value, text = paper
        for k, y in enumerate(value if isinstance(value, (tuple, list)) else (value,)):
            ax.axhline(
                y, color="0.35", linestyle=":", linewidth=1.2, label=text if k == 0 else None
            )
    if statistic is not None:
        value, text = statistic
        ax.axhline(value, color="black", linestyle="-.", linewidth=1, label=text)
    if at is not None:
        ax.axvline(at[0], color="black", linestyle="-", linewidth=1, label=at[1])
    if paper_at is not None:
        ax.axvline(paper_at[0], color="0.35", linestyle=":", linewidth=1.2, label=paper_at[1])
    if events is not None:
        xs, text = events
        for k, x in enumerate(xs):
            ax.axvline(
                x, color="0.6", linestyle="-.", linewidth=0.7, label=text if k == 0 else None
            )
    if empty is not None:
        ax.axvspan(empty[0], empty[1], color="0.92", label=empty[2])
    if bottom is not None:
        ax.set_ylim(bottom=bottom)
    if log:
        ax.set_yscale("log")


def requirement(path: Path, title: str, x, rows, met, xlabel: str) -> Path:
    """Metrics against a design variable (log x), each with its requirement line; points
    that meet every requirement filled green, the others open red (legend says so)."""
    from matplotlib.lines import Line2D

    fig, axes = _subplots(len(rows))
    for ax, (label, values, limit) in zip(axes[:, 0], rows):
        ax.plot(x, values, color="0.6", linewidth=1)
        for xi, v, ok in zip(x, values, met):
            ax.plot(
                xi,
                v,
                "o",
                color="tab:green" if ok else "tab:red",
                fillstyle="full" if ok else "none",
            )
        line = ax.axhline(limit, color="tab:blue", linestyle="--")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(
            [
                line,
                Line2D([], [], marker="o", color="tab:green", linestyle=""),
                Line2D([], [], marker="o", color="tab:red", fillstyle="none", linestyle=""),
            ],
            ["requirement", "meets both requirements", "fails one or both"],
            fontsize=8,
        )
    return _save(fig, axes, path, title, xlabel)


def signals(
    path: Path, runs: dict, variables, deg: bool = False, instance: str | None = None
) -> Path:
    """Recorded variables (scalar columns or whole arrays by base name), one panel each,
    every run in ``runs`` ({label: Results}) overlaid (one line style per run); units from
    the results, angles in degrees with ``deg``; a Boolean's axis says false and true.
    With ``instance`` (all variables of that one), it is the title and the axes name the
    variables alone."""
    import numpy as np

    fig, axes = _subplots(len(variables), sharex=True)
    for ax, name in zip(axes[:, 0], variables):
        for k, (run, results) in enumerate(runs.items()):
            values = results.get(name, deg=deg).reshape(len(results), -1)
            locked = _near_gimbal_lock(results, name)
            if locked is not None:
                values = np.where(locked[:, None], np.nan, values)
                _shade(
                    ax,
                    results.time,
                    locked,
                    f"not shown: within {math.degrees(GIMBAL_LOCK_MARGIN):g}° of gimbal lock "
                    "(θ = ±90°)",
                )
            columns = results.columns(name)
            for column, v in zip(columns, values.T):
                element = _element(name, column, len(columns))
                ax.plot(
                    results.time,
                    v,
                    linewidth=1.4,
                    linestyle=_STYLES[k % len(_STYLES)],
                    label=f"{run} {element}".strip(),
                )
        unit = results.unit(name)
        if unit is None and all(set(np.unique(line.get_ydata())) <= {0, 1} for line in ax.lines):
            ax.set_yticks([0, 1], ["false", "true"])  # a Boolean (or a 0/1 flag)
            ax.set_ylim(-0.15, 1.15)
        ax.set_ylabel(
            unit_label(
                name.split(".", 1)[1] if instance else name, to_degrees(unit)[1] if deg else unit
            )
        )
        ax.grid(True, alpha=0.3)
        _legend(ax)
    return _save(fig, axes, path, instance or textwrap.fill(", ".join(variables), 90), "time [s]")


#: Euler rates within this of the 1-2-3 sequence's gimbal lock (θ = ±90°) are not drawn:
#: they grow as 1/cos θ and a pass near the lock would flatten the rest of the panel
GIMBAL_LOCK_MARGIN = math.radians(5.0)


def _near_gimbal_lock(results, name: str):
    """For Euler rates ("…euler_rate_XY", beside their angles "…euler_XY", 1-2-3): the
    rows within :data:`GIMBAL_LOCK_MARGIN` of θ = ±90°; None for any other variable."""
    import numpy as np

    instance, _, variable = name.rpartition(".")
    angles = f"{instance}.{variable.replace('euler_rate', 'euler', 1)}"
    if not variable.startswith("euler_rate") or angles not in results:
        return None
    theta = results.vector(angles)[:, 1]
    return np.abs(np.cos(theta)) < math.sin(GIMBAL_LOCK_MARGIN)


def _shade(ax, t, rows, text: str) -> None:
    """Grey spans over the runs of ``rows`` (a Boolean per sample), one legend entry."""
    import numpy as np

    edges = np.flatnonzero(np.diff(np.concatenate(([0], rows.astype(int), [0]))))
    for k, (first, end) in enumerate(zip(edges[::2], edges[1::2])):
        ax.axvspan(
            t[max(first - 1, 0)],
            t[min(end, len(t) - 1)],
            color="0.85",
            label=text if k == 0 else None,
        )


def _element(name: str, column: str, n: int) -> str:
    """A line's label: x, y, z for a 3-vector's elements, w, x, y, z for a quaternion's
    (scalar first), else the element's index ([2,3]); a scalar's name."""
    index = column[len(name) :]
    if not index:
        return name.split(".")[-1]
    axes = "wxyz" if n == 4 and name.split(".")[-1].startswith("q_") else "xyz" if n == 3 else ""
    return axes[int(index[1:-1]) - 1] if axes else index


def overview(results, out_dir) -> list[Path]:
    """Generic figures of any run: per instance, one panel per output variable."""
    by_instance: dict[str, list[str]] = {}
    for name in results.names[1:]:
        base = name.rsplit("[", 1)[0]
        variables = by_instance.setdefault(name.split(".")[0], [])
        if base not in variables:
            variables.append(base)
    paths = []
    for instance, variables in by_instance.items():
        paths.append(
            signals(
                Path(out_dir) / f"overview_{instance}.png",
                {"": results},
                variables,
                deg=True,  # angles in degrees, as people read them
                instance=instance,
            )
        )
    return paths


def _subplots(n: int, sharex: bool = False):
    """A figure (no pyplot: no global state) of ``n`` stacked axes, 8 in wide, at the
    PNG's resolution."""
    from cycler import cycler
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 1.2 + 2.6 * n), dpi=DPI, layout="none")  # whatever rcParams say
    axes = fig.subplots(n, 1, squeeze=False, sharex=sharex)
    for ax in axes[:, 0]:
        ax.set_prop_cycle(cycler(color=SERIES_COLOURS))
    return fig, axes


def _save(fig, axes, path: Path, title: str, xlabel: str, title_pad=None, title_size=None) -> Path:
    """Label the stacked axes, lay them out once (:mod:`.figure_layout`), write the PNG
    from that one Agg drawing and each other format with its own renderer."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.image import imsave

    watched = _drawing.get()
    if watched is not None and watched[1] is not None:
        watched[1](formats(path))
    axes[-1, 0].set_xlabel(xlabel)
    size = {} if title_size is None else {"fontsize": title_size}
    axes[0, 0].set_title(title, pad=title_pad, **size)  # above the phases' names, if any
    figure_layout.fixed(fig, axes, title)
    canvas = FigureCanvasAgg(fig)
    figure_layout.draw(fig, axes, canvas)
    png, *others = formats(path)
    with atomically(png) as temporary:  # a full disk: an error naming the file, no half PNG
        imsave(temporary, canvas.buffer_rgba(), format="png", origin="upper", dpi=fig.dpi)
    for target in others:
        with atomically(target) as temporary:
            fig.savefig(temporary, dpi=DPI, format=Path(target).suffix[1:])
    if watched is not None:
        watched[0].extend([png, *others])
    if _figure_objects.get() is not None:
        _figure_objects.get()[Path(path).name] = fig
    return Path(path)


def __getattr__(name):
    if name == "plt":  # pyplot for callers that use it (campaign reports), on first use
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot

        return matplotlib.pyplot
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
