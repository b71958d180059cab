"""The shim's fast path (fmus/shim/agilesat_fmi2.c, "fast get/set"; fmus/slave.py): valid
fmi2GetReal/fmi2SetReal in step mode are served in C from the slave's value array, every
other call reaches the slave as before.  In-process: the slave's side of the contract (the
arrays it shares are never replaced, a prediction no get used is undone exactly).  In clean
processes through FMPy's ctypes bindings: the path is taken (the shim's counters) and off
with AGILESAT_SHIM_FAST=0, the answers and the results are the same either way, and FMU
states and fmi2Reset leave no stale pointer or flag in the shim.  The statuses and messages
of invalid calls are those of tests/test_faults_fmu.py and tests/test_faults_master.py,
which run on the same built FMUs, fast path on."""

import copy
import json
import pickle

import numpy as np
import pytest
from count_python_entries import count

from agilesat.fmus import FMUS, model_class
from agilesat.fmus.protocol import FAST_PATH_N, FAST_PATH_VR, OUTPUTS_VALID, PREDICTED, STEP_MODE
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
def test_the_shared_arrays_are_never_replaced(name):
    """The shim keeps the addresses of the handshake: state restore, steps and terminate
    copy into the same arrays (fmi2Reset makes a new slave, and the shim asks again)."""
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


@pytest.mark.parametrize("name", FMUS)
def test_the_flags_follow_the_mode_and_the_outputs(name):
    fmu = slave(name)
    assert not fmu._fast.control[STEP_MODE]
    fmu.exit_initialization_mode()
    assert fmu._fast.control[STEP_MODE] and not fmu._fast.control[OUTPUTS_VALID]
    assert fmu.do_step(0.0, STEP)
    assert (
        fmu._fast.control[OUTPUTS_VALID] and fmu._fast.control[PREDICTED]
    )  # evaluated at the step
    fmu.get_real([fmu._outputs.start])
    assert fmu._fast.control[OUTPUTS_VALID] and not fmu._fast.control[PREDICTED]  # used
    for vr in feedthrough_inputs(fmu)[:1]:
        fmu.set_real([vr], [fmu.get_real([vr])[0]])
        assert not fmu._fast.control[OUTPUTS_VALID]
    fmu.terminate()
    assert not fmu._fast.control[STEP_MODE]
    assert logged(fmu) == []


def test_predictions_stop_while_a_feedthrough_set_comes_first_and_resume():
    fmu = started("SatelliteDynamics")
    q_OI = fmu.model.layout.offset["q_OI"]
    turned = [q_OI, q_OI + 1, q_OI + 2, q_OI + 3]
    first = fmu._outputs.start
    predicted = []
    for k in range(6):
        assert fmu.do_step(k * STEP, STEP)
        predicted.append(bool(fmu._fast.control[PREDICTED]))
        if k in (1, 2):  # as a Jacobi master's feedthrough pass
            fmu.set_real(turned, fmu.model.values[turned].tolist())
        fmu.get_real([first])
    assert predicted == [True, True, False, False, True, True]
    assert logged(fmu) == []


def attributes(model):
    return {k: v for k, v in vars(model).items() if k not in model._NOT_STATE}


@pytest.mark.parametrize("name", FMUS)
def test_output_assigns_its_memories_instead_of_modifying_them(name):
    """The undo of a prediction puts the model's attribute references back and the contents
    of its arrays (the kernels' state arrays, updated in place): output() must leave every
    other object it found unchanged (a model that updates a remembered list in place would
    make the undo incomplete, and results depend on whether a host reads)."""
    fmu = started(name)
    model = fmu.model
    for k in range(3):
        assert fmu.do_step(k * STEP, STEP)
        fmu._fast.consume()
        found = attributes(model)
        copies = copy.deepcopy(found)
        model.output()
        for key, value in found.items():
            if type(value) is not np.ndarray:
                assert pickle.dumps(value) == pickle.dumps(copies[key]), f"{name}.{key}"


@pytest.mark.parametrize("name", FMUS)
def test_an_undone_prediction_puts_the_state_arrays_back(name):
    """Two steps with no get between them: the first step's prediction is undone, also in
    the arrays output() updates in place (a kernel's state array: the last q_BO and Euler
    angles of SatelliteDynamics, for the sign and branch continuity), so the model ends as
    the plain model stepped twice."""
    fmu = started(name)
    model = model_class(name)()
    model.values[:] = fmu.model.values
    model.start(0.0)
    fmu.get_real([fmu._outputs.start])
    for k in range(2):
        assert fmu.do_step(k * STEP, STEP)
        model.step(k * STEP, STEP)
    fmu._fast.consume()
    ours, plain = attributes(fmu.model), attributes(model)
    for key in plain:
        if type(plain[key]) is np.ndarray:
            assert ours[key].tobytes() == plain[key].tobytes(), key


@pytest.mark.parametrize("name", FMUS)
def test_a_prediction_no_get_used_leaves_no_trace(name):
    """Steps read only every other step, and feedthrough inputs set between a step and the
    first get: the slave's model ends exactly (values, attributes, warnings) as the plain
    model evaluated only where a host reads, which is what the FMU did before the shim
    predicted outputs."""
    fmu = started(name)
    model = model_class(name)()
    model.values[:] = fmu.model.values
    model.start(0.0)
    fmu.get_real([fmu._outputs.start])
    inputs = feedthrough_inputs(fmu)
    reals = np.flatnonzero(fmu._type == 0).tolist()
    rng = np.random.default_rng(11)
    for k in range(6):
        assert fmu.do_step(k * STEP, STEP)
        model.step(k * STEP, STEP)
        if k % 3 == 1 and inputs:
            x = model.values[inputs] * (1 + 1e-9 * rng.standard_normal(len(inputs)))
            fmu.set_real(inputs, x.tolist())
            model.values[inputs] = x
        if k % 3 != 2:
            model.output()
            assert fmu.get_real(reals) == model.values[reals].tolist()
    fmu._fast.consume()
    assert fmu.model.values.tolist() == model.values.tolist()
    ours, plain = attributes(fmu.model), attributes(model)
    ours.pop("_initial_inputs", None), plain.pop("_initial_inputs", None)  # start() sets it
    assert sorted(ours) == sorted(plain)
    for key in plain:
        assert pickle.dumps(ours[key]) == pickle.dumps(plain[key]), key
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
    # it is served, and the two gets after it (outputs evaluated by the step).  From step
    # 10 on, q_OI, which feeds outputs through, is set between the step and the gets: at
    # step 10 that set and the first get go to the slave (which undoes the evaluation and
    # evaluates again), after that the slave no longer predicts: the set is served, the
    # first get goes to the slave
    assert np.diff(served).tolist() == [3] * 10 + [2] + [3] * 9 + [0]
    assert np.diff(forwarded).tolist() == [0] * 10 + [2] + [1] * 9 + [0] and forwarded[0] == 1
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
