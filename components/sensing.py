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

Reusing the advanced section
----------------------------
A sampled model's state holds a committed section (the model at its time) and an advanced
one: the committed section brought to a time ``now`` with the inputs of ``now`` (its
``advance``), which the output shows.  A step from ``now`` advances the committed section to
``now`` again and commits the result: when the output was evaluated at ``now`` with the same
inputs, that result is already there.  A stamp at the end of the state says when:
``advance`` clears it as it starts and writes it as it ends (:func:`stamp`: ``now``, the
status, a copy of the inputs it read, spans of the value array); a commit clears it (the
advanced section then no longer comes from the committed one).  :func:`reused` gives the
status of the advanced section when the stamp is set and its time and every input are
those of the call bit for bit (:func:`same`: −0.0 is not 0.0, a NaN never the same), and
the step commits the section as it is.  The bits are those of advancing again: ``advance``
is a function of the committed section, the constants, the parameters (fixed after
initialisation, which zeroes the state), the inputs it reads and ``now``; an FMU state
saves and restores the stamp with the sections.

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
from .runtime.flat import state_table
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


#: a stamp (module docstring): 1 when set, the time and status of the advanced section, then
#: the inputs it was made with
STAMP = state_table("stamp of the advanced section", made=1, now=1, status=1)


def stamp_size(spans) -> int:
    """The length of a stamp of the inputs values[start:stop] for (start, stop) in spans."""
    return STAMP.size + sum(stop - start for start, stop in spans)


@jitable
def same(a: float, b: float) -> bool:
    """a and b the same double, bit for bit (a NaN never is)."""
    return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)


@jitable
def stamp(values, state, at: int, spans, now: float, status: int) -> None:
    """The advanced section made at ``now``, with status ``status``, from the inputs
    values[start:stop] of ``spans`` (the stamp at state[at:])."""
    state[at + STAMP.made], state[at + STAMP.now], state[at + STAMP.status] = 1.0, now, status
    k = at + STAMP.size
    for start, stop in spans:
        for i in range(start, stop):
            state[k] = values[i]
            k += 1


@jitable
def unstamp(state, at: int) -> None:
    """The advanced section no longer known to come from the committed one."""
    state[at + STAMP.made] = 0.0


@jitable
def reused(values, state, at: int, spans, now: float) -> int:
    """The status of the advanced section if it was made at ``now`` from the committed one
    with the inputs the value array holds, bit for bit; else −1 (advance it again)."""
    if state[at + STAMP.made] == 0.0 or not same(state[at + STAMP.now], now):
        return -1
    k = at + STAMP.size
    for start, stop in spans:
        for i in range(start, stop):
            if not same(values[i], state[k]):
                return -1
            k += 1
    return int(state[at + STAMP.status])
