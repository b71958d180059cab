"""Met, not met or undecided: a requirement at a confidence, by anytime-valid tests.

A requirement at level P with confidence C states that the probability of the index
exceeding its bound is at most q = 1 − P.  A campaign's runs are independent; for each run
i, x_i ∈ [0, 1] says how much of it lies above the bound: an ensemble requirement, at one
time, 1 if the run is above it (or, t random in Δt, the share of the window's positions
that are); a mixed one, the run's share of its time.  E[x] is the exceedance probability
p.  Two tests at risk α = 1 − C:

- **met** (compliance shown): the hypothesis p ≥ q is rejected;
- **not met** (violation shown): the hypothesis p ≤ q is rejected;
- **undecided**: neither.

Both are e-processes, capital processes of bets against their hypothesis ([Ville 1939],
[Ramdas 2023]): a bet λ on x below q pays 1 + λ (q − x) per run, a bet on x above q
1 + λ (x − q); while the hypothesis holds each factor has mean ≤ 1, so the product over
the runs, mixed over bets, is a non-negative supermartingale and by Ville's inequality
Pr[sup_n E_n ≥ 1/α] ≤ α.  A test that rejects when E ≥ 1/α keeps its risk whenever it is
looked at, after any number of runs chosen after looking (a campaign extended with
``--resume``, ``--until-decided``) ([Howard 2021]).  For runs above or not (x ∈ {0, 1})
each bet is the likelihood ratio of an alternative p' (λ = |q − p'|/(q (1 − q))), so the
evidence depends on the number S of runs above only; shares use the same bets.

- violation: the bets of the alternatives whose odds are those of q times √2, 2, …, 2^10,
  mixed uniformly (a scale-free prior on how large the violation is);
- compliance: w₀ · the all-in bet λ = 1/(1 − q), which pays (1 − x)/(1 − q) per run:
  (1 − q)^(−n) while no run is above, nothing once one is wholly above; plus (1 − w₀) · the
  bets of odds of q times 2^(−1/2) … 2^(−10).  w₀ = (1 − q)^(n₀)/α, n₀ = ⌈ln α / ln(1 − q)⌉
  the classic zero-failure count ([Wilks 1941]), so that n₀ runs with none above show
  compliance exactly as the order statistic does (1,109 at 99.73 % with 95 %); the
  remaining weight lets a campaign with runs above the bound show it later.

Multiplicity: an ensemble requirement holds at every time.  Compliance must be shown at
every time: the intersection-union test needs no correction ([Berger 1982]); the
compliance evidence is the least over the times.  A violation at *some* time, the worst
one chosen after looking, is shown when the violation evidence there reaches T/α over the
T evaluated times (Bonferroni: at most α over all of them, however they are correlated).
A mixed requirement is one statement about one mean: no correction.

See docs/pointing.md.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .statistics import check_probability, runs_needed

MET, NOT_MET, UNDECIDED = "met", "not met", "undecided"
#: bets on each side: those of the alternatives whose odds are q's times 2^±(j/2),
#: j = 1 … GRID (√2 apart, up to 2^±10: a violation or a margin from 1.4 to 1,000 times)
GRID = 20
#: relative slack on a threshold, so that a case exact in real numbers is not lost
_ROUNDING = 1e-12
#: the most runs :meth:`Decision.runs_to_decide` looks for
MAX_RUNS = 10**7


@functools.cache
def _bets(q: float, alpha: float, side: int) -> tuple[np.ndarray, np.ndarray]:
    """(λ, ln weight) of the bets of ``side`` (+1: violation, −1: compliance, whose first
    is the all-in bet)."""
    odds = q / (1.0 - q) * 2.0 ** (side * np.arange(1, GRID + 1) / 2)
    alternative = odds / (1.0 + odds)
    lam = np.abs(alternative - q) / (q * (1.0 - q))
    weights = np.full(GRID, -math.log(GRID))
    if side > 0:
        return lam, weights
    n0 = runs_needed(1.0 - q, 1.0 - alpha)
    w0 = min(1.0, math.exp(n0 * math.log1p(-q) - math.log(alpha)) * (1.0 + _ROUNDING))
    rest = math.log1p(-w0) if w0 < 1.0 else -math.inf
    return np.concatenate(([1.0 / (1.0 - q)], lam)), np.concatenate(
        ([math.log(w0)], weights + rest)
    )


def _log_capital(x: np.ndarray, q: float, lam: np.ndarray, side: int) -> np.ndarray:
    """ln Π_i (1 + λ side (x_i − q)) for each bet λ (first axis) and each stream (the
    second axis of the shares ``x[run, stream]``)."""
    with np.errstate(divide="ignore"):  # a factor 0: ln 0 = −inf, the bet lost
        return np.stack([np.log1p(np.maximum(-1.0, side * b * (x - q))).sum(axis=0) for b in lam])


def _log_capital_of_counts(above, runs: int, q: float, lam: np.ndarray, side: int):
    """:func:`_log_capital` of runs above or not (x ∈ {0, 1}): ``above[stream]`` of
    ``runs`` are (a factor 1 + λ side (1 − q) each, the others 1 − λ side q)."""
    above = np.asarray(above)[None, :]
    lam = lam[:, None]
    with np.errstate(divide="ignore"):
        return _times(above, np.log1p(side * lam * (1.0 - q))) + _times(
            runs - above, np.log1p(-side * lam * q)
        )


def _times(count, log_factor):
    """count · ln factor, 0 where the count is 0 (also when the factor is 0)."""
    return count * np.where(count > 0, log_factor, 0.0)


@dataclass(frozen=True)
class Decision:
    """The verdict on ``runs`` runs at ``level`` with ``confidence`` over ``tests``
    evaluated times: ``stream`` the time that decides (the one with the least compliance
    evidence, or where a violation is shown), ``above`` the runs' Σ x there; the evidences
    (e-values) and the thresholds they are held to.  ``increments``: the mean ln-capital
    of each bet per run at that time, for :meth:`runs_to_decide`."""

    status: str
    stream: int
    above: float
    runs: int
    level: float
    confidence: float
    tests: int
    log_compliance: float  # ln e-value; met when ≥ ln(1/α)
    log_violation: float  # ln e-value; not met when ≥ ln(tests/α)
    increments: tuple = ()

    @property
    def compliance(self) -> float:
        """The compliance evidence (e-value; inf beyond the floats)."""
        return _exp(self.log_compliance)

    @property
    def violation(self) -> float:
        """The violation evidence (e-value; inf beyond the floats)."""
        return _exp(self.log_violation)

    @property
    def needed_compliance(self) -> float:
        return 1.0 / (1.0 - self.confidence)

    @property
    def needed_violation(self) -> float:
        return self.tests / (1.0 - self.confidence)

    @property
    def compliance_confidence(self) -> float:
        """The highest confidence at which compliance is shown (0 if none)."""
        return max(0.0, 1.0 - math.exp(-self.log_compliance))

    @property
    def violation_confidence(self) -> float:
        """The highest confidence at which a violation is shown, corrected for the tests."""
        return max(0.0, 1.0 - self.tests * math.exp(-min(self.log_violation, 700.0)))

    def runs_to_decide(self) -> int | None:
        """Undecided: roughly the runs that would settle it if the runs to come were like
        those made (each bet's capital growing at its mean rate per run so far); None if
        decided, or if more than :data:`MAX_RUNS` would."""
        if self.status != UNDECIDED:
            return None
        return _runs_to_decide(self.increments, self.runs, self.level, self.confidence, self.tests)


def _exp(x: float) -> float:
    return math.exp(x) if x < 700 else math.inf


def _check(level: float, confidence: float) -> tuple[float, float]:
    check_probability(level, "level")
    check_probability(confidence, "confidence")
    return 1.0 - level, 1.0 - confidence


def decide(x, level: float, confidence: float) -> Decision:
    """Met, not met or undecided on ``x[run]`` (one statement: a mixed requirement's
    shares) or ``x[run, time]`` (an ensemble requirement: every time must comply; the
    violation corrected for the times): bool, above the bound or not (then by the counts,
    :func:`decide_counts`), or float shares in [0, 1] (module docstring)."""
    x = np.asarray(x)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2 or not len(x):
        raise ValueError(f"x: expected (runs,) or (runs, times) with runs ≥ 1, got {x.shape}")
    if x.dtype == bool:
        return decide_counts(x.sum(axis=0), len(x), level, confidence)
    if not ((x >= 0.0) & (x <= 1.0)).all():
        raise ValueError("x: shares above the bound, in [0, 1]")
    q, alpha = _check(level, confidence)
    capital = {side: _log_capital(x, q, _bets(q, alpha, side)[0], side) for side in (-1, 1)}
    return _decision(capital, x.sum(axis=0), len(x), level, confidence)


def decide_counts(above, runs: int, level: float, confidence: float) -> Decision:
    """:func:`decide` on runs above the bound or not: ``above[time]`` of ``runs`` runs are
    (an ensemble requirement at each of its times; one number: one statement)."""
    q, alpha = _check(level, confidence)
    above = np.atleast_1d(np.asarray(above, dtype=float))
    if runs < 1 or not ((above >= 0) & (above <= runs)).all():
        raise ValueError(f"above: counts in [0, runs = {runs}], runs ≥ 1")
    counts, at = np.unique(above, return_inverse=True)  # the evidence of each count, once
    capital = {
        side: _log_capital_of_counts(counts, runs, q, _bets(q, alpha, side)[0], side)
        for side in (-1, 1)
    }
    return _decision(capital, above, runs, level, confidence, at.ravel())


def _decision(
    capital: dict, above, runs: int, level: float, confidence: float, at=None
) -> Decision:
    """The verdict from each bet's ln-capital at each time, ``capital[side][bet, time]``
    (or, ``at`` given, at column ``at[time]``)."""
    q, alpha = _check(level, confidence)
    at = np.arange(len(above)) if at is None else at
    evidence = {
        side: np.logaddexp.reduce(c + _bets(q, alpha, side)[1][:, None], axis=0)[at]
        for side, c in capital.items()
    }  # ln e-value per time
    tests = len(above)
    slack = math.log1p(_ROUNDING)
    met = evidence[-1].min() >= -math.log(alpha) - slack
    shown = evidence[1].max() >= math.log(tests / alpha) - slack
    status = MET if met else NOT_MET if shown else UNDECIDED
    stream = int(np.argmax(evidence[1]) if status == NOT_MET else np.argmin(evidence[-1]))
    return Decision(
        status,
        stream,
        float(above[stream]),
        runs,
        level,
        confidence,
        tests,
        float(evidence[-1][stream] if status != NOT_MET else evidence[-1].min()),
        float(evidence[1][stream] if status == NOT_MET else evidence[1].max()),
        tuple(tuple(capital[side][:, at[stream]] / runs) for side in (-1, 1)),
    )


@functools.cache  # every verdict of a campaign asks it again (a bisection)
def allowed_above(runs: int, level: float, confidence: float) -> int | None:
    """The most runs that may lie above the bound (x ∈ {0, 1}) while ``runs`` runs still
    show compliance, or None when even none may (fewer runs than n₀)."""
    q, alpha = _check(level, confidence)
    threshold = -math.log(alpha) - math.log1p(_ROUNDING)
    lam, weights = _bets(q, alpha, -1)

    def shown(above: int) -> bool:
        capital = _log_capital_of_counts([above], runs, q, lam, -1)[:, 0]
        return float(np.logaddexp.reduce(capital + weights)) >= threshold

    if not shown(0):
        return None
    low, high = 0, runs + 1  # shown(low); not shown(high) (by convention)
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (middle, high) if shown(middle) else (low, middle)
    return low


def _runs_to_decide(increments, runs: int, level: float, confidence: float, tests: int):
    q, alpha = _check(level, confidence)
    sides = {-1: -math.log(alpha), 1: math.log(tests / alpha)}

    def decided(n: int) -> bool:
        for (side, threshold), rates in zip(sides.items(), increments):
            weights = _bets(q, alpha, side)[1]
            if np.logaddexp.reduce(n * np.asarray(rates) + weights) >= threshold:
                return True
        return False

    low, high = runs, max(runs, 1)
    while not decided(high):
        if high > MAX_RUNS:
            return None
        low, high = high, 2 * high
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (low, middle) if decided(middle) else (middle, high)
    return high


def next_look(runs: int, needed, max_runs: int) -> int:
    """The runs of a campaign's next look while it runs until decided: what the undecided
    requirements would need (``needed``: each one's :meth:`Decision.runs_to_decide`, None
    if it cannot say; twice the runs if none can), at least 10 % (and 10) more runs than
    now, at most ten times as many, and at most ``max_runs``.  Any schedule keeps the
    risks (the tests are anytime-valid); this one looks little and overshoots little."""
    known = [n for n in needed if n is not None]
    target = max(known) if known else 2 * runs
    return min(max_runs, max(runs + max(10, runs // 10), min(target, 10 * runs)))
