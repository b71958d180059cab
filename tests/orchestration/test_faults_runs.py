"""Faults of a run's output, its interruptions, what it is given, missions of a user's own,
what a run leaves and campaigns, each injected in fresh processes with real signals
(``tests/tools/fault_cases_runs.py``, ``fault_cases_inputs.py``, ``fault_cases_mission.py``,
``fault_cases_records.py``, ``fault_cases_campaign.py``)."""

import fault_cases_campaign
import fault_cases_inputs
import fault_cases_mission
import fault_cases_records
import fault_cases_runs
import pytest

CASES = (
    fault_cases_runs.CASES
    + fault_cases_inputs.CASES
    + fault_cases_mission.CASES
    + fault_cases_records.CASES
    + fault_cases_campaign.CASES
)


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("case", CASES, ids=lambda c: f"{c.__module__}.{c.__name__}")
def test_fault_case(fmus, case):
    result = case()
    if "skipped" in result:
        pytest.skip(result["skipped"])
    assert result["ok"], result
