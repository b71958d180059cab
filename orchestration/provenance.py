"""What made a result, and when: the tool's version with those of the packages a result
depends on, the command line and the date (``agilesat --version``; summary.json and
log.txt of a run)."""

from __future__ import annotations

import datetime
import functools
import shlex
import sys
from importlib import metadata


@functools.cache  # read once a process: a package's metadata costs ~5 ms a look-up
def version() -> str:
    """'agilesat X (fmpy A, pythonfmu B, numpy C; FMI 2.0 co-simulation)'."""
    used = ", ".join(f"{name} {metadata.version(name)}" for name in ("fmpy", "pythonfmu", "numpy"))
    return f"agilesat {metadata.version('agilesat')} ({used}; FMI 2.0 co-simulation)"


def provenance() -> dict:
    """{"version": :func:`version`, "command": this process's command line, "date": now,
    ISO 8601 UTC}."""
    return {
        "version": version(),
        "command": shlex.join(sys.argv),
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
    }


def header(made: dict) -> str:
    """log.txt's first lines, from a :func:`provenance`."""
    return "".join(f"# {key}: {value}\n" for key, value in made.items())
