"""The co-simulation against the independent monolithic reference (tests/tools/reference/).

The reference advances all states together with the exact gimbal motion inside each RK4
step and its controller sampled at 1 ms, so it stands for the continuous-time closed loop.
The co-simulation couples the FMUs at the macro step H: its controller and steering hold
their commands over H and phase switches fall on the H grid (the sample-period effect, a
design choice), and the hub sees the cluster's momentum at communication points (the
coupling error, test_coupling.py).  The first is first order in H.  Its dominant term: a
torque switch (I·θ̈m) misplaced by up to H/2 leaves a rate error up to θ̈m·H/2, which the
open-loop pitch channel integrates for up to T: |Δθ| ≤ θ̈m·H·T/2.  The largest
torque step is the terminal PD's start, c2·|θ̇0| (8.1 N·m); held up to a step early or late
it bounds the rate error by 2·c2·|θ̇0|·H / I.
"""

import math

import numpy as np
import pytest

from agilesat.orchestration.output.results import Results
from helpers import agilesat
from reference import scan_pitch as reference

pytestmark = [pytest.mark.slow, pytest.mark.integration]

DEG = math.pi / 180
STEPS = (0.1, 0.05, 0.025)
ACCEL, DURATION = 0.24 * DEG, 100.0  # θ̈m and T of the plan
PD_START = 578.0 * 0.8 * DEG / 956.0  # c2·|θ̇0| / I, rad/s²


def twist(q):
    """Pitch as the twist of q_BO about y (well defined through 90°)."""
    q = np.where(q[:, :1] < 0, -q, q)
    return 2 * np.arctan2(q[:, 2], q[:, 0])


@pytest.fixture(scope="module")
def truth():
    return reference.simulate(1e-3, 150.0)


@pytest.fixture(scope="module")
def errors(fmus, truth, scan_pitch_run, tmp_path_factory):
    """Max |pitch − reference| and max |w_BO_B − reference| for each macro step (the
    scenario's own 0.05 s is the session's shared run)."""
    result = {}
    for step in STEPS:
        if step == 0.05:
            cosim = scan_pitch_run[3]
        else:
            out = tmp_path_factory.mktemp(f"h{step}")
            run = agilesat(
                "run", "scan_pitch", "--step", step, "--out", out, "--no-figures", "--no-report"
            )
            assert run.returncode == 0, run.stderr
            cosim = Results.from_csv(out / "results.csv")
        every = round(step / 1e-3)
        pitch_ref, w_ref = twist(truth["q_BO"])[::every], truth["w_BO_B"][::every]
        assert np.allclose(truth["time"][::every], cosim.time)
        result[step] = (
            np.abs(twist(cosim.vector("SatelliteDynamics.q_BO")) - pitch_ref).max(),
            np.abs(cosim.vector("SatelliteDynamics.w_BO_B") - w_ref).max(),
        )
    return result


def test_the_reference_itself_has_converged(truth):
    finer = reference.simulate(5e-4, 150.0)
    assert np.abs(twist(finer["q_BO"])[::2] - twist(truth["q_BO"])).max() < 0.01 * DEG


@pytest.mark.parametrize("step", STEPS)
def test_cosimulation_agrees_within_the_expected_coupling_error(errors, step):
    pitch_error, rate_error = errors[step]
    assert pitch_error <= ACCEL * step * DURATION / 2
    assert rate_error <= 2 * PD_START * step


@pytest.mark.parametrize("step", STEPS)
def test_the_difference_is_the_sample_period_effect(errors, truth, step):
    """With Jacobi (the scenario's default) the coupling error is below 0.01° (see
    test_coupling.py): what separates the co-simulation from the continuous reference is
    its controller's sample period, the difference of the sampled-data reference
    (controller at H, zero-order hold) to the continuous one."""
    sampled = reference.simulate(1e-3, 150.0, control_period=step)
    effect = np.abs(twist(sampled["q_BO"]) - twist(truth["q_BO"])).max()
    assert abs(errors[step][0] - effect) <= 0.01 * DEG
