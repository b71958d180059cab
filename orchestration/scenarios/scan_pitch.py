"""``scan_pitch``: CMG pitch maneuver 120° → 0° in 100 s with a −0.8 °/s scanning phase
([Zhao 2016], DESIGN.md §4.1).

Variant ``literal_spin``: the rotor spin exactly as printed in the paper's A_s0.  The
cluster momentum bias then lies along +y and the maneuver pushes it beyond the cluster's
capacity: the run is diagnosed as failed instead of flying a wrong maneuver silently.

Variant ``sensed``: the loop as flown (:mod:`.closed_loop`): star tracker, gyro and MEKF,
the controller on the estimate relative to the orbit frame (``q_BO_est``, ``w_BO_B_est``)
and the steering's w × h on the estimated rate, disturbance torques on.  The star tracker
looks 60° from −z_B towards +x_B, at the zenith when the pitch is 60°: within 60° of the
zenith over the whole 120° maneuver, never near the Earth's limb.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from agilesat.components.cmg_cluster import GIMBAL_AXES, five_pyramid
from agilesat.components.cmg_steering import PSEUDO_INVERSE
from agilesat.components.orbit_environment import WGS84_A
from agilesat.components.pitch_maneuver_controller import PitchProfile
from agilesat.components.rotations import dcm, qmul
from agilesat.components.vectors import rotate
from agilesat.orchestration.mission import (
    Metric,
    NotEvaluable,
    Pointing,
    Scenario,
    SignalBound,
    System,
    Variant,
    lines,
    panels,
    within,
)
from agilesat.orchestration.mission import metrics as m
from agilesat.orchestration.output.results import per_results
from agilesat.orchestration.pointing import (
    PointingRequirement,
    performance_error,
    quaternion_product,
)
from agilesat.orchestration.scenarios import flexible
from agilesat.orchestration.scenarios.closed_loop import (
    KNOWLEDGE_METRICS,
    close_the_loop,
    knowledge_rows,
    magnitude_row,
    mounting,
)
from agilesat.orchestration.scenarios.constants import POINTING_CONFIDENCE, POINTING_LEVEL

DEG = math.pi / 180
# the paper's case ([Zhao 2016], DESIGN.md §4.1)
ALTITUDE = 681000.0  # m, sun-synchronous
INCLINATION = math.radians(98.1)
INERTIA = 956.0
H_ROTOR = 16.65
#: initial gimbal angles (Table 1)
PAPER_DELTA0 = (math.pi / 4, 0.0, -math.pi / 4, math.pi / 2, math.pi / 4, 0.0)
#: the rotor spin as printed in A_s0 (the cluster's default is its reverse)
PAPER_SPINS = five_pyramid()[1]
RATE_LIMIT = 0.6  # rad/s, gimbal rate limit (DESIGN.md §3)
ACCEL_LIMIT = 0.5  # rad/s², gimbal acceleration limit
PROFILE = PitchProfile(theta0=120 * DEG, theta_f=0.0, duration=100.0, scan_rate=-0.8 * DEG)
SCAN_RATE_TOLERANCE = 0.02 * DEG
SETTLED_RATE = 0.01 * DEG  # |pitch rate| below this counts as stable
#: the paper's results (Figs 4–11 and their text), SI
PAPER = {
    "imaging_pitch_rate_mean": -0.8075 * DEG,
    "max_gimbal_rate": 0.15,
    "max_gimbal_accel": 0.4,
    "feedforward_torque_phase1": -4.0,
    "feedforward_torque_phase3": 4.0,
    "max_abs_output_torque": 4.0,
    "settling_time": 105.0,
}

# The system: five of our FMUs.  Jacobi coupling (the System's default): the hub
# extrapolates the devices' momentum over the step with their hdot, a coupling error of
# second order (tests/orchestration/cosim/test_coupling.py, docs/coupling.md).
SYSTEM = System("scan_pitch", step=0.05, stop=150.0)
SYSTEM.add(
    "OrbitEnvironment",
    semi_major_axis=WGS84_A + ALTITUDE,
    eccentricity=0.0,
    inclination=INCLINATION,
)
SYSTEM.add(
    "SatelliteDynamics",
    inertia=INERTIA * np.eye(3),
    attitude0=[0.0, PROFILE.theta0, 0.0],
    rate0=[0.0, 0.0, 0.0],
    gravity_gradient=True,
)
SYSTEM.add(  # the steering must be computed for this cluster: the same h_rotor
    "CmgCluster",
    h_rotor=H_ROTOR,
    delta0=PAPER_DELTA0,
    rate_limit=RATE_LIMIT,
    accel_limit=ACCEL_LIMIT,
)
SYSTEM.add("CmgSteering", h_rotor=H_ROTOR, law=PSEUDO_INVERSE, null_gain=0.0)
SYSTEM.add(
    "PitchManeuverController",
    inertia=INERTIA,  # the feedforward I θ̈ uses the hub's pitch-axis inertia
    pitch0=PROFILE.theta0,
    pitch_final=PROFILE.theta_f,
    duration=PROFILE.duration,
    scan_rate=PROFILE.scan_rate,
    kp=0.9,
    kd=578.0,
)
SYSTEM.connect("OrbitEnvironment.r_I", "SatelliteDynamics.r_I")
SYSTEM.connect("OrbitEnvironment.q_OI", "SatelliteDynamics.q_OI")
SYSTEM.connect("OrbitEnvironment.w_OI_O", "SatelliteDynamics.w_OI_O")
SYSTEM.connect("CmgCluster.h", "SatelliteDynamics.h_cmg")
SYSTEM.connect("CmgCluster.hdot", "SatelliteDynamics.hdot_cmg")
SYSTEM.connect("SatelliteDynamics.q_BO", "PitchManeuverController.q_BO")
SYSTEM.connect("SatelliteDynamics.w_BO_B", "PitchManeuverController.w_BO_B")
SYSTEM.connect("PitchManeuverController.tau_cmd", "CmgSteering.tau_cmd")
SYSTEM.connect("CmgCluster.delta", "CmgSteering.delta")
SYSTEM.connect("CmgCluster.h", "CmgSteering.h")
SYSTEM.connect("SatelliteDynamics.w_BI_B", "CmgSteering.w_BI_B")
SYSTEM.connect("CmgSteering.delta_dot_cmd", "CmgCluster.delta_dot_cmd")

#: the star tracker's boresight: at the zenith when the pitch is 60°, halfway through the
#: maneuver (−z_B turned 60° about y_B towards +x_B)
STAR_TRACKER_BORESIGHT = (math.sin(60 * DEG), 0.0, -math.cos(60 * DEG))


def sensed(system: System) -> None:
    """The loop as flown (:func:`.closed_loop.close_the_loop`): the controller on the
    estimate relative to the orbit frame, the steering's w × h on the estimated rate."""
    close_the_loop(
        system,
        controller="PitchManeuverController",
        mount=mounting(STAR_TRACKER_BORESIGHT),
        frame="BO",
        rate_inputs=("CmgSteering.w_BI_B",),
    )


#: the recorded columns the planned attitude is made of
PLAN_SIGNALS = (
    "PitchManeuverController.pitch_ref",
    *(f"OrbitEnvironment.q_OI[{i}]" for i in range(1, 5)),
)


@per_results  # a run's metrics and requirements read it: computed once per results
def planned_attitude(columns) -> np.ndarray:
    """q_RI (..., N, 4) of the planned attitude R: the planned pitch about the orbit's y
    axis, roll and yaw zero (q_RI = q_OI ⊗ q_RO); ``columns[name]``: the recorded
    :data:`PLAN_SIGNALS` (a run's results, or a campaign's arrays)."""
    half = np.asarray(columns[PLAN_SIGNALS[0]]) / 2
    zero = np.zeros_like(half)
    q_RO = np.stack((np.cos(half), zero, np.sin(half), zero), axis=-1)
    q_OI = np.stack([columns[name] for name in PLAN_SIGNALS[1:]], axis=-1)
    return quaternion_product(q_OI, q_RO)


@per_results
def planned_error(results):
    """The performance error of the body from the planned attitude (3-axis), computed once
    per results."""
    return performance_error(
        results.vector("SatelliteDynamics.q_BI"), planned_attitude(results), results.time
    )


@per_results
def attitude_error(results) -> np.ndarray:
    """The angle (rad) of the body from the planned attitude (3-axis), per sample."""
    return np.linalg.norm(planned_error(results).values[0], axis=1)


def _over_imaging(name: str, index: str, bound: float, **window) -> Pointing:
    """A pointing requirement about the pitch axis over the imaging phase, from the plan."""
    return Pointing(
        name,
        PointingRequirement(
            index,
            bound,
            POINTING_LEVEL,
            "ensemble",
            axis=(0.0, 1.0, 0.0),
            confidence=POINTING_CONFIDENCE,
            **window,
        ),
        reference=planned_attitude,
        reference_signals=PLAN_SIGNALS,
        start=PROFILE.times[2],
        stop=PROFILE.times[3],
    )


#: the imaging-rate band as a contract states it ([Ecss 2008], docs/pointing.md): over the
#: imaging phase, the pitch error from the plan (a scan at exactly the scan rate) drifts by
#: at most the band's half-width in a second from one 1 s mean to the next (the mean scan
#: rate over a second within ±0.02 °/s of −0.8 °/s), at every time for 99.73 % of the runs,
#: with 95 % confidence; and the scan's stability within a second: a pitch error drifting at
#: the band's edge, 0.02 °/s, moves from its 1 s mean by half of 0.02° at the window's end
REQUIREMENTS = [
    _over_imaging(
        "imaging_rate_pde", "PDE", SCAN_RATE_TOLERANCE * 1.0, window=1.0, separation=1.0
    ),  # rad/s over Δt_s = 1 s
    _over_imaging("imaging_rpe", "RPE", SCAN_RATE_TOLERANCE * 1.0 / 2, window=1.0),
]


def imaging_rate_error(results) -> tuple[np.ndarray, np.ndarray]:
    """(t, pitch rate − scan rate) over the imaging phase (t3, t4]."""
    t = results.time
    imaging = (t > PROFILE.times[2]) & (t <= PROFILE.times[3])
    rate = results["SatelliteDynamics.euler_rate_BO[2]"][imaging]
    return t[imaging], rate - PROFILE.scan_rate


def sensed_figure(results, out_dir):
    """The attitude's departure from the plan, the imaging rate against its band (truth)
    and the attitude knowledge error (estimate against the truth), in arcseconds."""
    t_imaging, rate_error = imaging_rate_error(results)
    tolerance = SCAN_RATE_TOLERANCE / DEG
    return panels(
        out_dir / "pointing_and_knowledge.png",
        "Attitude from the plan, imaging rate (performance) and attitude knowledge",
        [
            magnitude_row(
                results.time, "from the planned attitude", attitude_error(results), "angle [{unit}]"
            ),
            magnitude_row(
                t_imaging,
                "pitch rate − scan rate (imaging)",
                rate_error,
                "rate error [{unit}/s]",
                limit=(SCAN_RATE_TOLERANCE, f"required within ±{tolerance:g} °/s"),
            ),
            *knowledge_rows(results),
        ],
    )


def imaging_error(results):
    """The performance error of the body from the planned attitude about the pitch axis,
    the scan's (the requirements' axis)."""
    return planned_error(results).about((0.0, 1.0, 0.0))


IMAGING = PROFILE.times[2], PROFILE.times[3]

VARIANTS = {
    "flexible": flexible.variant(imaging_error, *IMAGING, "from the plan"),
    "literal_spin": Variant(
        "rotor spin as printed in the paper's A_s0 (momentum bias along +y)",
        parameters={"CmgCluster.spin_ref": PAPER_SPINS, "CmgSteering.spin_ref": PAPER_SPINS},
    ),
    "sensed": Variant(
        "star tracker, gyro and MEKF in the loop, disturbance torques on",
        system=sensed,
        metrics=[
            m.max_abs(
                attitude_error,
                start=PROFILE.times[2],
                stop=PROFILE.times[3],
                unit="rad",
                name="attitude_error_imaging_max",
                display_unit="arcsec",
                description="max angle of the body from the planned attitude over the "
                "imaging phase (performance, 3-axis)",
            ),
            *KNOWLEDGE_METRICS,
        ],
        figures=[sensed_figure],
    ),
}


def _during(function, phase: int, what: str):
    """``function`` of a column's values over a phase of the maneuver (1 … 5, phase p ending
    at t_p), or no value when the run did not get through it."""
    end = PROFILE.times[phase - 1]

    def compute(values, results):
        if results.time[-1] < end - 1e-9:
            raise NotEvaluable(
                f"the run ends at {results.time[-1]:g} s, before the end of the {what} "
                f"(phase {phase}) at {end:.4g} s"
            )
        return function(values[results["PitchManeuverController.phase"] == phase])

    return compute


def _imaging_rate(function):
    during = _during(function, 4, "imaging phase")
    return lambda results: during(results["SatelliteDynamics.euler_rate_BO[2]"], results)


def _feedforward(phase: int):
    during = _during(np.mean, phase, f"phase {phase}")
    return lambda results: during(results.vector("PitchManeuverController.tau_cmd")[:, 1], results)


def _pitch_at_T(results):
    t = results.time
    if t[-1] < PROFILE.duration:
        raise NotEvaluable(f"the run ends at {t[-1]:g} s, before T = {PROFILE.duration:g} s")
    return np.interp(PROFILE.duration, t, results["SatelliteDynamics.euler_BO[2]"])


def _max_gimbal_accel(results):
    delta_dot = results.vector("CmgCluster.delta_dot")
    return np.abs(np.diff(delta_dot, axis=0)).max() / (results.time[1] - results.time[0])


#: the headline numbers (SI), beside the paper's
METRICS = [
    Metric(
        "imaging_pitch_rate_mean",
        _imaging_rate(np.mean),
        "rad/s",
        "deg/s",
        "mean pitch rate relative to O over the imaging phase (t3, t4]",
        # the imaging rate −0.8 ± 0.02 °/s ([Zhao 2016])
        require=within(
            PROFILE.scan_rate - SCAN_RATE_TOLERANCE, PROFILE.scan_rate + SCAN_RATE_TOLERANCE
        ),
        paper=PAPER["imaging_pitch_rate_mean"],
    ),
    Metric(
        "imaging_pitch_rate_span",
        _imaging_rate(np.ptp),
        "rad/s",
        "deg/s",
        "max − min pitch rate over the imaging phase",
    ),
    Metric(
        "pitch_at_T",
        _pitch_at_T,
        "rad",
        "deg",
        "pitch at the end of the maneuver time T = 100 s (target 0)",
    ),
    m.final_value(
        "SatelliteDynamics.euler_BO[2]",
        name="pitch_final",
        display_unit="deg",
        description="pitch at the end of the run",
    ),
    m.settling_time(
        "SatelliteDynamics.w_BO_B[2]",
        SETTLED_RATE,
        after=PROFILE.times[3],
        description="from then on |body pitch rate| < 0.01 °/s",
        paper=PAPER["settling_time"],
    ),
    m.max_abs(
        "CmgCluster.delta_dot",
        name="max_gimbal_rate",
        description="max |gimbal rate|",
        paper=PAPER["max_gimbal_rate"],
    ),
    Metric(
        "max_gimbal_accel",
        _max_gimbal_accel,
        "rad/s2",
        "rad/s2",
        "max |gimbal acceleration| (rate change over a step)",
        paper=PAPER["max_gimbal_accel"],
    ),
    Metric(
        "feedforward_torque_phase1",
        _feedforward(1),
        "N.m",
        "N.m",
        "commanded pitch torque in phase 1 (I θ̈m)",
        paper=PAPER["feedforward_torque_phase1"],
    ),
    Metric(
        "feedforward_torque_phase3",
        _feedforward(3),
        "N.m",
        "N.m",
        "commanded pitch torque in phase 3 (−I θ̈m)",
        paper=PAPER["feedforward_torque_phase3"],
    ),
    m.max_abs(
        lambda results: delivered_torque(results),
        name="max_abs_output_torque",
        unit="N.m",
        description="max |torque delivered by the cluster| (−ḣ − ω × h), any axis",
        paper=PAPER["max_abs_output_torque"],
    ),
    m.max_abs(
        lambda results: delivered_torque(results),
        stop=PROFILE.times[3],
        name="max_abs_output_torque_phases_1_4",
        unit="N.m",
        description="the same over phases 1–4 (feedforward only)",
    ),
    m.singularity_measure(),
    Metric(
        "required_momentum_peak",
        lambda results: np.linalg.norm(required_momentum(results)[1]),
        "N.m.s",
        "N.m.s",
        "largest cluster momentum the planned maneuver needs",
    ),
    Metric(
        "momentum_capacity_there",
        lambda results: momentum_capacity(required_momentum(results)[1]),
        "N.m.s",
        "N.m.s",
        "the cluster's largest momentum in that direction",
    ),
    m.max_abs(
        lambda results: roll_yaw_error(results),
        name="max_roll_yaw_error",
        unit="rad",
        display_unit="deg",
        description="max tilt of the pitch axis from the orbit's y axis",
    ),
    m.momentum_drift(
        description="max |H_I(t) − H_I(0)| / |H_I(0)|: 0 on the isotropic hub (a conservation "
        "check); with an anisotropic inertia (a campaign's), the gravity-gradient torque's effect"
    ),
    *flexible.stability_metrics(
        lambda results: imaging_error(results), *IMAGING, "the pitch from the plan"
    ),
]


def diagnose(results, metrics) -> list[str]:
    """Why the maneuver was not flown as planned, in words (empty: it was)."""
    t = results.time
    commands = results.vector("CmgSteering.delta_dot_cmd")
    over = np.abs(commands).max(axis=1) > RATE_LIMIT
    if not over.any():
        return []
    t_need, h_need = required_momentum(results)
    direction = h_need / np.linalg.norm(h_need)
    return [
        f"the CMG cluster could not deliver the commanded torque: gimbal rate commands "
        f"exceeded the {RATE_LIMIT} rad/s limit at {over.sum()} communication points between "
        f"t = {t[over][0]:.2f} s and {t[over][-1]:.2f} s (max "
        f"{np.abs(commands).max():.2f} rad/s); the planned maneuver needs a cluster "
        f"momentum of {np.linalg.norm(h_need):.1f} N·m·s (at t = {t_need:.1f} s) where "
        f"the cluster holds at most {momentum_capacity(direction):.1f} N·m·s in that "
        f"direction; min singularity measure Q = {metrics['min_singularity']['value']:.3g}"
    ]


def delivered_torque(results) -> np.ndarray:
    """Torque of the cluster on the body, −ḣ − ω × h, in B (N, 3)."""
    h = results.vector("CmgCluster.h")
    w = results.vector("SatelliteDynamics.w_BI_B")
    return -results.vector("CmgCluster.hdot") - np.cross(w, h)


def roll_yaw_error(results) -> np.ndarray:
    """Angle between the body y axis and the orbit y axis (rad): the non-pitch error."""
    q = results.vector("SatelliteDynamics.q_BO")
    # y_O in B is the second column of C_BO: (2(q1q2+q0q3), q0²−q1²+q2²−q3², 2(q2q3−q0q1))
    cos_angle = q[:, 0] ** 2 - q[:, 1] ** 2 + q[:, 2] ** 2 - q[:, 3] ** 2
    return np.arccos(np.clip(cos_angle, -1.0, 1.0))


@per_results  # three metrics and the diagnosis ask for it
def required_momentum(results) -> tuple[float, np.ndarray]:
    """When and what the cluster momentum must be to fly the planned maneuver (largest |h|).

    Along the planned attitude q_BI = q_OI ⊗ q_BO,plan and rate w_BI = w_BO,plan +
    C_BO w_OI_O, the devices must hold h = C_BI H_I − J w_BI, H_I being the (conserved)
    total momentum.
    """
    t = results.time
    pitch, rate = PROFILE.references(t)
    zero = np.zeros_like(pitch)
    q_BO = (np.cos(pitch / 2), zero, np.sin(pitch / 2), zero)  # pitch about y
    C_BI = dcm(qmul(tuple(results.vector("OrbitEnvironment.q_OI").T), q_BO))
    w_BI = (
        np.column_stack((zero, rate, zero))
        + np.array(rotate(dcm(q_BO), tuple(results.vector("OrbitEnvironment.w_OI_O").T))).T
    )
    needed = (
        np.array(rotate(C_BI, tuple(results.vector("SatelliteDynamics.H_I").T))).T - INERTIA * w_BI
    )
    k = int(np.argmax(np.linalg.norm(needed, axis=1)))
    return float(t[k]), needed[k]


def momentum_capacity(direction, h_rotor: float = H_ROTOR) -> float:
    """Largest cluster momentum along a direction: h Σ √(1 − (g_i·d)²)."""
    d = np.asarray(direction) / np.linalg.norm(direction)
    return float(h_rotor * np.sqrt(1.0 - (GIMBAL_AXES @ d) ** 2).sum())


#: the maneuver's phases as figures name them: (name, start, end), phase p ending at t_p
PHASES = tuple(
    zip(
        ("1 accel.", "2 coast", "3 decel.", "4 imaging", "5 settling"),
        (0.0, *PROFILE.times[:4]),
        (*PROFILE.times[:4], math.inf),
    )
)


def figures(results, out_dir) -> list:
    """The paper's Figs 4–11 from a run, with the gimbal limits, the scan-rate requirement,
    the settling threshold and time, the paper's values and the maneuver's phases drawn."""
    t = results.time
    deg = 180 / math.pi
    pitch = results["SatelliteDynamics.euler_BO[2]"] * deg
    rate = results["SatelliteDynamics.w_BO_B[2]"] * deg  # Euler rates spike at the lock
    reference = np.column_stack(PROFILE.references(t)) * deg
    delta_dot = results.vector("CmgCluster.delta_dot")
    accel = np.diff(delta_dot, axis=0) / (t[1] - t[0])  # as max_gimbal_accel
    t3, t4 = PROFILE.times[2], PROFILE.times[3]
    imaging, settling, start = (t > t3) & (t <= t4), t >= t4, t <= 2.0
    gyros = [f"gimbal {i + 1}" for i in range(6)]
    scan, tolerance = PROFILE.scan_rate * deg, SCAN_RATE_TOLERANCE * deg
    rate_limit = {
        "limit": (RATE_LIMIT, f"limit ±{RATE_LIMIT:g} rad/s"),
        "paper": (
            (-PAPER["max_gimbal_rate"], PAPER["max_gimbal_rate"]),
            f"paper: max {PAPER['max_gimbal_rate']:g} rad/s",
        ),
    }
    accel_limit = ACCEL_LIMIT
    torque = delivered_torque(results)
    paper_torque = PAPER["max_abs_output_torque"]
    settled = next(x for x in METRICS if x.name == "settling_time").evaluate(results).value
    settling_marks = {
        "limit": ((SETTLED_RATE * deg,), f"stable: |ω_y| < {SETTLED_RATE * deg:g} °/s"),
        "paper_at": (PAPER["settling_time"], f"paper: stable from {PAPER['settling_time']:g} s"),
        "log": True,
        **({"at": (settled, f"stable from {settled:g} s")} if settled is not None else {}),
    }
    magnitude = np.abs(rate[settling])
    return [
        panels(
            out_dir / "fig04_pitch.png",
            "Fig. 4 pitch angle (B rel. O)",
            [
                (t, {"achieved": pitch, "planned": reference[:, 0]}, "pitch [°]"),
                (t, {"achieved − planned": pitch - reference[:, 0]}, "error [°]"),
            ],
            phases=PHASES,
        ),
        panels(
            out_dir / "fig05_pitch_rate.png",
            "Fig. 5 pitch rate",
            [
                (
                    t,
                    {"body pitch rate ω_y (B rel. O, in B)": rate, "planned": reference[:, 1]},
                    "pitch rate [°/s]",
                ),
                (t, {"achieved − planned": rate - reference[:, 1]}, "error [°/s]"),
            ],
            phases=PHASES,
        ),
        panels(
            out_dir / "fig06_imaging_and_settling.png",
            "Fig. 6 imaging-phase and settling pitch rate (B rel. O, in B)",
            [
                (
                    t[imaging],
                    {"pitch rate": rate[imaging]},
                    "imaging [°/s]",
                    {
                        "band": (
                            scan - tolerance,
                            scan + tolerance,
                            f"required {scan:g} ± {tolerance:g} °/s",
                        ),
                        "paper": (
                            PAPER["imaging_pitch_rate_mean"] * deg,
                            f"paper: mean {PAPER['imaging_pitch_rate_mean'] * deg:g} °/s",
                        ),
                    },
                ),
                (
                    t[settling],
                    {"|pitch rate|": np.where(magnitude > 0, magnitude, np.nan)},
                    "settling |ω_y| [°/s]",
                    settling_marks,
                ),
            ],
        ),
        lines(
            out_dir / "fig07_gimbal_rates.png",
            "Fig. 7 gimbal rates",
            t,
            dict(zip(gyros, delta_dot.T)),
            "gimbal rate [rad/s]",
            phases=PHASES,
            **rate_limit,
        ),
        panels(
            out_dir / "fig08_initial_gimbal_rates.png",
            "Fig. 8 gimbal rates and accelerations, first 2 s",
            [
                (t[start], dict(zip(gyros, delta_dot[start].T)), "gimbal rate [rad/s]", rate_limit),
                (
                    t[1:][start[1:]],
                    dict(zip(gyros, accel[start[1:]].T)),
                    "gimbal accel. [rad/s²]",
                    {
                        "limit": (accel_limit, f"limit ±{accel_limit:g} rad/s²"),
                        "paper": (
                            (-PAPER["max_gimbal_accel"], PAPER["max_gimbal_accel"]),
                            f"paper: max {PAPER['max_gimbal_accel']:g} rad/s²",
                        ),
                    },
                ),
            ],
        ),
        lines(
            out_dir / "fig09_gimbal_angles.png",
            "Fig. 9 gimbal angles",
            t,
            dict(zip(gyros, results.vector("CmgCluster.delta").T * deg)),
            "gimbal angle [°]",
            phases=PHASES,
        ),
        lines(  # log: near a singularity (literal_spin) Q falls by decades
            out_dir / "fig10_singularity.png",
            "Fig. 10 singularity measure",
            t,
            {"Q": results["CmgCluster.singularity"]},
            "Q = det(A Aᵀ) [-], A = [a₁ … a₆] torque axes",
            phases=PHASES,
            log=True,
        ),
        panels(
            out_dir / "fig11_output_torque.png",
            "Fig. 11 cluster output torque −ḣ − ω × h, in B",
            [
                (
                    t,
                    {f"τ_{axis} (B)": torque[:, i]},
                    f"τ_{axis} [N·m]",
                    {"paper": ((-paper_torque, paper_torque), f"paper: ±{paper_torque:g} N·m")},
                )
                for i, axis in enumerate("xyz")
            ],
            phases=PHASES,
        ),
    ]


#: what a campaign's envelopes of the recorded signals draw: the imaging rate's band over
#: the imaging phase (the Euler pitch rate relative to O, as the metric reads it) and the
#: gimbal rate limit
BOUNDS = [
    SignalBound(
        "SatelliteDynamics.euler_rate_BO[2]",
        PROFILE.scan_rate - SCAN_RATE_TOLERANCE,
        PROFILE.scan_rate + SCAN_RATE_TOLERANCE,
        f"required imaging rate {PROFILE.scan_rate / DEG:g} ± {SCAN_RATE_TOLERANCE / DEG:g} °/s "
        f"({PROFILE.scan_rate:.4g} ± {SCAN_RATE_TOLERANCE:.2g} rad/s)",
        start=PROFILE.times[2],
        stop=PROFILE.times[3],
        requirement="imaging_pitch_rate_mean",
    ),
    SignalBound(
        "CmgCluster.delta_dot",
        -RATE_LIMIT,
        RATE_LIMIT,
        f"gimbal rate limit ±{RATE_LIMIT:g} rad/s",
        limit=True,
        parameter="CmgCluster.rate_limit",
    ),
]


SCENARIO = Scenario(
    "scan_pitch",
    "CMG pitch maneuver 120° → 0° in 100 s with a −0.8 °/s scanning phase",
    SYSTEM,
    metrics=METRICS,
    requirements=REQUIREMENTS,
    variants=VARIANTS,
    figures=figures,
    diagnose=diagnose,
    systems_dir=Path(__file__).resolve().parent.parent / "systems",  # agilesat generate
    bounds=BOUNDS,
    phases=PHASES,
)
