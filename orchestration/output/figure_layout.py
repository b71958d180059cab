"""Stacked axes laid out with fixed margins where they fit, else with the tight layout.

matplotlib's tight layout measures every axes' ticks and labels before a figure is drawn:
a pass over the artists that takes ~18 % of drawing our figures as PNGs (measured: README,
"First-run latency").  Our figures are stacked axes 8 in wide under one title, and fixed
margins (:data:`MARGINS`, the tight layout's own for most of them) fit nearly all of them.
So a figure is laid out with those (:func:`fixed`), drawn (:func:`draw`), and checked:
every text, and each legend, lies inside the figure and clear of the other axes and of
their texts.  Only where one does not is the figure laid out tight and drawn again, as
before: no text clipped or overlapping either way.  The check costs a few percent of a
drawing (the texts' sizes are those the drawing measured; only the tick locations are
asked for again).
"""

from __future__ import annotations

import itertools

#: fixed margins [in]: figure edges, and the gap between two axes (with and without x tick
#: labels of their own); a title's extra lines add ``title_line`` each at the top
MARGINS = {
    "left": 0.9,
    "right": 0.15,
    "bottom": 0.59,
    "top": 0.36,
    "title_line": 0.17,
    "gap": 0.40,
    "gap_shared": 0.22,
}


def fixed(fig, axes, title: str) -> None:
    """Lay the stacked ``axes`` (an n × 1 array) out with :data:`MARGINS`."""
    width, height = fig.get_size_inches()
    n = len(axes)
    shared = n > 1 and axes[0, 0].get_shared_x_axes().joined(axes[0, 0], axes[1, 0])
    gap = MARGINS["gap_shared" if shared else "gap"]
    top = MARGINS["top"] + MARGINS["title_line"] * title.count("\n")
    axes_height = (height - top - MARGINS["bottom"] - (n - 1) * gap) / n
    fig.subplots_adjust(
        left=MARGINS["left"] / width,
        right=1 - MARGINS["right"] / width,
        bottom=MARGINS["bottom"] / height,
        top=1 - top / height,
        hspace=gap / axes_height,
    )


def draw(fig, axes, canvas) -> bool:
    """Draw ``fig`` on ``canvas`` (Agg) as laid out; if a text falls outside the figure or
    on other axes, lay it out tight and draw it again.  True if it fitted."""
    canvas.draw()
    if _fits(fig, axes, canvas.get_renderer()):
        return True
    fig.tight_layout()
    fig.set_layout_engine("none")  # laid out once (None would read rcParams again)
    canvas.draw()
    return False


def _texts(ax) -> list:
    """The texts drawn around ``ax``: title, axis labels and offsets, the tick labels
    inside its view (as the drawing placed them; ticks a locator gives beyond the view
    are not drawn) and its legend (checked whole: a legend may not reach other axes)."""
    texts = [ax.title, *ax.texts]
    for axis in (ax.xaxis, ax.yaxis):
        texts += [axis.label, axis.offsetText]
        low, high = sorted(axis.get_view_interval())
        slack = 1e-10 * (high - low)  # matplotlib's own, drawing a tick at the view's edge
        for locs, ticks in (
            (axis.get_majorticklocs(), axis.get_major_ticks),
            (axis.get_minorticklocs(), axis.get_minor_ticks),
        ):
            for loc, tick in zip(locs, ticks(len(locs))):
                if low - slack <= loc <= high + slack:
                    texts += [tick.label1, tick.label2]
    texts = [t for t in texts if t.get_visible() and t.get_text()]
    legend = ax.get_legend()
    return texts if legend is None or not legend.get_visible() else [*texts, legend]


def _fits(fig, axes, renderer) -> bool:
    if fig.legends or fig.texts:  # figure-level artists: left to the tight layout
        return False
    placed = [(ax, t.get_window_extent(renderer)) for ax in axes[:, 0] for t in _texts(ax)]
    edge = fig.bbox.padded(1.0)  # a pixel of rounding is no clipping
    for ax, box in placed:
        if not (edge.x0 <= box.x0 and box.x1 <= edge.x1 and edge.y0 <= box.y0 <= box.y1 <= edge.y1):
            return False
        if any(other is not ax and box.overlaps(other.bbox) for other in axes[:, 0]):
            return False
    return not any(
        a is not b and p.overlaps(q) for (a, p), (b, q) in itertools.combinations(placed, 2)
    )
