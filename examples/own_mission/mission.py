"""My own mission: after separation the satellite detumbles, then slews to point its
payload at a target, and holds it there for an observation window.

A mission of your own, written as the shipped scenarios are (copy this directory anywhere):

    agilesat build mode_controller.py           # the controller of your own, as an FMU
    agilesat info mission.py                    # the system as the master sees it
    agilesat run mission.py                     # run, judge the requirements, draw the figure
    agilesat run mission.py:sensed              # a variant: star tracker and gyro in the loop
    agilesat export mission.py --out mission.ssp
    agilesat campaign mission.py --runs 20 --vary "SatelliteDynamics.rate0=+normal(0, 0.5deg)"

The system: the orbit (OrbitEnvironment), the rigid body with gravity gradient
(SatelliteDynamics), three reaction wheels (Flywheel) and the two-mode controller of
``mode_controller.py``.  A 12/14/10 kg·m² small satellite in a 550 km sun-synchronous
orbit, tumbling at 2.7 °/s after separation, HR12-class wheels (0.2 N·m, 12 N·m·s).
"""

import math

import numpy as np

from agilesat.orchestration.mission import (
    Metric,
    NotEvaluable,
    Pointing,
    Scenario,
    System,
    Variant,
    at_least,
    at_most,
    deg,
    panels,
)
from agilesat.orchestration.mission import metrics as m
from agilesat.orchestration.pointing import PointingRequirement

INERTIA = np.diag([12.0, 14.0, 10.0])  # kg·m²
WINDOW = (200.0, 240.0)  # s: the observation window, where the pointing is judged
BORESIGHT = (0.0, 0.0, 1.0)  # the payload's, in body axes
CAPACITY = 12.0  # N·m·s: each wheel's momentum limit

SYSTEM = System("own_mission", step=0.1, stop=WINDOW[1])  # Jacobi, derivatives: the default
SYSTEM.add(
    "OrbitEnvironment",
    semi_major_axis=6378137.0 + 550e3,
    inclination=deg(97.6),
)
SYSTEM.add(
    "SatelliteDynamics",
    inertia=INERTIA,
    rate0="[2, -1.5, 1] deg/s",  # the tumble after separation, relative to the orbit frame
    gravity_gradient=True,
)
SYSTEM.add("Controller", "mode_controller.py", detumble_gain=1.0, slew_rate="2 deg/s")
SYSTEM.add("Flywheel", momentum_limit=CAPACITY)
SYSTEM.connect("OrbitEnvironment.r_I", "SatelliteDynamics.r_I")
SYSTEM.connect("OrbitEnvironment.q_OI", "SatelliteDynamics.q_OI")
SYSTEM.connect("OrbitEnvironment.w_OI_O", "SatelliteDynamics.w_OI_O")
SYSTEM.connect("SatelliteDynamics.q_BI", "Controller.q_BI")
SYSTEM.connect("SatelliteDynamics.w_BI_B", "Controller.w_BI_B")
SYSTEM.connect("Controller.tau_cmd", "Flywheel.tau_cmd")
SYSTEM.connect("SatelliteDynamics.w_BI_B", "Flywheel.w_BI_B")
SYSTEM.connect("Flywheel.h", "SatelliteDynamics.h_wheel")
SYSTEM.connect("Flywheel.hdot", "SatelliteDynamics.hdot_wheel")

#: the boresight's angle from where it should point, per sample (rad)
OFF_TARGET = m.pointing_angle("SatelliteDynamics.q_BI", "Controller.q_ref", boresight=BORESIGHT)


def detumbled_at(results) -> float:
    """The time the controller hands over from detumbling to pointing."""
    pointing = np.flatnonzero(results["Controller.mode"] == 2)
    if not len(pointing):
        raise NotEvaluable(f"still detumbling at the end of the run ({results.time[-1]:g} s)")
    return float(results.time[pointing[0]])


METRICS = [
    Metric(
        "detumbled_at",
        detumbled_at,
        "s",
        "s",
        "time of the hand-over from detumbling to pointing",
        require=at_most(60.0),
    ),
    m.settling_time(
        OFF_TARGET,
        deg(0.05),
        name="on_target_at",
        description="from then on the boresight is within 0.05° of the target",
        require=at_most(WINDOW[0]),
    ),
    m.pointing_error(
        "SatelliteDynamics.q_BI",
        "Controller.q_ref",
        boresight=BORESIGHT,
        start=WINDOW[0],
        name="pointing_accuracy",
        description="max boresight error over the observation window",
        require=at_most(deg(0.02)),
    ),
    m.rate_error(
        "SatelliteDynamics.w_BI_B",
        start=WINDOW[0],
        name="pointing_stability",
        description="max |body rate| over the observation window (an inertial target)",
        require=at_most("0.002 deg/s"),
    ),
    m.saturation_fraction("Flywheel.saturated", name="wheel_saturation"),
    m.momentum_margin(
        "Flywheel.h",
        CAPACITY,
        name="momentum_margin",
        description="min (12 N·m·s − |h|) of the wheels",
        require=at_least(0.5 * CAPACITY),
    ),
    m.max_abs("Flywheel.motor_torque", name="max_wheel_torque"),
]

#: the pointing requirement as an ECSS contract states it (docs/pointing.md): the absolute
#: performance error of the boresight within 0.02° for 99 % of the runs at every time of
#: the window (ensemble); a single run is judged on its own record
REQUIREMENTS = [
    Pointing(
        "boresight_ape",
        PointingRequirement(
            "APE",
            bound=math.radians(0.02),
            level=0.99,
            interpretation="ensemble",
            boresight=BORESIGHT,
        ),
        attitude="SatelliteDynamics.q_BI",
        reference="Controller.q_ref",
        start=WINDOW[0],
    ),
]


def sensed(system: System) -> None:
    """A star tracker and a gyro in the loop: the controller reads the star tracker's
    attitude and the gyro's rate instead of the truth (their noise replaces the
    controller's own)."""
    system.add("StarTracker")
    system.add("Gyro")
    system.connect("SatelliteDynamics.q_BI", "StarTracker.q_BI")
    system.connect("SatelliteDynamics.w_BI_B", "StarTracker.w_BI_B")
    system.connect("OrbitEnvironment.sun_I", "StarTracker.sun_I")
    system.connect("OrbitEnvironment.r_I", "StarTracker.r_I")
    system.connect("SatelliteDynamics.w_BI_B", "Gyro.w_BI_B")
    system.connect("StarTracker.q_BI_meas", "Controller.q_BI", replace=True)
    system.connect("Gyro.w_meas_B", "Controller.w_BI_B", replace=True)
    system.set("Controller.gyro_noise", 0.0)


VARIANTS = {
    "sensed": Variant("star tracker and gyro in the loop, not the truth", system=sensed),
}


def figures(results, out_dir):
    """Rates, the boresight's angle from the target (log scale) and the wheels."""
    t = results.time
    rate = results.get("SatelliteDynamics.w_BI_B", deg=True)
    return [
        panels(
            out_dir / "mission.png",
            "Detumble, slew and observation",
            [
                (t, dict(zip(("x", "y", "z"), rate.T)), "body rate [°/s]"),
                (
                    t,
                    {"boresight from target": np.degrees(OFF_TARGET(results))},
                    "off target [°]",
                    {"limit": ((0.02,), "required ≤ 0.02° in the window"), "log": True},
                ),
                (t, dict(zip(("x", "y", "z"), results.vector("Flywheel.h").T)), "wheel h [N·m·s]"),
                (t, {"mode": results["Controller.mode"]}, "mode (1 detumble, 2 point)"),
            ],
        )
    ]


SCENARIO = Scenario(
    "own_mission",
    "Detumble after separation, then point the payload at a target",
    SYSTEM,
    metrics=METRICS,
    requirements=REQUIREMENTS,
    variants=VARIANTS,
    figures=figures,
)
