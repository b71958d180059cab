"""Fault cases of a run's output and its interruptions: two runs on one ``--out``, signals
while the figures are drawn, a second Ctrl-C.  Each measured in fresh processes with real
signals (``CASES``, as in ``fault_cases_master``)."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from fault_cases_master import CLI, _case, _csv_rows, _stderr_line, _summary

from helpers import ROOT


def _start(out: Path, *extra, env=None, code=None, target="scan_pitch") -> subprocess.Popen:
    """`agilesat run TARGET --out out ...` (or ``code`` with those arguments) in a session
    of its own: a signal to its process group is a terminal's Ctrl-C."""
    command = [*CLI, "run", str(target), "--out", str(out), "-q", *extra]
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
            a = _start(out, "--stop", str(stop), "--no-figures", "--no-report", env=hook)
            if not together:
                _until(lambda: _stopped(a), a)
            b = _start(out, "--stop", str(stop), "--no-figures", "--no-report")
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
            out,
            "--no-figures",
            "--no-report",
            env={"AGILESAT_TEST_SIGNAL": f"SIGINT@step:{at}"},
            code=_TWICE,
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


#: `agilesat run` as the program, and a SIGINT as Python finalises the process (from an
#: object of __main__ collected then, after Python has put its default handlers back)
_AS_IT_EXITS = """
import os, signal, sys, time
from agilesat.orchestration import cli

class Late:
    def __del__(self):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.2)

late = Late()
sys.argv = ["agilesat", *sys.argv[1:]]
sys.exit(cli.main())
"""


def sigint_as_python_exits(at: int = 30):
    with tempfile.TemporaryDirectory() as tmp:
        observed, ok = [], True
        for signal_at, code in ((f"SIGINT@step:{at}", 130), ("", 0)):
            out = Path(tmp) / f"out{code}"
            env = {"AGILESAT_TEST_SIGNAL": signal_at} if signal_at else {}
            process = _start(
                out, "--no-figures", "--no-report", "--stop", "2", env=env, code=_AS_IT_EXITS
            )
            _, stderr = process.communicate(timeout=600)
            good = process.returncode == code and "Traceback" not in stderr
            ok &= good
            observed.append(
                f"{'interrupted at step ' + str(at) if code else 'a whole run'}: exit "
                f"{process.returncode}; summary {_summary(out).get('status')}"
                + ("" if good else " (!)")
            )
        return _case(
            "a SIGINT as Python finalises `agilesat run scan_pitch` (after its default "
            "handlers are back), after a run interrupted at step 30 and after a whole run",
            "exit 130 and 0: the exit status decided by the command, not killed by the signal",
            "; ".join(observed),
            ok,
        )


def _wild(out: Path, *extra, env=None) -> subprocess.Popen:
    """`agilesat run Wild.fmu` (``wild_model``) for 2 s, in a session of its own."""
    import wild_model

    fmu = wild_model.built()
    extra = ("--step", "0.1", "--stop", "2", "--no-figures", "--no-report", *extra)
    return _start(out, *extra, env=env, target=fmu)


def stuck_step(grace: float = 1.0):
    """A user's model stuck in its step at t = 0.5 s (an endless loop; an endless sleep),
    signalled once its rows up to there are on disk."""
    observed, ok = [], True
    for fault, signum in (("stick_at", signal.SIGINT), ("sleep_at", signal.SIGTERM)):
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "out"
            process = _wild(
                out, "--set", f"Wild.{fault}=0.5", env={"AGILESAT_STEP_GRACE": str(grace)}
            )
            reached = _until(lambda: _csv_rows(out / "results.csv")[0] >= 6, process)
            os.kill(process.pid, signum)
            try:
                _, stderr = process.communicate(timeout=120)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                _, stderr = process.communicate()
            summary = _summary(out)
            rows, whole = _csv_rows(out / "results.csv")
            good = (
                reached
                and process.returncode == 128 + signum
                and summary.get("status") == "interrupted"
                and "did not return within" in summary.get("error", "")
                and summary.get("rows") == rows == 6
                and whole
                and (out / "results.npz").exists()
                and (out / "log.txt").exists()
                and "Traceback" not in stderr
            )
            ok &= good
            observed.append(
                f"{fault} 0.5 s, {signal.Signals(signum).name}: exit {process.returncode}; "
                f"status {summary.get('status')}, {rows} rows"
                + ("" if good else f" (!) {stderr.strip()[-200:]}")
            )
    return _case(
        f"SIGINT and SIGTERM to `agilesat run` while a user's model is stuck in its step "
        f"(an endless loop; an endless sleep), AGILESAT_STEP_GRACE={grace:g}",
        "the watchdog stops the step after the grace: exit 130/143; results.csv, results.npz, "
        "log.txt and summary.json ('interrupted', the step that did not return) of the 6 rows "
        "made; no traceback",
        "; ".join(observed),
        ok,
    )


def killed_run_leftovers():
    """SIGKILL to a run stuck in its step, then a second run into the same --out."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        process = _wild(out, "--set", "Wild.stick_at=0.5")
        reached = _until(lambda: _csv_rows(out / "results.csv")[0] >= 6, process)
        os.kill(process.pid, signal.SIGKILL)
        process.communicate(timeout=120)
        rows, whole = _csv_rows(out / "results.csv")
        # what a kill while summary.json is being written leaves (its temporary name)
        (out / f".summary.json.{process.pid}.partial").write_text('{"status": "o')
        left = sorted(p.name for p in out.iterdir())
        again = _wild(out)
        _, stderr = again.communicate(timeout=600)
        after = sorted(p.name for p in out.iterdir() if p.name.startswith("."))
        ok = (
            reached
            and rows == 6
            and whole
            and again.returncode == 0
            and "removed what a killed run or campaign left" in stderr
            and not after
        )
        return _case(
            "kill -9 of `agilesat run` (a model stuck at t = 0.5 s; and the half summary.json a "
            "kill while it is written leaves under its temporary name), then another run on "
            "its --out",
            "the killed run leaves results.csv with its 6 whole rows, its scratch file and the "
            "temporary one; the next run removes them, says so, and runs",
            f"after the kill: {rows} whole rows ({whole}), files {left}; the next run: exit "
            f"{again.returncode}, hidden files left {after}",
            ok,
        )


def unwritable_out():
    """--out on a read-only file system (a directory to make, and one that exists), and on
    a full one (a 640 KiB tmpfs, its records fit: the figures fill it)."""
    if os.geteuid() != 0:
        return _case(
            "a read-only and a full --out",
            "(needs root to mount a tmpfs)",
            "not run: not root",
            False,
            skipped="needs root to mount a tmpfs",
        )
    observed, ok = [], True
    with tempfile.TemporaryDirectory() as tmp:
        mount = Path(tmp) / "small"
        mount.mkdir()
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=640k", "tmpfs", str(mount)], check=True)
        try:
            (mount / "exists").mkdir()
            subprocess.run(["mount", "-o", "remount,ro", str(mount)], check=True)
            trials = [
                ("run, a read-only --out to make", "run", "new"),
                ("campaign, a read-only --out", "campaign", "exists"),
            ]
            for label, command, directory in trials:
                result = subprocess.run(
                    [*CLI, command, "scan_pitch", "--stop", "0.5", "--out", str(mount / directory)]
                    + ["-q", "--no-report"],
                    cwd=ROOT,
                    capture_output=True,
                    text=True,
                    timeout=600,
                )
                said = _stderr_line(result, "error")
                good = (
                    result.returncode == 1
                    and f"{mount / directory}" in said
                    and "Read-only file system" in said
                    and ".partial" not in result.stderr
                    and "[Errno" not in result.stderr
                )
                ok &= good
                said += "" if good else " (!)"
                observed.append(f"{label}: exit {result.returncode}: {said}")
            subprocess.run(["mount", "-o", "remount,rw", str(mount)], check=True)
            result = subprocess.run(
                [*CLI, "run", "scan_pitch", "--stop", "5", "--out", str(mount / "full"), "-q"]
                + ["--no-report"],
                cwd=ROOT,
                capture_output=True,
                text=True,
                timeout=600,
            )
            lines = (result.stdout + result.stderr).splitlines()
            said = next((line.strip() for line in lines if "No space left" in line), "(nothing)")
            pngs = list((mount / "full").glob("*.png"))
            whole = all(p.read_bytes().endswith(b"IEND\xaeB`\x82") for p in pngs)  # PNG's end
            good = (
                result.returncode == 1
                and re.search(r"full/fig\w+\.png: No space left on device", said)
                and whole
                and not [p for p in (mount / "full").iterdir() if p.name.startswith(".")]
            )
            ok &= bool(good)
            observed.append(
                f"run, a full --out: exit {result.returncode}: {said}; {len(pngs)} whole figures"
                + ("" if good else " (!)")
            )
        finally:
            subprocess.run(["umount", str(mount)], check=True)
    return _case(
        "`agilesat run` and `agilesat campaign` on a read-only --out (one to make, one that "
        "exists); `agilesat run scan_pitch` whose figures fill its --out (640 KiB)",
        "exit 1 naming the directory or file and the reason (no bare OS error, no .partial "
        "name); a figure that does not fit is not left half-written",
        "; ".join(observed),
        ok,
    )


CASES = [
    two_runs_one_out,
    ctrl_c_while_figures,
    sigterm_at_figure,
    second_sigint,
    sigint_as_python_exits,
    stuck_step,
    killed_run_leftovers,
    unwritable_out,
]
