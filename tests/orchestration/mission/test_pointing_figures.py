"""The pointing figures of runs and campaigns plot the data: a run's index against time
(the closed-form error of a synthetic run), a campaign's values with their quantile (the
order statistic of synthetic runs)."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from agilesat.orchestration.campaign import report
from agilesat.orchestration.campaign.pointing_figures import campaign_figures
from agilesat.orchestration.campaign.summary import ensemble_entry
from agilesat.orchestration.mission.pointing_figures import run_figures
from agilesat.orchestration.mission.requirements import Pointing
from agilesat.orchestration.mission.scenario import Scenario, Variant
from agilesat.orchestration.output import plots
from agilesat.orchestration.output.results import Results
from agilesat.orchestration.pointing import PointingRequirement, format_angle
from agilesat.orchestration.scenarios.video_sar import SYSTEM

DT, BIAS, AMPLITUDE = 0.05, 3e-5, 1e-5  # s, rad, rad
T = np.arange(1201) * DT
NAMES = [
    f"{base}[{i}]"
    for base in ("SatelliteDynamics.q_BI", "OrbitEnvironment.q_OI")
    for i in range(1, 5)
]


def about_z(angle):
    angle = np.asarray(angle)
    zero = np.zeros_like(angle)
    return np.stack((np.cos(angle / 2), zero, zero, np.sin(angle / 2)), axis=-1)


def requirement(name, bound, level, interpretation, **options):
    r = PointingRequirement("APE", bound, level, interpretation, axis=(0, 0, 1), **options)
    return Pointing(name, r, reference="OrbitEnvironment.q_OI")


def judged(r, signals) -> dict:
    """campaign.json's ``ensemble`` of requirement ``r`` over ``signals`` (its columns)."""
    return {r.name: ensemble_entry(r, r.evaluate_campaign(signals, T))}


def saved_axes(module, monkeypatch):
    """What ``module``'s ``_save`` is handed from now on (no file written)."""
    saved = []
    monkeypatch.setattr(module, "_save", lambda *args, **_: saved.append(args) or args[2])
    return saved


def test_a_run_draws_each_judged_pointing_requirement_as_its_index_against_time(
    tmp_path, monkeypatch
):
    """APE about z of a body off the orbit frame by b + A sin(2π t/10 s) is that angle;
    its median over time (50 %, temporal) is the ⌈n/2⌉-th smallest; a requirement the
    variant does not judge has no figure."""
    angle = BIAS + AMPLITUDE * np.sin(2 * math.pi * T / 10.0)
    results = Results(["time", *NAMES], np.column_stack((T, about_z(angle), about_z(0 * T))))
    scenario = Scenario(
        "synthetic",
        "a synthetic run",
        SYSTEM,
        requirements=[
            requirement("ape", 3.5e-5, 0.5, "temporal"),
            requirement("skipped", 1e-3, 0.5, "temporal"),
        ],
        variants={"v": Variant("skips one", not_judged=["skipped"])},
    )
    with plots.written_as([".png"]), plots.drawing() as drawn:
        paths = run_figures(scenario, "v", results, tmp_path)
    assert paths == [tmp_path / "pointing_ape.png"] and drawn == paths
    assert paths[0].stat().st_size > 10_000
    saved = saved_axes(plots, monkeypatch)
    run_figures(scenario, "v", results, tmp_path)
    [(_, axes, _, title, xlabel)] = saved
    profile, bound, median = axes[0, 0].lines
    np.testing.assert_allclose(profile.get_xdata(), T)
    np.testing.assert_allclose(profile.get_ydata(), np.degrees(angle), rtol=1e-9)
    assert bound.get_ydata()[0] == pytest.approx(math.degrees(3.5e-5))
    expected = np.sort(angle)[math.ceil(0.5 * T.size) - 1]
    assert median.get_ydata()[0] == pytest.approx(math.degrees(expected), rel=1e-9)
    assert title.splitlines() == [  # the quantity, then the verdict in a line
        "Absolute performance error, APE about (0, 0, 1)",
        f"met: {format_angle(expected)}, bound {format_angle(3.5e-5)}",
    ]
    assert xlabel == "time [s]"


def test_a_windowed_index_has_no_value_before_its_first_full_window(tmp_path):
    """MPE over 10 s of the same run from t = 0: its first value is the mean of [0, 10] s,
    dated 10 s (the sinusoid's whole period: the bias); nothing is drawn before it, the
    axis starts with the window and shades the span without a value.  The title's two
    lines fit the figure as drawn."""
    angle = BIAS + AMPLITUDE * np.sin(2 * math.pi * T / 10.0)
    results = Results(["time", *NAMES], np.column_stack((T, about_z(angle), about_z(0 * T))))
    r = Pointing(
        "mpe",
        PointingRequirement("MPE", 1e-4, 0.9973, "ensemble", window=10.0, confidence=0.95),
        reference="OrbitEnvironment.q_OI",
    )
    scenario = Scenario("synthetic", "a synthetic run", SYSTEM, requirements=[r])
    with plots.written_as([".png"]), plots.figure_objects() as figures:
        run_figures(scenario, None, results, tmp_path)
    fig = figures["pointing_mpe.png"]
    ax = fig.axes[0]
    profile = ax.lines[0]
    assert profile.get_xdata()[0] == pytest.approx(10.0)  # the first full window's end
    assert profile.get_ydata()[0] == pytest.approx(math.degrees(BIAS), rel=1e-9)
    [span] = ax.patches
    assert span.get_label() == "no value yet" and ax.get_xlim()[0] <= 0.0
    assert (span.get_x(), span.get_x() + span.get_width()) == pytest.approx((0.0, 10.0))
    quantity, verdict = ax.get_title().splitlines()
    assert quantity == "Mean performance error, MPE(10 s)"
    assert verdict.startswith("judged over the campaign: ")  # an ensemble one, in a run
    renderer = fig.canvas.get_renderer()
    assert fig.bbox.contains(*ax.title.get_window_extent(renderer).p0)
    assert fig.bbox.contains(*ax.title.get_window_extent(renderer).p1)


@pytest.fixture
def campaign():
    """30 runs of white angle noise about z (σ 1e-5 rad) and one that stopped early."""
    angles = np.random.default_rng(3).normal(size=(31, T.size)) * 1e-5
    signals = np.empty((31, len(NAMES), T.size))
    signals[:, :4] = about_z(angles).transpose(0, 2, 1)
    signals[:, 4:] = about_z(0 * T).T
    signals[30, :, 600:] = np.nan
    return signals, np.abs(angles[:30])


def test_a_campaign_draws_the_runs_at_the_worst_time_with_their_quantile(
    campaign, tmp_path, monkeypatch
):
    """Ensemble at 90 %: at each time the 27th smallest of the 30 runs' |angle|, worst over
    time; the figure's curve is the 30 runs' values at that time, the fraction above each,
    and its value line is that order statistic: where the curve first reaches 10 %."""
    signals, magnitude = campaign
    r = requirement("ape", 3e-5, 0.9, "ensemble")
    verdicts = judged(r, signals)
    saved = saved_axes(report, monkeypatch)
    [path] = campaign_figures([r], signals, NAMES, T, verdicts, tmp_path)
    [(_, ax, saved_path)] = saved
    assert path == saved_path == tmp_path / "pointing_ape.png"
    quantiles = np.sort(magnitude, axis=0)[26]
    worst = int(np.argmax(quantiles))
    curve, level, bound, value = ax.lines
    np.testing.assert_allclose(curve.get_xdata(), np.degrees(np.sort(magnitude[:, worst])))
    np.testing.assert_allclose(curve.get_ydata(), (29 - np.arange(30)) / 30)
    assert level.get_ydata()[0] == pytest.approx(0.1)
    assert bound.get_xdata()[0] == pytest.approx(math.degrees(3e-5))
    assert value.get_xdata()[0] == pytest.approx(math.degrees(quantiles.max()), rel=1e-12)
    at = np.searchsorted(curve.get_xdata(), value.get_xdata()[0])
    assert curve.get_ydata()[at] <= 0.1 < curve.get_ydata()[at - 1]
    assert ax.get_title().splitlines() == [
        "Absolute performance error, APE about (0, 0, 1)",
        f"met on the estimate: {format_angle(quantiles.max())}, bound {format_angle(3e-5)}",
    ]
    assert f"t = {T[worst]:g} s" in ax.get_xlabel()


def test_a_campaign_too_small_for_the_confidence_shows_its_estimate(campaign, tmp_path):
    """30 runs cannot show 99.73 % with 95 % confidence: no value compared, the estimate
    drawn; the title is the verdict (written here: a real file)."""
    signals, magnitude = campaign
    r = requirement("ape", 1e-4, 0.9973, "ensemble", confidence=0.95)
    verdicts = judged(r, signals)
    [path] = campaign_figures([r], signals, NAMES, T, verdicts, tmp_path)
    assert path.stat().st_size > 10_000
    saved = []
    report_save = report._save
    try:
        report._save = lambda fig, ax, p: saved.append(ax) or p
        campaign_figures([r], signals, NAMES, T, verdicts, tmp_path)
    finally:
        report._save = report_save
    [ax] = saved
    labels = [line.get_label() for line in ax.lines]
    assert labels[2].startswith("requirement") and labels[3].startswith("empirical quantile")
    assert len(labels) == 4
    assert ax.get_title().splitlines()[1].startswith("undecided: about 1109 runs: estimate")
    assert ax.lines[3].get_xdata()[0] == pytest.approx(math.degrees(magnitude.max()))


@pytest.mark.slow
def test_run_and_campaign_of_a_scenario_draw_its_pointing_requirements(tmp_path, fmus):
    """payload_sweep states APE and PDE requirements: a run and a campaign list a figure
    of each among theirs."""
    from helpers import agilesat

    names = {"pointing_pointing_ape.png", "pointing_stability_pde.png"}
    run = agilesat("run", "payload_sweep", "--stop", "3", "--out", tmp_path / "run")
    assert run.returncode == 3, run.stdout + run.stderr  # its requirements are not met
    figures = json.loads((tmp_path / "run" / "summary.json").read_text())["figures"]
    assert names <= {Path(f).name for f in figures}
    out = tmp_path / "campaign"
    result = agilesat(
        "campaign", "payload_sweep", "--stop", "3", "--runs", "2", "--workers", "1",
        "--vary", "SatelliteDynamics.rate0[3]=+normal(0, 0.01deg)", "--no-progress",
        "--no-report", "--out", out,
    )  # fmt: skip
    assert result.returncode in (0, 3), result.stdout + result.stderr
    summary = json.loads((out / "campaign.json").read_text())
    assert names <= set(summary["figures"]) and all((out / n).exists() for n in names)


def test_a_campaign_no_run_of_which_reached_the_end_draws_nothing(campaign, tmp_path):
    """Every run stopped early (NaN kept): no figure, and no crash (the verdict says why)."""
    signals, _ = campaign
    r = requirement("ape", 1e-4, 0.9, "ensemble")
    none = np.full_like(signals, np.nan)
    assert campaign_figures([r], none, NAMES, T, judged(r, none), tmp_path) == []


def test_a_campaign_figure_draws_the_magnitudes_its_verdict_judged(campaign, tmp_path, monkeypatch):
    """evaluate_campaign hands the magnitudes it judged (the 30 complete runs' |angle|, the
    stopped one left out); the figure draws those without computing them again from the
    signals (here all NaN: computed again, there would be no run)."""
    signals, magnitude = campaign
    r = requirement("ape", 3e-5, 0.9, "ensemble")
    keep: dict = {}
    verdicts = {r.name: ensemble_entry(r, r.evaluate_campaign(signals, T, keep=keep))}
    t, m = keep["magnitudes"]
    np.testing.assert_array_equal(t, T)
    np.testing.assert_allclose(m, magnitude, rtol=1e-9)
    saved = saved_axes(report, monkeypatch)
    unusable = np.full_like(signals, np.nan)
    [path] = campaign_figures([r], unusable, NAMES, T, verdicts, tmp_path, {r.name: (t, m)})
    [(_, ax, _)] = saved
    worst = int(np.argmax(np.sort(magnitude, axis=0)[26]))
    curve = ax.lines[0]
    np.testing.assert_allclose(curve.get_xdata(), np.degrees(np.sort(magnitude[:, worst])))


def test_a_violation_draws_the_runs_where_its_estimate_lies_not_where_it_is_decided(
    tmp_path, monkeypatch
):
    """At t₁ all 30 runs are at 2 B (the violation is shown there), at t₂ four at 5 B (the
    27th smallest of 30, the 90 % quantile, is largest there): the figure draws the runs at
    t₂, so that its empirical-quantile mark, 5 B, lies where the curve reaches 10 %."""
    bound, first, second = 1e-5, 100, 200
    angles = np.zeros((30, T.size))
    angles[:, first] = 2 * bound
    angles[:4, second] = 5 * bound
    signals = np.empty((30, len(NAMES), T.size))
    signals[:, :4] = about_z(angles).transpose(0, 2, 1)
    signals[:, 4:] = about_z(0 * T).T
    r = requirement("ape", bound, 0.9, "ensemble", confidence=0.95)
    verdicts = judged(r, signals)
    details = verdicts["ape"]["details"]
    assert details["status"] == "not met"
    assert details["worst_time"] == pytest.approx(T[first])
    assert details["estimate_time"] == pytest.approx(T[second])
    assert details["estimate"] == pytest.approx(5 * bound, rel=1e-9)
    saved = saved_axes(report, monkeypatch)
    campaign_figures([r], signals, NAMES, T, verdicts, tmp_path)
    [(_, ax, _)] = saved
    curve = ax.lines[0]
    np.testing.assert_allclose(
        curve.get_xdata(), np.degrees(np.sort(angles[:, second])), atol=1e-15
    )
    marks = {line.get_xdata()[0] for line in ax.lines[2:]}
    assert math.degrees(details["estimate"]) in marks
    at = np.searchsorted(curve.get_xdata(), math.degrees(details["estimate"]) * (1 - 1e-9))
    assert curve.get_ydata()[at] <= 0.1 < curve.get_ydata()[at - 1]
    assert f"t = {T[second]:g} s" in ax.get_xlabel()
