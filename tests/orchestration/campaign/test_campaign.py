"""Campaigns end to end: the CLI on a LocalCluster, reproducibility, replay with
``agilesat run``, resume after a real interruption, extension, recorded failures, a real
scheduler with two workers (one killed mid-campaign), and bit identity of a reused worker.
Interruptions and kills come at a chosen run ($AGILESAT_TEST_SIGNAL,
orchestration/cosim/signals.py), not after a wait: they cannot race the runs.
"""

import contextlib
import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from helpers import agilesat, run_python

pytestmark = [pytest.mark.slow, pytest.mark.integration]

STOP = "4"
VARY = [
    "--vary",
    "SatelliteDynamics.inertia=inertia(0.03, 1deg)",
    "--vary",
    "CmgCluster.delta0=+normal(0, 0.5deg)",
    "--vary",
    "CmgCluster.gimbal_axis=rotate(0.1deg)",
    "--vary",
    "SatelliteDynamics.rate0[2]=+normal(0, 0.01deg)",
]
COMMAND = [
    "campaign",
    "scan_pitch",
    "--no-report",
    "--stop",
    STOP,
    "--seed",
    "11",
    *VARY,
    "--keep",
    "SatelliteDynamics.w_BO_B[2]",
    "--no-progress",
]
MACHINE = (
    "worker",
    "seconds",
    "cpu_seconds",
)  # where and how fast: the only columns that may differ


def rows(out):
    with (out / "runs.csv").open() as stream:
        return [{k: v for k, v in r.items() if k not in MACHINE} for r in csv.DictReader(stream)]


def journal(out):
    return [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]


@pytest.fixture(scope="module")
def three(tmp_path_factory, fmus):
    out = tmp_path_factory.mktemp("campaign") / "three"
    result = agilesat(*COMMAND, "--runs", "3", "--workers", "2", "--out", out)
    assert result.returncode in (0, 3), result.stdout + result.stderr
    # no Dask noise as the cluster closes (a CommClosedError traceback was seen)
    assert "Traceback" not in result.stderr and "Error" not in result.stderr, result.stderr
    return out


def test_same_command_gives_the_identical_table(three, tmp_path):
    again = tmp_path / "again"
    result = agilesat(*COMMAND, "--runs", "3", "--workers", "1", "--out", again)
    assert result.returncode in (0, 3), result.stderr
    first = rows(three)
    assert len(first) == 3 and all(r["status"] == "ok" for r in first)
    assert rows(again) == first
    assert np.array_equal(np.load(three / "signals.npy"), np.load(again / "signals.npy"))
    summary = json.loads((three / "campaign.json").read_text())
    assert summary["runs"]["ok"] == 3 and summary["spec"]["seed"] == 11
    assert summary["pass_rates"]["imaging_pitch_rate_mean"]["method"] == "Clopper-Pearson"
    assert "hist_max_gimbal_rate.png" in summary["figures"]
    assert "envelope_SatelliteDynamics.w_BO_B_2.png" in summary["figures"]


def test_any_run_replays_exactly_with_agilesat_run(three, tmp_path):
    row = rows(three)[2]
    dispersed = list(row)[list(row).index("grid") + 1 : list(row).index("status")]
    assert len(dispersed) == 9 + 6 + 18 + 1
    sets = [arg for key in dispersed for arg in ("--set", f"{key}={row[key]}")]
    result = agilesat(
        "run", "scan_pitch", "--stop", STOP, *sets, "--out", tmp_path, "--no-figures", "--no-report"
    )
    assert result.returncode in (0, 3), result.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    for name, metric in summary["metrics"].items():
        value = metric["value"]
        assert (row[name] == "") if value is None else float(row[name]) == value, name
    replayed = np.load(tmp_path / "results.npz")
    column = list(replayed["names"]).index("SatelliteDynamics.w_BO_B[2]")
    assert np.array_equal(np.load(three / "signals.npy")[2, 0], replayed["data"][:, column])


def test_resume_after_an_interruption_and_extend(three, tmp_path, monkeypatch):
    out = tmp_path / "resumed"
    # SIGTERM once two runs are in the journal ($AGILESAT_TEST_SIGNAL: no race with the runs)
    monkeypatch.setenv("AGILESAT_TEST_SIGNAL", "SIGTERM@run:2")
    result = agilesat(*COMMAND, "--runs", "40", "--workers", "1", "--out", out)
    monkeypatch.delenv("AGILESAT_TEST_SIGNAL")
    assert result.returncode == 143, result.stdout + result.stderr  # 128 + SIGTERM
    summary = json.loads((out / "campaign.json").read_text())
    assert summary["status"] == "interrupted"
    made = journal(out)
    # after the batch that brought the journal to 2 runs (at most 2 + 19: a batch is at most
    # an even share of what is left, 38 runs over 2 batches in flight)
    assert 2 <= len(made) <= 21 and len(rows(out)) == len(made)
    assert summary["runs"]["made"] == len(made)

    result = agilesat(*COMMAND, "--runs", "40", "--workers", "1", "--out", out, "--resume")
    assert result.returncode in (0, 3), result.stderr
    assert f"{len(made)} already made" in result.stderr
    after = journal(out)
    assert after[: len(made)] == made  # finished runs not redone
    assert sorted(r["index"] for r in after) == list(range(40))
    assert rows(out)[:3] == rows(three)  # run i is run i, whatever N

    result = agilesat(*COMMAND, "--runs", "42", "--workers", "1", "--out", out, "--resume")
    assert result.returncode in (0, 3), result.stderr
    assert journal(out)[:40] == after and len(journal(out)) == 42
    assert np.load(out / "signals.npy").shape[0] == 42
    assert not np.isnan(np.load(out / "signals.npy")).any()

    result = agilesat(*COMMAND, "--runs", "42", "--workers", "1", "--out", out)
    assert result.returncode == 1 and "--resume" in result.stderr
    result = agilesat(*COMMAND, "--runs", "42", "--seed", "12", "--out", out, "--resume")
    assert result.returncode == 1 and "seed: 12 here, 11 in the campaign" in result.stderr


@pytest.mark.parametrize("when", ["start", "fresh start", "close", "nanny"])
def test_an_interrupt_while_the_cluster_starts_or_closes_keeps_the_summary(
    three, tmp_path, monkeypatch, when
):
    """Ctrl-C or SIGTERM outside the loop over the runs (the LocalCluster starting, on a
    resumed or a new campaign, or closing once every run is made) summarises the journal
    in campaign.json; it used to escape and leave the campaign "running" (CI saw it: a
    fast campaign finished before the test's SIGTERM, which came while the cluster
    closed).  While a resumed campaign runs, campaign.json says "running" (it said the
    last run's "complete").  "nanny": a terminal's Ctrl-C reaches the worker processes
    Dask starts too, and Dask says "Nanny failed to start" (a RuntimeError): the signal the
    campaign's handler took is what stopped it (it exited 1, campaign.json "running")."""
    from agilesat.orchestration import cli
    from agilesat.orchestration.campaign import engine

    out = tmp_path / "copy"
    if when != "fresh start":
        shutil.copytree(three, out)
    real = engine.cluster
    seen = []  # campaign.json's status while the runs go on

    @contextlib.contextmanager
    def cluster(workers=None, scheduler=None, *settings):
        seen.append(json.loads((out / "campaign.json").read_text())["status"])
        if when == "nanny":  # as cluster() while the LocalCluster starts: a flag
            monkeypatch.setattr(engine.INTERRUPTS, "deferred", True)
            engine.INTERRUPTS(signal.SIGINT, None)
            raise RuntimeError("Nanny failed to start.")
        if when != "close":
            raise KeyboardInterrupt
        with real(workers, scheduler, *settings) as client:
            yield client
        raise KeyboardInterrupt  # as if it came while the cluster closed

    monkeypatch.setattr(engine, "cluster", cluster)
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}  # it sets its own
    resume = ["--resume"] if when != "fresh start" else []
    try:
        code = cli.main([*COMMAND, "--runs", "4", "--workers", "1", "--out", str(out), *resume])
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    summary = json.loads((out / "campaign.json").read_text())
    made = {"start": 3, "fresh start": 0, "close": 4, "nanny": 3}[when]
    assert seen == ["running"]
    assert summary["runs"]["made"] == len(rows(out)) == made
    assert summary["status"] == ("complete" if when == "close" else "interrupted")
    assert code in (0, 3) if when == "close" else code == 130
    assert rows(out)[:3] == (rows(three) if made else [])


@pytest.mark.parametrize("held", ["the same", "another command", "other versions", "none"])
def test_a_resumed_complete_campaign_makes_its_nominal_run_only_if_it_differs(
    three, tmp_path, monkeypatch, capsys, held
):
    """Resuming a complete campaign makes no run; its finish kept making the nominal run
    again.  It is kept when campaign.json has it from the same command and versions, made
    again (and stderr says why) otherwise; either way the files are those of the fresh
    finish, byte for byte."""
    from agilesat.orchestration import cli
    from agilesat.orchestration.campaign import isolated

    out = tmp_path / "copy"
    shutil.copytree(three, out)
    summary = json.loads((out / "campaign.json").read_text())
    if held == "another command":
        summary["nominal"]["command"] += " --set CmgCluster.h_rotor=1.0"
    elif held == "other versions":
        summary["versions"]["numpy"] = "0.0"
    elif held == "none":
        del summary["nominal"]
    (out / "campaign.json").write_text(json.dumps(summary, indent=2) + "\n")
    made = []
    real = isolated.start
    monkeypatch.setattr(isolated, "start", lambda *a: made.append(a[0]) or real(*a))
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}  # it sets its own
    try:
        code = cli.main([*COMMAND, "--runs", "3", "--workers", "2", "--out", str(out), "--resume"])
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    assert code in (0, 3)
    err = capsys.readouterr().err
    assert made == ([] if held == "the same" else ["scan_pitch"])
    assert ("(kept: campaign.json has it" in err) == (held == "the same")
    reason = {"another command": "was another command", "other versions": "(numpy)"}
    assert (f"{reason[held]}" in err) if held in reason else ": made again" not in err
    for name in ("campaign.json", "runs.csv"):
        assert (out / name).read_text() == (three / name).read_text(), name


def test_resume_after_the_process_is_killed(three, tmp_path, monkeypatch):
    """SIGKILL: no clean-up at all; the journal and the spec written at the start suffice."""
    out = tmp_path / "killed"
    monkeypatch.setenv("AGILESAT_TEST_SIGNAL", "SIGKILL@run:1")  # once a run is journaled
    result = agilesat(*COMMAND, "--runs", "30", "--workers", "1", "--out", out)
    monkeypatch.delenv("AGILESAT_TEST_SIGNAL")
    assert result.returncode == -signal.SIGKILL
    made = journal(out)
    assert len(made) == 1 and not (out / "runs.csv").exists()  # the first task is one run
    result = agilesat(*COMMAND, "--runs", "30", "--workers", "1", "--out", out, "--resume")
    assert result.returncode in (0, 3), result.stderr
    assert journal(out)[: len(made)] == made
    assert rows(out)[:3] == rows(three)


def test_failures_are_recorded_outcomes(tmp_path, fmus):
    """A run that stops (bad value) and one that is diagnosed (exit 3 in run) are rows
    with their messages; the campaign goes on and exits 3."""
    out = tmp_path / "failures"
    result = agilesat(
        "campaign",
        "--no-report",
        "scan_pitch",
        "--stop",
        "100",
        "--workers",
        "2",
        "--vary",
        "PitchManeuverController.scan_rate=values(-0.8deg, -0.7deg)",
        "--vary",
        "CmgCluster.rate_limit=values(0.6, -1)",
        "--out",
        out,
        "--no-progress",
    )
    assert result.returncode == 3, result.stderr
    table = rows(out)
    assert [r["status"] for r in table] == ["ok", "error", "failed", "error"]
    required = "requirement imaging_pitch_rate_mean in [-0.82, -0.78] °/s not met: "
    assert re.search(re.escape(required) + r"-0\.6\d+ °/s", table[2]["message"])
    assert "rate_limit (-1.0) and accel_limit (0.5) must be positive" in table[1]["message"]
    assert table[0]["met_imaging_pitch_rate_mean"] == "True"
    assert table[2]["met_imaging_pitch_rate_mean"] == "False"
    summary = json.loads((out / "campaign.json").read_text())
    assert [f["index"] for f in summary["failures"]] == [1, 2, 3]
    assert "CmgCluster.rate_limit=-1.0" in summary["failures"][0]["replay"]
    rate = summary["pass_rates"]["imaging_pitch_rate_mean"]
    assert (rate["met"], rate["runs"]) == (1, 4)


@pytest.fixture
def dask_cluster(tmp_path, request):
    """A `dask scheduler` and two `dask worker` processes on 127.0.0.1 (always killed);
    the first worker with ``$AGILESAT_TEST_SIGNAL`` = the fixture's parameter, if any."""
    bin_dir = os.path.dirname(sys.executable)
    file = tmp_path / "scheduler.json"
    processes = []
    first_worker = {"AGILESAT_TEST_SIGNAL": getattr(request, "param", "")}

    def start(*args, env=None):
        processes.append(
            subprocess.Popen(
                [os.path.join(bin_dir, "dask"), *args],
                cwd=tmp_path,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                start_new_session=True,
                env={**os.environ, **(env or {})},
            )
        )
        return processes[-1]

    try:
        start(
            "scheduler",
            "--host",
            "127.0.0.1",
            "--port",
            "0",
            "--no-dashboard",
            "--scheduler-file",
            str(file),
        )
        deadline = time.monotonic() + 60
        while not file.exists():
            assert time.monotonic() < deadline, "no scheduler"
            time.sleep(0.2)
        address = json.loads(file.read_text())["address"]
        workers = [
            start(
                "worker",
                address,
                "--nthreads",
                "1",
                "--no-nanny",
                "--no-dashboard",
                "--host",
                "127.0.0.1",
                env=first_worker if k == 0 else None,
            )
            for k in range(2)
        ]
        from distributed import Client

        with Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=60)
        yield address, workers
    finally:
        for process in processes:
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGKILL)
            process.wait()


@pytest.mark.parametrize("dask_cluster", ["SIGKILL@worker:1"], indirect=True)
def test_distributed_campaign_survives_a_worker_killed_midway(dask_cluster, tmp_path, fmus):
    """The first worker kills itself (SIGKILL) as it starts its first run
    ($AGILESAT_TEST_SIGNAL): Dask runs what it held on the other."""
    address, workers = dask_cluster
    out = tmp_path / "remote"
    result = agilesat(
        "campaign",
        "--no-report",
        "scan_pitch",
        "--stop",
        "20",
        "--runs",
        "30",
        *VARY,
        "--scheduler",
        address,
        "--out",
        out,
        "--no-progress",
    )
    output = result.stdout + result.stderr
    assert result.returncode in (0, 3), output
    summary = json.loads((out / "campaign.json").read_text())
    assert summary["runs"]["ok"] == 30, output
    assert summary["cluster"] == {"scheduler": address, "workers": 2}
    pids = {r["pid"] for r in journal(out)}
    assert workers[1].pid in pids
    assert len(summary["lost_workers"]) == 1, output
    assert "left; Dask re-runs the runs it held" in output
    # after the kill, every run is made by the surviving worker
    later = journal(out)[len(journal(out)) // 2 :]
    assert {r["pid"] for r in later} == {workers[1].pid}


def test_python_api_returns_the_table(dask_cluster, tmp_path):
    from agilesat.orchestration.campaign import campaign

    address, _ = dask_cluster
    table = campaign(
        "payload_sweep",
        stop=2.0,
        scheduler=address,
        out_dir=tmp_path / "api",
        vary=["Flywheel.torque_limit=values(0.2, 2.0)"],
        progress=False,
        as_frame=False,
    )
    assert table.dtype.names[:4] == ("index", "seed", "grid", "Flywheel.torque_limit")
    assert list(table["Flywheel.torque_limit"]) == [0.2, 2.0]
    # within 2 s the 0.2 N·m wheel already misses the pointing requirement, 2 N·m meets it
    assert list(table["status"]) == ["failed", "ok"]
    assert list(table["met_pointing_accuracy"]) == [False, True]
    assert "requirement pointing_accuracy ≤ 0.032° not met: " in table["message"][0]


REUSE = """
import sys
import numpy as np
from agilesat.orchestration import RunOptions
from agilesat.orchestration.campaign.worker import run_one
nominal = RunOptions(stop=20.0, parameters={"CmgCluster.h_rotor": 16.65})
other = RunOptions(
    stop=20.0, parameters={"CmgCluster.h_rotor": 17.0, "SatelliteDynamics.inertia[1,1]": 900.0}
)
keep = ["SatelliteDynamics.q_BI[1]", "SatelliteDynamics.w_BI_B[2]", "CmgCluster.delta[3]"]
order = sys.argv[1].split(",")
runs = [run_one(i, "scan_pitch", nominal if k == "a" else other, keep, 401)
        for i, k in enumerate(order)]
assert all(r["status"] == "ok" for r in runs), [r["message"] for r in runs]
np.save(sys.argv[2], np.stack([r["signals"] for r in runs]))
"""


def test_a_reused_worker_is_bit_identical_to_a_fresh_process(tmp_path, fmus):
    reused, fresh = tmp_path / "reused.npy", tmp_path / "fresh.npy"
    result = run_python(REUSE, "a,b,a,a", reused)
    assert result.returncode == 0, result.stderr
    result = run_python(REUSE, "a", fresh)
    assert result.returncode == 0, result.stderr
    runs, alone = np.load(reused), np.load(fresh)[0]
    assert not np.isnan(alone).any()
    assert not np.array_equal(runs[1], alone)  # the other parameters do differ
    for k in (0, 2, 3):
        assert np.array_equal(runs[k], alone)


BATCHED = [
    "CmgCluster.rate_limit=values(0.6, -1)",
    "SatelliteDynamics.rate0[2]=+normal(0, 0.01deg)",
]
ONE_PER_TASK = """
import json, sys
from agilesat.orchestration.campaign import engine, run_campaign, Spec
engine.MAX_BATCH = 1
spec = Spec("scan_pitch", 8, 0, json.loads(sys.argv[2]), stop=0.5)
run_campaign(spec, sys.argv[1], workers=1, progress=False)
"""


def test_runs_in_one_batch_are_each_their_own_outcome(tmp_path, fmus):
    """Short runs go several to a Dask task; a run that stops inside a batch is its own
    row with its message and the others of its batch are made; the table is the one of
    runs made one per task (run i depends on i alone)."""
    out = tmp_path / "batched"
    result = agilesat(
        "campaign",
        "--no-report",
        "scan_pitch",
        "--stop",
        "0.5",
        "--runs",
        "8",
        "--workers",
        "1",
        *[arg for vary in BATCHED for arg in ("--vary", vary)],
        "--out",
        out,
        "--no-progress",
    )
    assert result.returncode == 3, result.stderr
    made = {r["index"]: r for r in journal(out)}
    assert sorted(made) == list(range(16))
    batches = {}
    for r in made.values():
        batches.setdefault(r["batch"], []).append(r["index"])
    # several runs shared a task, one that stopped with one that did not
    assert any({i % 2 for i in b} == {0, 1} for b in batches.values()), batches
    for index, r in made.items():
        if index % 2:  # rate_limit -1
            assert r["status"] == "error"
            assert "rate_limit (-1.0) and accel_limit (0.5) must be positive" in r["message"]
        else:
            assert r["status"] == "ok", r["message"]
    one_by_one = tmp_path / "one_by_one"
    result = run_python(ONE_PER_TASK, one_by_one, json.dumps(BATCHED))
    assert result.returncode == 0, result.stderr
    assert {r["batch"] for r in journal(one_by_one)} == set(range(16))
    assert rows(one_by_one) == rows(out)


def test_a_named_choice_is_recorded_by_name_and_replays(tmp_path, fmus):
    out = tmp_path / "laws"
    result = agilesat(
        "campaign",
        "--no-report",
        "scan_pitch",
        "--stop",
        STOP,
        "--workers",
        "1",
        "--vary",
        "CmgSteering.law=values(PSEUDO_INVERSE, SR_INVERSE)",
        "--out",
        out,
        "--no-progress",
    )
    assert result.returncode in (0, 3), result.stderr
    assert "CmgSteering.law=SR_INVERSE: " in result.stdout
    table = rows(out)
    assert [r["CmgSteering.law"] for r in table] == ["PSEUDO_INVERSE", "SR_INVERSE"]
    assert table[0]["max_abs_output_torque"] != table[1]["max_abs_output_torque"]
    result = agilesat(
        "run",
        "scan_pitch",
        "--stop",
        STOP,
        "--set",
        "CmgSteering.law=SR_INVERSE",
        "--out",
        tmp_path / "replay",
        "--no-figures",
        "--no-report",
    )
    assert result.returncode in (0, 3), result.stderr
    summary = json.loads((tmp_path / "replay" / "summary.json").read_text())
    for name, metric in summary["metrics"].items():
        value = metric["value"]
        assert (table[1][name] == "") if value is None else float(table[1][name]) == value


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_to_the_process_group_says_one_line_and_no_tracebacks(tmp_path, fmus, signum):
    """Ctrl-C in a terminal signals the whole process group (the campaign, its nannies and
    workers): one line says what was kept and how to resume; no worker prints a traceback
    (they printed ~60 lines of CancelledError/KeyboardInterrupt)."""
    from helpers import ROOT

    out = tmp_path / "group"
    process = subprocess.Popen(
        [sys.executable, "-m", "agilesat.orchestration", *COMMAND]
        + ["--runs", "400", "--workers", "2", "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        cwd=ROOT,
    )
    try:
        deadline = time.monotonic() + 300
        while not ((out / "runs.jsonl").exists() and len(journal(out)) >= 2):
            assert process.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        os.killpg(process.pid, signum)
        stdout, stderr = process.communicate(timeout=300)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    summary = json.loads((out / "campaign.json").read_text())
    assert process.returncode == 128 + signum, stdout + stderr
    assert summary["status"] == "interrupted"
    assert stdout.splitlines() == [
        f"interrupted by {signal.Signals(signum).name}: {summary['runs']['made']} of 400 runs "
        f"kept in {out}/ (runs.csv, campaign.json); the same command with --resume continues it"
    ]
    assert "Traceback" not in stderr and "Error" not in stderr, stderr
