"""The metrics library and the requirements' verdicts (orchestration/mission/metrics.py,
requirements.py, scenario.py) on signals of known closed forms; a value that does not exist
is no value, with its reason, never a number."""

import math

import numpy as np
import pytest

from agilesat.orchestration import assert_requirements_met
from agilesat.orchestration.mission import (
    Bound,
    Metric,
    NotEvaluable,
    Scenario,
    System,
    Variant,
    at_least,
    at_most,
    deg,
    within,
)
from agilesat.orchestration.mission import metrics as m
from agilesat.orchestration.output.results import Results
from agilesat.orchestration.pointing import rotation_quaternion

DEG = math.pi / 180
T = np.arange(0, 1001) * 0.1  # 0 … 100 s
TAU = 10.0


def results(**columns) -> Results:
    """Results of time T and the given columns (name: (values, unit))."""
    names, data, units = ["time"], [T], {}
    for name, (values, unit) in columns.items():
        values = np.asarray(values, dtype=float).reshape(len(T), -1)
        element = (
            [f"{name}[{i + 1}]" for i in range(values.shape[1])] if values.shape[1] > 1 else [name]
        )
        names += element
        data += list(values.T)
        units.update(dict.fromkeys(element, unit))
    return Results(names, np.column_stack(data), {"units": units})


DECAY = results(**{"S.w": (np.column_stack([np.exp(-T / TAU), -0.5 * np.exp(-T / TAU)]), "rad/s")})


def test_settling_time_of_an_exponential_decay():
    """|x| = e^(−t/τ) ≤ b from t = τ ln(1/b): the first sample after the last one above."""
    bound = 0.01
    value = m.settling_time("S.w", bound).evaluate(DECAY)
    exact = TAU * math.log(1 / bound)
    assert value.value == T[T > exact][0] and value.unit == "s"
    assert m.settling_time("S.w", bound, after=60.0).evaluate(DECAY).value == 60.0
    in_degrees = m.settling_time("S.w", "0.573 deg/s").evaluate(DECAY).value  # 0.01 rad/s
    assert in_degrees == pytest.approx(exact, abs=0.11)


def test_not_settled_is_no_value_with_its_reason():
    never = m.settling_time("S.w", 1e-6).evaluate(DECAY)
    assert never.value is None and never.reason.startswith("not settled: |S.w| > 5.73e-05 °/s")
    in_degrees = m.settling_time("S.w", 1e-4 * DEG).evaluate(DECAY)  # the bound as people say it
    assert in_degrees.reason.startswith("not settled: |S.w| > 0.0001 °/s at the end")
    late = m.settling_time("S.w", 0.01, after=150.0).evaluate(DECAY)
    assert (
        late.value is None
        and "the records end at 100 s, before the window's start 150 s" in late.reason
    )


def test_max_and_rms_over_a_window_of_a_sine():
    """A sin(2π t / P) over whole periods: max A, RMS A/√2 (trapezoid-free: samples)."""
    signal = results(**{"C.e": (2.0 * np.sin(2 * np.pi * T / 4.0), "rad")})
    assert m.max_abs("C.e").evaluate(signal).value == pytest.approx(2.0, rel=1e-12)
    windowed = m.rms("C.e", start=20.0, stop=59.9).evaluate(signal).value  # 10 periods
    assert windowed == pytest.approx(2.0 / math.sqrt(2), rel=1e-12)
    assert m.max_abs("C.e", start=0.0, stop=0.5).evaluate(signal).value == pytest.approx(
        2.0 * math.sin(2 * np.pi * 0.5 / 4.0), rel=1e-12
    )


def test_pointing_error_about_and_across_the_boresight():
    """A rotation by θ about the boresight leaves the line of sight where it was; about a
    perpendicular axis it turns it by θ; the 3-axis angle is θ either way."""
    theta = np.radians(0.5) * T / T[-1]
    about_z = rotation_quaternion(np.column_stack([0 * T, 0 * T, theta]))
    about_x = rotation_quaternion(np.column_stack([theta, 0 * T, 0 * T]))
    identity = (1.0, 0.0, 0.0, 0.0)
    run = results(**{"B.q_z": (about_z, "1"), "B.q_x": (about_x, "1")})
    line_of_sight = dict(boresight=(0, 0, 1))
    assert m.pointing_error("B.q_z", identity, **line_of_sight).evaluate(
        run
    ).value == pytest.approx(0.0, abs=1e-12)
    assert m.pointing_error("B.q_x", identity, **line_of_sight).evaluate(
        run
    ).value == pytest.approx(np.radians(0.5), rel=1e-12)
    assert m.pointing_error("B.q_z", identity).evaluate(run).value == pytest.approx(
        np.radians(0.5), rel=1e-12
    )
    rms = m.pointing_error("B.q_x", identity, statistic="rms", **line_of_sight)
    exact = math.sqrt(np.mean(theta**2))
    assert rms.evaluate(run).value == pytest.approx(exact, rel=1e-12)


def test_rate_error_saturation_and_momentum_margin():
    w = np.column_stack([np.full_like(T, 0.03), np.full_like(T, 0.04), 0 * T])
    flags = (T >= 75.0).astype(float)
    h = np.column_stack([T / 10, 0 * T, 0 * T])  # 0 … 10 N·m·s along x
    run = results(**{"S.w": (w, "rad/s"), "W.saturated": (flags, "1"), "W.h": (h, "N.m.s")})
    assert m.rate_error("S.w").evaluate(run).value == pytest.approx(0.05, rel=1e-12)
    assert m.rate_error("S.w", (0.03, 0.04, 0.0)).evaluate(run).value == 0.0
    # samples 750 … 1000 set (t = 75.000000000000014 … 100 s)
    assert m.saturation_fraction("W.saturated").evaluate(run).value == pytest.approx(251 / 1001)
    limit = m.saturation_fraction("W.h", limit=9.0).evaluate(run).value
    assert limit == pytest.approx(101 / 1001)
    assert m.momentum_margin("W.h", 12.0).evaluate(run).value == pytest.approx(2.0, rel=1e-12)

    # a cluster holding 12 along x, 30 across: the margin is taken in h's own direction
    def envelope(d):
        return 12.0 * abs(d[0]) + 30.0 * math.hypot(d[1], d[2])

    assert m.momentum_margin("W.h", envelope).evaluate(run).value == pytest.approx(2.0)


def test_a_nan_is_no_value_and_a_missing_column_is_a_mistake():
    """A metric that raises (a column its run recorded not, any exception) is not
    evaluated, ``failed``: the reason names it, where it was written and what it raised."""
    nan = Metric("x", lambda r: float("nan")).evaluate(DECAY)
    assert nan.value is None and nan.reason == "not a number" and not nan.failed
    missing = m.max_abs("S.v").evaluate(DECAY)
    line = next(n for n, text in enumerate(open(__file__), 1) if 'max_abs("S.v").eval' in text)
    assert missing.value is None and missing.failed
    assert missing.reason.startswith(f"metric max_abs_v ({__file__}:{line}) raised ColumnError")
    assert "no column 'S.v'" in missing.reason
    broken = Metric("broken", lambda r: 1 / 0).evaluate(DECAY)
    assert broken.failed and broken.reason.endswith("raised ZeroDivisionError: division by zero")
    partial = m.max_abs("S.v").evaluate(DECAY, partial=True)  # --record chose the columns
    assert partial.value is None and partial.reason.startswith("not recorded")


def test_bounds_with_units_and_their_verdicts():
    values = {"a": m.MetricValue(0.5 * DEG, "rad"), "b": m.MetricValue(None, "s", "not settled")}
    assert at_most(deg(1)).on("a").evaluate(None, values).status == "met"
    assert at_least("0.6 deg").on("a").evaluate(None, values).status == "not met"
    assert within(deg(0.4), deg(0.6)).on("a").limits("rad") == {
        "min": pytest.approx(0.4 * DEG),
        "max": pytest.approx(0.6 * DEG),
    }
    verdict = at_most(10.0).on("b").evaluate(None, values)
    assert verdict.status == "not evaluated" and verdict.met is None
    assert "b has no value: not settled" in verdict.reason
    mismatch = r"unit mismatch: 1.0 deg/s is an angular rate \[rad/s\], the variable is an angle"
    with pytest.raises(ValueError, match=mismatch):
        at_most("1 deg/s").on("a").evaluate(None, values)
    with pytest.raises(ValueError, match="a bound needs min, max or both"):
        Bound()


def scenario() -> Scenario:
    """A scenario over DECAY (its system is never run here)."""
    return Scenario(
        "decay",
        "an exponential decay",
        System("decay", step=0.1, stop=100.0),
        metrics=[
            m.settling_time("S.w", 0.01, require=at_most(50.0)),
            m.max_abs("S.w", name="peak", require=at_most(0.5)),
        ],
        variants={
            "relaxed": Variant("peak not judged", not_judged={"peak": "a start we do not judge"})
        },
        diagnose=lambda r, metrics: (
            ["the peak is the initial rate"] if metrics["peak"]["value"] > 0.5 else []
        ),
    )


def test_a_run_is_judged_by_its_requirements_and_diagnosed():
    summary = scenario().evaluate(DECAY)
    verdicts = {name: r["verdict"] for name, r in summary["requirements"].items()}
    assert verdicts == {"settling_time": "met", "peak": "not met"}
    assert summary["status"] == "failed"
    assert summary["diagnostics"] == [
        "requirement peak ≤ 0.5 rad/s not met: 1 rad/s",
        "the peak is the initial rate",
    ]
    assert summary["metrics"]["peak"]["requirement"] == {"max": 0.5}
    with pytest.raises(AssertionError, match=r"peak ≤ 0.5 rad/s: not met = 1 rad/s"):
        assert_requirements_met(summary)
    assert_requirements_met(summary, "settling_time")


def test_a_variant_not_meant_to_meet_a_requirement_does_not_judge_it():
    summary = scenario().evaluate(DECAY, "relaxed")
    peak = summary["requirements"]["peak"]
    assert peak["verdict"] == "not judged" and peak["met"] is None
    assert peak["reason"] == "a start we do not judge"
    assert summary["diagnostics"] == ["the peak is the initial rate"]  # its own words stay
    assert_requirements_met(summary)  # what is not judged is not asserted
    with pytest.raises(AssertionError, match="not judged"):
        assert_requirements_met(summary, "peak")


def test_a_requirement_not_evaluated_is_neither_met_nor_a_failure():
    short = Results(DECAY.names, DECAY.data[:300], DECAY.meta)  # 0 … 29.9 s: still above
    summary = scenario().evaluate(short, "relaxed")
    settling = summary["requirements"]["settling_time"]
    assert settling["verdict"] == "not evaluated" and settling["met"] is None
    assert summary["metrics"]["settling_time"]["value"] is None
    assert summary["status"] == "failed"  # the diagnosis, not the unevaluated requirement
    with pytest.raises(AssertionError, match="settling_time ≤ 50 s: not evaluated"):
        assert_requirements_met(summary)


def test_a_metric_raising_not_evaluable_has_no_value():
    def before(results):
        raise NotEvaluable("the run ends before the window")

    value = Metric("late", before, "s").evaluate(DECAY)
    assert (value.value, value.reason) == (None, "the run ends before the window")


def test_a_requirement_of_ones_own_judged_over_the_campaign_is_marked_so_in_the_summary():
    """A user's requirement with ``evaluate_campaign`` (and no ``over_campaign``) is judged
    over a campaign's runs (campaign/plan.py) and the run's summary says so: one rule
    (mission.requirements.judged_over_campaign)."""
    from agilesat.orchestration.mission.requirements import MET, Requirement, Verdict

    class Spread(Requirement):
        name = "spread"
        signals = ("S.w[1]",)

        def evaluate(self, results, metrics):
            return Verdict(MET, 0.0)

        def evaluate_campaign(self, signals, t):
            return Verdict(MET, 0.0)

    ours = scenario()
    ours.requirements.append(Spread())
    spread = ours.evaluate(DECAY)["requirements"]["spread"]
    assert spread["judged_over"] == "campaign" and spread["verdict"] == "judged over the campaign"
    assert spread["text"] == "spread: judged over the campaign"


def test_an_undecided_requirement_fails_no_run_and_exits_4():
    """A requirement of one's own may be undecided: the run is not failed, `agilesat run`
    exits 4 (3 if another is not met), and the assertion fails unless told to accept it."""
    from agilesat.orchestration.cli import exit_status
    from agilesat.orchestration.mission.requirements import UNDECIDED, Requirement, Verdict

    class Unsure(Requirement):
        name = "unsure"

        def evaluate(self, results, metrics):
            return Verdict(UNDECIDED, reason="neither shown")

    ours = scenario()
    ours.requirements.append(Unsure())
    summary = ours.evaluate(DECAY)
    unsure = summary["requirements"]["unsure"]
    assert unsure["verdict"] == "undecided" and unsure["met"] is None
    assert not any("unsure" in problem for problem in summary["diagnostics"])
    assert exit_status(False, {"unsure": unsure}) == 4
    assert exit_status(False, {"a": {"verdict": "not met"}, "unsure": unsure}) == 3
    with pytest.raises(AssertionError, match=r"requirement undecided \(accept_undecided"):
        assert_requirements_met(summary, "unsure")
    assert_requirements_met(summary, "unsure", accept_undecided=True)


def test_settling_time_of_a_vector_norm():
    """x = e^(−t/τ) (1, −0.5): per axis the largest element decides, |x_1| ≤ b from
    τ ln(1/b); the norm ‖x‖ = e^(−t/τ) √1.25 ≤ b from τ ln(√1.25/b), later."""
    bound = 0.01
    axes = m.settling_time("S.w", bound).evaluate(DECAY).value
    norm = m.settling_time("S.w", bound, norm=True).evaluate(DECAY).value
    assert axes == T[T > TAU * math.log(1 / bound)][0]
    assert norm == T[T > TAU * math.log(math.sqrt(1.25) / bound)][0] and norm > axes
    held = results(**{"S.w": (np.full((len(T), 3), 0.01), "rad/s")})  # each axis inside
    assert m.settling_time("S.w", 0.015).evaluate(held).value == 0.0
    said = m.settling_time("S.w", 0.015, norm=True).evaluate(held)
    assert said.value is None and said.reason.startswith("not settled: ‖S.w‖ > 0.8594 °/s")


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: within(5, 1), r"a bound in \[5, 1\]: its lower end is above its upper end"),
        (lambda: within("1 deg", "0.5 deg"), "its lower end is above its upper end"),
        (lambda: within("1 deg", "2 m"), "its ends are not in one unit"),
        (lambda: at_most(math.nan), "a bound's max must be a finite number"),
        (lambda: at_least(math.inf), "a bound's min must be a finite number"),
        (lambda: at_most("nan deg"), "a bound's max must be a finite number"),
    ],
)
def test_a_bound_no_value_can_meet_is_refused(make, message):
    with pytest.raises(ValueError, match=message):
        make()
    assert within("-0.82 deg/s", "-0.78 deg/s").limits("rad/s")["min"] < 0


def test_an_infinite_metric_is_no_value_and_json_holds_none():
    """JSON has no Infinity: the metric has no value, its reason says why, and whatever
    else is not finite is null in summary.json."""
    import json

    from agilesat.orchestration.output.summary import summary_text

    value = Metric("blows_up", lambda r: math.inf).evaluate(DECAY)
    assert value.value is None and value.reason == "inf (not a finite number)"
    text = summary_text({"a": [1.0, -math.inf], "b": {"c": math.nan}})

    def strict(constant):
        raise ValueError(constant)

    assert json.loads(text, parse_constant=strict) == {"a": [1.0, None], "b": {"c": None}}
