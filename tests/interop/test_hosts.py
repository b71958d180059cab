"""Our FMUs as third-party hosts and checkers use them, each in a clean process: FMPy's
``simulate_fmu`` at every FMU's own defaults, ``fmutool -check``, a host that sets inputs
only after initialisation, a host that stops on fmi2Warning; and what the exported SSDs
offer hosts (one parameter-set name, no unbound Strings, OMSimulator's annotation)."""

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from agilesat.components.cmg_cluster import CmgCluster
from agilesat.components.cmg_steering import CmgSteering
from agilesat.components.model import ModelError
from agilesat.components.orbit_environment import OrbitEnvironment
from agilesat.components.rotations import quat_from_euler123, quat_mul
from agilesat.components.satellite_dynamics import SatelliteDynamics
from agilesat.fmus import FMUS
from agilesat.orchestration.scenarios import NAMES, get
from agilesat.orchestration.system.ssp import NS, OMS_NAMESPACE
from helpers import TOOLS, run_python

HOST = TOOLS / "late_input_host.py"
FMUTOOL = Path(sys.executable).parent / "fmutool"  # fmu-manipulation-toolbox's CLI


def host(*args):
    result = run_python(
        f"import runpy, sys; sys.argv = ['host'] + {[str(a) for a in args]!r}; "
        f"runpy.run_path({str(HOST)!r}, run_name='__main__')"
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.strip().splitlines()[-1])


# -- every FMU at its own defaults -----------------------------------------------------
@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("name", FMUS)
def test_fmpy_simulate_fmu_runs_every_fmu_at_its_defaults_without_a_message(fmus, name):
    """At its DefaultExperiment: FMPy takes its stop time, and its step as the
    communication step (doubled while more than 1000 steps)."""
    answer = host("defaults", fmus[name])
    assert answer["messages"] == []  # no error, no warning, nothing
    start, stop, step = answer["experiment"]
    assert start == 0.0 and stop > 0.0 and 0.0 < step < stop
    while stop / step > 1000:
        step *= 2
    assert answer["rows"] == round(stop / step) + 1 and answer["stop"] == pytest.approx(stop)
    assert answer["finite"]


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("name", FMUS)
def test_fmutool_check_finds_every_fmu_compliant(fmus, name):
    run = subprocess.run(
        [str(FMUTOOL), "-input", str(fmus[name]), "-check"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    output = run.stdout + run.stderr
    assert run.returncode == 0, output
    assert "This FMU seems to be compliant with FMI-2.0" in output, output
    assert "No semantic error against the FMI-2 standard" in output, output
    assert not [
        line for line in output.splitlines() if line.startswith(("CRITICAL", "ERROR", "WARNING"))
    ], output


def test_satellite_defaults_are_a_satellite_at_the_default_orbit_radius_at_nadir():
    """r_I at nadir of the identity orbit frame (z_O = -r/|r|), at the radius of the
    default orbit, so the gravity gradient (on by default) has a position."""
    r_I = SatelliteDynamics().get("r_I")
    radius = np.linalg.norm(OrbitEnvironment().start(0.0).get("r_I"))
    assert np.allclose(r_I, [0.0, 0.0, -radius], rtol=1e-15)
    body = SatelliteDynamics(
        inertia=np.diag([900.0, 1000.0, 1100.0]), attitude0=[0.1, 0.0, 0.0]
    ).start()
    body.advance(0.0, 1.0)  # gravity gradient on, no error
    assert SatelliteDynamics().get("gravity_gradient")


def test_steering_defaults_are_the_default_cluster_away_from_singularity():
    cluster = CmgCluster().start()
    law = CmgSteering().start()
    assert np.array_equal(law.get("delta"), cluster.get("delta"))
    assert np.allclose(law.get("h"), cluster.get("h"), rtol=1e-12, atol=1e-12)
    assert law.get("singularity") == pytest.approx(cluster.get("singularity"), rel=1e-12)
    assert law.get("singularity") > 0.5 and not law.warnings


# -- inputs set only after initialisation --------------------------------------------
ORBIT_Q = quat_from_euler123([0.3, -1.2, 2.0])


def fmi_like(attitude0=(0.0, 2.0, 0.0)):
    """A model initialised the way the FMU is (initialize, no in-process start)."""
    body = SatelliteDynamics(attitude0=list(attitude0), gravity_gradient=False)
    body.initialize(0.0)
    return body


def test_inputs_given_only_after_initialisation_are_an_error():
    body = fmi_like()
    body.set("q_OI", ORBIT_Q)  # the host's first input: too late
    body.set("h_cmg", [0.0, 57.0, 0.0])
    with pytest.raises(ModelError, match=r"\['h_cmg', 'q_OI'\]|\['q_OI', 'h_cmg'\]") as error:
        body.step(0.0, 0.05)
    assert "before exitInitializationMode" in str(error.value)


def test_inputs_moving_by_one_gauss_seidel_step_are_accepted():
    """A Gauss-Seidel host passes the inputs at the step's end: that is not a late start."""
    w, h, hdot, dt = (
        np.array([0.0, -1.06e-3, 0.0]),
        np.array([1.0, 30.0, -4.0]),
        np.array([0.5, -4.0, 2.0]),
        0.05,
    )
    body = SatelliteDynamics(gravity_gradient=False)
    body.set("q_OI", ORBIT_Q)
    body.set("w_OI_O", w)
    body.set("h_cmg", h)
    body.initialize(0.0)
    turned = quat_mul(
        ORBIT_Q, np.array([math.cos(w[1] * dt / 2), 0.0, math.sin(w[1] * dt / 2), 0.0])
    )
    body.set("q_OI", turned)
    body.set("h_cmg", h + hdot * dt)
    body.set("hdot_cmg", hdot)
    body.step(0.0, dt)  # no error
    assert body.t == dt


def test_the_initial_state_uses_the_inputs_given_in_initialisation():
    body = SatelliteDynamics(attitude0=[0.0, 2.0, 0.0], gravity_gradient=False)
    body.set("q_OI", ORBIT_Q)
    body.initialize(0.0)
    body.output()
    expected = quat_mul(ORBIT_Q, quat_from_euler123([0.0, 2.0, 0.0]))
    assert abs(np.dot(body.get("q_BI"), expected)) == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize("late, error", [(True, True), (False, False)])
def test_a_servo_payload_commanded_only_after_initialisation_is_an_error(late, error):
    """PayloadGimbals with a servo starts its angles at the commands: 15° roll set late is
    an error; the same command moved by one step at 6°/s is not."""
    from agilesat.components.payload_gimbals import PayloadGimbals

    model = PayloadGimbals(bandwidth=5.0)
    rate = math.radians(6.0)
    if not late:
        model.set("roll_cmd", [math.radians(15.0)] * 2)
    model.initialize(0.0)
    model.set("roll_cmd", [math.radians(15.0) + rate * 0.05] * 2)
    model.set("roll_rate_cmd", [rate] * 2)
    if error:
        with pytest.raises(ModelError, match=r"\['roll_cmd'\]"):
            model.step(0.0, 0.05)
    else:
        model.step(0.0, 0.05)


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("read_first", [0, 1])
def test_a_host_setting_inputs_only_after_initialisation_gets_fmi2Error(fmus, read_first):
    """A host like FMPy's SSP prototype: parameters, initialisation with no inputs, then
    the inputs before the first doStep (reading the outputs first or not)."""
    inputs = {"q_OI": ORBIT_Q.tolist(), "h_cmg": [0.0, 57.0, 0.0]}
    answer = host("late", fmus["SatelliteDynamics"], read_first, json.dumps(inputs))
    assert answer["status"] == 3  # fmi2Error
    ((status, category, message),) = answer["messages"]
    assert status == 3 and "q_OI" in message and "h_cmg" in message
    assert "before exitInitializationMode" in message


@pytest.mark.slow
@pytest.mark.integration
def test_a_host_changing_no_input_after_initialisation_runs(fmus):
    answer = host("late", fmus["SatelliteDynamics"], 1, json.dumps({"tau_ext": [0.0, 0.0, 0.0]}))
    assert answer["status"] == 0 and answer["messages"] == []


# -- warnings for hosts that stop on fmi2Warning ---------------------------------------
def test_every_model_has_the_warnings_return_ok_parameter():
    from agilesat.fmus import model_class

    for name in FMUS:
        v = model_class(name)().layout.by_name["warnings_return_ok"]
        assert (v.causality, v.type, v.start) == ("parameter", "Boolean", False)


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("jit_after", ["default", "0"])
def test_a_warning_returns_fmi2Warning_by_default(fmus, monkeypatch, jit_after):
    """Also with the kernels compiled from the first call, where the steps after it may run
    in the shim's C step path: the warning of an output evaluated in Python is reported by
    the next doStep all the same."""
    if jit_after != "default":
        monkeypatch.setenv("AGILESAT_JIT_AFTER", jit_after)
    answer = host("warning", fmus["CmgSteering"], 0)
    assert answer["status"] == 1  # fmi2Warning
    assert [m[:2] for m in answer["messages"]] == [[1, "logStatusWarning"]]
    assert "singular gimbal configuration" in answer["messages"][0][2]


@pytest.mark.slow
@pytest.mark.integration
def test_with_warnings_return_ok_the_warning_is_logged_and_the_call_returns_fmi2OK(fmus):
    """Needs both sides: the slave logs at fmi2OK, category logStatusWarning; the shim
    forwards such a message to the host even with debug logging off, as a message of
    status fmi2Warning (hosts log it as a warning), from a call that returns fmi2OK."""
    answer = host("warning", fmus["CmgSteering"], 1)
    assert answer["status"] == 0  # fmi2OK
    assert [m[:2] for m in answer["messages"]] == [[1, "logStatusWarning"]]
    assert "singular gimbal configuration" in answer["messages"][0][2]


# -- what the exported SSDs offer hosts -------------------------------------------------
def system_file(name):
    return etree.parse(str(get(name).ssd))


@pytest.mark.parametrize("name", NAMES)
def test_every_parameter_set_has_the_systems_name(name):
    root = system_file(name).getroot()
    sets = root.findall(".//ssv:ParameterSet", {**NS})
    assert sets and {s.get("name") for s in sets} == {root.get("name")} == {name}


@pytest.mark.parametrize("name", NAMES)
def test_no_unbound_string_connector_is_exported(name):
    tree = system_file(name)
    for connector in tree.iterfind(".//ssd:Connector[ssc:String]", NS):
        component = connector.getparent().getparent()
        bound = component.findall(f".//ssv:Parameter[@name='{connector.get('name')}']", NS)
        assert bound, f"{component.get('name')}.{connector.get('name')}"


def test_video_sar_needs_no_string():
    tree = system_file("video_sar")
    assert not tree.findall(".//ssc:String", NS) and not tree.findall(".//ssv:String", NS)


@pytest.mark.parametrize("name", NAMES)
def test_omsimulator_fixed_step_annotation_is_on_the_system(name):
    tree = system_file(name)
    ns = {**NS, "oms": OMS_NAMESPACE}
    (master,) = tree.findall(
        "ssd:System/ssd:Annotations/ssc:Annotation[@type='org.openmodelica']"
        "/oms:Annotations/oms:SimulationInformation/oms:FixedStepMaster",
        ns,
    )
    assert float(master.get("stepSize")) == get(name).step


# -- the epoch as a Real ------------------------------------------------------------------
def test_epoch_j2000_is_the_same_instant_as_the_epoch_string():
    """2016-11-25T08:08:03 UTC is 6172 days + 72483 s after 2000-01-01T12:00:00 (by hand:
    16 years with 4 leap days (2000, 2004, 2008, 2012) to 2016-01-01 12:00, 329 days to
    2016-11-25 12:00 in a leap year, then 08:08:03 is 3 h 51 min 57 s = 13917 s earlier)."""
    seconds = (16 * 365 + 4 + 329) * 86400.0 - 13917.0
    common = dict(target_lat=0.5, target_lon=2.2, j2=True)
    by_string = OrbitEnvironment(epoch="2016-11-25T08:08:03", **common).start(0.0)
    by_real = OrbitEnvironment(epoch_j2000=seconds, **common).start(0.0)
    for model in (by_string, by_real):
        model.advance(0.0, 100.0)
    for name in ("earth_angle", "r_T_I", "v_T_I", "r_I"):
        assert np.array_equal(by_real.get(name), by_string.get(name)), name
    assert get("video_sar").system.parameters["OrbitEnvironment.epoch_j2000"] == seconds


def test_giving_the_epoch_twice_is_an_error():
    with pytest.raises(ModelError, match="epoch is given twice"):
        OrbitEnvironment(epoch="2016-11-25T08:08:03", epoch_j2000=5.3e8).start(0.0)
