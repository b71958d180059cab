"""``agilesat report DIR``: one self-contained, interactive HTML page of a run or a
campaign (docs/running.md, "The report"), written with plotly (its JavaScript inlined:
opened from disk, offline).

- a run (:mod:`.run_page`): what ran, the headline numbers beside the paper's with the
  verdicts, the 3-D view (:mod:`.scene`), the bounded signals and pointing indices, every
  output;
- a campaign (:mod:`.campaign_page`): pass rates, statistics, histograms, envelopes, the
  per-run table.

Series are thinned for display with each bucket's extremes kept (:mod:`.decimate`).
"""

from __future__ import annotations

from pathlib import Path

from ...output.recorder import write_text

#: the page's file name in the directory
NAME = "report.html"


def write_report(directory, out=None) -> Path:
    """Write the report of the run or campaign in ``directory`` to ``out`` (default
    ``directory/report.html``); returns its path."""
    directory = Path(directory)
    if (directory / "campaign.json").exists():
        from . import campaign_page

        page = campaign_page.build(directory)
    else:
        from ..run_directory import RunDirectory
        from . import run_page

        page = run_page.build(RunDirectory(directory))
    path = Path(out) if out is not None else directory / NAME
    write_text(path, page.html())
    return path
