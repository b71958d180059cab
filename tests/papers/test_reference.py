"""Checks of the independent monolithic reference ``tests/tools/reference/scan_pitch.py`` itself.

These tests do not touch the co-simulation: they make sure the reference is a trustworthy yardstick
(conventions, geometry, servo, steering, conservation, convergence, plan) before it is used to
judge the FMUs and the master.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from reference import scan_pitch as sp  # tests/tools/ is on sys.path (conftest.py)

DEG = math.pi / 180.0


@functools.cache
def run(step: float, stop: float = 150.0):
    return sp.simulate(step, stop)


def rand_quat(rng):
    q = rng.normal(size=4)
    return tuple(q / np.linalg.norm(q))


# --- conventions ---------------------------------------------------------------------------------
def test_dcm_of_elementary_quaternions_are_R1_R2_R3():
    for k in (1, 2, 3):
        for a in (0.3, -1.2, 2.9):
            np.testing.assert_allclose(sp.dcm(sp.q_axis(k, a)), sp.R(k, a), atol=1e-15)


def test_composition_order_and_rot():
    rng = np.random.default_rng(1)
    for _ in range(20):
        p, q = rand_quat(rng), rand_quat(rng)
        # C(p ⊗ q) = C(q) C(p): q_BI = q_OI ⊗ q_BO  <=>  C_BI = C_BO C_OI
        np.testing.assert_allclose(sp.dcm(sp.qmul(p, q)), sp.dcm(q) @ sp.dcm(p), atol=1e-14)
        v = rng.normal(size=3)
        np.testing.assert_allclose(sp.rot(q, tuple(v)), sp.dcm(q) @ v, atol=1e-14)
        C = sp.dcm(q)
        np.testing.assert_allclose(C @ C.T, np.eye(3), atol=1e-14)
        assert np.linalg.det(C) == pytest.approx(1.0, abs=1e-14)
        qq = np.array(sp.dcm_to_quat(C))
        assert min(np.abs(qq - q).max(), np.abs(qq + q).max()) < 1e-14


def test_euler_123_quaternion():
    phi, theta, psi = 0.1, -0.7, 0.4
    C = sp.R(3, psi) @ sp.R(2, theta) @ sp.R(1, phi)
    np.testing.assert_allclose(sp.dcm(sp.euler123_to_q(phi, theta, psi)), C, atol=1e-15)


def test_kinematics_convention_matches_body_rate():
    # q̇ = ½ q ⊗ (0, w_B) must be the rotation with body rate w_B:  Ċ_BI = −[w×] C_BI
    rng = np.random.default_rng(2)
    q = np.array(rand_quat(rng))
    w = rng.normal(size=3)
    qdot = 0.5 * np.array(sp.qmul(tuple(q), (0.0, *w)))
    eps = 1e-6
    Cdot = (sp.dcm(q + eps * qdot) - sp.dcm(q - eps * qdot)) / (2 * eps)
    wx = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    np.testing.assert_allclose(Cdot, -wx @ sp.dcm(q), atol=1e-8)


# --- orbit ---------------------------------------------------------------------------------------
def test_orbit_frame_quaternion_matches_definition():
    for t in np.linspace(0.0, 6000.0, 13):
        r, v = sp.orbit_rv(t)
        C = sp.c_oi_from_rv(r, v)
        np.testing.assert_allclose(sp.dcm(sp.q_oi(t)), C, atol=2e-15)
        # z to nadir, y along the negative orbit normal, x ≈ along velocity
        np.testing.assert_allclose(C[2], -r / np.linalg.norm(r), atol=1e-15)
        assert C[0] @ v / np.linalg.norm(v) == pytest.approx(1.0, abs=1e-14)


def test_orbit_rate_and_period():
    assert 2 * math.pi / sp.N_ORBIT / 60.0 == pytest.approx(98.4, abs=0.3)  # ≈ 98 min
    assert sp.N_ORBIT / DEG == pytest.approx(0.0612, abs=5e-4)  # 0.06099 °/s
    # Ċ_OI = −[w_OI_O×] C_OI with w_OI_O = (0, −n, 0)
    t, eps = 123.0, 1e-3
    Cdot = (sp.dcm(sp.q_oi(t + eps)) - sp.dcm(sp.q_oi(t - eps))) / (2 * eps)
    w = np.array(sp.W_OI_O)
    wx = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    np.testing.assert_allclose(Cdot, -wx @ sp.dcm(sp.q_oi(t)), atol=1e-12)


def test_orbit_quaternion_is_continuous():
    t = np.arange(0.0, 6000.0, 1.0)
    q = np.array([sp.q_oi(x) for x in t])
    assert np.abs(np.diff(q, axis=0)).max() < 2 * sp.N_ORBIT


# --- CMG cluster ---------------------------------------------------------------------------------
def test_cmg_axes():
    G, S, T = sp.cmg_axes()
    for M in (G, S, T):
        np.testing.assert_allclose(np.linalg.norm(M, axis=0), 1.0, atol=1e-15)
    np.testing.assert_allclose(np.einsum("ij,ij->j", G, S), 0.0, atol=1e-15)
    np.testing.assert_allclose(T, np.cross(G.T, S.T).T, atol=1e-15)
    np.testing.assert_allclose(G[:, 5], [0, 0, 1])
    np.testing.assert_allclose(S[:, 5], [-1, 0, 0])  # reversed spin of gyro 6
    _, P, _ = sp.cmg_axes(reversed_spin=False)
    np.testing.assert_allclose(S, -P)
    # gyro 1 (az = 90°): g = (0, −sin α0, cos α0), paper spin (0, cos α0, sin α0)
    a0 = sp.ALPHA0
    np.testing.assert_allclose(G[:, 0], [0, -math.sin(a0), math.cos(a0)], atol=1e-15)
    np.testing.assert_allclose(P[:, 0], [0, math.cos(a0), math.sin(a0)], atol=1e-15)


def test_jacobian_is_derivative_of_spin():
    rng = np.random.default_rng(3)
    d = rng.uniform(-3, 3, 6)
    eps = 1e-6
    A = sp.jacobian(d)
    for i in range(6):
        e = np.zeros(6)
        e[i] = eps
        fd = (sp.cluster_momentum(d + e) - sp.cluster_momentum(d - e)) / (2 * eps * sp.H_ROTOR)
        np.testing.assert_allclose(fd, A[:, i], atol=1e-9)


def test_initial_momentum_bias():
    h0 = sp.cluster_momentum(sp.DELTA0)
    assert np.linalg.norm(h0) == pytest.approx(57.0, abs=0.5)  # DESIGN.md §4.1: "about 57 N m s"
    assert sp.singularity_measure(np.array(sp.DELTA0))[0] > 0.5


def test_steering_delivers_commanded_torque():
    rng = np.random.default_rng(4)
    for _ in range(10):
        d = rng.uniform(-3, 3, 6)
        w = rng.normal(scale=0.05, size=3)
        tau = rng.normal(scale=4.0, size=3)
        h = sp.cluster_momentum(d)
        cmd = sp.steering(tau, w, h, d)
        hdot = sp.H_ROTOR * sp.jacobian(d) @ cmd
        np.testing.assert_allclose(-hdot - np.cross(w, h), tau, atol=1e-12)
        # minimum norm: no component in the null space of A
        null = np.linalg.svd(sp.jacobian(d))[2][3:]
        np.testing.assert_allclose(null @ cmd, 0.0, atol=1e-12)


@pytest.mark.parametrize(
    "r0,cmd", [(0.0, 0.3), (0.2, -0.1), (-0.55, 2.0), (0.4, 0.4), (0.6, -5.0), (0.1, 0.1004)]
)
def test_servo_closed_form_matches_fine_integration(r0, cmd):
    tau = 2.5
    n = 250000
    dt = tau / n
    target = min(max(cmd, -sp.RATE_MAX), sp.RATE_MAX)
    angle = 0.3
    # literal fine integration: the rate moves toward the clipped command by at most a·dt per
    # step; the angle is the trapezoid integral of the rate
    rates = np.empty(n + 1)
    rates[0] = r = r0
    dv = sp.ACCEL_MAX * dt
    for k in range(n):
        r = r + min(max(target - r, -dv), dv)
        rates[k + 1] = r
    angle_fine = angle + dt * (rates.sum() - 0.5 * (rates[0] + rates[-1]))
    a, rr = sp.servo(angle, r0, cmd, tau)
    assert float(rr) == pytest.approx(rates[-1], abs=1e-12)
    assert float(a) == pytest.approx(angle_fine, abs=1e-9)
    # limits at intermediate times
    ts = np.linspace(0, tau, 101)
    _, rs = sp.servo(np.full(101, angle), np.full(101, r0), np.full(101, cmd), ts)
    assert np.all(np.abs(rs) <= sp.RATE_MAX + 1e-15)
    assert np.all(np.abs(np.diff(rs)) <= sp.ACCEL_MAX * (ts[1] - ts[0]) + 1e-15)


# --- plan and controller -------------------------------------------------------------------------
def test_plan_phase_times_and_profile():
    p = sp.plan()
    assert [p[k] for k in ("t1", "t2", "t3", "t4", "t5")] == pytest.approx(
        [10.0, 30.0, 36.0 + 2.0 / 3.0, 96.0 + 2.0 / 3.0, 100.0], abs=1e-12
    )
    assert p["acc"] / DEG == pytest.approx(-0.24, abs=1e-12)
    assert p["rate"] / DEG == pytest.approx(-2.4, abs=1e-12)
    # integrate the planned acceleration profile exactly: ends at θf with zero rate
    t1, t2, t3, t4, t5, a = (p[k] for k in ("t1", "t2", "t3", "t4", "t5", "acc"))
    th, rt = sp.THETA0, 0.0
    for dur, acc in ((t1, a), (t2 - t1, 0.0), (t3 - t2, -a), (t4 - t3, 0.0), (t5 - t4, -a)):
        th += rt * dur + 0.5 * acc * dur * dur
        rt += acc * dur
        if dur == t4 - t3:
            assert rt == pytest.approx(sp.SCAN_RATE, abs=1e-15)  # imaging phase at −0.8 °/s
    assert th == pytest.approx(sp.THETAF, abs=1e-12)
    assert rt == pytest.approx(0.0, abs=1e-15)
    assert sp.TAU_FF == pytest.approx(-4.0045, abs=1e-4)


@pytest.mark.parametrize("step", [0.1, 0.05, 0.025, 0.01, 0.001])
def test_phase_boundaries_on_the_grid(step):
    # t1 = 10 s and t2 = 30 s are grid points: they belong to the later phase ([t_{k−1}, t_k))
    assert sp.phase_of(round(10.0 / step) * step) == 2
    assert sp.phase_of((round(10.0 / step) - 1) * step) == 1
    assert sp.phase_of(round(30.0 / step) * step) == 3
    assert sp.phase_of((round(30.0 / step) - 1) * step) == 2
    assert sp.phase_of(36.66) == 3 and sp.phase_of(36.67) == 4
    assert sp.phase_of(96.66) == 4 and sp.phase_of(96.67) == 5


def test_pitch_measurement_is_singularity_free():
    for theta in np.radians([120.0, 91.0, 90.0, 89.0, 45.0, 0.0, -3.0]):
        for roll, yaw in ((0.0, 0.0), (0.01, 0.0), (0.0, -0.02)):
            th, ex, ez = sp.pitch_errors(sp.euler123_to_q(roll, theta, yaw))
            assert th == pytest.approx(theta, abs=1e-3)
            # a small roll or yaw reads back as a swing of the same size, at any pitch (the
            # roll axis is seen rotated by the pitch in the body-side swing vector)
            assert math.hypot(ex, ez) == pytest.approx(abs(roll) + abs(yaw), rel=1e-3, abs=1e-12)
        # yaw alone is e_z alone, with the right sign, at any pitch
        _, ex, ez = sp.pitch_errors(sp.euler123_to_q(0.0, theta, 0.01))
        assert ex == pytest.approx(0.0, abs=1e-12) and ez == pytest.approx(0.01, rel=1e-4)
        q = np.array(sp.euler123_to_q(0.0, theta, 0.0))
        assert sp.pitch_errors(tuple(-q))[0] == pytest.approx(theta, abs=1e-12)


@pytest.mark.slow
def test_recorded_torque_and_phase():
    r = run(1e-3)
    t, ph, tau = r["time"], r["phase"], r["tau_cmd"]
    p = sp.plan()
    expect = np.select(
        [t < p["t1"] - 1e-9, t < p["t2"] - 1e-9, t < p["t3"], t < p["t4"]], [1, 2, 3, 4], 5
    )
    np.testing.assert_array_equal(ph, expect)
    ff = sp.I_AXIS * p["acc"]
    np.testing.assert_array_equal(tau[ph == 1, 1], ff)
    np.testing.assert_array_equal(tau[ph == 3, 1], -ff)
    np.testing.assert_array_equal(tau[(ph == 2) | (ph == 4), 1], 0.0)
    assert tau[ph == 1, 1][0] == pytest.approx(-4.0045, abs=1e-4)
    # phase 5: PD on the twist angle
    k = np.nonzero(ph == 5)[0]
    np.testing.assert_allclose(
        tau[k, 1], sp.C1 * (0 - r["pitch"][k]) - sp.C2 * r["w_BO_B"][k, 1], atol=1e-13
    )
    # roll / yaw PD on the singularity-free errors
    for j in (0, len(t) // 3, len(t) - 1):
        _, ex, ez = sp.pitch_errors(tuple(r["q_BO"][j]))
        assert tau[j, 0] == pytest.approx(-86 * ex - 574 * r["w_BO_B"][j, 0], abs=1e-13)
        assert tau[j, 2] == pytest.approx(-86 * ez - 574 * r["w_BO_B"][j, 2], abs=1e-13)


# --- the simulation ------------------------------------------------------------------------------
def test_output_shapes_and_time_grid():
    r = run(0.1)
    n = 1501
    shapes = {
        "time": (n,),
        "q_BO": (n, 4),
        "w_BO_B": (n, 3),
        "w_BI_B": (n, 3),
        "pitch": (n,),
        "delta": (n, 6),
        "delta_dot": (n, 6),
        "h": (n, 3),
        "H_I": (n, 3),
        "tau_cmd": (n, 3),
        "phase": (n,),
    }
    for key, shape in shapes.items():
        assert r[key].shape == shape, key
        assert np.all(np.isfinite(r[key])), key
    np.testing.assert_array_equal(r["time"], np.arange(n) * 0.1)
    with pytest.raises(ValueError):
        sp.simulate(0.07, 1.0)


def test_initial_state():
    r = run(0.1)
    np.testing.assert_allclose(r["q_BO"][0], sp.euler123_to_q(0, 120 * DEG, 0), atol=1e-15)
    assert r["pitch"][0] == pytest.approx(120 * DEG, abs=1e-15)
    np.testing.assert_allclose(r["w_BO_B"][0], 0.0, atol=1e-16)
    np.testing.assert_allclose(r["delta"][0], sp.DELTA0)
    np.testing.assert_array_equal(r["delta_dot"][0], 0.0)
    np.testing.assert_allclose(r["h"][0], sp.cluster_momentum(sp.DELTA0), atol=1e-14)
    # w_BI_B(0) = C_BO w_OI_O: the body only co-rotates with the orbit frame
    np.testing.assert_allclose(
        r["w_BI_B"][0], sp.dcm(r["q_BO"][0]) @ np.array(sp.W_OI_O), atol=1e-16
    )


@pytest.mark.slow
@pytest.mark.parametrize("step", [0.1, 1e-3])
def test_total_angular_momentum_is_conserved(step):
    r = run(step)
    H = r["H_I"]
    assert np.abs(H - H[0]).max() <= 1e-12 * np.linalg.norm(H[0])
    # and its magnitude seen in B: |J w + h| = |H_I|
    L = sp.J_HUB * r["w_BI_B"] + r["h"]
    np.testing.assert_allclose(np.linalg.norm(L, axis=1), np.linalg.norm(H[0]), rtol=1e-13)


@pytest.mark.slow
def test_outputs_consistent_with_hub_equation():
    """Finite differences of the outputs satisfy J ẇ = −w × (J w + h) − ḣ (DESIGN.md §2)."""
    r = run(1e-3)
    dt = 1e-3
    w, h = r["w_BI_B"], r["h"]
    A = np.swapaxes(
        sp.T_AX[None] * np.cos(r["delta"])[:, None, :]
        - sp.S_AX[None] * np.sin(r["delta"])[:, None, :],
        1,
        2,
    )
    hdot = sp.H_ROTOR * np.einsum("kij,ki->kj", A, r["delta_dot"])
    wdot = (w[2:] - w[:-2]) / (2 * dt)
    rhs = (-np.cross(w[1:-1], sp.J_HUB * w[1:-1] + h[1:-1]) - hdot[1:-1]) / sp.J_HUB
    res = sp.J_HUB * np.abs(wdot - rhs).max(axis=1)  # N·m
    # central differences are O(dt²) where the servo is smooth and O(dt) at its kinks (ramp
    # ends, phase switches); a wrong sign of w × h would give ~|w||h| ≈ 2 N·m
    assert np.median(res) < 1e-4
    assert np.percentile(res, 99) < 2e-3
    assert res.max() < 1e-2
    # ḣ from the gimbal rates agrees with the finite difference of h (same kinks)
    res_h = np.abs((h[2:] - h[:-2]) / (2 * dt) - hdot[1:-1]).max(axis=1)
    assert np.median(res_h) < 1e-5
    assert res_h.max() < 1e-2
    # kinematics: q_BI finite difference vs ½ q ⊗ (0, w)
    q = r["q_BI"]
    qd = np.array([sp.qmul(tuple(a), (0.0, *b)) for a, b in zip(q[1:-1:50], w[1:-1:50])]) * 0.5
    np.testing.assert_allclose((q[2::50] - q[:-2:50]) / (2 * dt), qd, atol=1e-8)


def test_relative_outputs_follow_their_definitions():
    r = run(0.1)
    for k in range(0, 1501, 50):
        t = r["time"][k]
        q_bi = tuple(r["q_BI"][k])
        q_bo = sp.qmul(sp.qconj(sp.q_oi(t)), q_bi)
        np.testing.assert_allclose(r["q_BO"][k], q_bo, atol=1e-15)
        w_bo = r["w_BI_B"][k] - sp.dcm(q_bo) @ np.array(sp.W_OI_O)
        np.testing.assert_allclose(r["w_BO_B"][k], w_bo, atol=1e-17)
        assert np.linalg.norm(r["q_BI"][k]) == pytest.approx(1.0, abs=1e-15)


def _simulate_plain(step, stop):
    """A second, deliberately literal implementation from the module's building blocks."""
    n = int(round(stop / step))
    q_bo0 = sp.euler123_to_q(0.0, sp.THETA0, 0.0)
    q_bi = np.array(sp.qmul(sp.q_oi(0.0), q_bo0))
    delta = np.array(sp.DELTA0)
    rate = np.zeros(6)
    w0 = sp.dcm(q_bo0) @ np.array(sp.W_OI_O)
    H = sp.dcm(q_bi).T @ (sp.J_HUB * w0 + sp.cluster_momentum(delta))
    pitch, wbo_all, delta_all = [], [], []
    for k in range(n + 1):
        t = k * step
        q_bo = sp.qmul(sp.qconj(sp.q_oi(t)), tuple(q_bi))
        h = sp.cluster_momentum(delta)
        w_bi = (sp.dcm(q_bi) @ H - h) / sp.J_HUB
        w_bo = w_bi - sp.dcm(q_bo) @ np.array(sp.W_OI_O)
        theta, tau = sp.control(sp.phase_of(t), q_bo, w_bo)
        pitch.append(theta)
        wbo_all.append(w_bo)
        delta_all.append(delta.copy())
        if k == n:
            break
        cmd = sp.steering(tau, w_bi, h, delta)

        def f(q, s):
            hs = sp.cluster_momentum(sp.servo(delta, rate, cmd, s)[0])
            w = (sp.dcm(q / np.linalg.norm(q)) @ H - hs) / sp.J_HUB
            return 0.5 * np.array(sp.qmul(tuple(q), (0.0, *w)))

        k1 = f(q_bi, 0.0)
        k2 = f(q_bi + step / 2 * k1, step / 2)
        k3 = f(q_bi + step / 2 * k2, step / 2)
        k4 = f(q_bi + step * k3, step)
        q_bi = q_bi + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        q_bi /= np.linalg.norm(q_bi)
        delta, rate = sp.servo(delta, rate, cmd, step)
    return np.array(pitch), np.array(wbo_all), np.array(delta_all)


@pytest.mark.slow
def test_fast_loop_agrees_with_literal_implementation():
    # fine run over phases 1–4 (servo in its ramp and hold branches), coarse run into phase 5
    for step, stop in ((0.05, 40.0), (0.5, 100.0)):
        pitch, wbo, delta = _simulate_plain(step, stop)
        r = sp.simulate(step, stop)
        np.testing.assert_allclose(r["pitch"], pitch, atol=1e-11)
        np.testing.assert_allclose(r["w_BO_B"], wbo, atol=1e-13)
        np.testing.assert_allclose(r["delta"], delta, atol=1e-11)


@pytest.mark.slow
def test_self_convergence():
    a, b = run(1e-3), run(5e-4)
    dp = np.abs(a["pitch"] - b["pitch"][::2]).max()
    dw = np.abs(a["w_BO_B"] - b["w_BO_B"][::2]).max()
    # measured: 0.0043° and 4.6e-6 rad/s (first order: zero-order hold of the gimbal command)
    assert dp < 0.01 * DEG
    assert dw < 2e-5
    c = run(0.01)
    dp_coarse = np.abs(c["pitch"] - b["pitch"][::20]).max()
    assert dp_coarse > 3 * dp  # the error shrinks with the step


@pytest.mark.slow
def test_maneuver_physics():
    r = run(1e-3)
    t, pitch, w = r["time"], r["pitch"], r["w_BO_B"]
    p = sp.plan()
    # continuous branch through 90°, no 180° flip
    assert np.abs(np.diff(pitch)).max() < 1e-3 * 0.05
    assert pitch[0] == pytest.approx(120 * DEG)
    assert np.all(np.diff(pitch[t < p["t4"]]) < 0)
    # imaging phase at −0.8 ± 0.02 °/s once the phase-3→4 transient has died out
    img = (t > p["t3"] + 3) & (t < p["t4"])
    assert np.abs(w[img, 1] / DEG + 0.8).max() < 0.02
    # pitch follows the plan closely and ends near 0 (the weak phase-5 PD, c1/c2 ≈ 1/640 s)
    assert abs(pitch[-1]) < 1.0 * DEG
    # roll and yaw held near zero (errors from q_BO): ≈ 0.004° outside the phase-3→4 transient,
    # 0.116° at t ≈ 40.5 s after it (the acceleration-limited gimbals lag the torque step)
    e = np.abs([sp.pitch_errors(tuple(q))[1:] for q in r["q_BO"][::10]]).max(axis=1)
    tt = t[::10]
    assert e.max() < 0.2 * DEG
    assert e[(tt < p["t3"]) | (tt > 100.0)].max() < 0.01 * DEG
    # servo limits, non-singular cluster
    assert np.abs(r["delta_dot"]).max() <= sp.RATE_MAX
    assert np.abs(np.diff(r["delta_dot"], axis=0)).max() <= sp.ACCEL_MAX * 1e-3 * (1 + 1e-12)
    assert sp.singularity_measure(r["delta"][::100]).min() > 0.1
    assert r["Q"].min() > 0.1


def test_twist_angle_equals_euler_pitch_away_from_90_degrees():
    r = run(0.1)
    C = sp._dcm_batch(r["q_BO"])
    theta_euler = -np.arcsin(np.clip(C[:, 0, 2], -1, 1))  # C_BO[1,3] = −sin θ for 1-2-3
    ok = np.abs(r["pitch"]) < 80 * DEG
    assert ok.sum() > 500
    np.testing.assert_allclose(r["pitch"][ok], theta_euler[ok], atol=1e-5)
