"""The five-phase pitch law of [Zhao 2016] (eqs 6–11) and its errata."""

import math

import numpy as np
import pytest

from agilesat.components.model import ModelError
from agilesat.components.pitch_maneuver_controller import PitchManeuverController, PitchProfile
from agilesat.components.rotations import quat_from_axis_angle, quat_from_euler123

DEG = math.pi / 180
PAPER = PitchProfile(theta0=120 * DEG, theta_f=0.0, duration=100.0, scan_rate=-0.8 * DEG)


def test_phase_times_follow_the_papers_planning():
    """t1 = T/10, t2 − t1 = 2T/10, t4 − t3 = 6T/10, (t5 − t4) + (t3 − t2) = t1 (§4)."""
    t1, t2, t3, t4, t5 = PAPER.times
    assert (t1, t2, t5) == pytest.approx((10.0, 30.0, 100.0))
    assert t4 - t3 == pytest.approx(60.0) and (t5 - t4) + (t3 - t2) == pytest.approx(t1)
    assert (t3, t4) == pytest.approx((36.6667, 96.6667), abs=1e-4)


def test_acceleration_rate_and_torque_match_eqs_8_to_10():
    assert PAPER.accel / DEG == pytest.approx(-0.24)
    assert PAPER.rate_max / DEG == pytest.approx(-2.4)
    assert 956 * PAPER.accel == pytest.approx(-4.0, abs=0.01)  # T_cym ≈ −4.0 N·m


def test_printed_closed_forms_have_the_wrong_sign():
    """Paper: θ̈m = −100θ_T/(3T²) − 20θ̇0/T; the physics needs +100θ_T/(3T²) − 20θ̇0/T."""
    theta_T, T, rate0 = -120.0, 100.0, -0.8
    printed = -100 * theta_T / (3 * T**2) - 20 * rate0 / T
    corrected = 100 * theta_T / (3 * T**2) - 20 * rate0 / T
    assert printed == pytest.approx(0.56) and corrected == pytest.approx(PAPER.accel / DEG)
    printed_rate = -10 * theta_T / (3 * T) - 2 * rate0
    assert printed_rate == pytest.approx(5.6)
    assert 10 * theta_T / (3 * T) - 2 * rate0 == pytest.approx(PAPER.rate_max / DEG)


def test_reference_trajectory_reaches_each_waypoint():
    t1, t2, t3, t4, t5 = PAPER.times
    theta = lambda t: PAPER.reference(t)[0] / DEG
    assert theta(0) == pytest.approx(120) and theta(t1) == pytest.approx(108)
    assert theta(t2) == pytest.approx(60) and theta(t3) == pytest.approx(49.3333, abs=1e-4)
    assert theta(t4) == pytest.approx(1.3333, abs=1e-4) and theta(t5) == pytest.approx(0, abs=1e-9)
    assert PAPER.reference(50.0)[1] / DEG == pytest.approx(-0.8)


def test_reference_rate_is_the_derivative_of_the_reference_angle():
    t = np.linspace(0.01, 110, 4000)
    h = 1e-5
    numeric = [(PAPER.reference(x + h)[0] - PAPER.reference(x - h)[0]) / (2 * h) for x in t]
    assert np.allclose(numeric, [PAPER.reference(x)[1] for x in t], atol=1e-7)


def test_references_on_arrays_are_the_reference_at_each_time():
    """At every time, the phase times themselves, just past them, before the start and
    after the end: the same (θ, θ̇) as the scalar reference, bit for bit."""
    t = np.concatenate([np.arange(-1.0, 120.0, 0.05), PAPER.times, np.nextafter(PAPER.times, 1e9)])
    pitch, rate = PAPER.references(t)
    assert np.array_equal(np.column_stack((pitch, rate)), [PAPER.reference(x) for x in t])


def controller_at(t, q_BO, w_BO_B=(0.0, 0.0, 0.0)):
    c = PitchManeuverController()
    c.set("q_BO", q_BO)
    c.set("w_BO_B", w_BO_B)
    c.initialize(0.0)
    c.t = t
    c.output()
    return c


@pytest.mark.parametrize(
    "t, phase, torque",
    [(0.0, 1, -4.0045), (9.99, 1, -4.0045), (10.0, 2, 0.0), (35.0, 3, 4.0045), (50.0, 4, 0.0)],
)
def test_feedforward_torque_by_phase(t, phase, torque):
    c = controller_at(t, quat_from_axis_angle([0, 1, 0], PAPER.reference(t)[0]))
    assert c.get("phase") == phase
    assert c.get("tau_cmd") == pytest.approx([0.0, torque, 0.0], abs=1e-4)


def test_terminal_pd_acts_from_t4():
    pitch, rate = 1.0 * DEG, -0.5 * DEG
    c = controller_at(97.0, quat_from_axis_angle([0, 1, 0], pitch), (0.0, rate, 0.0))
    assert c.get("phase") == 5
    assert c.get("tau_cmd")[1] == pytest.approx(0.9 * (0 - pitch) + 578 * (0 - rate))


def test_roll_and_yaw_are_held_with_the_right_sign():
    """Small roll +ε about x → negative x torque (and likewise yaw), at any pitch."""
    for pitch in (120 * DEG, 90 * DEG, 30 * DEG):
        c = controller_at(50.0, quat_from_euler123((1e-3, pitch, 2e-3)), (1e-4, 0.0, -1e-4))
        tau = c.get("tau_cmd")
        assert tau[0] < 0 and tau[2] < 0


def test_pitch_measurement_is_singularity_free_at_90_degrees():
    c = controller_at(97.0, quat_from_axis_angle([0, 1, 0], 90 * DEG))
    assert c.get("tau_cmd")[1] == pytest.approx(0.9 * -90 * DEG)


def test_unreachable_profile_is_rejected():
    with pytest.raises(ModelError, match="fractions"):
        PitchProfile(0.0, 1.0, 10.0, 0.1, cruise_fraction=0.5, imaging_fraction=0.6)
