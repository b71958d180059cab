"""Three-axis quaternion PD attitude law with momentum-device feedforward.

Errors of the body frame B relative to the reference frame R (R given by its attitude
q_ref = q_RI and angular velocity w_ref = w_RI_R)::

    q_BR = q_ref* ⊗ q_BI                       (Hamilton, scalar first: q_BI = q_RI ⊗ q_BR)
    q_BR ← −q_BR if its scalar part is negative (the short way round)
    att_error  = φ n = 2 atan2(|q_v|, q0) q_v / |q_v|       (rotation vector, |φ| ≤ π)
    rate_error = w_BI_B − C(q_BR) w_ref                     (= w_BR_B)
    tau_cmd    = −kp ∘ att_error − kd ∘ rate_error + hdot_ff + w_BI_B × h_ff
                 + J (C(q_BR) dw_ref − rate_error × C(q_BR) w_ref) + w_BI_B × J w_BI_B

att_error is the rotation vector (angle times axis) of q_BR, not 2·q_v: the two agree to
second order, and the rotation vector keeps the restoring torque proportional to the true
angle up to 180°.  It is continuous everywhere except at exactly 180°, where the shortest
way flips (no continuous error field exists on the whole rotation group); its magnitude
never exceeds π.  The last term cancels the torque −hdot_ff − w_BI_B × h_ff that a known
momentum device (h_ff relative to the body, in B) exerts on the body (DESIGN.md §2).

Extension (not in DESIGN.md §3): with ``acceleration_feedforward`` on (default off) and the
hub ``inertia`` J given, the last line feeds forward the torque that makes the body follow
R exactly: the hub equation J ẇ = −w × J w + τ (the steering law supplies −w × h of the
actuators) with ẇ the derivative, seen in B, of the reference rate C_BR w_ref, i.e.
d/dt(C_BR w_ref) = C_BR dw_ref − w_BR × C_BR w_ref (dw_ref = d/dt w_ref in R axes, an
optional input).  The PD terms then only correct errors instead of carrying the maneuver.

Default gains: a 150 kg·m² satellite ([Chang 2015]) at ω_n = 0.2 rad/s, ζ = 1/√2 on each axis
(linearised closed loop J θ̈ + kd θ̇ + kp θ = 0): kp = J ω_n² = 6 N·m/rad,
kd = 2 ζ ω_n J = 42.4 N·m·s/rad.  A 0.2 N·m wheel then stays linear up to about 1.9°
of attitude error or 0.27 °/s of rate error, and the settling time 4/(ζ ω_n) ≈ 28 s is
short against the 300 s pitch envelope of the payload sweep.

Modes (DESIGN.md §3.2).  The Integer input ``mode`` (0 to N_MODES − 1: SlewGuidance's
0 SLEW, 1 INERTIAL, 2 NADIR, 3 STARE, or a mode manager's own) selects row ``mode`` of the
gain tables ``kp_modes``, ``kd_modes``, ``ki_modes``; a row still at the tables' start
values (the default gains, no integral) is not given, and that mode runs ``kp``, ``kd``
without integral — so with no table every mode, mode 0 among them, runs ``kp``, ``kd``.
With an integral gain the law gains an integral term u_I, and a switch a transfer term
u_T::

    tau_cmd = (the law above) − u_I − u_T
    u̇_I = ki ∘ att_error,  |u_I| ≤ integral_limit          u̇_T = −u_T / transfer_time

u_I integrates over each step with att_error at its start (the inputs held) and is
clamped to ``integral_limit`` per axis (anti-windup: it never holds more torque than the
limit, so it comes off it as soon as the error changes sign).  Bumpless switching: when
``mode`` changes, the command's jump Δ = PD_new − PD_old (PD = −kp ∘ att_error −
kd ∘ rate_error at the switch) is taken up by the transfer term, u_T ← u_T + Δ, so that
tau_cmd is continuous, and u_T then decays with ``transfer_time`` (short against the new
mode's loop: the torque the old gains gave a transient is not held open loop); the
integrator keeps u_I where the new mode integrates (the disturbance it has learnt) and
hands it to u_T on an axis where the new mode does not (no bias held forever).  The mode,
u_I and u_T change at communication points: an output evaluated again at the same time (a
Gauss-Seidel host) gives the same command.

``step`` and ``output`` are kernels (components/runtime/jit.py) on the value array and a
state array of the gains per mode, the inertia, u_I and the mode of the last step (``S``).
"""

from __future__ import annotations

import math

import numpy as np

from .model import Model, ModelError
from .rotations import IDENTITY_Q, dcm, qmul
from .runtime.flat import state_table
from .runtime.jit import floats, jitable, output_kernel, step_kernel
from .variables import input_, output, parameter
from .vectors import rotate

DESIGN_INERTIA = 150.0  # kg·m² ([Chang 2015] satellite, each axis)
DESIGN_BANDWIDTH = 0.2  # rad/s
DESIGN_DAMPING = 1.0 / math.sqrt(2.0)
KP = DESIGN_INERTIA * DESIGN_BANDWIDTH**2
KD = 2.0 * DESIGN_DAMPING * DESIGN_BANDWIDTH * DESIGN_INERTIA
_ATTITUDE = ("q_BI", "q_ref")
_RATE = ("q_BI", "w_BI_B", "q_ref", "w_ref")
_ALL = _RATE + ("h_ff", "hdot_ff", "dw_ref", "mode")
N_MODES = 8
INTEGRAL_LIMIT = 0.1  # N·m: half the default (Chang 2015) wheels' 0.2 N·m


class AttitudeController(Model):
    """Quaternion PD law tracking a reference frame, with device-momentum feedforward."""

    VARIABLES = (
        parameter(
            "kp", KP, "N.m/rad", "attitude gain per body axis (per rad of att_error)", shape=(3,)
        ),
        parameter(
            "kd", KD, "N.m.s/rad", "rate gain per body axis (per rad/s of rate_error)", shape=(3,)
        ),
        parameter(
            "kp_modes",
            [[KP] * 3] * N_MODES,
            "N.m/rad",
            "attitude gains of modes 0 to 7 (rows; a row at the start values: kp)",
            shape=(N_MODES, 3),
        ),
        parameter(
            "kd_modes",
            [[KD] * 3] * N_MODES,
            "N.m.s/rad",
            "rate gains of modes 0 to 7 (rows; a row at the start values: kd)",
            shape=(N_MODES, 3),
        ),
        parameter(
            "ki_modes",
            0.0,
            "N.m/rad/s",
            "integral gains of modes 0 to 7 (rows; zero: no integral action)",
            shape=(N_MODES, 3),
        ),
        parameter(
            "integral_limit",
            (INTEGRAL_LIMIT,) * 3,
            "N.m",
            "largest integral torque |u_I| per axis (anti-windup)",
            shape=(3,),
        ),
        parameter(
            "transfer_time",
            1.0,
            "s",
            "time constant of the decay of the transfer term that keeps the command "
            "continuous across a change of mode",
        ),
        parameter(
            "inertia",
            np.zeros((3, 3)),
            "kg.m2",
            "hub inertia J for the acceleration feedforward, in B",
            shape=(3, 3),
        ),
        parameter(
            "acceleration_feedforward",
            False,
            "1",
            "true: feed forward "
            "J d/dt(C_BR w_ref) + w_BI_B x J w_BI_B with inertia (which must then be "
            "non-zero)",
            type="Boolean",
        ),
        input_("q_BI", "1", "attitude of B relative to I", IDENTITY_Q, shape=(4,)),
        input_(
            "w_BI_B",
            "rad/s",
            "angular velocity of B relative to I, in B",
            shape=(3,),
            display_unit="deg/s",
        ),
        input_(
            "q_ref",
            "1",
            "attitude of the reference frame R relative to I (identity: inertial hold)",
            IDENTITY_Q,
            shape=(4,),
            optional="identity: hold the inertial attitude (R = I)",
        ),
        input_(
            "w_ref",
            "rad/s",
            "angular velocity of R relative to I, in R axes",
            shape=(3,),
            optional="zero: the reference frame does not rotate",
            display_unit="deg/s",
        ),
        input_(
            "h_ff",
            "N.m.s",
            "momentum of a known disturbing device relative to the body, in B (compensated)",
            shape=(3,),
            optional="zero: no device momentum to compensate",
        ),
        input_(
            "hdot_ff",
            "N.m",
            "time derivative of h_ff as seen in B",
            shape=(3,),
            optional="zero: no device torque to compensate",
        ),
        input_(
            "dw_ref",
            "rad/s2",
            "time derivative of w_ref, in R axes (for the acceleration feedforward)",
            shape=(3,),
            display_unit="deg/s2",
            optional="zero: no acceleration feedforward (constant reference rate)",
        ),
        input_(
            "mode",
            "1",
            "control mode: the row of the gain tables (0 to 7)",
            type="Integer",
            optional="0: mode 0",
        ),
        output("tau_cmd", "N.m", "torque wanted on the body, in B", shape=(3,), depends=_ALL),
        output(
            "att_error",
            "rad",
            "rotation vector of B relative to R (angle <= pi), in B",
            shape=(3,),
            depends=_ATTITUDE,
            display_unit="deg",
        ),
        output(
            "rate_error",
            "rad/s",
            "angular velocity of B relative to R, in B",
            shape=(3,),
            depends=_RATE,
            display_unit="deg/s",
        ),
    )

    def initialize(self, t0):
        p = self.p
        J = p.inertia
        if not np.all(np.isfinite(J)) or not np.allclose(J, J.T, rtol=1e-9, atol=0.0):
            raise ModelError(f"inertia must be a finite symmetric matrix, got {J.tolist()}")
        if p.acceleration_feedforward and not J.any():
            raise ModelError(
                "acceleration_feedforward is on but inertia is zero: set the hub inertia it needs"
            )
        for name in ("kp", "kd", "kp_modes", "kd_modes", "ki_modes"):
            if not np.all(np.isfinite(getattr(p, name))):
                raise ModelError(f"{name} must be finite, got {getattr(p, name).tolist()}")
        if not (np.all(p.integral_limit >= 0.0) and p.transfer_time > 0.0):
            raise ModelError(
                f"integral_limit must be >= 0 and transfer_time > 0, got "
                f"{p.integral_limit.tolist()} and {p.transfer_time}"
            )
        self.state = S.zeros()
        for m, row in enumerate(self.gains()):
            self.state[S.gains + 9 * m : S.gains + 9 * m + 9] = row
        self.state[S.inertia : S.inertia + 9] = J.reshape(-1)
        self.state[S.feedforward] = p.acceleration_feedforward
        self.state[S.limit : S.limit + 3] = p.integral_limit
        self.state[S.transfer_time] = p.transfer_time
        self.state[S.mode] = -1.0  # no step yet: the first mode is taken without a switch
        self.t = t0

    def gains(self) -> np.ndarray:
        """(kp, kd, ki) of each mode (rows of 9): the table's row where it is given (not at
        the tables' start values), else kp, kd and no integral."""
        p, start = self.p, {v.name: v.start_array() for v in self.VARIABLES}
        rows = np.hstack((p.kp_modes, p.kd_modes, p.ki_modes))
        given = np.hstack([getattr(p, n).reshape(-1) != start[n] for n in _TABLES])
        given = given.reshape(3, N_MODES, 3).transpose(1, 0, 2).reshape(N_MODES, 9).any(axis=1)
        fallback = np.concatenate((p.kp, p.kd, np.zeros(3)))
        return np.where(given[:, None], rows, fallback)

    def step(self, t, dt):
        self._check(controller_step(self.values, self.state, self.t, dt))
        self.t = t + dt

    def output(self):
        self._check(controller_output(self.values, self.state, self.t))

    def _check(self, status: int) -> None:
        if status == NOT_UNIT:
            raise ModelError(
                f"t={self.t:.6g} s: q_BI and q_ref must be unit quaternions, got "
                f"{self.u.q_BI.tolist()} and {self.u.q_ref.tolist()}"
            )
        if status == BAD_MODE:
            raise ModelError(
                f"t={self.t:.6g} s: mode {self.u.mode} has no row in the gain tables "
                f"(0 to {N_MODES - 1})"
            )


# -- kernels (components/runtime/jit.py) ----------------------------------------------
_TABLES = ("kp_modes", "kd_modes", "ki_modes")
P, U, Y = AttitudeController.names()
#: the state array: (kp, kd, ki) of each mode, the hub inertia (row-major), 1 with the
#: acceleration feedforward on, the integral limit and transfer time, u_I, u_T and the mode
#: of the last step (−1 before the first)
S = state_table(
    "AttitudeController state", gains=9 * N_MODES, inertia=9, feedforward=1, limit=3,
    transfer_time=1, integral=3, transfer=3, mode=1,
)  # fmt: skip
#: the kernels' statuses: q_BI or q_ref is not a unit quaternion; the mode has no gains
#: (nothing written)
NOT_UNIT, BAD_MODE = 1, 2


@jitable
def errors(v) -> tuple:
    """(unit, att_error, rate_error, C_BR, 1/|q_BR|², C_BR w_ref unscaled) (module
    docstring); ``unit`` false: q_BI or q_ref is not a unit quaternion."""
    r0, r1, r2, r3 = v[U.q_ref], v[U.q_ref + 1], v[U.q_ref + 2], v[U.q_ref + 3]
    q0, q1, q2, q3 = qmul((r0, -r1, -r2, -r3), v[U.q_BI : U.q_BI + 4])
    norm2 = q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3
    if q0 < 0.0:
        q0, q1, q2, q3 = -q0, -q1, -q2, -q3
    n = math.sqrt(q1 * q1 + q2 * q2 + q3 * q3)
    f = 2.0 * math.atan2(n, q0) / n if n > 0.0 else 0.0  # angle / |q_v|, scale-free
    k = 1.0 / norm2 if norm2 > 0.0 else 0.0
    C_BR = dcm((q0, q1, q2, q3))
    wrx, wry, wrz = rotate(C_BR, v[U.w_ref : U.w_ref + 3])
    wx, wy, wz = v[U.w_BI_B], v[U.w_BI_B + 1], v[U.w_BI_B + 2]
    return (
        0.25 < norm2 < 4.0,
        (f * q1, f * q2, f * q3),
        (wx - k * wrx, wy - k * wry, wz - k * wrz),
        C_BR,
        k,
        (wrx, wry, wrz),
    )


@jitable
def offsets(v, s, e, r) -> tuple:
    """(u_I, u_T) at this communication point: the state's, across a change of mode the
    transfer term taking up the command's jump (module docstring)."""
    m, last = int(v[U.mode]), int(s[S.mode])
    new, old = S.gains + 9 * m, S.gains + 9 * last
    u_I = [s[S.integral], s[S.integral + 1], s[S.integral + 2]]
    u_T = [s[S.transfer], s[S.transfer + 1], s[S.transfer + 2]]
    if last >= 0 and m != last:
        for i in range(3):
            pd_new = -s[new + i] * e[i] - s[new + 3 + i] * r[i]
            pd_old = -s[old + i] * e[i] - s[old + 3 + i] * r[i]
            u_T[i] += pd_new - pd_old
            if s[new + 6 + i] == 0.0:  # no integral action in the new mode
                u_I[i], u_T[i] = 0.0, u_T[i] + u_I[i]
    return (u_I[0], u_I[1], u_I[2]), (u_T[0], u_T[1], u_T[2])


@step_kernel(AttitudeController)
def controller_step(values, state, t, dt):
    """u_I, u_T and the mode from t to t + dt: u̇_I = ki ∘ att_error (att_error at t),
    clamped; u_T decays as e^(−dt/transfer_time)."""
    v, s = floats(values), floats(state)
    unit, e, r, _, _, _ = errors(v)
    m = v[U.mode]
    if not unit:
        return NOT_UNIT
    if not (0.0 <= m < N_MODES and m == int(m)):
        return BAD_MODE
    u_I, u_T = offsets(v, s, e, r)
    ki = S.gains + 9 * int(m) + 6
    decay = math.exp(-dt / s[S.transfer_time])
    for i in range(3):
        x = u_I[i] + s[ki + i] * e[i] * dt
        state[S.integral + i] = min(s[S.limit + i], max(-s[S.limit + i], x))
        state[S.transfer + i] = u_T[i] * decay
    state[S.mode] = m
    return 0


@output_kernel(AttitudeController)
def controller_output(values, state, t):
    """tau_cmd, att_error and rate_error (module docstring); 0, NOT_UNIT or BAD_MODE."""
    v, s = floats(values), floats(state)
    unit, (ex, ey, ez), (rx, ry, rz), C_BR, k, (wrx, wry, wrz) = errors(v)
    m = v[U.mode]
    if not unit:
        return NOT_UNIT
    if not (0.0 <= m < N_MODES and m == int(m)):
        return BAD_MODE
    g = S.gains + 9 * int(m)
    u_I, u_T = offsets(v, s, (ex, ey, ez), (rx, ry, rz))
    ux, uy, uz = u_I[0] + u_T[0], u_I[1] + u_T[1], u_I[2] + u_T[2]
    wx, wy, wz = v[U.w_BI_B], v[U.w_BI_B + 1], v[U.w_BI_B + 2]
    hx, hy, hz = v[U.h_ff], v[U.h_ff + 1], v[U.h_ff + 2]
    dx, dy, dz = v[U.hdot_ff], v[U.hdot_ff + 1], v[U.hdot_ff + 2]
    tx = -s[g] * ex - s[g + 3] * rx - ux + dx + (wy * hz - wz * hy)
    ty = -s[g + 1] * ey - s[g + 4] * ry - uy + dy + (wz * hx - wx * hz)
    tz = -s[g + 2] * ez - s[g + 5] * rz - uz + dz + (wx * hy - wy * hx)
    if s[S.feedforward] != 0.0:
        J = s[S.inertia : S.inertia + 9]
        ax, ay, az = rotate(C_BR, v[U.dw_ref : U.dw_ref + 3])
        wrx, wry, wrz = k * wrx, k * wry, k * wrz  # C_BR w_ref
        ux = k * ax - (ry * wrz - rz * wry)  # d/dt (C_BR w_ref), seen in B
        uy = k * ay - (rz * wrx - rx * wrz)
        uz = k * az - (rx * wry - ry * wrx)
        jx = J[0] * wx + J[1] * wy + J[2] * wz  # J w
        jy = J[3] * wx + J[4] * wy + J[5] * wz
        jz = J[6] * wx + J[7] * wy + J[8] * wz
        tx += J[0] * ux + J[1] * uy + J[2] * uz + (wy * jz - wz * jy)
        ty += J[3] * ux + J[4] * uy + J[5] * uz + (wz * jx - wx * jz)
        tz += J[6] * ux + J[7] * uy + J[8] * uz + (wx * jy - wy * jx)
    values[Y.tau_cmd], values[Y.tau_cmd + 1], values[Y.tau_cmd + 2] = tx, ty, tz
    values[Y.att_error], values[Y.att_error + 1], values[Y.att_error + 2] = ex, ey, ez
    values[Y.rate_error], values[Y.rate_error + 1], values[Y.rate_error + 2] = rx, ry, rz
    return 0
