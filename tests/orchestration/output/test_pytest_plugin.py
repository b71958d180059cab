"""The shipped pytest plugin, as a user's test suite sees it (``pytester``, in a separate
process: the plugin comes from the installed entry point, the FMUs run there)."""

import pytest

pytest_plugins = ["pytester"]

USER_TESTS = """
import math
import pytest
from agilesat.orchestration import (
    assert_momentum_conserved, assert_pointing, assert_requirements_met, assert_settles,
    assert_within)

DEG = math.pi / 180


@pytest.fixture(scope="session")
def slew(agilesat_run):
    return agilesat_run("scan_pitch", stop=30.0)


def test_same_run_is_shared(agilesat_run, slew):
    assert agilesat_run("scan_pitch", stop=30.0) is slew


def test_gimbal_rates_within_limits(slew):
    results, _ = slew
    assert_within(results, "CmgCluster.delta_dot", -0.6, 0.6)


def test_pitch_rate_follows_the_planned_coast(slew):
    from agilesat.orchestration.scenarios.scan_pitch import PROFILE
    planned = PROFILE.reference(20.0)[1] / DEG      # phase 2 (10-30 s): a constant rate
    assert planned == pytest.approx(PROFILE.reference(12.0)[1] / DEG)
    assert_within(slew[0], "SatelliteDynamics.w_BO_B[2]", planned - 0.05, planned + 0.05,
                  start=12, stop=28, deg=True)


def test_momentum_conserved(slew):
    assert_momentum_conserved(slew[0], rtol=1e-9)


def test_too_tight_a_bound_fails(slew):
    assert_settles(slew[0], "SatelliteDynamics.w_BO_B[2]", bound=1.0, after=12, deg=True)


def test_requirement_not_reached_fails(slew):
    assert_requirements_met(slew[1], "imaging_pitch_rate_mean")


def test_pointing_index_of_the_slew_fails(slew):
    assert_pointing(slew[0], "APE", bound=0.01 * DEG, reference="OrbitEnvironment.q_OI")
"""


@pytest.mark.slow
@pytest.mark.integration
def test_plugin_fixtures_and_assertions_in_a_user_suite(pytester, fmus):
    pytester.makepyfile(test_user=USER_TESTS)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-q", timeout=600)
    result.assert_outcomes(passed=4, failed=3)
    result.stdout.fnmatch_lines(
        [
            "*SatelliteDynamics.w_BO_B[[]2[]] does not settle within ±1 °/s after t = 12 s*",
            "*requirement not evaluated: imaging_pitch_rate_mean in [[]-0.82, -0.78[]] °/s: "
            "not evaluated (imaging_pitch_rate_mean has no value: the run ends at 30 s*",
            "*AssertionError: not met: APE at 99.73 % (temporal): *° (requirement 0.01°): not met",
        ]
    )
