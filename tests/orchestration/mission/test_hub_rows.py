"""Any number of devices and torques into the hub without editing a model: its tables of
slots (SatelliteDynamics ``h_extra``, ``tau_extra``), fed row by row, one line of
``System.connect`` each (orchestration/mission/system.py), in the SSD as plain
connections, and checked as the master checks any input."""

import math
import textwrap

import numpy as np
import pytest

from agilesat.orchestration import simulate
from agilesat.orchestration.mission import System
from agilesat.orchestration.system.ssp import SystemFileError


def disturbances(system: System, name: str) -> None:
    """DisturbanceTorques ``name`` on the system's orbit and hub."""
    system.add(name, "DisturbanceTorques")
    for signal in ("r_I", "v_I", "sun_I", "earth_angle"):
        system.connect(f"OrbitEnvironment.{signal}", f"{name}.{signal}")
    for signal in ("q_BI", "w_BI_B"):
        system.connect(f"SatelliteDynamics.{signal}", f"{name}.{signal}")


def hub_with_torques(*sources: str, **rows: str) -> System:
    """A hub and DisturbanceTorques instances feeding it: each name in ``sources`` into
    the table tau_extra (the next free row), each in ``rows`` into the row given."""
    system = System("torques", step=0.1, stop=1.0)
    system.add("OrbitEnvironment")
    system.add("SatelliteDynamics", gravity_gradient=False)
    for name in (*sources, *rows):
        disturbances(system, name)
    for name in sources:
        system.connect(f"{name}.tau_ext_B", "SatelliteDynamics.tau_extra")
    for name, row in rows.items():
        system.connect(f"{name}.tau_ext_B", f"SatelliteDynamics.tau_extra[{row}]")
    return system


def fed_rows(system: System) -> dict[str, list[int]]:
    """{source component: the rows of tau_extra it feeds}."""
    rows: dict[str, set] = {}
    for c in system.system_file().connections:
        if c.end_element == "SatelliteDynamics" and c.end_connector.startswith("tau_extra"):
            rows.setdefault(c.start_element, set()).add(int(c.end_connector[10]))
    return {name: sorted(found) for name, found in rows.items()}


def test_each_torque_source_takes_the_next_free_row(fmus):
    """Three sources named whole go to rows 1, 2, 3; a row named is kept for its source
    whatever the order of the calls."""
    assert fed_rows(hub_with_torques("A", "B", "C")) == {"A": [1], "B": [2], "C": [3]}
    assert fed_rows(hub_with_torques("A", "B", C="1")) == {"A": [2], "B": [3], "C": [1]}


def test_a_full_table_says_so_and_a_row_is_fed_once(fmus):
    with pytest.raises(SystemFileError, match=r"every row of SatelliteDynamics.tau_extra \(4\)"):
        hub_with_torques("A", "B", "C", "D", "E").check()
    with pytest.raises(ValueError, match=r"tau_extra\[2\] is already connected"):
        hub_with_torques(A="2", B="2")


def test_a_table_of_rows_takes_consecutive_rows_and_open_rows_are_listed(fmus):
    """The Flywheel's four jitter rows into h_extra's first four; the hub's rows 5 and 6
    stay open, each listed with what its default means."""
    system = System("wheels", step=0.1, stop=0.2)
    system.add("SatelliteDynamics", gravity_gradient=False)
    system.add("Flywheel", tau_cmd=[0.0, 0.0, 0.0])
    system.connect("SatelliteDynamics.w_BI_B", "Flywheel.w_BI_B")
    system.connect("Flywheel.h_jitter_B", "SatelliteDynamics.h_extra")
    system.connect("Flywheel.hdot_jitter_B", "SatelliteDynamics.hdot_extra")
    system.connect("Flywheel.speed", "SatelliteDynamics.h_extra_frequency")
    pairs = {(c.start_connector, c.end_connector) for c in system.system_file().connections}
    assert ("h_jitter_B[4,3]", "h_extra[4,3]") in pairs
    assert ("speed[2]", "h_extra_frequency[2,1]") in pairs
    results = simulate(system.system_file(), stop=0.2)
    open_rows = {entry["input"] for entry in results.meta["unconnected_optional_inputs"]}
    assert {"SatelliteDynamics.h_extra[5]", "SatelliteDynamics.h_extra[6]"} <= open_rows


TORQUER = '''
"""A constant torque on the body (a user's model: a thruster's leak, a magnetorquer)."""
from agilesat.components.model import Model
from agilesat.components.variables import output, parameter


class ConstantTorque(Model):
    VARIABLES = (
        parameter("torque_B", 0.0, "N.m", "the torque on the body, in B", shape=(3,)),
        output("tau_B", "N.m", "the torque on the body, in B", shape=(3,)),
    )
    STATELESS = True

    def step(self, t, dt):
        self.t = t + dt

    def output(self):
        self.y.tau_B[:] = self.p.torque_B
'''


@pytest.mark.slow
def test_a_new_torque_source_in_a_users_mission_is_one_line(fmus, tmp_path):
    """A model of the user's (a constant torque) beside DisturbanceTorques on tau_ext: one
    connect into tau_extra and the hub's total momentum about the spin axis grows by the
    sum of the two torques, H_z(t) = H_z(0) + (τ_1 + τ_2) t (both along the spin axis z,
    which the body keeps), to round-off."""
    (tmp_path / "torquer.py").write_text(textwrap.dedent(TORQUER))
    system = System("two_torques", step=0.05, stop=10.0)
    system.add("OrbitEnvironment")
    system.add("SatelliteDynamics", gravity_gradient=False, rate0=[0.0, 0.0, 0.1])
    disturbances(system, "Disturbances")
    system.set({f"Disturbances.{s}": False for s in ("aero", "srp", "magnetic")})
    system.connect("Disturbances.tau_ext_B", "SatelliteDynamics.tau_ext")
    system.add("Torquer", tmp_path / "torquer.py", torque_B=[0.0, 0.0, 0.02])
    system.connect("Torquer.tau_B", "SatelliteDynamics.tau_extra")  # the one line
    results = simulate(system.system_file(), stop=10.0)
    H = results.vector("SatelliteDynamics.H_I")
    assert np.allclose(H[:, 2], H[0, 2] + 0.02 * results.time, rtol=0, atol=1e-12)
    assert math.isclose(results.vector("SatelliteDynamics.w_BI_B")[-1, 2], 0.1 + 0.02 * 10 / 956)
