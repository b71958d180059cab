"""A campaign pointing figure's curve of more values than pixel columns is thinned: the
staircase through the kept points is the full one at every slice's end, and its tail from
the level's quantile on is every value (the quantile: numpy's inverted-CDF one, the
⌈P n⌉-th smallest)."""

from types import SimpleNamespace

import numpy as np

from agilesat.orchestration.campaign import pointing_figures, report
from agilesat.orchestration.campaign.pointing_figures import step_points
from agilesat.orchestration.pointing import ANGLE_UNITS


def fraction_above(n):
    return (n - 1 - np.arange(n)) / n


def step(x, y, at):
    """A step curve (where='post') through (x, y) read at ``at`` (1 before its first x)."""
    i = np.searchsorted(x, at, side="right") - 1
    return np.where(i >= 0, y[np.maximum(i, 0)], 1.0)


def test_a_curve_no_longer_than_the_columns_keeps_every_point():
    x = np.sort(np.random.default_rng(0).random(50))
    assert np.array_equal(step_points(x, fraction_above(50), 0.01, columns=50), np.arange(50))


def test_a_thinned_staircase_is_the_full_one_at_each_slice_end_and_in_its_tail():
    """Integer values 0..999 in 10 slices of width 100: read just before each slice's end
    (99.5, 199.5, ...) both curves hold the value of the last value at or below."""
    rng = np.random.default_rng(1)
    x = np.sort(rng.integers(0, 1000, 20_000)).astype(float)
    x[-1] = 1000.0  # the range [0, 1000]: slices [0, 100), [100, 200), ...
    y = fraction_above(len(x))
    kept = step_points(x, y, 0.01, columns=10)
    assert len(kept) < 300
    ends = np.arange(10) * 100 + 99.5
    assert np.array_equal(step(x[kept], y[kept], ends), step(x, y, ends))
    quantile = np.quantile(x, 0.99, method="inverted_cdf")
    every = np.unique(np.r_[x[x >= quantile], quantile - 0.5])
    assert np.array_equal(step(x[kept], y[kept], every), step(x, y, every))


def test_a_mixed_figure_of_many_values_draws_fewer_points_and_the_exact_quantile_step(
    monkeypatch,
):
    """20 000 values, more than the (here 200) columns: the curve drawn is shorter, and
    where it first reaches 1 − 0.9973 or below is the 0.9973 quantile of the values."""
    monkeypatch.setattr(pointing_figures, "COLUMNS", 200)
    saved = []
    monkeypatch.setattr(report, "_save", lambda fig, ax, path: saved.append(ax) or path)
    x = np.radians(np.random.default_rng(2).lognormal(size=20_000))
    r = SimpleNamespace(level=0.9973, bound=0.5)
    quantile = float(np.quantile(x, 0.9973, method="inverted_cdf"))
    verdict = {"value": quantile, "estimate": quantile}
    pointing_figures.distribution(None, "title", r, verdict, x, "values")
    x, quantile = x / ANGLE_UNITS["deg"], quantile / ANGLE_UNITS["deg"]  # as drawn
    [ax] = saved
    curve = ax.lines[0]
    xs, ys = curve.get_xdata(), curve.get_ydata()
    assert len(xs) < len(x) / 10 and curve.get_label() == "20000 values"
    first = int(np.argmax(ys <= 1 - 0.9973))
    assert xs[first] == quantile and ys[first - 1] > 1 - 0.9973
    assert np.array_equal(xs[first:], np.sort(x)[-len(xs) + first :])
