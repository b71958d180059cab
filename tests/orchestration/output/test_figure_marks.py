"""What the figures mark (issue #28): limits, thresholds, the instants metrics give, the
phases of a maneuver, log axes where a quantity spans decades; asked of the matplotlib
objects the figures are made of (:func:`plots.figure_objects`)."""

import math

import numpy as np
import pytest

from agilesat.orchestration.output import plots

ARCSEC = math.pi / 180 / 3600


def _horizontal(ax) -> list[float]:
    """The y of every horizontal line drawn across the axes (axhline)."""
    return [
        line.get_ydata()[0]
        for line in ax.lines
        if len(set(line.get_xdata())) == 2 and len(set(line.get_ydata())) == 1
    ]


def _vertical(ax) -> list[float]:
    """The x of every vertical line drawn across the axes (axvline)."""
    return [
        line.get_xdata()[0]
        for line in ax.lines
        if len(set(line.get_xdata())) == 1 and len(line.get_xdata()) == 2
    ]


def _covered(figure) -> list[str]:
    """What the legends of ``figure`` cover: "y label: line" of each data point or
    horizontal line (a limit, a requirement) a legend lies on, in the drawn figure's
    pixels.  Vertical lines (phases, instants) span the axes' height: a legend above the
    data crosses them, and they show below it."""
    figure.canvas.draw()
    covered = []
    for ax in figure.axes:
        legend = ax.get_legend()
        if legend is None:
            continue
        box = legend.get_window_extent()
        for line in ax.lines:
            x, y = (np.asarray(v, dtype=float) for v in line.get_data())
            if len(x) == 2 and x[0] == x[1]:
                continue  # vertical
            if len(set(y)) == 1 and len(x) == 2:  # horizontal: sample it along its width
                x = np.linspace(x[0], x[1], 200)
                y = np.full_like(x, y[0])
            xy = line.get_transform().transform(np.column_stack((x, y)))
            xy = xy[np.isfinite(xy).all(axis=1)]
            if len(xy) and box.count_contains(xy):
                covered.append(f"{ax.get_ylabel()}: {line.get_label()}")
    return covered


def test_axes_of_their_own_x_each_say_what_x_is(tmp_path):
    t1, t2 = np.linspace(0, 10, 11), np.linspace(10, 20, 11)
    with plots.figure_objects() as figures:
        plots.panels(
            tmp_path / "two.png", "two spans", [(t1, {"a": t1}, "a [m]"), (t2, {"b": t2}, "b [m]")]
        )
    assert [ax.get_xlabel() for ax in figures["two.png"].axes] == ["time [s]", "time [s]"]


def test_phases_are_marked_on_every_axes_and_named_above_the_top_one(tmp_path):
    t = np.linspace(0, 30, 301)
    phases = [("1 accel.", 0.0, 10.0), ("2 coast", 10.0, 20.0), ("3 hold", 20.0, math.inf)]
    with plots.figure_objects() as figures:
        plots.panels(
            tmp_path / "p.png",
            "phases",
            [(t, {"x": t}, "x [m]"), (t, {"y": -t}, "y [m]")],
            phases=phases,
        )
    top, bottom = figures["p.png"].axes
    for ax in (top, bottom):
        assert sorted(_vertical(ax)) == [10.0, 20.0]  # between phases, not at the start
    assert [text.get_text() for text in top.texts] == ["1 accel.", "2 coast", "3 hold"]
    assert not bottom.texts


def test_an_instant_the_papers_instant_and_events_are_vertical_lines_in_the_legend(tmp_path):
    t = np.linspace(0, 10, 101)
    with plots.figure_objects() as figures:
        plots.lines(
            tmp_path / "v.png",
            "instants",
            t,
            {"x": t},
            "x [m]",
            at=(4.0, "ours"),
            paper_at=(5.0, "paper"),
            events=((1.0, 2.0, 3.0), "reversal"),
        )
    ax = figures["v.png"].axes[0]
    assert sorted(_vertical(ax)) == [1.0, 2.0, 3.0, 4.0, 5.0]
    assert {"ours", "paper", "reversal"} <= {t.get_text() for t in ax.get_legend().get_texts()}


@pytest.mark.slow
def test_scan_pitch_figures_mark_phases_settling_and_a_log_singularity_measure(
    scan_pitch_run, tmp_path
):
    from agilesat.orchestration.scenarios.scan_pitch import PROFILE, SCENARIO

    _, _, summary, results = scan_pitch_run
    with plots.figure_objects() as figures:
        SCENARIO.draw(results, tmp_path)
    imaging, settling = figures["fig06_imaging_and_settling.png"].axes
    assert imaging.get_xlabel() == settling.get_xlabel() == "time [s]"
    assert settling.get_yscale() == "log"
    assert _horizontal(settling) == [pytest.approx(0.01)]  # °/s: stable below it
    settled = summary["metrics"]["settling_time"]["value"]
    assert sorted(_vertical(settling)) == pytest.approx(sorted([settled, 105.0]))
    assert figures["fig10_singularity.png"].axes[0].get_yscale() == "log"
    for name in ("fig04_pitch.png", "fig07_gimbal_rates.png", "fig11_output_torque.png"):
        for ax in figures[name].axes:
            assert sorted(_vertical(ax)) == pytest.approx(PROFILE.times[:4])
    assert {name: _covered(figure) for name, figure in figures.items()} == {
        name: [] for name in figures
    }


@pytest.mark.slow
def test_payload_sweep_figures_draw_the_wheel_limits_and_the_errors_in_arcsec_on_log_axes(
    fmus, tmp_path
):
    from agilesat.orchestration.runner import run
    from agilesat.orchestration.scenarios.payload_sweep import SCENARIO

    results, _ = run("payload_sweep", figures=False, stop=60.0)
    with plots.figure_objects() as figures:
        SCENARIO.draw(results, tmp_path)
    torque, momentum = figures["fig09_wheel.png"].axes
    assert sorted(_horizontal(torque)) == [-0.2, 0.2]  # N·m, the paper's wheel
    assert sorted(_horizontal(momentum)) == [-12.0, 12.0]  # N·m·s, the HR12's
    accuracy, stability = figures["fig08_pointing.png"].axes
    assert accuracy.get_yscale() == stability.get_yscale() == "log"
    assert _horizontal(accuracy) == [pytest.approx(0.032 * 3600)]  # arcsec
    assert _horizontal(stability) == [pytest.approx(0.006 * 3600)]  # arcsec/s
    assert "arcsec" in accuracy.get_ylabel()
    assert {name: _covered(figure) for name, figure in figures.items()} == {
        name: [] for name in figures
    }
    zoomed = figures["fig05_payload_momentum.png"].axes[1]
    reversals = _vertical(zoomed)  # a stroke: 30° at 6 °/s, and half the 1 s turnaround
    assert np.diff(reversals) == pytest.approx(5.5, abs=0.06)


def test_overview_leaves_out_euler_rates_near_gimbal_lock_and_says_so(tmp_path):
    from agilesat.orchestration.output.results import Results

    t = np.linspace(0.0, 80.0, 8001)
    theta = np.radians(50.0 + t)  # through θ = 90° at t = 40 s
    theta_dot = np.full_like(t, math.radians(1.0))
    spike = 0.01 / np.maximum(np.abs(np.cos(theta)), 1e-9)  # φ̇ grows as 1/cos θ
    names = ["time"] + [f"S.euler_BO[{i}]" for i in (1, 2, 3)]
    names += [f"S.euler_rate_BO[{i}]" for i in (1, 2, 3)]
    zero = np.zeros_like(t)
    data = np.column_stack((t, zero, theta, zero, spike, theta_dot, -spike))
    units = {n: ("rad" if "euler_BO" in n else "rad/s") for n in names[1:]}
    results = Results(names, data, {"units": units})
    with plots.figure_objects() as figures:
        plots.overview(results, tmp_path)
    angles, rates = figures["overview_S.png"].axes
    near, far = np.abs(t - 40.0) < 4.99, np.abs(t - 40.0) > 5.01  # 5° of the lock at 1 °/s
    for line in rates.lines:
        y = line.get_ydata()
        assert np.isnan(y[near]).all() and np.isfinite(y[far]).all()
    assert rates.get_ylim()[1] < 20  # °/s: ±6.6 °/s 5° from the lock (and the legend) set it
    assert "gimbal lock" in " ".join(t.get_text() for t in rates.get_legend().get_texts())
    assert all(np.isfinite(line.get_ydata()).all() for line in angles.lines)


def test_campaign_envelopes_draw_the_scenarios_bounds_of_the_signal(tmp_path, monkeypatch):
    """A requirement on a signal as a green band over its window, a device limit as dashed
    red lines; a variant that does not judge the requirement draws no band."""
    from matplotlib.collections import LineCollection, PolyCollection

    from agilesat.orchestration.campaign import report
    from agilesat.orchestration.scenarios.payload_sweep import SCENARIO as PAYLOAD
    from agilesat.orchestration.scenarios.scan_pitch import SCENARIO as SCAN

    saved = []
    monkeypatch.setattr(report, "_save", lambda fig, ax, path: saved.append(ax) or path)
    t = np.linspace(0.0, 150.0, 151)
    signals = np.random.default_rng(0).normal(0.0, 1e-3, (5, 2, len(t)))
    names = ["SatelliteDynamics.euler_rate_BO[2]", "CmgCluster.delta_dot[4]"]
    report.envelopes(signals, names, {}, t, tmp_path, SCAN.bounds_for("literal_spin"))
    rate, gimbal = saved
    band = [c for c in rate.collections if isinstance(c, PolyCollection)][-1]
    x, y = band.get_paths()[0].vertices.T
    deg = math.pi / 180
    assert (x.min(), x.max()) == pytest.approx((110 / 3, 290 / 3))  # t3, t4 of the maneuver
    assert (y.min(), y.max()) == pytest.approx((-0.82 * deg, -0.78 * deg))
    limits = [c for c in gimbal.collections if isinstance(c, LineCollection)]
    assert sorted(s[0][1] for s in limits[0].get_segments()) == [-0.6, 0.6]  # rad/s
    saved.clear()
    w = ["SatelliteDynamics.w_BO_B[3]"]
    report.envelopes(signals[:, :1], w, {}, t, tmp_path, PAYLOAD.bounds_for(None))
    report.envelopes(signals[:, :1], w, {}, t, tmp_path, PAYLOAD.bounds_for("no_control"))
    judged, not_judged = (len(ax.collections) for ax in saved)
    assert judged == not_judged + 1  # the ±0.006 °/s band, not where it is not judged


def test_a_campaign_histogram_marks_the_nominal_run_with_its_legend_off_the_bars(
    tmp_path, monkeypatch
):
    from agilesat.orchestration.campaign import report

    drawn = []
    monkeypatch.setattr(report, "_save", lambda fig, ax, path: drawn.append(ax) or path)
    meta = {"unit": "rad", "display_unit": "deg", "paper": math.radians(1.5)}
    array = np.array([(math.radians(x),) for x in (0.5, 1.0, 1.2)], dtype=[("m", float)])
    report.histograms(array, {"metrics": {"m": meta}}, tmp_path, {"m": math.radians(0.9)})
    [ax] = drawn
    marks = {line.get_label(): line.get_xdata()[0] for line in ax.lines}
    assert marks == pytest.approx({"paper": 1.5, "nominal run": 0.9})  # °
    ax.figure.canvas.draw()
    legend = ax.get_legend().get_window_extent()
    assert not legend.overlaps(ax.get_window_extent())  # beside the axes


@pytest.mark.slow
def test_the_nominal_run_is_the_campaigns_target_without_its_dispersions(fmus):
    from agilesat.orchestration.campaign.nominal import start
    from agilesat.orchestration.campaign.plan import Plan, Spec
    from agilesat.orchestration.runner import run

    spec = Spec(
        "scan_pitch",
        runs=3,
        vary=["CmgCluster.h_rotor=*normal(1, 0.005)"],
        set={"SatelliteDynamics.gravity_gradient": "false"},
        stop=40.0,
    )
    nominal = start(Plan(spec)).result()
    assert nominal["command"] == (
        "agilesat run scan_pitch --stop 40.0 --set SatelliteDynamics.gravity_gradient=false"
    )
    _, summary = run(
        "scan_pitch", stop=40.0, parameters={"SatelliteDynamics.gravity_gradient": "false"}
    )
    assert nominal["metrics"] == {
        k: m["value"] for k, m in summary["metrics"].items() if m["value"] is not None
    }


class Answering:
    """A started isolated run (isolated.Started) that answers ``answer`` (raised if an
    exception)."""

    def __init__(self, answer):
        self.answer = answer

    def result(self):
        if isinstance(self.answer, BaseException):
            raise self.answer
        return self.answer

    def cancel(self):
        pass


def test_the_nominal_run_of_a_one_point_grid_is_at_that_point(monkeypatch, capsys):
    """A grid of one value is the campaign's setting, not a dispersion: the nominal run
    sets it too (it ran at the system's value), and says so on stderr."""
    from agilesat.orchestration.campaign import isolated
    from agilesat.orchestration.campaign.nominal import start
    from agilesat.orchestration.campaign.plan import Plan, Spec

    given = []
    summary = {"metrics": {"m": {"value": 1.0}}}
    answer = lambda target, options: given.append(options) or Answering(summary)
    monkeypatch.setattr(isolated, "start", answer)
    vary = ["CmgCluster.rate_limit=values(0.3)", "CmgCluster.h_rotor=*normal(1, 0.005)"]
    nominal = start(Plan(Spec("scan_pitch", runs=3, vary=vary, stop=40.0))).result()
    assert given[0].parameters == {"CmgCluster.rate_limit": 0.3}
    assert nominal == {
        "command": "agilesat run scan_pitch --stop 40.0 --set CmgCluster.rate_limit=0.3",
        "metrics": {"m": 1.0},
    }
    assert "the nominal run, for the histograms: agilesat run scan_pitch" in capsys.readouterr().err


def test_a_signal_during_the_nominal_run_is_kept_for_the_exit_status(monkeypatch, capsys):
    """The runs are made and kept; the nominal run stopped by SIGTERM is said and recorded,
    and the campaign command exits 143 (the signal in engine.INTERRUPTS)."""
    import signal

    from agilesat.orchestration.campaign import engine, isolated
    from agilesat.orchestration.campaign.nominal import start
    from agilesat.orchestration.campaign.plan import Plan, Spec
    from agilesat.orchestration.cosim.master import Interrupted

    stopped = Interrupted("interrupted by SIGTERM at t = 3 s", None, signal.SIGTERM)
    monkeypatch.setattr(isolated, "start", lambda target, options: Answering(stopped))
    monkeypatch.setattr(engine.INTERRUPTS, "signals", [])
    nominal = start(Plan(Spec("scan_pitch", runs=3, stop=40.0))).result()
    assert nominal["reason"] == "Interrupted: interrupted by SIGTERM at t = 3 s"
    assert engine.INTERRUPTS.signals == [signal.SIGTERM]
    assert "no nominal run (Interrupted: interrupted by SIGTERM" in capsys.readouterr().err

    # a KeyboardInterrupt that is no signal the campaign's handler recorded: not hidden
    monkeypatch.setattr(isolated, "start", lambda target, options: Answering(KeyboardInterrupt()))
    monkeypatch.setattr(engine.INTERRUPTS, "signals", [])
    with pytest.raises(KeyboardInterrupt):
        start(Plan(Spec("scan_pitch", runs=3, stop=40.0))).result()


@pytest.mark.parametrize(
    "settings, limit_drawn",
    [
        ({}, True),
        ({"set": {"CmgCluster.rate_limit": "0.4"}}, False),
        ({"vary": ["CmgCluster.rate_limit=*normal(1, 0.01)"]}, False),
        ({"vary": ["CmgCluster.rate_limit=values(0.3, 0.6)"]}, False),
        ({"vary": ["CmgCluster.h_rotor=*normal(1, 0.005)"]}, True),
    ],
)
def test_a_limit_the_campaign_changes_is_not_drawn_at_the_systems_value(settings, limit_drawn):
    from agilesat.orchestration.campaign.plan import Plan, Spec
    from agilesat.orchestration.campaign.summary import _bounds

    bounds = _bounds(Plan(Spec("scan_pitch", runs=2, stop=40.0, **settings)))
    assert [b.requirement for b in bounds if not b.limit] == ["imaging_pitch_rate_mean"]
    assert any(b.parameter == "CmgCluster.rate_limit" for b in bounds) == limit_drawn
