"""Rigid satellite hub carrying momentum-exchange devices ([Zhao 2016] eqs 1–3).

States: the attitude q_BI and the *total* angular momentum H_I (hub + devices, inertial
axes).  With J the hub inertia, h the devices' momentum relative to the body (in B) and
τ the external torque on the body (in B: ``tau_ext``, the environment's, plus
``tau_ctrl``, that of external-torque actuators such as magnetorquers)::

    w_BI_B = J⁻¹ (C_BI H_I − h)                       (eq. 2 solved for w)
    q̇_BI  = ½ q_BI ⊗ (0, w_BI_B)
    Ḣ_I   = C_BIᵀ (τ_ext + τ_gg),   τ_gg = 3 μ/|r|⁵ · r_B × J r_B,   r_B = C_BI r_I

which is the hub equation J ẇ = −w × (J w + h) − ḣ + τ (eq. 3 with all terms kept):
H_I changes only by external torque, so total momentum is conserved exactly whatever the
co-simulation step.  Across a step the inputs the model integrates follow their
derivatives (FMI 2.0 input interpolation, components/model.py): the devices' momentum
h(t_c + s) = h + ḣ s + ½ ḧ s², with ḣ its slope (the derivative a host set for ``h_*``,
else the input ``hdot_*``: :meth:`Model.slope`) and ḧ the derivative set for ``hdot_*``;
τ + τ̇ s and r_I + ṙ s likewise (never set: zero, the input held).  q_OI and w_OI_O
enter only the outputs, at communication points.  Integration: classical RK4 with
sub-steps of at most 0.02 rad of rotation.  The gravity-gradient torque is skipped when
J ∝ 1, where it vanishes identically.

Outputs relative to the orbit frame O (inputs q_OI, w_OI_O): q_BO = q_OI* ⊗ q_BI,
w_BO_B = w_BI_B − C_BO w_OI_O and the 1-2-3 Euler angles of B relative to O on a branch
continuous in time (pitch may pass through ±90°; see rotations.euler123), with their
rates (video-SAR eq. 13).

Output derivatives (``output_derivatives``), at the current time with the inputs as
interpolated: q̇_BI and Ḣ_I from the equations above, ẇ_BI_B = J⁻¹ (−w × C_BI H_I + τ − ḣ),
q̇_BO = ½ q_BO ⊗ (0, w_BO_B), ẇ_BO_B = ẇ_BI_B + w_BO_B × C_BO w_OI_O − C_BO ẇ_OI_O (ẇ_OI_O
the derivative set for w_OI_O), the Euler angles' first and second derivatives
(rotations.euler123_ddot).

``step`` and ``output`` are each one kernel (components/runtime/jit.py: their Python in short
runs, compiled by numba in long ones, bit for bit the same) on the model's value array,
read and written at the offsets of the variable table, and on ``self.state``: q_BI, H_I,
the last q_BO and euler_BO, and the constants ``initialize`` derives (the state table
``S``).  A kernel returns a status code; the methods raise its ModelError.
"""

from __future__ import annotations

import math

import numpy as np

from .model import Model, ModelError
from .orbit_environment import DEFAULT_SEMI_MAJOR_AXIS
from .rotations import (
    IDENTITY_Q,
    dcm,
    dcm_from_euler123,
    euler123,
    euler123_ddot,
    euler123_dot,
    qmul,
    quat_from_dcm,
)
from .runtime.flat import matrix, put, quaternion, state_table, vector
from .runtime.jit import floats, jitable, output_kernel, step_kernel
from .variables import input_, output, parameter
from .vectors import add, quat_dot, quat_norm, rotate, rotate_back

MAX_ROTATION_PER_SUBSTEP = 0.02  # rad
MAX_SUBSTEPS = 10000
#: rad/s, above the orbit-frame rate of any Earth orbit: h/r² is largest at the perigee of an
#: orbit grazing the surface, √2 · √(μ/R³) ≈ 1.75e-3 rad/s for e → 1
MAX_ORBIT_FRAME_RATE = 2e-3
DEVICES = ("cmg", "wheel", "payload")
MOMENTUM_INPUTS = tuple(f"h_{d}" for d in DEVICES)
#: r_I when unconnected: the default orbit's radius (OrbitEnvironment) on the nadir
#: (+z_O) of the identity orbit frame that q_OI defaults to, so that the FMU at its
#: defaults is a satellite at 681 km with the gravity gradient on
DEFAULT_R_I = (0.0, 0.0, -DEFAULT_SEMI_MAJOR_AXIS)


def _device_inputs():
    for device in DEVICES:
        yield input_(
            f"h_{device}",
            "N.m.s",
            f"{device} angular momentum relative to the body, in B",
            shape=(3,),
            optional=f"zero: no {device} momentum",
        )
        yield input_(
            f"hdot_{device}",
            "N.m",
            f"time derivative of h_{device} as seen in B",
            shape=(3,),
            optional=f"zero: constant {device} momentum",
            derivative_of=f"h_{device}",
        )


class SatelliteDynamics(Model):
    """Rigid-body attitude dynamics with internal momentum and gravity-gradient torque."""

    INTERPOLATES_INPUTS = True
    OUTPUT_DERIVATIVES = True

    _BO_DEPENDS = ("q_OI",)
    _RATE_DEPENDS = MOMENTUM_INPUTS + ("q_OI", "w_OI_O")
    VARIABLES = (
        parameter(
            "inertia",
            956.0 * np.eye(3),
            "kg.m2",
            "hub inertia about the centre of mass, in B",
            shape=(3, 3),
        ),
        parameter(
            "attitude0",
            0.0,
            "rad",
            "initial 1-2-3 Euler angles (roll, pitch, yaw) of B relative to O",
            shape=(3,),
            display_unit="deg",
        ),
        parameter(
            "rate0",
            0.0,
            "rad/s",
            "initial angular velocity of B relative to O, in B",
            shape=(3,),
            display_unit="deg/s",
        ),
        parameter(
            "gravity_gradient", True, "1", "apply the gravity-gradient torque", type="Boolean"
        ),
        parameter("mu", 3.986004418e14, "m3/s2", "gravitational parameter of the Earth"),
        *_device_inputs(),
        input_(
            "tau_ext",
            "N.m",
            "other external torque on the body, in B",
            shape=(3,),
            optional="zero: no other external torque",
        ),
        input_(
            "tau_ctrl",
            "N.m",
            "torque of external-torque actuators (magnetorquers, thrusters) on the body, in "
            "B; added to tau_ext",
            shape=(3,),
            optional="zero: no such actuator",
        ),
        input_(
            "r_I",
            "m",
            "satellite position in I (for the gravity gradient); the start "
            "value is the default orbit's radius at nadir of the identity orbit frame",
            DEFAULT_R_I,
            shape=(3,),
            optional="a fixed position, the default orbit's radius at nadir of the "
            "identity orbit frame: connect it for the gravity gradient of a real "
            "orbit",
        ),
        input_(
            "q_OI",
            "1",
            "attitude of the orbit frame O relative to I",
            IDENTITY_Q,
            shape=(4,),
            optional="identity: O is the inertial frame (q_BO = q_BI)",
        ),
        input_(
            "w_OI_O",
            "rad/s",
            "angular velocity of O relative to I, in O",
            shape=(3,),
            optional="zero: O does not rotate",
        ),
        output("q_BI", "1", "attitude of B relative to I", shape=(4,)),
        output(
            "w_BI_B",
            "rad/s",
            "angular velocity of B relative to I, in B",
            shape=(3,),
            depends=MOMENTUM_INPUTS,
            display_unit="deg/s",
        ),
        output("q_BO", "1", "attitude of B relative to O", shape=(4,), depends=_BO_DEPENDS),
        output(
            "euler_BO",
            "rad",
            "1-2-3 Euler angles of B relative to O (continuous branch)",
            shape=(3,),
            depends=_BO_DEPENDS,
            display_unit="deg",
        ),
        output(
            "euler_rate_BO",
            "rad/s",
            "rates of euler_BO",
            shape=(3,),
            depends=_RATE_DEPENDS,
            display_unit="deg/s",
        ),
        output(
            "w_BO_B",
            "rad/s",
            "angular velocity of B relative to O, in B",
            shape=(3,),
            depends=_RATE_DEPENDS,
            display_unit="deg/s",
        ),
        output("H_I", "N.m.s", "total angular momentum (hub + devices), in I", shape=(3,)),
    )
    INITIAL_STATE_DEPENDS = MOMENTUM_INPUTS + ("q_OI", "w_OI_O")

    def initialize(self, t0):
        p, u = self.p, self.u
        J = np.array(p.inertia)
        if not np.allclose(J, J.T, rtol=1e-12, atol=1e-12 * np.abs(J).max()):
            raise ModelError(f"inertia must be symmetric, got {J.tolist()}")
        moments = np.linalg.eigvalsh(J)  # ascending
        if np.any(moments <= 0):
            raise ModelError(f"inertia must be positive definite, got {J.tolist()}")
        if moments[2] > (moments[0] + moments[1]) * (1 + 1e-12):
            raise ModelError(
                f"inertia {J.tolist()}: no rigid body has it: its largest principal moment "
                f"{moments[2]:.6g} exceeds the sum of the other two ({moments[0]:.6g} + "
                f"{moments[1]:.6g}; the triangle inequality of principal moments)"
            )
        # the gravity-gradient torque r × J r vanishes identically for J ∝ 1
        isotropic = np.allclose(J, J[0, 0] * np.eye(3), rtol=1e-15, atol=0.0)
        q_OI = _unit(u.q_OI, "q_OI")
        C_BO = dcm_from_euler123(p.attitude0)
        q_BO = quat_from_dcm(C_BO)
        q_BI = qmul(q_OI, q_BO)
        w_BI_B = p.rate0 + C_BO @ u.w_OI_O
        H_B = rotate(J.tolist(), w_BI_B)
        h = (u.h_cmg + u.h_wheel + u.h_payload).tolist()
        #: the state and the constants of the step and output kernels (STATE)
        self.state = state = S.zeros()
        state[S.q_BI : S.q_BI + 4] = q_BI
        state[S.H_I : S.H_I + 3] = rotate_back(dcm(q_BI), [H_B[i] + h[i] for i in range(3)])
        state[S.q_BO : S.q_BO + 4] = q_BO
        state[S.euler : S.euler + 3] = p.attitude0
        state[S.J : S.J + 9] = J.reshape(-1)
        state[S.J_inv : S.J_inv + 9] = np.linalg.inv(J).reshape(-1)
        state[S.mu] = p.mu
        state[S.gravity_gradient] = p.gravity_gradient and not isotropic
        state[S.needs_position] = p.gravity_gradient
        self.t = t0
        self.remember_initial_inputs()

    def step(self, t, dt):
        self.check_initial_inputs(dt)
        status = _step(self.values, self.state, self.t, dt)
        if status == SLOPE_CONFLICT:
            conflicts = [
                text for h in MOMENTUM_INPUTS for text in self.slope_conflicts(h, "hdot" + h[1:])
            ]
            self.warnings.append(
                f"t={t:.6g} s: {'; '.join(conflicts)}: the derivative a host sets for h_* "
                "(fmi2SetRealInputDerivatives) is its slope over the step, hdot_* only "
                "where none was set (reported once)"
            )
            status = OK
        if status == NO_POSITION:
            raise ModelError(
                "gravity_gradient is on but r_I is zero: connect r_I or set "
                "gravity_gradient = false"
            )
        if status == TOO_MANY_SUBSTEPS:
            rate, needed = _substeps(floats(self.values), floats(self.state), dt)
            n = math.ceil(needed) if math.isfinite(needed) else needed
            raise ModelError(
                f"t={t:.6g} s: body rate {rate:.3g} rad/s would need "
                f"{n} sub-steps of {dt:g} s: the state is unphysical"
            )
        if status == NON_FINITE:
            raise ModelError(f"non-finite state at t={t + dt:.6g} s")
        self.t = t + dt

    def output(self):
        if _output(self.values, self.state, self.t) == NOT_UNIT:
            _unit(self.u.q_OI, "q_OI")  # raises its ModelError

    def output_derivatives(self):
        """See the module docstring: d/dt of the outputs at ``self.t``."""
        v, s, y = floats(self.values), floats(self.state), self.y
        q_BI, H_I = quaternion(s, S.q_BI), vector(s, S.H_I)
        J, J_inv = matrix(s, S.J), matrix(s, S.J_inv)
        slope, _, _, r_rate, tau_rate = _rates(v)
        torque = (external(v), vector(v, U.r_I), tau_rate, r_rate)
        q_dot_H_dot = _derivative(
            q_BI + H_I, 0.0, _device_sum(v, U.h_cmg, U.h_wheel, U.h_payload), slope, (0.0,) * 3,
            torque, J, J_inv, s[S.mu], s[S.gravity_gradient] != 0.0, (False, False, False),
        )  # fmt: skip
        C_BI = dcm(q_BI)
        w, H_B = y.w_BI_B.tolist(), rotate(C_BI, H_I)
        tau_B = rotate(C_BI, q_dot_H_dot[4:])
        w_dot = rotate(J_inv, np.subtract(tau_B, slope) - np.cross(w, H_B))
        q_BO, w_BO = y.q_BO.tolist(), y.w_BO_B.tolist()
        C_BO = dcm(q_BO)
        w_OI_B = rotate(C_BO, self.u.w_OI_O.tolist())
        w_BO_dot = (
            np.add(w_dot, np.cross(w_BO, w_OI_B)) - rotate(C_BO, self.input_rate("w_OI_O"))
        ).tolist()
        euler, euler_dot = y.euler_BO.tolist(), y.euler_rate_BO.tolist()
        return np.array(
            [
                *q_dot_H_dot[:4],
                *w_dot,
                *(0.5 * x for x in qmul(q_BO, (0.0, *w_BO))),
                *euler_dot,
                *euler123_ddot(euler, euler_dot, w_BO, w_BO_dot),
                *w_BO_dot,
                *q_dot_H_dot[4:],
            ]
        )

    def initial_input_jumps(self, used, dt):
        """Bounds of one step of dt (margin 4): the orbit frame turns by at most
        |w_OI_O| dt, its rate changes by a small fraction, each device's momentum by
        |hdot| dt.  A host that passed nothing in initialisation jumps by the whole
        orbit attitude or stored momentum (radians, tens of N·m·s).  The frame's rate is
        taken as at least that of any Earth orbit (``MAX_ORBIT_FRAME_RATE``), so that a
        system leaving the optional w_OI_O open still passes its moving q_OI."""
        u, jumps = self.u, {}
        w = max(np.linalg.norm(used["w_OI_O"]), np.linalg.norm(u.w_OI_O), MAX_ORBIT_FRAME_RATE)
        cos_half = abs(float(np.dot(_unit(u.q_OI, "q_OI"), _unit(used["q_OI"], "q_OI"))))
        angle = 2.0 * math.acos(min(1.0, cos_half))
        if angle > 4.0 * w * dt + 1e-9:
            jumps["q_OI"] = f"turned {math.degrees(angle):.4g} deg"
        change = np.linalg.norm(u.w_OI_O - used["w_OI_O"])
        if change > 0.01 * w + 1e-12:
            jumps["w_OI_O"] = f"changed by {change:.3g} rad/s"
        for h in MOMENTUM_INPUTS:
            change = np.linalg.norm(getattr(u, h) - used[h])
            hdot = self.slope(h, "hdot" + h[1:])
            if change > 4.0 * np.linalg.norm(hdot) * dt + 1e-9 * (1.0 + np.linalg.norm(used[h])):
                jumps[h] = f"changed by {change:.4g} N.m.s"
        return jumps


# -- step and output: kernels on the value array (components/runtime/jit.py) -------------
P, U, Y = SatelliteDynamics.names()
#: the derivatives a host set for the inputs, and 1 where it set one (of h_*)
DU, GIVEN = SatelliteDynamics.derivative_names()
#: SatelliteDynamics.state: the state (q_BI, H_I), the last output's q_BO and euler_BO
#: (their sign and branch are kept continuous), and constants set by initialize: the hub
#: inertia and its inverse (row-major), μ, whether to apply the gravity-gradient torque
#: (gravity_gradient on and J not ∝ 1) and whether r_I must not be zero (gravity_gradient on);
#: 1 once a conflict of hdot_* with a derivative set for h_* was reported
S = state_table(
    "SatelliteDynamics state", q_BI=4, H_I=3, q_BO=4, euler=3, J=9, J_inv=9, mu=1,
    gravity_gradient=1, needs_position=1, slope_conflict=1,
)  # fmt: skip
#: the kernels' status codes (the Python wrapper raises the message, or warns: a step
#: returning SLOPE_CONFLICT is done)
OK, NO_POSITION, TOO_MANY_SUBSTEPS, NON_FINITE, NOT_UNIT, SLOPE_CONFLICT = range(6)


@step_kernel(SatelliteDynamics)
def _step(values, state, t, dt):
    """Advance (q_BI, H_I) in ``state`` by ``dt`` with the inputs in ``values``, as
    interpolated (module docstring): RK4 in n = ⌈max|w_BI_B| dt / MAX_ROTATION_PER_SUBSTEP⌉
    sub-steps, q_BI normalised after.  Returns the status; on an error nothing changes;
    SLOPE_CONFLICT (the step done) the first time an hdot_* input differs from a
    derivative set for its h_*."""
    v, s = floats(values), floats(state)
    h0 = _device_sum(v, U.h_cmg, U.h_wheel, U.h_payload)
    hdot, conflict, curvature, r_rate, tau_rate = _rates(v)
    tau, r_I = external(v), vector(v, U.r_I)
    if s[S.needs_position] != 0.0 and r_I[0] == 0.0 and r_I[1] == 0.0 and r_I[2] == 0.0:
        return NO_POSITION
    q_BI, H_I = quaternion(s, S.q_BI), vector(s, S.H_I)
    J, J_inv = matrix(s, S.J), matrix(s, S.J_inv)
    needed = _substeps(v, s, dt)[1]
    if not needed <= MAX_SUBSTEPS:
        return TOO_MANY_SUBSTEPS
    n = max(1, int(math.ceil(needed)))
    moving = (_nonzero(curvature), _nonzero(tau_rate), _nonzero(r_rate))
    x = _integrate(
        q_BI + H_I, n, dt / n, h0, hdot, curvature, (tau, r_I, tau_rate, r_rate),
        J, J_inv, s[S.mu], s[S.gravity_gradient] != 0.0, moving,
    )  # fmt: skip
    for xi in x:
        if not math.isfinite(xi):
            return NON_FINITE
    norm = quat_norm(x)
    put(state, S.q_BI, (x[0] / norm, x[1] / norm, x[2] / norm, x[3] / norm))
    put(state, S.H_I, x[4:])
    if conflict and s[S.slope_conflict] == 0.0:
        state[S.slope_conflict] = 1.0
        return SLOPE_CONFLICT
    return OK


@jitable
def _rates(v):
    """The inputs' rates over the step (module docstring): (ḣ summed over the devices as
    _device_sum adds h, whether a non-zero hdot_* differs from a derivative set for its
    h_*, ḧ summed, ṙ_I, τ̇_ext)."""
    slope = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    conflict = False
    for k, (d, g, stated) in enumerate(
        ((DU.h_cmg, GIVEN.h_cmg, U.hdot_cmg), (DU.h_wheel, GIVEN.h_wheel, U.hdot_wheel),
         (DU.h_payload, GIVEN.h_payload, U.hdot_payload))
    ):  # fmt: skip
        for i in range(3):
            slope[3 * k + i] = v[d + i] if v[g + i] != 0.0 else v[stated + i]
            if v[g + i] != 0.0 and v[stated + i] != 0.0 and v[stated + i] != v[d + i]:
                conflict = True
    hdot = (
        (slope[0] + slope[3]) + slope[6],
        (slope[1] + slope[4]) + slope[7],
        (slope[2] + slope[5]) + slope[8],
    )
    curvature = _device_sum(v, DU.hdot_cmg, DU.hdot_wheel, DU.hdot_payload)
    tau_rate = add(vector(v, DU.tau_ext), vector(v, DU.tau_ctrl))
    return hdot, conflict, curvature, vector(v, DU.r_I), tau_rate


@jitable
def external(v) -> tuple:
    """τ = tau_ext + tau_ctrl, the external torque on the body (in B)."""
    return add(vector(v, U.tau_ext), vector(v, U.tau_ctrl))


@jitable
def _nonzero(x):
    return x[0] != 0.0 or x[1] != 0.0 or x[2] != 0.0


@jitable
def _substeps(v, s, dt):
    """(max|w_BI_B| at the step's start, the RK4 sub-steps of ``dt`` it needs, unrounded)."""
    h0 = _device_sum(v, U.h_cmg, U.h_wheel, U.h_payload)
    w = _rate(quaternion(s, S.q_BI), vector(s, S.H_I), h0, matrix(s, S.J_inv))
    rate = abs(w[0])
    if abs(w[1]) > rate:
        rate = abs(w[1])
    if abs(w[2]) > rate:
        rate = abs(w[2])
    return rate, rate * dt / MAX_ROTATION_PER_SUBSTEP


@output_kernel(SatelliteDynamics)
def _output(values, state, t):
    """Write the outputs into ``values`` from ``state`` and the inputs; keep q_BO's sign
    and euler_BO's branch in ``state``.  Returns the status: NOT_UNIT (nothing written) if
    q_OI is not a unit quaternion."""
    v, s = floats(values), floats(state)
    q0, q1, q2, q3 = q = quaternion(v, U.q_OI)
    norm = quat_norm(q)
    if not _is_unit(norm):
        return NOT_UNIT
    q_OI = (q0 / norm, q1 / norm, q2 / norm, q3 / norm)
    q_BI, H_I = quaternion(s, S.q_BI), vector(s, S.H_I)
    w_BI_B = _rate(q_BI, H_I, _device_sum(v, U.h_cmg, U.h_wheel, U.h_payload), matrix(s, S.J_inv))
    q_BO = qmul((q_OI[0], -q_OI[1], -q_OI[2], -q_OI[3]), q_BI)
    last = quaternion(s, S.q_BO)
    if quat_dot(q_BO, last) < 0:
        q_BO = (-q_BO[0], -q_BO[1], -q_BO[2], -q_BO[3])  # keep the sign continuous
    C_BO = dcm(q_BO)
    euler = euler123(q_BO, C_BO, vector(s, S.euler), True)
    w_OI_B = rotate(C_BO, vector(v, U.w_OI_O))
    w_BO_B = (w_BI_B[0] - w_OI_B[0], w_BI_B[1] - w_OI_B[1], w_BI_B[2] - w_OI_B[2])
    put(state, S.q_BO, q_BO)
    put(state, S.euler, euler)
    put(values, Y.q_BI, q_BI)
    put(values, Y.w_BI_B, w_BI_B)
    put(values, Y.q_BO, q_BO)
    put(values, Y.euler_BO, euler)
    put(values, Y.euler_rate_BO, euler123_dot(euler, w_BO_B))
    put(values, Y.w_BO_B, w_BO_B)
    put(values, Y.H_I, H_I)
    return OK


@jitable
def _rate(q, H_I, h, J_inv):
    """w_BI_B = J⁻¹ (C_BI H_I − h)."""
    H_B = rotate(dcm(q), H_I)
    return rotate(J_inv, (H_B[0] - h[0], H_B[1] - h[1], H_B[2] - h[2]))


@jitable
def _integrate(x, n, sub, h0, hdot, curvature, torque, J, J_inv, mu, gravity_gradient, moving):
    """x = (q_BI, H_I) after n RK4 sub-steps of ``sub``."""
    for k in range(n):
        x = _rk4(
            x, k * sub, sub, h0, hdot, curvature, torque, J, J_inv, mu, gravity_gradient, moving
        )
    return x


@jitable
def _rk4(x, s, ds, h0, hdot, curvature, torque, J, J_inv, mu, gravity_gradient, moving):
    """One classical Runge-Kutta step of ``ds`` from ``s`` into the macro step."""
    f, half = _derivative, ds / 2
    inputs = h0, hdot, curvature, torque, J, J_inv, mu, gravity_gradient, moving
    k1 = f(x, s, *inputs)
    k2 = f(_shift(x, half, k1), s + half, *inputs)
    k3 = f(_shift(x, half, k2), s + half, *inputs)
    k4 = f(_shift(x, ds, k3), s + ds, *inputs)
    return _shift(x, ds / 6, _weighted(k1, k2, k3, k4))


@jitable
def _shift(x, a, k):
    """x + a k (7-tuples)."""
    return (
        x[0] + a * k[0], x[1] + a * k[1], x[2] + a * k[2], x[3] + a * k[3],
        x[4] + a * k[4], x[5] + a * k[5], x[6] + a * k[6],
    )  # fmt: skip


@jitable
def _weighted(k1, k2, k3, k4):
    """RK4's k1 + 2 (k2 + k3) + k4 (7-tuples)."""
    a, b, c, d = k1, k2, k3, k4
    return (
        a[0] + 2 * (b[0] + c[0]) + d[0], a[1] + 2 * (b[1] + c[1]) + d[1],
        a[2] + 2 * (b[2] + c[2]) + d[2], a[3] + 2 * (b[3] + c[3]) + d[3],
        a[4] + 2 * (b[4] + c[4]) + d[4], a[5] + 2 * (b[5] + c[5]) + d[5],
        a[6] + 2 * (b[6] + c[6]) + d[6],
    )  # fmt: skip


@jitable
def _derivative(x, s, h0, hdot, curvature, torque, J, J_inv, mu, gravity_gradient, moving):
    """(q̇_BI, Ḣ_I) at time s into the step (the hot loop: plain floats).  ``torque`` is
    (τ_ext, r_I, τ̇_ext, ṙ_I); ``moving`` says which of ḧ, τ̇_ext, ṙ_I are not zero (a
    rate of zero leaves the arithmetic of a held input untouched, bit for bit)."""
    tau, r_I, tau_rate, r_rate = torque
    q0, q1, q2, q3 = q = x[:4]
    k = 1.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)  # C(q)/|q|² is a rotation for any q
    (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = dcm(q)
    C = (k * c00, k * c01, k * c02), (k * c10, k * c11, k * c12), (k * c20, k * c21, k * c22)
    H_B = rotate(C, x[4:])
    if moving[0]:  # h + ḣ s + ½ ḧ s²
        a = (hdot[0] + 0.5 * curvature[0] * s, hdot[1] + 0.5 * curvature[1] * s,
             hdot[2] + 0.5 * curvature[2] * s)  # fmt: skip
        relative = (H_B[0] - h0[0] - a[0] * s, H_B[1] - h0[1] - a[1] * s, H_B[2] - h0[2] - a[2] * s)
    else:
        relative = (
            H_B[0] - h0[0] - hdot[0] * s,
            H_B[1] - h0[1] - hdot[1] * s,
            H_B[2] - h0[2] - hdot[2] * s,
        )
    if moving[1]:
        tau = (tau[0] + tau_rate[0] * s, tau[1] + tau_rate[1] * s, tau[2] + tau_rate[2] * s)
    if moving[2]:
        r_I = (r_I[0] + r_rate[0] * s, r_I[1] + r_rate[1] * s, r_I[2] + r_rate[2] * s)
    wx, wy, wz = rotate(J_inv, relative)
    q_dot = (
        0.5 * (-q1 * wx - q2 * wy - q3 * wz),
        0.5 * (q0 * wx + q2 * wz - q3 * wy),
        0.5 * (q0 * wy - q1 * wz + q3 * wx),
        0.5 * (q0 * wz + q1 * wy - q2 * wx),
    )
    if not gravity_gradient:
        return q_dot + rotate_back(C, tau)
    rx, ry, rz = r_B = rotate(C, r_I)
    r2 = rx * rx + ry * ry + rz * rz
    g = 3.0 * mu / (r2 * r2 * math.sqrt(r2))
    jx, jy, jz = rotate(J, r_B)
    torque = (
        tau[0] + g * (ry * jz - rz * jy),
        tau[1] + g * (rz * jx - rx * jz),
        tau[2] + g * (rx * jy - ry * jx),
    )
    return q_dot + rotate_back(C, torque)


@jitable
def _device_sum(a, cmg, wheel, payload):
    """(cmg + wheel) + payload of three 3-vectors at these offsets."""
    c, w, p = vector(a, cmg), vector(a, wheel), vector(a, payload)
    return (c[0] + w[0]) + p[0], (c[1] + w[1]) + p[1], (c[2] + w[2]) + p[2]


@jitable
def _is_unit(norm):
    """|q| near enough to 1 for a quaternion meant to be a unit one."""
    return 0.5 < norm < 2.0


def _unit(q, name) -> tuple:
    q0, q1, q2, q3 = q = q.tolist()
    norm = quat_norm(q)
    if not _is_unit(norm):
        raise ModelError(f"{name} must be a unit quaternion, got {q} (norm {norm})")
    return q0 / norm, q1 / norm, q2 / norm, q3 / norm
