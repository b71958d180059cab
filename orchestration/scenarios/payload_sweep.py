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
the roll amplitude allows: a 10 s ramp every stroke).
"""

from __future__ import annotations

import math

import numpy as np

from ...components.orbit_environment import WGS84_A
from ..output import plots
from ..output.summary import relative_drift
from . import Scenario, inertial_momentum, summarize
from .constants import PAYLOAD_SWEEP_ACCURACY, PAYLOAD_SWEEP_STABILITY

DEG = math.pi / 180
ALTITUDE, INCLINATION = 500e3, 97.40 * DEG
ORBIT_RATE = math.sqrt(3.986004418e14 / (WGS84_A + ALTITUDE) ** 3)
INERTIA = 150.0 * np.eye(3)  # kg·m², payloads included
ACCURACY, STABILITY = PAYLOAD_SWEEP_ACCURACY, PAYLOAD_SWEEP_STABILITY

CONNECTIONS = (
    ("OrbitEnvironment.r_I", "SatelliteDynamics.r_I"),
    ("OrbitEnvironment.q_OI", "SatelliteDynamics.q_OI"),
    ("OrbitEnvironment.w_OI_O", "SatelliteDynamics.w_OI_O"),
    ("OrbitEnvironment.q_OI", "AttitudeController.q_ref"),
    ("OrbitEnvironment.w_OI_O", "AttitudeController.w_ref"),
    *(
        (f"SweepPlanner.{name}", f"PayloadGimbals.{name}")
        for name in (
            "roll_cmd",
            "pitch_cmd",
            "roll_rate_cmd",
            "pitch_rate_cmd",
            "roll_accel_cmd",
            "pitch_accel_cmd",
        )
    ),
    ("PayloadGimbals.h", "SatelliteDynamics.h_payload"),
    ("PayloadGimbals.hdot", "SatelliteDynamics.hdot_payload"),
    ("PayloadGimbals.h", "AttitudeController.h_ff"),
    ("PayloadGimbals.hdot", "AttitudeController.hdot_ff"),
    ("SatelliteDynamics.q_BI", "AttitudeController.q_BI"),
    ("SatelliteDynamics.w_BI_B", "AttitudeController.w_BI_B"),
    ("AttitudeController.tau_cmd", "Flywheel.tau_cmd"),
    ("SatelliteDynamics.w_BI_B", "Flywheel.w_BI_B"),
    ("Flywheel.h", "SatelliteDynamics.h_wheel"),
    ("Flywheel.hdot", "SatelliteDynamics.hdot_wheel"),
)

PARAMETERS = {
    "OrbitEnvironment.semi_major_axis": WGS84_A + ALTITUDE,
    "OrbitEnvironment.inclination": INCLINATION,
    "SatelliteDynamics.inertia": INERTIA,
    "SatelliteDynamics.attitude0": [0.0, 0.0, 0.0],
    "SatelliteDynamics.rate0": [0.0, 0.0, 0.0],
    "PayloadGimbals.J_payload": [45.5, 35.8, 36.7],
    "PayloadGimbals.bandwidth": 0.0,
    "PayloadGimbals.accel_inputs": True,
    "SweepPlanner.roll_amplitude": 15 * DEG,
    "SweepPlanner.roll_rate": 6 * DEG,
    "SweepPlanner.pitch_amplitude": 45 * DEG,
    "SweepPlanner.pitch_rate": 0.6 * DEG,
    "SweepPlanner.turnaround_time": 1.0,
    "SweepPlanner.symmetric": True,
    "Flywheel.torque_limit": 0.2,
}

_AT_REST_INERTIAL = {"SatelliteDynamics.rate0": [0.0, ORBIT_RATE, 0.0]}  # w_BI = 0 at t = 0
VARIANTS = {
    "no_control": (
        "wheel motors off: the payloads' momentum goes into the satellite",
        {"Flywheel.torque_limit": 0.0},
    ),
    "inertial": (
        "starts at rest in inertial space (the controller takes up the orbit rate)",
        _AT_REST_INERTIAL,
    ),
    "no_control_inertial": (
        "at rest in inertial space, wheel motors off",
        {**_AT_REST_INERTIAL, "Flywheel.torque_limit": 0.0},
    ),
    "turnaround_10s": (
        "the slowest reversal the roll sweep allows (10 s)",
        {"SweepPlanner.turnaround_time": 10.0},
    ),
}

PAPER = {
    "payload_torque_yaw_max": 0.2,  # "< 0.2 N·m" (§3)
    "pointing_accuracy": ACCURACY,  # with the 0.2 N·m wheel (Fig. 8)
    "pointing_stability": STABILITY,
    "yaw_period_slow": 300.0,
    "yaw_period_ripple": 10.0,
}


#: the paper's pointing accuracy and stability ([Chang 2015])
REQUIREMENTS = {"pointing_accuracy": {"max": ACCURACY}, "pointing_stability": {"max": STABILITY}}


def metrics(results) -> dict:
    h = results.vector("PayloadGimbals.h")
    hdot = results.vector("PayloadGimbals.hdot")
    error = results.vector("AttitudeController.att_error")
    rate_error = results.vector("AttitudeController.rate_error")
    euler = results.vector("SatelliteDynamics.euler_BO")
    euler_rate = results.vector("SatelliteDynamics.euler_rate_BO")
    motor = results.vector("Flywheel.motor_torque")
    wheel_h = results.vector("Flywheel.h")
    saturated = results["Flywheel.saturated"]
    slow, ripple = yaw_periods(results)
    m = {  # name: (value, unit, display unit, description)
        "payload_momentum_xy_max": (
            np.abs(h[:, :2]).max(),
            "N.m.s",
            "N.m.s",
            "max |h_x|, |h_y| of the payload pair (cancel)",
        ),
        "payload_torque_xy_max": (
            np.abs(hdot[:, :2]).max(),
            "N.m",
            "N.m",
            "max |ḣ_x|, |ḣ_y| of the payload pair (cancel)",
        ),
        "payload_momentum_yaw_max": (
            np.abs(h[:, 2]).max(),
            "N.m.s",
            "N.m.s",
            "max |h_z| of the payload pair",
        ),
        "payload_torque_yaw_max": (
            np.abs(hdot[:, 2]).max(),
            "N.m",
            "N.m",
            "max |ḣ_z| of the payload pair (the yaw torque)",
        ),
        "yaw_period_slow": (slow, "s", "s", "period of h_z's slow envelope (demodulated)"),
        "yaw_period_ripple": (ripple, "s", "s", "period of h_z's ripple (the roll stroke)"),
        "pointing_accuracy": (
            np.abs(error).max(),
            "rad",
            "deg",
            "max |attitude error| about any body axis (reference: the orbit frame)",
        ),
        "pointing_stability": (
            np.abs(rate_error).max(),
            "rad/s",
            "deg/s",
            "max |rate error| about any body axis",
        ),
        "euler_max": (
            np.abs(euler).max(),
            "rad",
            "deg",
            "max |roll|, |pitch|, |yaw| relative to the orbit frame",
        ),
        "euler_rate_max": (
            np.abs(euler_rate).max(),
            "rad/s",
            "deg/s",
            "max |Euler angle rate| relative to the orbit frame",
        ),
        "wheel_torque_max": (np.abs(motor).max(), "N.m", "N.m", "max |motor torque|"),
        "wheel_momentum_max": (
            np.abs(wheel_h).max(),
            "N.m.s",
            "N.m.s",
            "max |wheel momentum| along any body axis",
        ),
        "wheel_saturated_fraction": (
            saturated.mean(),
            "1",
            "1",
            "fraction of the run with a wheel limit active",
        ),
        "momentum_drift": (
            relative_drift(
                inertial_momentum(results, INERTIA, "Flywheel.h", "PayloadGimbals.h"),
                scale=max(
                    np.linalg.norm(results.vector(part), axis=1).max()
                    for part in ("Flywheel.h", "PayloadGimbals.h")
                ),
            ),
            "1",
            "1",
            "max change of C_BIᵀ(J w + h_wheel + h_payload), recomputed from the recorded "
            "outputs, relative to |H(0)| or the largest device momentum if larger",
        ),
    }
    summary = summarize(m, PAPER, REQUIREMENTS)
    return {"metrics": summary, "diagnostics": diagnose(results, summary)}


def controlled(results) -> bool:
    """Did the wheels act at all (no: motors off, e.g. the no_control variants)?"""
    return bool(np.abs(results.vector("Flywheel.motor_torque")).max() > 0.0)


def diagnose(results, summary) -> list[str]:
    if not controlled(results):
        return []  # nothing is asked of an uncontrolled satellite
    problems = []
    accuracy, stability = (summary[k]["value"] for k in ("pointing_accuracy", "pointing_stability"))
    if accuracy > ACCURACY or stability > STABILITY:
        text = (
            f"pointing accuracy {accuracy / DEG:.3g}° and stability "
            f"{stability / DEG:.3g} °/s against the required {ACCURACY / DEG}° and "
            f"{STABILITY / DEG} °/s"
        )
        if summary["wheel_saturated_fraction"]["value"] > 0:
            text += (
                f": the wheels saturate at "
                f"{summary['wheel_torque_max']['value']:.2g} N·m "
                f"({100 * summary['wheel_saturated_fraction']['value']:.1f} % of the time); "
                f"the payloads' yaw torque peaks at "
                f"{summary['payload_torque_yaw_max']['value']:.2f} N·m (run "
                "`agilesat size-flywheel` for the wheel that meets the requirement)"
            )
        problems.append(text)
    return problems


def yaw_periods(results) -> tuple[float, float]:
    """(envelope, ripple) periods of the payloads' yaw momentum h_z.

    h_z ≈ 2 (Jz − Jx) φ̇ sin θ cos θ cos φ + 2 Jy θ̇ sin φ: a ripple whose sign follows the
    roll stroke (φ̇ = ±r) modulated by the slow pitch sweep (sin 2θ).  Its spectrum shows
    sidebands, not the two periods, so h_z is demodulated with the stroke direction: the
    ripple period is that of the stroke, the envelope period the strongest Fourier period of
    h_z · sign(φ̇) (zero-padded).
    """
    t = results.time
    carrier = np.sign(results["SweepPlanner.roll_rate_cmd[1]"])
    flips = t[1:][np.diff(carrier) != 0]
    ripple = 2 * float(np.median(np.diff(flips))) if len(flips) > 2 else float("nan")
    envelope = results["PayloadGimbals.h[3]"] * carrier
    x = envelope - envelope.mean()
    n = 32 * len(x)
    spectrum = np.abs(np.fft.rfft(x, n))
    frequency = np.fft.rfftfreq(n, t[1] - t[0])
    slow = (frequency > 1 / (t[-1] - t[0])) & (frequency < 1 / 60)
    if not slow.any():  # a run shorter than a minute
        return float("nan"), ripple
    return 1 / float(frequency[slow][np.argmax(spectrum[slow])]), ripple


def figures(results, out_dir) -> list:
    """The paper's Figs 4–8 from a run, body-frame (B) quantities named as such, the pointing
    requirement and the paper's yaw-torque bound drawn."""
    t = results.time
    deg = 180 / math.pi
    roll, pitch = (
        results.vector("PayloadGimbals.roll") * deg,
        results.vector("PayloadGimbals.pitch") * deg,
    )
    h, hdot = results.vector("PayloadGimbals.h"), results.vector("PayloadGimbals.hdot")
    zoom = t <= min(t[-1], 30.0)
    axes = ("x (B)", "y (B)", "z (B)")
    angles = ("roll", "pitch", "yaw")
    label = "Fig. 8 compensated" if controlled(results) else "Fig. 7 uncompensated"
    yaw_torque = PAPER["payload_torque_yaw_max"]
    return [
        plots.panels(
            out_dir / "fig04_payload_angles.png",
            "Fig. 4 payload angles",
            [
                (t, {"payload 1": pitch[:, 0], "payload 2": pitch[:, 1]}, "pitch [°]"),
                (
                    t[zoom],
                    {"payload 1": roll[zoom, 0], "payload 2": roll[zoom, 1]},
                    "roll [°] (first 30 s)",
                ),
            ],
        ),
        plots.panels(
            out_dir / "fig05_payload_momentum.png",
            "Fig. 5 payload pair momentum h, in B",
            [
                (t, dict(zip(axes, h.T)), "h [N·m·s]"),
                (t[zoom], {"z (B)": h[zoom, 2]}, "h_z, first 30 s [N·m·s]"),
            ],
        ),
        plots.panels(
            out_dir / "fig06_payload_torque.png",
            "Fig. 6 payload pair torque ḣ, in B",
            [
                (
                    t,
                    dict(zip(axes, hdot.T)),
                    "ḣ [N·m]",
                    {"paper": ((-yaw_torque, yaw_torque), f"paper: |ḣ_z| < {yaw_torque:g} N·m")},
                ),
                (t[zoom], {"z (B)": hdot[zoom, 2]}, "ḣ_z, first 30 s [N·m]"),
            ],
        ),
        plots.panels(
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
        plots.panels(
            out_dir / "fig08_pointing.png",
            "Pointing error (controller, in B) against the requirement",
            [
                (
                    t,
                    dict(zip(axes, results.vector("AttitudeController.att_error").T * deg)),
                    "attitude error [°]",
                    {"limit": (ACCURACY * deg, f"required ±{ACCURACY * deg:g}°")},
                ),
                (
                    t,
                    dict(zip(axes, results.vector("AttitudeController.rate_error").T * deg)),
                    "rate error [°/s]",
                    {"limit": (STABILITY * deg, f"required ±{STABILITY * deg:g} °/s")},
                ),
            ],
        ),
        plots.panels(
            out_dir / "fig09_wheel.png",
            "Reaction wheels (axes in B)",
            [
                (
                    t,
                    dict(zip(axes, results.vector("Flywheel.motor_torque")[:, :3].T)),
                    "motor torque [N·m]",
                ),
                (t, dict(zip(axes, results.vector("Flywheel.h").T)), "wheel momentum [N·m·s]"),
            ],
        ),
    ]


SCENARIO = Scenario(
    name="payload_sweep",
    title="Two symmetric swinging payloads compensated by a reaction wheel",
    components=(
        "OrbitEnvironment",
        "SweepPlanner",
        "PayloadGimbals",
        "Flywheel",
        "SatelliteDynamics",
        "AttitudeController",
    ),
    connections=CONNECTIONS,
    parameters=PARAMETERS,
    stop=600.0,
    step=0.05,
    metrics=metrics,
    figures=figures,
    variants=VARIANTS,
)
