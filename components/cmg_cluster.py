"""Cluster of six single-gimbal control-moment gyros ([Zhao 2016] §3.2).

Gyro i has gimbal axis g_i, reference spin s_i (its spin direction at δ_i = 0) and
transverse axis t_i = g_i × s_i.  Its rotor momentum relative to the body, in B, is
``h_rotor (s_i cos δ_i + t_i sin δ_i)``, so the cluster's (eq. 12 with δ counted from s_i)
and its body-frame derivative (eq. 13) are::

    h    = h_rotor Σ (s_i cos δ_i + t_i sin δ_i)
    hdot = h_rotor Σ a_i δ̇_i,   a_i = t_i cos δ_i − s_i sin δ_i   (Jacobian columns)
    Q    = det(A Aᵀ),           A = [a_1 … a_6]                   (singularity measure)

and the cluster exerts −hdot − w_BI_B × h on the body (DESIGN.md §2).

Gimbal servo: each gimbal rate follows its command, clipped to ±``rate_limit``, as fast
as ``accel_limit`` allows and exactly otherwise.  With the command held over a step the
motion is piecewise parabolic and is integrated in closed form (:func:`servo_step`); a
command a host interpolates with its derivative ċ (FMI 2.0 input derivatives,
components/model.py), c + ċ s, is followed in closed form too, piece by piece between the
moments the rate reaches the target or the command crosses a limit (:func:`servo_ramp`).

Rotor microvibration (DESIGN.md §3.2, components/imbalance.py): rotor i spins at
``rotor_speed`` Ω about σ_i with static and dynamic imbalance U_s,i, U_d,i, centred at
``rotor_position_B`` r_i, at angle φ_i = ``imbalance_phase0``_i + Ω t from its gimbal axis
g_i (u_i = g_i, v_i = σ_i × g_i; the gimbal carries them: ν_i = δ̇_i g_i).  The cluster
outputs the sums ``f_jitter_B`` = Σ U_s Ω² e_i, ``tau_jitter_B`` = Σ (U_d Ω² e_i + r_i × F_i)
and the imbalances' momentum ``h_jitter_B`` with its rate ``hdot_jitter_B``, all at the one
frequency ``jitter_frequency`` = Ω: a hub row for them (SatelliteDynamics ``h_extra``,
``h_extra_frequency``).  All zero without imbalance.

Output derivatives at the current time: δ̇; δ̈ (±accel_limit toward the target, or the
target's own slope once on it); ḣ; ḧ = h_rotor Σ (a_i δ̈_i − σ_i δ̇_i²) (ȧ_i = −σ_i δ̇_i);
Q̇ = tr(adj(A Aᵀ) d(A Aᵀ)/dt); the jitter's Ḟ, τ̇, ḣ_u, ḧ_u (components/imbalance.py).

Faults (DESIGN.md §3.2): gyro i's gimbal locks at ``fail_time[i]`` (inf: never) at the
angle it has then — the step that contains the time moves it until then — and holds it;
``healthy[i]`` is false from then on.  A locked gyro keeps its rotor's momentum in h; its
column leaves the torque Jacobian, so Q (and its rate) is that of the healthy gyros, the
measure of what the cluster can still deliver (CmgSteering steers the healthy ones).

Default geometry: the paper's five-pyramid cluster (α0 = 63.4°; gimbals 1–5 at azimuths
90°, 162°, 234°, 306°, 18°; gimbal 6 along z, reference spin x) with the rotor spin
*reversed* with respect to the printed A_s0: the paper's eq. (14) delivers +ḣ to the
body, which is physical only if the rotor momentum is −h(A_s cos δ + A_c sin δ); with the
printed spin the maneuver saturates the cluster (DESIGN.md §4.1).
"""

from __future__ import annotations

import math

import numpy as np

from .imbalance import rotor_imbalance
from .model import Model, ModelError
from .runtime.flat import put, state_table
from .runtime.jit import floats, jitable, output_kernel, step_kernel
from .variables import input_, output, parameter
from .vectors import (
    add,
    adjugate,
    det3,
    gram,
    mat_add,
    outer_sum,
    scale,
    total,
    trace_product,
)

N_GYROS = 6
#: rad/s: 6000 rpm, the speed of the Honeywell HR12 class of wheels (components/flywheel.py)
ROTOR_SPEED = 200.0 * math.pi
PYRAMID_HALF_ANGLE = math.radians(63.4)  # α0
PYRAMID_AZIMUTHS = np.radians([90.0, 162.0, 234.0, 306.0, 18.0])


def five_pyramid(alpha0: float = PYRAMID_HALF_ANGLE, azimuths=PYRAMID_AZIMUTHS):
    """Gimbal axes G and the paper's printed reference spins S (rows, 6×3).

    Gimbals 1–5 point from the pyramid's base vertices to its apex on +z:
    g = (−sin α0 cos az, −sin α0 sin az, cos α0), s = (cos α0 cos az, cos α0 sin az,
    sin α0); gimbal 6 is z with reference spin x.
    """
    c, s = math.cos(alpha0), math.sin(alpha0)
    G = np.array([[-s * math.cos(a), -s * math.sin(a), c] for a in azimuths] + [[0, 0, 1.0]])
    S = np.array([[c * math.cos(a), c * math.sin(a), s] for a in azimuths] + [[1.0, 0, 0]])
    return G, S


GIMBAL_AXES, _PRINTED_SPINS = five_pyramid()
DEFAULT_SPINS = -_PRINTED_SPINS  # the printed rotor spin reversed (DESIGN.md §4.1)


class ClusterGeometry:
    """h, Jacobian and singularity measure of a cluster, shared by cluster and steering.

    ``st`` holds, per gyro i, its reference spin s_i and transverse axis t_i at
    ``st[6i : 6i + 3]`` and ``st[6i + 3 : 6i + 6]``: what the kernels read.
    """

    def __init__(self, h_rotor: float, gimbal_axes, spins):
        G = np.asarray(gimbal_axes, dtype=float).reshape(N_GYROS, 3)
        S = np.asarray(spins, dtype=float).reshape(N_GYROS, 3)
        norms = np.linalg.norm(G, axis=1)
        if np.any(norms < 1e-9):
            raise ModelError(f"gimbal axes must be non-zero, got norms {norms}")
        G = G / norms[:, None]
        S = S - np.sum(S * G, axis=1)[:, None] * G  # spin must be perpendicular to gimbal
        spin_norms = np.linalg.norm(S, axis=1)
        if np.any(spin_norms < 1e-9):
            raise ModelError(
                "each reference spin must have a component perpendicular to its gimbal axis"
            )
        self.h_rotor = float(h_rotor)
        self.G = G
        self.S = S / spin_norms[:, None]
        self.T = np.cross(self.G, self.S)
        self.st = np.hstack([self.S, self.T]).reshape(-1)

    def axes(self, delta) -> tuple[list, list]:
        """(spins σ_i = s_i cos δ_i + t_i sin δ_i, Jacobian columns a_i = ∂σ_i/∂δ_i)."""
        return axes(np.asarray(delta, dtype=float).tolist(), self.st.tolist())

    def momentum(self, delta) -> np.ndarray:
        """h = h_rotor Σ σ_i."""
        return self.h_rotor * np.array(total(self.axes(delta)[0]))

    def spins(self, delta) -> np.ndarray:
        """σ_i as rows (6×3)."""
        return np.array(self.axes(delta)[0])

    def jacobian(self, delta) -> np.ndarray:
        """A (3×6) with columns a_i; hdot = h_rotor A δ̇."""
        return np.array(self.axes(delta)[1]).T

    @staticmethod
    def singularity(A) -> float:
        """Q = det(A Aᵀ): zero at a singular gimbal configuration."""
        return det3(gram(np.asarray(A).T.tolist()))


@jitable
def axes(delta, st) -> tuple[list, list]:
    """Spins σ_i = s_i cos δ_i + t_i sin δ_i and Jacobian columns a_i = ∂σ_i/∂δ_i of the
    gyros with reference spins and transverse axes ``st`` (s_i, t_i at 6i, 6i + 3)."""
    spins, columns = [], []
    for i in range(len(delta)):
        c, n = math.cos(delta[i]), math.sin(delta[i])
        s0, s1, s2, t0, t1, t2 = st[6 * i : 6 * i + 6]
        spins.append((s0 * c + t0 * n, s1 * c + t1 * n, s2 * c + t2 * n))
        columns.append((t0 * c - s0 * n, t1 * c - s1 * n, t2 * c - s2 * n))
    return spins, columns


def zero_momentum_angles(
    geometry: ClusterGeometry, delta, iterations: int = 300, gain: float = 0.05
) -> np.ndarray:
    """Gimbal angles near ``delta`` at which the cluster holds no momentum, moved along the
    null space toward the largest singularity measure Q (the best-conditioned such set)::

        δ ← δ − A⁺ Σσ_i + gain (1 − A⁺ A) ∇ ln Q,   ∂ ln Q/∂δ_i = −2 a_iᵀ (A Aᵀ)⁻¹ σ_i

    (∂a_i/∂δ_i = −σ_i), then Newton steps alone.  Returns angles wrapped to [−π, π);
    ModelError if |h| does not reach 1e-12 h_rotor."""
    d = np.array(delta, dtype=float)
    for k in range(iterations + 10):  # the last ten: Newton alone, to convergence
        spins, columns = (np.array(x) for x in geometry.axes(d))
        A = columns.T
        pinv = np.linalg.pinv(A)
        d = d - pinv @ spins.sum(axis=0)
        if k < iterations:
            grad = -2.0 * np.einsum("ij,jk,ik->i", columns, np.linalg.inv(A @ A.T), spins)
            d = d + gain * (np.eye(N_GYROS) - pinv @ A) @ grad
    d = np.remainder(d + math.pi, 2.0 * math.pi) - math.pi
    if not np.linalg.norm(geometry.momentum(d)) < 1e-12 * geometry.h_rotor:
        raise ModelError(f"no zero-momentum gimbal set found near {list(delta)}")
    return d


@jitable
def servo_step(delta, rate, command, dt, rate_limit, accel_limit) -> tuple[list, list]:
    """Gimbal angles and rates after ``dt`` with the rate command held (:func:`servo1`)."""
    angles, rates = [], []
    for d, r, c in zip(delta, rate, command):
        angle, speed = servo1(d, r, c, dt, rate_limit, accel_limit)
        angles.append(angle)
        rates.append(speed)
    return angles, rates


@jitable
def servo1(d, r, c, dt, rate_limit, accel_limit) -> tuple:
    """One gimbal's angle and rate after ``dt`` with the rate command ``c`` held.

    The rate moves toward clip(c, ±rate_limit) at ±accel_limit and then holds it:
    δ(dt) = δ + δ̇ dt + a τ (dt − τ/2), δ̇(dt) = δ̇ + a τ, with a = ±accel_limit and
    τ = min(|target − δ̇| / accel_limit, dt).
    """
    gap = min(max(c, -rate_limit), rate_limit) - r
    tau = min(abs(gap) / accel_limit, dt)
    a = accel_limit if gap > 0 else -accel_limit if gap < 0 else 0.0
    return d + r * dt + a * tau * (dt - tau / 2), r + a * tau


@jitable
def _target(c, m, s, rate_limit, dt) -> tuple:
    """The servo's target clip(c + m s', ±rate_limit) on its current piece, from ``s``:
    (value at s, slope, where the piece ends; at most dt)."""
    cs, end = c + m * s, dt
    if cs > rate_limit or (cs == rate_limit and m >= 0.0):
        if m < 0.0:
            end = (rate_limit - c) / m
        return rate_limit, 0.0, min(end, dt)
    if cs < -rate_limit or (cs == -rate_limit and m <= 0.0):
        if m > 0.0:
            end = (-rate_limit - c) / m
        return -rate_limit, 0.0, min(end, dt)
    if m > 0.0:
        end = (rate_limit - c) / m
    elif m < 0.0:
        end = (-rate_limit - c) / m
    return cs, m, min(end, dt)


@jitable
def servo_accel(r, c, m, rate_limit, accel_limit) -> float:
    """δ̈ now, at rate ``r`` with the command c + m s: ±accel_limit toward the target, or
    the target's slope (within ±accel_limit) once the rate is on it."""
    target, slope, _ = _target(c, m, 0.0, rate_limit, 1.0)
    if target != r:
        return accel_limit if target > r else -accel_limit
    return min(max(slope, -accel_limit), accel_limit)


@jitable
def servo_ramp(d, r, c, m, dt, rate_limit, accel_limit) -> tuple:
    """One gimbal's angle and rate after ``dt`` with the rate command c + m s (s from the
    step's start): on each piece of the clipped target (value g, slope k) the rate either
    rides on it (|k| ≤ accel_limit) or moves at ±accel_limit toward it, until it reaches
    it or the piece ends; every part is parabolic in δ and integrated exactly."""
    s, on = 0.0, False  # on: the rate has reached the target and rides on it
    for _ in range(16):  # at most 3 pieces of the target, 2 parts each
        if not s < dt:
            break
        g, k, end = _target(c, m, s, rate_limit, dt)
        span = max(end - s, 0.0)
        if span == 0.0:  # the piece ends here (rounding): step past it
            span = min(dt - s, 1e-12 * dt)
        if on:
            r = g  # the same value, up to the rounding of c + m s
        gap = g - r
        if gap == 0.0 and abs(k) <= accel_limit:
            d += r * span + 0.5 * k * span * span
            r, s, on = g + k * span, s + span, True
            continue
        a = accel_limit if gap > 0.0 or (gap == 0.0 and k > 0.0) else -accel_limit
        tau, closing, on = span, k - a, False  # the gap changes at k − a
        if gap != 0.0 and gap * closing < 0.0 and -gap / closing < span:
            tau, on = -gap / closing, True
        d += r * tau + 0.5 * a * tau * tau
        r = g + k * tau if on else r + a * tau
        s += tau
    return d, r


class CmgCluster(Model):
    """Six single-gimbal CMGs with rate- and acceleration-limited gimbals."""

    INTERPOLATES_INPUTS = True
    OUTPUT_DERIVATIVES = True

    VARIABLES = (
        parameter("h_rotor", 16.65, "N.m.s", "rotor angular momentum of each gyro"),
        parameter(
            "gimbal_axis",
            GIMBAL_AXES,
            "1",
            "gimbal axis of each gyro in B (rows; five-pyramid default)",
            shape=(6, 3),
        ),
        parameter(
            "spin_ref",
            DEFAULT_SPINS,
            "1",
            "rotor spin direction of each gyro at zero gimbal angle, in B (rows; "
            "default: the paper's A_s0 spin reversed)",
            shape=(6, 3),
        ),
        parameter(
            "delta0",
            (math.pi / 4, 0.0, -math.pi / 4, math.pi / 2, math.pi / 4, 0.0),
            "rad",
            "initial gimbal angles",
            shape=(6,),
            display_unit="deg",
        ),
        parameter("rate_limit", 0.6, "rad/s", "gimbal rate limit", display_unit="deg/s"),
        parameter("accel_limit", 0.5, "rad/s2", "gimbal acceleration limit", display_unit="deg/s2"),
        parameter(
            "fail_time",
            math.inf,
            "s",
            "time each gimbal locks at its angle (inf: never)",
            shape=(N_GYROS,),
        ),
        parameter(
            "static_imbalance", 0.0, "kg.m", "static imbalance U_s of each rotor", shape=(6,)
        ),
        parameter(
            "dynamic_imbalance", 0.0, "kg.m2", "dynamic imbalance U_d of each rotor", shape=(6,)
        ),
        parameter(
            "rotor_position_B",
            0.0,
            "m",
            "centre of each rotor from the centre of mass, in B (rows)",
            shape=(6, 3),
        ),
        parameter("rotor_speed", ROTOR_SPEED, "rad/s", "rotor spin rate", display_unit="rpm"),
        parameter(
            "imbalance_phase0",
            0.0,
            "rad",
            "angle of each rotor's imbalance from its gimbal axis at t = 0",
            shape=(6,),
            display_unit="deg",
        ),
        input_(
            "delta_dot_cmd", "rad/s", "commanded gimbal rates", shape=(6,), display_unit="deg/s"
        ),
        output("delta", "rad", "gimbal angles", shape=(6,), display_unit="deg"),
        output("delta_dot", "rad/s", "gimbal rates", shape=(6,), display_unit="deg/s"),
        output("h", "N.m.s", "cluster angular momentum relative to the body, in B", shape=(3,)),
        output("hdot", "N.m", "time derivative of h as seen in B", shape=(3,), derivative_of="h"),
        output("singularity", "1", "singularity measure Q = det(A A^T) of the healthy gyros"),
        output(
            "healthy", "1", "each gimbal is free (not locked)", shape=(N_GYROS,), type="Boolean"
        ),
        output("f_jitter_B", "N", "force of the rotors' imbalances on the body, in B", shape=(3,)),
        output(
            "tau_jitter_B",
            "N.m",
            "torque of the rotors' imbalances on the body about the centre of mass, in B",
            shape=(3,),
        ),
        output(
            "h_jitter_B",
            "N.m.s",
            "angular momentum of the rotors' imbalances relative to the body, in B",
            shape=(3,),
        ),
        output(
            "hdot_jitter_B",
            "N.m",
            "time derivative of h_jitter_B as seen in B",
            shape=(3,),
            derivative_of="h_jitter_B",
        ),
        output("jitter_frequency", "rad/s", "frequency of the jitter outputs (the rotor speed)"),
    )

    def initialize(self, t0):
        p = self.p
        if not (p.rate_limit > 0 and p.accel_limit > 0):
            raise ModelError(
                f"rate_limit ({p.rate_limit}) and accel_limit ({p.accel_limit}) must be positive"
            )
        self.geometry = ClusterGeometry(p.h_rotor, p.gimbal_axis, p.spin_ref)
        self.state = S.zeros()
        self.state[S.st : S.st + 6 * N_GYROS] = self.geometry.st
        self.state[[S.h_rotor, S.rate_limit, S.accel_limit]] = (
            p.h_rotor,
            p.rate_limit,
            p.accel_limit,
        )
        self.state[S.delta : S.delta + N_GYROS] = p.delta0
        if np.any(np.isnan(p.fail_time)):
            raise ModelError(f"fail_time must be a time or inf, got {p.fail_time.tolist()}")
        self.state[S.fail : S.fail + N_GYROS] = p.fail_time
        if np.any(p.static_imbalance != 0.0) or np.any(p.dynamic_imbalance != 0.0):
            self.state[S.jitter] = 1.0
            put(self.state, S.us, p.static_imbalance)
            put(self.state, S.ud, p.dynamic_imbalance)
            put(self.state, S.r, p.rotor_position_B.reshape(-1))
            put(self.state, S.phase0, p.imbalance_phase0)
            put(self.state, S.g, self.geometry.G.reshape(-1))
        self.state[S.speed] = p.rotor_speed
        self.t = t0

    def step(self, t, dt):
        gimbal = cluster_step(self.values, self.state, self.t, dt)
        if gimbal:
            command = float(self.values[U.delta_dot_cmd + gimbal - 1])
            self.warnings.append(
                f"t={t:.3f} s: gimbal {gimbal} rate command {command:.3f} rad/s "
                f"exceeds the rate limit {float(self.state[S.rate_limit])} rad/s (the cluster "
                "cannot deliver the commanded torque)"
            )
        self.t = t + dt

    def output(self):
        cluster_output(self.values, self.state, self.t)

    def output_derivatives(self):
        """See the module docstring: d/dt of δ, δ̇, h, ḣ and Q at ``self.t``
        (:func:`cluster_rates`, on the kernels' own functions)."""
        return np.array(cluster_rates(self.values.tolist(), self.state.tolist(), self.t))


# -- kernels (components/runtime/jit.py) ----------------------------------------------
P, U, Y = CmgCluster.names()
DU, _ = CmgCluster.derivative_names()  # DU.delta_dot_cmd: the command's slope a host set
#: the state array: δ and δ̇, the constants, s_i and t_i of each gyro (ClusterGeometry.st),
#: 1 while a rate command exceeds the rate limit (saturated); the gimbals' fail times before
#: the axes; for the rotors' imbalance: Ω, 1 if any, and (read only then) U_s, U_d, r (rows),
#: φ0 and the gimbal axes
S = state_table(
    "CmgCluster state", delta=N_GYROS, rate=N_GYROS, rate_limit=1, accel_limit=1, h_rotor=1,
    fail=N_GYROS, speed=1, jitter=1, st=6 * N_GYROS, saturated=1, us=N_GYROS, ud=N_GYROS,
    r=3 * N_GYROS, phase0=N_GYROS, g=3 * N_GYROS,
)  # fmt: skip


@step_kernel(CmgCluster)
def cluster_step(values, state, t, dt):
    """Each gimbal's :func:`servo_step` over ``dt`` with its command held, or its
    :func:`servo_ramp` where a host set the command's derivative.  The cluster is
    saturated while the largest |command| at the step's start exceeds the rate limit (it
    cannot deliver the commanded torque): returns 1 + the gimbal with the largest |command|
    (the first of equals) when it becomes saturated (step() warns), else 0.  A gimbal whose
    fail time falls in the step moves until then and is locked after (zero rate)."""
    command, s = floats(values[U.delta_dot_cmd : U.delta_dot_cmd + N_GYROS]), floats(state[: S.st])
    slope = floats(values[DU.delta_dot_cmd : DU.delta_dot_cmd + N_GYROS])
    delta, rate = s[S.delta : S.delta + N_GYROS], s[S.rate : S.rate + N_GYROS]
    limit, accel = s[S.rate_limit], s[S.accel_limit]
    angles, rates = servo_step(delta, rate, command, dt, limit, accel)
    for i in range(N_GYROS):
        if slope[i] != 0.0:
            angles[i], rates[i] = servo_ramp(
                delta[i], rate[i], command[i], slope[i], dt, limit, accel
            )
        fail = s[S.fail + i]
        if fail < t + dt:  # locked at its angle at fail_time (moving until then)
            moving = min(dt, max(0.0, fail - t))
            if slope[i] != 0.0:
                angle = servo_ramp(delta[i], rate[i], command[i], slope[i], moving, limit, accel)
            else:
                angle = servo1(delta[i], rate[i], command[i], moving, limit, accel)
            angles[i], rates[i] = angle[0], 0.0
    state[S.delta : S.delta + N_GYROS] = angles
    state[S.rate : S.rate + N_GYROS] = rates
    worst, largest = 0, -1.0  # over the gimbals free throughout the step
    for i in range(N_GYROS):
        if abs(command[i]) > largest and s[S.fail + i] >= t + dt:
            worst, largest = i, abs(command[i])
    saturated = largest > s[S.rate_limit]
    started = saturated and state[S.saturated] == 0.0
    state[S.saturated] = 1.0 if saturated else 0.0
    return worst + 1 if started else 0


@output_kernel(CmgCluster)
def cluster_output(values, state, t):
    """δ, δ̇, h = h_rotor Σ σ_i, hdot = h_rotor Σ a_i δ̇_i and Q = det(A Aᵀ) (module doc)."""
    s = floats(state[: S.us])
    delta, rates = s[S.delta : S.delta + N_GYROS], s[S.rate : S.rate + N_GYROS]
    spins, columns = axes(delta, s[S.st : S.st + 6 * N_GYROS])
    h = total(spins)
    hdot = total([(a[0] * r, a[1] * r, a[2] * r) for a, r in zip(columns, rates)])
    h_rotor = s[S.h_rotor]
    values[Y.delta : Y.delta + N_GYROS] = delta
    values[Y.delta_dot : Y.delta_dot + N_GYROS] = rates
    for k in range(3):
        values[Y.h + k], values[Y.hdot + k] = h_rotor * h[k], h_rotor * hdot[k]
    for i in range(N_GYROS):
        values[Y.healthy + i] = 1.0 if t < s[S.fail + i] else 0.0
    free = healthy_columns(columns, values[Y.healthy : Y.healthy + N_GYROS])
    values[Y.singularity] = det3(gram(free))
    values[Y.jitter_frequency] = s[S.speed]
    if s[S.jitter] != 0.0:
        jitter = _jitter(floats(state), t, spins, rates, (0.0, 0.0, 0.0, 0.0, 0.0, 0.0))
        for k in range(3):
            values[Y.f_jitter_B + k], values[Y.tau_jitter_B + k] = jitter[3][k], jitter[5][k]
            values[Y.h_jitter_B + k], values[Y.hdot_jitter_B + k] = jitter[0][k], jitter[1][k]
    return 0


@jitable
def _jitter(s, t, spins, rates, accels) -> list:
    """Σ over the rotors of :func:`.imbalance.rotor_imbalance` (h_u, ḣ_u, ḧ_u, F, Ḟ, τ, τ̇)
    at time t, the gimbals at spins σ_i, rates δ̇_i and accelerations δ̈_i."""
    speed = s[S.speed]
    sums = [(0.0, 0.0, 0.0) for _ in range(7)]
    for i in range(N_GYROS):
        g = (s[S.g + 3 * i], s[S.g + 3 * i + 1], s[S.g + 3 * i + 2])
        r = (s[S.r + 3 * i], s[S.r + 3 * i + 1], s[S.r + 3 * i + 2])
        parts = rotor_imbalance(
            s[S.us + i], s[S.ud + i], r, spins[i], g, speed, 0.0, s[S.phase0 + i] + speed * t,
            scale(rates[i], g), scale(accels[i], g),
        )  # fmt: skip
        for k in range(7):
            sums[k] = add(sums[k], parts[k])
    return sums


@jitable
def healthy_columns(columns, healthy) -> list:
    """The Jacobian columns a_i of the healthy gyros, zero for the others."""
    return [a if healthy[i] != 0.0 else (0.0, 0.0, 0.0) for i, a in enumerate(columns)]


@jitable
def cluster_rates(v, s, t) -> list:
    """d/dt of the outputs at the model's time ``t``, in the table's order (module
    docstring): δ̇; δ̈ (:func:`servo_accel`); ḣ as :func:`cluster_output` wrote it;
    ḧ = h_rotor Σ (a_i δ̈_i + ȧ_i δ̇_i) with ȧ_i = −σ_i δ̇_i; Q̇ = tr(adj(G) Ġ) with
    G = Σ a_i a_iᵀ, the Gram matrix of Q = det G, and Ġ = Σ (ȧ_i a_iᵀ + a_i ȧ_iᵀ); the
    jitter's Ḟ, τ̇, ḣ_u and ḧ_u (:func:`_jitter`), and 0 for its constant frequency."""
    rates = s[S.rate : S.rate + N_GYROS]
    limit, accel, h_rotor = s[S.rate_limit], s[S.accel_limit], s[S.h_rotor]
    accels = [
        servo_accel(rates[i], v[U.delta_dot_cmd + i], v[DU.delta_dot_cmd + i], limit, accel)
        if v[Y.healthy + i] != 0.0
        else 0.0
        for i in range(N_GYROS)
    ]
    spins, columns = axes(s[S.delta : S.delta + N_GYROS], s[S.st : S.st + 6 * N_GYROS])
    a_dots = [scale(-rates[i], spins[i]) for i in range(N_GYROS)]
    hddot = scale(
        h_rotor,
        add(
            total([scale(accels[i], columns[i]) for i in range(N_GYROS)]),
            total([scale(rates[i], a_dots[i]) for i in range(N_GYROS)]),
        ),
    )
    free = healthy_columns(columns, v[Y.healthy : Y.healthy + N_GYROS])
    gram_dot = mat_add(outer_sum(a_dots, free), outer_sum(free, a_dots))
    q_dot = trace_product(adjugate(gram(free)), gram_dot)
    hdot = (v[Y.hdot], v[Y.hdot + 1], v[Y.hdot + 2])
    jitter = [(0.0, 0.0, 0.0) for _ in range(7)]
    if s[S.jitter] != 0.0:
        jitter = _jitter(s, t, spins, rates, accels)
    return [
        *rates, *accels, *hdot, *hddot, q_dot, *[0.0] * N_GYROS,  # healthy: held
        *jitter[4], *jitter[6], *jitter[1], *jitter[2], 0.0,
    ]  # fmt: skip
