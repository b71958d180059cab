"""The compiled monolithic kernel of scan_pitch (tests/tools/reference/scan_pitch_compiled.py,
the benchmark's physical limit) against the co-simulation's results.

The kernel computes the same equations with the co-simulation's own scheme (Jacobi at the
macro step: the hub's RK4 extrapolates the cluster's h with its ḣ of t_n, the gimbals
follow the exact servo under the held command), written independently of components/, so
the two runs are one discrete system: only the order of floating-point operations differs,
and a stable closed loop keeps that at rounding level over the 3,000 steps (1e-10 rad
leaves four orders of magnitude for it; a wrong term, a step's lag or a sign is at least
1e-6).  Compared as tests/papers/test_reference_agreement.py compares the NumPy reference:
the pitch (twist of q_BO about y) and w_BO_B, plus the gimbal angles and the torque command.
"""

import numpy as np
import pytest

from agilesat.orchestration.output.results import Results
from helpers import agilesat
from reference import scan_pitch_compiled as monolith

pytestmark = [pytest.mark.slow, pytest.mark.integration]

ANGLE, RATE, TORQUE = 1e-10, 1e-12, 1e-9  # rad, rad/s, N·m


def twist(q):
    """Pitch as the twist of q_BO about y (well defined through 90°)."""
    q = np.where(q[:, :1] < 0, -q, q)
    return 2 * np.arctan2(q[:, 2], q[:, 0])


def differences(cosim: Results, step: float, null_gain: float = 0.0) -> dict:
    kernel = monolith.simulate(step, float(cosim.time[-1]), null_gain=null_gain)
    assert np.allclose(kernel["time"], cosim.time)
    return {
        "pitch": np.abs(twist(cosim.vector("SatelliteDynamics.q_BO")) - twist(kernel["q_BO"])),
        "w_BO_B": np.abs(cosim.vector("SatelliteDynamics.w_BO_B") - kernel["w_BO_B"]),
        "delta": np.abs(cosim.vector("CmgCluster.delta") - kernel["delta"]),
        "tau_cmd": np.abs(cosim.vector("PitchManeuverController.tau_cmd") - kernel["tau_cmd"]),
    }


def check(found: dict) -> None:
    assert found["pitch"].max() <= ANGLE
    assert found["delta"].max() <= ANGLE
    assert found["w_BO_B"].max() <= RATE
    assert found["tau_cmd"].max() <= TORQUE


def test_the_kernel_is_the_scenario_as_shipped(scan_pitch_run):
    """The session's nominal run (0.05 s, null-motion gain 0 as the scenario sets it)."""
    check(differences(scan_pitch_run[3], 0.05))


def test_the_kernel_null_motion_is_the_steering_law(fmus, tmp_path):
    """With a null-motion gain ε the gimbals take another path (radians away from the
    nominal one): the kernel's ε (1 − Aᵀ M⁻¹ A) ∂Q/∂δ against the FMU's, at 0.1 s."""
    run = agilesat(
        "run", "scan_pitch", "--step", 0.1, "--set", "CmgSteering.null_gain=0.1",
        "--out", tmp_path, "--no-figures", "--no-report", "-q",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    results = Results.from_csv(tmp_path / "results.csv")
    found = differences(results, 0.1, null_gain=0.1)
    check(found)
    without = monolith.simulate(0.1, 150.0)
    assert np.abs(without["delta"] - results.vector("CmgCluster.delta")).max() > 0.1
