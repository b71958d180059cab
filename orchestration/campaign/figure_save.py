"""A campaign figure (one axes: a histogram, a sweep, an envelope, a pointing distribution)
laid out and drawn once, then written as a PNG from that drawing.

``fig.tight_layout()`` then ``fig.savefig`` drew each figure three times over: the tight
layout measures every tick and text, and a figure laid out tight keeps a layout engine,
for which savefig makes a dry drawing before the real one.  Here the margins are those
the texts around the axes need, in inches (:func:`margins`):

- top: the title's height (its lines measured) + ``pad``;
- right: ``pad``, or where the legend stands beside the axes (anchored at x ≥ 1 of them,
  the campaign figures' habit) its width + the gap to it + ``pad``;
- left, bottom: :data:`MARGINS` (y tick labels of up to ~6 characters with their label,
  one line of x tick labels with theirs).

Only the title and the legend are measured (their sizes are kept by matplotlib's text
cache, which the drawing reuses); the tick labels are not.  The figure is drawn once and
checked (:func:`.figure_layout.draw`): where a text falls outside the figure or on the
axes, it is laid out tight and drawn again, as before: no text clipped either way.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..output import figure_layout
from ..output.recorder import atomically

#: fixed margins [in] of the sides whose texts are not measured, and the space [in] kept
#: beyond the measured ones (~ the tight layout's pad, 1.08 × 10 pt)
MARGINS = {"left": 0.85, "bottom": 0.55, "pad": 0.15, "title_gap": 0.1}


def margins(fig, ax, renderer) -> dict:
    """The subplot parameters (figure fractions) leaving the title and a legend beside
    the axes room (module)."""
    width, height = fig.get_size_inches()
    dpi = fig.dpi
    pad = MARGINS["pad"]
    title = ax.title
    top = pad
    if title.get_visible() and title.get_text():
        top += title.get_window_extent(renderer).height / dpi + MARGINS["title_gap"]
    right = pad
    legend = ax.get_legend()
    if legend is not None and legend.get_visible() and _beside(legend):
        anchor = legend.get_bbox_to_anchor()
        axes_width = width - MARGINS["left"]  # the anchor's offset scales with the axes
        offset = (anchor.x0 - ax.bbox.x1) / ax.bbox.width if ax.bbox.width else 0.0
        box = legend.get_window_extent(renderer).width / dpi
        right += box + max(offset, 0.0) * axes_width + legend.borderaxespad * legend._fontsize / 72
        right = min(right, 0.5 * width)  # a legend wider than that: the tight layout's turn
    return {
        "left": MARGINS["left"] / width,
        "right": 1 - right / width,
        "bottom": MARGINS["bottom"] / height,
        "top": 1 - top / height,
    }


def _beside(legend) -> bool:
    """True if ``legend`` is anchored right of its axes (x ≥ 1 in their coordinates)."""
    anchor = legend.get_bbox_to_anchor()
    axes = legend.axes.bbox
    return anchor.x0 >= axes.x1 - 1e-9 * max(axes.width, 1.0)


def save(fig, ax, path: Path, dpi: float) -> Path:
    """``fig`` (one axes ``ax``) laid out (module), drawn once at ``dpi`` and written as a
    PNG, its title also in the PNG's "Title"."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.image import imsave

    fig.set_dpi(dpi)
    canvas = FigureCanvasAgg(fig)
    fig.set_layout_engine("none")  # laid out here (None would read rcParams again)
    fig.subplots_adjust(**margins(fig, ax, canvas.get_renderer()))
    figure_layout.draw(fig, np.array([[ax]]), canvas)
    with atomically(path) as temporary:  # an error naming the file, no half PNG
        imsave(
            temporary,
            canvas.buffer_rgba(),
            format=Path(path).suffix[1:],
            origin="upper",
            dpi=fig.dpi,
            metadata={"Title": ax.get_title()},
        )
    return Path(path)
