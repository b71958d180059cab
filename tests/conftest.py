"""Shared fixtures: FMUs built as users get them, and clean processes to run them in.

Built FMUs are only ever *run* in a separate, fresh interpreter (``run_python`` and
``agilesat``): pythonfmu executes FMU code inside the host's interpreter, where modules
this pytest process imported could mask a file missing from an FMU.
"""
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def fmus() -> dict:
    """Every FMU, built (if stale) into fmus/build: {name: path}."""
    from agilesat.fmus.build import build_all
    return {path.stem: path for path in build_all()}


def run_python(code: str, *args, timeout: float = 600, cwd=None) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter of this environment (nothing pre-imported)."""
    return subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, cwd=cwd or ROOT)


def agilesat(*args, timeout: float = 900, cwd=None) -> subprocess.CompletedProcess:
    """The ``agilesat`` command line, in a fresh interpreter."""
    return subprocess.run([sys.executable, "-m", "agilesat.orchestration", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, cwd=cwd or ROOT)
