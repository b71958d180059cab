"""Order-statistic confidence of an ensemble statistic: the runs needed, the bound a
campaign supports, and its coverage measured on synthetic campaigns."""

import math
from fractions import Fraction

import numpy as np
import pytest
from scipy import stats

from agilesat.orchestration.pointing import (
    NotEvaluable,
    allowed_exceedances,
    confidence_achieved,
    runs_needed,
    statistic,
)


def at_most(k, n, p):
    """Pr[Bin(n, p) ≤ k] summed term by term."""
    return sum(math.comb(n, i) * p**i * (1 - p) ** (n - i) for i in range(k + 1))


@pytest.mark.parametrize("level", [0.9, 0.95, 0.99, 0.9973, 0.999])
@pytest.mark.parametrize("confidence", [0.9, 0.95, 0.99])
def test_runs_needed_without_exceedance_is_the_closed_form(level, confidence):
    assert runs_needed(level, confidence) == math.ceil(math.log(1 - confidence) / math.log(level))


def test_the_runs_the_issue_quotes():
    assert runs_needed(0.9973, 0.95) == 1109
    assert 0.9973**1109 <= 0.05 < 0.9973**1108


def test_a_case_exact_in_real_numbers_is_not_lost_to_rounding():
    """0.9³ = 1 − 0.271: three runs suffice (in floats 0.9³ = 0.7290000000000001 > 0.729)."""
    assert runs_needed(0.9, 0.271) == 3
    assert allowed_exceedances(3, 0.9, 0.271) == 0


@pytest.mark.parametrize("level,confidence", [(0.9973, 0.95), (0.99, 0.9), (0.95, 0.99)])
@pytest.mark.parametrize("k", [1, 2, 5])
def test_runs_needed_with_exceedances_is_the_smallest_binomial_solution(level, confidence, k):
    n = runs_needed(level, confidence, k)
    assert at_most(k, n, 1 - level) <= 1 - confidence < at_most(k, n - 1, 1 - level)
    assert allowed_exceedances(n, level, confidence) == k
    assert allowed_exceedances(n - 1, level, confidence) == k - 1


def test_a_campaign_too_small_is_not_evaluable_and_says_how_many_runs():
    with pytest.raises(
        NotEvaluable, match=r"needs at least 1109 runs \(none above it\); it has 1108"
    ):
        allowed_exceedances(1108, 0.9973, 0.95)
    with pytest.raises(NotEvaluable, match="1109 runs"):
        statistic(np.ones((1108, 3)), 0.9973, "ensemble", confidence=0.95)
    with pytest.raises(ValueError, match="needs the ensemble or mixed interpretation"):
        statistic(np.ones((2000, 3)), 0.9973, "temporal", confidence=0.95)


@pytest.mark.parametrize("runs", [1, 2, 10, 59, 300, 1109])
@pytest.mark.parametrize("level", [0.5, 0.9, 0.99, 0.9973])
def test_confidence_achieved_is_the_exact_binomial_tail(runs, level):
    """Pr[Bin(n, 1 − P) > k] against its sum in exact rational arithmetic (the level as the
    float it is), and for k = 0 the closed form 1 − P^n."""
    q = 1 - Fraction(level)
    for k in sorted({0, 1, 2, 10, runs // 2 if runs <= 300 else 0} & set(range(runs))):
        tail = 1 - sum(math.comb(runs, i) * q**i * (1 - q) ** (runs - i) for i in range(k + 1))
        assert confidence_achieved(runs, k, level) == pytest.approx(float(tail), rel=1e-13)
    assert confidence_achieved(runs, 0, level) == pytest.approx(1 - level**runs, rel=1e-12)
    assert confidence_achieved(runs, runs, level) == 0.0


@pytest.mark.parametrize("runs,exceedances", [(1109, 0), (2000, 3), (300, 10)])
def test_confidence_achieved_is_the_one_sided_clopper_pearson_level(runs, exceedances):
    """The lower Clopper-Pearson limit of the fraction within, at the confidence achieved
    for a level, is that level: B(1 − C; n − k, k + 1) = P."""
    for level in (0.9, 0.99, 0.9973):
        c = confidence_achieved(runs, exceedances, level)
        if 1e-12 < c < 1 - 1e-12:
            lower = stats.beta.ppf(1 - c, runs - exceedances, exceedances + 1)
            assert lower == pytest.approx(level, rel=1e-9)


@pytest.mark.parametrize(
    "runs,level,confidence,design",
    [(1109, 0.9973, 0.95, "verdict"), (500, 0.99, 0.95, "verdict"), (500, 0.99, 0.95, "fixed")],
)
def test_coverage_of_the_bound_on_ten_thousand_synthetic_campaigns(runs, level, confidence, design):
    """Each column a campaign of ``runs`` exponential values (true quantile −ln(1 − P)): the
    bound exceeds the true quantile in a fraction of campaigns Pr[Bin(n, P) ≤ n − k − 1]
    ≥ C, as measured within its binomial sampling error; k: the runs the verdicts'
    anytime-valid rule allows above it (``statistic``), or a design fixed in advance
    (``allowed_exceedances``: one of 500 at 99 %)."""
    campaigns = 10_000
    values = np.random.default_rng(8).exponential(size=(runs, campaigns))
    if design == "verdict":
        bound = statistic(values, level, "ensemble", confidence=confidence)
        allowed, profile = bound.allowed, bound.profile
        assert bound.value == bound.profile.max()
    else:
        allowed = allowed_exceedances(runs, level, confidence)
        profile = np.sort(values, axis=0)[runs - allowed - 1]
    covered = np.mean(profile >= -math.log(1 - level))
    exact = stats.binom.cdf(runs - allowed - 1, runs, level)
    sampling = math.sqrt(exact * (1 - exact) / campaigns)
    print(f"n = {runs}, k = {allowed} ({design}): coverage {covered:.4f}, exact {exact:.4f}")
    assert exact >= confidence
    assert covered == pytest.approx(exact, abs=4 * sampling)
