"""Reaction-wheel assembly against closed-form wheel dynamics and first principles."""

import math

import numpy as np
import pytest

from agilesat.components.flywheel import Flywheel, wheel_step
from agilesat.components.model import ModelError

RNG = np.random.default_rng(5)
X_WHEEL = [[0, 0, 0], [0, 0, 0], [1.0, 0, 0], [0, 0, 0]]  # one wheel (the 3rd) along x


def wheel(tau=(0.0, 0.0, 0.0), w=(0.0, 0.0, 0.0), **parameters):
    m = Flywheel(**parameters)
    m.set("tau_cmd", tau)
    m.set("w_BI_B", w)
    return m.start()


def body_torque(m, w):
    """Torque the assembly exerts on the body: −hdot − w × h."""
    return -m.get("hdot") - np.cross(w, m.get("h"))


def unit_rows(axes):
    axes = np.asarray(axes, dtype=float)
    norms = np.linalg.norm(axes, axis=1)
    return np.where(norms[:, None] > 0, axes / np.where(norms > 0, norms, 1)[:, None], 0)


# -- momentum and delivered torque ------------------------------------------------------
def test_momentum_is_the_sum_of_J_omega_a():
    for _ in range(10):
        axes = RNG.normal(size=(4, 3)) * RNG.uniform(0.5, 3, size=(4, 1))  # not unit
        speeds, J = RNG.uniform(-300, 300, 4), RNG.uniform(0.01, 0.05)
        m = wheel(axis=axes, speed0=speeds, J_wheel=J, momentum_limit=100.0)
        assert np.allclose(m.get("h"), J * unit_rows(axes).T @ speeds, rtol=1e-13)
        assert np.array_equal(m.get("speed"), speeds)


def test_default_assembly_is_three_orthogonal_wheels_of_a_0_2_Nm_class_wheel():
    m = wheel(speed0=[100.0, -50.0, 20.0, 0.0])
    J = m.p.J_wheel
    assert np.allclose(m.get("h"), [100 * J, -50 * J, 20 * J], rtol=1e-15)
    assert m.p.torque_limit == 0.2
    # momentum limit reached at 6000 rpm
    assert m.p.momentum_limit / J == pytest.approx(6000 * 2 * math.pi / 60, rel=1e-12)


@pytest.mark.parametrize("n_wheels", [3, 4])
def test_delivered_body_torque_is_the_command_within_limits(n_wheels):
    """−hdot − w × h = τ_cmd for random axes, rates, speeds; friction compensated."""
    for _ in range(20):
        axes = RNG.normal(size=(4, 3))
        if n_wheels == 3:
            axes[3] = 0.0
        while np.linalg.cond(unit_rows(axes)[:n_wheels]) > 3:  # keep motor torques small
            axes[:n_wheels] = RNG.normal(size=(n_wheels, 3))
        w = RNG.normal(scale=0.01, size=3)
        tau = RNG.normal(scale=0.02, size=3)
        speeds = RNG.uniform(-200, 200, 4)
        m = wheel(tau, w, axis=axes, speed0=speeds, viscous_friction=2e-5, coulomb_friction=1e-3)
        assert not m.get("saturated")
        assert np.allclose(body_torque(m, w), tau, rtol=0, atol=1e-12)


def test_wheel_at_rest_breaks_away_to_deliver_a_small_torque():
    """At Ω = 0 the drive must exceed the static friction: m = J Ω̇ + c_c sign(J Ω̇)."""
    cc = 1e-3
    m = wheel((0.0, 0.0, -2e-4), coulomb_friction=cc)
    assert m.get("motor_torque")[2] == pytest.approx(2e-4 + cc, rel=1e-12)
    assert np.allclose(body_torque(m, np.zeros(3)), [0, 0, -2e-4], rtol=0, atol=1e-15)


def test_hdot_is_the_derivative_of_h():
    w = np.array([0.01, -0.02, 0.015])
    m = wheel(
        (0.05, -0.03, 0.08),
        w,
        speed0=[200.0, -100.0, 50.0, 0.0],
        viscous_friction=1e-4,
        coulomb_friction=2e-3,
    )
    h0, hdot = m.get("h"), m.get("hdot")
    dt = 1e-6
    m.advance(0.0, dt)
    assert np.allclose((m.get("h") - h0) / dt, hdot, rtol=1e-6, atol=1e-12)


def test_motor_torque_less_friction_is_J_times_the_wheel_acceleration():
    cv, cc = 1e-4, 2e-3
    speeds = np.array([300.0, -100.0, 0.0, 0.0])
    m = wheel(
        (0.05, -0.03, 0.08),
        axis=np.eye(4, 3),
        speed0=speeds,
        viscous_friction=cv,
        coulomb_friction=cc,
    )
    net = m.get("motor_torque")[:3] - cv * speeds[:3] - cc * np.sign(speeds[:3])
    net[2] = m.get("motor_torque")[2] - cc * np.sign(m.get("motor_torque")[2])  # break-away
    assert np.allclose(m.get("hdot"), net, rtol=1e-12, atol=1e-15)


def test_four_wheels_share_the_torque_by_least_squares():
    """Minimum-norm split: the wheel torques have no component along A's null space."""
    beta = math.radians(54.74)
    az = np.radians([45, 135, 225, 315])
    axes = np.column_stack(
        [np.sin(beta) * np.cos(az), np.sin(beta) * np.sin(az), np.full(4, np.cos(beta))]
    )
    m = wheel((0.03, -0.05, 0.07), axis=axes, coulomb_friction=0.0, viscous_friction=0.0)
    torques = m.get("motor_torque")
    null = np.linalg.svd(axes.T)[2][-1]
    assert axes.T @ null == pytest.approx(np.zeros(3), abs=1e-15)
    assert torques @ null == pytest.approx(0.0, abs=1e-15)
    assert np.allclose(axes.T @ torques, -np.array([0.03, -0.05, 0.07]), atol=1e-15)


def test_unused_wheel_reports_zero_and_one_axis_delivers_only_its_component():
    m = wheel(
        (0.01, 0.02, 0.03),
        axis=X_WHEEL,
        speed0=[5.0, 0, 7.0, 0],
        coulomb_friction=0.0,
        viscous_friction=0.0,
    )
    assert np.array_equal(m.get("speed"), [0.0, 0.0, 7.0, 0.0])
    assert m.get("motor_torque")[[0, 1, 3]].tolist() == [0.0, 0.0, 0.0]
    assert np.allclose(body_torque(m, np.zeros(3)), [0.01, 0, 0], atol=1e-15)
    assert any("span only 1" in w for w in m.warnings)
    assert any("speed0[1] ignored" in w for w in m.warnings)


# -- exact wheel dynamics ---------------------------------------------------------------
def test_constant_torque_spin_up_follows_the_viscous_exponential():
    """Motor at the torque limit: Ω(t) = Ω∞ + (Ω0 − Ω∞) e^{−c t / J}, Ω∞ = (m − c_c)/c."""
    J, cv, cc, m_max, omega0 = 0.02, 1e-3, 0.01, 0.2, 30.0
    m = wheel(
        (0.0, 0.0, -5.0),
        J_wheel=J,
        viscous_friction=cv,
        coulomb_friction=cc,
        speed0=[0, 0, omega0, 0],
    )
    omega_inf = (m_max - cc) / cv
    dt = 0.5
    for k in range(80):
        assert m.get("saturated") and m.get("motor_torque")[2] == m_max
        t = k * dt
        expected = omega_inf + (omega0 - omega_inf) * math.exp(-cv * t / J)
        assert m.get("speed")[2] == pytest.approx(expected, rel=1e-13)
        assert m.get("hdot")[2] == pytest.approx(m_max - cv * expected - cc, rel=1e-11)
        m.advance(t, dt)


def test_coulomb_run_down_stops_at_J_omega0_over_cc_and_stays():
    """Motor off (torque_limit = 0): Ω(t) = Ω0 − c_c t / J until rest, then rest."""
    J, cc, omega0 = 0.02, 0.01, -40.0
    t_stop = abs(omega0) * J / cc  # 80 s
    m = wheel(
        J_wheel=J,
        viscous_friction=0.0,
        coulomb_friction=cc,
        torque_limit=0.0,
        speed0=[0, omega0, 0, 0],
    )
    dt = 0.3
    for k in range(400):
        t = (k + 1) * dt
        m.advance(k * dt, dt)
        expected = omega0 + cc * t / J if t < t_stop else 0.0
        assert m.get("speed")[1] == pytest.approx(expected, abs=1e-11)
        if t > t_stop:
            assert m.get("speed")[1] == 0.0 and m.get("hdot")[1] == 0.0


def test_viscous_and_coulomb_run_down_time_is_exact_in_one_step():
    """J Ω̇ = −c Ω − c_c reaches rest at t* = (J/c) ln(1 + c Ω0 / c_c)."""
    J, cv, cc, omega0 = 0.02, 1e-3, 0.01, 120.0
    t_stop = J / cv * math.log(1 + cv * omega0 / cc)
    assert wheel_step(omega0, 0.0, t_stop * (1 - 1e-9), J, cv, cc) > 0
    assert wheel_step(omega0, 0.0, t_stop * (1 + 1e-9), J, cv, cc) == 0.0
    assert wheel_step(omega0, 0.0, 10 * t_stop, J, cv, cc) == 0.0


def reference_speed(omega, m, dt, J, cv, cc, n=200000):
    """Fine explicit integration with the stiction rule, independent of the model."""
    h = dt / n
    for _ in range(n):
        if omega == 0.0 and abs(m) <= cc:
            continue
        s = math.copysign(1.0, omega) if omega != 0.0 else math.copysign(1.0, m)
        new = omega + h * (m - cv * omega - cc * s) / J
        omega = 0.0 if omega != 0.0 and new * omega < 0 else new
    return omega


@pytest.mark.parametrize(
    "omega0, m, dt",
    [
        (50.0, -0.15, 20.0),  # decelerates through zero and spins up the other way
        (50.0, -0.004, 400.0),  # |m| < c_c: stops and sticks
        (0.0, 0.004, 5.0),  # at rest, |m| < c_c: stays
        (0.0, -0.12, 5.0),  # at rest, breaks away
        (-20.0, 0.2, 3.0),  # plain deceleration
    ],
)
def test_wheel_step_matches_fine_integration(omega0, m, dt):
    J, cv, cc = 0.02, 1e-3, 0.01
    assert wheel_step(omega0, m, dt, J, cv, cc) == pytest.approx(
        reference_speed(omega0, m, dt, J, cv, cc), abs=1e-4
    )


def test_one_long_step_equals_many_short_ones():
    """The exact flow composes: Ω(t1 + t2) = Ω(t2; Ω(t1)) with the torque held."""
    J, cv, cc = 0.02, 1e-3, 0.01
    for omega0, m in [(50.0, -0.15), (80.0, 0.0), (-5.0, 0.3), (0.0, -0.05)]:
        one = wheel_step(omega0, m, 30.0, J, cv, cc)
        many = omega0
        for _ in range(300):
            many = wheel_step(many, m, 0.1, J, cv, cc)
        assert many == pytest.approx(one, rel=1e-9, abs=1e-9)


def test_resting_wheel_does_not_chatter():
    """Sub-break-away torques, tiny steps: the wheel stays exactly at rest."""
    m = wheel(
        (0.0, 0.0, 0.0), torque_limit=5e-4, coulomb_friction=5e-4, speed0=[0.0, 0.0, 0.0, 0.0]
    )
    for k in range(2000):
        m.set("tau_cmd", [0.0, 0.0, 0.01 * (-1) ** k])  # drive clips at c_c: no break-away
        m.advance(k * 1e-3, 1e-3)
        assert m.get("speed").tolist() == [0.0] * 4 and m.get("hdot").tolist() == [0.0] * 3


# -- limits -------------------------------------------------------------------------------
def test_torque_saturation_clips_each_motor_and_is_reported():
    m = wheel((0.5, -0.1, 0.0), viscous_friction=0.0, coulomb_friction=0.0)
    assert m.get("saturated")
    assert m.get("motor_torque")[:3].tolist() == [-0.2, 0.1, 0.0]
    assert np.allclose(body_torque(m, np.zeros(3)), [0.2, -0.1, 0.0], atol=1e-15)
    m.advance(0.0, 0.1)
    assert any("wheel 1 motor torque at the limit" in w for w in m.warnings)


def test_momentum_limit_holds_the_wheel_and_releases_it():
    J, h_max, cv, cc = 0.02, 2.0, 1e-4, 1e-3
    speed_max = h_max / J
    m = wheel(
        (0.0, -0.1, 0.0),
        J_wheel=J,
        momentum_limit=h_max,
        viscous_friction=cv,
        coulomb_friction=cc,
        speed0=[0, speed_max - 2.0, 0, 0],
    )
    assert not m.get("saturated")
    for k in range(40):  # 2 rad/s at 5 rad/s² takes 0.4 s: reached in the 4th step
        m.advance(k * 0.1, 0.1)
        assert m.get("speed")[1] <= speed_max
    assert m.get("speed")[1] == speed_max and m.get("h")[1] == pytest.approx(h_max)
    assert m.get("saturated") and m.get("hdot")[1] == 0.0
    assert m.get("motor_torque")[1] == pytest.approx(cv * speed_max + cc)  # holds speed
    assert sum("held at the momentum limit" in w for w in m.warnings) == 1
    m.set("tau_cmd", [0.0, 0.1, 0.0])  # unload
    m.output()
    assert not m.get("saturated") and m.get("hdot")[1] == pytest.approx(-0.1)
    m.advance(4.0, 0.1)
    assert m.get("speed")[1] < speed_max


def test_other_wheels_keep_delivering_when_one_saturates():
    m = wheel(
        (0.01, -0.1, 0.02),
        J_wheel=0.02,
        momentum_limit=2.0,
        viscous_friction=0.0,
        coulomb_friction=0.0,
        speed0=[0, 100.0, 0, 0],
    )
    torque = body_torque(m, np.zeros(3))
    assert m.get("saturated") and torque == pytest.approx([0.01, 0.0, 0.02], abs=1e-15)


@pytest.mark.parametrize(
    "parameters, message",
    [
        (dict(axis=np.zeros((4, 3))), "no wheel"),
        (dict(J_wheel=0.0), "J_wheel"),
        (dict(momentum_limit=-1.0), "momentum_limit"),
        (dict(coulomb_friction=-1e-3), "must not be negative"),
    ],
)
def test_bad_parameters_are_rejected(parameters, message):
    with pytest.raises(ModelError, match=message):
        Flywheel(**parameters).start()
