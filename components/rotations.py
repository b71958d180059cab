"""Attitude conventions of the whole toolkit (DESIGN.md §2).

Quaternion ``q_XY = (q0, q1, q2, q3)``: scalar first, Hamilton product; the attitude of
frame X relative to Y, mapping Y-coordinates to X-coordinates::

    v_X = C(q_XY) v_Y,   C(q) = (q0² − q·q) 1 + 2 q qᵀ − 2 q0 [q×]

so that ``C(q_XZ) = C(q_XY) C(q_YZ)`` and ``q_XZ = q_YZ ⊗ q_XY``.  Kinematics:
``q̇_BI = ½ q_BI ⊗ (0, w_BI_B)``.

Euler angles of B relative to O, sequence 1-2-3 (roll φ about x, pitch θ about the new y,
yaw ψ about the new z)::

    C_BO = R3(ψ) R2(θ) R1(φ)

which is the transpose of the matrix of the video-SAR paper's eq. (9).  Its body rates
are eq. (13): ``w = (φ̇ cψ cθ + θ̇ sψ, −φ̇ sψ cθ + θ̇ cψ, ψ̇ + φ̇ sθ)``.
"""
from __future__ import annotations

import math

import numpy as np

IDENTITY_Q = np.array([1.0, 0.0, 0.0, 0.0])


def skew(v) -> np.ndarray:
    """[v×], so that skew(a) @ b = a × b."""
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def cross(a, b) -> np.ndarray:
    """a × b for 3-vectors (np.cross is ten times slower on tiny arrays)."""
    return np.array([a[1] * b[2] - a[2] * b[1],
                     a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def quat_mul(p, q) -> np.ndarray:
    """Hamilton product p ⊗ q."""
    p0, p1, p2, p3 = p
    q0, q1, q2, q3 = q
    return np.array([p0 * q0 - p1 * q1 - p2 * q2 - p3 * q3,
                     p0 * q1 + p1 * q0 + p2 * q3 - p3 * q2,
                     p0 * q2 - p1 * q3 + p2 * q0 + p3 * q1,
                     p0 * q3 + p1 * q2 - p2 * q1 + p3 * q0])


def quat_conj(q) -> np.ndarray:
    return np.array([q[0], -q[1], -q[2], -q[3]])


def quat_normalize(q) -> np.ndarray:
    """Unit quaternion with non-negative scalar part (one representative of ±q)."""
    q = np.asarray(q, dtype=float)
    q = q / math.sqrt(float(q @ q))
    return -q if q[0] < 0.0 else q


def quat_from_axis_angle(axis, angle: float) -> np.ndarray:
    """Attitude of a frame rotated by ``angle`` about ``axis`` relative to the reference."""
    axis = np.asarray(axis, dtype=float)
    axis = axis / np.linalg.norm(axis)
    return np.concatenate(([math.cos(angle / 2)], math.sin(angle / 2) * axis))


def dcm_from_quat(q) -> np.ndarray:
    """C(q): maps reference-frame coordinates to the rotated frame."""
    q0, q1, q2, q3 = q
    return np.array([
        [q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2 * (q1 * q2 + q0 * q3), 2 * (q1 * q3 - q0 * q2)],
        [2 * (q1 * q2 - q0 * q3), q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2 * (q2 * q3 + q0 * q1)],
        [2 * (q1 * q3 + q0 * q2), 2 * (q2 * q3 - q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3],
    ])


def quat_from_dcm(C) -> np.ndarray:
    """Inverse of :func:`dcm_from_quat` (Shepperd's method), scalar part ≥ 0."""
    C = np.asarray(C, dtype=float)
    trace = C[0, 0] + C[1, 1] + C[2, 2]
    candidates = (trace, C[0, 0], C[1, 1], C[2, 2])
    k = int(np.argmax(candidates))
    if k == 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = [0.25 * s, (C[1, 2] - C[2, 1]) / s, (C[2, 0] - C[0, 2]) / s, (C[0, 1] - C[1, 0]) / s]
    elif k == 1:
        s = 2.0 * math.sqrt(1.0 + 2 * C[0, 0] - trace)
        q = [(C[1, 2] - C[2, 1]) / s, 0.25 * s, (C[0, 1] + C[1, 0]) / s, (C[0, 2] + C[2, 0]) / s]
    elif k == 2:
        s = 2.0 * math.sqrt(1.0 + 2 * C[1, 1] - trace)
        q = [(C[2, 0] - C[0, 2]) / s, (C[0, 1] + C[1, 0]) / s, 0.25 * s, (C[1, 2] + C[2, 1]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + 2 * C[2, 2] - trace)
        q = [(C[0, 1] - C[1, 0]) / s, (C[0, 2] + C[2, 0]) / s, (C[1, 2] + C[2, 1]) / s, 0.25 * s]
    return quat_normalize(q)


def rot1(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]])


def rot2(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


def rot3(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def dcm_from_euler123(euler) -> np.ndarray:
    """C_BO = R3(ψ) R2(θ) R1(φ) for euler = (φ, θ, ψ)."""
    phi, theta, psi = euler
    return rot3(psi) @ rot2(theta) @ rot1(phi)


def quat_from_euler123(euler) -> np.ndarray:
    return quat_from_dcm(dcm_from_euler123(euler))


#: below this |cos θ| the 1-2-3 angles are in gimbal lock and only φ ± ψ is defined
GIMBAL_LOCK_COS = 1e-9


def euler123_from_quat(q, previous=None) -> np.ndarray:
    """(φ, θ, ψ) with C(q) = R3(ψ) R2(θ) R1(φ), on a branch continuous in time.

    Every rotation has two 1-2-3 representations, (φ, θ, ψ) with |θ| ≤ π/2 and
    (φ+π, π−θ, ψ+π).  The one whose pitch is nearer the twist of q about y,
    2 atan2(q2, q0), is returned: that angle is continuous and well conditioned through
    the gimbal lock at θ = ±90°, where φ and ψ alone swing, so a slew in pitch from 120° to
    0° keeps roll and yaw near zero instead of flipping them by 180°.  ``previous`` (the
    last output) shifts each angle by multiples of 2π to keep it continuous; in exact
    gimbal lock, where only φ + ψ (θ = +90°) or φ − ψ (θ = −90°) is defined, the change of
    that combination is split equally between φ and ψ.
    """
    q = np.asarray(q, dtype=float)
    C = dcm_from_quat(q)
    sin_theta = min(1.0, max(-1.0, C[2, 0]))
    theta = math.asin(sin_theta)
    if math.cos(theta) > GIMBAL_LOCK_COS:
        phi = math.atan2(-C[2, 1], C[2, 2])
        psi = math.atan2(-C[1, 0], C[0, 0])
        twist = 2.0 * math.atan2(q[2], q[0]) if q[0] >= 0 else 2.0 * math.atan2(-q[2], -q[0])
        if abs(_wrap(math.pi - theta - twist)) < abs(_wrap(theta - twist)):
            phi, theta, psi = phi + math.pi, math.pi - theta, psi + math.pi
        angles = np.array([phi, theta, psi])
        return angles if previous is None else _unwrap_near(angles, previous)
    # gimbal lock: C[0,1] = ±sin(φ ± ψ), C[1,1] = cos(φ ± ψ) (upper signs for θ = +90°)
    sign = 1.0 if sin_theta > 0 else -1.0
    combination = math.atan2(sign * C[0, 1], C[1, 1])
    if previous is None:
        return np.array([combination, theta, 0.0])
    phi0, theta0, psi0 = previous
    change = _wrap(combination - (phi0 + sign * psi0))
    result = np.array([phi0 + change / 2, theta, psi0 + sign * change / 2])
    return _unwrap_near(result, previous)


def euler123_rates(euler, w) -> np.ndarray:
    """(φ̇, θ̇, ψ̇) from the body rates ``w`` of B relative to O (eq. 13 inverted).

    Singular at cos θ = 0; there φ̇ is set to 0 and ψ̇ takes the whole z rate.
    """
    _, theta, psi = euler
    cp, sp = math.cos(psi), math.sin(psi)
    ct, st = math.cos(theta), math.sin(theta)
    wx, wy, wz = w
    phi_dot = (wx * cp - wy * sp) / ct if abs(ct) > GIMBAL_LOCK_COS else 0.0
    return np.array([phi_dot, wx * sp + wy * cp, wz - phi_dot * st])


def _wrap(angle: float) -> float:
    """Angle wrapped to [−π, π)."""
    return angle - 2 * math.pi * math.floor((angle + math.pi) / (2 * math.pi))


def _unwrap_near(angles, reference) -> np.ndarray:
    return reference + np.array([_wrap(a - r) for a, r in zip(angles, reference)])
