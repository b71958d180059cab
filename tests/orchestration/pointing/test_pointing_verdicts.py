"""Met, not met, undecided (orchestration/pointing/verdicts.py) against independent truths:
the zero-failure count of order statistics, likelihood ratios written out in exact
arithmetic, Ville's inequality measured on campaigns looked at after every run.  The
error rates over many kinds of campaign: tests/tools/verdict_error_rates.py (slow)."""

import math
from fractions import Fraction

import numpy as np
import pytest

from agilesat.orchestration.pointing import decide, decide_counts, next_look, runs_needed
from agilesat.orchestration.pointing.verdicts import GRID, allowed_above
from helpers import ROOT


@pytest.mark.parametrize(
    "level,confidence", [(0.9973, 0.95), (0.99, 0.9), (0.9, 0.9), (0.95, 0.99), (0.999, 0.95)]
)
def test_with_no_run_above_compliance_takes_the_zero_failure_count(level, confidence):
    """n₀ = ⌈ln(1 − C) / ln P⌉ runs with none above show compliance, as the order
    statistic does ([Wilks 1941]); n₀ − 1 do not, nor do n₀ runs with one above."""
    n0 = math.ceil(math.log(1 - confidence) / math.log(level))
    assert decide_counts([0], n0, level, confidence).status == "met"
    assert decide_counts([0], n0 - 1, level, confidence).status == "undecided"
    assert decide_counts([1], n0, level, confidence).status == "undecided"
    assert (
        allowed_above(n0, level, confidence) == 0
        and allowed_above(n0 - 1, level, confidence) is None
    )
    if n0 > 200:
        assert decide_counts([0], 200, level, confidence).runs_to_decide() == n0


def likelihood_ratio_evidence(above: int, runs: int, level: float, confidence: float):
    """The two evidences written out as mixtures of likelihood ratios of alternatives p'
    whose odds are q's times 2^±(j/2), in exact rational arithmetic (the alternatives
    rounded to floats first)."""
    q = 1 - Fraction(level)
    alpha = 1 - Fraction(confidence)
    n0 = runs_needed(level, confidence)
    w0 = min(Fraction(1), (1 - q) ** n0 / alpha)

    def ratio(p):
        p = Fraction(p)
        return (p / q) ** above * ((1 - p) / (1 - q)) ** (runs - above)

    def alternatives(side):
        odds = float(q / (1 - q))
        return [
            odds * 2.0 ** (side * j / 2) / (1 + odds * 2.0 ** (side * j / 2))
            for j in range(1, GRID + 1)
        ]

    violation = sum(ratio(p) for p in alternatives(+1)) / GRID
    compliance = (1 - w0) * sum(ratio(p) for p in alternatives(-1)) / GRID
    if above == 0:
        compliance += w0 * (1 - q) ** -runs
    return float(compliance), float(violation)


@pytest.mark.parametrize("above,runs", [(0, 1109), (1, 600), (3, 60), (30, 60), (7, 7)])
def test_the_evidences_are_mixtures_of_likelihood_ratios(above, runs):
    """For runs above the bound or not, each bet is the likelihood ratio of an alternative
    exceedance probability p' against q ([Howard 2021])."""
    decision = decide_counts([above], runs, 0.9973, 0.95)
    compliance, violation = likelihood_ratio_evidence(above, runs, 0.9973, 0.95)
    assert decision.compliance == pytest.approx(compliance, rel=1e-9, abs=1e-300)
    assert decision.violation == pytest.approx(violation, rel=1e-9)


def test_runs_above_or_not_and_shares_of_0_or_1_are_the_same_verdict():
    rng = np.random.default_rng(2)
    for p in (0.001, 0.01, 0.05):
        x = rng.random((500, 7)) < p
        a, b = decide(x, 0.99, 0.95), decide(x.astype(float), 0.99, 0.95)
        assert (a.status, a.above) == (b.status, b.above)  # the stream: among equal ones
        assert a.log_compliance == pytest.approx(b.log_compliance, rel=1e-9, abs=1e-12)
        assert a.log_violation == pytest.approx(b.log_violation, rel=1e-9, abs=1e-12)


def test_a_violation_at_the_worst_time_is_corrected_for_the_times():
    """The same worst count is a violation shown among 40 times and not among 40,000:
    the violation evidence must reach T/α (Bonferroni)."""
    one = decide_counts([6] + [0] * 39, 200, 0.9973, 0.95)
    many = decide_counts([6] + [0] * 39_999, 200, 0.9973, 0.95)
    assert one.status == "not met" and many.status == "undecided"
    assert one.violation == many.violation and one.stream == many.stream == 0
    assert 40 / 0.05 <= one.violation < 40_000 / 0.05


def test_compliance_is_the_least_over_the_times():
    """Every time must comply: one time with a run above is enough to withhold it."""
    assert decide_counts([0] * 100, 1109, 0.9973, 0.95).status == "met"
    held = decide_counts([0] * 99 + [1], 1109, 0.9973, 0.95)
    assert held.status == "undecided" and held.stream == 99 and held.above == 1


@pytest.mark.parametrize("side", ["met", "not met"])
def test_looking_after_every_run_keeps_the_risk(side):
    """Ville's inequality, measured: 3,000 campaigns exactly at the bound (p = q), looked at
    after each of their first 100 runs; the share that is ever decided the wrong way stays
    within α (binomial sampling error allowed: 3 σ)."""
    level, confidence, runs, campaigns = 0.9, 0.9, 100, 3000
    above = np.cumsum(np.random.default_rng(5).random((campaigns, runs)) < 1 - level, axis=1)
    wrong = np.zeros(campaigns, bool)
    verdicts = {}
    for n in range(1, runs + 1):
        for s in np.unique(above[:, n - 1]):
            if (s, n) not in verdicts:
                verdicts[s, n] = decide_counts([s], n, level, confidence).status
        wrong |= np.array([verdicts[s, n] == side for s in above[:, n - 1]])
    alpha = 1 - confidence
    print(f"ever {side}: {wrong.mean():.4f} of {campaigns} campaigns (α = {alpha:g})")
    assert wrong.mean() <= alpha + 3 * math.sqrt(alpha * (1 - alpha) / campaigns)


def test_shares_use_what_a_run_shows_below_the_bound():
    """Shares concentrated at a fifth of the allowed exceedance are shown compliant in a
    few hundred runs (the all-in bet pays (1 − x)/(1 − q) per run: ln 20 / ln(0.998/0.99)
    = 373 runs), where one run wholly above in as many runs leaves it undecided."""
    assert decide(np.full(373, 0.002), 0.99, 0.95).status == "met"
    assert decide(np.full(372, 0.002), 0.99, 0.95).status == "undecided"
    assert decide_counts([1], 400, 0.99, 0.95).status == "undecided"
    assert decide(np.full(400, 0.02), 0.99, 0.95).status == "not met"


def test_roughly_the_runs_that_would_settle_it():
    """Undecided: the runs at which campaigns like the one made would be decided; a
    campaign of that many runs with the same share above is."""
    for above, runs in ((2, 300), (1, 1500)):
        decision = decide_counts([above], runs, 0.9973, 0.95)
        needed = decision.runs_to_decide()
        assert decision.status == "undecided" and needed > runs
        scale = needed / runs
        grown = decide_counts([above * scale], needed, 0.9973, 0.95)
        assert grown.status != "undecided"
    at_the_bound = decide_counts([27], 10_000, 0.9973, 0.95)  # exactly q
    assert at_the_bound.status == "undecided" and at_the_bound.runs_to_decide() is None


def test_the_cases_of_the_issue():
    """A shown violation is not met, "not shown" is undecided (issue 33): 30 of 60
    scan_pitch runs above the PDE bound at one of 1,160 times; 20 of 200 runs above an RPE
    bound; none of 200 above the video_sar APE bound (1,109 would show it); 8 of 200 above
    an AKE bound at 95 % whose estimate lies under it."""
    assert decide_counts([30] + [0] * 1159, 60, 0.9973, 0.95).status == "not met"
    assert decide_counts([20] + [0] * 3999, 200, 0.9973, 0.95).status == "not met"
    none = decide_counts([0] * 4001, 200, 0.9973, 0.95)
    assert none.status == "undecided" and none.runs_to_decide() == 1109
    few = decide_counts([8] + [0] * 4000, 200, 0.95, 0.95)
    assert few.status == "undecided" and 5_000 < few.runs_to_decide() < 20_000


def test_the_looks_of_a_campaign_run_until_decided():
    assert next_look(200, [1109], 10_000) == 1109
    assert next_look(200, [201], 10_000) == 220  # at least 10 % more
    assert next_look(20, [100_000], 10_000) == 200  # at most ten times as many
    assert next_look(200, [None], 10_000) == 400  # none can say: twice
    assert next_look(900, [1109], 1000) == 1000
    with pytest.raises(ValueError, match="counts in"):
        decide_counts([5], 3, 0.9, 0.9)
    with pytest.raises(ValueError, match="shares above the bound"):
        decide(np.array([0.5, 1.5]), 0.9, 0.9)


@pytest.mark.slow
def test_the_verdicts_error_rates_hold_and_are_the_documented_ones(capsys):
    """tests/tools/verdict_error_rates.py: every false rate within α + 3 binomial standard
    errors, and its tables (seeded) are those docs/pointing.md shows."""
    import verdict_error_rates

    assert verdict_error_rates.main(["--check"]) == 0
    printed = capsys.readouterr().out
    page = (ROOT / "docs" / "pointing.md").read_text(encoding="utf-8")
    shown = page.split("<!-- verdict-error-rates -->\n", 1)[1].split("<!-- /verdict", 1)[0]
    assert shown.strip() == printed.strip()
