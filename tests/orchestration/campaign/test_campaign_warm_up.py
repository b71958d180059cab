"""A campaign worker's warm-up (orchestration/campaign/worker.py): long enough that the
runs' compiled kernels load in it, short beside a run, said in its batch's first record,
and a warm-up that raises leaves the run its own outcome."""

import dataclasses
import json

import pytest

from agilesat.components.runtime.jit import PAYS_AFTER
from agilesat.orchestration import RunOptions
from agilesat.orchestration.campaign.report import warm_ups
from agilesat.orchestration.campaign.worker import (
    WARM_UP_FRACTION,
    WARM_UP_STEPS,
    warm_up_steps,
)
from helpers import run_python


@pytest.mark.parametrize("steps", [1, 3, 40, 400, 4000, 24_000])
@pytest.mark.parametrize("share", [1, 2, 20, 555, 5000])
def test_the_warm_up_expects_the_compiled_tier_where_the_runs_do(steps, share):
    n = warm_up_steps(steps, share)
    assert 1 <= n <= steps
    if n * share >= PAYS_AFTER:  # it loads the compiled kernels: no longer than needed
        assert n == min(WARM_UP_STEPS, steps) or (n - 1) * share < PAYS_AFTER
    if steps * share >= PAYS_AFTER and n * share < PAYS_AFTER:  # only when a tenth is short
        assert n == min(WARM_UP_STEPS, steps) and PAYS_AFTER / share > WARM_UP_FRACTION * steps
    assert n <= max(WARM_UP_STEPS, WARM_UP_FRACTION * steps)


def test_the_campaign_summary_counts_every_warm_up_and_its_error():
    records = {
        0: {"worker": "a", "pid": 1, "warm_up_seconds": 1.5, "warm_up_cpu_seconds": 1.25},
        1: {"worker": "a", "pid": 1, "seconds": 0.1},
        2: {"worker": "b", "pid": 2, "warm_up_seconds": 0.5, "warm_up_cpu_seconds": 0.25}
        | {"warm_up_error": "RuntimeError: x"},
        3: {"status": "lost"},
    }
    summary = warm_ups(records)
    assert (summary["processes"], summary["seconds"], summary["cpu_seconds"]) == (2, 2.0, 1.5)
    assert [w["pid"] for w in summary["workers"]] == [1, 2]
    assert summary["workers"][1]["error"] == "RuntimeError: x"
    assert "error" not in summary["workers"][0]
    assert warm_ups({})["processes"] == 0


BATCHES = """
import json, sys
from agilesat.orchestration import RunOptions, runner
from agilesat.orchestration.campaign.worker import run_batch

if sys.argv[1] == "raising":
    planned = runner.planned
    calls = []

    def first_raises(target, options):
        calls.append(options.stop)
        if len(calls) == 1:
            raise RuntimeError("the warm-up broke")
        return planned(target, options)

    runner.planned = first_raises
batch = [(0, {}), (1, {"SatelliteDynamics.rate0[2]": 0.001})]
options = RunOptions(step=0.05, stop=20.0)
first = run_batch(batch, "scan_pitch", options, [], 401, share=1000)
second = run_batch([(2, {})], "scan_pitch", options, [], 401, share=1000)
print(json.dumps(first + second))
"""


def _records(mode: str) -> list[dict]:
    """Two batches of scan_pitch runs in a fresh process (two runs, then one)."""
    result = run_python(BATCHES, mode)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.splitlines()[-1])


@pytest.mark.slow
@pytest.mark.integration
def test_the_first_batch_of_a_process_says_its_warm_up(fmus):
    first, second, third = _records("plain")
    assert [r["status"] for r in (first, second, third)] == ["ok"] * 3
    assert first["warm_up_seconds"] > 0 and first["warm_up_cpu_seconds"] > 0
    assert "warm_up_error" not in first
    assert not any(k.startswith("warm_up") for r in (second, third) for k in r)
    for r in (first, second, third):
        assert 0 < r["cpu_seconds"] and 0 < r["seconds"]


@pytest.mark.slow
@pytest.mark.integration
def test_a_warm_up_that_raises_is_said_and_the_run_makes_its_own_outcome(fmus):
    first, second, third = _records("raising")
    assert first["warm_up_error"] == "RuntimeError: the warm-up broke"
    assert [r["status"] for r in (first, second, third)] == ["ok"] * 3


HOOKED = """
import sys
from agilesat.orchestration import RunOptions, runner
from agilesat.orchestration.campaign.worker import run_batch

planned = runner.planned

def said(target, options):
    print("run to", options.stop, flush=True)
    return planned(target, options)

runner.planned = said
run_batch([(0, {})], "scan_pitch", RunOptions(step=0.05, stop=20.0), [], 401, share=1000)
print("done", flush=True)
"""


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("k,calls", [(0, []), (1, ["run to 0.25"])])
def test_the_signal_hook_of_the_warm_up_is_run_zero(fmus, monkeypatch, k, calls):
    """``SIGKILL@worker:0`` kills a worker process as it starts its warm-up (nothing run),
    ``SIGKILL@worker:1`` after its warm-up (0.25 s: 5 steps, 5 × 1,000 runs ≥ PAYS_AFTER), as
    its first run starts."""
    monkeypatch.setenv("AGILESAT_TEST_SIGNAL", f"SIGKILL@worker:{k}")
    result = run_python(HOOKED)
    assert result.returncode == -9, result.stderr
    assert result.stdout.splitlines() == calls


@pytest.fixture
def calls(monkeypatch):
    """runner.planned replaced by a recorder of runs (each flies), in a process that has
    made no run and warmed up for nothing: [(target, stop, parameters), ...]."""
    from agilesat.orchestration import runner
    from agilesat.orchestration.campaign import worker

    made = []

    class Recorded:
        def __init__(self, target, options):
            self.target, self.options = target, options

        def swapped(self, values):
            parameters = {**self.options.parameters, **values}
            return Recorded(self.target, dataclasses.replace(self.options, parameters=parameters))

        def run(self, wall=None):
            made.append((self.target, self.options.stop, self.options.parameters))
            return None, {"status": "ok"}

    monkeypatch.setattr(runner, "planned", Recorded)
    monkeypatch.setattr(worker, "_started", 0)
    monkeypatch.setattr(worker, "_warmed", set(), raising=False)
    monkeypatch.setenv("AGILESAT_JIT_RUNS", "1")
    return made


def test_a_process_warms_up_once_per_target_on_its_first_runs_parameters(calls):
    from agilesat.orchestration.campaign.worker import run_batch

    first = {"SatelliteDynamics.rate0[2]": 0.001}
    scan, sar = RunOptions(step=0.05, stop=20.0), RunOptions(step=0.05, stop=200.0)
    a = run_batch([(0, first), (1, {})], "scan_pitch", scan, [], 401, 1000)
    b = run_batch([(2, {})], "scan_pitch", scan, [], 401, 1000)
    c = run_batch([(0, {})], "video_sar", sar, [], 4001, 1000)
    steps = warm_up_steps(400, 1000)
    assert calls[0] == ("scan_pitch", pytest.approx(steps * 0.05), first)  # the warm-up
    assert [call[0] for call in calls] == ["scan_pitch"] * 4 + ["video_sar"] * 2
    assert calls[4][1] == pytest.approx(warm_up_steps(4000, 1000) * 0.05)
    assert ["warm_up_seconds" in r for r in a + b + c] == [True, False, False, True]


def test_a_warm_up_without_a_step_or_stop_is_said_not_raised(calls):
    from agilesat.orchestration.campaign.worker import run_batch

    (record,) = run_batch([(0, {})], "scan_pitch", RunOptions(), [], 0, 1)
    assert record["warm_up_error"].startswith("TypeError")
    assert record["status"] == "ok" and len(calls) == 1  # the run itself, at its defaults


def test_the_campaign_report_prints_the_warm_ups_and_what_they_raised():
    from agilesat.orchestration.cli.campaign import format_campaign

    summary = {
        "runs": {"planned": 2, "made": 2, "ok": 2, "failed": 0, "error": 0, "lost": 0},
        "lost_workers": [],
        "warm_up": warm_ups(
            {
                0: {"worker": "tcp://a", "warm_up_seconds": 0.75, "warm_up_cpu_seconds": 0.5},
                1: {"worker": "tcp://b", "warm_up_seconds": 1.25, "warm_up_cpu_seconds": 1.0}
                | {"warm_up_error": "RuntimeError: no FMU"},
            }
        ),
        "statistics": {},
        "pass_rates": {},
        "grid_pass_rates": [],
        "failures": [],
    }
    lines = format_campaign(summary).splitlines()
    assert lines[1] == (
        "  workers' warm-up: 2.0 s in 2 worker process(es) (0.75, 1.25 s), 1.5 s CPU; "
        "not in the runs' seconds"
    )
    assert lines[2] == "  the warm-up of worker tcp://b raised: RuntimeError: no FMU"
