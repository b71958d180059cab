"""The kernel convention (components/jit.py) that the FMU's C step path relies on: a declared
step or output kernel returning 0 did everything its method does but advance ``t``, so the
shim may call the kernel alone; a STATELESS model's step changes nothing but ``t``.  Checked
for every model, on random operating points and through the states that used to keep
the C path off (a saturated cluster, a singular steering, a given orbit)."""

import math
import pickle

import numpy as np
import pytest

from agilesat.components.model import Model
from agilesat.components.runtime import jit
from agilesat.fmus import FMUS, c_entries, model_class
from helpers import ISS_TLE, operating_point

STEP = 0.05
DECLARING = [name for name in FMUS if c_entries.of(model_class(name)).any]


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
    model.step(t, STEP)
    alone, method = twins(model)
    if output is not None:
        status = output(alone.values, alone.state, model.t)
        method.output()
        cases["output", status == 0] = cases.get(("output", status == 0), 0) + 1
        if status == 0:
            same(alone, method)
            assert method.warnings == model.warnings
    model.output()


def run(model, inputs, steps: int) -> dict:
    cases: dict = {}
    for k in range(steps):
        for name, value in inputs(k).items():
            model.set(name, value)
        check(model, k * STEP, cases)
    return cases


def test_the_models_with_kernels():
    assert DECLARING == [
        "AttitudeController", "AttitudeEstimator", "CmgCluster", "CmgSteering",
        "DisturbanceTorques", "Flywheel", "Gyro", "OrbitEnvironment", "PayloadGimbals",
        "PitchManeuverController", "SatelliteDynamics", "StarTracker", "StaringGuidance",
        "SweepPlanner",
    ]  # fmt: skip


@pytest.mark.parametrize("name", DECLARING)
@pytest.mark.parametrize("seed", [1, 2])
def test_a_kernel_returning_zero_did_what_its_method_does(name, seed):
    rng = np.random.default_rng(seed)
    model = model_class(name)()
    point = operating_point(name, rng)
    for variable, value in point.items():
        model.set(variable, value)
    model.start(0.0)
    cases = run(model, lambda k: point, 20)
    step, output = jit.declared(type(model))
    assert cases.get(("step", True), 0) == (20 if step else 0)
    assert cases.get(("output", True), 0) == (20 if output else 0)


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
