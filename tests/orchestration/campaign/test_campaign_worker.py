"""What a campaign worker keeps between runs, and that keeping it changes no result: the
system file read once per content (an edited ``.ssd`` or ``.ssv`` is read again), each
FMU bound once, and the worker's memory bounded over many runs.  Each runs in a fresh
process, as a worker would.
"""

import json
import re

import pytest

from agilesat.orchestration.scenarios import get
from agilesat.orchestration.system.ssp import read_system
from helpers import run_python

pytestmark = [pytest.mark.slow, pytest.mark.integration]

EDITS = """
import json, sys
from pathlib import Path
import numpy as np
from agilesat.orchestration import RunOptions
from agilesat.orchestration.system import ssp
from agilesat.orchestration.campaign.worker import run_batch, run_one

ssd, ssv = Path(sys.argv[1]), Path(sys.argv[2])
reads = []
read_ssd = ssp._read_ssd  # what every read of a system goes through
ssp._read_ssd = lambda path, *a, **kw: reads.append(Path(path).name) or read_ssd(path, *a, **kw)
keep = ["SatelliteDynamics.w_BI_B[2]", "CmgCluster.delta[1]", "CmgCluster.h[2]"]

def signals(parameters=None):
    r = run_one(0, str(ssd), RunOptions(stop=4.0, parameters=parameters or {}), keep, 81)
    assert r["status"] == "ok", r["message"]
    return r["signals"]

def edit(path, old, new):
    text = path.read_text()
    assert text.count(old) == 1, old
    path.write_text(text.replace(old, new))

G = '<ssv:Parameter name="delta0[2]">\\n                    <ssv:Real value="0.0"/>'
R = '<ssv:Parameter name="rate0[2]">\\n                    <ssv:Real value="0.0"/>'
nominal = signals()
again = signals()
edit(ssd, G, G.replace("0.0", "0.01"))
gimbal = signals()
edit(ssv, R, R.replace("0.0", "0.001"))
both = signals()
edit(ssd, G.replace("0.0", "0.01"), G)
edit(ssv, R.replace("0.0", "0.001"), R)
set_gimbal = signals({"CmgCluster.delta0[2]": 0.01})
set_both = signals({"CmgCluster.delta0[2]": 0.01, "SatelliteDynamics.rate0[2]": 0.001})
runs = reads[:]
run_batch([(0, {})], str(ssd), RunOptions(stop=4.0), keep, 81)  # the process's warm-up
batch = reads[:]
made = run_batch([(k, {}) for k in range(3)], str(ssd), RunOptions(stop=4.0), keep, 81)
assert all(r["status"] == "ok" for r in made), made
print(json.dumps({
    "runs": runs,
    "batch": reads[len(batch):],
    "batched": bool(all(np.array_equal(r["signals"], nominal) for r in made)),
    "again": bool(np.array_equal(nominal, again)),
    "gimbal differs": not np.array_equal(gimbal, nominal),
    "both differs": not np.array_equal(both, gimbal),
    "gimbal as set": bool(np.array_equal(gimbal, set_gimbal)),
    "both as set": bool(np.array_equal(both, set_both)),
}))
"""


@pytest.fixture
def system_with_ssv(fmus, tmp_path):
    """scan_pitch.ssd with absolute FMU sources, SatelliteDynamics' parameters moved to an
    .ssv file: (ssd, ssv)."""
    text = get("scan_pitch").ssd.read_text()
    for name, path in fmus.items():
        text = text.replace(f'source="../../fmus/build/{name}.fmu"', f'source="{path}"')
    component = text.index('<ssd:Component name="SatelliteDynamics"')
    binding = re.compile(r"<ssd:ParameterBinding>.*?</ssd:ParameterBinding>", re.S)
    match = binding.search(text, component)
    parameter_set = re.search(r"<ssv:ParameterSet.*?</ssv:ParameterSet>", match.group(), re.S)
    ssv = tmp_path / "dynamics.ssv"
    ssv.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        + parameter_set.group().replace(
            "<ssv:ParameterSet",
            '<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"',
            1,
        )
        + "\n"
    )
    ssd = tmp_path / "system.ssd"
    ssd.write_text(
        text[: match.start()]
        + '<ssd:ParameterBinding source="dynamics.ssv"/>'
        + text[match.end() :]
    )
    return ssd, ssv


def test_a_worker_reads_the_system_once_per_batch(system_with_ssv):
    """A batch of runs plans them once: it reads the .ssd once.  Each batch reads it: an
    edit of the .ssd or its .ssv between two is read, and gives the result of setting the
    same value (--set) on the original files."""
    result = run_python(EDITS, *system_with_ssv)
    assert result.returncode == 0, result.stderr
    facts = json.loads(result.stdout.splitlines()[-1])
    assert facts.pop("runs") == ["system.ssd"] * 6  # run_one: a batch of one
    assert facts.pop("batch") == ["system.ssd"]
    assert all(facts.values()), facts


QUIET = """
import json, os
from agilesat.orchestration.campaign import engine

def facts(dask_worker):
    import dask
    tick = dask.config.get("distributed.admin.tick.interval")
    trimmed = "MALLOC_TRIM_THRESHOLD_" in os.environ
    return sorted(dask_worker.periodic_callbacks), tick, trimmed

with engine.cluster(1) as client:
    facts = list(list(client.run(facts).values())[0])
    print(json.dumps(facts + ["MALLOC_TRIM_THRESHOLD_" in os.environ]))
"""


def test_the_local_cluster_leaves_the_cpu_to_the_runs():
    """The workers of our LocalCluster do not sample their stacks every 10 ms (Dask's
    statistical profiler, for a dashboard page nobody opens) and tick every 1 s rather
    than 20 ms: together about 45 ms of CPU per second per worker at Dask's defaults; and
    they do not trim malloc's heap (the page faults per run it costs:
    tests/tools/benchmark_resources.py; a count of them is no test on a busy machine)."""
    result = run_python(QUIET)
    assert result.returncode == 0, result.stderr
    callbacks, tick, trimmed, client_trimmed = json.loads(result.stdout.splitlines()[-1])
    assert "heartbeat" in callbacks  # the worker's own callbacks are there
    assert not {"profile", "profile-cycle"} & set(callbacks)
    assert tick == "1s"
    # no MALLOC_TRIM_THRESHOLD_ (in the worker, nor left in the client's environment):
    # glibc keeps its dynamic mmap threshold, a run's arrays are not mapped afresh
    assert not trimmed and not client_trimmed


MEMORY = """
import gc, json, sys, tracemalloc
from agilesat.orchestration.campaign.plan import Plan, Spec
from agilesat.orchestration.campaign.worker import run_one

warm, runs = int(sys.argv[1]), int(sys.argv[2])
vary = ["SatelliteDynamics.inertia=inertia(0.03, 1deg)", "CmgCluster.delta0=+normal(0, 0.5deg)"]
plan = Plan(Spec("scan_pitch", warm + runs, 1, vary, stop=0.5))
keep = ["SatelliteDynamics.w_BI_B[2]"]

def make(i):
    r = run_one(i, "scan_pitch", plan.run_options(plan.run_values(i)), keep, 11)
    assert r["status"] == "ok", r["message"]

tracemalloc.start()
for i in range(warm):
    make(i)
gc.collect()
before = tracemalloc.get_traced_memory()[0]
for i in range(warm, warm + runs):
    make(i)
gc.collect()
print(json.dumps({"growth": tracemalloc.get_traced_memory()[0] - before}))
"""


def test_a_worker_keeps_nothing_per_run():
    """The Python memory of a process making run after run (what a worker does, without
    Dask) stays flat: 150 runs after 20 warm-up runs add less than 500 bytes a run.  What
    tracemalloc sees change is the state of the reused components (the last run's arrays in
    place of an earlier run's: some 30-45 kB in all, not per run); a Log, a result or a
    component kept per run, or pythonfmu's ~1 kB per fmi2Instantiate, would exceed it."""
    result = run_python(MEMORY, 20, 150)
    assert result.returncode == 0, result.stderr
    growth = json.loads(result.stdout.splitlines()[-1])["growth"]
    assert growth < 150 * 500, f"{growth / 150:.0f} bytes per run"


BINDINGS = """
import json
from fmpy.fmi1 import _FMU
from agilesat.orchestration import RunOptions
from agilesat.orchestration.campaign.worker import run_one

bound = []
load = _FMU._loadFunctions  # fmpy's inspect.signature binding of every FMI function
_FMU._loadFunctions = lambda self: bound.append(self.instanceName) or load(self)
keep = ["SatelliteDynamics.w_BI_B[2]"]
options = [RunOptions(stop=1.0, parameters={"CmgCluster.h_rotor": h}) for h in (16.65, 17.0, 16.65)]
runs = [run_one(i, "scan_pitch", chosen, keep, 21) for i, chosen in enumerate(options)]
assert all(r["status"] == "ok" for r in runs), [r["message"] for r in runs]
print(json.dumps({"bound": bound, "same": (runs[0]["signals"] == runs[2]["signals"]).all().item()}))
"""


def test_a_worker_binds_each_fmu_once():
    """fmpy's FMU2Slave (its ~70 FMI functions bound through inspect.signature, ~1.5 ms
    per FMU) is made once per FMU and instance name in a worker, not once per run."""
    result = run_python(BINDINGS)
    assert result.returncode == 0, result.stderr
    facts = json.loads(result.stdout.splitlines()[-1])
    components = [c.name for c in read_system(get("scan_pitch").ssd).components]
    assert sorted(facts["bound"]) == sorted(components)
    assert facts["same"]
