"""Sensed systems for the benchmarks, until the scenarios' ``:sensed`` variants exist: a
shipped scenario's system with the four sensing FMUs in the loop (StarTracker, Gyro,
AttitudeEstimator on the true body; DisturbanceTorques on the hub), at their defaults but
for the star tracker's mounting: looking along −z_B, away from the nadir the payloads
point at (the estimator told so).

- ``scan_pitch:sensed``: the steering law's body rate is the estimator's (the pitch
  controller keeps the true attitude relative to the orbit frame, which the estimator
  does not give);
- ``video_sar:sensed``: the attitude controller tracks the estimated attitude and rate.

    from sensed import sensed
    scenario = sensed("video_sar", out_dir)   # .ssd (written there), .components, .step, .stop
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from agilesat.orchestration.scenarios import get

SENSING = ("StarTracker", "Gyro", "AttitudeEstimator", "DisturbanceTorques")
SENSORS = (
    ("SatelliteDynamics.q_BI", "StarTracker.q_BI"),
    ("SatelliteDynamics.w_BI_B", "StarTracker.w_BI_B"),
    ("OrbitEnvironment.sun_I", "StarTracker.sun_I"),
    ("OrbitEnvironment.r_I", "StarTracker.r_I"),
    ("SatelliteDynamics.w_BI_B", "Gyro.w_BI_B"),
    ("Gyro.w_meas_B", "AttitudeEstimator.w_meas_B"),
    ("StarTracker.q_BI_meas", "AttitudeEstimator.q_BI_meas"),
    ("StarTracker.valid", "AttitudeEstimator.meas_valid"),
    ("StarTracker.t_meas", "AttitudeEstimator.t_meas"),
    ("SatelliteDynamics.q_BI", "DisturbanceTorques.q_BI"),
    ("SatelliteDynamics.w_BI_B", "DisturbanceTorques.w_BI_B"),
    ("OrbitEnvironment.r_I", "DisturbanceTorques.r_I"),
    ("OrbitEnvironment.v_I", "DisturbanceTorques.v_I"),
    ("OrbitEnvironment.sun_I", "DisturbanceTorques.sun_I"),
    ("OrbitEnvironment.earth_angle", "DisturbanceTorques.earth_angle"),
    ("DisturbanceTorques.tau_ext_B", "SatelliteDynamics.tau_ext"),
)
#: the star tracker along −z_B: 180° about x_B
MOUNTING = {
    "StarTracker.q_SB": [0.0, 1.0, 0.0, 0.0],
    "AttitudeEstimator.q_SB": [0.0, 1.0, 0.0, 0.0],
}
#: per scenario: (the connection the estimate replaces, its new source)
ESTIMATED = {
    "scan_pitch": {"CmgSteering.w_BI_B": "AttitudeEstimator.w_BI_B_est"},
    "video_sar": {
        "AttitudeController.q_BI": "AttitudeEstimator.q_BI_est",
        "AttitudeController.w_BI_B": "AttitudeEstimator.w_BI_B_est",
    },
}


def sensed(name: str, out_dir: Path):
    """Scenario ``name``'s system with the sensing FMUs in its loop (the mission API's
    System), its SSD written to ``out_dir``: a namespace with ``ssd``, ``components``,
    ``step`` and ``stop``."""
    system = get(name).system.copy(f"{name}_sensed")
    for component in SENSING:
        system.add(component)
    for target, source in ESTIMATED[name].items():
        system.connect(source, target, replace=True)
    for source, target in SENSORS:
        system.connect(source, target)
    system.set(MOUNTING)
    ssd = system.write(Path(out_dir) / f"{name}_sensed.ssd")
    return SimpleNamespace(
        ssd=ssd, components=system.components, step=system.step, stop=system.stop
    )
