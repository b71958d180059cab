"""The same FMU files give bit-identical results: twice in one process (the FMUs loaded,
freed and loaded again by the same interpreter) and in two separate processes."""

import numpy as np
import pytest

from agilesat.orchestration.scenarios import NAMES, get
from helpers import run_python

pytestmark = [pytest.mark.slow, pytest.mark.integration]

TWICE = """
import sys
import numpy as np
from agilesat.orchestration.cosim.master import simulate
runs = [simulate(sys.argv[1], stop=float(sys.argv[2])).data for _ in range(2)]
np.save(sys.argv[3], np.stack(runs))
"""


@pytest.mark.parametrize("scenario", NAMES)
def test_runs_are_bit_identical_in_one_process_and_across_processes(scenario, fmus, tmp_path):
    outputs = []
    for process in (1, 2):
        out = tmp_path / f"process{process}.npy"
        result = run_python(TWICE, get(scenario).ssd, 30.0, out)
        assert result.returncode == 0, result.stderr
        outputs.append(np.load(out))
    runs = np.concatenate(outputs)
    assert runs.shape[0] == 4 and runs.shape[1] == 601
    assert not np.isnan(runs).any()
    for other in runs[1:]:
        assert np.array_equal(runs[0], other)
