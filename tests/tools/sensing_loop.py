"""A closed attitude loop through the sensing FMUs, for the hosts' tests: a hub holding the
orbit frame with a reaction wheel, closed through the sensors and the MEKF by the mission
API's own wiring (:func:`agilesat.orchestration.scenarios.closed_loop.close_the_loop`, the
``sensed`` variants' and docs/sensing.md's: star tracker and gyro measure the hub, the
controller reads the estimate, the disturbance torques act on the hub), with the four FMUs
no shipped scenario's nominal system uses (StarTracker, Gyro, AttitudeEstimator,
DisturbanceTorques).  ``write_ssd(directory)`` writes it."""

from __future__ import annotations

from pathlib import Path

import numpy as np

STEP, STOP = 0.05, 60.0
#: the star tracker looking at the zenith (−z_B), not at the Earth
BORESIGHT = (0.0, 0.0, -1.0)


def write_ssd(directory: Path) -> Path:
    """The loop's SSD in ``directory`` (its FMUs ours, built)."""
    from agilesat.orchestration.mission import System
    from agilesat.orchestration.scenarios.closed_loop import close_the_loop, mounting

    system = System("sensing_loop", stop=STOP, step=STEP, algorithm="jacobi")
    system.add("OrbitEnvironment")
    # a non-isotropic hub (gravity gradient on), turning slowly away from the orbit frame
    system.add(
        "SatelliteDynamics",
        inertia=np.diag([956.0, 1120.0, 830.0]).tolist(),
        rate0=[2e-4, -3e-4, 1e-4],
    )
    system.add("Flywheel")
    system.add("AttitudeController")
    for signal in ("q_OI", "w_OI_O", "r_I"):
        system.connect(f"OrbitEnvironment.{signal}", f"SatelliteDynamics.{signal}")
    system.connect("OrbitEnvironment.q_OI", "AttitudeController.q_ref")
    system.connect("OrbitEnvironment.w_OI_O", "AttitudeController.w_ref")
    system.connect("SatelliteDynamics.q_BI", "AttitudeController.q_BI")  # the estimate's, below
    system.connect("SatelliteDynamics.w_BI_B", "AttitudeController.w_BI_B")
    system.connect("AttitudeController.tau_cmd", "Flywheel.tau_cmd")
    system.connect("SatelliteDynamics.w_BI_B", "Flywheel.w_BI_B")
    system.connect("Flywheel.h", "SatelliteDynamics.h_wheel")
    system.connect("Flywheel.hdot", "SatelliteDynamics.hdot_wheel")
    close_the_loop(system, controller="AttitudeController", mount=mounting(BORESIGHT))
    return system.write(Path(directory) / "sensing_loop.ssd")
