"""Coupling error of the co-simulation, measured against a monolithic run of the SAME
sampled-data system (tests/reference/scan_pitch.py with ``control_period``).

The sampled reference runs controller and steering at the co-simulation's control period
with zero-order hold and integrates hub and gimbals together (exact gimbal motion, RK4 at
1 ms), so co-simulation − sampled reference is the coupling error of the method alone;
sampled − continuous reference is the effect of the sample period, a design choice.

Jacobi: every FMU steps from t_n with the outputs of t_n; the hub extrapolates the
cluster momentum over the step with the cluster's own hdot(t_n) (a first-order Taylor
polynomial), so the momentum it sees is wrong by O(H²) within a step and the attitude by
O(H²) globally.  Gauss-Seidel in our order (cluster before hub) hands the hub h(t_{n+1})
as the value at t_n: the cluster torque arrives a step early, a first-order error.
"""

import dataclasses
import math

import numpy as np
import pytest

from agilesat.orchestration.results import Results
from agilesat.orchestration.scenarios import get
from helpers import agilesat
from reference import scan_pitch as reference

pytestmark = [pytest.mark.slow, pytest.mark.integration]

DEG = math.pi / 180
FINE = 1e-3


def twist(q):
    """Pitch as the twist of q_BO about y (well defined through 90°)."""
    q = np.where(q[:, :1] < 0, -q, q)
    return 2 * np.arctan2(q[:, 2], q[:, 0])


@pytest.fixture(scope="module")
def sampled():
    """The sampled-data reference for each control period used below."""
    return {H: reference.simulate(FINE, 150.0, control_period=H) for H in (0.05, 0.025)}


def cosim(tmp_path_factory, *args):
    out = tmp_path_factory.mktemp("run")
    args = args if str(args[0]).endswith(".ssd") else ("scan_pitch", *args)
    run = agilesat("run", *args, "--out", out, "--no-figures", "-q")
    assert run.returncode == 0, run.stderr
    return Results.from_csv(out / "results.csv")


def pitch_error(results, truth, step):
    every = round(step / FINE)
    assert np.allclose(truth["time"][::every], results.time)
    return np.abs(twist(results.vector("SatelliteDynamics.q_BO")) - twist(truth["q_BO"])[::every])


def test_sampled_reference_has_converged_and_is_not_the_continuous_one():
    a = reference.simulate(FINE, 150.0, control_period=0.05)
    b = reference.simulate(FINE / 2, 150.0, control_period=0.05)
    assert np.abs(twist(a["q_BO"]) - twist(b["q_BO"])[::2]).max() < 1e-6 * DEG
    continuous = reference.simulate(FINE, 150.0)
    # the 0.05 s sample period alone moves the pitch by tenths of a degree (t3 off the grid)
    assert np.abs(twist(a["q_BO"]) - twist(continuous["q_BO"])).max() > 0.1 * DEG


@pytest.fixture(scope="module")
def default_error(sampled, scan_pitch_run):
    """The coupling error of the scenario as shipped (Jacobi, 0.05 s), the session's run."""
    assert scan_pitch_run[2]["settings"]["algorithm"] == "jacobi"
    return pitch_error(scan_pitch_run[3], sampled[0.05], 0.05).max()


def test_the_scenario_as_shipped_has_a_coupling_error_below_a_hundredth_of_a_degree(
    default_error,
):
    assert default_error <= 0.01 * DEG


def test_jacobi_coupling_error_is_second_order(fmus, sampled, default_error, tmp_path_factory):
    results = cosim(tmp_path_factory, "--step", 0.025, "--algorithm", "jacobi")
    assert math.log2(default_error / pitch_error(results, sampled[0.025], 0.025).max()) >= 1.9


def test_multirate_plant_steps_shrink_the_coupling_error_at_second_order(
    fmus, sampled, default_error, tmp_path_factory
):
    """Controller and steering at 0.05 s (the sampled reference's period) and the plant at
    0.025 s: the same sampled-data system as the scenario's, coupled more finely."""
    scenario = dataclasses.replace(
        get("scan_pitch"), steps=dict.fromkeys(("PitchManeuverController", "CmgSteering"), 0.05)
    )
    path = tmp_path_factory.mktemp("system") / "multirate.ssd"
    path.write_bytes(scenario.render_ssd({n: str(fmus[n]) for n in scenario.components}))
    results = cosim(tmp_path_factory, path, "--step", 0.025, "--algorithm", "jacobi")
    assert math.log2(default_error / pitch_error(results, sampled[0.05], 0.025).max()) >= 1.9


def test_gauss_seidel_hands_the_hub_the_torque_a_step_early(fmus, sampled, tmp_path_factory):
    """The plain first-order scheme, still available: its coupling error is large."""
    results = cosim(tmp_path_factory, "--algorithm", "gauss-seidel")
    assert pitch_error(results, sampled[0.05], 0.05).max() > 0.1 * DEG
