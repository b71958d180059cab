r"""Independent monolithic reference of the ``video_sar`` scenario as a sampled-data system.

Written from DESIGN.md §2, §4.1 and §4.3 and the equations below; it imports nothing from
``components/``, ``fmus/`` or ``orchestration/``.  The hub and the CMG cluster (geometry,
reversed spin, exact gimbal servo with the 0.6 rad/s and 0.5 rad/s² limits) and the
pseudo-inverse steering without null motion are those of ``scan_pitch``: their equations
are taken from tests/tools/reference/scan_pitch.py (documented and tested there).

Exogenous input (taken from a recorded co-simulation, not computed here)
------------------------------------------------------------------------
The guidance (StaringGuidance, [Liang 2019] eqs 10–13) and the orbit are open loop: they do
not depend on the satellite's attitude.  The reference therefore takes, as given inputs,
the guidance outputs ``q_ref`` (= q_RI), ``w_ref`` (= w_RI_R) and ``dw_ref`` (d/dt w_ref,
in R) at the controller's samples t = j·control_period, and the orbit frame at t = 0
(``q_OI(0)``, ``w_OI_O(0)``, for the initial state only), from a run of the scenario
(:func:`guidance_from`); every run gives the same values there whatever its algorithm or
step (the guidance sees only the orbit, a function of time).  Everything that closes the
loop is computed here.

Hub (J = 956·1 kg m²: the gravity-gradient torque vanishes, no external torque)
---------------------------------------------------------------------------------
``w_BI_B = J⁻¹ (C_BI H_I − h)``, ``Ḣ_I = 0``, ``q̇_BI = ½ q_BI ⊗ (0, w_BI_B)``.

CMG cluster and steering: tests/tools/reference/scan_pitch.py (h = h_r Σ σ_i, A = [a_i],
δ̇_cmd = Aᵀ (A Aᵀ)⁻¹ (−τ_cmd − w_BI_B × h) / h_r; Q = det(A Aᵀ) ≥ 7 here, far from singular).

Controller (AttitudeController with the acceleration feedforward; kp = J ω_n², kd = 2 ζ ω_n J,
ω_n = 0.5 rad/s, ζ = 0.7)
----------------------------------------------------------------------------------------------
``q_BR = q_ref* ⊗ q_BI`` (sign with q0 ≥ 0), ``e = 2 atan2(|q_v|, q0) q_v/|q_v|``,
``ω_r = C(q_BR) w_ref``, ``r = w_BI_B − ω_r``::

    τ_cmd = −kp e − kd r + J (C(q_BR) dw_ref − r × ω_r) + w_BI_B × J w_BI_B

(the last term is zero for J ∝ 1).  Controller and steering are sampled at
``control_period`` and their commands (τ_cmd, δ̇_cmd) held in between (zero-order hold).

Initial state (the scenario's frozen values: the body on the reference, the cluster empty)
-----------------------------------------------------------------------------------------
``q_BO(0)`` = 1-2-3 Euler ``ATTITUDE0``, ``w_BO_B(0) = RATE0``; ``q_BI = q_OI(0) ⊗ q_BO``,
``w_BI_B = RATE0 + C_BO w_OI_O(0)``; δ = ``DELTA0``, δ̇ = 0; ``H_I = C_BIᵀ (J w + h)``.

Integration: one loop, step h, t_k = k h (integer counter); the gimbals exact at h/2 and h,
``q_BI`` by RK4 with h from the exact gimbal angles at the stage times, normalised after each
step; ``H_I`` constant.  The only discretisation is RK4: O(h⁴) on smooth stretches, but after
each new command a gimbal reaches its new rate within the first step (at 0.5 rad/s²), a jump
of δ̈ inside that step that leaves a lower-order term with a small constant.  Measured
(P = 0.05 s): the step 2.5 ms against 1.25 ms moves the attitude by 2e-11° over the 200 s
(tests/tools/benchmark_coupling.py), 5 ms against 2.5 ms by 5e-10° over 60 s.
"""

from __future__ import annotations

import math

import numpy as np

from .scan_pitch import (
    H_ROTOR,
    J_HUB,
    S_AX,
    T_AX,
    _qdot,
    cluster_momentum,
    dcm,
    euler123_to_q,
    qconj,
    qmul,
    rot,
    servo,
    singularity_measure,
    steering,
)

BANDWIDTH, DAMPING = 0.5, 0.7
KP = J_HUB * BANDWIDTH**2
KD = 2.0 * DAMPING * BANDWIDTH * J_HUB
#: the scenario's frozen initial state (orchestration/scenarios/video_sar.py ON_REFERENCE,
#: DELTA0; tests/orchestration/cosim/test_coupling.py checks that they are still the scenario's)
ATTITUDE0 = (-0.446370651122, 0.804885764925, 0.0)
RATE0 = (-0.000684611902, -0.004466724288, -0.000198845573)
DELTA0 = (0.629541998, 1.095833318, -3.137358127, 1.108768403, 2.362250577, -1.073359566)

GUIDANCE = ("q_ref", "w_ref", "dw_ref")


def guidance_from(results, control_period: float) -> dict[str, np.ndarray]:
    """The exogenous inputs from a recorded run (a Results with ``StaringGuidance.*`` and
    ``OrbitEnvironment.*``): the guidance at t = j·control_period, the orbit frame at t = 0."""
    t = results.time
    every = int(round(control_period / (t[1] - t[0])))
    out = {name: results.vector(f"StaringGuidance.{name}")[::every] for name in GUIDANCE}
    out["time"] = t[::every]
    out["q_OI0"] = results.vector("OrbitEnvironment.q_OI")[0]
    out["w_OI_O0"] = results.vector("OrbitEnvironment.w_OI_O")[0]
    return out


def control(q_bi, w, q_ref, w_ref, dw_ref) -> tuple:
    """(τ_cmd, att_error, rate_error) of the quaternion PD with the acceleration feedforward."""
    q = qmul(qconj(tuple(q_ref)), q_bi)  # q_BR
    if q[0] < 0.0:
        q = tuple(-x for x in q)
    s = math.sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    f = 2.0 * math.atan2(s, q[0]) / s if s > 0.0 else 2.0
    e = np.array([f * q[1], f * q[2], f * q[3]])
    C_BR = dcm(q)
    wr = C_BR @ w_ref
    r = np.asarray(w) - wr
    tau = -KP * e - KD * r + J_HUB * (C_BR @ dw_ref - np.cross(r, wr))
    return tau, e, r


def simulate(
    step: float, stop: float, guidance: dict, control_period: float | None = None
) -> dict[str, np.ndarray]:
    """Run the monolithic reference with step ``step`` up to ``stop``; samples at t = k·step.

    ``guidance``: :func:`guidance_from` of a run, sampled at ``control_period`` (an integer
    multiple of ``step``; default ``step``), at which the controller and the steering run.

    Returns arrays over the N+1 samples: ``time``, ``q_BI``, ``w_BI_B``, ``delta``,
    ``delta_dot`` (actual gimbal rates), ``h``, ``H_I`` (recomputed from the outputs as
    C_BIᵀ (J w_BI_B + h)), ``Q`` and the commands in force from t_k: ``tau_cmd``,
    ``att_error``, ``rate_error``, ``delta_dot_cmd``.
    """
    n_steps = int(round(stop / step))
    if n_steps < 1 or abs(n_steps * step - stop) > 1e-9 * max(1.0, stop):
        raise ValueError(f"stop={stop} is not an integer multiple of step={step}")
    period = step if control_period is None else control_period
    every = int(round(period / step))
    if every < 1 or abs(every * step - period) > 1e-9 * step:
        raise ValueError(f"control_period={control_period} is not a multiple of step={step}")
    samples = n_steps // every + 1
    times = np.asarray(guidance["time"])
    if len(times) < samples or not np.allclose(times[:samples], period * np.arange(samples)):
        raise ValueError(f"guidance must be sampled at t = j·{period} s up to {stop} s")
    dt = float(step)
    half = 0.5 * dt

    q_bo = euler123_to_q(*ATTITUDE0)
    q = qmul(tuple(guidance["q_OI0"]), q_bo)
    w = np.array(RATE0) + dcm(q_bo) @ np.asarray(guidance["w_OI_O0"])
    delta = np.array(DELTA0)
    rate = np.zeros(6)
    h = cluster_momentum(delta)
    H = tuple(dcm(q).T @ (J_HUB * w + h))

    stages = np.array([[half], [dt]])  # the gimbals at h/2 and h of each step
    rec, rec_d, rec_r, rec_c = [], [], [], []
    for k in range(n_steps + 1):
        w = (np.array(rot(q, H)) - h) / J_HUB
        if k % every == 0:
            j = k // every
            tau, e, r = control(q, w, *(np.asarray(guidance[n][j]) for n in GUIDANCE))
            cmd = steering(tau, w, h, delta)
        rec.append((*q, *w, *h, *tau, *e, *r))
        rec_d.append(delta)
        rec_r.append(rate)
        rec_c.append(cmd)
        if k == n_steps:
            break
        angles, rates = servo(delta, rate, cmd, stages)
        mid, end = H_ROTOR * (np.cos(angles) @ S_AX.T + np.sin(angles) @ T_AX.T)
        delta, rate = angles[1], rates[1]
        k1 = _qdot(q, H, h)
        k2 = _qdot(tuple(x + half * y for x, y in zip(q, k1)), H, mid)
        k3 = _qdot(tuple(x + half * y for x, y in zip(q, k2)), H, mid)
        k4 = _qdot(tuple(x + dt * y for x, y in zip(q, k3)), H, end)
        q = tuple(
            x + dt / 6.0 * (a + 2.0 * (b + c) + d) for x, a, b, c, d in zip(q, k1, k2, k3, k4)
        )
        nrm = 1.0 / math.sqrt(sum(x * x for x in q))
        q = tuple(x * nrm for x in q)
        h = end

    st = np.array(rec)
    q_bi, w_bi, h_c = st[:, 0:4], st[:, 4:7], st[:, 7:10]
    H_I = np.array([dcm(x).T @ (J_HUB * y + z) for x, y, z in zip(q_bi, w_bi, h_c)])
    return {
        "time": np.arange(n_steps + 1) * dt,
        "q_BI": q_bi,
        "w_BI_B": w_bi,
        "h": h_c,
        "H_I": H_I,
        "tau_cmd": st[:, 10:13],
        "att_error": st[:, 13:16],
        "rate_error": st[:, 16:19],
        "Q": singularity_measure(np.array(rec_d)),
        "delta": np.array(rec_d),
        "delta_dot": np.array(rec_r),
        "delta_dot_cmd": np.array(rec_c),
    }
