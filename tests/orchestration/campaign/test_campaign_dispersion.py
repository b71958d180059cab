"""Campaign building blocks that need no FMU run: the dispersion language, run indexing,
pass-rate intervals, the table, absent values and the requirements' verdicts."""

import json
import math
import re

import numpy as np
import pytest

from agilesat.orchestration.campaign import dispersion, report
from agilesat.orchestration.campaign.plan import Plan, Spec

DEG = math.pi / 180


def test_parse_numbers_degrees_and_modes():
    d = dispersion.parse("CmgCluster.delta0=+normal(0, 0.5deg)")
    assert (d.key, d.kind, d.mode) == ("CmgCluster.delta0", "normal", "+")
    assert d.args == (0.0, 0.5 * DEG)
    assert dispersion.parse("A.x[2,3] = *uniform(0.9,1.1e0)").args == (0.9, 1.1)
    assert dispersion.parse("A.x=linspace(1, 2, 3)").grid() == [1.0, 1.5, 2.0]
    assert dispersion.parse("A.x=values(-1, .5)").grid() == [-1.0, 0.5]


@pytest.mark.parametrize(
    "text, match",
    [
        ("A.x", "expected Instance.variable=DIST"),
        ("A=normal(0,1)", "expected Instance.variable=DIST"),
        ("A.x=gauss(0,1)", "unknown distribution 'gauss'"),
        ("A.x=normal(0)", "normal takes 2 argument"),
        ("A.x=normal(0, -1)", "standard deviation must be ≥ 0"),
        ("A.x=uniform(2, 1)", "lo <= hi"),
        ("A.x=linspace(0, 1, 2.5)", "positive integer"),
        ("A.x=normal(0, one)", "'one' is not a number"),
        ("A.x=+rotate(1deg)", "drop the '\\+'"),
    ],
)
def test_parse_errors_name_the_problem(text, match):
    with pytest.raises(ValueError, match=match):
        dispersion.parse(text)


def test_rotate_keeps_unit_vectors_and_has_the_stated_sd():
    d = dispersion.parse("A.axis=rotate(0.1deg)")
    axes = np.array([[1.0, 0, 0], [0, 0.6, 0.8]])
    draws = np.array([d.draw(7, i, axes) for i in range(4000)])
    assert np.allclose(np.linalg.norm(draws, axis=2), 1.0, atol=1e-15)
    tilt = np.arccos(np.clip(np.einsum("nij,ij->ni", draws, axes), -1, 1))
    # tilt² = φ₁² + φ₂², each N(0, sd²): E[tilt²] = 2 sd²
    assert np.sqrt(np.mean(tilt**2) / 2) == pytest.approx(0.1 * DEG, rel=0.05)
    # about each perpendicular axis: the component of the draw along e has sd = sd
    assert np.std(draws[:, 0, 1]) == pytest.approx(0.1 * DEG, rel=0.05)
    assert np.std(draws[:, 0, 2]) == pytest.approx(0.1 * DEG, rel=0.05)


def test_inertia_stays_symmetric_positive_definite_and_physical():
    nominal = np.diag([600.0, 1000.0, 1200.0])
    d = dispersion.parse("S.inertia=inertia(0.03, 1deg)")
    draws = np.array([d.draw(3, i, nominal) for i in range(3000)])
    assert np.array_equal(draws, np.transpose(draws, (0, 2, 1)))
    moments = np.linalg.eigvalsh(draws)
    assert moments.min() > 0
    assert np.all(2 * moments.max(axis=1) <= moments.sum(axis=1) * (1 + 1e-12))
    # principal moments: 3 % relative sd (moments stay ordered at this spread)
    assert np.std(moments / [600, 1000, 1200], axis=0) == pytest.approx([0.03] * 3, rel=0.07)
    # principal axes: a rotation vector of 1° per axis; the x axis tilts by φ_y, φ_z
    x_axis = np.linalg.eigh(draws)[1][:, :, 0] * np.sign(np.linalg.eigh(draws)[1][:, 0:1, 0])
    assert np.std(x_axis[:, 1]) == pytest.approx(1 * DEG, rel=0.07)


def test_draws_depend_on_seed_and_index_only():
    a = dispersion.parse("A.x=normal(0, 1)")
    nominal = np.zeros(3)
    assert np.array_equal(a.draw(1, 5, nominal), a.draw(1, 5, nominal))
    assert not np.array_equal(a.draw(1, 5, nominal), a.draw(1, 6, nominal))
    assert not np.array_equal(a.draw(1, 5, nominal), a.draw(2, 5, nominal))
    b = dispersion.parse("A.y=normal(0, 1)")  # another key: an independent stream
    assert not np.array_equal(a.draw(1, 5, nominal), b.draw(1, 5, nominal))


def test_mode_adds_to_or_multiplies_the_nominal():
    nominal = np.array([10.0, 20.0])
    plain, added, scaled = (dispersion.parse(f"A.x={m}normal(1, 0.1)") for m in ("", "+", "*"))
    raw = plain.draw(0, 0, nominal)
    assert np.array_equal(added.draw(0, 0, nominal), nominal + raw)
    assert np.array_equal(scaled.draw(0, 0, nominal), nominal * raw)


def test_plan_grid_full_factorial_and_index_mapping():
    plan = Plan(
        Spec(
            "payload_sweep",
            runs=3,
            seed=4,
            vary=[
                "Flywheel.torque_limit=values(0.2, 2.0)",
                "SweepPlanner.turnaround_time=linspace(1, 10, 3)",
                "SatelliteDynamics.rate0[3]=normal(0, 1e-5)",
            ],
        )
    )
    assert plan.total == 3 * 6 and len(plan.grid) == 6
    seen = {
        (
            plan.run_values(i)["Flywheel.torque_limit"],
            plan.run_values(i)["SweepPlanner.turnaround_time"],
        )
        for i in range(6)
    }
    assert seen == {(t, r) for t in (0.2, 2.0) for r in (1.0, 5.5, 10.0)}
    # run i is grid point i % 6: the same point, another draw, one replicate later
    assert (
        plan.run_values(1)["Flywheel.torque_limit"] == plan.run_values(7)["Flywheel.torque_limit"]
    )
    assert (
        plan.run_values(1)["SatelliteDynamics.rate0[3]"]
        != plan.run_values(7)["SatelliteDynamics.rate0[3]"]
    )
    # extending --runs keeps every run already planned
    longer = Plan(Spec("payload_sweep", runs=5, seed=4, vary=plan.spec.vary))
    assert all(longer.run_values(i) == plan.run_values(i) for i in range(plan.total))


def test_plan_whole_variables_start_from_the_system_values():
    plan = Plan(
        Spec(
            "scan_pitch",
            vary=["CmgCluster.delta0=+normal(0, 0)", "SatelliteDynamics.inertia=inertia(0, 0)"],
        )
    )
    values = plan.run_values(0)
    from agilesat.orchestration.scenarios.scan_pitch import PAPER_DELTA0

    assert [values[f"CmgCluster.delta0[{i}]"] for i in range(1, 7)] == pytest.approx(
        PAPER_DELTA0, abs=1e-15
    )
    assert values["SatelliteDynamics.inertia[2,2]"] == pytest.approx(956.0, rel=1e-14)
    assert values["SatelliteDynamics.inertia[1,2]"] == pytest.approx(0.0, abs=1e-12)
    assert plan.columns[:6] == [f"CmgCluster.delta0[{i}]" for i in range(1, 7)]


@pytest.mark.parametrize(
    "vary, match",
    [
        ("Nobody.x=normal(0,1)", "no component 'Nobody'"),
        ("CmgCluster.nothing=normal(0,1)", "CmgCluster has no variable 'nothing'"),
        ("CmgCluster.h_rotr=normal(0,1)", "no variable 'h_rotr'; did you mean h_rotor"),
        ("CmgClustr.h_rotor=normal(0,1)", "no component 'CmgClustr'.*did you mean CmgCluster"),
        (
            "SatelliteDynamics.attitude0=rotate(1deg)",
            "rotate\\(\\) turns unit vectors; SatelliteDynamics.attitude0 has norm",
        ),
        ("CmgCluster.delta0[7]=normal(0,1)", "has shape \\(6,\\)"),
        ("CmgCluster.delta=normal(0,1)", "only numeric parameters"),
        ("CmgSteering.law=normal(0,1)", "Integer parameter: use choice"),
        ("CmgCluster.delta0=values(0, 1)", "grids take scalar names"),
        ("CmgCluster.h_rotor=rotate(1deg)", "rotate\\(\\) turns a 3-vector"),
        ("CmgCluster.gimbal_axis=inertia(0.1, 0)", "disperses a 3×3 inertia"),
        (
            "CmgSteering.law=choice(PSEUDO_INVERSE, NOPE)",
            "law must be one of 0 \\(PSEUDO_INVERSE\\), 1 \\(SR_INVERSE\\), got 'NOPE'",
        ),
        ("CmgCluster.h_rotor=choice(A, B)", "CmgCluster.h_rotor has none: give numbers"),
        ("CmgSteering.law=+choice(0, 1)", "a named choice cannot be added or multiplied"),
        ("CmgCluster.h_rotor=normal(1e999, 1)", "normal must be finite numbers, got inf"),
        ("CmgCluster.h_rotor=*uniform(1, 1e400)", "uniform must be finite numbers"),
        ("CmgCluster.h_rotor=linspace(0, 1, 1e9)", "1e\\+09 points, more than the 100000 runs"),
    ],
)
def test_plan_rejects_dispersions_that_do_not_fit(vary, match):
    with pytest.raises(ValueError, match=match):
        Plan(Spec("scan_pitch", vary=[vary]))


@pytest.mark.parametrize(
    "runs, vary, total",
    [
        (10**9, ["CmgCluster.h_rotor=normal(16.65, 0.1)"], "1000000000 runs"),
        (
            1,
            ["CmgCluster.h_rotor=linspace(1, 2, 1000)", "CmgCluster.rate_limit=values(0.5, 0.6)"],
            None,
        ),
        (
            1,
            [
                "CmgCluster.h_rotor=linspace(1, 2, 1000)",
                "CmgCluster.rate_limit=linspace(0, 1, 1000)",
            ],
            "1 run\\(s\\) × 1000 × 1000 grid points = 1000000 runs",
        ),
    ],
)
def test_a_campaign_of_more_than_max_runs_is_refused_before_anything_is_made(runs, vary, total):
    """At once, from the counts alone: the grid is not built, no run index listed."""
    if total is None:
        assert Plan(Spec("scan_pitch", runs=runs, vary=vary)).total == 2000
        return
    with pytest.raises(ValueError, match=f"{total}, more than the {dispersion.MAX_RUNS}"):
        Plan(Spec("scan_pitch", runs=runs, vary=vary))


def test_dispersion_files_toml_and_json_agree(tmp_path):
    (tmp_path / "d.toml").write_text(
        '[vary]\n"A.x" = "normal(1, 2)"\n"A.y[2]" = "values(1, 2)"\n[set]\n"A.z" = 3.0\n'
    )
    (tmp_path / "d.json").write_text(
        json.dumps({"vary": {"A.x": "normal(1, 2)", "A.y[2]": "values(1, 2)"}, "set": {"A.z": 3.0}})
    )
    assert dispersion.load(tmp_path / "d.toml") == dispersion.load(tmp_path / "d.json")
    (tmp_path / "bad.toml").write_text('[vary]\n"A.x" = "normal(1"\n')
    with pytest.raises(ValueError, match="bad.toml A.x"):
        dispersion.load(tmp_path / "bad.toml")
    (tmp_path / "empty.json").write_text("{}")
    with pytest.raises(ValueError, match="empty.json: expected a table 'vary'"):
        dispersion.load(tmp_path / "empty.json")


def test_clopper_pearson_against_closed_forms_and_a_table():
    # k = n: lower = (α/2)^(1/n); k = 0: upper = 1 − (α/2)^(1/n)
    assert report.clopper_pearson(100, 100)[0] == pytest.approx(0.025 ** (1 / 100), rel=1e-12)
    assert report.clopper_pearson(0, 20)[1] == pytest.approx(1 - 0.025 ** (1 / 20), rel=1e-12)
    # n = 10, k = 5: (0.1871, 0.8129) (tabulated exact interval)
    assert report.clopper_pearson(5, 10) == pytest.approx((0.1871, 0.8129), abs=1e-4)


def _record(i: int, plan, value, verdict: str, reason: str | None = None) -> dict:
    metric = {"value": value, **({"reason": reason} if reason else {})}
    return {
        "index": i,
        "seed": 0,
        "grid": 0,
        "values": plan.run_values(i),
        "status": "ok",
        "message": "",
        "worker": "w",
        "seconds": 0.1,
        "metrics": {"m": metric},
        "requirements": {"m": verdict},
    }


CATALOG = {
    "metrics": {"m": {"unit": "rad", "display_unit": "deg", "requirement": {"max": 1.0}}},
    "requirements": {"m": {"statement": "m ≤ 57.3°", "unit": "rad", "display_unit": "deg"}},
}


def test_table_round_trips_floats_exactly_through_csv_and_absent_values_are_empty(tmp_path):
    plan = Plan(Spec("scan_pitch", runs=3, vary=["CmgCluster.h_rotor=normal(16.65, 0.1)"]))
    records = {
        1: _record(1, plan, 1 / 3 + 1, "not met"),
        0: _record(0, plan, 1 / 3, "met"),
        2: _record(2, plan, None, "not evaluated", "not settled: |x| > 1 at the end"),
    }
    array = report.table(plan, records, CATALOG)
    assert list(array["index"]) == [0, 1, 2] and list(array["met_m"]) == [True, False, False]
    assert list(array["verdict_m"]) == ["met", "not met", "not evaluated"]
    report.write_table(array, tmp_path)
    import csv

    rows = list(csv.DictReader((tmp_path / "runs.csv").open()))
    assert float(rows[1]["m"]) == 1 / 3 + 1
    assert rows[2]["m"] == ""  # no value: an empty cell, never a number
    assert float(rows[0]["CmgCluster.h_rotor"]) == plan.run_values(0)["CmgCluster.h_rotor"]
    rates = report.pass_rates(array, CATALOG)["m"]
    assert (rates["met"], rates["not_met"], rates["not_evaluated"], rates["runs"]) == (1, 1, 1, 3)
    stats = report.statistics(array, CATALOG, records)["m"]
    assert (stats["count"], stats["missing"]) == (2, 1)
    assert stats["mean"] == pytest.approx(1 / 3 + 0.5, rel=1e-15)  # the absent run left out
    assert stats["reasons"] == {"not settled": 1}


def test_a_requirement_a_variant_does_not_judge_has_no_pass_rate():
    plan = Plan(Spec("scan_pitch", runs=1, vary=["CmgCluster.h_rotor=normal(16.65, 0.1)"]))
    catalog = {
        "metrics": CATALOG["metrics"],
        "requirements": {"m": {"statement": "m ≤ 1", "not_judged": "motors off"}},
    }
    array = report.table(plan, {0: _record(0, plan, 2.0, "not judged")}, catalog)
    assert report.pass_rates(array, catalog) == {}


def test_progress_prints_plain_lines_off_a_terminal(capsys):
    import sys

    progress = report.Progress(4, 1, period=0.0, stream=sys.stdout)
    progress.update("ok")
    progress.update("failed")
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("campaign: 2/4 runs done (none failed)")
    assert "3/4 runs done (1 failed)" in lines[1] and "runs/s, ETA" in lines[1]


def test_progress_is_a_bar_on_a_terminal():
    import io

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    stream = Terminal()
    progress = report.Progress(5, 2, stream=stream)
    progress.update("ok")
    progress.update("error")
    progress.close()
    text = stream.getvalue()
    assert "4/5" in text and "1 error" in text and "run/s" in text


def test_batch_size_aims_at_a_few_seconds_and_an_even_share():
    from agilesat.orchestration.campaign import engine

    assert engine.BATCH_SECONDS == 2.0 and engine.IN_FLIGHT_PER_WORKER == 2
    assert engine.batch_size(None, 1000, 2) == 1  # a run's duration not known yet
    assert engine.batch_size(0.4, 1000, 2) == 5  # 2 s of runs
    assert engine.batch_size(1e-4, 10**6, 2) == engine.MAX_BATCH
    assert engine.batch_size(10.0, 1000, 2) == 1  # long runs: one per task
    # the end of a campaign: at most an even share of what is left per batch in flight
    assert engine.batch_size(0.1, 9, 2) == 3
    assert engine.batch_size(0.1, 1, 2) == 1
    # a large cluster: longer batches, at most MAX_TASKS_PER_SECOND tasks for the client
    assert engine.MAX_TASKS_PER_SECOND == 20
    assert engine.batch_size(1.0, 10**6, 40) == 2
    assert engine.batch_size(1.0, 10**6, 200) == 10


def test_a_worker_lost_in_the_last_second_is_still_noted():
    """Checks come at most once a second while batches return; the campaign's last one is
    forced: a worker that died just before the end used to be missing from lost_workers."""
    from agilesat.orchestration.campaign import engine

    class Client:
        workers = {"tcp://a": {}, "tcp://b": {}}

        def scheduler_info(self):
            return {"workers": dict(self.workers)}

        def processing(self):
            return {}

    client = Client()
    watcher = engine.WorkerWatch(client)
    watcher.check({})
    del client.workers["tcp://a"]
    watcher.check({})  # within the second: not looked at
    assert watcher.lost == []
    watcher.check({}, force=True)
    assert watcher.lost == [{"worker": "tcp://a", "runs_in_flight": []}]


@pytest.mark.parametrize(
    "keep, match",
    [
        (
            "CmgCluster.h_rotor",
            "CmgCluster has 'h_rotor' as a parameter; a run records the "
            "outputs, CmgCluster's are: delta, delta_dot, h, hdot, singularity",
        ),
        ("SatelliteDynamics.nope", "SatelliteDynamics has no variable 'nope'; .* w_BI_B"),
        (
            "SatelliteDynamics.w_BI_B[4]",
            "the elements of SatelliteDynamics.w_BI_B are w_BI_B\\[1\\] \\.\\. w_BI_B\\[3\\]",
        ),
        ("Nobody.x", "no component 'Nobody'"),
    ],
)
def test_keep_of_what_is_not_recorded_is_refused_before_the_campaign(tmp_path, keep, match):
    """Not one run: the error names the signal and the outputs there are (it used to be
    a ColumnError inside every run)."""
    from agilesat.orchestration.campaign import run_campaign

    with pytest.raises(ValueError, match=f"--keep {re.escape(keep)}: {match}"):
        run_campaign(Spec("scan_pitch", keep=[keep], stop=1.0), tmp_path / "out")
    assert not (tmp_path / "out").exists()
    plan = Plan(Spec("scan_pitch", keep=["CmgCluster.h", "SatelliteDynamics.w_BI_B[2]"]))
    kept = [f"CmgCluster.h[{i}]" for i in (1, 2, 3)] + ["SatelliteDynamics.w_BI_B[2]"]
    assert plan.kept == kept and plan.signals[:4] == kept  # then the requirements' signals
    assert "PitchManeuverController.pitch_ref" in plan.signals[4:]


def test_choice_takes_the_names_of_a_named_choice_and_records_them():
    """The table and the replay command get the name, as ``--set`` takes it; the draws
    are those of the numbers 0, 1 (the names' values)."""
    from agilesat.orchestration.campaign import replay_arguments

    named = Plan(Spec("scan_pitch", 20, 3, ["CmgSteering.law=choice(PSEUDO_INVERSE, sr_inverse)"]))
    numbers = Plan(Spec("scan_pitch", 20, 3, ["CmgSteering.law=choice(0, 1)"]))
    drawn = [named.run_values(i)["CmgSteering.law"] for i in range(20)]
    assert set(drawn) == {"PSEUDO_INVERSE", "SR_INVERSE"}
    assert drawn == [numbers.run_values(i)["CmgSteering.law"] for i in range(20)]
    assert named.kinds == {"CmgSteering.law": "s"}
    sweep = Plan(Spec("scan_pitch", 1, 0, ["CmgSteering.law=values(SR_INVERSE, PSEUDO_INVERSE)"]))
    assert [sweep.run_values(i) for i in (0, 1)] == [
        {"CmgSteering.law": "SR_INVERSE"},
        {"CmgSteering.law": "PSEUDO_INVERSE"},
    ]
    index = drawn.index("SR_INVERSE")
    assert replay_arguments(named, index)[-2:] == ["--set", "CmgSteering.law=SR_INVERSE"]


def test_integers_give_each_run_its_own_seed_within_the_bounds():
    """A noise seed (an Integer parameter) takes integers(lo, hi): whole numbers, both
    bounds reachable, uniform (χ² over the 5 values of 2000 draws), recorded as integers."""
    plan = Plan(Spec("video_sar:sensed", 2000, 7, ["Gyro.seed=integers(3, 7)"]))
    seeds = [plan.run_values(i)["Gyro.seed"] for i in range(2000)]
    assert all(type(x) is int for x in seeds) and plan.kinds == {"Gyro.seed": "i"}
    drawn = np.array(seeds)
    counts = np.bincount(drawn, minlength=8)[3:]
    assert counts.sum() == 2000 and counts.min() > 0
    assert ((counts - 400) ** 2 / 400).sum() < 13.28  # χ²(4) at 99 %
    with pytest.raises(ValueError, match=r"integers\(lo, hi\) takes whole numbers"):
        dispersion.parse("Gyro.seed=integers(0, 2.5)")
    with pytest.raises(ValueError, match="use choice\\(\\), values\\(\\) or integers\\(\\)"):
        Plan(Spec("video_sar:sensed", 2, 0, ["Gyro.seed=normal(0, 1)"]))


def test_the_sensed_variants_ship_their_sensor_dispersions_on_top_of_the_scenarios():
    from agilesat.orchestration.campaign import shipped_files

    for name in ("video_sar", "scan_pitch", "payload_sweep"):
        files = shipped_files(f"{name}:sensed")
        assert [f.name for f in files] == [f"{name}.toml", f"{name}.sensed.toml"]
        vary = [d.text for f in files for d in dispersion.load(f)[0]]
        plan = Plan(Spec(f"{name}:sensed", 1, vary=vary))
        assert {"StarTracker.seed", "Gyro.seed"} <= set(plan.columns)
        assert [f.name for f in shipped_files(name)] == [f"{name}.toml"]


def test_a_requirement_judged_over_the_campaign_has_no_pass_rate_per_run():
    plan = Plan(Spec("scan_pitch", runs=1, vary=["CmgCluster.h_rotor=normal(16.65, 0.1)"]))
    catalog = {
        "metrics": CATALOG["metrics"],
        "requirements": {"m": {"statement": "APE ≤ 1", "judged_over": "campaign"}},
    }
    array = report.table(plan, {0: _record(0, plan, 2.0, "not evaluated")}, catalog)
    assert report.pass_rates(array, catalog) == {}


MISSION = """
import math
from agilesat.orchestration.mission import Pointing, Scenario
from agilesat.orchestration.pointing import PointingRequirement
from agilesat.orchestration.scenarios.payload_sweep import SYSTEM

def ape(interpretation):
    return PointingRequirement("APE", math.radians(0.05), 0.9973, interpretation)

SCENARIO = Scenario("mission", "two APE requirements", SYSTEM, requirements=[
    Pointing("per_run", ape("temporal"), reference="SatelliteDynamics.q_BO"),
    Pointing("over_runs", ape("ensemble"), reference="OrbitEnvironment.q_OI"),
])
"""


def test_a_pointing_requirement_judged_run_by_run_is_not_judged_over_the_campaign(tmp_path):
    """A temporal requirement states each run's share of its time: the campaign gives it a
    pass rate (its verdict in every run), not a second verdict over the runs, and keeps
    none of its columns for one; an ensemble requirement is judged over the runs."""
    (tmp_path / "mission.py").write_text(MISSION)
    plan = Plan(Spec(str(tmp_path / "mission.py"), runs=2))
    assert [r.name for r in plan.ensemble] == ["over_runs"]
    assert not [c for c in plan.signals if "q_BO" in c]


def test_progress_of_a_resumed_campaign_counts_the_earlier_failures(capsys):
    import sys

    progress = report.Progress(6, 3, period=0.0, stream=sys.stdout, before={"ok": 1, "failed": 2})
    progress.update("error")
    assert "4/6 runs done (2 failed, 1 error)" in capsys.readouterr().out


def test_the_failure_list_says_how_many_more_there_are():
    from agilesat.orchestration.cli.campaign import format_campaign

    failures = [
        {"index": i, "status": "failed", "message": f"m{i}", "replay": ""} for i in range(8)
    ]
    summary = {
        "runs": {"planned": 10, "made": 10, "ok": 2, "failed": 8, "error": 0, "lost": 0},
        "lost_workers": [],
        "statistics": {},
        "pass_rates": {},
        "grid_pass_rates": [],
        "failures": failures,
    }
    lines = format_campaign(summary).splitlines()
    assert [line.split(":")[0] for line in lines[2:7]] == [f"  run {i} failed" for i in range(5)]
    assert lines[7].startswith("  and 3 more")


def test_a_worker_that_left_with_no_run_seen_is_not_said_to_have_had_runs_re_run():
    from agilesat.orchestration.cli.campaign import format_campaign

    summary = {
        "runs": {"planned": 4, "made": 4, "ok": 4, "failed": 0, "error": 0, "lost": 0},
        "lost_workers": [
            {"worker": "tcp://a", "runs_in_flight": []},
            {"worker": "tcp://b", "runs_in_flight": [2, 3]},
        ],
        "statistics": {},
        "pass_rates": {},
        "grid_pass_rates": [],
        "failures": [],
    }
    lines = format_campaign(summary).splitlines()
    assert lines[1] == (
        "  worker tcp://a left; no run of it was seen in flight (Dask re-runs any it held)"
    )
    assert lines[2] == "  worker tcp://b died; Dask re-ran runs [2, 3] elsewhere"


def test_a_histogram_says_what_the_metric_is_and_marks_the_requirement_and_the_paper(
    tmp_path, monkeypatch
):
    import math

    drawn = []
    monkeypatch.setattr(report, "_save", lambda fig, ax, path: drawn.append(ax) or path)
    meta = {
        "unit": "rad",
        "display_unit": "deg",
        "description": "max tilt of the pitch axis",
        "requirement": {"max": math.radians(2.0)},
        "paper": math.radians(1.5),
    }
    array = np.array([(math.radians(x),) for x in (0.5, 1.0, 1.2)], dtype=[("m", float)])
    [path] = report.histograms(array, {"metrics": {"m": meta}}, tmp_path)
    [ax] = drawn
    assert path.name == "hist_m.png" and ax.get_xlabel() == "m [°]"
    assert ax.get_title().startswith("max tilt of the pitch axis\n3 runs")
    marks = {line.get_label(): line.get_xdata()[0] for line in ax.lines}
    assert marks == pytest.approx({"requirement (max)": 2.0, "paper": 1.5})


@pytest.fixture
def hidden(fmus, tmp_path):
    """scan_pitch.ssd with SatelliteDynamics and CmgSteering as FMU files whose names are
    none of ours (copies: nothing but their model descriptions says what they are, as of
    a third party's FMUs): the .ssd's path."""
    from agilesat.orchestration.scenarios import get

    text = get("scan_pitch").ssd.read_text()
    for name, path in fmus.items():
        alias = {"SatelliteDynamics": "Hub", "CmgSteering": "Steering"}.get(name)
        if alias:
            (tmp_path / f"{alias}.fmu").write_bytes(path.read_bytes())
            path = tmp_path / f"{alias}.fmu"
        text = text.replace(f'source="../../fmus/build/{name}.fmu"', f'source="{path}"')
    (tmp_path / "system.ssd").write_text(text)
    return str(tmp_path / "system.ssd")


def test_a_campaign_of_fmus_not_ours_is_checked_and_drawn_from_their_model_descriptions(hidden):
    """Shapes, types, start values, named choices and units come from the model
    descriptions, for any FMU: the same plan as of ours, and the same errors before any
    run (whole-variable dispersions, names, elements, causality)."""
    from agilesat.orchestration.scenarios import get

    vary = [
        "SatelliteDynamics.inertia=inertia(0.03, 1deg)",
        "CmgSteering.law=choice(PSEUDO_INVERSE, sr_inverse)",
        "CmgSteering.gimbal_axis=rotate(0.1deg)",
    ]
    keep = ["SatelliteDynamics.w_BI_B"]
    theirs = Plan(Spec(hidden, 5, 3, vary, keep=keep, stop=1.0))
    ours = Plan(Spec(str(get("scan_pitch").ssd), 5, 3, vary, keep=keep, stop=1.0))
    assert theirs.fmus["SatelliteDynamics"] == "Hub"
    assert theirs.kinds == ours.kinds and theirs.units == ours.units
    assert theirs.units["SatelliteDynamics.w_BI_B[2]"] == "rad/s"
    for i in range(5):
        assert theirs.run_values(i) == ours.run_values(i)
    for text, match in [
        ("SatelliteDynamics.inertai=normal(1, 0.1)", "Hub has no variable 'inertai'; did you"),
        ("SatelliteDynamics.inertia[4,4]=normal(1, 0.1)", r"has shape \(3, 3\); elements"),
        ("SatelliteDynamics.w_BI_B=rotate(1deg)", "Real output; only numeric parameters"),
        ("CmgSteering.law=choice(FASTEST, 0)", "law must be one of 0 \\(PSEUDO_INVERSE\\)"),
        ("SatelliteDynamics.inertia=rotate(1deg)", "rotate\\(\\) turns unit vectors"),
    ]:
        with pytest.raises(ValueError, match=match):
            Plan(Spec(hidden, 2, vary=[text], stop=1.0))
