"""``payload_sweep``: two symmetric swinging payloads, reaction-wheel compensation ([Chang 2015],
DESIGN.md §4.2).

Satellite 150 kg·m² on each axis (payloads included), holding the orbit frame: an
AttitudeController (quaternion PD with feedforward of the payloads' momentum) commands a
three-wheel Flywheel (0.2 N·m, the paper's).  The SweepPlanner drives both payloads' roll
(±15°, 6 °/s) and pitch (±45°, 0.6 °/s) symmetrically, reversing in ``turnaround_time``
(1 s by default).  The paper gives no orbit: 500 km sun-synchronous (i = 97.40°), our choice.

Variants: ``no_control`` (wheel motors off), ``inertial`` (the satellite starts at rest in
inertial space instead of at rest relative to the orbit frame; the controller then first
takes up the orbit rate), ``no_control_inertial``, ``turnaround_10s`` (the slowest reversal
the roll amplitude allows: a 10 s ramp every stroke), ``sensed`` (the loop as flown: star
tracker, gyro and MEKF, the controller and the wheel drive on the estimate, disturbance
torques on; :mod:`.closed_loop`; the star tracker looks at the zenith, −z_B).

The pointing metrics are those of the truth, the body against the orbit frame (in the
sensed variant the controller's own errors are those of the estimate).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from agilesat.components.orbit_environment import WGS84_A
from agilesat.components.rotations import dcm
from agilesat.components.vectors import rotate_back
from agilesat.orchestration.mission import (
    Metric,
    Pointing,
    Scenario,
    SignalBound,
    System,
    Variant,
    at_most,
    panels,
)
from agilesat.orchestration.mission import metrics as m
from agilesat.orchestration.output.results import per_results
from agilesat.orchestration.pointing import PointingRequirement, performance_error
from agilesat.orchestration.scenarios.closed_loop import (
    KNOWLEDGE_METRICS,
    UNITS,
    close_the_loop,
    knowledge_rows,
    magnitude_row,
    mounting,
)
from agilesat.orchestration.scenarios.constants import (
    PAYLOAD_SWEEP_ACCURACY,
    PAYLOAD_SWEEP_STABILITY,
    POINTING_CONFIDENCE,
    POINTING_LEVEL,
)
from agilesat.orchestration.scenarios.spectrum import strongest_bin

DEG = math.pi / 180
ALTITUDE, INCLINATION = 500e3, 97.40 * DEG
ORBIT_RATE = math.sqrt(3.986004418e14 / (WGS84_A + ALTITUDE) ** 3)
INERTIA = 150.0 * np.eye(3)  # kg·m², payloads included
ACCURACY, STABILITY = PAYLOAD_SWEEP_ACCURACY, PAYLOAD_SWEEP_STABILITY
#: the sweep of both payloads ([Chang 2015])
SWEEP = {
    "roll_amplitude": 15 * DEG,
    "roll_rate": 6 * DEG,
    "pitch_amplitude": 45 * DEG,
    "pitch_rate": 0.6 * DEG,
    "turnaround_time": 1.0,
    "symmetric": True,
}
PAPER = {
    "payload_torque_yaw_max": 0.2,  # "< 0.2 N·m" (§3)
    "pointing_accuracy": ACCURACY,  # with the 0.2 N·m wheel (Fig. 8)
    "pointing_stability": STABILITY,
    "yaw_period_slow": 300.0,
    "yaw_period_ripple": 10.0,
}

SYSTEM = System("payload_sweep", step=0.05, stop=600.0)
SYSTEM.add("OrbitEnvironment", semi_major_axis=WGS84_A + ALTITUDE, inclination=INCLINATION)
SYSTEM.add("SweepPlanner", **SWEEP)
SYSTEM.add("PayloadGimbals", J_payload=[45.5, 35.8, 36.7], bandwidth=0.0, accel_inputs=True)
SYSTEM.add("Flywheel", torque_limit=0.2)
SYSTEM.add("SatelliteDynamics", inertia=INERTIA, attitude0=[0.0, 0.0, 0.0], rate0=[0.0, 0.0, 0.0])
SYSTEM.add("AttitudeController")
SYSTEM.connect("OrbitEnvironment.r_I", "SatelliteDynamics.r_I")
SYSTEM.connect("OrbitEnvironment.q_OI", "SatelliteDynamics.q_OI")
SYSTEM.connect("OrbitEnvironment.w_OI_O", "SatelliteDynamics.w_OI_O")
SYSTEM.connect("OrbitEnvironment.q_OI", "AttitudeController.q_ref")
SYSTEM.connect("OrbitEnvironment.w_OI_O", "AttitudeController.w_ref")
for command in ("roll", "pitch", "roll_rate", "pitch_rate", "roll_accel", "pitch_accel"):
    SYSTEM.connect(f"SweepPlanner.{command}_cmd", f"PayloadGimbals.{command}_cmd")
SYSTEM.connect("PayloadGimbals.h", "SatelliteDynamics.h_payload")
SYSTEM.connect("PayloadGimbals.hdot", "SatelliteDynamics.hdot_payload")
SYSTEM.connect("PayloadGimbals.h", "AttitudeController.h_ff")
SYSTEM.connect("PayloadGimbals.hdot", "AttitudeController.hdot_ff")
SYSTEM.connect("SatelliteDynamics.q_BI", "AttitudeController.q_BI")
SYSTEM.connect("SatelliteDynamics.w_BI_B", "AttitudeController.w_BI_B")
SYSTEM.connect("AttitudeController.tau_cmd", "Flywheel.tau_cmd")
SYSTEM.connect("SatelliteDynamics.w_BI_B", "Flywheel.w_BI_B")
SYSTEM.connect("Flywheel.h", "SatelliteDynamics.h_wheel")
SYSTEM.connect("Flywheel.hdot", "SatelliteDynamics.hdot_wheel")

#: the star tracker's boresight: the zenith (the satellite holds the orbit frame, +z_B nadir)
STAR_TRACKER_BORESIGHT = (0.0, 0.0, -1.0)


def sensed(system: System) -> None:
    """The loop as flown (:func:`.closed_loop.close_the_loop`): the controller and the
    wheel drive's w × h on the estimate."""
    close_the_loop(
        system,
        controller="AttitudeController",
        mount=mounting(STAR_TRACKER_BORESIGHT),
        rate_inputs=("Flywheel.w_BI_B",),
    )


@per_results  # a metric and the sensed figure
def attitude_error(results) -> np.ndarray:
    """Rotation vector (rad) of the body from the orbit frame, in B (N, 3): the truth's
    error, as the controller computes its own from what it reads."""
    q_BI, q_OI = results.vector("SatelliteDynamics.q_BI"), results.vector("OrbitEnvironment.q_OI")
    return performance_error(q_BI, q_OI, results.time).values[0]


def sensed_figure(results, out_dir):
    """Pointing accuracy and stability (truth against the orbit frame, the worst body axis)
    and the attitude knowledge error (estimate against the truth), in arcseconds."""
    t = results.time
    return panels(
        out_dir / "pointing_and_knowledge.png",
        "Pointing (performance, worst axis) and attitude knowledge (estimate − truth)",
        [
            magnitude_row(
                t,
                "attitude error",
                np.abs(attitude_error(results)).max(axis=1),
                "accuracy [{unit}]",
                limit=(ACCURACY, f"required ≤ {ACCURACY / DEG:g}°"),
            ),
            magnitude_row(
                t,
                "rate error",
                np.abs(results.vector("SatelliteDynamics.w_BO_B")).max(axis=1),
                "stability [{unit}/s]",
                limit=(STABILITY, f"required ≤ {STABILITY / DEG:g} °/s"),
            ),
            *knowledge_rows(results),
        ],
    )


_AT_REST_INERTIAL = {"SatelliteDynamics.rate0": [0.0, ORBIT_RATE, 0.0]}  # w_BI = 0 at t = 0
#: nothing is asked of an uncontrolled satellite
_UNCONTROLLED = {
    name: "the wheel motors are off: the pointing requirement is for control"
    for name in ("pointing_accuracy", "pointing_stability", "pointing_ape", "stability_pde")
}
VARIANTS = {
    "no_control": Variant(
        "wheel motors off: the payloads' momentum goes into the satellite",
        parameters={"Flywheel.torque_limit": 0.0},
        not_judged=_UNCONTROLLED,
    ),
    "inertial": Variant(
        "starts at rest in inertial space (the controller takes up the orbit rate)",
        parameters=_AT_REST_INERTIAL,
    ),
    "no_control_inertial": Variant(
        "at rest in inertial space, wheel motors off",
        parameters={**_AT_REST_INERTIAL, "Flywheel.torque_limit": 0.0},
        not_judged=_UNCONTROLLED,
    ),
    "turnaround_10s": Variant(
        "the slowest reversal the roll sweep allows (10 s)",
        parameters={"SweepPlanner.turnaround_time": 10.0},
    ),
    "sensed": Variant(
        "star tracker, gyro and MEKF in the loop, disturbance torques on",
        system=sensed,
        metrics=KNOWLEDGE_METRICS,
        figures=[sensed_figure],
    ),
}


def inertial_momentum(results, inertia, *devices: str) -> np.ndarray:
    """C_BIᵀ (J w + Σ h) per row (N, 3), from the recorded SatelliteDynamics attitude and
    rate and the named devices' momentum columns."""
    w = results.vector("SatelliteDynamics.w_BI_B")
    body = w @ np.asarray(inertia).T + sum(results.vector(d) for d in devices)
    C = dcm(tuple(results.vector("SatelliteDynamics.q_BI").T))
    return np.array(rotate_back(C, tuple(body.T))).T


def _yaw_period(k: int):
    return lambda results: yaw_periods(results)[k]


#: the headline numbers (SI), beside the paper's; its pointing accuracy and stability as
#: requirements ([Chang 2015])
METRICS = [
    m.max_abs(
        lambda results: results.vector("PayloadGimbals.h")[:, :2],
        name="payload_momentum_xy_max",
        unit="N.m.s",
        description="max |h_x|, |h_y| of the payload pair (cancel)",
    ),
    m.max_abs(
        lambda results: results.vector("PayloadGimbals.hdot")[:, :2],
        name="payload_torque_xy_max",
        unit="N.m",
        description="max |ḣ_x|, |ḣ_y| of the payload pair (cancel)",
    ),
    m.max_abs(
        "PayloadGimbals.h[3]",
        name="payload_momentum_yaw_max",
        description="max |h_z| of the payload pair",
    ),
    m.max_abs(
        "PayloadGimbals.hdot[3]",
        name="payload_torque_yaw_max",
        description="max |ḣ_z| of the payload pair (the yaw torque)",
        paper=PAPER["payload_torque_yaw_max"],
    ),
    Metric(
        "yaw_period_slow",
        _yaw_period(0),
        "s",
        "s",
        "period of h_z's slow envelope (demodulated)",
        paper=PAPER["yaw_period_slow"],
    ),
    Metric(
        "yaw_period_ripple",
        _yaw_period(1),
        "s",
        "s",
        "period of h_z's ripple (the roll stroke)",
        paper=PAPER["yaw_period_ripple"],
    ),
    m.max_abs(
        attitude_error,
        unit="rad",
        name="pointing_accuracy",
        display_unit="deg",
        description="max |attitude error| about any body axis (reference: the orbit frame)",
        require=at_most(ACCURACY),
        paper=PAPER["pointing_accuracy"],
    ),
    m.max_abs(
        "SatelliteDynamics.w_BO_B",
        name="pointing_stability",
        display_unit="deg/s",
        description="max |rate error| about any body axis (rate relative to the orbit frame)",
        require=at_most(STABILITY),
        paper=PAPER["pointing_stability"],
    ),
    m.max_abs(
        "SatelliteDynamics.euler_BO",
        name="euler_max",
        display_unit="deg",
        description="max |roll|, |pitch|, |yaw| relative to the orbit frame",
    ),
    m.max_abs(
        "SatelliteDynamics.euler_rate_BO",
        name="euler_rate_max",
        display_unit="deg/s",
        description="max |Euler angle rate| relative to the orbit frame",
    ),
    m.max_abs("Flywheel.motor_torque", name="wheel_torque_max", description="max |motor torque|"),
    m.max_abs(
        "Flywheel.h",
        name="wheel_momentum_max",
        description="max |wheel momentum| along any body axis",
    ),
    m.saturation_fraction(
        "Flywheel.saturated",
        name="wheel_saturated_fraction",
        description="fraction of the run with a wheel limit active",
    ),
    m.momentum_drift(
        lambda results: inertial_momentum(results, INERTIA, "Flywheel.h", "PayloadGimbals.h"),
        scale=lambda results: max(
            np.linalg.norm(results.vector(part), axis=1).max()
            for part in ("Flywheel.h", "PayloadGimbals.h")
        ),
        description="max change of C_BIᵀ(J w + h_wheel + h_payload), recomputed from the "
        "recorded outputs, relative to |H(0)| or the largest device momentum if larger",
    ),
]


def controlled(results) -> bool:
    """Did the wheels act at all (no: motors off, e.g. the no_control variants)?"""
    return bool(np.abs(results.vector("Flywheel.motor_torque")).max() > 0.0)


def diagnose(results, metrics) -> list[str]:
    """Why the pointing requirements were missed, where the wheels are the cause."""
    accuracy, stability = (metrics[k]["value"] for k in ("pointing_accuracy", "pointing_stability"))
    if not controlled(results) or (accuracy <= ACCURACY and stability <= STABILITY):
        return []
    if metrics["wheel_saturated_fraction"]["value"] == 0:
        return []
    return [
        f"the wheels saturate at {metrics['wheel_torque_max']['value']:.2g} N·m "
        f"({100 * metrics['wheel_saturated_fraction']['value']:.1f} % of the time); "
        f"the payloads' yaw torque peaks at "
        f"{metrics['payload_torque_yaw_max']['value']:.2f} N·m (run "
        "`agilesat size-flywheel` for the wheel that meets the requirement)"
    ]


@per_results
def yaw_periods(results) -> tuple[float, float]:
    """(envelope, ripple) periods of the payloads' yaw momentum h_z.

    h_z ≈ 2 (Jz − Jx) φ̇ sin θ cos θ cos φ + 2 Jy θ̇ sin φ: a ripple whose sign follows the
    roll stroke (φ̇ = ±r) modulated by the slow pitch sweep (sin 2θ).  Its spectrum shows
    sidebands, not the two periods, so h_z is demodulated with the stroke direction: the
    ripple period is that of the stroke, the envelope period the strongest Fourier period of
    h_z · sign(φ̇) (zero-padded: its strongest slow bin, :func:`.spectrum.strongest_bin`).
    Computed once per results (both metrics read it).
    """
    t = results.time
    carrier = np.sign(results["SweepPlanner.roll_rate_cmd[1]"])
    flips = t[1:][np.diff(carrier) != 0]
    ripple = 2 * float(np.median(np.diff(flips))) if len(flips) > 2 else float("nan")
    envelope = results["PayloadGimbals.h[3]"] * carrier
    x = envelope - envelope.mean()
    n = 32 * len(x)
    frequency = np.fft.rfftfreq(n, t[1] - t[0])
    slow = np.flatnonzero((frequency > 1 / (t[-1] - t[0])) & (frequency < 1 / 60))
    if not len(slow):  # a run shorter than a minute
        return float("nan"), ripple
    return 1 / float(frequency[slow[strongest_bin(x, n, slow)]]), ripple


def roll_reversals(results) -> np.ndarray:
    """The times the payloads' roll stroke reverses: its commanded rate changes sign (the
    start from rest is none)."""
    sign = np.sign(results["SweepPlanner.roll_rate_cmd[1]"])
    moving = np.flatnonzero(sign)
    return results.time[moving[1:][np.diff(sign[moving]) != 0]]


def _per_axis_magnitude(t, values, limit: float, text: str, ylabel: str):
    """A figure row of |value| about each body axis (rad or rad/s) in arcsec on a log axis,
    the requirement ``limit`` drawn; the axis starts at 10⁻⁴ of it."""
    scale, shown = UNITS["arcsec"]
    magnitude = np.abs(values) / scale
    return (
        t,
        {axis: np.where(m > 0, m, np.nan) for axis, m in zip(AXES_B, magnitude.T)},
        ylabel.format(unit=shown),
        {"limit": ((limit / scale,), text), "bottom": 1e-4 * limit / scale, "log": True},
    )


AXES_B = ("x (B)", "y (B)", "z (B)")


def _wheel_limit(results, name: str, unit: str):
    """The limit mark (±value, label) of a Flywheel parameter as the run set it: {} when
    the run did not say (results read back from a file)."""
    value = results.meta.get("parameters", {}).get(f"Flywheel.{name}")
    if value is None:
        return {}
    if value == 0:
        return {"limit": ((0.0,), f"{name.replace('_', ' ')} 0: motors off")}
    return {"limit": (value, f"{name.replace('_', ' ')} ±{value:g} {unit}")}


def figures(results, out_dir) -> list:
    """The paper's Figs 4–8 from a run, body-frame (B) quantities named as such, the pointing
    requirement, the paper's yaw-torque bound, the wheels' limits and the roll reversals
    (on the first 30 s) drawn."""
    t = results.time
    deg = 180 / math.pi
    roll, pitch = (
        results.vector("PayloadGimbals.roll") * deg,
        results.vector("PayloadGimbals.pitch") * deg,
    )
    h, hdot = results.vector("PayloadGimbals.h"), results.vector("PayloadGimbals.hdot")
    zoom = t <= min(t[-1], 30.0)
    flips = roll_reversals(results)
    reversals = {"events": (flips[flips <= t[zoom][-1]], "roll reversal")}
    axes = AXES_B
    angles = ("roll", "pitch", "yaw")
    label = "Fig. 8 compensated" if controlled(results) else "Fig. 7 uncompensated"
    yaw_torque = PAPER["payload_torque_yaw_max"]
    return [
        panels(
            out_dir / "fig04_payload_angles.png",
            "Fig. 4 payload angles",
            [
                (t, {"payload 1": pitch[:, 0], "payload 2": pitch[:, 1]}, "pitch [°]"),
                (
                    t[zoom],
                    {"payload 1": roll[zoom, 0], "payload 2": roll[zoom, 1]},
                    "roll [°] (first 30 s)",
                    reversals,
                ),
            ],
        ),
        panels(
            out_dir / "fig05_payload_momentum.png",
            "Fig. 5 payload pair momentum h, in B",
            [
                (t, dict(zip(axes, h.T)), "h [N·m·s]"),
                (t[zoom], {"z (B)": h[zoom, 2]}, "h_z, first 30 s [N·m·s]", reversals),
            ],
        ),
        panels(
            out_dir / "fig06_payload_torque.png",
            "Fig. 6 payload pair torque ḣ, in B",
            [
                (
                    t,
                    dict(zip(axes, hdot.T)),
                    "ḣ [N·m]",
                    {"paper": ((-yaw_torque, yaw_torque), f"paper: |ḣ_z| < {yaw_torque:g} N·m")},
                ),
                (t[zoom], {"z (B)": hdot[zoom, 2]}, "ḣ_z, first 30 s [N·m]", reversals),
            ],
        ),
        panels(
            out_dir / "fig07_08_attitude.png",
            f"{label}: attitude of B relative to the orbit frame O",
            [
                (
                    t,
                    dict(zip(angles, results.vector("SatelliteDynamics.euler_BO").T * deg)),
                    "Euler angle [°]",
                ),
                (
                    t,
                    dict(zip(angles, results.vector("SatelliteDynamics.euler_rate_BO").T * deg)),
                    "Euler rate [°/s]",
                ),
            ],
        ),
        panels(
            out_dir / "fig08_pointing.png",
            "Pointing error (body relative to the orbit frame, about each axis of B)",
            [
                _per_axis_magnitude(
                    t,
                    attitude_error(results),
                    ACCURACY,
                    f"required ≤ {ACCURACY * deg:g}° ({ACCURACY / UNITS['arcsec'][0]:.4g} arcsec)",
                    "|attitude error| [{unit}]",
                ),
                _per_axis_magnitude(
                    t,
                    results.vector("SatelliteDynamics.w_BO_B"),
                    STABILITY,
                    f"required ≤ {STABILITY * deg:g} °/s "
                    f"({STABILITY / UNITS['arcsec'][0]:.4g} arcsec/s)",
                    "|rate error| [{unit}/s]",
                ),
            ],
        ),
        panels(
            out_dir / "fig09_wheel.png",
            "Reaction wheels (axes in B)",
            [
                (
                    t,
                    dict(zip(axes, results.vector("Flywheel.motor_torque")[:, :3].T)),
                    "motor torque [N·m]",
                    _wheel_limit(results, "torque_limit", "N·m"),
                ),
                (
                    t,
                    dict(zip(axes, results.vector("Flywheel.h").T)),
                    "wheel momentum [N·m·s]",
                    _wheel_limit(results, "momentum_limit", "N·m·s"),
                ),
            ],
        ),
    ]


#: the paper's requirements as a contract states them ([Ecss 2008], docs/pointing.md):
#: accuracy, the 3-axis angle of the body from the orbit frame (it bounds the error about
#: each axis); stability, the drift of the mean pointing from one second to the next, the
#: mean rate error over a second times a second; both at every time for 99.73 % of the
#: runs, with 95 % confidence
REQUIREMENTS = [
    Pointing(
        "pointing_ape",
        PointingRequirement(
            "APE", ACCURACY, POINTING_LEVEL, "ensemble", confidence=POINTING_CONFIDENCE
        ),
        reference="OrbitEnvironment.q_OI",
    ),
    Pointing(
        "stability_pde",
        PointingRequirement(
            "PDE",
            STABILITY * 1.0,  # rad/s over Δt_s = 1 s
            POINTING_LEVEL,
            "ensemble",
            window=1.0,
            separation=1.0,
            confidence=POINTING_CONFIDENCE,
        ),
        reference="OrbitEnvironment.q_OI",
    ),
]


#: what a campaign's envelopes of the recorded signals draw: the stability requirement on
#: the rate relative to the orbit frame, about every body axis (pointing_stability)
BOUNDS = [
    SignalBound(
        "SatelliteDynamics.w_BO_B",
        -STABILITY,
        STABILITY,
        f"required within ±{STABILITY / DEG:g} °/s (±{STABILITY:.3g} rad/s)",
        requirement="pointing_stability",
    )
]


SCENARIO = Scenario(
    "payload_sweep",
    "Two symmetric swinging payloads compensated by a reaction wheel",
    SYSTEM,
    metrics=METRICS,
    requirements=REQUIREMENTS,
    variants=VARIANTS,
    figures=figures,
    diagnose=diagnose,
    systems_dir=Path(__file__).resolve().parent.parent / "systems",  # agilesat generate
    bounds=BOUNDS,
)
