"""What the sensor and estimator models share: their sample clock and small rotations.

Sample clock
------------
A sampled unit (star tracker, gyro, estimator) ticks at t_k = t0 + k / rate, k an integer
(negative before the start), counted from the model's start time t0, never accumulated.
The latest tick at or before t is k(t) = ⌊(t − t0) rate + ε⌋ with ε = :data:`TICK_TOLERANCE`
(a tick computed from a host's step counter as n h may fall a few ulps before the exact
time; ε = 1e-6 of a sample period).

Between communication points a model knows its inputs only at the two ends; at a tick
strictly inside a step it interpolates them linearly (:func:`lerp`), an attitude by the
shortest rotation between the two (:func:`slerp`), which is exact for a constant rate.

The Earth's radius and rotation rate are orbit_environment.py's (a test checks they agree).

Rotations
---------
``quat_exp(v)`` is the quaternion of the rotation vector v (angle |v| about v/|v|)::

    exp(v) = (cos(|v|/2), sin(|v|/2) v/|v|)

so that q_BI(t + h) = q_BI(t) ⊗ exp(w h) for a constant body rate w (DESIGN.md §2), and an
error rotation e in B axes acts as q ⊗ exp(e).  ``rotation_vector(q)`` is its inverse on
the short way round (angle ≤ π).
"""

from __future__ import annotations

import math

from .rotations import qmul
from .runtime.jit import jitable
from .vectors import cross, dot, norm, quat_norm

#: fraction of a sample period by which a time may fall short of a tick and still be it
TICK_TOLERANCE = 1e-6
#: Earth constants of orbit_environment.py (not imported here: its compiled kernels would be
#: packed into every sensor FMU): WGS-84 equatorial radius (m) and rotation rate (rad/s)
EARTH_RADIUS = 6378137.0
EARTH_RATE = 7.2921150e-5


@jitable
def tick(t: float, t0: float, rate: float) -> int:
    """Index k of the latest tick t_k = t0 + k / rate at or before t."""
    return math.floor((t - t0) * rate + TICK_TOLERANCE)


@jitable
def tick_time(k: int, t0: float, rate: float) -> float:
    return t0 + k / rate


@jitable
def lerp(a, b, s: float) -> tuple:
    """a + s (b − a), element by element, of 3-vectors."""
    return (a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2]))


@jitable
def quat_exp(v) -> tuple:
    """Quaternion of the rotation vector v."""
    vx, vy, vz = v
    angle = math.sqrt(vx * vx + vy * vy + vz * vz)
    if angle < 1e-8:  # series: sin(a/2)/a = 1/2 − a²/48, cos(a/2) = 1 − a²/8 (to a⁴ ≈ 1e-32)
        f, c = 0.5 - angle * angle / 48.0, 1.0 - angle * angle / 8.0
    else:
        f, c = math.sin(0.5 * angle) / angle, math.cos(0.5 * angle)
    return (c, f * vx, f * vy, f * vz)


@jitable
def rotation_vector(q) -> tuple:
    """Rotation vector (angle ≤ π) of the unit quaternion q (either sign)."""
    q0, q1, q2, q3 = q
    if q0 < 0.0:
        q0, q1, q2, q3 = -q0, -q1, -q2, -q3
    s = math.sqrt(q1 * q1 + q2 * q2 + q3 * q3)
    f = 2.0 * math.atan2(s, q0) / s if s > 0.0 else 2.0 / q0
    return (f * q1, f * q2, f * q3)


@jitable
def normalized(q) -> tuple:
    n = quat_norm(q)
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


@jitable
def conj(q) -> tuple:
    return (q[0], -q[1], -q[2], -q[3])


@jitable
def slerp(qa, qb, s: float) -> tuple:
    """The attitude a fraction s of the way from qa to qb (body-frame rotation
    qa* ⊗ qb taken the short way), with the sign of qa: qa ⊗ exp(s log(qa* ⊗ qb))."""
    v = rotation_vector(qmul(conj(qa), qb))
    return qmul(qa, quat_exp((s * v[0], s * v[1], s * v[2])))


@jitable
def angle_between(a, b) -> float:
    """Angle between two non-zero vectors, accurate at every angle (atan2 form)."""
    return math.atan2(norm(cross(a, b)), dot(a, b))
