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

The functions take any sequence and compute on Python floats: models call them once or
several times per co-simulation step on 3- and 4-vectors, where NumPy's per-call cost
would dominate.  The tuple primitives (``dcm``, ``qmul``, ``euler123``, ...) return tuples
for such hot loops, compiled in kernels (:mod:`.runtime.jit`), on the small-vector algebra
of :mod:`.vectors` (``rotate`` is M v); the rest return NumPy arrays.
"""

from __future__ import annotations

import math

import numpy as np

from .runtime.jit import floats as _floats
from .runtime.jit import jitable

IDENTITY_Q = np.array([1.0, 0.0, 0.0, 0.0])
#: below this |cos θ| the 1-2-3 angles are in gimbal lock and only φ ± ψ is defined
GIMBAL_LOCK_COS = 1e-9
#: below this |cos θ| (within 2.9° of ±90°) the branch is chosen by the twist about y
LOCK_ZONE_COS = 0.05


# -- tuple primitives ------------------------------------------------------------------
@jitable
def dcm(q) -> tuple:
    """C(q) as a tuple of rows."""
    q0, q1, q2, q3 = _floats(q)
    return (
        (q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2 * (q1 * q2 + q0 * q3), 2 * (q1 * q3 - q0 * q2)),
        (2 * (q1 * q2 - q0 * q3), q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2 * (q2 * q3 + q0 * q1)),
        (2 * (q1 * q3 + q0 * q2), 2 * (q2 * q3 - q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3),
    )


@jitable
def qmul(p, q) -> tuple:
    """Hamilton product p ⊗ q."""
    p0, p1, p2, p3 = _floats(p)
    q0, q1, q2, q3 = _floats(q)
    return (
        p0 * q0 - p1 * q1 - p2 * q2 - p3 * q3,
        p0 * q1 + p1 * q0 + p2 * q3 - p3 * q2,
        p0 * q2 - p1 * q3 + p2 * q0 + p3 * q1,
        p0 * q3 + p1 * q2 - p2 * q1 + p3 * q0,
    )


# -- array API ---------------------------------------------------------------------------
def skew(v) -> np.ndarray:
    """[v×], so that skew(a) @ b = a × b."""
    x, y, z = _floats(v)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def quat_mul(p, q) -> np.ndarray:
    """Hamilton product p ⊗ q."""
    return np.array(qmul(p, q))


def quat_conj(q) -> np.ndarray:
    q0, q1, q2, q3 = _floats(q)
    return np.array([q0, -q1, -q2, -q3])


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
    return np.array(dcm(q))


@jitable
def quat_of_rows(c00, c01, c02, c10, c11, c12, c20, c21, c22):
    """q (scalar first, q0 ≥ 0) of the rotation matrix with rows (c00, c01, c02), ...:
    Shepperd's method, the largest of 1 + trace, 1 + 2 c_kk − trace chosen (the first on a
    tie), what :func:`quat_from_dcm` returns, compilable."""
    trace = c00 + c11 + c22
    k, largest = 0, trace
    for j, c in ((1, c00), (2, c11), (3, c22)):
        if c > largest:
            k, largest = j, c
    if k == 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = (0.25 * s, (c12 - c21) / s, (c20 - c02) / s, (c01 - c10) / s)
    elif k == 1:
        s = 2.0 * math.sqrt(1.0 + 2 * c00 - trace)
        q = ((c12 - c21) / s, 0.25 * s, (c01 + c10) / s, (c02 + c20) / s)
    elif k == 2:
        s = 2.0 * math.sqrt(1.0 + 2 * c11 - trace)
        q = ((c20 - c02) / s, (c01 + c10) / s, 0.25 * s, (c12 + c21) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + 2 * c22 - trace)
        q = ((c01 - c10) / s, (c02 + c20) / s, (c12 + c21) / s, 0.25 * s)
    norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    sign = -1.0 if q[0] < 0.0 else 1.0
    return (sign * q[0] / norm, sign * q[1] / norm, sign * q[2] / norm, sign * q[3] / norm)


def quat_from_dcm(C) -> np.ndarray:
    """Inverse of :func:`dcm_from_quat` (Shepperd's method), scalar part ≥ 0."""
    (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = _floats(C)
    return np.array(quat_of_rows(c00, c01, c02, c10, c11, c12, c20, c21, c22))


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
    phi, theta, psi = _floats(euler)
    return rot3(psi) @ rot2(theta) @ rot1(phi)


def quat_from_euler123(euler) -> np.ndarray:
    return quat_from_dcm(dcm_from_euler123(euler))


def euler123_from_quat(q, previous=None) -> np.ndarray:
    """(φ, θ, ψ) with C(q) = R3(ψ) R2(θ) R1(φ), on a branch continuous in time
    (:func:`euler123`; without ``previous`` the principal one)."""
    q = tuple(_floats(q))
    if previous is None:
        return np.array(euler123(q, dcm(q), (0.0, 0.0, 0.0), False))
    return np.array(euler123(q, dcm(q), tuple(_floats(previous)), True))


@jitable
def euler123(q, C, previous, continuous) -> tuple:
    """(φ, θ, ψ) with C = C(q) = R3(ψ) R2(θ) R1(φ), on a branch continuous in time.

    Every rotation has two 1-2-3 representations, (φ, θ, ψ) with |θ| ≤ π/2 and
    (φ+π, π−θ, ψ+π).  Without ``continuous`` the first (principal) one is returned.  With
    it, ``previous`` is the last output and the one nearer it is returned, each angle
    shifted by multiples of 2π to stay continuous.  Near the gimbal lock at θ = ±90°
    (|cos θ| < ``LOCK_ZONE_COS``) φ and ψ alone swing with tiny attitude changes and cannot
    choose: there the representation whose pitch is nearer the twist of q about y,
    2 atan2(q2, q0), wins — that angle is well conditioned through the lock, so a pitch
    slew from 120° to 0° keeps roll and yaw near zero instead of flipping them by 180°.
    In exact lock only φ + ψ (θ = +90°) or φ − ψ (θ = −90°) is defined; the change of that
    combination is split equally between φ and ψ.
    """
    q0, _, q2, _ = q
    (c00, c01, _), (c10, c11, _), (c20, c21, c22) = C
    sin_theta = min(1.0, max(-1.0, c20))
    theta = math.asin(sin_theta)
    cos_theta = math.cos(theta)
    if cos_theta > GIMBAL_LOCK_COS:
        principal = (math.atan2(-c21, c22), theta, math.atan2(-c10, c00))
        if not continuous:
            return principal
        other = (principal[0] + math.pi, math.pi - theta, principal[2] + math.pi)
        if cos_theta < LOCK_ZONE_COS:
            twist = 2.0 * math.atan2(q2, q0) if q0 >= 0 else 2.0 * math.atan2(-q2, -q0)
            use_other = abs(wrap_pi(other[1] - twist)) < abs(wrap_pi(theta - twist))
        else:
            use_other = _distance(other, previous) < _distance(principal, previous)
        return _unwrap3(other if use_other else principal, previous)
    # gimbal lock: C[0,1] = ±sin(φ ± ψ), C[1,1] = cos(φ ± ψ) (upper signs for θ = +90°)
    sign = 1.0 if sin_theta > 0 else -1.0
    combination = math.atan2(sign * c01, c11)
    if not continuous:
        return (combination, theta, 0.0)
    phi0, _, psi0 = previous
    change = wrap_pi(combination - (phi0 + sign * psi0))
    return _unwrap3((phi0 + change / 2, theta, psi0 + sign * change / 2), previous)


def euler123_rates(euler, w) -> np.ndarray:
    """(φ̇, θ̇, ψ̇) from the body rates ``w`` of B relative to O (:func:`euler123_dot`)."""
    return np.array(euler123_dot(tuple(_floats(euler)), tuple(_floats(w))))


@jitable
def euler123_dot(euler, w) -> tuple:
    """(φ̇, θ̇, ψ̇) from the body rates ``w`` of B relative to O (eq. 13 inverted).

    Singular at cos θ = 0; there φ̇ is set to 0 and ψ̇ takes the whole z rate.
    """
    _, theta, psi = euler
    cp, sp = math.cos(psi), math.sin(psi)
    ct, st = math.cos(theta), math.sin(theta)
    wx, wy, wz = w
    phi_dot = (wx * cp - wy * sp) / ct if abs(ct) > GIMBAL_LOCK_COS else 0.0
    return (phi_dot, wx * sp + wy * cp, wz - phi_dot * st)


def euler123_ddot(euler, euler_dot, w, w_dot) -> tuple:
    """d/dt of :func:`euler123_dot`: (φ̈, θ̈, ψ̈) from the angles, their rates and the body
    rates w and their derivative ẇ (differentiating φ̇ = u / cos θ with u = w_x cos ψ −
    w_y sin ψ, θ̇ = w_x sin ψ + w_y cos ψ, ψ̇ = w_z − φ̇ sin θ)::

        u̇ = ẇ_x cos ψ − ẇ_y sin ψ − ψ̇ θ̇
        φ̈ = u̇ / cos θ + φ̇ θ̇ tan θ,   θ̈ = ẇ_x sin ψ + ẇ_y cos ψ + ψ̇ u,
        ψ̈ = ẇ_z − φ̈ sin θ − φ̇ θ̇ cos θ

    At gimbal lock (φ̇ = 0 there) φ̈ = 0."""
    _, theta, psi = euler
    phi_dot, theta_dot, psi_dot = euler_dot
    cp, sp = math.cos(psi), math.sin(psi)
    ct, st = math.cos(theta), math.sin(theta)
    wx, wy, _ = w
    ax, ay, az = w_dot
    u = wx * cp - wy * sp
    phi_ddot = 0.0
    if abs(ct) > GIMBAL_LOCK_COS:
        phi_ddot = (ax * cp - ay * sp - psi_dot * theta_dot) / ct + phi_dot * theta_dot * st / ct
    theta_ddot = ax * sp + ay * cp + psi_dot * u
    return (phi_ddot, theta_ddot, az - phi_ddot * st - phi_dot * theta_dot * ct)


@jitable
def wrap_pi(angle: float) -> float:
    """Angle wrapped to [−π, π)."""
    return angle - 2 * math.pi * math.floor((angle + math.pi) / (2 * math.pi))


@jitable
def _distance(angles, reference) -> float:
    """Σ wrap_pi(a − r)² over three angles."""
    d0 = wrap_pi(angles[0] - reference[0])
    d1 = wrap_pi(angles[1] - reference[1])
    d2 = wrap_pi(angles[2] - reference[2])
    return d0 * d0 + d1 * d1 + d2 * d2


@jitable
def _unwrap3(angles, reference) -> tuple:
    """:func:`unwrap_near` of three angles."""
    return (
        reference[0] + wrap_pi(angles[0] - reference[0]),
        reference[1] + wrap_pi(angles[1] - reference[1]),
        reference[2] + wrap_pi(angles[2] - reference[2]),
    )


def unwrap_near(angles, reference) -> tuple:
    """Each angle shifted by a multiple of 2π to lie within π of its reference."""
    return tuple(r + wrap_pi(a - r) for a, r in zip(angles, _floats(reference)))
