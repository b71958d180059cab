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

    def before(paths):
        if len(drawn) >= 1:
            raise KeyboardInterrupt

    with plots.written_as((".png",)), plots.drawing(before) as drawn:
        plots.lines(tmp_path / "a.png", "a", t, {"x": t}, "x")
        with pytest.raises(KeyboardInterrupt):
            plots.lines(tmp_path / "b.png", "b", t, {"x": t}, "x")
    assert drawn == [tmp_path / "a.png"] and sorted(tmp_path.iterdir()) == drawn


def _stuck(stop):
    """A model's step that does not return by itself (this test module is no code of the
    master's: the watchdog may stop it here)."""
    while stop.watched:
        pass


def test_the_watchdog_stops_a_call_that_does_not_return_after_its_grace(monkeypatch):
    """After a signal, a run inside an FMU's code for longer than AGILESAT_STEP_GRACE is
    stopped there (StepOverdue, a KeyboardInterrupt pythonfmu answers fmi2Fatal); the
    first signal stays what stopped the run."""
    from agilesat.orchestration.cosim.signals import StepOverdue

    monkeypatch.setenv("AGILESAT_STEP_GRACE", "0.2")
    with stop_on_signals() as stop:
        with pytest.raises(StepOverdue, match="no return within 0.2 s of the signal"):
            with stop.watching():
                os.kill(os.getpid(), signal.SIGTERM)
                _stuck(stop)
        assert (stop.signal, stop.overdue, stop.watched) == (signal.SIGTERM, 0.2, False)
        with stop.watching():  # a later signal is a flag again: nothing raised
            os.kill(os.getpid(), signal.SIGINT)
        assert stop.signal == signal.SIGTERM
    with stop_on_signals() as stop, stop.watching():  # reached the flag in time: nothing
        os.kill(os.getpid(), signal.SIGINT)
    assert stop.overdue is None


def test_a_process_ignores_signals_once_its_exit_status_is_decided(monkeypatch, capsys):
    """`agilesat` as a program: its handlers stay SIG_IGN when main() returns (Python's
    finalisation restores the default ones, and a Ctrl-C then killed the process); a
    KeyboardInterrupt before a command took the signals is exit 130, said in a line."""
    from agilesat.orchestration import cli

    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        monkeypatch.setattr(sys, "argv", ["agilesat", "list"])
        assert cli.main() == 0
        assert all(signal.getsignal(s) is signal.SIG_IGN for s in before)
        for s, handler in before.items():
            signal.signal(s, handler)

        def interrupted(argv, program):
            raise KeyboardInterrupt

        monkeypatch.setattr(cli, "_main", interrupted)
        assert cli.main(["list"]) == 130  # not the program: the handlers are left alone
        assert signal.getsignal(signal.SIGINT) is before[signal.SIGINT]
        assert capsys.readouterr().err == "agilesat: interrupted by SIGINT\n"
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)


def test_the_next_holder_removes_what_a_killed_process_left(tmp_path, capsys):
    """The raw rows' scratch file and the temporary files writes are renamed from: nobody
    else writes there while the directory is held; anything else stays."""
    out = tmp_path / "out"
    out.mkdir()
    left = [".results.f64", ".summary.json.4242.partial", ".runs.csv.17.partial"]
    for name in [*left, "results.csv", ".notes.partial", "mine.partial"]:
        (out / name).write_text("x")
    with holding(out):
        pass
    assert sorted(p.name for p in out.iterdir()) == [
        ".notes.partial",
        "mine.partial",
        "results.csv",
    ]
    assert f"removed what a killed run or campaign left in {out}: {', '.join(sorted(left))}" in (
        capsys.readouterr().err
    )
