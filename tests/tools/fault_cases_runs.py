"""Fault cases of a run's output and its interruptions: two runs on one ``--out``, signals
while the figures are drawn, a second Ctrl-C.  Each measured in fresh processes with real
signals (``CASES``, as in ``fault_cases_master``)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from fault_cases_master import CLI, _case, _csv_rows, _summary

from helpers import ROOT


def _start(out: Path, *extra, env=None, code=None) -> subprocess.Popen:
    """`agilesat run scan_pitch --out out ...` (or ``code`` with those arguments) in a
    session of its own: a signal to its process group is a terminal's Ctrl-C."""
    command = [*CLI, "run", "scan_pitch", "--out", str(out), "-q", *extra]
    if code is not None:
        command = [sys.executable, "-c", code, *command[3:]]
    return subprocess.Popen(
        command,
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, **(env or {})},
        start_new_session=True,
    )


def _until(condition, process, timeout: float = 300.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        if condition():
            return True
        time.sleep(0.005)
    return False


def _whole_run(out: Path, rows: int) -> bool:
    """results.csv and results.npz hold exactly one run's rows, in time order."""
    try:
        data = np.load(out / "results.npz")["data"]
    except (OSError, ValueError, KeyError):
        return False
    csv_rows, whole = _csv_rows(out / "results.csv")
    return (
        whole
        and csv_rows == rows == len(data)
        and bool(np.all(np.diff(data[:, 0]) > 0))
        and _summary(out).get("rows") == rows
    )


def _stopped(process) -> bool:
    return Path(f"/proc/{process.pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "T"


def two_runs_one_out(stop: float = 100.0):
    """B starts while A is in mid-run (A stops itself, SIGSTOP at macro step 100, until B
    has ended); then A and B start together.  Each time exactly one runs, the other is
    refused before it writes, and the directory holds one run."""
    rows = int(stop / 0.05) + 1
    observed, ok = [], True
    for together in (False, True):
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "out"
            hook = {} if together else {"AGILESAT_TEST_SIGNAL": "SIGSTOP@step:100"}
            a = _start(out, "--stop", str(stop), "--no-figures", env=hook)
            if not together:
                _until(lambda: _stopped(a), a)
            b = _start(out, "--stop", str(stop), "--no-figures")
            b_err = b.communicate(timeout=600)[1]
            os.kill(a.pid, signal.SIGCONT)
            a_err = a.communicate(timeout=600)[1]
            codes = sorted([(a.returncode, "A", a_err), (b.returncode, "B", b_err)])
            (won, winner, _), (lost, loser, said) = codes
            good = (
                (won, lost) == (0, 1)
                and (together or winner == "A")
                and "is being written by another run or campaign (process " in said
                and _whole_run(out, rows)
            )
            ok &= good
            observed.append(
                f"{'together' if together else 'B while A is at step 100'}: {winner} exit {won}, "
                f"{loser} exit {lost} ({said.strip().splitlines()[-1][:120] if said else ''})"
                f"; one whole run in the directory: {_whole_run(out, rows)}"
                + ("" if good else " (!)")
            )
    return _case(
        "two `agilesat run scan_pitch` on one --out: the second while the first is in "
        "mid-run, and both at once",
        "one runs to the end, the other exits 1 before it writes anything, naming the "
        "directory and the process holding it; results.csv, results.npz and summary.json "
        "hold the one run",
        "; ".join(observed),
        ok,
    )


def ctrl_c_while_figures():
    """SIGINT to the process group (a terminal's Ctrl-C) as soon as the first figure is
    on disk."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        process = _start(out)
        seen = _until(lambda: any(out.glob("*.png")), process)
        if seen:
            os.killpg(process.pid, signal.SIGINT)
        _, stderr = process.communicate(timeout=600)
        summary = _summary(out)
        listed = summary.get("figures") or []
        on_disk = sorted(str(p) for p in out.glob("*.png"))
        ok = (
            seen
            and process.returncode == 130
            and summary.get("status") == "interrupted"
            and summary.get("interruption", {}).get("during") == "the figures"
            and sorted(listed) == on_disk
            and _whole_run(out, 3001)
            and "Traceback" not in stderr
        )
        return _case(
            "Ctrl-C (SIGINT to the process group) to `agilesat run scan_pitch` once its first "
            "figure is written",
            "exit 130; summary.json: status 'interrupted' during the figures, the figures "
            "written (those on disk) and that the rest were not; results whole",
            f"exit {process.returncode}; status {summary.get('status')}; "
            f"{summary.get('interruption')}; {len(listed)} listed, {len(on_disk)} on disk",
            ok,
        )


def sigterm_at_figure(k: int = 2):
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        process = _start(out, env={"AGILESAT_TEST_SIGNAL": f"SIGTERM@figure:{k}"})
        _, stderr = process.communicate(timeout=600)
        summary = _summary(out)
        listed = summary.get("figures") or []
        ok = (
            process.returncode == 143
            and summary.get("status") == "interrupted"
            and len(listed) == k - 1
            and all(Path(p).exists() for p in listed)
            and sorted(listed) == sorted(str(p) for p in out.glob("*.png"))
            and summary.get("interruption", {}).get("not_written")
            and _whole_run(out, 3001)
        )
        return _case(
            f"SIGTERM to `agilesat run scan_pitch` as it starts its figure {k}",
            f"exit 143; summary.json: status 'interrupted', the {k - 1} figure(s) written "
            "and that the rest were not; results whole",
            f"exit {process.returncode}; status {summary.get('status')}; {len(listed)} "
            f"listed; {summary.get('interruption')}; {stderr.strip()[-160:]}",
            ok,
        )


#: `agilesat run` as the program, with a second SIGINT while the records are written and a
#: third as the process ends (after main() returned)
_TWICE = """
import os, signal, sys, time
from agilesat.orchestration import cli, runner
write = runner.write_records
def again(*args):
    os.kill(os.getpid(), signal.SIGINT)
    return write(*args)
runner.write_records = again
sys.argv = ["agilesat", *sys.argv[1:]]
code = cli.main()
os.kill(os.getpid(), signal.SIGINT)
time.sleep(0.2)
sys.exit(code)
"""


def second_sigint(at: int = 30):
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        process = _start(
            out, "--no-figures", env={"AGILESAT_TEST_SIGNAL": f"SIGINT@step:{at}"}, code=_TWICE
        )
        _, stderr = process.communicate(timeout=600)
        summary = _summary(out)
        ok = (
            process.returncode == 130
            and summary.get("status") == "interrupted"
            and _whole_run(out, at + 1)
            and "Traceback" not in stderr
        )
        return _case(
            "Ctrl-C at macro step 30 of `agilesat run scan_pitch`, a second one while its "
            "records are written and a third as the process exits",
            "exit 130 (not killed by the later signals); results and summary of the 31 rows",
            f"exit {process.returncode}; status {summary.get('status')}; rows "
            f"{summary.get('rows')}; {json.dumps(stderr.strip().splitlines()[-1:])[:160]}",
            ok,
        )


CASES = [two_runs_one_out, ctrl_c_while_figures, sigterm_at_figure, second_sigint]
