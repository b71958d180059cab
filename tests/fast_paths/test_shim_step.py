"""The lane "C step against Python step": the shim's C step path (fmus/shim/fast_paths.c,
fmus/fast_paths.py, fmus/c_entries.py): with the kernels compiled, fmi2DoStep and the
evaluation of the outputs run in C, calling the models' compiled kernels, for every model
with kernels.  Driven through
the built FMUs in clean processes (tests/tools/shim_step_host.py), with the path on and off
(AGILESAT_SHIM_STEP=0): the path is taken (the shim's counters), and everything a host sees
is the same bit for bit: values, statuses, messages, FMU states (serialized bytes), the run
after a state restore, a reset, a step the kernel leaves to the Python (a warning, an
error), bad steps."""

import ctypes
import json
import math

import numpy as np
import pytest

from agilesat.components.runtime import jit
from agilesat.fmus import FMUS, c_entries, model_class
from helpers import TOOLS, run_python

pytestmark = [pytest.mark.slow, pytest.mark.integration]
HOST = (TOOLS / "shim_step_host.py").read_text()
#: every FMU with C entries
NAMES = [name for name in FMUS if c_entries.of(model_class(name)).any]
#: the FMUs whose first step after initialisation is the Python's (it checks the inputs
#: the initial state was computed from, Model.check_initial_inputs)
CHECKS_INITIAL_INPUTS = ("SatelliteDynamics",)
OK, WARNING, ERROR = 0, 1, 3


@pytest.fixture(scope="module")
def hosts(fmus):
    """{"on": results, "off": results} of the host, one clean process each."""
    got = {}
    for mode in ("on", "off"):
        result = run_python(HOST, mode, *(f"{name}={fmus[name]}" for name in NAMES))
        assert result.returncode == 0, result.stderr
        got[mode] = json.loads(result.stdout.strip().splitlines()[-1])
    return got


def same(on, off, *keys):
    for key in keys:
        assert on[key] == off[key], key  # JSON floats: bit for bit


@pytest.mark.parametrize("name", NAMES)
def test_the_c_step_path_is_the_python_step_path(hosts, name):
    """The lane "C step against Python step", over every model with kernels: a run, FMU
    states (get, set, serialize, deserialize mid-run), bad steps and a reset give the same
    values, statuses, messages and serialized states with the path on and off, and the
    path is taken: every step in C (the FMU's entries compiled ahead of time, fmus/native.py)
    but a first step that checks the initial inputs, which the Python must take."""
    checks = name in CHECKS_INITIAL_INPUTS
    on, off = hosts["on"][f"{name}:run"], hosts["off"][f"{name}:run"]
    same(on, off, "record")
    assert {row[0] for row in on["record"]} == {OK}
    enabled, steps, outputs, fallbacks = on["counts"]
    assert (enabled, steps, fallbacks) == (1, 30 - checks, 0)
    assert outputs >= 29
    assert off["counts"] == [-1, 0, 0, 0]

    on, off = hosts["on"][f"{name}:states"], hosts["off"][f"{name}:states"]
    same(on, off, "state", "after", "restored", "deserialized")
    assert on["restored"] == on["after"] and on["deserialized"] == on["after"]
    assert on["counts"][1] == 26 - checks  # the kernels compiled by the run before

    on, off = hosts["on"][f"{name}:faults"], hosts["off"][f"{name}:faults"]
    same(on, off, "calls", "messages", "record")
    calls = on["calls"]
    assert calls["close enough"] == calls["terminate"] == OK
    assert {calls[k] for k in calls if k not in ("close enough", "terminate")} == {ERROR}
    text = "\n".join(message for _, message in on["messages"])
    assert "time discontinuity: the last step ended at t=0.25, doStep starts at t=0.55" in text
    assert "step size must be positive and finite, got 0.0" in text
    assert "not allowed in mode 'terminated'" in text
    assert on["counts"][1] == 9 - checks  # the steps before and after the bad ones

    on, off = hosts["on"][f"{name}:reset"], hosts["off"][f"{name}:reset"]
    same(on, off, "first", "again")
    assert on["again"] == on["first"]
    assert on["after"][1] - on["before"][1] == 6 - checks


def test_a_warning_from_the_step_falls_back_to_the_slave(hosts):
    on, off = hosts["on"]["CmgCluster:saturation"], hosts["off"]["CmgCluster:saturation"]
    same(on, off, "record", "messages")
    assert [row[0] for row in on["record"]] == [OK] * 5 + [WARNING] + [OK] * 6
    assert "rate command 5.000 rad/s exceeds the rate limit" in on["messages"][0][1]
    enabled, steps, _, fallbacks = on["counts"]
    # step 5 (the kernel's warning: fallback) in Python, the others in C (the kernels were
    # compiled by the programs before), the saturated step 6 too (the saturation is state)
    assert (fallbacks, steps) == (1, 11)


def test_an_error_from_the_step_falls_back_to_the_slave(hosts):
    on = hosts["on"]["SatelliteDynamics:unphysical"]
    off = hosts["off"]["SatelliteDynamics:unphysical"]
    same(on, off, "record", "messages")
    assert [row[0] for row in on["record"]] == [OK] * 5 + [ERROR] + [OK] * 4
    assert "sub-steps of 0.05 s: the state is unphysical" in on["messages"][0][1]
    assert on["counts"][3] == 1 and on["counts"][1] == 8  # the first step is the Python's


@pytest.mark.parametrize("name", ["SatelliteDynamics", "CmgCluster"])
def test_interpolated_inputs_step_in_c_as_in_the_python(hosts, name):
    """Input derivatives set before every step (FMI 2.0 canInterpolateInputs): the C
    step path gives the Python's values, statuses and messages; the hub's slope conflict
    (a set derivative of h_cmg against a different hdot_cmg, from step 12) is its one
    step left to the slave, with its warning."""
    on, off = hosts["on"][f"{name}:interpolated"], hosts["off"][f"{name}:interpolated"]
    same(on, off, "record", "messages")
    hub = name == "SatelliteDynamics"
    assert [row[:2] for row in on["record"]] == [
        [OK, WARNING if hub and k == 12 else OK] for k in range(20)
    ]
    if hub:
        assert len(on["messages"]) == 1
        assert "hdot_cmg[2] = 0.1, the derivative of h_cmg[2] = 0.2" in on["messages"][0][1]
    enabled, steps, _, fallbacks = on["counts"]
    assert (steps, fallbacks) == ((18, 1) if hub else (20, 0))


_BROKEN_BUILD = """
import json, os, sys
os.environ["AGILESAT_JIT_AFTER"] = "0"
os.environ["AGILESAT_NATIVE"] = "0"  # numba compiles the C entries in the process
sys.path.insert(0, sys.argv[2])
import fmi_host
fmu = fmi_host.Fmu(sys.argv[1], "a")
c_entries = next(
    m for n, m in sys.modules.items() if n.startswith("agilesat_") and n.endswith(".c_entries")
)
def broken(self):
    raise TypeError("numba moved")
c_entries.CEntry._cfunc = property(broken)  # every C entry fails to build
fmu.initialize(fmi_host.plausible_inputs(fmu))
statuses = [fmu.step(k * 0.05, 0.05) for k in range(5)]
said = [m for s, m in fmu.messages if "C step path is off" in m]
print(json.dumps({"statuses": statuses, "said": said}))
"""


def test_a_c_entry_that_cannot_be_built_leaves_the_steps_to_the_python_with_a_warning(fmus):
    """(Without the FMU's own entries: another numba version, say.)  The calls succeed;
    the first step reports it once, as a warning; the Python steps from then on."""
    result = run_python(_BROKEN_BUILD, fmus["CmgCluster"], TOOLS)
    assert result.returncode == 0, result.stderr
    answer = json.loads(result.stdout.strip().splitlines()[-1])
    assert answer["statuses"] == [WARNING, OK, OK, OK, OK]
    assert len(answer["said"]) == 1 and "TypeError: numba moved" in answer["said"][0]


def test_an_exception_in_a_c_entry_returns_minus_one(tmp_path, monkeypatch):
    """numba's cfunc wrapper would print an exception and return an undefined value: the C
    entry catches it (here a ZeroDivisionError, numba's Python error model) and returns -1,
    so the shim falls back to the Python, which raises it with its message."""
    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path))

    def divide(values, state, t, dt):
        state[0] = values[0] / dt
        return 0

    inner = jit.Kernel(divide, 0)
    entry = c_entries.CEntry(inner, "step")
    assert entry.address is None  # not compiled yet
    values, state = np.array([3.0]), np.zeros(1)
    inner(values, state, 0.0, 2.0)  # the tier switch
    assert entry.address is not None
    call = ctypes.CFUNCTYPE(
        ctypes.c_int32,
        ctypes.c_void_p,
        ctypes.c_int64,
        ctypes.c_void_p,
        ctypes.c_int64,
        ctypes.c_double,
        ctypes.c_double,
    )(entry.address)
    assert call(values.ctypes.data, 1, state.ctypes.data, 1, 0.0, 4.0) == 0 and state[0] == 0.75
    assert call(values.ctypes.data, 1, state.ctypes.data, 1, 0.0, 0.0) == -1 and state[0] == 0.75
    with pytest.raises(ZeroDivisionError):
        inner(values, state, 0.0, 0.0)
    assert math.isfinite(state[0])


def test_scan_pitch_never_enters_python_in_a_macro_step(monkeypatch):
    """With the kernels compiled, a macro step of scan_pitch (five FMUs, the master's Jacobi
    passes) does not enter Python: every step and output is a C entry (the pitch
    controller's CPython math.hypot too: components/runtime/flat.py), every get and set
    the shim's."""
    from count_python_entries import count

    monkeypatch.setenv("AGILESAT_JIT_AFTER", "0")
    short, long = count("1", 0.05, 1.0), count("1", 0.05, 2.0)
    per_step = {name: (long[name] - short.get(name, 0)) / 20 for name in long}
    assert {name: n for name, n in per_step.items() if n} == {}


SCAN_PITCH = r"""
import json, os, sys
os.environ["AGILESAT_JIT_AFTER"], os.environ["AGILESAT_SHIM_STEP"] = sys.argv[1:3]
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
steps = []  # the slaves' do_step entries (Python)
sys.setprofile(lambda frame, event, arg: event == "call" and frame.f_code.co_name == "do_step"
               and frame.f_code.co_filename.endswith("fmus/slave.py") and steps.append(1))
results = simulate(get("scan_pitch").ssd, stop=20.0)
sys.setprofile(None)
print(json.dumps({"names": list(results.names), "data": results.data.tolist(),
                  "python steps": len(steps)}))
"""


def test_kernels_switching_mid_run_hand_the_steps_to_c_bit_for_bit():
    """The tier switch after 150 calls (400 macro steps): the C step path takes over mid-run
    and the results are those of the run without it, bit for bit."""
    runs = []
    for step_path in ("1", "0"):
        result = run_python(SCAN_PITCH, "150", step_path)
        assert result.returncode == 0, result.stderr
        runs.append(json.loads(result.stdout.strip().splitlines()[-1]))
    assert runs[0]["names"] == runs[1]["names"] and len(runs[0]["data"]) == 401
    assert runs[0]["data"] == runs[1]["data"]
    # 5 FMUs x 400 steps in Python without the path; with it only until the switch
    assert runs[1]["python steps"] == 2000 and runs[0]["python steps"] < 1000
