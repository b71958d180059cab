"""Five orbits of a nadir-pointing satellite whose gravity-gradient torque loads its wheels,
unloaded by MomentumManager and Magnetorquer in DisturbanceTorques' field: the wheels'
momentum settles where the law's orbit-averaged closed form puts it and stays far inside
the envelope it would leave after three orbits without management (CAPACITY / loading:
3.1 orbits).

Closed forms.  Nadir pointing (B = O) with a product of inertia J_xz, the gravity-gradient
torque 3 n² ẑ × J ẑ = (0, 3 n² J_xz, 0) in B is constant: unmanaged, h_y grows at that
rate.  Along y_B = −ĥ (the orbit normal) the cross-product law unloads at k (1 − ⟨b̂_n²⟩),
b̂_n the field's orbit-normal component: for a dipole on the Earth's axis
b ∝ 3 (ẑ·r̂) r̂ − ẑ, b·ĥ ∝ −cos i, |b|² ∝ 1 + 3 sin² i sin² u, so
⟨b̂_n²⟩ = cos² i / √(1 + 3 sin² i) (⟨1/(a + b sin² u)⟩ = 1/√(a (a + b))), and the
momentum settles at h_y = 3 n² J_xz / (k (1 − ⟨b̂_n²⟩)) (the in-plane axes decouple from
it in the average: ⟨b̂_n b̂_in-plane⟩ = 0)."""

import math

import numpy as np
import pytest

from agilesat.components.orbit_environment import (
    DEFAULT_SEMI_MAJOR_AXIS,
    MU_EARTH,
    OrbitEnvironment,
)
from agilesat.orchestration import run
from agilesat.orchestration.mission import System, nadir, timeline

PERIOD = 2 * math.pi * math.sqrt(DEFAULT_SEMI_MAJOR_AXIS**3 / MU_EARTH)
J = [[60.0, 0.0, 8.0], [0.0, 80.0, 0.0], [8.0, 0.0, 50.0]]  # kg·m²
GAIN, CAPACITY, BANDWIDTH = 1e-3, 0.5, 0.1  # 1/s, N·m·s, rad/s


def managed_nadir(orbits: int) -> System:
    system = System("momentum", step=2.0, stop=2.0 * math.ceil(orbits * PERIOD / 2.0))
    system.add("OrbitEnvironment")
    system.add("SatelliteDynamics", inertia=J, gravity_gradient=True)
    system.add("SlewGuidance", **timeline(nadir(0.0)))
    system.add(
        "AttitudeController",
        kp=[J[i][i] * BANDWIDTH**2 for i in range(3)],
        kd=[2 * 0.7 * BANDWIDTH * J[i][i] for i in range(3)],
        inertia=J,
        acceleration_feedforward=True,
    )
    system.add("Flywheel", momentum_limit=CAPACITY, torque_limit=0.05)
    # the field alone (its torques off), a dipole on the Earth's axis for the closed form
    system.add(
        "DisturbanceTorques", aero=False, srp=False, magnetic=False, igrf_g11=0.0, igrf_h11=0.0
    )
    system.add("MomentumManager", gain=GAIN)
    system.add("Magnetorquer", max_dipole=[5.0, 5.0, 5.0])
    for name in ("r_I", "q_OI", "w_OI_O"):
        system.connect(f"OrbitEnvironment.{name}", f"SatelliteDynamics.{name}")
    for name in ("r_I", "v_I", "q_OI", "w_OI_O", "earth_angle"):
        system.connect(f"OrbitEnvironment.{name}", f"SlewGuidance.{name}")
    for name in ("r_I", "v_I", "sun_I", "earth_angle"):
        system.connect(f"OrbitEnvironment.{name}", f"DisturbanceTorques.{name}")
    for name in ("q_ref", "w_ref", "dw_ref"):
        system.connect(f"SlewGuidance.{name}", f"AttitudeController.{name}")
    for name in ("q_BI", "w_BI_B"):
        system.connect(f"SatelliteDynamics.{name}", f"AttitudeController.{name}")
        system.connect(f"SatelliteDynamics.{name}", f"DisturbanceTorques.{name}")
    system.connect("SatelliteDynamics.w_BI_B", "Flywheel.w_BI_B")
    system.connect("AttitudeController.tau_cmd", "Flywheel.tau_cmd")
    system.connect("Flywheel.h", "SatelliteDynamics.h_wheel")
    system.connect("Flywheel.hdot", "SatelliteDynamics.hdot_wheel")
    system.connect("Flywheel.h", "MomentumManager.h_B")
    system.connect("DisturbanceTorques.b_B", "MomentumManager.b_B")
    system.connect("DisturbanceTorques.b_B", "Magnetorquer.b_B")
    system.connect("MomentumManager.m_cmd_B", "Magnetorquer.m_cmd_B")
    system.connect("Magnetorquer.tau_B", "SatelliteDynamics.tau_ext")
    return system


@pytest.mark.slow
@pytest.mark.integration
def test_managed_wheel_momentum_settles_at_the_orbit_averaged_closed_form(tmp_path):
    results, _ = run(managed_nadir(orbits=5), out_dir=tmp_path, figures=False)
    t, h = results.time, results.vector("Flywheel.h")
    inclination = OrbitEnvironment().get("inclination")
    n2 = MU_EARTH / DEFAULT_SEMI_MAJOR_AXIS**3
    loading = 3 * n2 * J[0][2]  # N·m: the gravity-gradient torque about y_B
    along_normal = math.cos(inclination) ** 2 / math.sqrt(1 + 3 * math.sin(inclination) ** 2)
    settled = loading / (GAIN * (1 - along_normal))
    last = t >= t[-1] - PERIOD
    assert np.mean(h[last, 1]) == pytest.approx(settled, rel=0.01)  # measured: 0.3 %
    assert np.linalg.norm(h, axis=1).max() < 1.1 * settled < 0.1 * CAPACITY
    assert not results["Flywheel.saturated"].any() and not results["Magnetorquer.saturated"].any()
    # unmanaged, the wheels would leave their envelope in the fourth orbit
    assert 3 * PERIOD < CAPACITY / loading < 4 * PERIOD
