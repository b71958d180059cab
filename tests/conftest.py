"""Shared fixtures (helpers that are not fixtures live in ``helpers.py``)."""

import json

import pytest


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
    from agilesat.orchestration.results import Results
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
