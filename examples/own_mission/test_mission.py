"""The mission's promises, checked from pytest with agilesat's plugin (active when pytest
is installed beside agilesat): ``python -m pytest test_mission.py`` in this directory."""

import math
from pathlib import Path

import numpy as np
import pytest

from agilesat.orchestration import assert_requirements_met, assert_settles, assert_within

MISSION = Path(__file__).with_name("mission.py")
J_MIN, J_MAX, GAIN = 10.0, 14.0, 1.0  # kg·m², N·m·s/rad: as mission.py sets them
WINDOW = 200.0  # s: the start of mission.py's observation window


@pytest.fixture(scope="session")
def nominal(agilesat_run):
    return agilesat_run(MISSION)


def test_every_requirement_is_met(nominal):
    _, summary = nominal
    assert_requirements_met(summary)


def test_the_wheels_stay_within_their_torque_and_the_pointing_holds(nominal):
    results, _ = nominal
    assert_within(results, "Flywheel.motor_torque", -0.2, 0.2)
    assert_settles(results, "SatelliteDynamics.w_BI_B", bound=0.002, after=WINDOW, deg=True)


def test_the_detumble_dissipates_energy_as_rate_damping_must(nominal):
    """Rate damping τ = −k ω takes kinetic energy T = ½ ωᵀJω out at dT/dt = −k |ω|²
    (the gyroscopic torque does no work), and 2T/J_max ≤ |ω|² ≤ 2T/J_min, so
    T0 e^(−2k t/J_min) ≤ T(t) ≤ T0 e^(−2k t/J_max) while the controller detumbles."""
    results, summary = nominal
    t = results.time
    detumbling = t < summary["metrics"]["detumbled_at"]["value"]
    w = results.vector("SatelliteDynamics.w_BI_B")[detumbling]
    J = np.diag([12.0, 14.0, 10.0])
    energy = 0.5 * np.einsum("ij,jk,ik->i", w, J, w)
    ratio = energy / energy[0]
    elapsed = t[detumbling]
    assert np.all(ratio >= 0.99 * np.exp(-2 * GAIN * elapsed / J_MIN))
    assert np.all(ratio <= 1.01 * np.exp(-2 * GAIN * elapsed / J_MAX))
    assert ratio[-1] < math.exp(-2 * GAIN * 30.0 / J_MAX)  # it did detumble
