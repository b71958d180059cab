"""Fault injection on our FMU binary, each case in its own process (tests/fault_cases_fmu.py),
and the resource figures with a small N (the full N: tests/fault_matrix.py)."""
import re

import pytest

from fault_cases_fmu import CASES, resource_figures

pytestmark = [pytest.mark.slow, pytest.mark.integration]


@pytest.mark.parametrize("case", CASES, ids=[case.__name__ for case in CASES])
def test_the_fmu_survives_and_answers(fmus, case):
    result = case()
    assert result["ok"], result


def test_repeated_runs_and_instances_do_not_grow_memory_or_mappings(fmus):
    """N = 300: the raw pythonfmu leak (~1 KB per instantiation) would show as ~0.3 MB per
    FMU; the simulate() loop without load caching grew ~30 mappings and 1.4 MB per call."""
    figures = dict(resource_figures(300))
    for label, value in figures.items():
        if "mappings" in label:
            assert int(value) <= 3, (label, value)
        elif "raw" not in label and "growth" in label:
            assert float(value.split()[0]) < 5.0, (label, value)
    per_instance = next(v for k, v in figures.items() if k.startswith("resident memory per"))
    assert int(re.match(r"(\d+) KB", per_instance).group(1)) < 2000
