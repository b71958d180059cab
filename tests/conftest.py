"""Shared fixtures (helpers that are not fixtures live in ``helpers.py``)."""

import json
import sys

import pytest

from helpers import TOOLS

sys.path.insert(0, str(TOOLS))  # the tools: reference, coupling_cases, fault cases, hosts


@pytest.fixture(scope="session")
def fmus() -> dict:
    """Every FMU, built (if stale) into fmus/build: {name: path}."""
    from agilesat.fmus.build import build_all

    return {path.stem: path for path in build_all()}


@pytest.fixture(scope="session")
def scan_pitch_run(fmus, tmp_path_factory):
    """The nominal scan_pitch run (0.05 s, with figures), once per session through the CLI
    in a fresh process: (out_dir, completed process, summary.json, results.csv).  Tests
    that need this very run share it instead of repeating it."""
    from agilesat.orchestration.output.results import Results
    from helpers import agilesat

    out = tmp_path_factory.mktemp("scan_pitch")
    result = agilesat("run", "scan_pitch", "--out", out)
    assert result.returncode == 0, result.stderr
    return (
        out,
        result,
        json.loads((out / "summary.json").read_text()),
        Results.from_csv(out / "results.csv"),
    )


@pytest.fixture(scope="session")
def c_host(tmp_path_factory):
    """The plain C FMI 2.0 host (tests/tools/c_host/fmi2_host.c), compiled once."""
    from c_host.harness import compile_host

    return compile_host(tmp_path_factory.mktemp("c_host"))
