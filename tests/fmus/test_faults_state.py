"""What an FMU loads and restores, injected in fresh processes
(``tests/tools/fault_cases_state.py``): tampered FMU states through a plain fmpy host with
Python and with compiled kernels, a modelDescription.xml whose GUID is not the binary's, a
damaged shim, each corruption of the compile cache."""

import pytest
from fault_cases_state import CASES

pytestmark = [pytest.mark.slow, pytest.mark.integration]


@pytest.mark.parametrize("case", CASES, ids=[case.__name__ for case in CASES])
def test_the_fault_is_refused_or_repaired_never_silent(fmus, case):
    result = case()
    assert result["ok"], result
