"""SIGINT and SIGTERM while a run goes: a flag the master looks at between macro steps
(:func:`stop_on_signals`), never an exception inside an FMU.

A command (``agilesat run``) is :func:`interruptible` as a whole: a signal that comes
before anything is written stops it at once (:class:`Interruption`, a KeyboardInterrupt);
from the moment a run writes its output directory (its ``stop_on_signals``) every signal,
the first and any later one, is a flag until the command ends, so that a second Ctrl-C
while the results, summary or figures are written changes nothing but the status said.
The command exits 128 + the first signal's number: 130 for SIGINT, 143 for SIGTERM.

A watchdog keeps a run interruptible when an FMU call does not return (a model stuck in
its step): once a signal has set the flag while a run's FMUs are being called
(:meth:`_Stop.watching`), a timer waits ``$AGILESAT_STEP_GRACE`` seconds (default 5) for
the master to reach the flag; if the run is still inside an FMU's code then, the signal is
delivered again and its handler raises :class:`StepOverdue` there.  pythonfmu answers that
call fmi2Fatal, the master calls nothing more on that FMU and stops with every row so far,
as for any interruption (:class:`.master.Interrupted`).  Code that never returns to the
interpreter (a compiled kernel in an endless loop that holds it) cannot be stopped from
inside: SIGKILL then, which leaves what a killed run leaves (docs/reliability.md).

``$AGILESAT_TEST_SIGNAL`` delivers a signal at a chosen point of a run or a campaign, for
tests of interruptions that must not race the run on a loaded machine
(:func:`signal_at`):

- ``SIGINT@step:K``: a run sends its own process SIGINT at its first progress report at or
  after macro step K (reports come every 1 % of the run: :func:`at_step`);
- ``SIGTERM@run:K``: a campaign sends its own process the signal once K runs of this
  invocation are in its journal (``campaign/engine.py``);
- ``SIGKILL@worker:K``: a campaign worker process sends itself the signal as it starts its
  K-th run, K = 0 its warm-up (``campaign/worker.py``);
- ``SIGTERM@figure:K``: a run sends itself the signal as it starts drawing its K-th
  figure (``runner.py``).
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading

from ...components.runtime.switches import SwitchError, value


class Interruption(KeyboardInterrupt):
    """A signal that stopped a command before it wrote anything (``signal`` says which)."""

    def __init__(self, signum: int):
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signal = signum


class StepOverdue(KeyboardInterrupt):
    """Raised by the watchdog inside an FMU call that did not return within the grace of
    the signal that stopped the run (module docstring)."""


class _Stop:
    signal: int | None = None  # the first signal
    deferring = True  # a signal is a flag (else: Interruption, the first time)
    watched = False  # a run's FMUs are being called (the watchdog may stop one)
    overdue: float | None = None  # the grace after which the watchdog stopped a call

    def handler(self, signum, frame):
        first = self.signal is None
        self.signal = self.signal or signum
        if first and not self.deferring:
            raise Interruption(signum)
        if first and self.watched:
            timer = threading.Timer(self.grace, self._overdue, (self.grace,))
            timer.daemon = True
            timer.start()
        elif self._kick and self.watched and _inside_an_fmu(frame):
            self._kick = self.watched = False  # once, for the watchdog's own signal
            raise StepOverdue(f"no return within {self.overdue:g} s of the signal")

    _kick = False  # the watchdog's signal is on its way

    def _overdue(self, grace: float) -> None:
        """The watchdog (a timer thread): the run has not reached the flag."""
        if self.watched and self.overdue is None:
            self.overdue, self._kick = grace, True
            main = threading.main_thread().ident
            assert main is not None  # the main thread has started
            signal.pthread_kill(main, self.signal or signal.SIGINT)

    grace = 5.0  # AGILESAT_STEP_GRACE's, read as the run starts watching

    @contextlib.contextmanager
    def watching(self):
        """While inside, the run calls its FMUs: the watchdog may stop a call that does
        not return after a signal (module docstring)."""
        self.grace = value("AGILESAT_STEP_GRACE")  # a bad value: said here, not in a handler
        self.watched = True
        try:
            yield self
        finally:
            self.watched = False


def _inside_an_fmu(frame) -> bool:
    """The main thread is running code that is not the master's (an FMU's model)."""
    return frame is not None and not str(frame.f_globals.get("__name__", "")).startswith(
        __package__.rpartition(".")[0]
    )


_active: _Stop | None = None


@contextlib.contextmanager
def stop_on_signals():
    """While inside: SIGINT and SIGTERM set ``.signal`` of the object yielded instead of
    raising or killing; the previous handlers come back on exit.  Only the main thread can
    install handlers; elsewhere (and nested) the active object, if any, is shared (inside
    :func:`interruptible`, signals stay flags from here to the end of the command)."""
    if _active is not None or threading.current_thread() is not threading.main_thread():
        stop = _active or _Stop()
        stop.deferring = True
        yield stop
        return
    with _installed(_Stop()) as stop:
        yield stop


@contextlib.contextmanager
def interruptible(restore: bool = True):
    """A whole command (module docstring): a signal raises :class:`Interruption` until a
    run starts writing, and is a flag after.  ``restore=False`` (a process that ends with
    the command): an interrupted command leaves the handlers in place, so that a signal
    while the process exits changes nothing either."""
    stop = _Stop()
    stop.deferring = False
    with _installed(stop, lambda: restore or stop.signal is None):
        yield stop


@contextlib.contextmanager
def _installed(stop: _Stop, restore=lambda: True):
    global _active
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return
    _active = stop
    previous = {s: signal.signal(s, stop.handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        _active = None
        if restore():
            for s, handler in previous.items():
                signal.signal(s, handler)


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
