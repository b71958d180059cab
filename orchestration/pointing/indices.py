"""The ECSS-E-ST-60-10C error indices of error histories (pure NumPy).

Definitions ([Ecss 2008] §3.2, the terms of the standard; e(t) the performance error
e_P or the knowledge error e_K, ē(Δt) = (1/Δt) ∫_Δt e(t) dt its mean over a window Δt):

======  ======  ===========================================================================
perf.   knowl.  definition
======  ======  ===========================================================================
APE     AKE     absolute error: e(t), the instantaneous error
MPE     MKE     mean error: ē(Δt), the mean over a window Δt
RPE     RKE     relative error: e(t) − ē(Δt), t ∈ Δt, the instantaneous error about the mean
                of a window containing t (the definition's note leaves the relation of t to
                Δt to the requirement, e.g. "t random in Δt" or "t at the end of Δt", and
                refers to Annex A.1.4)
PDE     KDE     drift error: ē(Δt₂) − ē(Δt₁), the difference of the means of two windows in
                one observation period, Δt₂ starting Δt_s after Δt₁
PRE     KRE     reproducibility error: the same difference, the windows in different
                observation periods (§3.2 notes the two definitions are identical; PRE
                quantifies how well an observation repeats later)
======  ======  ===========================================================================

On samples ``e_i`` at ``t_i = t_0 + i T``, a window of duration Δt = N T holds the N + 1
samples ``t_{j}..t_{j+N}``; its mean is the trapezoid rule, ``ē = (e_j/2 + e_{j+1} + … +
e_{j+N}/2)/N``, the integral's discretisation with an O(T²) error on sampled continuous
signals.  Every window lies inside the record.  Index values carry times:

- APE: every sample; MPE and RPE (t at the window's end): the window's end ``t_{j+N}``;
- RPE with t random in the window: each sample ``t_i`` whose every window lies in the
  record (``N ≤ i ≤ n − 1 − N``), with a window drawn for it at random: its start
  ``j = i − m``, ``m ∈ {0..N}`` drawn with the trapezoid weights (½, 1, …, 1, ½)/N, the
  discrete form of t uniform in Δt (a seeded generator: the draw is reproducible);
- PDE, PRE: the end of the second window.

The index of a rotation-vector error is a vector (the same linear operation on each
component); :func:`magnitude` is what a bound applies to: ``|x|`` for a scalar, the norm
for a vector (the 3-axis angle, or the half-cone angle of a line of sight).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import ErrorHistory
from .names import INDICES, T_IN_WINDOW


class NotEvaluable(ValueError):
    """The data cannot answer: a record shorter than the windows, no run, or (for a bound
    at a confidence, :func:`.statistics.statistic`) a campaign too small to show any."""


@dataclass(frozen=True, eq=False)
class IndexSeries:
    """Index values ``values[run, k, component]`` at times ``t[k]`` (s)."""

    index: str
    values: np.ndarray
    t: np.ndarray


def check_index(
    index: str, window: float | None, separation: float | None, t_in_window: str
) -> tuple[str, str]:
    """(operation, kind) of ``index``, once its arguments are those it takes."""
    if index not in INDICES:
        raise ValueError(f"unknown index {index!r}: expected one of {', '.join(INDICES)}")
    operation, kind = INDICES[index]
    for name, value, wanted in (
        ("window", window, operation != "absolute"),
        ("separation", separation, operation == "drift"),
    ):
        if wanted and (value is None or not value > 0.0):
            raise ValueError(f"{index} needs a {name} > 0 s, got {value}")
        if not wanted and value is not None:
            raise ValueError(f"{index} takes no {name}")
    if t_in_window not in T_IN_WINDOW:
        raise ValueError(f"t_in_window {t_in_window!r}: expected one of {T_IN_WINDOW}")
    if t_in_window != "end" and operation != "relative":
        raise ValueError("t_in_window is the relation of t to the window of RPE/RKE only")
    return operation, kind


def samples_in(duration: float, dt: float, name: str) -> int:
    """``duration`` as a whole number (≥ 1) of sample periods ``dt``."""
    count = round(duration / dt)
    if count < 1 or abs(count * dt - duration) > 1e-6 * dt:
        raise ValueError(f"{name} = {duration} s is not a whole number of samples of {dt} s")
    return count


def window_means(values: np.ndarray, n: int) -> np.ndarray:
    """Trapezoid means of every window of ``n`` sample periods along axis 1."""
    offset = values.mean(axis=1, keepdims=True)  # sums of small deviations: no cancellation
    v = values - offset
    sums = np.cumsum(v, axis=1)
    sums = np.concatenate((np.zeros_like(sums[:, :1]), sums), axis=1)
    inner = sums[:, n + 1 :] - sums[:, : -n - 1]  # e_j + … + e_{j+n}
    return offset + (inner - 0.5 * (v[:, :-n] + v[:, n:])) / n


def index_series(
    error: ErrorHistory,
    index: str,
    window: float | None = None,
    separation: float | None = None,
    t_in_window: str = "end",
    seed: int | np.random.Generator = 0,
) -> IndexSeries:
    """The values of ``index`` over the record (see the module's docstring).

    ``window`` is Δt (s) for every index but APE/AKE; ``separation`` is Δt_s (s), the
    time from the start of the first window to the start of the second, for PDE/PRE/KDE/KRE;
    ``t_in_window`` ("end" or "random") for RPE/RKE; ``seed`` (or a generator, whose
    stream the draw continues) draws the random positions, run after run.
    """
    operation, kind = check_index(index, window, separation, t_in_window)
    if error.kind != kind:
        raise ValueError(
            f"{index} is a {kind} index: it needs the {kind} error "
            f"({'estimate vs truth' if kind == 'knowledge' else 'truth vs reference'}), "
            f"not a {error.kind} error"
        )
    e, t = error.values, error.t
    if operation == "absolute":
        return IndexSeries(index, e, t)
    assert window is not None
    n = samples_in(window, error.dt, "window Δt")
    shift = 0 if separation is None else samples_in(separation, error.dt, "separation Δt_s")
    needed = n + shift  # sample periods of record that one index value takes
    if operation == "relative" and t_in_window == "random":
        needed = 2 * n
    if t.size <= needed:
        raise NotEvaluable(
            f"{index}: the record ({t[-1] - t[0]:g} s) is too short for its windows "
            f"({needed * error.dt:g} s)"
        )
    means = window_means(e, n)  # means[:, j]: the window t_j..t_{j+n}
    if operation == "mean":
        return IndexSeries(index, means, t[n:])
    if operation == "drift":
        return IndexSeries(index, means[:, shift:] - means[:, :-shift], t[n + shift :])
    if t_in_window == "end":
        return IndexSeries(index, e[:, n:] - means, t[n:])
    samples = np.arange(n, t.size - n)
    rng = np.random.default_rng(seed)
    starts = samples - rng.choice(n + 1, size=(e.shape[0], samples.size), p=position_weights(n))
    drawn = np.take_along_axis(means, starts[..., None], axis=1)
    return IndexSeries(index, e[:, samples] - drawn, t[samples])


def position_weights(n: int) -> np.ndarray:
    """The weights (½, 1, …, 1, ½)/n of the n + 1 positions of a window of n sample
    periods around a time: the discrete form of t uniform in Δt."""
    weights = np.ones(n + 1) / n
    weights[[0, -1]] = 0.5 / n
    return weights


def window_positions(error: ErrorHistory, index: str, window: float) -> IndexSeries:
    """RPE/RKE with t random in Δt, exactly: ``values[run, k, m, component]`` = e_i −
    ē(the window starting at t_{i − m}), m = 0 … N, at each sample t_i = ``t[k]`` whose
    every window lies in the record; position m weighs :func:`position_weights` (N)[m].
    The mixture over the positions is the index's distribution at t_i: what a single draw
    per time (:func:`index_series`) samples."""
    operation, _ = check_index(index, window, None, "random")
    if operation != "relative":
        raise ValueError(f"{index}: window positions are those of RPE/RKE only")
    n = samples_in(window, error.dt, "window Δt")
    e, t = error.values, error.t
    if t.size <= 2 * n:
        raise NotEvaluable(
            f"{index}: the record ({t[-1] - t[0]:g} s) is too short for its windows "
            f"({2 * n * error.dt:g} s)"
        )
    means = window_means(e, n)
    samples = np.arange(n, t.size - n)
    starts = samples[:, None] - np.arange(n + 1)  # (k, m)
    return IndexSeries(index, e[:, samples, None] - means[:, starts], t[samples])


def magnitude(series: IndexSeries) -> np.ndarray:
    """``(runs, times)``: |x| of a scalar index, the norm of a vector one."""
    return np.linalg.norm(series.values, axis=-1)
