"""A campaign's kept signals (``signals.npy``: (runs, signals, points), NaN where a run was
not made or stopped early, :mod:`..campaign.engine`) and the runs of them that reached the
end, the only ones a statistic over the campaign is taken of (the others are left out,
and said)."""

from __future__ import annotations

import numpy as np


def reached_the_end(signals: np.ndarray) -> np.ndarray:
    """Which runs of ``signals`` (runs, signals, points) reached the end: a boolean per
    run, true where every kept value of the run is finite."""
    return np.isfinite(signals).all(axis=(1, 2))
