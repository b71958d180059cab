"""A user's model that misbehaves on request, built once per process with ``agilesat build``
(:func:`built`): the fault cases of outputs out of their type's range, a step that does not
return, a crash in a native call.  Its parameters are its faults (all off by default)."""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

from helpers import ROOT

SOURCE = '''"""Outputs what its parameters say; sticks, sleeps or crashes in its step on request."""
import ctypes
import time

from agilesat.components.model import Model
from agilesat.components.variables import output, parameter


class Wild(Model):
    """A model of a user's that misbehaves on request."""

    VARIABLES = (
        parameter("count", 1.0, "1", "the value of the Integer output n"),
        parameter("flag", 1.0, "1", "the value of the Boolean output b"),
        parameter("stick_at", -1.0, "s", "an endless loop in the step at or after (< 0: never)"),
        parameter("sleep_at", -1.0, "s", "an endless sleep in the step at or after (< 0: never)"),
        parameter("crash_at", -1.0, "s", "a segfault in the step at or after (< 0: never)"),
        output("n", "1", "an Integer output", type="Integer"),
        output("b", "1", "a Boolean output", type="Boolean"),
        output("x", "1", "a Real output: the time"),
    )

    def initialize(self, t0):
        self.t = t0

    def step(self, t, dt):
        if 0 <= self.p.stick_at <= t:
            while True:
                pass
        if 0 <= self.p.sleep_at <= t:
            time.sleep(1e6)
        if 0 <= self.p.crash_at <= t:
            ctypes.string_at(0)  # reads address 0: SIGSEGV
        self.t = t + dt

    def output(self):
        self.y.n = self.p.count
        self.y.b = self.p.flag
        self.y.x = self.t
'''

_built: list = []  # (the temporary directory, kept until the process ends; the FMU)


def built() -> Path:
    """Wild.fmu (built into a temporary directory once per process)."""
    if not _built:
        kept = tempfile.TemporaryDirectory(prefix="agilesat-wild-")
        directory = Path(kept.name)
        (directory / "wild.py").write_text(SOURCE)
        subprocess.run(
            [sys.executable, "-m", "agilesat.orchestration", "build", str(directory / "wild.py")],
            cwd=ROOT,
            check=True,
            capture_output=True,
            timeout=600,
        )
        _built[:] = [kept, directory / "build" / "Wild.fmu"]
    return _built[1]
