"""A run the campaign process makes itself (the nominal run the histograms mark), made in a
process of its own: an FMU that crashes (a segfault in a model's native code) kills that
process, not the campaign, which says so and keeps every run it made.

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
    """:func:`..runner.run` ``(target, options)`` in a fresh process: its summary;
    RunFailed when it failed or its process died (naming the signal that killed it),
    Interrupted when a signal stopped it."""
    child = subprocess.run(
        [sys.executable, "-c", CHILD],
        input=pickle.dumps((target, options)),
        capture_output=True,
    )
    lines = child.stdout.decode(errors="replace").splitlines()
    try:
        answer = json.loads(lines[-1])
    except (IndexError, ValueError):
        said = child.stderr.decode(errors="replace").strip().splitlines()
        if child.returncode < 0:
            why = f"its process was killed by {signal.Signals(-child.returncode).name}"
        else:
            why = f"its process ended with exit status {child.returncode}"
        raise RunFailed(why + (f" ({said[-1][:300]})" if said else "")) from None
    if "signal" in answer:
        raise Interrupted(answer["reason"], None, answer["signal"])
    if "reason" in answer:
        raise RunFailed(answer["reason"])
    return answer["summary"]
