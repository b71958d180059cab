"""A run the campaign process makes itself (the nominal run the histograms mark), made in a
process of its own: an FMU that crashes (a segfault in a model's native code) kills that
process, not the campaign, which says so and keeps every run it made.  :func:`start` starts
it and returns at once (the campaign writes its summary meanwhile); :meth:`Started.result`
waits for its answer.

The child is ``python -c`` :data:`CHILD` given :func:`..runner.run`'s target and
:class:`..cosim.options.RunOptions` (pickled on its stdin, by this process) and answering
one JSON line: the run's summary, or why it has none.
"""

from __future__ import annotations

import json
import pickle
import signal
import subprocess
import sys
import threading

from ..cosim.master import Interrupted

CHILD = """
import json, pickle, sys
from agilesat.orchestration.cosim.master import Interrupted
from agilesat.orchestration.runner import run

target, options = pickle.load(sys.stdin.buffer)
try:
    answer = {"summary": run(target, options)[1]}
except Interrupted as exc:
    answer = {"signal": int(exc.signal), "reason": str(exc)}
except Exception as exc:
    answer = {"reason": f"{type(exc).__name__}: {exc}"}
print(json.dumps(answer, default=repr))
"""


class RunFailed(RuntimeError):
    """The run made no summary (the message says why)."""


def run(target: str, options) -> dict:
    """:func:`..runner.run` ``(target, options)`` in a fresh process: its summary (see
    :meth:`Started.result`)."""
    return start(target, options).result()


def start(target: str, options) -> Started:
    """:func:`..runner.run` ``(target, options)`` started in a fresh process."""
    return Started(target, options)


class Started:
    """A run going on in a process of its own; a thread hands it its target and options and
    collects what it says (no pipe fills while this process does other work)."""

    def __init__(self, target: str, options):
        self.child = subprocess.Popen(
            [sys.executable, "-c", CHILD],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        self.said: tuple = (b"", b"")
        payload = pickle.dumps((target, options))
        self.thread = threading.Thread(target=self._talk, args=(payload,), daemon=True)
        self.thread.start()

    def _talk(self, payload: bytes) -> None:
        self.said = self.child.communicate(payload)

    def result(self) -> dict:
        """Its summary, once it ends; RunFailed when it failed or its process died (naming
        the signal that killed it), Interrupted when a signal stopped it.  An exception
        while waiting (KeyboardInterrupt) kills the process."""
        try:
            self.thread.join()
        except BaseException:
            self.cancel()
            raise
        stdout, stderr = self.said
        lines = stdout.decode(errors="replace").splitlines()
        try:
            answer = json.loads(lines[-1])
        except (IndexError, ValueError):
            said = stderr.decode(errors="replace").strip().splitlines()
            code = self.child.returncode
            if code < 0:
                why = f"its process was killed by {signal.Signals(-code).name}"
            else:
                why = f"its process ended with exit status {code}"
            raise RunFailed(why + (f" ({said[-1][:300]})" if said else "")) from None
        if "signal" in answer:
            raise Interrupted(answer["reason"], None, answer["signal"])
        if "reason" in answer:
            raise RunFailed(answer["reason"])
        return answer["summary"]

    def cancel(self) -> None:
        """Kill the process if it still runs (its answer is no longer wanted)."""
        if self.child.poll() is None:
            self.child.kill()
