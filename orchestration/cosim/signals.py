"""SIGINT and SIGTERM while a run goes: a flag the master looks at between macro steps
(:func:`stop_on_signals`), never an exception inside an FMU.

``$AGILESAT_TEST_SIGNAL`` delivers a signal at a chosen point of a run or a campaign, for
tests of interruptions that must not race the run on a loaded machine
(:func:`signal_at`):

- ``SIGINT@step:K``: a run sends its own process SIGINT at its first progress report at or
  after macro step K (reports come every 1 % of the run: :func:`at_step`);
- ``SIGTERM@run:K``: a campaign sends its own process the signal once K runs of this
  invocation are in its journal (``campaign/engine.py``);
- ``SIGKILL@worker:K``: a campaign worker process sends itself the signal as it starts its
  K-th run (``campaign/worker.py``).
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading

from ...components.switches import SwitchError, value


class _Stop:
    signal: int | None = None

    def handler(self, signum, _frame):
        self.signal = signum


_active: _Stop | None = None


@contextlib.contextmanager
def stop_on_signals():
    """While inside: SIGINT and SIGTERM set ``.signal`` of the object yielded instead of
    raising or killing; the previous handlers come back on exit.  Only the main thread can
    install handlers; elsewhere (and nested) the active object, if any, is shared."""
    global _active
    if _active is not None or threading.current_thread() is not threading.main_thread():
        yield _active or _Stop()
        return
    stop = _active = _Stop()
    previous = {s: signal.signal(s, stop.handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        _active = None


def signal_at(point: str) -> tuple[int, int] | None:
    """(signal number, K) of ``$AGILESAT_TEST_SIGNAL`` if it names ``point`` ("step",
    "run" or "worker"), else None."""
    asked = value("AGILESAT_TEST_SIGNAL")
    if asked is None:
        return None
    name, kind, count = asked
    try:
        signum = signal.Signals[name].value
    except KeyError:
        raise SwitchError(f"AGILESAT_TEST_SIGNAL: {name} is not a signal of this system") from None
    return (signum, count) if kind == point else None


def at_step(progress):
    """``progress`` (a run's progress callback, or None), or, if ``$AGILESAT_TEST_SIGNAL``
    asks for a signal at a macro step, a callback that also sends it at the first report at
    or after that step."""
    asked = signal_at("step")
    if asked is None:
        return progress
    signum, step = asked
    sent = []

    def reported(done: int, total: int) -> None:
        if progress is not None:
            progress(done, total)
        if done >= step and not sent:
            sent.append(done)
            os.kill(os.getpid(), signum)

    return reported
