"""Rigid satellite hub carrying momentum-exchange devices (seeds 000/003 eqs 1–3).

States: the attitude q_BI and the *total* angular momentum H_I (hub + devices, inertial
axes).  With J the hub inertia, h the devices' momentum relative to the body (in B) and
τ the external torque on the body (in B)::

    w_BI_B = J⁻¹ (C_BI H_I − h)                       (eq. 2 solved for w)
    q̇_BI  = ½ q_BI ⊗ (0, w_BI_B)
    Ḣ_I   = C_BIᵀ (τ_ext + τ_gg),   τ_gg = 3 μ/|r|⁵ · r_B × J r_B,   r_B = C_BI r_I

which is the hub equation J ẇ = −w × (J w + h) − ḣ + τ (eq. 3 with all terms kept):
H_I changes only by external torque, so total momentum is conserved exactly whatever the
co-simulation step.  Across a step the devices' momentum is extrapolated with the
derivative they report, h(t + s) = h + ḣ s, held at the communication point (FMI inputs
are the values at the step's start).  Integration: classical RK4 with sub-steps of at
most 0.02 rad of rotation.

Outputs relative to the orbit frame O (inputs q_OI, w_OI_O): q_BO = q_OI* ⊗ q_BI,
w_BO_B = w_BI_B − C_BO w_OI_O and the 1-2-3 Euler angles of B relative to O on a branch
continuous in time (pitch may pass through ±90°; see rotations.euler123_from_quat), with
their rates (video-SAR eq. 13).
"""
from __future__ import annotations

import math

import numpy as np

from .model import Model, ModelError
from .rotations import (IDENTITY_Q, dcm_from_euler123, dcm_from_quat, euler123_from_quat,
                        euler123_rates, quat_conj, quat_from_dcm, quat_mul)
from .variables import input_, output, parameter

MAX_ROTATION_PER_SUBSTEP = 0.02  # rad
DEVICES = ("cmg", "wheel", "payload")
MOMENTUM_INPUTS = tuple(f"h_{d}" for d in DEVICES)


def _device_inputs():
    for device in DEVICES:
        yield input_(f"h_{device}", "N.m.s",
                     f"{device} angular momentum relative to the body, in B", shape=(3,),
                     required=False)
        yield input_(f"hdot_{device}", "N.m",
                     f"time derivative of h_{device} as seen in B", shape=(3,),
                     required=False)


class SatelliteDynamics(Model):
    """Rigid-body attitude dynamics with internal momentum and gravity-gradient torque."""

    _BO_DEPENDS = ("q_OI",)
    _RATE_DEPENDS = MOMENTUM_INPUTS + ("q_OI", "w_OI_O")
    VARIABLES = (
        parameter("inertia", 956.0 * np.eye(3), "kg.m2",
                  "hub inertia about the centre of mass, in B", shape=(3, 3)),
        parameter("attitude0", 0.0, "rad",
                  "initial 1-2-3 Euler angles (roll, pitch, yaw) of B relative to O",
                  shape=(3,), display_unit="deg"),
        parameter("rate0", 0.0, "rad/s", "initial angular velocity of B relative to O, in B",
                  shape=(3,), display_unit="deg/s"),
        parameter("gravity_gradient", True, "1", "apply the gravity-gradient torque",
                  type="Boolean"),
        parameter("mu", 3.986004418e14, "m3/s2", "gravitational parameter of the Earth"),
        *_device_inputs(),
        input_("tau_ext", "N.m", "other external torque on the body, in B", shape=(3,),
               required=False),
        input_("r_I", "m", "satellite position in I (for the gravity gradient)", shape=(3,),
               required=False),
        input_("q_OI", "1", "attitude of the orbit frame O relative to I", IDENTITY_Q,
               shape=(4,), required=False),
        input_("w_OI_O", "rad/s", "angular velocity of O relative to I, in O", shape=(3,),
               required=False),
        output("q_BI", "1", "attitude of B relative to I", shape=(4,)),
        output("w_BI_B", "rad/s", "angular velocity of B relative to I, in B", shape=(3,),
               depends=MOMENTUM_INPUTS, display_unit="deg/s"),
        output("q_BO", "1", "attitude of B relative to O", shape=(4,), depends=_BO_DEPENDS),
        output("euler_BO", "rad", "1-2-3 Euler angles of B relative to O (continuous branch)",
               shape=(3,), depends=_BO_DEPENDS, display_unit="deg"),
        output("euler_rate_BO", "rad/s", "rates of euler_BO", shape=(3,),
               depends=_RATE_DEPENDS, display_unit="deg/s"),
        output("w_BO_B", "rad/s", "angular velocity of B relative to O, in B", shape=(3,),
               depends=_RATE_DEPENDS, display_unit="deg/s"),
        output("H_I", "N.m.s", "total angular momentum (hub + devices), in I", shape=(3,)),
    )
    INITIAL_STATE_DEPENDS = MOMENTUM_INPUTS + ("q_OI", "w_OI_O")

    def initialize(self, t0):
        p, u = self.p, self.u
        J = np.array(p.inertia)
        if not np.allclose(J, J.T, rtol=1e-12, atol=1e-12 * np.abs(J).max()):
            raise ModelError(f"inertia must be symmetric, got {J.tolist()}")
        if np.any(np.linalg.eigvalsh(J) <= 0):
            raise ModelError(f"inertia must be positive definite, got {J.tolist()}")
        self.J = J
        self.J_inv = np.linalg.inv(J)
        self._J = tuple(map(tuple, J))
        self._J_inv = tuple(map(tuple, self.J_inv))
        self.gravity_gradient = p.gravity_gradient
        self.mu = p.mu
        q_OI = _unit(u.q_OI, "q_OI")
        C_BO = dcm_from_euler123(p.attitude0)
        q_BO = quat_from_dcm(C_BO)
        self.q_BI = quat_mul(q_OI, q_BO)
        w_BI_B = p.rate0 + C_BO @ u.w_OI_O
        self.H_I = dcm_from_quat(self.q_BI).T @ (J @ w_BI_B + self._h_total())
        self.euler = np.array(p.attitude0, dtype=float)
        self.q_BO = q_BO
        self.t = t0

    def step(self, t, dt):
        u = self.u
        h0, hdot = self._h_total(), u.hdot_cmg + u.hdot_wheel + u.hdot_payload
        tau = tuple(u.tau_ext)
        r_I = tuple(u.r_I)
        if self.gravity_gradient and not any(r_I):
            raise ModelError("gravity_gradient is on but r_I is zero: connect r_I or set "
                             "gravity_gradient = false")
        w = self.J_inv @ (dcm_from_quat(self.q_BI) @ self.H_I - h0)
        n = max(1, math.ceil(float(np.abs(w).max()) * dt / MAX_ROTATION_PER_SUBSTEP))
        x = (*self.q_BI, *self.H_I)
        hs, hdots = tuple(h0), tuple(hdot)
        sub = dt / n
        for k in range(n):
            x = self._rk4(x, k * sub, sub, hs, hdots, tau, r_I)
        q = np.array(x[:4])
        self.q_BI = q / math.sqrt(float(q @ q))
        self.H_I = np.array(x[4:])
        if not np.all(np.isfinite(x)):
            raise ModelError(f"non-finite state at t={t + dt}")
        self.t = t + dt

    def output(self):
        u, y = self.u, self.y
        C_BI = dcm_from_quat(self.q_BI)
        w_BI_B = self.J_inv @ (C_BI @ self.H_I - self._h_total())
        q_BO = quat_mul(quat_conj(_unit(u.q_OI, "q_OI")), self.q_BI)
        if q_BO @ self.q_BO < 0:  # keep the quaternion sign continuous
            q_BO = -q_BO
        self.q_BO = q_BO
        C_BO = dcm_from_quat(q_BO)
        self.euler = euler123_from_quat(q_BO, previous=self.euler)
        w_BO_B = w_BI_B - C_BO @ u.w_OI_O
        y.q_BI[:] = self.q_BI
        y.w_BI_B[:] = w_BI_B
        y.q_BO[:] = q_BO
        y.euler_BO[:] = self.euler
        y.euler_rate_BO[:] = euler123_rates(self.euler, w_BO_B)
        y.w_BO_B[:] = w_BO_B
        y.H_I[:] = self.H_I

    # -- internals -----------------------------------------------------------------
    def _h_total(self) -> np.ndarray:
        u = self.u
        return u.h_cmg + u.h_wheel + u.h_payload

    def _rk4(self, x, s, ds, h0, hdot, tau, r_I):
        f = self._derivative
        k1 = f(x, s, h0, hdot, tau, r_I)
        k2 = f(_axpy(x, ds / 2, k1), s + ds / 2, h0, hdot, tau, r_I)
        k3 = f(_axpy(x, ds / 2, k2), s + ds / 2, h0, hdot, tau, r_I)
        k4 = f(_axpy(x, ds, k3), s + ds, h0, hdot, tau, r_I)
        return tuple(xi + ds / 6 * (a + 2 * b + 2 * c + d)
                     for xi, a, b, c, d in zip(x, k1, k2, k3, k4))

    def _derivative(self, x, s, h0, hdot, tau, r_I):
        """(q̇_BI, Ḣ_I) at time s into the step, in plain floats (this is the hot loop)."""
        q0, q1, q2, q3, Hx, Hy, Hz = x
        C = _dcm(q0, q1, q2, q3)
        H_B = _mv(C, (Hx, Hy, Hz))
        w = _mv(self._J_inv, tuple(H_B[i] - h0[i] - hdot[i] * s for i in range(3)))
        wx, wy, wz = w
        q_dot = (0.5 * (-q1 * wx - q2 * wy - q3 * wz),
                 0.5 * (q0 * wx + q2 * wz - q3 * wy),
                 0.5 * (q0 * wy - q1 * wz + q3 * wx),
                 0.5 * (q0 * wz + q1 * wy - q2 * wx))
        torque = tau
        if self.gravity_gradient:
            r_B = _mv(C, r_I)
            r2 = r_B[0] ** 2 + r_B[1] ** 2 + r_B[2] ** 2
            k = 3.0 * self.mu / (r2 * r2 * math.sqrt(r2))
            Jr = _mv(self._J, r_B)
            torque = (tau[0] + k * (r_B[1] * Jr[2] - r_B[2] * Jr[1]),
                      tau[1] + k * (r_B[2] * Jr[0] - r_B[0] * Jr[2]),
                      tau[2] + k * (r_B[0] * Jr[1] - r_B[1] * Jr[0]))
        H_dot = tuple(C[0][i] * torque[0] + C[1][i] * torque[1] + C[2][i] * torque[2]
                      for i in range(3))  # Cᵀ τ
        return (*q_dot, *H_dot)


def _unit(q, name) -> np.ndarray:
    norm = math.sqrt(float(q @ q))
    if not 0.5 < norm < 2.0:
        raise ModelError(f"{name} must be a unit quaternion, got {list(q)} (norm {norm})")
    return q / norm


def _dcm(q0, q1, q2, q3):
    """C(q) as nested tuples (see rotations.dcm_from_quat)."""
    return ((q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2 * (q1 * q2 + q0 * q3), 2 * (q1 * q3 - q0 * q2)),
            (2 * (q1 * q2 - q0 * q3), q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2 * (q2 * q3 + q0 * q1)),
            (2 * (q1 * q3 + q0 * q2), 2 * (q2 * q3 - q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3))


def _mv(M, v):
    return (M[0][0] * v[0] + M[0][1] * v[1] + M[0][2] * v[2],
            M[1][0] * v[0] + M[1][1] * v[1] + M[1][2] * v[2],
            M[2][0] * v[0] + M[2][1] * v[1] + M[2][2] * v[2])


def _axpy(x, a, k):
    return tuple(xi + a * ki for xi, ki in zip(x, k))
