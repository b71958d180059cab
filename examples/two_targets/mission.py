"""Two ground targets on one pass: slew → stare → slew → stare with six CMGs, the CMGs'
momentum unloaded by magnetorquers (docs/own-mission.md):

    agilesat run mission.py
"""

import math

import numpy as np

from agilesat.orchestration.mission import (
    Metric,
    Scenario,
    System,
    at_most,
    deg,
    nadir,
    stare,
    timeline,
)
from agilesat.orchestration.mission import metrics as m
from agilesat.orchestration.scenarios.video_sar import DELTA0, ORBIT  # the paper's pass

J, BANDWIDTH = 956.0, 0.5  # kg·m² about each axis, rad/s
A = (ORBIT["target_lat"], ORBIT["target_lon"])  # Sasebo; B 0.4° north and 0.5° east of it
B = (A[0] + math.radians(0.4), A[1] + math.radians(0.5))
STARE = 3  # SlewGuidance's mode while it stares

system = System("two_targets", step=0.05, stop=190.0)
system.add("OrbitEnvironment", **ORBIT)
system.add("SlewGuidance", **timeline(nadir(0.0), stare(10.0, *A), stare(110.0, *B)))
system.add(
    "AttitudeController",
    inertia=J * np.eye(3),
    acceleration_feedforward=True,
    kp=[J * BANDWIDTH**2] * 3,
    kd=[1.4 * J * BANDWIDTH] * 3,
)
system.add("CmgCluster", delta0=DELTA0)
system.add("CmgSteering")
system.add("SatelliteDynamics", inertia=J * np.eye(3), gravity_gradient=True)
system.add("DisturbanceTorques")  # drag, solar pressure, residual dipole; the field b_B
system.add("MomentumManager", gain=1e-3)
system.add("Magnetorquer")
for source, target, signals in [
    ("OrbitEnvironment", "SlewGuidance", "r_I v_I q_OI w_OI_O earth_angle"),
    ("OrbitEnvironment", "SatelliteDynamics", "r_I q_OI w_OI_O"),
    ("OrbitEnvironment", "DisturbanceTorques", "r_I v_I sun_I earth_angle"),
    ("SlewGuidance", "AttitudeController", "q_ref w_ref dw_ref"),
    ("SatelliteDynamics", "AttitudeController", "q_BI w_BI_B"),
    ("SatelliteDynamics", "DisturbanceTorques", "q_BI w_BI_B"),
    ("SatelliteDynamics", "CmgSteering", "w_BI_B"),
    ("AttitudeController", "CmgSteering", "tau_cmd"),
    ("CmgCluster", "CmgSteering", "delta h"),
    ("CmgSteering", "CmgCluster", "delta_dot_cmd"),
    ("DisturbanceTorques", "MomentumManager", "b_B"),
    ("DisturbanceTorques", "Magnetorquer", "b_B"),
]:
    for signal in signals.split():
        system.connect(f"{source}.{signal}", f"{target}.{signal}")
system.connect("CmgCluster.h", "SatelliteDynamics.h_cmg")
system.connect("CmgCluster.hdot", "SatelliteDynamics.hdot_cmg")
system.connect("CmgCluster.h", "MomentumManager.h_B")
system.connect("MomentumManager.m_cmd_B", "Magnetorquer.m_cmd_B")
system.connect("Magnetorquer.tau_B", "SatelliteDynamics.tau_ctrl")
system.connect("DisturbanceTorques.tau_ext_B", "SatelliteDynamics.tau_ext")

OFF_TARGET = m.pointing_angle("SatelliteDynamics.q_BI", "SlewGuidance.q_ref", boresight=(0, 0, 1))


def staring_error(results) -> float:
    """The boresight's largest angle from the target while SlewGuidance stares."""
    return float(OFF_TARGET(results)[results["SlewGuidance.mode"] == STARE].max())


def final_momentum(results) -> float:
    """What the CMGs hold at the end: the stare's J ω, less what the rods took out."""
    return float(np.linalg.norm(results.vector("CmgCluster.h")[-1]))


SCENARIO = Scenario(
    "two_targets",
    "Slew, stare, slew, stare over a pass, with momentum management",
    system,
    metrics=[
        Metric(
            "staring_error",
            staring_error,
            "rad",
            "deg",
            "max boresight error staring",
            require=at_most(deg(0.05)),
        ),
        m.max_abs("CmgCluster.h", norm=True, name="max_cmg_momentum"),
        Metric(
            "final_cmg_momentum", final_momentum, "N.m.s", "N.m.s", "|h| of the CMGs at the end"
        ),
        m.max_abs("Magnetorquer.m_B", name="max_dipole"),
    ],
)
