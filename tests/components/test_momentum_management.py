"""Magnetorquer and MomentumManager: the rods' saturation and torque by hand, the
cross-product law's torque −k Δh_⊥, and the orbit-averaged unloading rate it gives over a
polar orbit in an axial dipole field (derived in components/momentum_manager.py: the
in-plane momentum decays as e^(−k t/2), the orbit-normal one as e^(−k t)), with the field
from DisturbanceTorques' field model and the orbit from OrbitEnvironment."""

import math

import numpy as np
import pytest

from agilesat.components.disturbance_torques import DisturbanceTorques
from agilesat.components.magnetorquer import Magnetorquer
from agilesat.components.model import ModelError
from agilesat.components.momentum_manager import MomentumManager
from agilesat.components.orbit_environment import MU_EARTH, WGS84_A, OrbitEnvironment

FIELD = np.array([1.2e-5, -2.0e-5, 3.1e-5])  # T


def torque(h, b, gain=1e-3, target=(0.0, 0.0, 0.0), max_dipole=(1e3, 1e3, 1e3)):
    """(m_B, tau_B, saturated) of the law feeding the rods."""
    manager = MomentumManager(gain=gain, h_target=target, h_B=h, b_B=b).start(0.0)
    rods = Magnetorquer(max_dipole=max_dipole, m_cmd_B=manager.get("m_cmd_B"), b_B=b).start(0.0)
    return rods.get("m_B"), rods.get("tau_B"), rods.get("saturated")


def test_the_rods_saturate_per_axis_and_give_m_cross_b():
    rods = Magnetorquer(max_dipole=[5.0, 10.0, 20.0], m_cmd_B=[8.0, -3.0, -25.0], b_B=FIELD)
    rods.start(0.0)
    assert rods.get("m_B").tolist() == [5.0, -3.0, -20.0]
    m = np.array([5.0, -3.0, -20.0])
    expected = [m[1] * FIELD[2] - m[2] * FIELD[1], m[2] * FIELD[0] - m[0] * FIELD[2],
                m[0] * FIELD[1] - m[1] * FIELD[0]]  # fmt: skip
    assert rods.get("tau_B") == pytest.approx(expected, rel=1e-15)
    assert rods.get("saturated")
    rods.set("m_cmd_B", [1.0, 1.0, 1.0])
    assert not rods.advance(0.0, 1.0).get("saturated")


def test_the_cross_product_law_takes_out_the_momentum_across_the_field():
    """τ = m × b = −k (Δh − (Δh·b̂) b̂): perpendicular to b, nothing along it."""
    h, target, k = np.array([3.0, -1.0, 2.0]), np.array([0.5, 0.5, 0.0]), 2e-3
    _, tau, saturated = torque(h, FIELD, k, target)
    b = FIELD / np.linalg.norm(FIELD)
    excess = h - target
    assert tau == pytest.approx(-k * (excess - (excess @ b) * b), rel=1e-12)
    assert tau @ b == pytest.approx(0.0, abs=1e-18) and not saturated


def test_no_field_no_dipole():
    assert torque([1.0, 2.0, 3.0], [0.0, 0.0, 0.0])[0].tolist() == [0.0, 0.0, 0.0]


@pytest.mark.parametrize(
    "model, parameters, match",
    [
        (Magnetorquer, {"max_dipole": [1.0, -1.0, 1.0]}, "max_dipole must be finite and >= 0"),
        (MomentumManager, {"gain": math.nan}, "gain must be finite and >= 0"),
    ],
)
def test_bad_parameters_are_named(model, parameters, match):
    with pytest.raises(ModelError, match=match):
        model(**parameters).start(0.0)


def test_the_unloading_rate_over_a_polar_orbit_is_the_orbit_averaged_closed_form():
    """Five orbits of ḣ = m × b (the body held inertial: b_B = b_I) from h = (1, 1, 1)
    N·m·s, k T_orbit = 0.11: after each orbit h_x, h_z (in the orbit plane) are
    e^(−k t/2) of their start to the 2e-3 the averaging neglects (measured: 1.4e-3 after
    five orbits), h_y (along the orbit normal, which b never has a component along)
    e^(−k t) exactly."""
    a, k = WGS84_A + 550e3, 2e-5
    period = 2 * math.pi * math.sqrt(a**3 / MU_EARTH)
    orbit = OrbitEnvironment(semi_major_axis=a, inclination=math.pi / 2, raan=0.0)
    orbit.start(0.0)
    field = DisturbanceTorques(igrf_g11=0.0, igrf_h11=0.0)  # the dipole on the Earth's axis
    steps, dt = 40, period / 40

    def b(t):
        orbit.advance(0.0, t)
        field.set("r_I", orbit.get("r_I"))
        field.set("v_I", orbit.get("v_I"))
        return field.start(t).get("b_B")

    def hdot(h, b_B):
        return torque(h, b_B, k)[1]

    h = np.ones(3)
    for n in range(5 * steps):  # RK4 on the sampled field
        t = n * dt
        b0, b1, b2 = b(t), b(t + dt / 2), b(t + dt)
        k1 = hdot(h, b0)
        k2 = hdot(h + dt / 2 * k1, b1)
        k3 = hdot(h + dt / 2 * k2, b1)
        h = h + dt / 6 * (k1 + 2 * k2 + 2 * k3 + hdot(h + dt * k3, b2))
        if (n + 1) % steps == 0:
            t = (n + 1) * dt
            assert orbit.get("r_I")[1] == pytest.approx(0.0, abs=1e-6 * a)  # plane x-z
            in_plane, normal = math.exp(-k * t / 2), math.exp(-k * t)
            assert h[[0, 2]] == pytest.approx([in_plane] * 2, rel=2e-3)
            assert h[1] == pytest.approx(normal, rel=1e-9)
