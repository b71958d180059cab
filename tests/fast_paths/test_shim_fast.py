"""The shim's fast path (fmus/shim/fast_paths.c, fmus/fast_paths.py, "Fast get/set"): valid
fmi2GetReal/fmi2SetReal (and gets and input sets of Integer and Boolean) in step mode are
served in C from the slave's value array, every other call reaches the slave as before.
In-process: the slave's side of the contract (the arrays it shares are never replaced, the
flags follow the mode and the outputs). In clean processes through FMPy's ctypes bindings:
the path is taken (the shim's counters) and off with AGILESAT_SHIM_FAST=0, the answers and
the results are the same either way, and FMU states and fmi2Reset leave no stale pointer or
flag in the shim. The statuses and messages of invalid calls are those of
tests/fmus/test_faults_fmu.py and tests/orchestration/cosim/test_faults_master.py, which run
on the same built FMUs, fast path on."""

import json

import numpy as np
import pytest
from count_python_entries import count

from agilesat.fmus import FMUS
from agilesat.fmus.protocol import FAST_PATH_N, FAST_PATH_VR, OUTPUTS_VALID, STEP_MODE
from helpers import logged, operating_point, run_python, slave

STEP = 0.05


def started(name, seed=3):
    """FMU ``name``'s slave in-process, at an operating point, after initialisation."""
    fmu = slave(name)
    layout = fmu.model.layout
    for variable, value in operating_point(name, np.random.default_rng(seed)).items():
        vr = layout.offset[variable]
        fmu.set_real(list(range(vr, vr + np.size(value))), np.ravel(value).tolist())
    fmu.exit_initialization_mode()
    return fmu


def feedthrough_inputs(fmu):
    return [vr for vr in np.flatnonzero(fmu._feeds).tolist() if fmu._type[vr] == 0]


@pytest.mark.parametrize("name", FMUS)
def test_the_slave_keeps_its_side_of_the_fast_path(name):
    """The lane "fast get/set against the slave", the slave's side, in-process, for every
    FMU: the flags follow the mode and the outputs (step mode from initialisation to
    terminate; the outputs valid once a get evaluated them, until a feedthrough set), and
    the shim keeps the addresses of the handshake: state restore, steps and terminate copy
    into the same arrays (fmi2Reset makes a new slave, and the shim asks again)."""
    fmu = slave(name)
    assert not fmu._fast.control[STEP_MODE]
    fmu.exit_initialization_mode()
    assert fmu._fast.control[STEP_MODE] and not fmu._fast.control[OUTPUTS_VALID]
    assert fmu.do_step(0.0, STEP)
    assert not fmu._fast.control[OUTPUTS_VALID]  # evaluated when a get asks
    fmu.get_real([fmu._outputs.start])
    assert fmu._fast.control[OUTPUTS_VALID]
    for vr in feedthrough_inputs(fmu)[:1]:
        fmu.set_real([vr], [fmu.get_real([vr])[0]])
        assert not fmu._fast.control[OUTPUTS_VALID]
    fmu.terminate()
    assert not fmu._fast.control[STEP_MODE]
    assert logged(fmu) == []

    fmu = started(name)
    values, kind, control, block = (
        fmu.model.values,
        fmu._fast.kind,
        fmu._fast.control,
        fmu._fast.block,
    )
    answer = fmu.get_real([FAST_PATH_VR] * FAST_PATH_N)
    assert answer[1:] == [
        values.__array_interface__["data"][0],
        values.size,
        kind.__array_interface__["data"][0],
        control.__array_interface__["data"][0],
        block.__array_interface__["data"][0],
    ]
    state = fmu._get_fmu_state()
    for k in range(3):
        assert fmu.do_step(k * STEP, STEP)
        fmu.get_real([fmu._outputs.start])
    fmu._set_fmu_state(state)
    assert fmu.do_step(0.0, STEP)
    fmu.terminate()
    assert fmu.model.values is values and fmu._fast.kind is kind and fmu._fast.control is control
    assert fmu._fast.block is block
    assert logged(fmu) == []


# -- built FMUs, in clean processes ----------------------------------------------------
HOST = r"""
import ctypes, json, os, sys
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

path, fast = sys.argv[1], sys.argv[2]
if fast == "0":
    os.environ["AGILESAT_SHIM_FAST"] = "0"
md = read_model_description(path)
unzipped = extract(path)


def instance(name):
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, instanceName=name,
                    modelIdentifier=md.coSimulation.modelIdentifier)
    fmu.instantiate()
    counters = fmu.dll.agilesat_shim_counters
    counters.argtypes, counters.restype = [ctypes.c_void_p, ctypes.c_void_p], ctypes.c_int
    def count():
        c = (ctypes.c_ulonglong * 2)()
        on = counters(fmu.component, c)
        return [on, c[0], c[1]]
    fmu.count = count
    return fmu


real = {v.name: v.valueReference for v in md.modelVariables if v.type == "Real"}
outputs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
q_OI = [real[f"q_OI[{i}]"] for i in (1, 2, 3, 4)]
h_cmg = [real[f"h_cmg[{i}]"] for i in (1, 2, 3)]


def started():
    fmu = instance("a")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal(h_cmg, [1.0, -2.0, 0.5])
    fmu.exitInitializationMode()
    return fmu
"""

SCRIPT = {
    "steps": HOST
    + r"""
fmu = started()
counts, answers = [fmu.count()], []
for k in range(20):
    fmu.setReal(h_cmg, [1.0 + 0.01 * k, -2.0, 0.5])
    fmu.doStep(k * 0.05, 0.05)
    if k >= 10:  # q_OI feeds q_BO through: set after the step, before any get
        fmu.setReal(q_OI, [0.0, 1.0, 0.0, 0.0] if k % 2 else [1.0, 0.0, 0.0, 0.0])
    answers.append(fmu.getReal(outputs))
    answers.append(fmu.getReal(h_cmg + outputs[:3]))
    counts.append(fmu.count())
fmu.terminate()
counts.append(fmu.count())
answers.append(fmu.getReal(outputs))
fmu.freeInstance()
print(json.dumps({"counts": counts, "answers": answers}))
""",
    "states": HOST
    + r"""
fmu = started()
fmu.doStep(0.0, 0.05)
after_step = fmu.getFMUstate()          # outputs evaluated, no get yet
first = fmu.getReal(outputs)
fmu.setReal(q_OI, [0.0, 1.0, 0.0, 0.0])  # feeds q_BO through: outputs invalid
turned = fmu.getFMUstate()
turned_outputs = fmu.getReal(outputs)
for k in range(1, 4):
    fmu.doStep(k * 0.05, 0.05)
    fmu.getReal(outputs)
fmu.setFMUstate(turned)
again_turned = fmu.getReal(outputs)
fmu.setFMUstate(after_step)
again_first = fmu.getReal(outputs)
fmu.setFMUstate(turned)
fmu.doStep(0.05, 0.05)
stepped = fmu.getReal(outputs)
count_before_reset = fmu.count()
for k in range(2, 6):
    fmu.doStep(k * 0.05, 0.05)
fmu.reset()                              # pythonfmu makes a new slave: new arrays
count_after_reset = fmu.count()
fmu.setupExperiment(startTime=0.0)
fmu.enterInitializationMode()
fmu.setReal(h_cmg, [1.0, -2.0, 0.5])
fmu.exitInitializationMode()
fmu.doStep(0.0, 0.05)
after_reset = fmu.getReal(outputs)
fmu.setReal(q_OI, [0.0, 1.0, 0.0, 0.0])
after_reset_turned = fmu.getReal(outputs)
count_end = fmu.count()
os.environ["AGILESAT_SHIM_FAST"] = "0"   # read again at fmi2Reset
fmu.reset()
count_off = fmu.count()
fmu.freeInstance()
print(json.dumps({
    "first": first, "turned": turned_outputs, "again_turned": again_turned,
    "again_first": again_first, "stepped": stepped, "after_reset": after_reset,
    "after_reset_turned": after_reset_turned, "counts": [count_before_reset,
    count_after_reset, count_end, count_off]}))
""",
}


def run_host(fmus, script, fast):
    result = run_python(SCRIPT[script], fmus["SatelliteDynamics"], fast)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.strip().splitlines()[-1])


@pytest.mark.slow
@pytest.mark.integration
def test_valid_calls_are_served_by_the_shim_and_give_the_same_answers(fmus):
    fast, slow = run_host(fmus, "steps", "1"), run_host(fmus, "steps", "0")
    assert fast["answers"] == slow["answers"]  # bit for bit, Python entered or not
    on, served, forwarded = zip(*fast["counts"])
    assert set(on) == {1}
    # the set in initialization mode is forwarded.  Then each step the set of h_cmg before
    # it is served, and both gets (the first evaluates the outputs in C, with the FMU's
    # compiled output entry: fmus/native.py).  From step 10 on, q_OI, which feeds outputs
    # through, is set between the step and the gets: served
    assert np.diff(served).tolist() == [3] * 10 + [4] * 10 + [0]
    assert np.diff(forwarded).tolist() == [0] * 21 and forwarded[0] == 1
    assert {c[0] for c in slow["counts"]} == {-1} and {c[1] for c in slow["counts"]} == {0}
    assert np.diff([c[2] for c in slow["counts"]]).tolist() == [3] * 10 + [4] * 10 + [0]


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("fast", ["1", "0"])
def test_fmu_states_and_reset_leave_no_stale_pointer_or_flag(fmus, fast):
    got = run_host(fmus, "states", fast)
    assert got["turned"] != got["first"]  # q_OI feeds q_BO through
    assert got["again_turned"] == got["turned"]  # restored, outputs re-evaluated
    assert got["again_first"] == got["first"]
    assert got["after_reset"] == got["first"]  # a new slave, read through its own array
    assert got["after_reset_turned"] == got["turned"]
    before, after, end, off = got["counts"]
    if fast == "1":
        assert before[0] == after[0] == end[0] == 1  # handshake again after fmi2Reset
        assert end[1] > after[1]
    assert off[0] == -1


SCAN_PITCH = r"""
import json, os, sys
if sys.argv[1] == "0":
    os.environ["AGILESAT_SHIM_FAST"] = "0"
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
scenario = get("scan_pitch")
results = simulate(scenario.ssd, stop=20.0)
print(json.dumps({"names": list(results.names), "data": results.data.tolist()}))
"""


@pytest.mark.slow
@pytest.mark.integration
def test_scan_pitch_is_bit_identical_with_and_without_the_fast_path(fmus):
    runs = []
    for fast in ("1", "0"):
        result = run_python(SCAN_PITCH, fast)
        assert result.returncode == 0, result.stderr
        runs.append(json.loads(result.stdout.strip().splitlines()[-1]))
    assert runs[0]["names"] == runs[1]["names"]
    assert runs[0]["data"] == runs[1]["data"]
    # and the fast path was taken: entries into the slaves per macro step (20 more steps)
    on, off = (
        sum(count(fast, 0.05, 2.0).values()) - sum(count(fast, 0.05, 1.0).values())
        for fast in ("1", "0")
    )
    assert on < 0.6 * off


SIMULATE = r"""
import json, os, sys
if sys.argv[2] == "0":
    os.environ["AGILESAT_SHIM_FAST"] = "0"
from fmpy import simulate_fmu
result = simulate_fmu(sys.argv[1], stop_time=5.0, step_size=0.05, output_interval=0.05,
                      start_values={"h_cmg[1]": 2.0, "tau_ext[2]": 0.01})
print(json.dumps([list(map(float, row)) for row in result.tolist()]))
"""


@pytest.mark.slow
@pytest.mark.integration
def test_fmpy_simulate_fmu_is_bit_identical_with_and_without_the_fast_path(fmus):
    rows = []
    for fast in ("1", "0"):
        result = run_python(SIMULATE, fmus["SatelliteDynamics"], fast)
        assert result.returncode == 0, result.stderr
        rows.append(json.loads(result.stdout.strip().splitlines()[-1]))
    assert rows[0] == rows[1] and len(rows[0]) == 101


WHOLE = (
    HOST.replace("h_cmg = [", "# h_cmg = [").replace("q_OI = [", "# q_OI = [")
    + r"""
name, type_name, values = sys.argv[3], sys.argv[4], json.loads(sys.argv[5])
vr = next(v.valueReference for v in md.modelVariables if v.name == name)
setter = {"Integer": "setInteger", "Boolean": "setBoolean"}[type_name]
reals = [v.valueReference for v in md.modelVariables
         if v.causality == "output" and v.type == "Real"]
fmu = instance("a")
fmu.setupExperiment(startTime=0.0)
fmu.enterInitializationMode()
fmu.exitInitializationMode()
answers, counts = [], []
for k, value in enumerate(values):
    fmu.doStep(k * 0.05, 0.05)
    before = fmu.count()
    getattr(fmu, setter)([vr], [value])
    counts.append([a - b for a, b in zip(fmu.count()[1:], before[1:])])
    answers.append(fmu.getReal(reals))
fmu.freeInstance()
print(json.dumps({"counts": counts, "answers": answers}))
"""
)


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize(
    "fmu, name, type_name, values",
    [
        ("AttitudeEstimator", "meas_valid", "Boolean", [1, 0, 1, 1, 0]),
        ("AttitudeController", "mode", "Integer", [0, 3, 7, 1, 0]),
    ],
)
def test_integer_and_boolean_input_sets_are_served_as_the_slave_writes_them(
    fmus, fmu, name, type_name, values
):
    """In step mode a set of Integer or Boolean inputs is written by the shim (one served
    call, none forwarded), and every output after it is that of the slave's own write
    (AGILESAT_SHIM_FAST=0), bit for bit."""
    runs = {}
    for fast in ("1", "0"):
        done = run_python(WHOLE, fmus[fmu], fast, name, type_name, json.dumps(values))
        assert done.returncode == 0, done.stderr
        runs[fast] = json.loads(done.stdout.strip().splitlines()[-1])
    assert runs["1"]["answers"] == runs["0"]["answers"]
    assert runs["1"]["counts"] == [[1, 0]] * len(values)  # (served, forwarded)
