r"""Independent monolithic reference simulation of the ``scan_pitch`` scenario.

Written from DESIGN.md §2 and §4.1 and the equations below only; it imports
nothing from ``components/``, ``fmus/`` or ``orchestration/``, so it can be used to check the
co-simulation (FMUs + master).

Conventions
-----------
Quaternions ``q_XY = (q0, q1, q2, q3)`` scalar first, Hamilton product ⊗, mapping Y-coordinates
to X-coordinates::

    v_X = C(q_XY) v_Y,   C(q) = (q0² − q·q) 1 + 2 q qᵀ − 2 q0 [q×]      (q = vector part)

so that ``C(p ⊗ q) = C(q) C(p)`` and ``q_BI = q_OI ⊗ q_BO``.  Kinematics
``q̇_BI = ½ q_BI ⊗ (0, w_BI_B)``.  Elementary frame rotations ``R1, R2, R3`` (about x, y, z by
angle a) have quaternions ``(cos a/2, sin a/2 e_k)``; the 1-2-3 Euler attitude of B relative to O,
``C_BO = R3(ψ) R2(θ) R1(φ)``, is ``q_BO = q1(φ) ⊗ q2(θ) ⊗ q3(ψ)``.

Orbit (circular two-body, RAAN = 0)
-----------------------------------
``μ = 3.986004418e14``, ``a = 6378137 + 681000``, ``n = √(μ/a³)``, ``i = 98.1°``, ``u = n t``::

    r_I = a (cos u, sin u cos i, sin u sin i),   v_I = a n (−sin u, cos u cos i, cos u sin i)
    z_O = −r̂,  y_O = −(r×v)/|r×v|,  x_O = y_O × z_O,  C_OI = [x_O; y_O; z_O],  w_OI_O = (0, −n, 0)

In closed form ``C_OI = M0 R3(u) R1(i)`` with ``M0 = [[0,1,0],[0,0,−1],[−1,0,0]]``, hence
``q_OI(t) = q1(i) ⊗ q3(n t) ⊗ q(M0)`` (continuous in t; checked against the r, v construction
in the tests).

Hub (no external torque; J = 956·1 kg m², so the gravity-gradient torque is exactly zero)
-----------------------------------------------------------------------------------------------
States ``q_BI`` and the total inertial angular momentum ``H_I`` (constant)::

    w_BI_B = J⁻¹ (C_BI H_I − h),     Ḣ_I = 0

which is the hub equation ``J ẇ = −w × (J w + h) − ḣ`` of DESIGN.md §2 written in conserved form.
Outputs: ``q_BO = q_OI* ⊗ q_BI``, ``w_BO_B = w_BI_B − C_BO w_OI_O``.
Initial: ``q_BO(0)`` = Euler (0, 120°, 0); ``q_BI(0) = q_OI(0) ⊗ q_BO(0)``;
``w_BI_B(0) = C_BO(0) w_OI_O``; ``H_I(0) = C_BI(0)ᵀ (J w_BI_B(0) + h(0))``.

CMG cluster (6 SGCMGs, h_r = 16.65 N m s, α0 = 63.4°)
-----------------------------------------------------
Gyros 1–5 at azimuths 90°, 162°, 234°, 306°, 18°::

    g = (−sin α0 cos az, −sin α0 sin az, cos α0),   p = (cos α0 cos az, cos α0 sin az, sin α0)

gyro 6: ``g = (0,0,1)``, ``p = (1,0,0)``.  Reversed spin (scenario default): ``s = −p``,
``t = g × s``.  At gimbal angle δ_i::

    σ_i = s_i cos δ_i + t_i sin δ_i,   a_i = t_i cos δ_i − s_i sin δ_i
    h = h_r Σ σ_i,   ḣ = h_r Σ a_i δ̇_i,   A = [a_1 … a_6],   Q = det(A Aᵀ)

Initial ``δ = (π/4, 0, −π/4, π/2, π/4, 0)``, ``δ̇ = 0``.

Gimbal servo: over a step the command ``c`` is held; the target rate ``r* = clip(c, ±0.6)`` is
approached at ±0.5 rad/s² and then held.  With ``r0`` the rate at the start of the step,
``Δ = r* − r0``, ``t_r = |Δ|/0.5``, ``τ' = min(τ, t_r)``::

    δ̇(τ) = r0 + 0.5 sgn(Δ) τ'
    δ(τ)  = δ0 + r0 τ' + ¼ sgn(Δ) τ'² + r* (τ − τ')         (exact, piecewise quadratic)

Steering (pseudo-inverse, no null motion): the cluster's torque on the body is ``−ḣ − w_BI_B × h``::

    ḣ_req = −τ_cmd − w_BI_B × h,   δ̇_cmd = Aᵀ (A Aᵀ)⁻¹ ḣ_req / h_r

Controller (pitch 120° → 0° in T = 100 s, −0.8 °/s imaging phase)
-----------------------------------------------------------------
``θ0 = 120°, θf = 0, θ̇0 = −0.8 °/s, f2 = 0.2, f4 = 0.6``::

    t1 = T(1 − f2 − f4)/2,  t2 = t1 + f2 T,  θ̈m = (θf − θ0 − θ̇0 f4 T)/(t1 t2),  θ̇m = θ̈m t1,
    t3 = t2 + (θ̇m − θ̇0)/θ̈m,  t4 = t3 + f4 T,  t5 = t4 + θ̇0/θ̈m  (= T)

(10, 30, 36.667, 96.667, 100 s; θ̈m = −0.24 °/s²).  Phase k on [t_{k−1}, t_k) for k = 1..4, phase 5
for t ≥ t4; the comparisons use t_k − 1e-9 s so that the grid points t = 10.0 and 30.0 fall in the
later phase despite the formula rounding t1, t2 to 10.000000000000004, 30.000000000000004.
Singularity-free measurement from ``q = q_BO`` (sign chosen so q0 ≥ 0)::

    n = hypot(q0, q2), c = q0/n, s = q2/n,  θ = 2 atan2(q2, q0),
    e_x = 2 (c q1 − s q3),  e_z = 2 (c q3 + s q1),  w = w_BO_B
    τ_cmd = (−86 e_x − 574 w_x,  τ_y,  −86 e_z − 574 w_z)
    τ_y = I θ̈m (phase 1), 0 (2), −I θ̈m (3), 0 (4), 0.9 (θf − θ) − 578 w_y (5),   I = 956

Integration ("monolithic")
--------------------------
One loop, step ``h``, ``t_k = k h`` (integer counter).  At ``t_k``: τ_cmd and δ̇_cmd from the
current state (held over the step); gimbals advanced with the exact servo solution; ``q_BI``
advanced by classical RK4 whose stages use ``h`` from the exact gimbal angles at the stage times
(0, h/2, h/2, h); ``H_I`` is constant (Ḣ_I = 0 is integrated exactly); ``q_BI`` normalised
after each step.  The only discretisation is then the zero-order hold of the command (first
order in h) plus the O(h⁴) RK4 error; as h → 0 this converges to the continuous closed loop.
The largest first-order term is the quantisation of the phase switches t3, t4 (not grid points:
phase 3 lasts until the first sample ≥ t3, e.g. 36.7 s at h = 0.1 s, an extra 0.033 s of 4 N m).
Measured: max |pitch(1e-3) − pitch(5e-4)| = 0.0043°, max |Δw_BO_B| = 4.6e-6 rad/s; ≈ 23 µs/step.

Sampled-data reference: with ``control_period = m h`` the controller and the steering run only
at ``t = j m h`` and their commands (τ_cmd, phase, δ̇_cmd) are held for m plant steps (zero-order
hold); the plant still advances at h.  That is the system a co-simulation with its controller
at that period computes, so co-simulation − sampled reference is the coupling error alone and
sampled − continuous reference (control_period → 0) the effect of the sample period.

Outputs are recorded at t_k before the step: ``tau_cmd`` is the command computed at t_k and held
over [t_k, t_k+1); ``delta_dot`` is the actual gimbal rate at t_k; ``H_I`` is recomputed from the
outputs as C_BIᵀ (J w_BI_B + h); ``Q`` is det(A Aᵀ).
"""

from __future__ import annotations

import math

import numpy as np

# --- constants --------------------------------------------------------------------------------
MU = 3.986004418e14
A_ORBIT = 6378137.0 + 681000.0
N_ORBIT = math.sqrt(MU / A_ORBIT**3)
INCLINATION = math.radians(98.1)
W_OI_O = (0.0, -N_ORBIT, 0.0)

J_HUB = 956.0
H_ROTOR = 16.65
ALPHA0 = math.radians(63.4)
AZIMUTHS = tuple(math.radians(a) for a in (90.0, 162.0, 234.0, 306.0, 18.0))
DELTA0 = (math.pi / 4, 0.0, -math.pi / 4, math.pi / 2, math.pi / 4, 0.0)
RATE_MAX = 0.6
ACCEL_MAX = 0.5

THETA0 = math.radians(120.0)
THETAF = 0.0
SCAN_RATE = math.radians(-0.8)
T_MAN = 100.0
F2 = 0.2
F4 = 0.6
I_AXIS = 956.0
KP_RY, KD_RY = 86.0, 574.0  # roll / yaw PD
C1, C2 = 0.9, 578.0  # pitch PD in phase 5


# --- small quaternion helpers (plain floats, tuples) -------------------------------------------
def qmul(a, b):
    """Hamilton product a ⊗ b (scalar first)."""
    a0, a1, a2, a3 = a
    b0, b1, b2, b3 = b
    return (
        a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
        a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
        a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
        a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0,
    )


def qconj(q):
    return (q[0], -q[1], -q[2], -q[3])


def dcm(q) -> np.ndarray:
    """C(q) = (q0² − q·q) 1 + 2 q qᵀ − 2 q0 [q×] for a (not necessarily unit) quaternion."""
    q0, q1, q2, q3 = (float(x) for x in q)
    v = np.array([q1, q2, q3])
    qx = np.array([[0.0, -q3, q2], [q3, 0.0, -q1], [-q2, q1, 0.0]])
    return (q0 * q0 - v @ v) * np.eye(3) + 2.0 * np.outer(v, v) - 2.0 * q0 * qx


def rot(q, v):
    """C(q) v for a unit quaternion q (plain floats)."""
    q0, q1, q2, q3 = q
    v1, v2, v3 = v
    k = q0 * q0 - q1 * q1 - q2 * q2 - q3 * q3
    d = 2.0 * (q1 * v1 + q2 * v2 + q3 * v3)
    c0 = 2.0 * q0
    return (
        k * v1 + d * q1 - c0 * (q2 * v3 - q3 * v2),
        k * v2 + d * q2 - c0 * (q3 * v1 - q1 * v3),
        k * v3 + d * q3 - c0 * (q1 * v2 - q2 * v1),
    )


def dcm_to_quat(C) -> tuple:
    """Inverse of :func:`dcm` (Shepperd), returned with q0 ≥ 0."""
    C = np.asarray(C, dtype=float)
    tr = C[0, 0] + C[1, 1] + C[2, 2]
    cands = (tr, C[0, 0], C[1, 1], C[2, 2])
    i = int(np.argmax(cands))
    if i == 0:
        q0 = 0.5 * math.sqrt(1.0 + tr)
        f = 0.25 / q0
        q = (q0, f * (C[1, 2] - C[2, 1]), f * (C[2, 0] - C[0, 2]), f * (C[0, 1] - C[1, 0]))
    elif i == 1:
        q1 = 0.5 * math.sqrt(1.0 + 2.0 * C[0, 0] - tr)
        f = 0.25 / q1
        q = (f * (C[1, 2] - C[2, 1]), q1, f * (C[0, 1] + C[1, 0]), f * (C[0, 2] + C[2, 0]))
    elif i == 2:
        q2 = 0.5 * math.sqrt(1.0 + 2.0 * C[1, 1] - tr)
        f = 0.25 / q2
        q = (f * (C[2, 0] - C[0, 2]), f * (C[0, 1] + C[1, 0]), q2, f * (C[1, 2] + C[2, 1]))
    else:
        q3 = 0.5 * math.sqrt(1.0 + 2.0 * C[2, 2] - tr)
        f = 0.25 / q3
        q = (f * (C[0, 1] - C[1, 0]), f * (C[0, 2] + C[2, 0]), f * (C[1, 2] + C[2, 1]), q3)
    if q[0] < 0.0:
        q = tuple(-x for x in q)
    return tuple(float(x) for x in q)


def q_axis(k: int, angle: float) -> tuple:
    """Quaternion of the elementary frame rotation R_k(angle), k = 1, 2, 3."""
    q = [math.cos(0.5 * angle), 0.0, 0.0, 0.0]
    q[k] = math.sin(0.5 * angle)
    return tuple(q)


def R(k: int, a: float) -> np.ndarray:
    """Elementary frame rotation matrices R1, R2, R3 as defined in the brief."""
    c, s = math.cos(a), math.sin(a)
    if k == 1:
        return np.array([[1.0, 0, 0], [0, c, s], [0, -s, c]])
    if k == 2:
        return np.array([[c, 0, -s], [0, 1.0, 0], [s, 0, c]])
    return np.array([[c, s, 0], [-s, c, 0], [0, 0, 1.0]])


def euler123_to_q(phi: float, theta: float, psi: float) -> tuple:
    """q_BO for C_BO = R3(ψ) R2(θ) R1(φ)."""
    return qmul(qmul(q_axis(1, phi), q_axis(2, theta)), q_axis(3, psi))


# --- orbit --------------------------------------------------------------------------------------
_M0 = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]])
Q_M0 = dcm_to_quat(_M0)
_CI2, _SI2 = math.cos(0.5 * INCLINATION), math.sin(0.5 * INCLINATION)


def orbit_rv(t: float):
    """Inertial position and velocity of the circular orbit at time t."""
    u = N_ORBIT * t
    ci, si = math.cos(INCLINATION), math.sin(INCLINATION)
    r = A_ORBIT * np.array([math.cos(u), math.sin(u) * ci, math.sin(u) * si])
    v = A_ORBIT * N_ORBIT * np.array([-math.sin(u), math.cos(u) * ci, math.cos(u) * si])
    return r, v


def c_oi_from_rv(r, v) -> np.ndarray:
    """C_OI built literally from the definition of the orbit frame."""
    z = -r / np.linalg.norm(r)
    hv = np.cross(r, v)
    y = -hv / np.linalg.norm(hv)
    x = np.cross(y, z)
    return np.vstack([x, y, z])


def q_oi(t: float) -> tuple:
    """q_OI(t) = q1(i) ⊗ q3(n t) ⊗ q(M0), continuous in t."""
    hu = 0.5 * N_ORBIT * t
    cu, su = math.cos(hu), math.sin(hu)
    p = (_CI2 * cu, _SI2 * cu, -_SI2 * su, _CI2 * su)  # q1(i) ⊗ q3(u)
    return qmul(p, Q_M0)


# --- CMG cluster ----------------------------------------------------------------------------------
def cmg_axes(reversed_spin: bool = True):
    """Gimbal axes G, reference spins S and transverse axes T as 3×6 arrays (columns = gyros)."""
    sa, ca = math.sin(ALPHA0), math.cos(ALPHA0)
    g = [(-sa * math.cos(az), -sa * math.sin(az), ca) for az in AZIMUTHS] + [(0.0, 0.0, 1.0)]
    p = [(ca * math.cos(az), ca * math.sin(az), sa) for az in AZIMUTHS] + [(1.0, 0.0, 0.0)]
    G = np.array(g).T
    S = -np.array(p).T if reversed_spin else np.array(p).T
    T = np.cross(G.T, S.T).T
    return G, S, T


G_AX, S_AX, T_AX = cmg_axes()


def cluster_momentum(delta) -> np.ndarray:
    delta = np.asarray(delta, dtype=float)
    return H_ROTOR * (S_AX @ np.cos(delta) + T_AX @ np.sin(delta))


def jacobian(delta) -> np.ndarray:
    """A = [a_1 … a_6], a_i = dσ_i/dδ_i (3×6)."""
    delta = np.asarray(delta, dtype=float)
    return T_AX * np.cos(delta) - S_AX * np.sin(delta)


def steering(tau_cmd, w_bi, h, delta) -> np.ndarray:
    """Pseudo-inverse gimbal-rate command (unclipped)."""
    A = jacobian(delta)
    hreq = -np.asarray(tau_cmd, float) - np.cross(w_bi, h)
    return A.T @ np.linalg.solve(A @ A.T, hreq) / H_ROTOR


def servo(delta0, rate0, cmd, tau):
    """Exact gimbal servo over a held command: (angle, rate) after time tau (arrays broadcast)."""
    delta0 = np.asarray(delta0, float)
    rate0 = np.asarray(rate0, float)
    target = np.clip(np.asarray(cmd, float), -RATE_MAX, RATE_MAX)
    diff = target - rate0
    sgn = np.sign(diff)
    tr = np.abs(diff) / ACCEL_MAX
    tt = np.minimum(tau, tr)
    rate = rate0 + ACCEL_MAX * sgn * tt
    angle = delta0 + rate0 * tt + 0.5 * ACCEL_MAX * sgn * tt * tt + target * (tau - tt)
    return angle, rate


# --- maneuver plan / controller -------------------------------------------------------------------
def plan() -> dict:
    """Phase times t1..t5 and the planned acceleration / peak rate."""
    t1 = T_MAN * (1.0 - F2 - F4) / 2.0
    t2 = t1 + F2 * T_MAN
    acc = (THETAF - THETA0 - SCAN_RATE * F4 * T_MAN) / (t1 * t2)
    rate_m = acc * t1
    t3 = t2 + (rate_m - SCAN_RATE) / acc
    t4 = t3 + F4 * T_MAN
    t5 = t4 + SCAN_RATE / acc
    return {"t1": t1, "t2": t2, "t3": t3, "t4": t4, "t5": t5, "acc": acc, "rate": rate_m}


_PLAN = plan()
# Phase boundaries for the comparisons t >= t_k.  In exact arithmetic t1 = 10 s and t2 = 30 s fall
# on the sample grid of every usual step, but the plan formula rounds them to 10.000000000000004
# and 30.000000000000004, which would keep the grid point t = 10.0 (30.0) in the earlier phase for
# one extra step.  The boundaries are therefore lowered by PHASE_EPS so that a sample that equals
# t_k in exact arithmetic is assigned to the later phase, as the definition [t_{k-1}, t_k) says.
PHASE_EPS = 1e-9
_T1, _T2, _T3, _T4 = (_PLAN[k] - PHASE_EPS for k in ("t1", "t2", "t3", "t4"))
TAU_FF = I_AXIS * _PLAN["acc"]


def phase_of(t: float) -> int:
    """Phase (1..5) at time t: phase k on [t_{k-1}, t_k), phase 5 for t >= t4."""
    if t < _T1:
        return 1
    if t < _T2:
        return 2
    if t < _T3:
        return 3
    if t < _T4:
        return 4
    return 5


def pitch_errors(q_bo):
    """(θ, e_x, e_z) from q_BO, singularity-free (twist about body y)."""
    q0, q1, q2, q3 = q_bo
    if q0 < 0.0:
        q0, q1, q2, q3 = -q0, -q1, -q2, -q3
    nn = math.hypot(q0, q2)
    c, s = q0 / nn, q2 / nn
    return 2.0 * math.atan2(q2, q0), 2.0 * (c * q1 - s * q3), 2.0 * (c * q3 + s * q1)


def control(phase: int, q_bo, w_bo):
    """(θ, τ_cmd) for the given phase from q_BO and w_BO_B."""
    theta, ex, ez = pitch_errors(q_bo)
    if phase == 1:
        ty = TAU_FF
    elif phase == 3:
        ty = -TAU_FF
    elif phase == 5:
        ty = C1 * (THETAF - theta) + C2 * (0.0 - w_bo[1])
    else:
        ty = 0.0
    return theta, (-KP_RY * ex - KD_RY * w_bo[0], ty, -KP_RY * ez - KD_RY * w_bo[2])


# --- the monolithic simulation --------------------------------------------------------------------
def _qdot(q, H, h):
    """½ q ⊗ (0, w), w = (C(q̂) H − h)/J, with q̂ = q/|q| (RK4 stages need not be unit)."""
    q0, q1, q2, q3 = q
    inv = 1.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    cx, cy, cz = rot(q, H)
    wx = (cx * inv - h[0]) / J_HUB
    wy = (cy * inv - h[1]) / J_HUB
    wz = (cz * inv - h[2]) / J_HUB
    return (
        0.5 * (-q1 * wx - q2 * wy - q3 * wz),
        0.5 * (q0 * wx + q2 * wz - q3 * wy),
        0.5 * (q0 * wy + q3 * wx - q1 * wz),
        0.5 * (q0 * wz + q1 * wy - q2 * wx),
    )


def hub_qdot(H_I, jinv: float):
    """q̇_BI(q, h) = ½ q ⊗ (0, w), w = (C(q/|q|) H_I − h)/J for a hub of inertia J·1 with the
    (constant) total momentum H_I: the hub kinematics every reference integrates."""
    Hx, Hy, Hz = H_I

    def qdot(a0, a1, a2, a3, bx, by, bz):
        # ½ q ⊗ (0, w),  w = (C(q/|q|) H − h)/J
        inv = 1.0 / (a0 * a0 + a1 * a1 + a2 * a2 + a3 * a3)
        kk = a0 * a0 - a1 * a1 - a2 * a2 - a3 * a3
        dd = 2.0 * (a1 * Hx + a2 * Hy + a3 * Hz)
        c0 = 2.0 * a0
        wx = ((kk * Hx + dd * a1 - c0 * (a2 * Hz - a3 * Hy)) * inv - bx) * jinv
        wy = ((kk * Hy + dd * a2 - c0 * (a3 * Hx - a1 * Hz)) * inv - by) * jinv
        wz = ((kk * Hz + dd * a3 - c0 * (a1 * Hy - a2 * Hx)) * inv - bz) * jinv
        return (
            -0.5 * (a1 * wx + a2 * wy + a3 * wz),
            0.5 * (a0 * wx + a2 * wz - a3 * wy),
            0.5 * (a0 * wy + a3 * wx - a1 * wz),
            0.5 * (a0 * wz + a1 * wy - a2 * wx),
        )

    return qdot


def simulate(
    step: float, stop: float = 150.0, control_period: float | None = None
) -> dict[str, np.ndarray]:
    """Run the monolithic reference with step ``step`` up to ``stop``; samples at t = k·step.

    ``control_period`` (an integer multiple of ``step``; default ``step``): the controller
    and the steering are sampled only at t = j·control_period and their commands (τ_cmd,
    the phase, the gimbal-rate commands) held in between, a zero-order hold, while the plant
    (hub RK4, exact gimbal servo) advances at ``step``: the sampled-data system the
    co-simulation computes when its controller runs at that period.

    Returns arrays over the N+1 samples: ``time``, ``q_BO``, ``q_BI``, ``w_BO_B``, ``w_BI_B``,
    ``pitch``, ``delta``, ``delta_dot``, ``h``, ``H_I``, ``tau_cmd``, ``phase`` and ``Q``
    (singularity measure det(A Aᵀ)).  ``tau_cmd`` at t_k is the command computed from the state at
    t_k (held over [t_k, t_k+1)); ``delta_dot`` is the actual gimbal rate at t_k.
    """
    n_steps = int(round(stop / step))
    if n_steps < 1 or abs(n_steps * step - stop) > 1e-9 * max(1.0, stop):
        raise ValueError(f"stop={stop} is not an integer multiple of step={step}")
    every = 1 if control_period is None else int(round(control_period / step))
    if every < 1 or abs(every * step - (control_period or step)) > 1e-9 * step:
        raise ValueError(f"control_period={control_period} is not a multiple of step={step}")
    dt = float(step)
    half = 0.5 * dt
    sixth = dt / 6.0
    jinv = 1.0 / J_HUB
    hr = H_ROTOR
    rmax, acc = RATE_MAX, ACCEL_MAX
    nw = -N_ORBIT  # w_OI_O = (0, nw, 0)
    hq = 0.5 * N_ORBIT
    ci2, si2 = _CI2, _SI2
    m0, m1, m2, m3 = Q_M0
    t1, t2, t3, t4 = _T1, _T2, _T3, _T4
    tff = TAU_FF
    # per-gimbal constants: (Sx, Sy, Sz, Tx, Ty, Tz)
    gyro = [tuple(float(x) for x in (*S_AX[:, i], *T_AX[:, i])) for i in range(6)]
    idx = range(6)

    # initial state
    q_bo0 = euler123_to_q(0.0, THETA0, 0.0)
    q0, q1, q2, q3 = qmul(q_oi(0.0), q_bo0)
    d = [float(x) for x in DELTA0]
    r = [0.0] * 6
    c = [math.cos(x) for x in d]
    s = [math.sin(x) for x in d]
    hx = hr * sum(g[0] * ci + g[3] * si for g, ci, si in zip(gyro, c, s))
    hy = hr * sum(g[1] * ci + g[4] * si for g, ci, si in zip(gyro, c, s))
    hz = hr * sum(g[2] * ci + g[5] * si for g, ci, si in zip(gyro, c, s))
    w0 = rot(q_bo0, W_OI_O)
    Hx, Hy, Hz = rot(
        (q0, -q1, -q2, -q3), (J_HUB * w0[0] + hx, J_HUB * w0[1] + hy, J_HUB * w0[2] + hz)
    )  # C_BIᵀ (J w + h)

    qdot = hub_qdot((Hx, Hy, Hz), jinv)

    rec_state = []  # (q_BI, q_BO, w_BI, w_BO, pitch, h, tau, phase, Q)
    rec_d = []
    rec_r = []
    Q = 0.0
    for k in range(n_steps + 1):
        t = k * dt
        # --- orbit frame: q_OI = q1(i) ⊗ q3(n t) ⊗ q(M0);  q_BO = q_OI* ⊗ q_BI
        cu, su = math.cos(hq * t), math.sin(hq * t)
        p0, p1, p2, p3 = ci2 * cu, si2 * cu, -si2 * su, ci2 * su
        o0 = p0 * m0 - p1 * m1 - p2 * m2 - p3 * m3
        o1 = p0 * m1 + p1 * m0 + p2 * m3 - p3 * m2
        o2 = p0 * m2 - p1 * m3 + p2 * m0 + p3 * m1
        o3 = p0 * m3 + p1 * m2 - p2 * m1 + p3 * m0
        b0 = o0 * q0 + o1 * q1 + o2 * q2 + o3 * q3
        b1 = o0 * q1 - o1 * q0 - o2 * q3 + o3 * q2
        b2 = o0 * q2 + o1 * q3 - o2 * q0 - o3 * q1
        b3 = o0 * q3 - o1 * q2 + o2 * q1 - o3 * q0
        # --- body rate w_BI = (C_BI H − h)/J ;  w_BO = w_BI − C_BO w_OI_O
        kk = q0 * q0 - q1 * q1 - q2 * q2 - q3 * q3
        dd = 2.0 * (q1 * Hx + q2 * Hy + q3 * Hz)
        c0 = 2.0 * q0
        wx = (kk * Hx + dd * q1 - c0 * (q2 * Hz - q3 * Hy) - hx) * jinv
        wy = (kk * Hy + dd * q2 - c0 * (q3 * Hx - q1 * Hz) - hy) * jinv
        wz = (kk * Hz + dd * q3 - c0 * (q1 * Hy - q2 * Hx) - hz) * jinv
        # C_BO (0, nw, 0) = nw * (second column of C(q_BO))
        vx = wx - nw * 2.0 * (b1 * b2 + b0 * b3)
        vy = wy - nw * (b0 * b0 - b1 * b1 + b2 * b2 - b3 * b3)
        vz = wz - nw * 2.0 * (b2 * b3 - b0 * b1)
        # --- controller
        if b0 < 0.0:
            e0, e1, e2, e3 = -b0, -b1, -b2, -b3
        else:
            e0, e1, e2, e3 = b0, b1, b2, b3
        nn = math.hypot(e0, e2)
        cc, ss = e0 / nn, e2 / nn
        theta = 2.0 * math.atan2(e2, e0)
        ex = 2.0 * (cc * e1 - ss * e3)
        ez = 2.0 * (cc * e3 + ss * e1)
        sample = k % every == 0  # the controller and the steering run at this t
        if sample:
            if t < t1:
                phase, ty = 1, tff
            elif t < t2:
                phase, ty = 2, 0.0
            elif t < t3:
                phase, ty = 3, -tff
            elif t < t4:
                phase, ty = 4, 0.0
            else:
                phase, ty = 5, C1 * (THETAF - theta) + C2 * (0.0 - vy)
            tx = -KP_RY * ex - KD_RY * vx
            tz = -KP_RY * ez - KD_RY * vz

        # --- steering: M = A Aᵀ, ḣ_req = −τ − w × h, δ̇_cmd = Aᵀ M⁻¹ ḣ_req / h_r
        a = []
        mxx = mxy = mxz = myy = myz = mzz = 0.0
        for i in idx:
            g = gyro[i]
            ci, si = c[i], s[i]
            ax = g[3] * ci - g[0] * si
            ay = g[4] * ci - g[1] * si
            az = g[5] * ci - g[2] * si
            a.append((ax, ay, az))
            mxx += ax * ax
            mxy += ax * ay
            mxz += ax * az
            myy += ay * ay
            myz += ay * az
            mzz += az * az
        A11 = myy * mzz - myz * myz
        A12 = mxz * myz - mxy * mzz
        A13 = mxy * myz - mxz * myy
        Q = mxx * A11 + mxy * A12 + mxz * A13  # det(A Aᵀ)

        rec_state.append(
            (
                q0,
                q1,
                q2,
                q3,
                b0,
                b1,
                b2,
                b3,
                wx,
                wy,
                wz,
                vx,
                vy,
                vz,
                theta,
                hx,
                hy,
                hz,
                tx,
                ty,
                tz,
                phase,
                Q,
            )
        )
        rec_d.append(tuple(d))
        rec_r.append(tuple(r))
        if k == n_steps:
            break

        if sample:
            A22 = mxx * mzz - mxz * mxz
            A23 = mxy * mxz - mxx * myz
            A33 = mxx * myy - mxy * mxy
            fx = -tx - (wy * hz - wz * hy)
            fy = -ty - (wz * hx - wx * hz)
            fz = -tz - (wx * hy - wy * hx)
            scale = 1.0 / (Q * hr)
            yx = (A11 * fx + A12 * fy + A13 * fz) * scale
            yy = (A12 * fx + A22 * fy + A23 * fz) * scale
            yz = (A13 * fx + A23 * fy + A33 * fz) * scale
            cmds = [ax * yx + ay * yy + az * yz for ax, ay, az in a]

        # --- gimbals: exact servo at τ = h/2 and τ = h;  h(τ) from the exact angles
        mhx = mhy = mhz = ehx = ehy = ehz = 0.0
        for i in idx:
            cmd = cmds[i]
            tg = rmax if cmd > rmax else (-rmax if cmd < -rmax else cmd)
            d0, r0 = d[i], r[i]
            df = tg - r0
            if df >= 0.0:
                sg, tr = acc, df / acc
            else:
                sg, tr = -acc, -df / acc
            if tr >= dt:  # still ramping at the step end
                dm = d0 + (r0 + 0.5 * sg * half) * half
                de = d0 + (r0 + 0.5 * sg * dt) * dt
                r[i] = r0 + sg * dt
            else:
                base = d0 + (r0 + 0.5 * sg * tr) * tr
                de = base + tg * (dt - tr)
                r[i] = tg
                if tr >= half:
                    dm = d0 + (r0 + 0.5 * sg * half) * half
                else:
                    dm = base + tg * (half - tr)
            g = gyro[i]
            cm, sm = math.cos(dm), math.sin(dm)
            ce, se = math.cos(de), math.sin(de)
            mhx += g[0] * cm + g[3] * sm
            mhy += g[1] * cm + g[4] * sm
            mhz += g[2] * cm + g[5] * sm
            ehx += g[0] * ce + g[3] * se
            ehy += g[1] * ce + g[4] * se
            ehz += g[2] * ce + g[5] * se
            d[i], c[i], s[i] = de, ce, se
        mhx *= hr
        mhy *= hr
        mhz *= hr

        # --- RK4 on q_BI (H_I constant: Ḣ_I = 0 integrated exactly)
        k10, k11, k12, k13 = qdot(q0, q1, q2, q3, hx, hy, hz)
        k20, k21, k22, k23 = qdot(
            q0 + half * k10, q1 + half * k11, q2 + half * k12, q3 + half * k13, mhx, mhy, mhz
        )
        k30, k31, k32, k33 = qdot(
            q0 + half * k20, q1 + half * k21, q2 + half * k22, q3 + half * k23, mhx, mhy, mhz
        )
        hx, hy, hz = hr * ehx, hr * ehy, hr * ehz
        k40, k41, k42, k43 = qdot(
            q0 + dt * k30, q1 + dt * k31, q2 + dt * k32, q3 + dt * k33, hx, hy, hz
        )
        q0 += sixth * (k10 + 2.0 * (k20 + k30) + k40)
        q1 += sixth * (k11 + 2.0 * (k21 + k31) + k41)
        q2 += sixth * (k12 + 2.0 * (k22 + k32) + k42)
        q3 += sixth * (k13 + 2.0 * (k23 + k33) + k43)
        nrm = 1.0 / math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
        q0, q1, q2, q3 = q0 * nrm, q1 * nrm, q2 * nrm, q3 * nrm

    st = np.array(rec_state)
    q_bi = st[:, 0:4]
    w_bi = st[:, 8:11]
    h = st[:, 15:18]
    # total angular momentum recomputed from the recorded outputs: H_I = C_BIᵀ (J w_BI_B + h)
    H_I = np.einsum("kji,kj->ki", _dcm_batch(q_bi), J_HUB * w_bi + h)
    return {
        "time": np.arange(n_steps + 1) * dt,
        "q_BO": st[:, 4:8].copy(),
        "q_BI": q_bi.copy(),
        "w_BI_B": w_bi.copy(),
        "w_BO_B": st[:, 11:14].copy(),
        "pitch": st[:, 14].copy(),
        "delta": np.array(rec_d),
        "delta_dot": np.array(rec_r),
        "h": h.copy(),
        "H_I": H_I,
        "tau_cmd": st[:, 18:21].copy(),
        "phase": st[:, 21].astype(int),
        "Q": st[:, 22].copy(),
    }


def _dcm_batch(q: np.ndarray) -> np.ndarray:
    """C(q) for an (N, 4) array of quaternions → (N, 3, 3)."""
    q0, q1, q2, q3 = q.T
    out = np.empty((q.shape[0], 3, 3))
    k = q0 * q0 - q1 * q1 - q2 * q2 - q3 * q3
    out[:, 0, 0] = k + 2 * q1 * q1
    out[:, 1, 1] = k + 2 * q2 * q2
    out[:, 2, 2] = k + 2 * q3 * q3
    out[:, 0, 1] = 2 * (q1 * q2 + q0 * q3)
    out[:, 1, 0] = 2 * (q1 * q2 - q0 * q3)
    out[:, 0, 2] = 2 * (q1 * q3 - q0 * q2)
    out[:, 2, 0] = 2 * (q1 * q3 + q0 * q2)
    out[:, 1, 2] = 2 * (q2 * q3 + q0 * q1)
    out[:, 2, 1] = 2 * (q2 * q3 - q0 * q1)
    return out


def singularity_measure(delta: np.ndarray) -> np.ndarray:
    """Q = det(A Aᵀ) for each row of an (N, 6) array of gimbal angles."""
    delta = np.atleast_2d(delta)
    A = T_AX[None] * np.cos(delta)[:, None, :] - S_AX[None] * np.sin(delta)[:, None, :]
    return np.linalg.det(A @ np.swapaxes(A, 1, 2))
