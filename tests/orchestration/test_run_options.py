"""``agilesat run``'s everyday options (as fmpy simulate has them): one FMU at its defaults,
--start, --output-interval, --record; a run that would write a lot says so first; export
of a system file with --set."""

import json
import math

import numpy as np
import pytest

from agilesat.orchestration import runner
from agilesat.orchestration.cosim.plan import plan_run
from agilesat.orchestration.mission import targets
from agilesat.orchestration.output.results import Results
from agilesat.orchestration.system.ssp import read_system
from helpers import agilesat

slow = [pytest.mark.slow, pytest.mark.integration]


@pytest.fixture(scope="module")
def full_and_chosen(fmus, tmp_path_factory):
    """scan_pitch from 10 to 12 s: every output at every step, and two of them every 0.5 s."""
    base = tmp_path_factory.mktemp("options")
    window = ("--start", 10, "--stop", 12, "--no-figures", "--no-report", "-q")
    full = agilesat("run", "scan_pitch", *window, "--out", base / "full")
    chosen = agilesat(
        "run",
        "scan_pitch",
        *window,
        "--out",
        base / "chosen",
        "--output-interval",
        0.5,
        "--record",
        "SatelliteDynamics.w_BI_B",
        "CmgCluster.h[2]",
    )
    assert full.returncode == 0 and chosen.returncode == 0, full.stderr + chosen.stderr
    return Results.load(base / "full"), Results.load(base / "chosen"), base / "chosen"


@pytest.mark.slow
@pytest.mark.integration
def test_record_and_output_interval_choose_what_is_written_not_what_runs(full_and_chosen):
    full, chosen, _ = full_and_chosen
    assert sorted(chosen.names) == [  # in the master's order of the outputs
        "CmgCluster.h[2]",
        "SatelliteDynamics.w_BI_B[1]",
        "SatelliteDynamics.w_BI_B[2]",
        "SatelliteDynamics.w_BI_B[3]",
        "time",
    ]
    assert np.allclose(chosen.time, np.arange(10.0, 12.001, 0.5), rtol=0, atol=1e-9)
    rows = [int(round((t - 10.0) / 0.05)) for t in chosen.time]
    for name in chosen.names:
        assert np.array_equal(chosen[name], full[name][rows]), name  # the same run, bit for bit
    assert full.time[0] == 10.0 and len(full) == 41


@pytest.mark.slow
@pytest.mark.integration
def test_a_metric_needing_an_output_not_recorded_is_not_evaluated(full_and_chosen):
    summary = json.loads((full_and_chosen[2] / "summary.json").read_text())
    gimbal = summary["metrics"]["max_gimbal_rate"]
    assert gimbal["value"] is None and gimbal["reason"].startswith("not recorded: no ")
    assert summary["status"] == "ok"  # the diagnosis is left out, nothing is judged a failure


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize(
    "options, message",
    [
        (("--output-interval", 0.07), "must be a positive multiple of the step 0.05 s"),
        (("--output-interval", 0.15, "--stop", 1.0), "does not end on a recorded point"),
        (("--record", "CmgCluster.hh"), "no output of that name; did you mean CmgCluster.h"),
    ],
)
def test_a_wrong_option_is_named(fmus, tmp_path, options, message):
    result = agilesat("run", "scan_pitch", "--stop", 1.5, *options, "--out", tmp_path)
    assert result.returncode == 1 and message in result.stderr, result.stderr


@pytest.mark.slow
@pytest.mark.integration
def test_one_fmu_at_its_defaults_and_with_set(fmus, tmp_path):
    """A gyro alone for 200 s: its inputs held at their start values (zero rate: it
    measures its bias, +5 °/h on z), or at what --set gives (0.01 rad/s about z, with its
    500 ppm scale factor).  The mean of 4000 samples of its white noise (ARW 0.15 °/√h at
    20 Hz: σ = 1.95e-4 rad/s per sample) has σ = 3.1e-6 rad/s: within 4σ.  Given no step
    and stop, its FMU file runs its DefaultExperiment."""
    common = ("--step", 0.05, "--stop", 200, "--no-figures", "--no-report")
    alone = agilesat("run", "Gyro", *common, "--out", tmp_path / "a")
    assert alone.returncode == 0, alone.stderr
    bias = 5 * math.pi / 180 / 3600
    at_rest = Results.load(tmp_path / "a")["Gyro.w_meas_B[3]"][1:].mean()
    assert abs(at_rest - bias) < 1.3e-5
    turning = agilesat(
        "run", "Gyro", *common, "--set", "Gyro.w_BI_B=[0, 0, 0.01]", "--out", tmp_path / "b"
    )
    assert turning.returncode == 0, turning.stderr
    measured = Results.load(tmp_path / "b")["Gyro.w_meas_B[3]"][1:].mean()
    assert abs(measured - (0.01 * (1 + 5e-4) + bias)) < 1.3e-5
    summary = json.loads((tmp_path / "b" / "summary.json").read_text())
    assert summary["parameters"]["Gyro.w_BI_B[3]"] == {"value": 0.01, "type": "Real"}
    result = agilesat("run", fmus["Gyro"], "--no-figures", "--no-report", "--out", tmp_path / "c")
    assert result.returncode == 0, result.stderr  # its DefaultExperiment: 0.05 s, 10 s
    assert (
        Results.load(tmp_path / "c").time[-1] == 10.0
        and len(Results.load(tmp_path / "c").time) == 201
    )


def test_a_run_that_would_write_a_lot_says_so_first(fmus, tmp_path):
    system = targets.resolve("scan_pitch").system_file()
    plan = plan_run(system, stop=5e5, out_dir=tmp_path)  # 1e7 steps of 0.05 s
    said = []
    runner._say_size(plan, tmp_path, said.append)
    csv, npz = plan.output_bytes()
    assert csv == (10_000_000 + 1) * (1 + plan.outputs) * 20
    (text,) = said
    assert f"about {(csv + npz) / 2**30:.1f} GiB" in text and "--output-interval" in text
    small = plan_run(system, stop=5e5, out_dir=tmp_path, output_interval=100.0)
    runner._say_size(small, tmp_path, said.append)
    assert len(said) == 1  # 5001 rows: nothing to say


@pytest.mark.slow
@pytest.mark.integration
def test_export_a_system_file_with_set_values(fmus, tmp_path):
    ssd = targets.scenario("scan_pitch").ssd
    result = agilesat(
        "export",
        ssd,
        "--set",
        "CmgSteering.law=SR_INVERSE",
        "--set",
        "SatelliteDynamics.attitude0[2]=100 deg",
        "--out",
        tmp_path / "set.ssp",
    )
    assert result.returncode == 0, result.stderr
    values = {(p.component, p.name): p.value for p in read_system(tmp_path / "set.ssp").parameters}
    assert values[("CmgSteering", "law")] == 1
    assert values[("SatelliteDynamics", "attitude0[2]")] == 100 * math.pi / 180
    assert values[("CmgCluster", "h_rotor")] == 16.65  # the system's own values kept


@pytest.mark.slow
@pytest.mark.integration
def test_a_run_that_ends_before_it_settles_has_no_settling_time(fmus, tmp_path):
    """scan_pitch to 100 s: the pitch rate is still above 0.01 °/s at the end, so there is
    no settling time (it was once stop + step, a number a campaign averaged)."""
    result = agilesat(
        "run", "scan_pitch", "--stop", 100, "--no-figures", "--no-report", "-q", "--out", tmp_path
    )
    assert result.returncode == 0, result.stderr
    settling = json.loads((tmp_path / "summary.json").read_text())["metrics"]["settling_time"]
    assert settling["value"] is None and settling["reason"].startswith("not settled")
    assert "no value" in result.stdout and "(not settled: " in result.stdout
