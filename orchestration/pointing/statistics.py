"""An index at a probability level under a statistical interpretation, and the confidence
of a statistic over the runs from order statistics.

A requirement states a bound that the index's magnitude keeps with probability P.  The
probability is over time, over the statistical ensemble (the runs), or both: the standard's
three statistical interpretations ([Ecss 2008], detailed in [Esa 2011]):

- temporal: for each run, the fraction P of its time; the worst run is the statistic
  (profile: one value per run);
- ensemble: at each time, the fraction P of the runs; the worst time is the statistic
  (profile: one value per time);
- mixed: the fraction P of all (run, time) samples together (no profile).

The empirical P-quantile of n values is the ⌈P n⌉-th smallest: the smallest value that at
least a fraction P of the values do not exceed.

Confidence (over the runs: the n values of an ensemble statistic at one time come from n
independent runs; the samples of one run in time are correlated and give no such
statement).  If k of n runs may exceed a value X, X is the (n − k)-th smallest of the n;
it bounds the true P-quantile with probability Pr[Bin(n, 1 − P) > k] ([Wilks 1941]).  The
bound :func:`statistic` gives with a confidence takes the most runs k that the verdicts'
anytime-valid test allows above it (:func:`supported`, :mod:`.verdicts`); a design fixed
in advance, looked at once, may allow more:

- its bound at P with confidence C is the (n − k)-th smallest value with k the largest
  count such that Pr[Bin(n, 1 − P) ≤ k] ≤ 1 − C (:func:`allowed_exceedances`);
- the runs needed with k runs allowed above the bound: the smallest n with
  Pr[Bin(n, 1 − P) ≤ k] = Σ_{i≤k} C(n, i) (1 − P)^i P^(n−i) ≤ 1 − C; for k = 0,
  P^n ≤ 1 − C, n = ⌈ln(1 − C)/ln P⌉: 1109 runs for 99.73 % with 95 % confidence;
- the confidence a campaign achieves for a bound that k of its n runs exceed:
  C = Pr[Bin(n, 1 − P) > k], the level at which the one-sided Clopper-Pearson lower limit
  of the fraction within the bound is exactly P ([Clopper 1934]).

At the worst time the statement holds for that time; the maximum over time of the per-time
bounds is at least the bound at the true worst time, so it keeps the confidence.

The binomial tails are the regularised incomplete beta function (Abramowitz & Stegun 26.5.24):
Pr[Bin(n, q) ≤ k] = 1 − I_q(k + 1, n − k), Pr[Bin(n, q) > k] = I_q(k + 1, n − k) for k < n
(``scipy.special.betaincc``/``betainc``, what SciPy's binomial distribution evaluates; not
``scipy.stats``, whose import would be a large part of a campaign worker's start).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.special import betainc, betaincc  # type: ignore[import-untyped]

from .indices import NotEvaluable
from .names import INTERPRETATIONS

#: relative slack on Pr[...] ≤ 1 − C, so that a case exact in real numbers (0.5² ≤ 0.25)
#: is not lost to rounding
_ROUNDING = 1e-12


def check_probability(value: float, name: str) -> None:
    if not 0.0 < value < 1.0:
        raise ValueError(f"{name} must be a probability strictly between 0 and 1, got {value}")


def check_statistic(level: float, interpretation: str, confidence: float | None) -> None:
    check_probability(level, "level")
    if interpretation not in INTERPRETATIONS:
        raise ValueError(f"interpretation {interpretation!r}: expected one of {INTERPRETATIONS}")
    if confidence is not None:
        check_probability(confidence, "confidence")
        if interpretation == "temporal":
            raise ValueError(
                "a confidence needs the ensemble or mixed interpretation (a probability "
                "over independent runs); the temporal one holds each run to the level over "
                "its own time, whose samples are correlated: a run above the bound is a "
                "violation, and no number of runs shows that none would be"
            )


def percent(p: float) -> str:
    return f"{100 * p:.6g} %"


def quantile_rank(count: int, level: float) -> int:
    """0-based rank of the empirical ``level``-quantile of ``count`` values: ⌈P n⌉ − 1."""
    return max(0, math.ceil(level * count - 1e-9) - 1)


def order_statistic(x: np.ndarray, rank: int, axis: int | None) -> np.ndarray:
    """The ``rank``-th smallest (0-based) along ``axis`` (all values if None)."""
    if axis is None:
        x, axis = x.ravel(), 0
    return np.take(np.partition(x, rank, axis=axis), rank, axis=axis)


def upper_value(m: np.ndarray, above: float, axis: int | None, weights=None):
    """The smallest value of ``m`` along ``axis`` (None: all of it) that has at most
    ``above`` of the values' weight above it: with each value weighing 1, the (n − k)-th
    smallest, k = ⌊above⌋.  ``weights``: of ``m``'s last axis (window positions, each
    (run, time) weighing 1 in all), which is reduced too."""
    if weights is None:
        count = m.size if axis is None else m.shape[axis]
        k = min(count - 1, math.floor(above + 1e-9))
        return order_statistic(m, count - 1 - k, axis)
    if axis is None:
        values = m.reshape(1, -1)
    else:
        values = np.moveaxis(m, axis, -2)
        values = values.reshape(values.shape[:-2] + (-1,))
    w = np.tile(weights, values.shape[-1] // len(weights))
    order = np.argsort(values, axis=-1)
    tail = w.sum() - np.cumsum(w[order], axis=-1)  # the weight after each sorted value
    first = np.argmax(tail <= above + 1e-9 * max(1.0, above), axis=-1)
    sorted_values = np.take_along_axis(values, order, axis=-1)
    result = np.take_along_axis(sorted_values, first[..., None], axis=-1)[..., 0]
    return float(result[0]) if axis is None else result


def _exceeds_at_most(k: int, runs: int, level: float) -> float:
    """Pr[Bin(runs, 1 − level) ≤ k] = 1 − I_(1 − level)(k + 1, runs − k)."""
    return 1.0 if k >= runs else float(betaincc(k + 1, runs - k, 1.0 - level))


@functools.cache  # every run's verdict asks it again (a bisection of ~40 binomial CDFs)
def runs_needed(level: float, confidence: float, exceedances: int = 0) -> int:
    """The fewest runs whose (n − k)-th smallest value bounds the ``level``-quantile with
    ``confidence``, k = ``exceedances`` runs allowed above it."""
    check_probability(level, "level")
    check_probability(confidence, "confidence")
    if exceedances < 0:
        raise ValueError(f"exceedances must be ≥ 0, got {exceedances}")
    limit = (1.0 - confidence) * (1.0 + _ROUNDING)

    def enough(n: int) -> bool:
        return _exceeds_at_most(exceedances, n, level) <= limit

    low, high = exceedances, exceedances + 1  # low: too few (n = k cannot do)
    while not enough(high):
        low, high = high, 2 * high
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (low, middle) if enough(middle) else (middle, high)
    return high


def allowed_exceedances(runs: int, level: float, confidence: float) -> int:
    """The most runs that may exceed the bound a campaign of ``runs`` supports at ``level``
    with ``confidence``; :class:`NotEvaluable` if even none is too many."""
    check_probability(level, "level")
    check_probability(confidence, "confidence")
    limit = (1.0 - confidence) * (1.0 + _ROUNDING)
    if runs < 1 or _exceeds_at_most(0, runs, level) > limit:
        raise NotEvaluable(
            f"the campaign is too small: a bound at {percent(level)} with "
            f"{percent(confidence)} confidence needs at least "
            f"{runs_needed(level, confidence)} runs (none above it); it has {runs}"
        )
    low, high = 0, runs  # Pr[... ≤ low] ≤ limit < Pr[... ≤ high] = 1
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (
            (middle, high) if _exceeds_at_most(middle, runs, level) <= limit else (low, middle)
        )
    return low


def supported(runs: int, level: float, confidence: float, whole: bool = True):
    """The most runs (their weight: ``whole`` False) that may lie above a bound a campaign
    of ``runs`` shows at ``level`` with ``confidence`` by the anytime-valid test of
    :mod:`.verdicts`; :class:`NotEvaluable` if even none may (fewer runs than
    :func:`runs_needed`)."""
    from .verdicts import allowed_above

    allowed = allowed_above(runs, level, confidence)
    if allowed is None:
        raise NotEvaluable(
            f"the campaign is too small: a bound at {percent(level)} with "
            f"{percent(confidence)} confidence needs at least "
            f"{runs_needed(level, confidence)} runs (none above it); it has {runs}"
        )
    return math.floor(allowed + 1e-9) if whole else allowed


def confidence_achieved(runs: int, exceedances: int, level: float) -> float:
    """Pr[Bin(runs, 1 − level) > exceedances]: the confidence that at least ``level`` of the
    ensemble is within a bound that ``exceedances`` of ``runs`` runs exceed."""
    check_probability(level, "level")
    if exceedances >= runs:
        return 0.0
    return float(betainc(exceedances + 1, runs - exceedances, 1.0 - level))


@dataclass(frozen=True, eq=False)
class Statistic:
    """An index's magnitude at ``level`` under ``interpretation``.

    ``value`` is the worst case of ``profile`` (per run for temporal, per time for
    ensemble, none for mixed): the empirical quantile, or with ``confidence`` the order
    statistic that bounds it (``allowed`` runs may exceed it).  ``estimate`` is the worst
    case of the empirical quantile either way; ``worst`` the run or time index of ``value``.
    """

    interpretation: str
    level: float
    value: float
    estimate: float
    profile: np.ndarray | None
    worst: int | None
    confidence: float | None = None
    allowed: int | None = None


def quantile(m: np.ndarray, level: float, axis: int | None, weights=None):
    """The empirical ``level``-quantile of ``m`` along ``axis`` (None: all): the ⌈P n⌉-th
    smallest; with ``weights`` of a last axis of positions, the smallest value with at
    most 1 − P of the weight above it."""
    if weights is None:
        count = m.size if axis is None else m.shape[axis]
        return order_statistic(m, quantile_rank(count, level), axis)
    count = m[..., 0].size if axis is None else m.shape[axis]
    return upper_value(m, count * (1.0 - level), axis, weights)


def statistic(
    magnitudes: np.ndarray,
    level: float,
    interpretation: str,
    confidence: float | None = None,
    weights=None,
) -> Statistic:
    """The statistic of ``magnitudes[run, time]`` (see the module's docstring);
    ``magnitudes[run, time, position]`` with the ``weights`` of the positions (t random in
    the window: the exact mixture)."""
    check_statistic(level, interpretation, confidence)
    m = np.asarray(magnitudes, dtype=float)
    if m.ndim != 2 + (weights is not None) or m.size == 0:
        raise ValueError(f"magnitudes: expected a non-empty (runs, times) array, got {m.shape}")
    runs = m.shape[0]
    if interpretation == "mixed":
        value = float(quantile(m, level, None, weights))
        return Statistic(interpretation, level, value, value, None, None)
    axis = 1 if interpretation == "temporal" else 0
    estimates = quantile(m, level, axis, weights)
    profile, allowed = estimates, None
    if confidence is not None:
        allowed = supported(runs, level, confidence, whole=weights is None)
        profile = upper_value(m, allowed, 0, weights)
    worst = int(np.argmax(profile))
    return Statistic(
        interpretation,
        level,
        float(profile[worst]),
        float(estimates.max()),
        profile,
        worst,
        confidence,
        allowed,
    )
