"""A pointing requirement's verdict, text and record; the package stands on NumPy alone."""

import ast
import json
import math
from pathlib import Path

import numpy as np
import pytest

import agilesat.orchestration.pointing as pointing
from agilesat.orchestration.pointing import (
    ErrorHistory,
    NotEvaluable,
    PointingRequirement,
    format_angle,
    index_series,
    magnitude,
)

ARCSEC = math.pi / 648_000


def white_campaign(runs=1200, samples=400, sigma=1.0 * ARCSEC, seed=9, kind="performance"):
    rng = np.random.default_rng(seed)
    return ErrorHistory(rng.normal(size=(runs, samples, 3)) * sigma, np.arange(samples) * 0.1, kind)


def rpe(bound=1.0, **changes):
    settings = dict(index="RPE", bound=bound, level=0.9973, interpretation="ensemble")
    settings.update(window=1.0, axis=(0, 0, 1), confidence=0.95)
    settings.update(changes)
    return PointingRequirement(**settings)


def test_met_undecided_and_not_met_at_the_confidence():
    """White noise: each time's 99.73 % quantile of the RPE is 3σ.  A bound at 6σ: no run
    of 1200 above it at any time, compliance shown (1,109 runs with none above suffice);
    at 4σ two runs above at one time: neither shown (one run above takes thousands of runs
    more); at 3σ, the quantile itself, undecided; at 2.5σ, 1.2 % of the runs above it at
    each time against the 0.27 % allowed: a violation shown, corrected for the 390 times."""
    error = white_campaign()
    sigma = math.sqrt((1 - 1 / 20) ** 2 + 1 / 400 + 9 / 100) * ARCSEC  # RPE end, N = 10
    for bound_sigmas, status in ((6.0, "met"), (4.0, "undecided"), (3.0, "undecided")):
        result = rpe(bound_sigmas * sigma).evaluate(error)
        assert result.status == status and result.met is {"met": True}.get(status)
        assert (result.confidence_achieved >= 0.95) is (status == "met")
        assert result.value >= result.estimate  # the bound with confidence is the larger
        assert result.runs == 1200 and result.runs_needed == 1109
        assert (result.value <= result.requirement.bound) is (status == "met")
    violated = rpe(2.5 * sigma).evaluate(error)
    assert violated.status == "not met" and violated.met is False
    assert violated.above > 15 and violated.decision.tests == 390
    assert violated.violation_confidence >= 0.95
    assert violated.line("arcsec").endswith(
        "a violation shown with 95 % confidence, over 390 evaluated times)"
    )


def test_undecided_and_not_evaluated_say_why():
    """100 runs, none above: neither shown; 1,109 runs with none above would show
    compliance.  A record shorter than the windows: not evaluated."""
    few = rpe(10 * ARCSEC).evaluate(white_campaign(runs=100))
    assert few.status == "undecided" and few.met is None and few.value is None
    assert few.runs_needed == 1109 and few.runs_to_decide == 1109 and few.above == 0
    series = index_series(white_campaign(runs=100).about((0, 0, 1)), "RPE", 1.0)
    assert few.estimate == magnitude(series).max()
    assert few.line("arcsec") == (
        "RPE(1 s) about (0, 0, 1) at 99.73 % (ensemble) with 95 % confidence: estimate "
        f"{format_angle(few.estimate, 'arcsec')} (requirement 10 arcsec): undecided (none of "
        "the 100 run(s) above it at any time; neither compliance nor a violation shown with "
        "95 % confidence: about 1109 runs would settle it)"
    )
    assert few.short() == "undecided: about 1109 runs"
    short = rpe(ARCSEC, window=50.0).evaluate(white_campaign(runs=1200, samples=400))
    assert short.status == "not evaluated" and "too short" in short.reason
    with pytest.raises(NotEvaluable, match="too short"):
        index_series(white_campaign(runs=2), "PDE", window=20.0, separation=20.0)


def test_no_run_is_not_evaluated():
    """A campaign none of whose runs reached the end: no value, said (not a crash)."""
    none = rpe(ARCSEC).evaluate(white_campaign(runs=0))
    assert none.status == "not evaluated" and none.value is None and none.runs == 0
    assert "no run" in none.reason
    with pytest.raises(NotEvaluable, match="no run"):
        rpe(ARCSEC).magnitudes(white_campaign(runs=0))


def test_without_a_confidence_the_estimate_is_judged_and_says_so():
    error = white_campaign(runs=300)
    ensemble = rpe(3.0 * ARCSEC, confidence=None).evaluate(error)
    assert ensemble.basis == "estimate" and ensemble.decision is None
    assert ensemble.status == ("met" if ensemble.estimate <= 3.0 * ARCSEC else "not met")
    assert "on the estimate (no confidence stated;" in ensemble.line("arcsec")
    temporal = rpe(3.0 * ARCSEC, confidence=None, interpretation="temporal").evaluate(error)
    assert temporal.basis == "runs" and temporal.line("arcsec").endswith("runs above it)")
    assert temporal.status == "not met" and temporal.above >= 1  # a run above, 0.27 % of its time
    meets = rpe(4.0 * ARCSEC, confidence=None, interpretation="temporal").evaluate(error)
    assert meets.status == "met" and meets.line("arcsec").endswith("met in each of the 300 runs")


def test_the_line_and_the_record():
    result = rpe(0.001 * math.pi / 180).evaluate(white_campaign(sigma=0.5 * ARCSEC))
    assert result.line("deg") == (
        f"RPE(1 s) about (0, 0, 1) at 99.73 % (ensemble) with 95 % confidence: "
        f"{format_angle(result.value, 'deg')} (requirement 0.001°): met (none of the 1200 "
        "run(s) above it at any time; compliance shown with 95 % confidence)"
    )
    assert result.short() == "met (95 % confidence)"
    record = json.loads(json.dumps(result.to_dict()))
    assert record["requirement"]["window"] == 1.0 and record["requirement"]["t_in_window"] == "end"
    assert record["status"] == "met" and record["value"] == result.value
    assert record["basis"] == "confidence" and record["above"] == 0
    evidence = record["evidence"]
    assert evidence["log10_compliance"] >= evidence["log10_compliance_needed"]
    assert evidence["log10_compliance_needed"] == pytest.approx(math.log10(20))
    assert record["evidence"]["tests"] == 390
    assert 0.0 <= record["worst_time"] <= 39.9
    temporal = PointingRequirement("APE", ARCSEC, 0.9, "temporal", boresight=(0, 0, 1))
    record = temporal.evaluate(white_campaign(runs=5)).to_dict()
    assert record["confidence_achieved"] is None and record["runs_needed"] is None
    assert record["worst_run"] in range(5) and record["requirement"]["t_in_window"] is None
    assert temporal.label() == "APE half-cone of (0, 0, 1)"
    drift = PointingRequirement("KDE", ARCSEC, 0.9, "mixed", window=10.0, separation=60.0)
    assert drift.label() == "KDE(10 s, Δt_s 60 s)"
    assert rpe(ARCSEC, t_in_window="random").label() == "RPE(1 s, t random in Δt) about (0, 0, 1)"
    assert format_angle(1e-6, "urad") == "1 urad" and format_angle(ARCSEC, "arcsec") == "1 arcsec"
    with pytest.raises(ValueError, match="unknown angle unit 'gon'"):
        format_angle(1.0, "gon")


def test_the_error_signal_the_requirement_names():
    """About an axis, the half-cone of a boresight, or the 3-axis angle."""
    t = np.arange(3) * 1.0
    phi = np.tile([3e-6, 4e-6, 12e-6], (3, 1))
    error = ErrorHistory(phi, t)
    for kwargs, expected in (
        ({"axis": (0, 1, 0)}, 4e-6),
        ({"boresight": (0, 0, 1)}, 5e-6),
        ({}, 13e-6),
    ):
        result = PointingRequirement("APE", 1.0, 0.5, "mixed", **kwargs).evaluate(error)
        assert result.value == pytest.approx(expected, rel=1e-6)
    scalar = ErrorHistory(np.full(3, 2e-6), t)
    assert PointingRequirement("APE", 1.0, 0.5, "mixed").evaluate(scalar).value == 2e-6
    with pytest.raises(ValueError, match="needs a rotation-vector error"):
        PointingRequirement("APE", 1.0, 0.5, "mixed", axis=(1, 0, 0)).evaluate(scalar)


def test_t_random_in_the_window_is_the_exact_mixture_of_the_draws():
    """ "t random in Δt" weighs every window position of every time (no draw, no seed):
    the verdict's share of each run above the bound at each time is the probability that a
    random draw is above it, which the draws of 400 seeds estimate; blocks of runs change
    nothing."""
    error = white_campaign(runs=70, samples=60)
    requirement = rpe(2.0 * ARCSEC, t_in_window="random", confidence=None)
    t, m = requirement.magnitudes(error)
    assert m.shape == (70, 60 - 20, 11)  # N = 10 sample periods: 11 positions per time
    shares = requirement.shares(m, 2.0 * ARCSEC, pointing.position_weights(10))
    signal = error.about((0, 0, 1))
    draws = np.mean(
        [
            magnitude(index_series(signal, "RPE", 1.0, None, "random", seed)) > 2.0 * ARCSEC
            for seed in range(400)
        ],
        axis=0,
    )
    sampling = np.sqrt(shares * (1 - shares) / 400)
    assert np.all(np.abs(draws - shares) <= 5 * sampling + 1e-12)
    assert (shares > 0).any() and (shares < 1).any()
    ends = pointing.window_positions(signal, "RPE", 1.0).values
    assert np.array_equal(m[..., 0], np.abs(ends[..., 0, 0]))  # position 0: t at the end
    assert requirement.evaluate(error).value == requirement.evaluate(error).value
    with pytest.warns(DeprecationWarning, match="seed is no longer used"):
        assert requirement.evaluate(error, seed=4).value == requirement.evaluate(error).value


def test_a_temporal_requirement_with_t_random_goes_run_by_run_in_blocks(monkeypatch):
    """Each run's mixture on its own: blocks of 3 runs give the verdict of all at once."""
    import agilesat.orchestration.pointing.requirement as module

    error = white_campaign(runs=40, samples=60)
    requirement = rpe(
        2.0 * ARCSEC, t_in_window="random", interpretation="temporal", confidence=None
    )
    whole = requirement.judge(*requirement.magnitudes(error))
    monkeypatch.setattr(module, "MIXTURE_LIMIT", 3 * 40 * 11)
    blocks = requirement.evaluate(error)
    assert blocks.line("arcsec") == whole.line("arcsec") and blocks.runs == 40
    assert np.array_equal(blocks.statistic.profile, whole.statistic.profile)


def test_knowledge_indices_take_knowledge_errors():
    knowledge = white_campaign(runs=3, kind="knowledge")
    assert PointingRequirement("RKE", 1.0, 0.9, "mixed", window=1.0).evaluate(knowledge).met
    with pytest.raises(ValueError, match="RPE is a performance index: it needs the performance"):
        rpe(1.0, confidence=None, interpretation="mixed").evaluate(knowledge)


@pytest.mark.parametrize(
    "changes,message",
    [
        ({"index": "JITTER"}, "unknown index 'JITTER'"),
        ({"window": None}, "RPE needs a window > 0 s"),
        ({"index": "APE"}, "APE takes no window"),
        ({"separation": 5.0}, "RPE takes no separation"),
        ({"index": "PDE"}, "PDE needs a separation > 0 s"),
        ({"index": "MPE", "t_in_window": "random"}, "of RPE/RKE only"),
        ({"t_in_window": "start"}, "t_in_window 'start'"),
        ({"interpretation": "temporal"}, "a confidence needs the ensemble or mixed"),
        ({"interpretation": "worst"}, "interpretation 'worst'"),
        ({"level": 1.0}, "level must be a probability"),
        ({"confidence": 95}, "confidence must be a probability"),
        ({"level": 0.9, "bound": -1.0}, "bound must be a positive angle"),
        ({"boresight": (0, 0, 1)}, "an axis or a boresight, not both"),
        ({"axis": (0, 0)}, "axis must be a non-zero 3-vector"),
    ],
)
def test_a_malformed_requirement_is_refused(changes, message):
    with pytest.raises(ValueError, match=message):
        rpe(**changes)


def test_a_window_must_be_whole_samples():
    with pytest.raises(ValueError, match=r"window Δt = 0.25 s is not a whole number of samples"):
        index_series(white_campaign(runs=1), "MPE", window=0.25)


def test_the_package_imports_only_numpy_scipy_and_itself():
    """Usable on any arrays: no FMI, no other part of the toolkit."""
    allowed = {
        *("numpy", "scipy", "math", "functools", "dataclasses", "importlib", "warnings"),
        "__future__",
    }
    for path in Path(pointing.__file__).parent.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module]
            else:
                continue
            assert {n.split(".")[0] for n in names} <= allowed, f"{path.name}: {names}"
