"""The generic FMU wrapper (``fmus/slave.py``) in-process: instantiated and driven with
set_real/do_step/get_real as a host drives it, the way pythonfmu's own tests exercise their
slaves.  The same calls through built FMUs in other processes are in test_fmus.py."""

import math

import numpy as np
import pytest

from agilesat.components.model import Model
from agilesat.components.variables import output, parameter
from agilesat.fmus import FMUS, model_class, slave_class
from agilesat.fmus.slave import ModelSlave
from helpers import logged, operating_point, slave

STEP = 0.05


def scalars(model, causality):
    """(value reference, scalar name) of the Real scalars of one causality, in order."""
    layout = model.layout
    return [
        (vr, name)
        for vr, (v, name) in enumerate(layout.scalars)
        if v.causality == causality and v.type == "Real"
    ]


@pytest.mark.parametrize("name", FMUS)
def test_the_slave_computes_exactly_what_the_model_computes(name):
    """Inputs set and outputs read by value reference give the model's own numbers, bit
    for bit, step after step (the value references address the model's flat array)."""
    model = model_class(name)()
    fmu = slave(name)
    inputs, outputs = scalars(model, "input"), scalars(model, "output")
    rng = np.random.default_rng(7)
    for k in range(4):
        t = k * STEP
        x = model.values[[vr for vr, _ in inputs]] + 1e-7 * rng.standard_normal(len(inputs))
        fmu.set_real([vr for vr, _ in inputs], x.tolist())
        model.values[[vr for vr, _ in inputs]] = x
        if k == 0:  # the first inputs before initialisation ends, as FMI 2.0 asks
            fmu.exit_initialization_mode()
            model.start(0.0)
        else:
            model.output()
        assert (
            fmu.get_real([vr for vr, _ in outputs])
            == model.values[[vr for vr, _ in outputs]].tolist()
        )
        assert fmu.do_step(t, STEP)
        model.step(t, STEP)
    assert logged(fmu) == []


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda f: f.get_real([10**6]), "unknown value references [1000000]"),
        (lambda f: f.get_integer([0]), "not of type Integer"),
        (lambda f: f.set_real([f.model.layout.range["output"].start], [1.0]), "cannot be set"),
        (lambda f: f.set_real([0], [1.0]), "are fixed"),
        (
            lambda f: f.set_real([f.model.layout.range["input"].start], [math.nan]),
            "non-finite values rejected",
        ),
        (lambda f: f.do_step(0.0, 0.0), "step size must be positive"),
        (lambda f: f.do_step(1.0, STEP), "time discontinuity"),
    ],
)
def test_a_bad_call_is_logged_as_an_error_and_the_instance_carries_on(call, message):
    fmu = slave("CmgCluster")
    fmu.exit_initialization_mode()
    outputs = [vr for vr, _ in scalars(fmu.model, "output")]
    before = fmu.get_real(outputs)
    call(fmu)
    errors = logged(fmu)
    assert len(errors) == 1 and errors[0].startswith("CmgCluster 'test_CmgCluster': ")
    assert message in errors[0]
    assert fmu.get_real(outputs) == before  # nothing changed
    assert fmu.do_step(0.0, STEP) and logged(fmu) == errors  # and it still steps


def test_answers_to_rejected_calls_are_harmless():
    fmu = slave("CmgCluster")
    fmu.exit_initialization_mode()
    assert fmu.get_real([10**6, 10**6 + 1]) == [0, 0]
    assert fmu.do_step(5.0, STEP) is False
    assert len(logged(fmu)) == 2


def test_a_step_before_initialisation_is_rejected():
    fmu = slave("CmgCluster")
    assert fmu.do_step(0.0, STEP) is False
    assert "not allowed in mode 'initialization'" in logged(fmu)[0]


def test_a_model_error_is_logged_with_the_instance_name():
    fmu = slave("PayloadGimbals")
    bandwidth = next(vr for vr, name in scalars(fmu.model, "parameter") if name == "bandwidth")
    fmu.set_real([bandwidth], [-1.0])
    fmu.exit_initialization_mode()
    assert (
        "PayloadGimbals 'test_PayloadGimbals': exit_initialization_mode: bandwidth must "
        "be >= 0" in logged(fmu)[0]
    )


def test_parameters_set_before_initialisation_take_effect():
    fmu = slave("SatelliteDynamics")
    names = {name: vr for vr, name in scalars(fmu.model, "parameter")}
    fmu.set_real([names["inertia[1,1]"]], [900.0])
    fmu.exit_initialization_mode()
    assert fmu.model.get("inertia")[0, 0] == 900.0 and logged(fmu) == []


@pytest.mark.parametrize("name", FMUS)
def test_fmu_state_round_trips_through_bytes_bit_identically(name):
    fmu = slave(name)
    for var, value in operating_point(name, np.random.default_rng(3)).items():
        fmu.set_real(
            list(range(fmu.model.layout.slice(var).start, fmu.model.layout.slice(var).stop)),
            value.tolist(),
        )
    fmu.exit_initialization_mode()
    outputs = [vr for vr, _ in scalars(fmu.model, "output")]
    assert fmu.do_step(0.0, STEP)
    saved = fmu._fmu_state_to_bytes(fmu._get_fmu_state())
    assert fmu.do_step(STEP, STEP)
    after = fmu.get_real(outputs)
    assert fmu.do_step(2 * STEP, STEP)
    fmu._set_fmu_state(fmu._fmu_state_from_bytes(saved))
    assert fmu.do_step(STEP, STEP)  # the clock came back with the state
    assert fmu.get_real(outputs) == after
    assert logged(fmu) == []


def _codes(vrs, order=1):
    """The value references the shim passes the derivative calls on as (fmus/protocol.py)."""
    from agilesat.fmus.protocol import DERIVATIVE_BASE, ORDER_SHIFT

    return [DERIVATIVE_BASE + (order << ORDER_SHIFT) + vr for vr in vrs]


@pytest.mark.parametrize("name", FMUS)
def test_every_continuous_input_and_output_takes_its_derivative_or_none_does(name):
    """FMI 2.0 section 4.2.1: an FMU that declares canInterpolateInputs takes the first
    derivative of every continuous Real input (order 2 refused, naming the variable), one
    that declares maxOutputDerivativeOrder 1 answers every Real output; one that declares
    neither refuses both, saying why."""
    model = model_class(name)
    fmu = slave(name)
    for variable, value in operating_point(name, np.random.default_rng(3)).items():
        at = model.table_layout().offset[variable]
        fmu.set_real(list(range(at, at + len(np.atleast_1d(value)))), np.ravel(value).tolist())
    fmu.exit_initialization_mode()
    inputs, outputs = scalars(model(), "input"), scalars(model(), "output")
    if inputs:  # (OrbitEnvironment and SweepPlanner have none)
        fmu.set_real(_codes([vr for vr, _ in inputs]), [0.0] * len(inputs))
        fmu.set_real(_codes([inputs[0][0]], order=2), [0.0])
    rates = fmu.get_real(_codes([vr for vr, _ in outputs]))
    errors = logged(fmu)
    assert fmu.do_step(0.0, STEP)
    if model.INTERPOLATES_INPUTS:
        assert f"order 2 of {inputs[0][1]}: only order 1" in errors.pop(0)
    elif inputs:
        assert "does not interpolate its inputs (canInterpolateInputs is false)" in errors.pop(0)
        assert "does not interpolate its inputs" in errors.pop(0)
    if model.OUTPUT_DERIVATIVES:
        assert all(map(math.isfinite, rates)) and len(rates) == len(outputs)
    else:
        assert "no output derivatives (maxOutputDerivativeOrder is 0)" in errors.pop(0)
    assert errors == []


class _Counts(Model):
    """An Integer output n and a Boolean output b set from Real parameters, as a user's
    model might compute them."""

    VARIABLES = (
        parameter("count", 1.0, "1", "the value of n"),
        parameter("flag", 1.0, "1", "the value of b"),
        output("n", "1", "an Integer output", type="Integer"),
        output("b", "1", "a Boolean output", type="Boolean"),
    )

    def initialize(self, t0):
        self.t = t0

    def step(self, t, dt):
        self.t = t + dt

    def output(self):
        self.y.n, self.y.b = self.p.count, self.p.flag


class _CountsSlave(ModelSlave):
    model_class = _Counts


@pytest.mark.parametrize(
    "parameter, value, get, message",
    [
        ("count", 2.0**40, "get_integer", "Integer values n=1099511627776.0"),
        ("count", 1.5, "get_integer", "Integer values n=1.5"),
        ("count", -(2.0**31) - 1, "get_integer", "Integer values n=-2147483649.0"),
        ("flag", 0.5, "get_boolean", "Boolean values b=0.5"),
    ],
)
def test_an_output_its_fmi_type_cannot_hold_is_an_error_naming_it(parameter, value, get, message):
    """fmi2GetInteger would have wrapped 2**40 to 0 and truncated 1.5 to 1, fmi2GetBoolean
    read 0.5 as true: each is fmi2Error naming the model, the variable and the value (the
    ends of fmi2Integer's range are answered)."""
    for given, fine in ((value, False), (-(2.0**31) if get == "get_integer" else 1.0, True)):
        fmu = _CountsSlave(instance_name="counts")
        fmu.enter_initialization_mode()
        fmu.set_real([fmu._scalar_names.index(parameter)], [given])
        fmu.exit_initialization_mode()
        read = getattr(fmu, get)([fmu._scalar_names.index("n" if get == "get_integer" else "b")])
        if fine:
            assert read == [int(given)] and logged(fmu) == []
        else:
            assert read == [0] and len(logged(fmu)) == 1
            assert logged(fmu)[0].startswith("_Counts 'counts': ") and message in logged(fmu)[0]


def test_the_state_machine_refuses_a_get_before_initialisation_and_a_step_past_the_stop():
    """FMI 2.0 section 4.2.4: fmi2Get* only from initialisation mode on; section 4.2.1: no
    step past a defined stop time (continuous() tolerance: the last step may end on it)."""
    fmu = slave_class("CmgCluster")(instance_name="machine")
    assert fmu.get_real([0]) == [0]
    assert "not allowed in mode 'instantiated'" in logged(fmu)[0]
    fmu.setup_experiment(0.0, 0.1)
    fmu.enter_initialization_mode()
    fmu.exit_initialization_mode()
    assert fmu.do_step(0.0, STEP) and fmu.do_step(STEP, 0.1 - STEP)
    assert fmu.do_step(0.1, STEP) is False
    assert "ends after the stop time 0.1 of fmi2SetupExperiment" in logged(fmu)[-1]


def test_an_input_set_again_to_the_value_it_holds_keeps_the_initialized_state():
    """In initialisation mode a set input makes the model initialise again at the next read
    (its state may depend on the input); setting the values it holds, bit for bit, changes
    nothing and initialises nothing again, while another value, -0.0 for 0.0 included,
    does."""
    fmu = slave("CmgCluster")
    inputs = [vr for vr, _ in scalars(fmu.model, "input")]
    outputs = [vr for vr, _ in scalars(fmu.model, "output")]
    calls = []
    initialize = fmu.model.initialize
    fmu.model.initialize = lambda t0: calls.append(t0) or initialize(t0)
    held = fmu.model.values[inputs].tolist()
    first = fmu.get_real(outputs)
    assert len(calls) == 1
    fmu.set_real(inputs, held)
    assert fmu.get_real(outputs) == first and len(calls) == 1
    other = list(held)
    other[0] = -other[0] if other[0] != 0.0 else math.copysign(0.0, -math.copysign(1.0, other[0]))
    fmu.set_real(inputs, other)
    fmu.get_real(outputs)
    assert len(calls) == 2
    assert math.copysign(1.0, fmu.model.values[inputs[0]]) == math.copysign(1.0, other[0])
    fmu.exit_initialization_mode()
    assert len(calls) == 2 and logged(fmu) == []
