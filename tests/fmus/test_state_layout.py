"""A restored FMU state against the model's own layout (``fmus/state_layout.py``): every
state a model of ours can be in is accepted, in every shipped configuration; what does
not fit is refused naming it.  The same through built FMUs, in another process and with
compiled kernels: ``tests/tools/fault_cases_state.py``."""

import re

import numpy as np
import pytest

from agilesat.components import attitude_estimator as ae
from agilesat.components import star_tracker as st
from agilesat.fmus import FMUS, model_class, slave_class
from agilesat.fmus.fmu_state import StateError
from agilesat.fmus.state_layout import check, reference
from agilesat.orchestration.scenarios import NAMES, get
from helpers import logged, slave


def configurations() -> list:
    """(FMU, its parameters) of every component of every shipped scenario and variant."""
    found = []
    for name in NAMES:
        scenario = get(name)
        for variant in (None, *scenario.variants):
            system = scenario.system_for(variant)
            for component in system.components:
                own = {
                    key.partition(".")[2]: value
                    for key, value in system.parameters.items()
                    if key.partition(".")[0] == component
                }
                found.append(
                    pytest.param(system.fmu(component), own, id=f"{name}:{variant}:{component}")
                )
    return found


@pytest.mark.parametrize("component, parameters", configurations())
def test_every_state_of_a_shipped_configuration_fits_the_layout(component, parameters):
    """Initialised with a scenario's values, stepped: the state taken at every point has
    the reference's attribute names and kinds (no false refusal)."""
    cls = model_class(component)
    model = cls(**parameters).start(0.0)
    assert set(model.get_state()[2]) - {"_initial_inputs"} == set(reference(cls)) - {
        "_initial_inputs"
    }
    for k in range(3):
        check(cls, model.get_state(), initialized=True, outputs_valid=True)
        model.advance(0.1 * k, 0.1)
    check(cls, model.get_state(), initialized=True, outputs_valid=True)


@pytest.mark.parametrize("name", FMUS)
def test_a_state_taken_before_initialisation_fits(name):
    cls = model_class(name)
    check(cls, cls().get_state(), initialized=False, outputs_valid=False)


def _stepped(name="CmgCluster"):
    model = model_class(name)().start(0.0)
    model.advance(0.0, 0.1)
    return model_class(name), model.get_state()


@pytest.mark.parametrize(
    "tamper, message",
    [
        (lambda a: a["geometry"].__dict__.update(G=a["geometry"].G[:5]), "geometry.G is a float64"),
        (lambda a: a.update(state=a["state"][:40]), "state is a float64 array of shape (40,)"),
        (lambda a: a.update(state=a["state"].astype(np.float32)), "not a float64 array"),
        (lambda a: a.update(state=a["state"].tolist()), "state is a list, not a float64 array"),
        (lambda a: a["state"].__setitem__(0, np.inf), "state has non-finite values"),
        (lambda a: a.update(step=1), "would shadow the method CmgCluster.step"),
        (lambda a: a.update(INITIAL_STATE_DEPENDS=()), "shadow the class attribute"),
        (lambda a: a.update(spare=1), "an attribute 'spare', which CmgCluster has not"),
        (lambda a: a.update(t="0"), "t is a str, not a float"),
        (lambda a: a.update(geometry=None), "geometry is a NoneType, not a ClusterGeometry"),
        (lambda a: a.pop("state"), "lacks ['state']"),
    ],
)
def test_what_does_not_fit_is_refused_naming_it(tamper, message):
    cls, (values, strings, attributes) = _stepped()
    tamper(attributes)
    with pytest.raises(StateError, match=re.escape(message)):
        check(cls, (values, strings, attributes), initialized=True, outputs_valid=True)


@pytest.mark.parametrize(
    "name, parameters",
    [("StarTracker", {"latency": 0.7, "rate": 8.0}), ("AttitudeEstimator", {"history": 3.0})],
)
def test_an_array_sized_from_the_parameters_is_checked_against_them(name, parameters):
    """A state of a non-default pipeline or history fits (the reference is the model of
    the state's parameters, not the defaults); the same arrays with the default
    parameters' values do not."""
    cls = model_class(name)
    model = cls(**parameters).start(0.0)
    model.advance(0.0, 0.5)
    values, strings, attributes = model.get_state()
    check(cls, (values, strings, attributes), initialized=True, outputs_valid=True)
    defaults = cls().values
    group = cls.table_layout().range["parameter"]
    values[group.start : group.stop] = defaults[group.start : group.stop]
    with pytest.raises(StateError, match="state is a float64 array of shape"):
        check(cls, (values, strings, attributes), initialized=True, outputs_valid=True)


def _set(at: int, x: float):
    return lambda a: a["state"].__setitem__(at, x)


@pytest.mark.parametrize(
    "name, tamper, message",
    [
        ("Flywheel", _set(1, 40.0), "wheel constants (places, axes, distribution, imbalances)"),
        ("Flywheel", _set(0, 4.0), "wheel constants"),
        ("StarTracker", _set(st.S.section, 1e6), "constants (capacity, section length"),
        (
            "StarTracker",
            _set(st.SECTIONS + st.WAITING.n, 1e6),
            "count of samples waiting 1000000.0",
        ),
        ("StarTracker", _set(st.SECTIONS + st.WAITING.n, -1.0), "count of samples waiting -1.0"),
        ("AttitudeEstimator", _set(ae.S.capacity, 1e6), "constants (capacity, section length, R)"),
        ("AttitudeEstimator", _set(ae.SECTIONS + ae.FILTER.n_records, 2.5), "count of records 2.5"),
        (
            "AttitudeEstimator",
            _set(ae.SECTIONS + ae.FILTER.n_records, 1e6),
            "count of records 1000000.0",
        ),
    ],
)
def test_the_rows_the_kernels_index_with_are_those_the_model_could_hold(name, tamper, message):
    """The compiled kernels index with a state's counts and places: a state whose counts
    exceed what its arrays hold, or whose constants are not its parameters', is refused."""
    cls, (values, strings, attributes) = _stepped(name)
    tamper(attributes)
    with pytest.raises(StateError, match=re.escape(message)):
        check(cls, (values, strings, attributes), initialized=True, outputs_valid=True)


def test_an_estimator_whose_records_would_overflow_raises_instead_of_writing_past_them():
    """Records crowded after the horizon (never made by the model; the counts still in
    range) would grow past the capacity: the kernel stops with an error, nothing written."""
    model = model_class("AttitudeEstimator")().start(0.0)
    model.step(0.0, 0.1)  # no output after it: the next step advances the tampered section
    state, c = model.state, ae.SECTIONS
    capacity = int(state[ae.S.capacity])
    state[c + ae.FILTER.n_records] = capacity - 1  # one over what the state check lets through
    before = state.copy()
    with pytest.raises(Exception, match="more records than the history holds"):
        model.advance(0.1, 0.1)
    assert np.array_equal(
        state[: c + int(state[ae.S.section])], before[: c + int(before[ae.S.section])]
    )


@pytest.mark.parametrize(
    "variable, value, message",
    [
        ("h_rotor", np.nan, "parameter h_rotor is nan, not a number"),
        ("warnings_return_ok", 0.5, "warnings_return_ok is 0.5, not a Boolean"),
        ("delta_dot_cmd[2]", np.inf, "input delta_dot_cmd[2] is inf"),
    ],
)
def test_values_a_slave_never_holds_are_refused(variable, value, message):
    cls, (values, strings, attributes) = _stepped()
    layout = cls().layout
    vr = next(k for k, (_, scalar) in enumerate(layout.scalars) if scalar == variable)
    values = values.copy()
    values[vr] = value
    with pytest.raises(StateError, match=re.escape(message)):
        check(cls, (values, strings, attributes), initialized=True, outputs_valid=False)


def test_the_slave_refuses_a_tampered_state_with_fmi2error_and_steps_on():
    """In-process: the bytes of a state with a short kernel array are refused by the
    deserializer and by the setter; the slave keeps its own state."""
    from agilesat.fmus import fmu_state

    fmu = slave("SatelliteDynamics")
    fmu.exit_initialization_mode()
    assert fmu.do_step(0.0, 0.05)
    data = fmu._get_fmu_state()
    cls = slave_class("SatelliteDynamics")
    (model_state, wrapper) = fmu_state.decode(cls._identity(), data, "agilesat")
    model_state[2]["state"] = model_state[2]["state"][:30]
    bad = fmu_state.encode(cls._identity(), (model_state, wrapper), "agilesat")
    assert "shape (30,)" in cls._fmu_state_from_bytes(bad).reason
    fmu._set_fmu_state(bad)
    size = fmu.model.state.size  # SatelliteDynamics.STATE.size
    assert f"shape (30,), not a float64 array of shape ({size},)" in logged(fmu)[-1]
    assert fmu.model.state.shape == (size,) and fmu.do_step(0.05, 0.05)
