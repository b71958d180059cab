"""The shipped scenarios, one module each, written on the public API
(:mod:`agilesat.orchestration.mission`) exactly as a mission of your own is: a
:class:`~agilesat.orchestration.mission.System`, its metrics, requirements, variants and
figures, in ``SCENARIO``.  Copy ``scan_pitch.py`` as a template.

A module here that defines ``SCENARIO`` is a shipped scenario (found by reading the
sources, :func:`..mission.targets.shipped`); ``constants.py`` holds the papers' values the
studies share.  Their systems are also written as ``systems/<name>.ssd`` by ``agilesat
generate`` (committed, for other hosts and readers; a test keeps them in sync).
"""

from __future__ import annotations


def get(name: str):
    """The shipped (or registered) scenario ``name``
    (:func:`..mission.targets.scenario`)."""
    from ..mission.targets import scenario

    return scenario(name)


def __getattr__(name: str):
    """``NAMES``: the shipped scenarios' names, read from the sources."""
    if name == "NAMES":
        from ..mission.targets import shipped

        return tuple(shipped())
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
