"""The pieces of a run's interruptions and of its hold on its output directory, in this
process with real signals (the whole runs, in fresh processes:
``tests/tools/fault_cases_runs.py``)."""

import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from agilesat.orchestration.cosim.signals import Interruption, interruptible, stop_on_signals
from agilesat.orchestration.output import plots
from agilesat.orchestration.output.lock import OutputInUse, holding

HOLD = (
    "import sys, time\n"
    "from agilesat.orchestration.output.lock import holding\n"
    "with holding(sys.argv[1]):\n"
    "    print('held', flush=True)\n"
    "    sys.stdin.readline()\n"
)


def test_a_held_output_directory_is_refused_to_another_process_naming_the_holder(tmp_path):
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(tmp_path / "out")],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline() == "held\n"
        with pytest.raises(
            OutputInUse, match=rf"process {holder.pid}: .*python.*\): wait for it to end"
        ):
            with holding(tmp_path / "out"):
                pass
    finally:
        holder.communicate("\n", timeout=60)
    with holding(tmp_path / "out"), holding(tmp_path / "out"):  # free again; re-entrant
        assert not any((tmp_path / "out").iterdir())  # no lock file left there


def test_a_command_stops_at_once_until_a_run_writes_then_signals_are_flags():
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Interruption) as stopped:
        with interruptible():
            os.kill(os.getpid(), signal.SIGTERM)
    assert stopped.value.signal == signal.SIGTERM and signal.getsignal(signal.SIGTERM) is before
    with interruptible() as command:
        with stop_on_signals() as run:
            assert run is command
            os.kill(os.getpid(), signal.SIGINT)
        os.kill(os.getpid(), signal.SIGTERM)  # after the run: still a flag
        os.kill(os.getpid(), signal.SIGINT)
    assert command.signal == signal.SIGINT  # the first one
    assert signal.getsignal(signal.SIGTERM) is before


def test_figures_are_listed_as_written_and_a_check_before_each_can_stop_them(tmp_path):
    t = np.linspace(0.0, 1.0, 11)

    def before():
        if len(drawn) >= 1:
            raise KeyboardInterrupt

    with plots.written_as((".png",)), plots.drawing(before) as drawn:
        plots.lines(tmp_path / "a.png", "a", t, {"x": t}, "x")
        with pytest.raises(KeyboardInterrupt):
            plots.lines(tmp_path / "b.png", "b", t, {"x": t}, "x")
    assert drawn == [tmp_path / "a.png"] and sorted(tmp_path.iterdir()) == drawn
