"""The lane "kernel against its method": the kernel convention (components/runtime/jit.py)
the FMU's C step path relies on.  A model's step and output are each one call of its
declared kernel; a kernel returning 0 did everything its method does but advance ``t``, so
the shim may call the kernel alone; a STATELESS model's step changes nothing but ``t``.
Checked for every model's cases (tests/fast_paths/kernel_cases.py) and through the states
that used to keep the C path off (a saturated cluster, a singular steering, a given orbit)."""

import math
import pickle

import numpy as np
import pytest
from kernel_cases import CASES

from agilesat.components.model import Model
from agilesat.components.runtime import jit
from agilesat.fmus import FMUS, c_entries, model_class
from helpers import ISS_TLE

STEP = 0.05
DECLARING = [name for name in FMUS if c_entries.of(model_class(name)).any]
CALLS: list = []


def twins(model):
    """Two copies of a model (the one the kernel runs on, the one the method runs on)."""
    return _copy(model), _copy(model)


def _copy(model):
    other = type(model)()
    for name in type(model)._NOT_STATE - Model._NOT_STATE:  # what does not evolve: shared
        setattr(other, name, getattr(model, name))
    other.set_state(model.get_state())
    other.warnings[:] = model.warnings
    return other


def same(a, b):
    assert a.values.tobytes() == b.values.tobytes()
    assert a.state.tobytes() == b.state.tobytes()


def check(model, t, cases: dict):
    """One step then one output of ``model`` at t, each as the kernel alone and as the
    method; ``cases`` counts the statuses seen."""
    step, output = jit.declared(type(model))
    stateless = c_entries.of(type(model)).stateless
    alone, method = twins(model)
    if step is not None:
        status = step(alone.values, alone.state, model.t, STEP)
        method.step(t, STEP)
        cases["step", status == 0] = cases.get(("step", status == 0), 0) + 1
        if status == 0:
            same(alone, method)
            assert method.warnings == model.warnings
    elif stateless:
        values, strings, before = method.get_state()
        method.step(t, STEP)
        after = method.get_state()
        assert (after[0].tobytes(), after[1]) == (values.tobytes(), strings)
        changed = {k for k in after[2] if pickle.dumps(after[2][k]) != pickle.dumps(before[k])}
        assert changed <= {"t"} and method.t == t + STEP
    made = len(CALLS)
    model.step(t, STEP)
    assert len(CALLS) - made == (step is not None)  # one call of the kernel, or none
    alone, method = twins(model)
    if output is not None:
        status = output(alone.values, alone.state, model.t)
        method.output()
        cases["output", status == 0] = cases.get(("output", status == 0), 0) + 1
        if status == 0:
            same(alone, method)
            assert method.warnings == model.warnings
    made = len(CALLS)
    model.output()
    assert len(CALLS) - made == (output is not None)


def run(model, inputs, steps: int) -> dict:
    cases: dict = {}
    for k in range(steps):
        for name, value in inputs(k).items():
            model.set(name, value)
        check(model, k * STEP, cases)
    return cases


@pytest.fixture(autouse=True)
def counted(monkeypatch):
    """Every call of a declared kernel appended to CALLS."""
    CALLS.clear()
    for model in map(model_class, DECLARING):
        for kernel in filter(None, jit.declared(model)):
            run_ = kernel._run
            monkeypatch.setattr(kernel, "_run", lambda *a, run_=run_: CALLS.append(1) or run_(*a))


def test_the_models_with_kernels():
    assert set(DECLARING) >= {
        "AttitudeController", "AttitudeEstimator", "CmgCluster", "CmgSteering",
        "DisturbanceTorques", "Flywheel", "Gyro", "OrbitEnvironment", "PayloadGimbals",
        "PitchManeuverController", "SatelliteDynamics", "StarTracker", "StaringGuidance",
        "SweepPlanner",
    }  # fmt: skip
    assert {CASES[case][0].__name__ for case in CASES} >= set(DECLARING)  # every lane: all


@pytest.mark.parametrize("case", list(CASES))
def test_a_step_and_an_output_are_one_kernel_call_each_that_does_what_its_method_does(case):
    """The lane "kernel against its method", over every model's cases (random inputs, the
    input derivatives a host sets): each step and each output of the model is one call of
    its declared kernel (a stateless model's step none, and it changes only t), and a
    kernel returning 0 leaves the values, the state and the warnings its method leaves."""
    cls, parameters, *feeds = CASES[case]
    inputs, rates = ((*feeds, None, None)[i] for i in (0, 1))
    inputs, rates = inputs and inputs(1, 0.8), rates and rates(1, 0.8)
    model, rng = cls(**parameters).start(0.0), np.random.default_rng(1)
    cases: dict = {}
    for k in range(20):
        for v in model.layout.group("input"):
            model.set(v.name, inputs(k, v) if inputs else rng.uniform(-0.8, 0.8, v.size))
        for name, rate in (rates(k) if rates else {}).items():
            model.set_input_rate(name, rate)
        check(model, k * STEP, cases)
    step, output = jit.declared(cls)
    assert cases.get(("step", True), 0) >= (5 if step else 0)  # compared: the kernel alone
    assert cases.get(("output", True), 0) >= (5 if output else 0)


def test_a_saturated_cluster_warns_once_and_its_kernel_steps_alone_after():
    """The step kernel asks for its method only when the cluster becomes saturated (the
    warning); steps while it stays saturated are the kernel's alone."""
    model = model_class("CmgCluster")().start(0.0)
    commands = [0.1, 5.0, 5.0, 5.0, 0.1, 5.0]
    cases = run(model, lambda k: {"delta_dot_cmd": [commands[k]] + [0.0] * 5}, 6)
    assert cases == {("step", True): 4, ("step", False): 2, ("output", True): 6}
    assert len(model.warnings) == 2


def test_a_wheel_at_its_limit_warns_once_and_its_kernel_steps_alone_after():
    """The wheels' step kernel asks for its method only when a wheel reaches a limit it
    was not at (the warning names the wheel and the limit)."""
    model = model_class("Flywheel")().start(0.0)
    torques = [0.1, 0.5, 0.5, 0.5, 0.1, 0.5]  # x: within, beyond, ..., within, beyond
    cases = run(model, lambda k: {"tau_cmd": [torques[k], 0.0, 0.0]}, 6)
    assert cases == {("step", True): 4, ("step", False): 2, ("output", True): 6}
    assert model.warnings == [
        f"t={t:.3f} s: wheel 1 motor torque at the limit (the commanded torque is not delivered)"
        for t in (STEP, 5 * STEP)
    ]


@pytest.mark.parametrize("law", ["PSEUDO_INVERSE", "SR_INVERSE"])
def test_a_singular_steering_warns_once(law):
    """At a singular configuration (all gimbals at zero: every spin along its reference,
    the momentum envelope's edge) the output kernel asks for its method when the
    configuration becomes singular, and at every output of the pseudo-inverse (the SVD);
    the singularity-robust inverse stays the kernel's."""
    model = model_class("CmgSteering")(law=law).start(0.0)
    deltas = [None, [0.0] * 6, [0.0] * 6, [0.0] * 6]
    cases = run(model, lambda k: {} if deltas[k] is None else {"delta": deltas[k]}, 4)
    assert math.isclose(model.get("singularity"), 0.0, abs_tol=1e-12)
    alone = 1 if law == "PSEUDO_INVERSE" else 3
    assert cases == {("output", True): alone, ("output", False): 4 - alone}
    assert len(model.warnings) == 1 and "singular gimbal configuration" in model.warnings[0]


def test_sgp4_is_the_kernels_own():
    """SGP4 (a TLE): the output kernel calls the sgp4 package's compiled SGP4 itself
    (components/ephemeris.py, sgp4_entry), at every new time."""
    model = model_class("OrbitEnvironment")(tle_line1=ISS_TLE[0], tle_line2=ISS_TLE[1])
    model.start(0.0)
    assert run(model, lambda k: {}, 3) == {("output", True): 3}
