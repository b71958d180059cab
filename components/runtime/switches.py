"""Every ``AGILESAT_*`` environment variable, in one table (docs/fast_paths.md lists the
same; tests/fast_paths/test_switches.py keeps the repository to this table).

Python reads them through :func:`value`, which checks what a variable holds: a value it
cannot take is a :class:`SwitchError` naming the variable, what it holds and what it
accepts (``agilesat`` prints it as a one-line error).  The FMU's C shim reads four itself
(``fmus/shim``): AGILESAT_SHIM_FAST and AGILESAT_SHIM_STEP (off with ``0``; the slave checks
both at the shim's handshake and turns the fast paths off, with this message, on anything
but ``0`` or ``1``), AGILESAT_LIBPYTHON and AGILESAT_PYTHON (paths; the shim says when they
do not exist).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass


class SwitchError(ValueError):
    """An environment variable holds a value it cannot take."""


def _flag(text: str) -> bool:
    if text not in ("0", "1"):
        raise ValueError("0 (off) or 1 (on)")
    return text == "1"


def _count(text: str) -> int:
    if not (text.strip().isdigit()):
        raise ValueError("a whole number >= 0")
    return int(text)


def _loop(text: str) -> str:
    if text not in ("auto", "compiled", "python"):
        raise ValueError("auto, compiled or python")
    return text


def _path(text: str) -> str:
    return text


def _seconds(text: str) -> float:
    try:
        seconds = float(text)
    except ValueError:
        seconds = float("nan")
    if not 0.0 < seconds < float("inf"):
        raise ValueError("a positive, finite number of seconds")
    return seconds


def _test_signal(text: str) -> tuple[str, str, int]:
    """'SIGTERM@run:3' -> ('SIGTERM', 'run', 3)."""
    name, _, where = text.partition("@")
    point, _, count = where.partition(":")
    if not (
        name.startswith("SIG") and point in ("step", "run", "worker", "figure") and count.isdigit()
    ):
        raise ValueError(
            "SIGNAL@step:K, SIGNAL@run:K, SIGNAL@worker:K or SIGNAL@figure:K, SIGNAL as SIGTERM"
        )
    return name, point, int(count)


@dataclass(frozen=True)
class Switch:
    name: str
    default: object  # the value when the variable is unset or empty
    parse: Callable[[str], object]
    meaning: str
    read_by: str


SWITCHES = {
    s.name: s
    for s in (
        Switch(
            "AGILESAT_JIT",
            True,
            _flag,
            "1: the model kernels run compiled when a run pays for it (components/runtime/jit.py); "
            "0: their Python",
            "components/runtime/jit.py, at import",
        ),
        Switch(
            "AGILESAT_JIT_AFTER",
            50_000,
            _count,
            "the calls of a kernel before it runs compiled, fewer where a run's length says "
            "it pays; 0: from the first call",
            "components/runtime/jit.py, at import",
        ),
        Switch(
            "AGILESAT_JIT_RUNS",
            1,
            _count,
            "the runs a process expects to make of each model (a campaign worker's share): "
            "with a run's steps, it decides whether the kernels run compiled from the start",
            "components/runtime/jit.py, at import",
        ),
        Switch(
            "AGILESAT_NATIVE",
            True,
            _flag,
            "1: a model's C entries come from its FMU's ahead-of-time library from the first "
            "step (fmus/native.py); 0: compiled by numba in the process, as a run pays",
            "fmus/native.py, as an FMU's model is first stepped",
        ),
        Switch(
            "AGILESAT_CACHE_DIR",
            None,
            _path,
            "the compile cache: kernels, C entries, the master's loop, unpacked FMUs; "
            "default $XDG_CACHE_HOME/agilesat or ~/.cache/agilesat",
            "components/runtime/cache.py cache_root()",
        ),
        Switch(
            "AGILESAT_SHIM_FAST",
            True,
            _flag,
            "0: the shim serves no call itself, every get, set and doStep reaches the slave",
            "the shim (C) at fmi2Instantiate and fmi2Reset; checked by fmus/fast_paths.py",
        ),
        Switch(
            "AGILESAT_SHIM_STEP",
            True,
            _flag,
            "0: the shim's C step path is off, its fast get/set stay on",
            "the shim (C) and fmus/fast_paths.py, at the handshake",
        ),
        Switch(
            "AGILESAT_LIBPYTHON",
            None,
            _path,
            "the shared libpython an FMU loads in a host without Python; default: the "
            "building environment's",
            "the shim (C), at the first fmi2Instantiate",
        ),
        Switch(
            "AGILESAT_PYTHON",
            None,
            _path,
            "the python executable an FMU runs as in a host without Python; default: the "
            "building environment's",
            "the shim (C), at the first fmi2Instantiate",
        ),
        Switch(
            "AGILESAT_LOOP",
            None,
            _loop,
            "the master's loop; default auto",
            "orchestration/cosim/loop.py choose()",
        ),
        Switch(
            "AGILESAT_SSP_MAX_BYTES",
            None,
            _count,
            "the most bytes an SSP package may unpack to; default 256 MiB",
            "orchestration/system/ssp.py",
        ),
        Switch(
            "AGILESAT_FAULT_FMUS",
            None,
            _path,
            "the built FMUs the fault matrix runs, a test tool's",
            "tests/tools/fault_cases_fmu.py",
        ),
        Switch(
            "AGILESAT_OMSIMULATOR",
            None,
            _path,
            "the OMSimulator executable the OMSimulator tests run (not on the package registries)",
            "tests/interop/test_omsimulator.py",
        ),
        Switch(
            "AGILESAT_STEP_GRACE",
            5.0,
            _seconds,
            "seconds an FMU call may take to return after SIGINT/SIGTERM stopped a run before "
            "the watchdog stops it inside the call",
            "orchestration/cosim/signals.py",
        ),
        Switch(
            "AGILESAT_TEST_SIGNAL",
            None,
            _test_signal,
            "a test's hook: SIGNAL@step:K, SIGNAL@run:K, SIGNAL@worker:K or SIGNAL@figure:K "
            "sends the signal at macro step K of a run, once K runs of a campaign are "
            "journaled, as a campaign worker starts its K-th run, or as a run starts its "
            "K-th figure",
            "orchestration/cosim/signals.py signal_at()",
        ),
    )
}


def value(name: str, environ=None):
    """The value of switch ``name``: its default when unset or empty, else what it holds,
    checked (:class:`SwitchError` if it cannot take it)."""
    switch = SWITCHES[name]
    text = (os.environ if environ is None else environ).get(name, "")
    if not text:
        return switch.default
    try:
        return switch.parse(text)
    except ValueError as expected:
        raise SwitchError(
            f"{name}={text!r}: expected {expected} ({name}: {switch.meaning})"
        ) from None


def check_all(environ=None) -> None:
    """Every switch's value checked (:class:`SwitchError` on the first that cannot be
    taken): ``agilesat`` checks them before a command runs, so that a bad value is one
    line up front, not an FMU's failure inside a run."""
    for name in SWITCHES:
        value(name, environ)
