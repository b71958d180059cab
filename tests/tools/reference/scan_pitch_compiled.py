r"""Compiled monolithic kernel of the ``scan_pitch`` co-simulation: the physical limit.

The equations of tests/tools/reference/scan_pitch.py (its conventions, constants, plan,
controller, cluster geometry and initial state are imported from there; nothing from
``components/``, ``fmus/`` or ``orchestration/``), advanced by the co-simulation's own
scheme (DESIGN.md §3 and §5, the scenario's Jacobi coupling at macro step H), as one
numba function (nopython, no fastmath) looping over every step, its state in local floats
and arrays allocated once.  At t_n = n H:

1. Cluster outputs from (δ_i, δ̇_i):  σ_i = s_i cos δ_i + t_i sin δ_i,
   a_i = t_i cos δ_i − s_i sin δ_i,  h = h_r Σ σ_i,  ḣ = h_r Σ a_i δ̇_i,
   M = A Aᵀ, Q = det M.
2. Orbit ``q_OI(t) = q1(i) ⊗ q3(n t) ⊗ q(M0)``, ``w_OI_O = (0, −n, 0)``; hub outputs
   ``w_BI_B = (C_BI H_I − h)/J``, ``q_BO = q_OI* ⊗ q_BI``, ``w_BO_B = w_BI_B − C_BO w_OI_O``.
3. Controller (phase of t_n) → τ_cmd; steering
   ``δ̇_cmd = Aᵀ M⁻¹ (−τ_cmd − w_BI_B × h)/h_r + ε (1 − Aᵀ M⁻¹ A) ∂Q/∂δ`` with
   ``∂Q/∂δ_i = −2 Q a_iᵀ M⁻¹ σ_i`` (null motion; the scenario's gain ε is 0, the term then
   skipped as the co-simulation's CmgSteering skips it).
4. Cluster step: the exact servo with δ̇_cmd held over H (rate toward clip(c, ±0.6) at
   ±0.5 rad/s²): ``τ = min(|c* − δ̇|/0.5, H)``, ``δ += δ̇ H + a τ (H − τ/2)``, ``δ̇ += a τ``.
5. Hub step (Jacobi: the cluster's outputs of t_n extrapolated): RK4 on
   ``q̇_BI = ½ q_BI ⊗ (0, (C(q̂) H_I − h − ḣ s)/J)`` in ⌈max|w_BI_B| H / 0.02⌉ sub-steps
   (at least one), q_BI normalised after; H_I constant (no external torque, J ∝ 1).

The outputs of t_n are recorded before the step (the co-simulation's rows).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from . import scan_pitch as equations

#: recorded columns (slices of the output array)
COLUMNS = {
    "q_BI": slice(0, 4),
    "q_BO": slice(4, 8),
    "w_BI_B": slice(8, 11),
    "w_BO_B": slice(11, 14),
    "delta": slice(14, 20),
    "delta_dot": slice(20, 26),
    "h": slice(26, 29),
    "tau_cmd": slice(29, 32),
    "delta_dot_cmd": slice(32, 38),
    "Q": slice(38, 39),
}
WIDTH = 39
MAX_ROTATION_PER_SUBSTEP = 0.02  # rad, the hub's RK4 sub-step rule
SINGULAR_Q = 1e-12


@numba.njit(cache=False)
def _qdot(q0, q1, q2, q3, Hx, Hy, Hz, hx, hy, hz, jinv):
    """½ q ⊗ (0, w), w = (C(q)/|q|² H_I − h)/J."""
    inv = 1.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    kk = q0 * q0 - q1 * q1 - q2 * q2 - q3 * q3
    dd = 2.0 * (q1 * Hx + q2 * Hy + q3 * Hz)
    c0 = 2.0 * q0
    wx = ((kk * Hx + dd * q1 - c0 * (q2 * Hz - q3 * Hy)) * inv - hx) * jinv
    wy = ((kk * Hy + dd * q2 - c0 * (q3 * Hx - q1 * Hz)) * inv - hy) * jinv
    wz = ((kk * Hz + dd * q3 - c0 * (q1 * Hy - q2 * Hx)) * inv - hz) * jinv
    return (
        -0.5 * (q1 * wx + q2 * wy + q3 * wz),
        0.5 * (q0 * wx + q2 * wz - q3 * wy),
        0.5 * (q0 * wy + q3 * wx - q1 * wz),
        0.5 * (q0 * wz + q1 * wy - q2 * wx),
    )


@numba.njit(cache=False)
def _run(dt, n_steps, null_gain, gyro, delta, q, H, orbit, plan, gains, out):
    """Every step of the module docstring; the rows into ``out`` ((n_steps + 1) × WIDTH).
    ``gyro``: rows (s_i, t_i); ``delta``: δ0; ``q``: q_BI(0); ``H``: H_I; ``orbit``:
    (n, cos i/2, sin i/2, q(M0)); ``plan``: (t1..t4 lowered by 1e-9 s, I θ̈m, θf);
    ``gains``: (J, h_r, rate limit, accel limit, kp, kd roll/yaw, c1, c2).  Returns −1, or the
    step at which Q ≤ SINGULAR_Q (the run stops there)."""
    J, hr, rmax, acc, kp, kd, c1, c2 = gains
    jinv = 1.0 / J
    n_orbit, ci2, si2, m0, m1, m2, m3 = orbit
    t1, t2, t3, t4, tff, thetaf = plan
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    Hx, Hy, Hz = H[0], H[1], H[2]
    d = delta.copy()
    r = np.zeros(6)
    c, s = np.cos(d), np.sin(d)
    a = np.empty((6, 3))
    cmd = np.empty(6)
    for k in range(n_steps + 1):
        t = k * dt
        row = out[k]
        # 1. cluster outputs
        hx = hy = hz = hdx = hdy = hdz = 0.0
        mxx = mxy = mxz = myy = myz = mzz = 0.0
        for i in range(6):
            sx, sy, sz = gyro[i, 0], gyro[i, 1], gyro[i, 2]
            tx, ty, tz = gyro[i, 3], gyro[i, 4], gyro[i, 5]
            ax, ay, az = tx * c[i] - sx * s[i], ty * c[i] - sy * s[i], tz * c[i] - sz * s[i]
            a[i, 0], a[i, 1], a[i, 2] = ax, ay, az
            hx += sx * c[i] + tx * s[i]
            hy += sy * c[i] + ty * s[i]
            hz += sz * c[i] + tz * s[i]
            hdx += ax * r[i]
            hdy += ay * r[i]
            hdz += az * r[i]
            mxx += ax * ax
            mxy += ax * ay
            mxz += ax * az
            myy += ay * ay
            myz += ay * az
            mzz += az * az
        hx, hy, hz, hdx, hdy, hdz = hr * hx, hr * hy, hr * hz, hr * hdx, hr * hdy, hr * hdz
        A11, A12, A13 = myy * mzz - myz * myz, mxz * myz - mxy * mzz, mxy * myz - mxz * myy
        A22, A23, A33 = mxx * mzz - mxz * mxz, mxy * mxz - mxx * myz, mxx * myy - mxy * mxy
        Q = mxx * A11 + mxy * A12 + mxz * A13
        if Q <= SINGULAR_Q:
            return k
        # 2. orbit frame and hub outputs
        cu, su = math.cos(0.5 * n_orbit * t), math.sin(0.5 * n_orbit * t)
        p0, p1, p2, p3 = ci2 * cu, si2 * cu, -si2 * su, ci2 * su
        o0 = p0 * m0 - p1 * m1 - p2 * m2 - p3 * m3
        o1 = p0 * m1 + p1 * m0 + p2 * m3 - p3 * m2
        o2 = p0 * m2 - p1 * m3 + p2 * m0 + p3 * m1
        o3 = p0 * m3 + p1 * m2 - p2 * m1 + p3 * m0
        b0 = o0 * q0 + o1 * q1 + o2 * q2 + o3 * q3
        b1 = o0 * q1 - o1 * q0 - o2 * q3 + o3 * q2
        b2 = o0 * q2 + o1 * q3 - o2 * q0 - o3 * q1
        b3 = o0 * q3 - o1 * q2 + o2 * q1 - o3 * q0
        kk = q0 * q0 - q1 * q1 - q2 * q2 - q3 * q3
        dd = 2.0 * (q1 * Hx + q2 * Hy + q3 * Hz)
        c0 = 2.0 * q0
        wx = (kk * Hx + dd * q1 - c0 * (q2 * Hz - q3 * Hy) - hx) * jinv
        wy = (kk * Hy + dd * q2 - c0 * (q3 * Hx - q1 * Hz) - hy) * jinv
        wz = (kk * Hz + dd * q3 - c0 * (q1 * Hy - q2 * Hx) - hz) * jinv
        nw = -n_orbit  # C_BO (0, nw, 0) = nw × the second column of C(q_BO)
        vx = wx - nw * 2.0 * (b1 * b2 + b0 * b3)
        vy = wy - nw * (b0 * b0 - b1 * b1 + b2 * b2 - b3 * b3)
        vz = wz - nw * 2.0 * (b2 * b3 - b0 * b1)
        # 3. controller: twist θ about y and the swing's roll / yaw errors (q0 ≥ 0)
        e0, e1, e2, e3 = (-b0, -b1, -b2, -b3) if b0 < 0.0 else (b0, b1, b2, b3)
        nn = math.hypot(e0, e2)
        theta = 2.0 * math.atan2(e2, e0)
        ex = 2.0 * (e0 * e1 - e2 * e3) / nn
        ez = 2.0 * (e0 * e3 + e2 * e1) / nn
        if t < t1:
            tauy = tff
        elif t < t2:
            tauy = 0.0
        elif t < t3:
            tauy = -tff
        elif t < t4:
            tauy = 0.0
        else:
            tauy = c1 * (thetaf - theta) - c2 * vy
        taux, tauz = -kp * ex - kd * vx, -kp * ez - kd * vz
        #    steering: y = M⁻¹ (−τ − w × h)/h_r, δ̇_cmd = Aᵀ y (+ null motion)
        fx = -taux - (wy * hz - wz * hy)
        fy = -tauy - (wz * hx - wx * hz)
        fz = -tauz - (wx * hy - wy * hx)
        scale = 1.0 / (Q * hr)
        yx = (A11 * fx + A12 * fy + A13 * fz) * scale
        yy = (A12 * fx + A22 * fy + A23 * fz) * scale
        yz = (A13 * fx + A23 * fy + A33 * fz) * scale
        for i in range(6):
            cmd[i] = a[i, 0] * yx + a[i, 1] * yy + a[i, 2] * yz
        if null_gain != 0.0:
            gx = gy = gz = 0.0  # Σ a_i ∂Q/∂δ_i
            for i in range(6):
                sx = gyro[i, 0] * c[i] + gyro[i, 3] * s[i]  # σ_i
                sy = gyro[i, 1] * c[i] + gyro[i, 4] * s[i]
                sz = gyro[i, 2] * c[i] + gyro[i, 5] * s[i]
                ux = (A11 * sx + A12 * sy + A13 * sz) / Q  # M⁻¹ σ_i
                uy = (A12 * sx + A22 * sy + A23 * sz) / Q
                uz = (A13 * sx + A23 * sy + A33 * sz) / Q
                grad = -2.0 * Q * (a[i, 0] * ux + a[i, 1] * uy + a[i, 2] * uz)
                cmd[i] += null_gain * grad  # ε ∂Q/∂δ_i, minus its range part below
                gx += a[i, 0] * grad
                gy += a[i, 1] * grad
                gz += a[i, 2] * grad
            ux = (A11 * gx + A12 * gy + A13 * gz) / Q
            uy = (A12 * gx + A22 * gy + A23 * gz) / Q
            uz = (A13 * gx + A23 * gy + A33 * gz) / Q
            for i in range(6):
                cmd[i] -= null_gain * (a[i, 0] * ux + a[i, 1] * uy + a[i, 2] * uz)
        # the row of t_n
        row[0], row[1], row[2], row[3] = q0, q1, q2, q3
        row[4], row[5], row[6], row[7] = b0, b1, b2, b3
        row[8], row[9], row[10], row[11], row[12], row[13] = wx, wy, wz, vx, vy, vz
        for i in range(6):
            row[14 + i], row[20 + i], row[32 + i] = d[i], r[i], cmd[i]
        row[26], row[27], row[28], row[29], row[30], row[31] = hx, hy, hz, taux, tauy, tauz
        row[38] = Q
        if k == n_steps:
            break
        # 4. cluster step: exact servo, command held
        for i in range(6):
            gap = min(max(cmd[i], -rmax), rmax) - r[i]
            tau = min(abs(gap) / acc, dt)
            sign = acc if gap > 0.0 else (-acc if gap < 0.0 else 0.0)
            d[i] += r[i] * dt + sign * tau * (dt - 0.5 * tau)
            r[i] += sign * tau
            c[i], s[i] = math.cos(d[i]), math.sin(d[i])
        # 5. hub step: RK4 sub-steps with h + ḣ s
        fastest = max(abs(wx), abs(wy), abs(wz))
        n_sub = max(1, int(math.ceil(fastest * dt / MAX_ROTATION_PER_SUBSTEP)))
        sub = dt / n_sub
        half = 0.5 * sub
        for j in range(n_sub):
            s0 = j * sub
            ax, ay, az = hx + hdx * s0, hy + hdy * s0, hz + hdz * s0
            k10, k11, k12, k13 = _qdot(q0, q1, q2, q3, Hx, Hy, Hz, ax, ay, az, jinv)
            mx, my, mz = hx + hdx * (s0 + half), hy + hdy * (s0 + half), hz + hdz * (s0 + half)
            k20, k21, k22, k23 = _qdot(
                q0 + half * k10, q1 + half * k11, q2 + half * k12, q3 + half * k13,
                Hx, Hy, Hz, mx, my, mz, jinv,
            )  # fmt: skip
            k30, k31, k32, k33 = _qdot(
                q0 + half * k20, q1 + half * k21, q2 + half * k22, q3 + half * k23,
                Hx, Hy, Hz, mx, my, mz, jinv,
            )  # fmt: skip
            nx, ny, nz = hx + hdx * (s0 + sub), hy + hdy * (s0 + sub), hz + hdz * (s0 + sub)
            k40, k41, k42, k43 = _qdot(
                q0 + sub * k30, q1 + sub * k31, q2 + sub * k32, q3 + sub * k33,
                Hx, Hy, Hz, nx, ny, nz, jinv,
            )  # fmt: skip
            w6 = sub / 6.0
            q0 += w6 * (k10 + 2.0 * (k20 + k30) + k40)
            q1 += w6 * (k11 + 2.0 * (k21 + k31) + k41)
            q2 += w6 * (k12 + 2.0 * (k22 + k32) + k42)
            q3 += w6 * (k13 + 2.0 * (k23 + k33) + k43)
        norm = 1.0 / math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
        q0, q1, q2, q3 = q0 * norm, q1 * norm, q2 * norm, q3 * norm
    return -1


def _arguments(step: float, stop: float, null_gain: float) -> tuple:
    """The kernel's arguments for a run of ``stop`` s at macro step ``step``."""
    e = equations
    n_steps = int(round(stop / step))
    if n_steps < 1 or abs(n_steps * step - stop) > 1e-9 * max(1.0, stop):
        raise ValueError(f"stop={stop} is not an integer multiple of step={step}")
    gyro = np.ascontiguousarray(np.vstack([e.S_AX, e.T_AX]).T)  # rows (s_i, t_i)
    delta = np.array(e.DELTA0)
    # initial state as the reference's: q_BI = q_OI(0) ⊗ q_BO(0), w_BO_B = 0, H_I from it
    q_bo0 = e.euler123_to_q(0.0, e.THETA0, 0.0)
    q_bi = e.qmul(e.q_oi(0.0), q_bo0)
    w0 = np.array(e.rot(q_bo0, e.W_OI_O))
    H = np.array(e.rot(e.qconj(q_bi), tuple(e.J_HUB * w0 + e.cluster_momentum(delta))))
    orbit = (e.N_ORBIT, e._CI2, e._SI2, *e.Q_M0)
    plan = (e._T1, e._T2, e._T3, e._T4, e.TAU_FF, e.THETAF)
    gains = (e.J_HUB, e.H_ROTOR, e.RATE_MAX, e.ACCEL_MAX, e.KP_RY, e.KD_RY, e.C1, e.C2)
    out = np.empty((n_steps + 1, WIDTH))
    return (
        float(step),
        n_steps,
        float(null_gain),
        gyro,
        delta,
        np.array(q_bi),
        H,
        orbit,
        plan,
        gains,
        out,
    )


def runner(step: float, stop: float = 150.0, null_gain: float = 0.0):
    """A function of no arguments that runs the kernel once (its arguments made here, its
    output array reused): what a benchmark times."""
    arguments = _arguments(step, stop, null_gain)
    return lambda: _run(*arguments)


def simulate(step: float, stop: float = 150.0, null_gain: float = 0.0) -> dict[str, np.ndarray]:
    """Run the kernel at macro step ``step`` up to ``stop`` (``null_gain``: ε of the
    steering's null motion, the scenario's 0 by default); arrays over the N + 1 samples
    t_n = n·step: ``time`` and the :data:`COLUMNS`."""
    arguments = _arguments(step, stop, null_gain)
    singular = _run(*arguments)
    if singular >= 0:
        raise ArithmeticError(f"Q = det(A Aᵀ) <= {SINGULAR_Q} at t = {singular * step} s")
    out = arguments[-1]
    result = {name: out[:, columns].copy() for name, columns in COLUMNS.items()}
    result["Q"] = result["Q"][:, 0]
    result["time"] = np.arange(out.shape[0]) * float(step)
    return result
