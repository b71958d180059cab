"""Quaternion PD law with feedforward: signs, shortest path, continuity, closed loops."""

import math

import numpy as np
import pytest

from agilesat.components.attitude_controller import AttitudeController
from agilesat.components.flywheel import Flywheel
from agilesat.components.model import ModelError
from agilesat.components.rotations import (
    dcm_from_quat,
    euler123_from_quat,
    quat_conj,
    quat_from_axis_angle,
    quat_mul,
)
from agilesat.components.satellite_dynamics import SatelliteDynamics

RNG = np.random.default_rng(17)
AXES = np.eye(3)


def random_quat():
    q = RNG.normal(size=4)
    return q / np.linalg.norm(q)


def random_axis():
    v = RNG.normal(size=3)
    return v / np.linalg.norm(v)


def control(
    q_BI,
    w_BI_B=(0, 0, 0),
    q_ref=(1, 0, 0, 0),
    w_ref=(0, 0, 0),
    h_ff=(0, 0, 0),
    hdot_ff=(0, 0, 0),
    **parameters,
):
    c = AttitudeController(**parameters)
    for name, value in (
        ("q_BI", q_BI),
        ("w_BI_B", w_BI_B),
        ("q_ref", q_ref),
        ("w_ref", w_ref),
        ("h_ff", h_ff),
        ("hdot_ff", hdot_ff),
    ):
        c.set(name, value)
    return c.start()


def vee(M):
    """v with [v×] = M for a skew-symmetric M."""
    return np.array([M[2, 1], M[0, 2], M[1, 0]])


# -- attitude error -----------------------------------------------------------------------
@pytest.mark.parametrize("k", range(3))
def test_small_positive_error_about_each_axis_gives_a_restoring_torque(k):
    """B turned +θ about axis k from R (q_BI = q_RI ⊗ q_BR): torque −kp θ about axis k."""
    theta = 0.01
    q_ref = random_quat()
    c = control(quat_mul(q_ref, quat_from_axis_angle(AXES[k], theta)), q_ref=q_ref)
    assert np.allclose(c.get("att_error"), theta * AXES[k], rtol=0, atol=1e-14)
    tau = c.get("tau_cmd")
    assert tau[k] < 0
    assert np.allclose(tau, -c.p.kp[k] * theta * AXES[k], rtol=0, atol=1e-13)


def test_error_is_the_principal_rotation_vector_of_C_BR():
    """φ = arccos((tr C_BR − 1)/2), n sin φ = vee((C_BRᵀ − C_BR)/2), for either sign of q."""
    for _ in range(200):
        q_BI, q_ref = random_quat(), random_quat()
        C_BR = dcm_from_quat(q_BI) @ dcm_from_quat(q_ref).T
        phi = math.acos(np.clip((np.trace(C_BR) - 1) / 2, -1, 1))
        if not 1e-3 < phi < math.pi - 1e-3:
            continue
        expected = phi / math.sin(phi) * vee((C_BR.T - C_BR) / 2)
        for s1, s2 in ((1, 1), (-1, 1), (1, -1), (-1, -1)):
            error = control(s1 * q_BI, q_ref=s2 * q_ref).get("att_error")
            assert np.allclose(error, expected, rtol=1e-9, atol=1e-12)
            assert np.linalg.norm(error) <= math.pi


@pytest.mark.parametrize("theta_deg", [181.0, 200.0, 270.0, 359.0])
def test_error_takes_the_short_way_round(theta_deg):
    """A turn of θ > 180° about n is the turn of −(360° − θ) about n."""
    n, q_ref = random_axis(), random_quat()
    theta = math.radians(theta_deg)
    c = control(quat_mul(q_ref, quat_from_axis_angle(n, theta)), q_ref=q_ref)
    assert np.allclose(c.get("att_error"), -(2 * math.pi - theta) * n, atol=1e-12)
    assert n @ c.get("tau_cmd") > 0  # pushed on the way the angle is shortest


def test_error_is_continuous_through_90_degrees_and_up_to_180():
    """Sweep 0 → 179.9° about a fixed axis (sign of q_BI flipped every sample)."""
    n, q_ref = random_axis(), random_quat()
    angles = np.radians(np.arange(0.0, 179.9, 0.05))
    c = control(q_ref, q_ref=q_ref)
    errors = []
    for i, a in enumerate(angles):
        c.set("q_BI", (-1) ** i * quat_mul(q_ref, quat_from_axis_angle(n, a)))
        c.output()
        errors.append(c.get("att_error"))
    errors = np.array(errors)
    assert np.allclose(errors, angles[:, None] * n, rtol=0, atol=1e-12)
    steps = np.linalg.norm(np.diff(errors, axis=0), axis=1)
    assert steps.max() <= math.radians(0.05) * (1 + 1e-9)


@pytest.mark.parametrize("offset", [-1e-9, 0.0, 1e-9, 1e-4])
def test_error_is_bounded_at_and_near_180_degrees(offset):
    n, q_ref = random_axis(), random_quat()
    c = control(quat_mul(q_ref, quat_from_axis_angle(n, math.pi + offset)), q_ref=q_ref)
    error = c.get("att_error")
    assert np.linalg.norm(error) == pytest.approx(math.pi - abs(offset), abs=1e-9)
    assert abs(abs(error @ n) - np.linalg.norm(error)) < 1e-9  # along ±n
    assert np.all(np.isfinite(c.get("tau_cmd")))


def test_pitch_of_120_degrees_is_an_error_of_120_degrees_about_y():
    """The scan_pitch start (pitch 120°, beyond the 1-2-3 Euler singularity)."""
    c = control(quat_from_axis_angle([0, 1, 0], math.radians(120)))
    assert np.allclose(c.get("att_error"), [0, math.radians(120), 0], atol=1e-14)


def test_attitude_inputs_must_be_quaternions():
    with pytest.raises(ModelError, match="unit quaternions"):
        control([0, 0, 0, 0])


# -- rate error ---------------------------------------------------------------------------
def body_rate(q_of_t, t, h=1e-6):
    """w of a frame X relative to its reference, in X: (0, w) = 2 q* ⊗ q̇ (q̇ = ½ q ⊗ (0, w))."""
    q_dot = (q_of_t(t + h) - q_of_t(t - h)) / (2 * h)
    return 2 * quat_mul(quat_conj(q_of_t(t)), q_dot)[1:]


def test_rate_error_is_the_rate_of_B_relative_to_a_rotating_reference():
    u1, u2, u3 = random_axis(), random_axis(), random_axis()
    q_RI = lambda t: quat_mul(
        quat_from_axis_angle(u1, 0.3 * t + 0.02 * t * t), quat_from_axis_angle(u2, -0.1 * t)
    )
    for q_BR in (
        lambda t: quat_from_axis_angle(u3, 0.7),  # rides with R
        lambda t: quat_from_axis_angle(u3, 0.7 + 0.05 * t),
    ):  # turns within R
        q_BI = lambda t: quat_mul(q_RI(t), q_BR(t))
        for t in (0.0, 1.3, 4.0):
            c = control(q_BI(t), body_rate(q_BI, t), q_RI(t), body_rate(q_RI, t))
            assert np.allclose(c.get("rate_error"), body_rate(q_BR, t), atol=1e-8)
    assert np.allclose(body_rate(lambda t: quat_from_axis_angle(u3, 0.7), 1.0), 0, atol=1e-12)


def test_gains_act_per_axis():
    kp, kd = np.array([1.0, 2.0, 3.0]), np.array([10.0, 20.0, 30.0])
    q_BI, w = random_quat(), RNG.normal(scale=0.01, size=3)
    c = control(q_BI, w, kp=kp, kd=kd)
    assert np.allclose(
        c.get("tau_cmd"),
        -kp * c.get("att_error") - kd * c.get("rate_error"),
        rtol=1e-14,
        atol=1e-15,
    )
    assert np.allclose(c.get("rate_error"), w, atol=1e-17)  # inertial reference at rest


# -- feedforward -------------------------------------------------------------------------
def test_feedforward_exactly_cancels_the_device_torque():
    """On target, the body feels τ_cmd + (−hdot − w × h) = 0 from controller and device."""
    for _ in range(20):
        q, w = random_quat(), RNG.normal(scale=0.05, size=3)
        h, hdot = RNG.normal(scale=5, size=3), RNG.normal(scale=0.2, size=3)
        w_ref = w  # R = B: no attitude or rate error
        c = control(q, w, q, w_ref, h, hdot)
        assert np.allclose(c.get("att_error"), 0, atol=1e-15)
        assert np.allclose(c.get("rate_error"), 0, atol=1e-15)
        assert np.allclose(c.get("tau_cmd") - hdot - np.cross(w, h), 0, atol=1e-14)


def test_feedforward_adds_to_the_pd_torque():
    q, q_ref, w = random_quat(), random_quat(), RNG.normal(scale=0.05, size=3)
    h, hdot = RNG.normal(scale=5, size=3), RNG.normal(scale=0.2, size=3)
    without = control(q, w, q_ref).get("tau_cmd")
    with_ff = control(q, w, q_ref, h_ff=h, hdot_ff=hdot).get("tau_cmd")
    assert np.allclose(with_ff - without, hdot + np.cross(w, h), atol=1e-13)


# -- closed loops ------------------------------------------------------------------------
J_SAT = 150.0  # kg·m², the [Chang 2015] satellite the default gains are designed for


def second_order(theta0, t, wn, zeta):
    """θ(t) of J θ̈ + kd θ̇ + kp θ = 0 from rest at θ0 (underdamped)."""
    root = math.sqrt(1 - zeta**2)
    wd = wn * root
    return theta0 * math.exp(-zeta * wn * t) * (math.cos(wd * t) + zeta / root * math.sin(wd * t))


def run_loop(theta0, axis, dt, n_steps, wheels=None, device=None, feedforward=True):
    """Controller → (wheels →) satellite, inertial hold, Gauss-Seidel at each point:
    states first (wheel h), then body rates, control law, wheel hdot.  Starts at rest,
    turned θ0 about ``axis``; returns times, angle about ``axis``, H_I."""
    q0 = quat_from_axis_angle(axis, theta0)
    body = SatelliteDynamics(
        inertia=J_SAT * np.eye(3), gravity_gradient=False, attitude0=euler123_from_quat(q0)
    ).start()
    assert np.allclose(abs(body.get("q_BI") @ q0), 1.0, atol=1e-14)
    ctrl = AttitudeController().start()
    if wheels is not None:
        wheels.start()
    times, angles, momenta = [], [], []
    for k in range(n_steps + 1):
        t = k * dt
        h_dev, hdot_dev = device(t) if device else (np.zeros(3), np.zeros(3))
        body.set("h_payload", h_dev)
        body.set("hdot_payload", hdot_dev)
        if wheels is not None:
            body.set("h_wheel", wheels.get("h"))  # state output: no feedthrough
        body.output()
        ctrl.set("q_BI", body.get("q_BI"))
        ctrl.set("w_BI_B", body.get("w_BI_B"))
        if feedforward:
            ctrl.set("h_ff", h_dev)
            ctrl.set("hdot_ff", hdot_dev)
        ctrl.output()
        times.append(t)
        angles.append(ctrl.get("att_error") @ axis)
        momenta.append(body.get("H_I"))
        if k == n_steps:
            break
        if wheels is None:
            body.set("tau_ext", ctrl.get("tau_cmd"))
        else:
            wheels.set("tau_cmd", ctrl.get("tau_cmd"))
            wheels.set("w_BI_B", body.get("w_BI_B"))
            wheels.output()
            body.set("hdot_wheel", wheels.get("hdot"))
            wheels.advance(t, dt)  # state and h at t + dt
        body.step(t, dt)
        ctrl.step(t, dt)
    return np.array(times), np.array(angles), np.array(momenta)


def test_default_gains_give_the_designed_second_order_response():
    """J θ̈ = −kp θ − kd θ̇ with ω_n = 0.2 rad/s, ζ = 1/√2 (external torque, ideal actuator)."""
    theta0, axis = math.radians(1.0), random_axis()
    t, angle, _ = run_loop(theta0, axis, 0.05, 1200)
    expected = np.array([second_order(theta0, x, 0.2, 1 / math.sqrt(2)) for x in t])
    assert np.abs(angle - expected).max() < 0.01 * theta0  # sample-and-hold lag only


def test_wheels_in_the_loop_deliver_the_commanded_torque():
    """Same response through the reaction wheels (signs of τ_cmd, h, hdot, −w × h), and
    the wheels exchange momentum only: H_I stays zero."""
    theta0, axis = math.radians(1.0), random_axis()
    wheels = Flywheel()
    t, angle, H = run_loop(theta0, axis, 0.05, 1200, wheels=wheels)
    expected = np.array([second_order(theta0, x, 0.2, 1 / math.sqrt(2)) for x in t])
    assert np.abs(angle - expected).max() < 0.01 * theta0
    assert np.abs(H).max() < 1e-12
    assert not wheels.warnings


@pytest.mark.slow
@pytest.mark.parametrize("feedforward, dt", [(False, 0.1), (True, 0.1), (True, 0.05)])
def test_feedforward_removes_a_periodic_device_disturbance(feedforward, dt):
    """Device h = A sin(ω t) about z, torque −A ω cos(ω t) on the body.

    Without feedforward the body answers with the forced amplitude
    A ω / |J (ω_n² − ω²) + i kd ω|.  With it, what remains is the sample-and-hold lag:
    the wheels hold the compensating torque over a step while the device's torque moves
    on, a residual torque of A ω · ω dt/2 in amplitude, so the error shrinks by ω dt/2."""
    A, omega = 0.2, 2 * math.pi / 10
    device = lambda t: (
        np.array([0, 0, A * math.sin(omega * t)]),
        np.array([0, 0, A * omega * math.cos(omega * t)]),
    )
    kp, kd = J_SAT * 0.2**2, 2 / math.sqrt(2) * 0.2 * J_SAT
    forced = A * omega / abs(J_SAT * (kp / J_SAT - omega**2) + 1j * kd * omega)
    wheels = Flywheel()
    t, angle, _ = run_loop(
        0.0,
        np.array([0, 0, 1.0]),
        dt,
        round(200 / dt),
        wheels=wheels,
        device=device,
        feedforward=feedforward,
    )
    late = np.abs(angle[t >= 150]).max()  # transients (e^{-ζ ω_n t}) long gone
    expected = forced * (omega * dt / 2 if feedforward else 1.0)
    assert late == pytest.approx(expected, rel=0.05)
    assert not wheels.warnings  # within the wheels' torque and momentum


# -- acceleration feedforward (extension) --------------------------------------------------
J_TILTED = np.array([[900.0, 40.0, -25.0], [40.0, 1000.0, 30.0], [-25.0, 30.0, 800.0]])


def track_spin_up(feedforward: bool, dt=0.01, T=20.0, alpha=0.002):
    """Reference R spun up about a fixed axis n (in I) from rest: angle φ = ½ α t², so
    q_RI = (cos(φ/2), n sin(φ/2)) (the solution of q̇ = ½ q ⊗ (0, φ̇ n)), w_ref = α t n and
    dw_ref = α n in R axes (n is fixed in R too).  The body starts on the reference, with
    an off-principal inertia (gyroscopic torque w × J w ≠ 0) and weak gains; ideal torque.
    Returns the largest attitude error (rad)."""
    n = np.array([1.0, 2.0, 2.0]) / 3.0
    body = SatelliteDynamics(inertia=J_TILTED, gravity_gradient=False).start()
    ctrl = AttitudeController(
        kp=[1.0] * 3, kd=[30.0] * 3, inertia=J_TILTED, acceleration_feedforward=feedforward
    ).start()
    worst = 0.0
    for k in range(int(round(T / dt)) + 1):
        t = k * dt
        phi = 0.5 * alpha * t * t
        body.output()
        for name, value in (
            ("q_BI", body.get("q_BI")),
            ("w_BI_B", body.get("w_BI_B")),
            ("q_ref", np.concatenate(([math.cos(phi / 2)], n * math.sin(phi / 2)))),
            ("w_ref", alpha * t * n),
            ("dw_ref", alpha * n),
        ):
            ctrl.set(name, value)
        ctrl.output()
        worst = max(worst, np.linalg.norm(ctrl.get("att_error")))
        body.set("tau_ext", ctrl.get("tau_cmd"))
        body.step(t, dt)
        ctrl.step(t, dt)
    return worst


@pytest.mark.slow
def test_acceleration_feedforward_makes_the_body_follow_an_accelerating_reference():
    """J ẇ_des + w × J w: the error left is the torque's sample-and-hold over a step,
    O(α dt) against the PD-only lag, which grows with the reference rate."""
    with_ff, without = track_spin_up(True), track_spin_up(False)
    assert with_ff < 1e-5 and without > 0.05
    assert track_spin_up(True, dt=0.005) < 0.6 * with_ff  # and shrinks with dt


def test_no_acceleration_feedforward_unless_switched_on():
    """Default off: dw_ref and the inertia do nothing (the law of DESIGN.md §3)."""
    q = random_quat()
    plain = control(q, w_BI_B=(0.01, -0.02, 0.03))
    c = AttitudeController(inertia=J_TILTED)
    for name, value in (("q_BI", q), ("w_BI_B", (0.01, -0.02, 0.03)), ("dw_ref", (1.0, 2.0, 3.0))):
        c.set(name, value)
    c.start()
    assert np.array_equal(c.get("tau_cmd"), plain.get("tau_cmd"))


def test_acceleration_feedforward_without_an_inertia_is_rejected():
    with pytest.raises(ModelError, match="acceleration_feedforward is on but inertia is zero"):
        AttitudeController(acceleration_feedforward=True).start()


def test_asymmetric_feedforward_inertia_is_rejected():
    with pytest.raises(ModelError, match="inertia must be a finite symmetric matrix"):
        AttitudeController(inertia=[[1, 2, 0], [0, 1, 0], [0, 0, 1]]).start()


@pytest.mark.slow
def test_feedforward_keeps_the_rate_error_constant_for_any_reference_motion():
    """kp = kd = 0: with the exact feedforward J ẇ_des + w × J w the body's acceleration
    is that of the reference seen in B, so the rate error w − C_BR w_ref stays constant
    whatever the reference does (axis moving in R, non-principal J, body off the
    reference).  Rigid body, body and reference integrated together here with RK4, the
    law evaluated at every stage (continuous time)."""

    def w_ref(t):
        return np.array([0.02 * math.sin(0.3 * t), 0.03 * math.cos(0.2 * t), 0.01 + 0.002 * t])

    def dw_ref(t):
        return np.array([0.006 * math.cos(0.3 * t), -0.006 * math.sin(0.2 * t), 0.002])

    ctrl = AttitudeController(
        kp=[0.0] * 3, kd=[0.0] * 3, inertia=J_TILTED, acceleration_feedforward=True
    ).start()

    def f(t, x):
        qB, w, qR = x[:4], x[4:7], x[7:]
        for name, value in (
            ("q_BI", qB),
            ("w_BI_B", w),
            ("q_ref", qR),
            ("w_ref", w_ref(t)),
            ("dw_ref", dw_ref(t)),
        ):
            ctrl.set(name, value)
        ctrl.output()
        wdot = np.linalg.solve(J_TILTED, ctrl.get("tau_cmd") - np.cross(w, J_TILTED @ w))
        return np.concatenate(
            (0.5 * quat_mul(qB, np.r_[0.0, w]), wdot, 0.5 * quat_mul(qR, np.r_[0.0, w_ref(t)]))
        )

    def rate_error(x, t):
        C_BR = dcm_from_quat(x[:4]) @ dcm_from_quat(x[7:]).T
        return x[4:7] - C_BR @ w_ref(t)

    qR = np.array([1.0, 0.0, 0.0, 0.0])
    qB = quat_mul(qR, quat_from_axis_angle([0.3, -0.2, 0.4], 0.54))
    x = np.concatenate((qB, dcm_from_quat(qB) @ w_ref(0.0) + [0.01, -0.02, 0.015], qR))
    e0, dt, worst = rate_error(x, 0.0), 0.01, 0.0
    for k in range(3000):
        t = k * dt
        k1 = f(t, x)
        k2 = f(t + dt / 2, x + dt / 2 * k1)
        k3 = f(t + dt / 2, x + dt / 2 * k2)
        k4 = f(t + dt, x + dt * k3)
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        worst = max(worst, np.linalg.norm(rate_error(x, t + dt) - e0))
    assert worst < 1e-10 * np.linalg.norm(e0)
