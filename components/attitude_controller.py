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

Stateless: outputs are a function of the inputs at the communication point.  ``output`` is
one kernel (components/runtime/jit.py) on the value array and a state array of the gains and the
inertia (``S``).
"""

from __future__ import annotations

import math

import numpy as np

from .model import Model, ModelError
from .rotations import IDENTITY_Q, dcm, qmul
from .runtime.flat import state_table
from .runtime.jit import floats, output_kernel
from .variables import input_, output, parameter
from .vectors import rotate

DESIGN_INERTIA = 150.0  # kg·m² ([Chang 2015] satellite, each axis)
DESIGN_BANDWIDTH = 0.2  # rad/s
DESIGN_DAMPING = 1.0 / math.sqrt(2.0)
KP = DESIGN_INERTIA * DESIGN_BANDWIDTH**2
KD = 2.0 * DESIGN_DAMPING * DESIGN_BANDWIDTH * DESIGN_INERTIA
_ATTITUDE = ("q_BI", "q_ref")
_RATE = ("q_BI", "w_BI_B", "q_ref", "w_ref")
_ALL = _RATE + ("h_ff", "hdot_ff", "dw_ref")


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

    #: step() only advances t (the outputs are functions of the inputs)
    STATELESS = True

    def initialize(self, t0):
        J = self.p.inertia
        if not np.all(np.isfinite(J)) or not np.allclose(J, J.T, rtol=1e-9, atol=0.0):
            raise ModelError(f"inertia must be a finite symmetric matrix, got {J.tolist()}")
        if self.p.acceleration_feedforward and not J.any():
            raise ModelError(
                "acceleration_feedforward is on but inertia is zero: set the hub inertia it needs"
            )
        self.state = S.zeros()
        self.state[S.kp : S.kp + 3], self.state[S.kd : S.kd + 3] = self.p.kp, self.p.kd
        self.state[S.inertia : S.inertia + 9] = J.reshape(-1)
        self.state[S.feedforward] = self.p.acceleration_feedforward
        self.t = t0

    def step(self, t, dt):
        self.t = t + dt  # stateless between communication points

    def output(self):
        if controller_output(self.values, self.state, self.t) == NOT_UNIT:
            q_ref = self.u.q_ref.tolist()
            raise ModelError(
                f"t={self.t:.6g} s: q_BI and q_ref must be unit quaternions, got "
                f"{self.u.q_BI.tolist()} and {q_ref}"
            )


# -- kernel (components/runtime/jit.py) -----------------------------------------------
P, U, Y = AttitudeController.names()
#: the state array: the gains, the hub inertia (row-major) and 1 with the acceleration
#: feedforward on
S = state_table("AttitudeController state", kp=3, kd=3, inertia=9, feedforward=1)
#: controller_output's status: q_BI or q_ref is not a unit quaternion (nothing written)
NOT_UNIT = 1


@output_kernel(AttitudeController)
def controller_output(values, state, t):
    """tau_cmd, att_error and rate_error (module docstring); 0, or NOT_UNIT."""
    v, s = floats(values), floats(state)
    r0, r1, r2, r3 = v[U.q_ref], v[U.q_ref + 1], v[U.q_ref + 2], v[U.q_ref + 3]
    q0, q1, q2, q3 = qmul((r0, -r1, -r2, -r3), v[U.q_BI : U.q_BI + 4])
    norm2 = q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3
    if not 0.25 < norm2 < 4.0:
        return NOT_UNIT
    if q0 < 0.0:
        q0, q1, q2, q3 = -q0, -q1, -q2, -q3
    n = math.sqrt(q1 * q1 + q2 * q2 + q3 * q3)
    f = 2.0 * math.atan2(n, q0) / n if n > 0.0 else 0.0  # angle / |q_v|, scale-free
    ex, ey, ez = f * q1, f * q2, f * q3
    k = 1.0 / norm2
    C_BR = dcm((q0, q1, q2, q3))
    wrx, wry, wrz = rotate(C_BR, v[U.w_ref : U.w_ref + 3])
    wx, wy, wz = v[U.w_BI_B], v[U.w_BI_B + 1], v[U.w_BI_B + 2]
    rx, ry, rz = wx - k * wrx, wy - k * wry, wz - k * wrz
    hx, hy, hz = v[U.h_ff], v[U.h_ff + 1], v[U.h_ff + 2]
    dx, dy, dz = v[U.hdot_ff], v[U.hdot_ff + 1], v[U.hdot_ff + 2]
    tx = -s[S.kp] * ex - s[S.kd] * rx + dx + (wy * hz - wz * hy)
    ty = -s[S.kp + 1] * ey - s[S.kd + 1] * ry + dy + (wz * hx - wx * hz)
    tz = -s[S.kp + 2] * ez - s[S.kd + 2] * rz + dz + (wx * hy - wy * hx)
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
