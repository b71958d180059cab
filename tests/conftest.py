"""Shared fixtures (helpers that are not fixtures live in ``helpers.py``)."""
import pytest


@pytest.fixture(scope="session")
def fmus() -> dict:
    """Every FMU, built (if stale) into fmus/build: {name: path}."""
    from agilesat.fmus.build import build_all
    return {path.stem: path for path in build_all()}
