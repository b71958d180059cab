r"""Independent monolithic reference of the ``payload_sweep`` scenario as a sampled-data system.

Written from DESIGN.md §2 and §4.2, [Chang 2015] §1 and the equations below; it imports nothing
from ``components/``, ``fmus/`` or ``orchestration/``.  From tests/tools/reference/scan_pitch.py it
takes the quaternion helpers and the closed form of the circular orbit frame (both tested
there), with this scenario's radius and inclination.  Conventions as there (scalar-first
Hamilton quaternions, ``v_X = C(q_XY) v_Y``, passive elementary rotations R1, R2, R3).

Orbit (the scenario's OrbitEnvironment: circular two-body, a = 6378137 + 500e3 m,
i = 97.40°, RAAN = ω = ν0 = 0, no J2)
------------------------------------------------------------------------------------------
``n = √(μ/a³)``, ``q_OI(t) = q1(i) ⊗ q3(n t) ⊗ q(M0)``, ``w_OI_O = (0, −n, 0)``.

Payloads (motion prescribed by the sweep, ideal tracking)
---------------------------------------------------------
One sweep axis (amplitude A, rate r, reversal time τ): between the turning points ±A the rate
is ∓r; each reversal ramps the rate linearly through zero in τ, centred on the turning point,
so the period is ``T = 4A/r + τ``; t = 0 is the upper turning point (at rest at +A, moving
toward −A).  With s = t mod T in the first half period (the second mirrors it, f(s) = −f(s − T/2))::

    0 ≤ s < τ/2:           angle = A − r s²/τ,      rate = −2 r s/τ,  accel = −2r/τ
    τ/2 ≤ s < T/2 − τ/2:   angle = A + rτ/4 − r s,  rate = −r,        accel = 0
    T/2 − τ/2 ≤ s < T/2:   angle = −A + r w²/τ,     rate = −2 r w/τ,  accel = +2r/τ   (w = T/2 − s)

(each segment half-open: a sample on a boundary takes the later segment; see ``EDGE``).
Payload 1: roll φ (A = 15°, r = 6 °/s) and pitch θ (A = 45°, r = 0.6 °/s), τ = 1 s;
payload 2 at (−φ, −θ).  Each payload (J_p = diag(45.5, 35.8, 36.7) kg m², gimbal axes
through its centre of mass) has, with ``R_mb = R2(θ) R1(φ)`` (B → payload axes)::

    Ω = (φ̇ cos θ, θ̇, φ̇ sin θ),   Ω̇ = (φ̈ cos θ − φ̇θ̇ sin θ, θ̈, φ̈ sin θ + φ̇θ̇ cos θ)
    h_b = R_mbᵀ J_p Ω,            ḣ_b = R_mbᵀ (J_p Ω̇ + Ω × J_p Ω)          (as seen in B)

and h_p = h_b1 + h_b2, computed here for each payload with the matrices; the symmetric pair's
closed form h_p = (0, 0, 2 [Jy θ̇ sin φ + (Jz − Jx) φ̇ sin θ cos θ cos φ]) is a check
(tests/orchestration/cosim/test_coupling.py).

Wheels (three, spin axes x, y, z; HR12: J_w = 12/(200π) kg m², c_v = 1e-5 N m s/rad,
c_c = 5e-4 N m, motor limit 0.2 N m, start at rest)
-----------------------------------------------------------------------------------
``J_w Ω̇_i = m_i − c_v Ω_i − c_c sgn Ω_i``; at rest a wheel stays at rest while |m_i| ≤ c_c and
breaks away with the sign of m_i.  For a held m the solution is exact: between zero crossings
``Ω(s) = Ω + (b − c_v Ω) φ(s)/J_w``, ``b = m − c_c sgn``, ``φ(s) = (1 − e^{−k s})/k``,
``k = c_v/J_w``; a wheel moving toward zero reaches it at ``φ* = −J_w Ω/(b − c_v Ω)`` (when
b has the opposite sign of Ω), then sticks or restarts.  ``h_w = J_w Ω``.  The momentum
limit (12 N m s) is not modelled: the run stops with an error if a wheel reaches it.

Wheel drive, sampled at ``drive_period`` with zero-order hold (a drive electronics computing
motor torques; the Flywheel model computes them at its communication points, so the
co-simulation's system has drive_period = the Flywheel's step)::

    ḣ_req = −τ_cmd − w_BI_B × h_w,   m_i = clip(ḣ_req,i + c_v Ω_i + c_c σ_i, ±0.2)

σ_i = sgn Ω_i, or at rest sgn ḣ_req,i: within the limit the wheels deliver τ_cmd at the sample.

Hub (J = 150·1 kg m², payloads included; no external torque: J ∝ 1, so the gravity-gradient
torque vanishes)
--------------------------------------------------------------------------------------------
States q_BI and the total momentum H_I (constant): ``w_BI_B = J⁻¹ (C_BI H_I − h_w − h_p)``.

Controller, sampled at ``control_period`` with zero-order hold (AttitudeController, holding
the orbit frame R = O; kp = J ω_n² = 6, kd = 2 ζ ω_n J = 42.43, ω_n = 0.2 rad/s, ζ = 1/√2)
---------------------------------------------------------------------------------------------
``q_BR = q_OI* ⊗ q_BI`` (sign with q0 ≥ 0), ``e = 2 atan2(|q_v|, q0) q_v/|q_v|``,
``r = w_BI_B − C(q_BR) w_OI_O``, ``τ_cmd = −kp e − kd r + ḣ_p + w_BI_B × h_p``.

The feedforward (h_p, ḣ_p at the samples) is the closed form above.  At a sample exactly on
a kink of the sweep ḣ_p jumps, and the value held over the next period is its right limit (the
later segment, as the SweepPlanner's docstring defines the segments); a sample within ``EDGE``
of a kink counts as on it, since a floating-point grid n H lands on t = 150 s, 300.5 s, 451 s
(the pitch reversals) only up to rounding.

Initial state: at rest relative to O (attitude0 = rate0 = 0): q_BI(0) = q_OI(0),
w_BI_B(0) = (0, −n, 0); h_w = 0; h_p(0) = 0; ``H_I = C_BIᵀ (J w + h_w + h_p)``.

Integration ("monolithic")
--------------------------
One loop, step ``h``, ``t_k = k h`` (integer counter).  At t_k: the controller when k is a
multiple of control_period/h, the drive when k is a multiple of drive_period/h (both held);
the wheels advance exactly to h/2 and h; ``q_BI`` by classical RK4 whose stages take h_w from
the exact wheel speeds and h_p from the closed form at the stage times (0, h/2, h/2, h);
``H_I`` is constant; ``q_BI`` normalised after each step.  The only discretisation is RK4
(the commands are sampled on the grid by definition, and every kink of the payload motion
lies on a 0.5 s grid, hence on the step grid of the usual steps): O(h⁴), except that a wheel
speed crossing zero inside a step (the Coulomb torque flips there, a kink in h_w) leaves an
O(h²) term with a small constant.  Measured (P = 0.05 s, drive at 0.01 s, 600 s): the step
2.5 ms against 1.25 ms moves the attitude by 2.6e-10° (tests/tools/benchmark_coupling.py).
"""

from __future__ import annotations

import math

import numpy as np

from .scan_pitch import MU, Q_M0, dcm, hub_qdot, qconj, qmul, rot

# --- constants (the scenario's parameters and the FMUs' defaults it keeps) ------------------------
DEG = math.pi / 180.0
A_ORBIT = 6378137.0 + 500e3
N_ORBIT = math.sqrt(MU / A_ORBIT**3)
INCLINATION = 97.40 * DEG
W_OI_O = (0.0, -N_ORBIT, 0.0)

J_HUB = 150.0
J_PAYLOAD = (45.5, 35.8, 36.7)
ROLL = (15 * DEG, 6 * DEG)  # amplitude, rate
PITCH = (45 * DEG, 0.6 * DEG)
TURNAROUND = 1.0

J_WHEEL = 12.0 / (6000.0 * 2.0 * math.pi / 60.0)
VISCOUS = 1e-5
COULOMB = 5e-4
TORQUE_LIMIT = 0.2
MOMENTUM_LIMIT = 12.0

KP = J_HUB * 0.2**2
KD = 2.0 / math.sqrt(2.0) * 0.2 * J_HUB

#: a sample closer than this (s) before a segment boundary of the sweep takes the later segment
#: (t mod T rounds: 4A/r = 10.999999999999998 s for the roll)
EDGE = 1e-9


# --- orbit ----------------------------------------------------------------------------------------
_CI2, _SI2 = math.cos(0.5 * INCLINATION), math.sin(0.5 * INCLINATION)


def q_oi(t: float) -> tuple:
    """q_OI(t) = q1(i) ⊗ q3(n t) ⊗ q(M0) (tests/tools/reference/scan_pitch.py's closed form)."""
    cu, su = math.cos(0.5 * N_ORBIT * t), math.sin(0.5 * N_ORBIT * t)
    return qmul((_CI2 * cu, _SI2 * cu, -_SI2 * su, _CI2 * su), Q_M0)


def orbit_rv(t: float):
    """Inertial position and velocity (RAAN = 0, u = n t), for the check of q_oi."""
    u = N_ORBIT * t
    ci, si = math.cos(INCLINATION), math.sin(INCLINATION)
    r = A_ORBIT * np.array([math.cos(u), math.sin(u) * ci, math.sin(u) * si])
    v = A_ORBIT * N_ORBIT * np.array([-math.sin(u), math.cos(u) * ci, math.cos(u) * si])
    return r, v


# --- payloads -------------------------------------------------------------------------------------
def sweep(t, amplitude: float, rate: float, turnaround: float = TURNAROUND):
    """(angle, rate, acceleration) of one sweep axis at the times t (array)."""
    t = np.asarray(t, dtype=float)
    A, r, tau = amplitude, rate, turnaround
    period = 4.0 * A / r + tau
    half = 0.5 * period
    sc = np.mod(t + EDGE, period)  # classified EDGE late: a boundary sample takes the later segment
    upper = sc < half  # first half period (descending from +A)
    sign = np.where(upper, 1.0, -1.0)
    sc = np.where(upper, sc, sc - half)
    s = sc - EDGE
    w = half - s
    leaving = sc < 0.5 * tau
    arriving = ~leaving & (sc >= half - 0.5 * tau)
    cruise = A + 0.25 * r * tau - r * s
    angle = np.where(leaving, A - r * s * s / tau, np.where(arriving, -A + r * w * w / tau, cruise))
    rate_ = np.where(leaving, -2.0 * r * s / tau, np.where(arriving, -2.0 * r * w / tau, -r))
    accel = np.where(leaving, -2.0 * r / tau, np.where(arriving, 2.0 * r / tau, 0.0))
    return sign * angle, sign * rate_, sign * accel


def payload_pair(t):
    """(h_p, ḣ_p) of the symmetric pair at the times t, in B: arrays (N, 3)."""
    phi, dphi, ddphi = sweep(t, *ROLL)
    theta, dtheta, ddtheta = sweep(t, *PITCH)
    h = np.zeros((phi.size, 3))
    hdot = np.zeros((phi.size, 3))
    J = np.array(J_PAYLOAD)
    for k in (1.0, -1.0):  # payload 1, payload 2 = −payload 1
        f, df, ddf = k * phi, k * dphi, k * ddphi
        g, dg, ddg = k * theta, k * dtheta, k * ddtheta
        cg, sg = np.cos(g), np.sin(g)
        omega = np.stack([df * cg, dg, df * sg], axis=1)
        omega_dot = np.stack([ddf * cg - df * dg * sg, ddg, ddf * sg + df * dg * cg], axis=1)
        Jw = J * omega
        d = J * omega_dot + np.cross(omega, Jw)
        R_mb = np.einsum("nij,njk->nik", _rotations(2, g), _rotations(1, f))
        h += np.einsum("nji,nj->ni", R_mb, Jw)  # R_mbᵀ J Ω
        hdot += np.einsum("nji,nj->ni", R_mb, d)
    return h, hdot


def _rotations(axis: int, a) -> np.ndarray:
    """R1/R2(a) (passive, as scan_pitch.R) for each element of a: (N, 3, 3)."""
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((a.size, 3, 3))
    i, j = (1, 2) if axis == 1 else (2, 0)  # R1: (y, z) plane; R2: (z, x) plane
    out[:, axis - 1, axis - 1] = 1.0
    out[:, i, i] = out[:, j, j] = c
    out[:, i, j] = s
    out[:, j, i] = -s
    return out


# --- wheels ---------------------------------------------------------------------------------------
_K = VISCOUS / J_WHEEL


def wheel_speed(omega: float, m: float, tau: float) -> float:
    """Exact wheel speed after time tau with the motor torque m held (see the module notes)."""
    remaining = tau
    for _ in range(2):  # at most: run down to rest, then one regime from rest
        if omega == 0.0:
            if abs(m) <= COULOMB:
                return 0.0
            sgn = 1.0 if m > 0.0 else -1.0
        else:
            sgn = 1.0 if omega > 0.0 else -1.0
        drive = m - COULOMB * sgn - VISCOUS * omega  # J_w Ω̇ at the start of the regime
        phi = -math.expm1(-_K * remaining) / _K
        if omega != 0.0 and (m - COULOMB * sgn) * sgn < 0.0:  # its asymptote beyond rest
            phi_zero = -J_WHEEL * omega / drive
            if phi_zero <= phi:  # reaches rest within the remaining time
                remaining += math.log1p(-_K * phi_zero) / _K
                omega = 0.0
                continue
        return omega + drive * phi / J_WHEEL
    return omega


def motor_torques(tau_cmd, w, omega) -> list[float]:
    """The drive: m_i = clip(ḣ_req,i + c_v Ω_i + c_c σ_i, ±limit), ḣ_req = −τ_cmd − w × h_w."""
    hx, hy, hz = (J_WHEEL * x for x in omega)
    wx, wy, wz = w
    req = (
        -tau_cmd[0] - (wy * hz - wz * hy),
        -tau_cmd[1] - (wz * hx - wx * hz),
        -tau_cmd[2] - (wx * hy - wy * hx),
    )
    out = []
    for n, o in zip(req, omega):
        sigma = (o > 0.0) - (o < 0.0) if o != 0.0 else (n > 0.0) - (n < 0.0)
        m = n + VISCOUS * o + COULOMB * sigma
        out.append(max(-TORQUE_LIMIT, min(TORQUE_LIMIT, m)))
    return out


# --- controller -----------------------------------------------------------------------------------
def control(q_bi, w, t: float, h_p, hdot_p) -> tuple:
    """(τ_cmd, att_error, rate_error): the quaternion PD holding O, the payload feedforward."""
    q = qmul(qconj(q_oi(t)), q_bi)  # q_BR = q_BO
    if q[0] < 0.0:
        q = tuple(-x for x in q)
    s = math.sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    f = 2.0 * math.atan2(s, q[0]) / s if s > 0.0 else 2.0
    e = (f * q[1], f * q[2], f * q[3])
    wr = rot(q, W_OI_O)
    r = tuple(w[i] - wr[i] for i in range(3))
    hx, hy, hz = h_p
    gyro = (w[1] * hz - w[2] * hy, w[2] * hx - w[0] * hz, w[0] * hy - w[1] * hx)
    tau = tuple(-KP * e[i] - KD * r[i] + hdot_p[i] + gyro[i] for i in range(3))
    return tau, e, r


# --- the monolithic simulation --------------------------------------------------------------------
def _every(period, step: float, name: str) -> int:
    m = 1 if period is None else int(round(period / step))
    if m < 1 or abs(m * step - (period or step)) > 1e-9 * step:
        raise ValueError(f"{name}={period} is not a multiple of step={step}")
    return m


def simulate(
    step: float,
    stop: float = 600.0,
    control_period: float | None = None,
    drive_period: float | None = None,
) -> dict[str, np.ndarray]:
    """Run the monolithic reference with step ``step`` up to ``stop``; samples at t = k·step.

    ``control_period`` and ``drive_period`` (integer multiples of ``step``; default ``step``):
    the controller and the wheel drive are sampled only at their multiples and their commands
    (τ_cmd; the motor torques) held in between, while the plant (hub RK4, exact wheels, the
    payloads' closed form) advances at ``step``; the controller's feedforward is the closed
    form at its samples.

    Returns arrays over the N+1 samples: ``time``, ``q_BI``, ``q_BO``, ``w_BI_B``, ``w_BO_B``,
    ``h_wheel``, ``speed`` (wheel speeds), ``h_payload``, ``hdot_payload``, ``H_I`` (recomputed
    from the outputs as C_BIᵀ (J w_BI_B + h_wheel + h_payload)), and the commands in force from
    t_k: ``tau_cmd``, ``att_error``, ``rate_error`` (from the last controller sample) and
    ``motor_torque`` (from the last drive sample).
    """
    n_steps = int(round(stop / step))
    if n_steps < 1 or abs(n_steps * step - stop) > 1e-9 * max(1.0, stop):
        raise ValueError(f"stop={stop} is not an integer multiple of step={step}")
    every_c = _every(control_period, step, "control_period")
    every_d = _every(drive_period, step, "drive_period")
    dt = float(step)
    half, sixth, jinv = 0.5 * dt, dt / 6.0, 1.0 / J_HUB
    # the payloads' momentum at every half step (closed form, vectorised): index 2k ↔ t_k
    hp_all, hdp_all = payload_pair(0.5 * dt * np.arange(2 * n_steps + 1))
    hp = hp_all.tolist()
    hdp = hdp_all.tolist()
    ff = list(zip(hp[:: 2 * every_c], hdp[:: 2 * every_c]))

    q = q_oi(0.0)
    omega = [0.0, 0.0, 0.0]
    w0 = W_OI_O
    Hx, Hy, Hz = rot(qconj(q), tuple(J_HUB * w0[i] + hp[0][i] for i in range(3)))

    qdot = hub_qdot((Hx, Hy, Hz), jinv)

    rec = []
    for k in range(n_steps + 1):
        t = k * dt
        q0, q1, q2, q3 = q
        hpk = hp[2 * k]
        hw = [J_WHEEL * x for x in omega]
        h = (hw[0] + hpk[0], hw[1] + hpk[1], hw[2] + hpk[2])
        HB = rot(q, (Hx, Hy, Hz))
        w = ((HB[0] - h[0]) * jinv, (HB[1] - h[1]) * jinv, (HB[2] - h[2]) * jinv)
        if k % every_c == 0:
            tau, e, r = control(q, w, t, *ff[k // every_c])
        if k % every_d == 0:
            m = motor_torques(tau, w, omega)
        q_bo = qmul(qconj(q_oi(t)), q)
        w_oi_b = rot(q_bo, W_OI_O)
        rec.append(
            (*q, *q_bo, *w, *(w[i] - w_oi_b[i] for i in range(3)), *hw, *omega, *tau, *e, *r, *m)
        )
        if k == n_steps:
            break
        # wheels: exact at h/2 and h
        mid = [wheel_speed(o, mi, half) for o, mi in zip(omega, m)]
        omega = [wheel_speed(o, mi, dt) for o, mi in zip(omega, m)]
        if max(map(abs, omega)) * J_WHEEL >= MOMENTUM_LIMIT:
            raise ValueError(f"t={t:.3f} s: a wheel reached its momentum limit (not modelled)")
        a, b = hp[2 * k + 1], hp[2 * k + 2]
        mh = [J_WHEEL * mid[i] + a[i] for i in range(3)]
        eh = [J_WHEEL * omega[i] + b[i] for i in range(3)]
        k1 = qdot(q0, q1, q2, q3, *h)
        k2 = qdot(q0 + half * k1[0], q1 + half * k1[1], q2 + half * k1[2], q3 + half * k1[3], *mh)
        k3 = qdot(q0 + half * k2[0], q1 + half * k2[1], q2 + half * k2[2], q3 + half * k2[3], *mh)
        k4 = qdot(q0 + dt * k3[0], q1 + dt * k3[1], q2 + dt * k3[2], q3 + dt * k3[3], *eh)
        q = tuple(
            x + sixth * (a1 + 2.0 * (a2 + a3) + a4) for x, a1, a2, a3, a4 in zip(q, k1, k2, k3, k4)
        )
        nrm = 1.0 / math.sqrt(sum(x * x for x in q))
        q = tuple(x * nrm for x in q)

    st = np.array(rec)
    q_bi, w_bi, h_w = st[:, 0:4], st[:, 8:11], st[:, 14:17]
    h_p = hp_all[::2]
    C = np.array([dcm(x) for x in q_bi])
    H_I = np.einsum("kji,kj->ki", C, J_HUB * w_bi + h_w + h_p)
    return {
        "time": np.arange(n_steps + 1) * dt,
        "q_BI": q_bi,
        "q_BO": st[:, 4:8],
        "w_BI_B": w_bi,
        "w_BO_B": st[:, 11:14],
        "h_wheel": h_w,
        "speed": st[:, 17:20],
        "h_payload": h_p,
        "hdot_payload": hdp_all[::2],
        "H_I": H_I,
        "tau_cmd": st[:, 20:23],
        "att_error": st[:, 23:26],
        "rate_error": st[:, 26:29],
        "motor_torque": st[:, 29:32],
    }
