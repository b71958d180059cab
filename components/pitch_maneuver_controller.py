"""Five-phase pitch maneuver with a constant-rate scanning phase ([Zhao 2016] §2–3.1).

Pitch θ of B relative to O goes from θ0 to θf in T with the imaging phase (t3, t4] at the
scan rate θ̇0.  With the cruise and imaging fractions f2 = (t2 − t1)/T, f4 = (t4 − t3)/T
and the paper's condition (t5 − t4) + (t3 − t2) = t1, t5 = T::

    t1 = T (1 − f2 − f4) / 2,   t2 = t1 + f2 T,   t4 = t3 + f4 T
    θ̈m = (θ_T − θ̇0 (t4 − t3)) / (t1 t2),   θ̇m = θ̈m t1,   θ_T = θf − θ0   (eqs 6–9)
    t3 = t2 + (θ̇m − θ̇0) / θ̈m,   t5 = t4 + θ̇0 / θ̈m

Errata: the paper's printed closed forms θ̈m = −100θ_T/(3T²) − 20θ̇0/T and θ̇m = −10θ_T/(3T)
− 2θ̇0 have the wrong leading sign (they give +0.56 °/s², not −0.24), and eq. (11)'s first
line is garbled and gives the same torque sign in phase 3, which must decelerate.

Control law (eq. 11, corrected): pitch torque I θ̈m in phase 1, −I θ̈m in phase 3, zero in
phases 2 and 4, and c1 θe + c2 θ̇e with θe = θf − θ, θ̇e = −θ̇ from t4 on (phase 5, held
after t5).  Phases are half-open on the left, [t_{k−1}, t_k), so a controller sampled at
t_k already applies the next phase.  Roll and yaw are held at zero by PD laws of our own.

Attitude errors are singularity-free (pitch passes through 90°): q_BO is split into a
twist about body y, θ = 2 atan2(q2, q0), and the remaining swing q_BR = twist* ⊗ q_BO,
whose x and z components give the roll and yaw errors e = 2 (q_BR1, q_BR3) (q0 ≥ 0
chosen, so that θ is in (−180°, 180°]).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .model import Model, ModelError
from .runtime.flat import hypot, state_table
from .runtime.jit import floats, jitable, output_kernel
from .variables import input_, output, parameter

DEG = math.pi / 180.0
PHASE_TIME_TOLERANCE = 1e-9  # s


@dataclass(frozen=True)
class PitchProfile:
    """The planned pitch trajectory of eqs 6–9."""

    theta0: float
    theta_f: float
    duration: float
    scan_rate: float
    cruise_fraction: float = 0.2
    imaging_fraction: float = 0.6
    # set by __post_init__: phase times t1..t5, θ̈m, θ̇m
    times: tuple[float, float, float, float, float] = field(init=False, repr=False, compare=False)
    accel: float = field(init=False, repr=False, compare=False)
    rate_max: float = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        T, f2, f4 = self.duration, self.cruise_fraction, self.imaging_fraction
        if not (T > 0 and f2 >= 0 and f4 >= 0 and f2 + f4 < 1):
            raise ModelError(
                f"need duration > 0 and cruise + imaging fractions < 1, got T={T}, f2={f2}, f4={f4}"
            )
        t1 = T * (1 - f2 - f4) / 2
        t2 = t1 + f2 * T
        accel = (self.theta_f - self.theta0 - self.scan_rate * f4 * T) / (t1 * t2)
        rate_max = accel * t1
        t3 = t2 + (rate_max - self.scan_rate) / accel
        t4 = t3 + f4 * T
        t5 = t4 + self.scan_rate / accel
        if not (t1 <= t2 <= t3 <= t4 <= t5 and math.isclose(t5, T, rel_tol=1e-9)):
            raise ModelError(
                "the scan rate is not reachable with these phase fractions: "
                f"phase times {[t1, t2, t3, t4, t5]}"
            )
        object.__setattr__(self, "times", (t1, t2, t3, t4, t5))
        object.__setattr__(self, "accel", accel)  # θ̈m
        object.__setattr__(self, "rate_max", rate_max)  # θ̇m

    def phase(self, t: float) -> int:
        """Phase 1..5 at time t (:func:`phase_at`)."""
        return phase_at(self.times, t)

    def reference(self, t: float) -> tuple[float, float]:
        """Planned (θ, θ̇) at time t (:func:`reference_at`)."""
        return reference_at(
            self.theta0, self.theta_f, self.times, self.accel, self.rate_max, self.scan_rate, t
        )

    def references(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Planned (θ, θ̇) at each of the times ``t``: :meth:`reference` of each, the same
        operations on arrays."""
        t = np.asarray(t, dtype=float)
        theta, pitch, rate = (
            np.full(t.shape, self.theta0),
            np.full(t.shape, self.theta_f),
            np.zeros(t.shape),
        )
        ended = np.zeros(t.shape, bool)  # a piece already gave (θ, θ̇)
        for start, end, rate0, acc in pieces(self.times, self.accel, self.rate_max, self.scan_rate):
            s = np.minimum(np.maximum(t - start, 0.0), end - start)
            theta = theta + (rate0 * s + 0.5 * acc * s * s)
            here = ~ended & (t < end)
            pitch[here], rate[here] = theta[here], (rate0 + acc * s)[here]
            ended |= here
        return pitch, rate


@jitable
def phase_at(times, t: float) -> int:
    """Phase 1..5 at time t of the phase times t1..t5 (half-open on the left; 5 from t4 on).

    A time within 1e-9 s of a phase time counts as at it: t1 = T (1 − f2 − f4)/2 is
    10.000000000000004 s in floating point, and the communication point at 10 s must
    already switch to phase 2.
    """
    for k in range(4):
        if t < times[k] - PHASE_TIME_TOLERANCE:
            return k + 1
    return 5


@jitable
def pieces(times, accel, rate_max, scan_rate):
    """The maneuver's five pieces, (start, end, rate at the start, acceleration) each."""
    t1, t2, t3, t4, t5 = times
    a, r, r0 = accel, rate_max, scan_rate
    return (
        (0.0, t1, 0.0, a),
        (t1, t2, r, 0.0),
        (t2, t3, r, -a),
        (t3, t4, r0, 0.0),
        (t4, t5, r0, -a),
    )


@jitable
def reference_at(theta0, theta_f, times, accel, rate_max, scan_rate, t) -> tuple[float, float]:
    """Planned (θ, θ̇) at time t: piecewise parabolic, θf after t5."""
    theta = theta0
    for start, end, rate, acc in pieces(times, accel, rate_max, scan_rate):
        s = min(max(t - start, 0.0), end - start)
        theta += rate * s + 0.5 * acc * s * s
        if t < end:
            return theta, rate + acc * s
    return theta_f, 0.0


class PitchManeuverController(Model):
    """Five-phase pitch maneuver law (feedforward + terminal PD) with roll/yaw hold."""

    DEFAULT_STOP = 150.0  #: the maneuver (100 s) and its settling

    _ATTITUDE = ("q_BO", "w_BO_B")
    VARIABLES = (
        parameter("inertia", 956.0, "kg.m2", "pitch-axis inertia I used for the feedforward"),
        parameter("pitch0", 120 * DEG, "rad", "initial pitch theta0", display_unit="deg"),
        parameter("pitch_final", 0.0, "rad", "final pitch theta_f", display_unit="deg"),
        parameter("duration", 100.0, "s", "maneuver time T"),
        parameter(
            "scan_rate", -0.8 * DEG, "rad/s", "imaging-phase pitch rate", display_unit="deg/s"
        ),
        parameter("cruise_fraction", 0.2, "1", "(t2 - t1) / T"),
        parameter("imaging_fraction", 0.6, "1", "(t4 - t3) / T"),
        parameter("kp", 0.9, "N.m/rad", "phase-5 pitch gain c1"),
        parameter("kd", 578.0, "N.m.s/rad", "phase-5 pitch-rate gain c2"),
        parameter("kp_roll", 86.0, "N.m/rad", "roll hold gain"),
        parameter("kd_roll", 574.0, "N.m.s/rad", "roll-rate hold gain"),
        parameter("kp_yaw", 86.0, "N.m/rad", "yaw hold gain"),
        parameter("kd_yaw", 574.0, "N.m.s/rad", "yaw-rate hold gain"),
        input_("q_BO", "1", "attitude of B relative to O", (1.0, 0.0, 0.0, 0.0), shape=(4,)),
        input_("w_BO_B", "rad/s", "angular velocity of B relative to O, in B", shape=(3,)),
        output("tau_cmd", "N.m", "torque wanted on the body, in B", shape=(3,), depends=_ATTITUDE),
        output("phase", "1", "maneuver phase 1..5", type="Integer"),
        output("pitch_ref", "rad", "planned pitch", display_unit="deg"),
        output("pitch_rate_ref", "rad/s", "planned pitch rate", display_unit="deg/s"),
    )
    #: step() only advances t (the outputs are functions of t and the inputs)
    STATELESS = True

    def initialize(self, t0):
        p = self.p
        profile = PitchProfile(
            p.pitch0, p.pitch_final, p.duration, p.scan_rate, p.cruise_fraction, p.imaging_fraction
        )
        self.state = state = S.zeros()
        state[S.times : S.times + 5] = profile.times
        state[S.accel : S.theta_f + 1] = (
            profile.accel, profile.rate_max, profile.scan_rate, profile.theta0, profile.theta_f
        )  # fmt: skip
        state[S.inertia : S.kd_yaw + 1] = (
            p.inertia, p.kp, p.kd, p.kp_roll, p.kd_roll, p.kp_yaw, p.kd_yaw
        )  # fmt: skip
        self.t = t0

    def step(self, t, dt):
        self.t = t + dt

    def output(self):
        pitch_output(self.values, self.state, self.t)


# -- kernel (components/runtime/jit.py) -----------------------------------------------
P, U, Y = PitchManeuverController.names()
#: the state array: the profile (t1..t5, θ̈m, θ̇m, θ̇0, θ0, θf), the inertia and the gains
S = state_table(
    "PitchManeuverController state", times=5, accel=1, rate_max=1, scan_rate=1, theta0=1,
    theta_f=1, inertia=1, kp=1, kd=1, kp_roll=1, kd_roll=1, kp_yaw=1, kd_yaw=1,
)  # fmt: skip


@output_kernel(PitchManeuverController)
def pitch_output(values, state, t):
    """τ_cmd (eq. 11 corrected, roll/yaw hold), phase and the planned pitch and rate at
    time t (module docstring)."""
    s = floats(state)
    q0, q1, q2, q3 = floats(values[U.q_BO : U.q_BO + 4])
    if not q0 >= 0:
        q0, q1, q2, q3 = -q0, -q1, -q2, -q3
    n = hypot(q0, q2)  # CPython's math.hypot, bit for bit (components/runtime/flat.py)
    wx, wy, wz = floats(values[U.w_BO_B : U.w_BO_B + 3])
    c, sn = q0 / n, q2 / n
    pitch = 2.0 * math.atan2(q2, q0)
    roll_error, yaw_error = 2.0 * (c * q1 - sn * q3), 2.0 * (c * q3 + sn * q1)
    times = s[S.times : S.times + 5]
    phase = phase_at(times, t)
    if phase == 5:
        torque_y = s[S.kp] * (s[S.theta_f] - pitch) + s[S.kd] * (0.0 - wy)
    else:
        sign = 1.0 if phase == 1 else -1.0 if phase == 3 else 0.0
        torque_y = sign * s[S.inertia] * s[S.accel]
    values[Y.tau_cmd] = -s[S.kp_roll] * roll_error - s[S.kd_roll] * wx
    values[Y.tau_cmd + 1] = torque_y
    values[Y.tau_cmd + 2] = -s[S.kp_yaw] * yaw_error - s[S.kd_yaw] * wz
    values[Y.phase] = phase
    values[Y.pitch_ref], values[Y.pitch_rate_ref] = reference_at(
        s[S.theta0], s[S.theta_f], times, s[S.accel], s[S.rate_max], s[S.scan_rate], t
    )
    return 0
