"""Series thinned for display with their extremes kept.

A series of n samples drawn as a line a thousand pixels wide needs a few thousand points,
but a line that skips samples hides the spikes an engineer looks for.  :func:`min_max`
splits the samples into ``buckets`` runs of consecutive samples and keeps, of each, the
sample with the smallest and the one with the largest value, in time order (and the first
and last samples): every extreme wider than a bucket is drawn at its true height, and no
value is drawn that the series does not take.  A NaN (a sample not taken) stays a gap: the
first NaN of each run of them is kept.
"""

from __future__ import annotations

import numpy as np


def indices(values, buckets: int) -> np.ndarray:
    """The sample indices :func:`min_max` keeps of ``values`` (n,), or of the columns of
    ``values`` (n, k) together (the union of each column's: one time axis for all)."""
    values = np.asarray(values, dtype=float)
    n = len(values)
    if n <= 2 * buckets + 2:
        return np.arange(n)
    starts = np.linspace(0, n, buckets + 1).astype(int)[:-1]
    bucket = np.repeat(np.arange(buckets), np.diff(np.r_[starts, n]))
    keep = [np.array([0, n - 1])]
    for column in values.reshape(n, -1).T:
        nan = np.isnan(column)
        for fill, reduce in ((np.inf, np.minimum), (-np.inf, np.maximum)):
            filled = np.where(nan, fill, column)
            extreme = reduce.reduceat(filled, starts)
            hits = np.flatnonzero((filled == extreme[bucket]) & ~nan)
            keep.append(hits[np.r_[True, bucket[hits][1:] != bucket[hits][:-1]]])
        keep.append(np.flatnonzero(nan & ~np.r_[False, nan[:-1]]))
    return np.unique(np.concatenate(keep))


def min_max(t, values, buckets: int = 1000) -> tuple[np.ndarray, np.ndarray]:
    """(t, values) thinned to at most 2 ``buckets`` + 2 samples per column (module);
    ``values`` (n,) or (n, k) on one time axis ``t`` (n,)."""
    keep = indices(values, buckets)
    return np.asarray(t)[keep], np.asarray(values)[keep]
