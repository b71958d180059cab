"""Fault injection on our FMU binary, each case in its own process (tests/tools/fault_cases_fmu.py),
and the resource figures with a small N (the full N: tests/tools/fault_matrix.py)."""

import pytest
from fault_cases_fmu import CASES, resource_figures

pytestmark = [pytest.mark.slow, pytest.mark.integration]


@pytest.mark.parametrize("case", CASES, ids=[case.__name__ for case in CASES])
def test_the_fmu_survives_and_answers(fmus, case):
    result = case()
    assert result["ok"], result


def test_repeated_runs_and_instances_do_not_grow_mappings(fmus):
    """N = 150: the simulate() loop without load caching grew ~30 mappings per call (each
    run mapped the FMU's binary anew).  A count, not a resident-memory figure: those are
    printed by tests/tools/benchmark_resources.py (a memory bound is no test on a busy
    machine)."""
    figures = dict(resource_figures(150))
    mappings = {label: value for label, value in figures.items() if "mappings" in label}
    assert len(mappings) == 3 and all(int(v) <= 3 for v in mappings.values()), mappings


def test_runs_on_reused_fmus_are_bit_identical_to_a_fresh_process(fmus, tmp_path):
    """Three runs in one process (the second with another inertia, so a reused component
    that kept anything from its last run would show) against one run per fresh process."""
    code = (
        "import sys\n"
        "from agilesat.orchestration.cosim.master import simulate\n"
        "from agilesat.orchestration.scenarios import get\n"
        "ssd, out = get('scan_pitch').ssd, sys.argv[1]\n"
        "for k, changed in enumerate(sys.argv[2:]):\n"
        "    parameters = {'SatelliteDynamics.inertia[1,1]': 900.0} if changed == '1' else {}\n"
        "    simulate(ssd, stop=2.0, parameters=parameters).to_npz(f'{out}{k}.npz')\n"
        "from agilesat.orchestration.cosim import fmu\n"
        "assert sum(map(len, fmu._idle.values())) == 5  # the components were reused\n"
    )
    from agilesat.orchestration.output.results import Results
    from helpers import run_python

    assert run_python(code, tmp_path / "same", 0, 1, 0).returncode == 0
    assert run_python(code, tmp_path / "fresh", 0).returncode == 0
    assert run_python(code, tmp_path / "fresh_changed", 1).returncode == 0
    same = [Results.from_npz(tmp_path / f"same{k}.npz").data for k in range(3)]
    fresh = Results.from_npz(tmp_path / "fresh0.npz").data
    changed = Results.from_npz(tmp_path / "fresh_changed0.npz").data
    assert same[0].tobytes() == fresh.tobytes() and same[2].tobytes() == fresh.tobytes()
    assert same[1].tobytes() == changed.tobytes() and not (changed == fresh).all()
