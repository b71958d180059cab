"""SatelliteDynamics against closed-form rigid-body solutions and conservation laws."""

import numpy as np
import pytest

from agilesat.components.model import ModelError
from agilesat.components.rotations import (
    dcm_from_quat,
    quat_from_axis_angle,
    quat_from_euler123,
    quat_mul,
)
from agilesat.components.satellite_dynamics import SatelliteDynamics


def body(**parameters):
    """A body in inertial space (O = I: q_OI identity, w_OI_O zero), gravity gradient off."""
    return SatelliteDynamics(gravity_gradient=False, **parameters)


def test_torque_free_axisymmetric_body_cones_at_the_body_rate():
    """J = diag(I1, I1, I3): w3 fixed, (w1 + i w2) turns at λ = (I3 − I1) w3 / I1."""
    I1, I3 = 100.0, 160.0
    w0 = np.array([0.03, -0.01, 0.2])
    m = body(inertia=np.diag([I1, I1, I3]), rate0=w0).start()
    lam = (I3 - I1) * w0[2] / I1
    dt = 0.1
    for k in range(600):
        m.advance(k * dt, dt)
        t = (k + 1) * dt
        transverse = (w0[0] + 1j * w0[1]) * np.exp(1j * lam * t)
        expected = np.array([transverse.real, transverse.imag, w0[2]])
        assert np.allclose(m.get("w_BI_B"), expected, rtol=0, atol=1e-10)


def test_torque_free_body_keeps_momentum_and_energy():
    J = np.array([[120.0, 3.0, -2.0], [3.0, 90.0, 1.0], [-2.0, 1.0, 150.0]])
    m = body(inertia=J, rate0=[0.05, -0.1, 0.07]).start()
    H0, E0 = m.get("H_I"), m.get("w_BI_B") @ J @ m.get("w_BI_B")
    for k in range(1000):
        m.advance(k * 0.05, 0.05)
    w = m.get("w_BI_B")
    assert np.allclose(m.get("H_I"), H0, rtol=1e-14, atol=0)
    assert w @ J @ w == pytest.approx(E0, rel=1e-9)
    C_BI = dcm_from_quat(m.get("q_BI"))
    assert np.allclose(C_BI.T @ (J @ w), H0, rtol=1e-12)


def test_constant_torque_spins_up_about_a_principal_axis():
    """τ along z from rest: w3 = τ t / J3, rotation angle ½ τ t² / J3 about z."""
    J3, tau, dt = 200.0, 0.5, 0.2
    m = body(inertia=np.diag([100.0, 150.0, J3])).start()
    m.set("tau_ext", [0.0, 0.0, tau])
    for k in range(250):
        m.advance(k * dt, dt)
    t = 250 * dt
    assert m.get("w_BI_B") == pytest.approx([0, 0, tau * t / J3], abs=1e-13)
    expected = quat_from_axis_angle([0, 0, 1], 0.5 * tau * t**2 / J3)
    assert np.allclose(m.get("q_BI"), expected, atol=1e-11)


def test_internal_momentum_counter_rotates_the_hub():
    """A device spinning up along z at ḣ from rest: H = 0, so w = −h / J3 about z."""
    J3, hdot, dt = 80.0, 0.3, 0.5
    m = body(inertia=np.diag([60.0, 70.0, J3])).start()
    m.set("hdot_wheel", [0.0, 0.0, hdot])
    for k in range(100):
        m.set("h_wheel", [0.0, 0.0, hdot * k * dt])  # h at the start of each step
        m.advance(k * dt, dt)
    t = 100 * dt
    m.set("h_wheel", [0.0, 0.0, hdot * t])
    m.output()
    assert m.get("w_BI_B") == pytest.approx([0, 0, -hdot * t / J3], abs=1e-14)
    expected = quat_from_axis_angle([0, 0, 1], -0.5 * hdot * t**2 / J3)
    assert np.allclose(m.get("q_BI"), expected, atol=1e-12)
    assert np.allclose(m.get("H_I"), 0.0, atol=1e-14)


def test_devices_never_change_the_total_momentum():
    """Any device motion is internal: H_I stays fixed to rounding, whatever the step."""
    rng = np.random.default_rng(3)
    J = np.diag([300.0, 250.0, 400.0])
    m = body(inertia=J, rate0=[0.01, 0.02, -0.03]).start()
    H0 = m.get("H_I")
    for k in range(400):
        for device in ("cmg", "wheel", "payload"):
            m.set(f"h_{device}", rng.normal(scale=20, size=3))
            m.set(f"hdot_{device}", rng.normal(scale=5, size=3))
        m.advance(k * 0.1, 0.1)
        h_total = sum(m.get(f"h_{d}") for d in ("cmg", "wheel", "payload"))
        C_BI = dcm_from_quat(m.get("q_BI"))
        assert np.allclose(C_BI.T @ (J @ m.get("w_BI_B") + h_total), H0, rtol=1e-12)
    assert np.allclose(m.get("H_I"), H0, rtol=1e-13, atol=0)


def test_gravity_gradient_torque_is_three_mu_over_r5_r_cross_jr():
    mu, r_I = 3.986004418e14, np.array([7.0e6, 1.0e6, -2.0e6])
    J = np.diag([100.0, 200.0, 300.0])
    m = SatelliteDynamics(inertia=J, attitude0=[0.3, -0.2, 0.5], mu=mu)
    m.set("r_I", r_I)
    m.start()
    H0, C_BI = m.get("H_I"), dcm_from_quat(m.get("q_BI"))
    dt = 1e-3
    m.advance(0.0, dt)
    r_B = C_BI @ r_I
    tau_B = 3 * mu / np.linalg.norm(r_I) ** 5 * np.cross(r_B, J @ r_B)
    assert np.allclose((m.get("H_I") - H0) / dt, C_BI.T @ tau_B, rtol=1e-5)


def test_isotropic_body_feels_no_gravity_gradient():
    m = SatelliteDynamics(inertia=956.0 * np.eye(3), attitude0=[0.3, 1.0, -0.5])
    m.set("r_I", [7.0e6, 0.0, 0.0])
    m.start()
    H0 = m.get("H_I")
    for k in range(100):
        m.advance(k, 1.0)
    assert np.allclose(m.get("H_I"), H0, rtol=0, atol=1e-12)


def test_initial_state_relative_to_a_rotating_orbit_frame():
    q_OI = quat_from_axis_angle([0.2, -1.0, 0.4], 0.7)
    w_OI_O = np.array([0.0, -1.06e-3, 0.0])
    attitude, rate = np.array([0.1, 2.0, -0.2]), np.array([1e-3, -2e-3, 3e-3])
    m = SatelliteDynamics(attitude0=attitude, rate0=rate, gravity_gradient=False)
    m.set("q_OI", q_OI)
    m.set("w_OI_O", w_OI_O)
    m.start()
    q_BO = quat_from_euler123(attitude)
    assert np.allclose(m.get("euler_BO"), attitude, atol=1e-12)
    assert np.allclose(m.get("w_BO_B"), rate, atol=1e-15)
    assert np.allclose(
        dcm_from_quat(m.get("q_BI")), dcm_from_quat(quat_mul(q_OI, q_BO)), atol=1e-14
    )
    C_BO = dcm_from_quat(q_BO)
    assert np.allclose(m.get("w_BI_B"), rate + C_BO @ w_OI_O, atol=1e-15)


@pytest.mark.parametrize(
    "inertia, message",
    [
        (np.array([[1.0, 0.5, 0], [0, 1.0, 0], [0, 0, 1.0]]), "symmetric"),
        (np.diag([1.0, -1.0, 1.0]), "positive definite"),
        (np.diag([100.0, 100.0, 300.0]), "no rigid body has it: its largest principal moment"),
    ],
)
def test_bad_inertia_is_rejected(inertia, message):
    """Symmetric, positive definite and within the triangle inequality of principal
    moments (a plate, J_z = J_x + J_y, is the limit: test_gravity_gradient_needs_a_position)."""
    with pytest.raises(ModelError, match=message):
        body(inertia=inertia).start()


def test_gravity_gradient_needs_a_position():
    m = SatelliteDynamics(inertia=np.diag([1.0, 2.0, 3.0]), r_I=[0.0, 0.0, 0.0]).start()
    with pytest.raises(ModelError, match="r_I is zero"):
        m.step(0.0, 0.1)


def test_orbit_attitude_input_must_be_a_quaternion():
    m = body()
    m.set("q_OI", [0.0, 0.0, 0.0, 0.0])
    with pytest.raises(ModelError, match="unit quaternion"):
        m.start()
