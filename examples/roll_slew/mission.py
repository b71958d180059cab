"""A 25° roll slew with six CMGs, then a 60-s imaging hold (docs/own-mission.md):

agilesat run mission.py                  # gain-scheduled: an agile slew, a quiet hold
agilesat run mission.py:fixed_gains      # the slew's gains through the hold
"""

import math

import numpy as np

from agilesat.orchestration.mission import Pointing, Scenario, System, Variant, deg, nadir, timeline
from agilesat.orchestration.mission import metrics as m
from agilesat.orchestration.pointing import PointingRequirement
from agilesat.orchestration.scenarios.closed_loop import close_the_loop, mounting
from agilesat.orchestration.scenarios.video_sar import DELTA0  # six CMGs, no momentum

J = 956.0  # kg·m² about each axis
IMAGING = 40.0  # s: the imaging hold, to the end of the run
SLEW, HOLD = 0.5, 0.1  # rad/s: the attitude loop's bandwidth slewing and imaging
NADIR = 2  # SlewGuidance's mode while it holds a nadir segment (0: slewing)


def schedule(hold: float) -> dict:
    """AttitudeController's gain tables (ζ = 0.7): the nadir hold's at bandwidth ``hold``,
    the slew's in every other mode."""
    bandwidths = [hold if mode == NADIR else SLEW for mode in range(8)]
    return {
        "kp_modes": [[J * w**2] * 3 for w in bandwidths],
        "kd_modes": [[1.4 * J * w] * 3 for w in bandwidths],
    }


system = System("roll_slew", step=0.05, stop=IMAGING + 60.0)
system.add("OrbitEnvironment")
system.add("SlewGuidance", **timeline(nadir(0.0), nadir(10.0, roll=deg(25))))
system.add(
    "AttitudeController", inertia=J * np.eye(3), acceleration_feedforward=True, **schedule(HOLD)
)
system.add("CmgCluster", delta0=DELTA0)
system.add("CmgSteering")
system.add("SatelliteDynamics", inertia=J * np.eye(3), gravity_gradient=True)
for source, target, signals in [
    ("OrbitEnvironment", "SlewGuidance", "r_I v_I q_OI w_OI_O earth_angle"),
    ("OrbitEnvironment", "SatelliteDynamics", "r_I q_OI w_OI_O"),
    ("SlewGuidance", "AttitudeController", "q_ref w_ref dw_ref mode"),
    ("SatelliteDynamics", "AttitudeController", "q_BI w_BI_B"),
    ("SatelliteDynamics", "CmgSteering", "w_BI_B"),
    ("AttitudeController", "CmgSteering", "tau_cmd"),
    ("CmgCluster", "CmgSteering", "delta h healthy"),
    ("CmgSteering", "CmgCluster", "delta_dot_cmd"),
]:
    for signal in signals.split():
        system.connect(f"{source}.{signal}", f"{target}.{signal}")
system.connect("CmgCluster.h", "SatelliteDynamics.h_cmg")
system.connect("CmgCluster.hdot", "SatelliteDynamics.hdot_cmg")
# star tracker, gyro and MEKF in the loop, disturbance torques on (docs/sensing.md)
close_the_loop(
    system,
    controller="AttitudeController",
    mount=mounting((0, 0, -1)),
    rate_inputs=("CmgSteering.w_BI_B",),
)

#: the imaging requirement: the relative pointing error in 1-s windows, 6" at 99 % of the time
RPE = PointingRequirement("RPE", math.radians(6 / 3600), 0.99, "temporal", window=1.0)
FIXED = {f"AttitudeController.{k}": v for k, v in schedule(SLEW).items()}
SCENARIO = Scenario(
    "roll_slew",
    "A 25° roll slew with six CMGs, then a 60-s imaging hold",
    system,
    metrics=[m.max_abs("CmgCluster.delta_dot", name="max_gimbal_rate")],
    requirements=[Pointing("imaging_rpe", RPE, reference="SlewGuidance.q_ref", start=IMAGING)],
    variants={"fixed_gains": Variant("the slew's gains through the hold", parameters=FIXED)},
)
