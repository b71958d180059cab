"""Assertions on the detumbling system (make_system.py), with agilesat's pytest plugin.

Run: python -m pytest examples/own_system/test_detumble.py  (after make_system.py; set
DETUMBLE_SSD to use a system written elsewhere).
"""

import math
import os
from pathlib import Path

import numpy as np
import pytest

from agilesat.orchestration import assert_momentum_conserved, assert_settles, assert_within

SYSTEM = Path(os.environ.get("DETUMBLE_SSD", "out/own_system/detumble.ssd"))
J, GAIN = 50.0, 5.0  # kg·m², N·m·s/rad: as make_system.py sets them


@pytest.fixture(scope="session")
def run(agilesat_run):
    return agilesat_run(SYSTEM)


def test_detumbled_within_a_minute(run):
    results, _ = run
    assert_settles(results, "SatelliteDynamics.w_BI_B", bound=0.01, after=60.0, deg=True)


def test_rate_decays_with_the_designed_time_constant(run):
    # J dw/dt = −gain w for the hub, as long as the wheels are far from their limits
    results, _ = run
    w = np.linalg.norm(results["SatelliteDynamics.w_BI_B"], axis=1)
    tau = J / GAIN
    k = np.searchsorted(results.time, tau)
    assert w[k] / w[0] == pytest.approx(math.exp(-1), rel=0.02)


def test_wheels_take_up_the_momentum_within_their_torque_limit(run):
    results, summary = run
    assert_within(results, "Flywheel.motor_torque", -0.2, 0.2)
    assert_momentum_conserved(results, rtol=1e-9)
    assert summary["status"] == "ok"
