"""The system builder (orchestration/mission/system.py): every mistake named with the file
and line of the call that made it and what is wrong, in the master's own words; units where
a variable is a Real; the SSD it writes is the system it checked; a third-party FMU is
described from its model description alone."""

import math
from pathlib import Path

import numpy as np
import pytest

from agilesat.orchestration.mission import System, deg
from agilesat.orchestration.system.description import Description
from agilesat.orchestration.system.ssp import ConnectionRef, SystemFileError, read_system
from agilesat.orchestration.system.validation import check_system
from helpers import pythonfmu_damper

HERE = str(Path(__file__).resolve())


def line_of(text: str) -> int:
    """The line of this file that holds ``text``."""
    lines = Path(HERE).read_text().splitlines()
    return next(k + 1 for k, line in enumerate(lines) if text in line)


def detumble() -> System:
    """Satellite, wheels and a rate damper of ours (AttitudeController with kp = 0)."""
    system = System("detumble", step=0.05, stop=2.0)
    system.add("SatelliteDynamics", inertia=50 * np.eye(3), gravity_gradient=False)
    system.add("AttitudeController", kp=[0.0] * 3, kd=[5.0] * 3)
    system.add("Flywheel")
    system.connect("SatelliteDynamics.q_BI", "AttitudeController.q_BI")
    system.connect("SatelliteDynamics.w_BI_B", "AttitudeController.w_BI_B")
    system.connect("AttitudeController.tau_cmd", "Flywheel.tau_cmd")
    system.connect("SatelliteDynamics.w_BI_B", "Flywheel.w_BI_B")
    system.connect("Flywheel.h", "SatelliteDynamics.h_wheel")
    system.connect("Flywheel.hdot", "SatelliteDynamics.hdot_wheel")
    return system


def test_an_unknown_component_is_named_at_once_with_the_closest(fmus):
    system = detumble()
    with pytest.raises(KeyError, match=r"unknown component 'Flywhel'; did you mean Flywheel\?"):
        system.connect("Flywhel.h", "SatelliteDynamics.h_wheel", replace=True)
    with pytest.raises(KeyError, match=r"unknown component 'Sat'"):
        system.set("Sat.inertia", np.eye(3))


def test_an_unknown_fmu_is_named_with_file_and_line_where_it_is_added(fmus):
    """A misspelt FMU is said at add(), with the FMU meant (not at the first connection,
    whose closest component would be the misspelt one)."""
    system = System("s", step=0.1, stop=1.0)
    with pytest.raises(SystemFileError) as error:
        system.add("Wheel", "Flywhel")
    line = line_of('system.add("Wheel", "Flywhel")')
    at = f"{HERE}:{line}"
    assert str(error.value).startswith(
        f"{at}: component 'Wheel': unknown FMU 'Flywhel'; did you mean Flywheel? (ours: "
    )
    with pytest.raises(SystemFileError, match="unknown FMU 'Flywhel'; did you mean Flywheel?"):
        system.add("Flywhel")  # its name is its FMU's
    assert system.components == ()


def test_variable_shape_and_unit_mistakes_are_reported_together_where_they_were_made(fmus):
    system = detumble()
    system.connect("SatelliteDynamics.w_BI", "AttitudeController.w_ref")  # no such variable
    system.connect("SatelliteDynamics.q_BI", "AttitudeController.h_ff")  # 4 -> 3
    system.connect("SatelliteDynamics.w_BI_B", "AttitudeController.hdot_ff")  # rad/s -> N.m
    system.set("SatelliteDynamics.inertia", deg(np.eye(3).tolist()))  # an angle for an inertia
    with pytest.raises(SystemFileError) as error:
        system.check()
    text = str(error.value)
    assert text.startswith(f"{HERE}: 4 problem(s):")
    where = {
        "w_BI": line_of('"SatelliteDynamics.w_BI", "AttitudeController.w_ref"'),
        "shape": line_of('"SatelliteDynamics.q_BI", "AttitudeController.h_ff"'),
        "unit": line_of('"SatelliteDynamics.w_BI_B", "AttitudeController.hdot_ff"'),
        "inertia": line_of('system.set("SatelliteDynamics.inertia", deg('),
    }
    assert (
        f"{HERE}:{where['w_BI']}: connection SatelliteDynamics.w_BI -> AttitudeController.w_ref:"
        " SatelliteDynamics (SatelliteDynamics.fmu) has no variable 'w_BI'; did you mean w_BI_B"
    ) in text
    assert (
        f"{HERE}:{where['shape']}: connection SatelliteDynamics.q_BI -> AttitudeController.h_ff:"
        " shapes differ: SatelliteDynamics.q_BI is 4, AttitudeController.h_ff is 3"
    ) in text
    assert (
        f"{HERE}:{where['unit']}: connection SatelliteDynamics.w_BI_B -> "
        "AttitudeController.hdot_ff: unit mismatch, 'rad/s' -> 'N.m'"
    ) in text
    assert (
        f"{HERE}:{where['inertia']}: SatelliteDynamics.inertia[1,1]=1.0 deg: unit mismatch: "
        "1.0 deg is "
        "an angle [rad], the variable is an inertia [kg.m2]"
    ) in text


def test_the_unit_message_is_the_masters(fmus):
    """The builder's message for a connection of mismatched units is the one the master
    gives for the same connection in a system file."""
    system = detumble()
    system.connect("SatelliteDynamics.w_BI_B", "AttitudeController.hdot_ff")
    with pytest.raises(SystemFileError) as built:
        system.check()
    good = detumble().system_file()
    wrong = ConnectionRef("SatelliteDynamics", "w_BI_B[1]", "AttitudeController", "hdot_ff[1]", 9)
    good.connections.append(wrong)
    described = {c.name: Description(c.name, c.source) for c in good.components}
    with pytest.raises(SystemFileError) as master:
        check_system(good, described, good.parameters)
    message = "unit mismatch, 'rad/s' -> 'N.m'"
    assert message in str(built.value) and message in str(master.value)


def test_causality_and_an_input_left_open_in_the_masters_words(fmus):
    system = System("open", step=0.1, stop=1.0)
    system.add("SatelliteDynamics")
    system.add("Flywheel")
    system.connect("Flywheel.tau_cmd", "SatelliteDynamics.h_wheel")  # an input as the source
    with pytest.raises(
        SystemFileError, match="'tau_cmd' of Flywheel is an input, expected an output"
    ):
        system.check()
    system = System("open", step=0.1, stop=1.0).add("Flywheel")
    with pytest.raises(SystemFileError, match="required input Flywheel.tau_cmd.* is not connected"):
        system.check()


def test_an_input_is_connected_once_unless_replaced(fmus):
    system = detumble()
    first = r"\(to AttitudeController.tau_cmd, line \d+\): connect\(\.\.\., replace=True\)"
    with pytest.raises(ValueError, match=r"Flywheel.tau_cmd is already connected " + first):
        system.connect("SatelliteDynamics.w_BI_B", "Flywheel.tau_cmd")
    system.connect("SatelliteDynamics.w_BI_B", "Flywheel.tau_cmd", replace=True)
    assert ("SatelliteDynamics.w_BI_B", "Flywheel.tau_cmd") in system.connections
    assert ("AttitudeController.tau_cmd", "Flywheel.tau_cmd") not in system.connections


def test_values_with_units_convert_to_the_variables_unit(fmus):
    system = detumble()
    system.set("SatelliteDynamics.attitude0", deg([0, 120, 0]))
    system.set("SatelliteDynamics.rate0", "[1, 0, -2] deg/s")
    system.set("Flywheel.torque_limit", "200 mN.m")
    values = {(p.component, p.name): p.value for p in system.system_file().parameters}
    assert values[("SatelliteDynamics", "attitude0[2]")] == 120 * math.pi / 180
    assert values[("SatelliteDynamics", "rate0[3]")] == -2 * math.pi / 180
    assert values[("Flywheel", "torque_limit")] == pytest.approx(0.2, rel=1e-15)
    origin = next(p.origin for p in system.system_file().parameters if p.name == "rate0[1]")
    line = line_of('system.set("SatelliteDynamics.rate0"')
    assert origin == f"{HERE}:{line}"


def test_the_builder_defaults_to_the_masters_best_scheme(fmus, tmp_path):
    system = detumble()
    assert (system.algorithm, system.derivatives) == ("jacobi", True)
    path = system.write(tmp_path / "detumble.ssd")
    read = read_system(path)
    assert (read.algorithm, read.derivatives) == ("jacobi", None)  # derivatives: the default
    off = detumble()
    off.derivatives = False
    assert read_system(off.write(tmp_path / "off.ssd")).derivatives is False


def test_the_written_ssd_is_the_system_checked(fmus, tmp_path):
    system = detumble()
    built = system.system_file()
    read = read_system(system.write(tmp_path / "sub" / "detumble.ssd"))
    assert [(c.name, c.source) for c in read.components] == [
        (c.name, c.source) for c in built.components
    ]
    assert [str(c) for c in read.connections] == [str(c) for c in built.connections]
    assert [(p.component, p.name, p.type, p.value) for p in read.parameters] == [
        (p.component, p.name, p.type, p.value) for p in built.parameters
    ]
    assert (read.start_time, read.stop_time, read.step_size) == (0.0, 2.0, 0.05)


def test_a_system_of_one_unconnected_component_writes_and_runs(fmus, tmp_path):
    """No connections: the SSD has no (empty, schema-invalid) Connections element."""
    from agilesat.orchestration.cosim.master import simulate

    alone = System("alone", step=0.05, stop=0.5)
    alone.add("hub", "SatelliteDynamics", rate0=[0.01, 0.0, 0.0])
    path = alone.write(tmp_path / "alone.ssd")
    assert read_system(path).connections == []
    assert simulate(path)["hub.w_BI_B[1]"][-1] == pytest.approx(0.01)


def test_a_third_party_fmu_is_described_from_its_model_description(fmus, tmp_path):
    """An FMU made with pythonfmu alone (no units, no agilesat annotations): its connectors
    come from its model description, an array connects element by element."""
    fmu = pythonfmu_damper(tmp_path)
    system = detumble()
    system.remove("AttitudeController")
    system.add("Damper", fmu, gain=7.0)
    system.connect("SatelliteDynamics.w_BI_B", "Damper.w_BI_B")
    system.connect("Damper.tau_cmd", "Flywheel.tau_cmd")
    ssd = system.write(tmp_path / "third.ssd")
    read = read_system(ssd)
    damper = next(c for c in read.components if c.name == "Damper")
    assert [(c.name, c.kind, c.unit) for c in damper.connectors][:3] == [
        ("gain", "parameter", None),
        ("w_BI_B[1]", "input", None),
        ("tau_cmd[1]", "output", None),
    ]
    assert ("Damper", "gain", 7.0) in [(p.component, p.name, p.value) for p in read.parameters]
    assert sum(c.end_element == "Damper" for c in read.connections) == 3
