"""A closed attitude loop through the sensing FMUs, for the hosts' tests: the wiring of
docs/sensing.md (star tracker and gyro measure the hub, the MEKF estimates, the controller
holds the orbit frame with the reaction wheels from the estimate, the disturbance torques
act on the hub), with the four FMUs no shipped scenario uses (StarTracker, Gyro,
AttitudeEstimator, DisturbanceTorques).  ``write_ssd(directory, fmus)`` writes it."""

from __future__ import annotations

from pathlib import Path

import numpy as np

COMPONENTS = (
    "OrbitEnvironment",
    "SatelliteDynamics",
    "Flywheel",
    "AttitudeController",
    "Gyro",
    "StarTracker",
    "AttitudeEstimator",
    "DisturbanceTorques",
)
CONNECTIONS = [
    ("OrbitEnvironment.q_OI", "SatelliteDynamics.q_OI"),
    ("OrbitEnvironment.w_OI_O", "SatelliteDynamics.w_OI_O"),
    ("OrbitEnvironment.r_I", "SatelliteDynamics.r_I"),
    ("OrbitEnvironment.q_OI", "AttitudeController.q_ref"),
    ("OrbitEnvironment.w_OI_O", "AttitudeController.w_ref"),
    ("OrbitEnvironment.r_I", "StarTracker.r_I"),
    ("OrbitEnvironment.sun_I", "StarTracker.sun_I"),
    ("SatelliteDynamics.q_BI", "StarTracker.q_BI"),
    ("SatelliteDynamics.w_BI_B", "StarTracker.w_BI_B"),
    ("SatelliteDynamics.w_BI_B", "Gyro.w_BI_B"),
    ("Gyro.w_meas_B", "AttitudeEstimator.w_meas_B"),
    ("StarTracker.q_BI_meas", "AttitudeEstimator.q_BI_meas"),
    ("StarTracker.valid", "AttitudeEstimator.meas_valid"),
    ("StarTracker.t_meas", "AttitudeEstimator.t_meas"),
    ("AttitudeEstimator.q_BI_est", "AttitudeController.q_BI"),
    ("AttitudeEstimator.w_BI_B_est", "AttitudeController.w_BI_B"),
    ("AttitudeController.tau_cmd", "Flywheel.tau_cmd"),
    ("SatelliteDynamics.w_BI_B", "Flywheel.w_BI_B"),
    ("Flywheel.h", "SatelliteDynamics.h_wheel"),
    ("Flywheel.hdot", "SatelliteDynamics.hdot_wheel"),
    ("SatelliteDynamics.q_BI", "DisturbanceTorques.q_BI"),
    ("SatelliteDynamics.w_BI_B", "DisturbanceTorques.w_BI_B"),
    ("OrbitEnvironment.r_I", "DisturbanceTorques.r_I"),
    ("OrbitEnvironment.v_I", "DisturbanceTorques.v_I"),
    ("OrbitEnvironment.sun_I", "DisturbanceTorques.sun_I"),
    ("OrbitEnvironment.earth_angle", "DisturbanceTorques.earth_angle"),
    ("DisturbanceTorques.tau_ext_B", "SatelliteDynamics.tau_ext"),
]
#: a non-isotropic hub (gravity gradient on), turning slowly away from the orbit frame; the
#: star tracker looking at the zenith (−z_B: S turned 180° about x_B), not at the Earth
PARAMETERS = {
    "SatelliteDynamics.inertia": np.diag([956.0, 1120.0, 830.0]).tolist(),
    "SatelliteDynamics.rate0": [2e-4, -3e-4, 1e-4],
    "StarTracker.q_SB": [0.0, 1.0, 0.0, 0.0],
    "AttitudeEstimator.q_SB": [0.0, 1.0, 0.0, 0.0],
}
STEP, STOP = 0.05, 60.0


def write_ssd(directory: Path, fmus: dict) -> Path:
    """The loop's SSD in ``directory``, its FMUs ``fmus`` ({name: path})."""
    from agilesat.orchestration.mission import System

    system = System("sensing_loop", stop=STOP, step=STEP, algorithm="jacobi")
    for name in COMPONENTS:
        values = {
            key.split(".", 1)[1]: value
            for key, value in PARAMETERS.items()
            if key.split(".", 1)[0] == name
        }
        system.add(name, fmus[name], **values)
    for a, b in CONNECTIONS:
        system.connect(a, b)
    return system.write(Path(directory) / "sensing_loop.ssd")
