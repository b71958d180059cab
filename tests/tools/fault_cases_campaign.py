"""Fault cases of campaigns: resumes that would lose or mix runs, oversized and non-finite
dispersions, damaged campaign files, the cluster's sockets, a scheduler killed mid-way.
Each measured in fresh processes (``CASES``, as in ``fault_cases_master``)."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from fault_cases_master import CLI, _case, _refused, system_copy

from helpers import ROOT

KEEP = "SatelliteDynamics.w_BO_B[2]"
SMALL = [
    "--no-report",
    "--stop",
    "1",
    "--vary",
    "SatelliteDynamics.rate0[2]=+normal(0, 0.01deg)",
    "--keep",
    KEEP,
    "--no-progress",
]


def _campaign(target, out, *extra, env=None, timeout: float = 600):
    return subprocess.run(
        [*CLI, "campaign", str(target), *SMALL, "--out", str(out), *map(str, extra)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, **(env or {})},
    )


def _last(result) -> str:
    return _last_line(result.stderr + result.stdout)


def _last_line(text: str) -> str:
    lines = [line.strip() for line in text.splitlines() if line]
    errors = [line for line in lines if "error" in line or "Error" in line]
    return ((errors or lines or ["(nothing)"])[-1])[:200]


def resume_fewer_runs():
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "c"
        first = _campaign("scan_pitch", out, "--runs", "4", "--workers", "1")
        kept = np.load(out / "signals.npy") if (out / "signals.npy").exists() else None
        again = _campaign("scan_pitch", out, "--runs", "2", "--workers", "1", "--resume")
        after = np.load(out / "signals.npy") if (out / "signals.npy").exists() else None
        journal = (out / "runs.jsonl").read_text().splitlines()
        ok = (
            first.returncode in (0, 3)
            and again.returncode in (0, 3)
            and kept is not None
            and not np.isnan(kept).any()
            and after is not None
            and after.shape[0] >= 4
            and np.array_equal(after[:4], kept)
            and len(journal) == 4
        )
        lost = "?" if after is None else int(np.isnan(after).all(axis=(1, 2)).sum())
        return _case(
            "a campaign of 4 runs keeping SatelliteDynamics.w_BO_B[2], then `--resume --runs 2`",
            "nothing made is dropped: signals.npy still holds the 4 runs' signals "
            "bit for bit, the journal its 4 runs",
            f"exits {first.returncode}, {again.returncode}; signals.npy "
            f"{None if after is None else after.shape}, {lost} runs NaN after the resume; "
            f"journal {len(journal)} lines",
            ok,
        )


def resume_changed_system():
    with tempfile.TemporaryDirectory() as tmp:
        ssd = system_copy(tmp)
        out = Path(tmp) / "c"
        first = _campaign(ssd, out, "--runs", "2", "--workers", "1", "--step", "0.05")
        text = ssd.read_text()
        ssd.write_text(
            re.sub(
                r'(name="gravity_gradient">\s*<ssv:Boolean value=)"true"',
                r'\1"false"',
                text,
                count=1,
            )
        )
        assert ssd.read_text() != text
        again = _campaign(ssd, out, "--runs", "3", "--workers", "1", "--step", "0.05", "--resume")
        journal = (out / "runs.jsonl").read_text().splitlines()
        ok = (
            first.returncode in (0, 3)
            and again.returncode == 1
            and str(ssd) in again.stderr
            and "changed" in again.stderr
            and len(journal) == 2
        )
        return _case(
            "a campaign of 2 runs on a copy of scan_pitch.ssd, the file then edited "
            "(gravity_gradient true -> false), then `--resume --runs 3`",
            "exit 1 naming the system file and that it changed since the campaign began "
            "(its content hash is in campaign.json); no run added",
            f"exits {first.returncode}, {again.returncode}: {_last(again)}; journal "
            f"{len(journal)} lines",
            ok,
        )


def oversized():
    """Each in a fresh process held to 3 GiB of address space (a grid or journal built
    would be a MemoryError there); its time and peak memory are printed, not judged (a
    bound on them fails on a busy machine)."""
    trials = [
        (
            "--vary CmgCluster.h_rotor=linspace(0, 1, 1e9)",
            ["--vary", "CmgCluster.h_rotor=linspace(0, 1, 1e9)"],
        ),
        (
            "two grids of 10^5 points",
            [
                "--vary",
                "CmgCluster.h_rotor=linspace(0, 1, 100000)",
                "--vary",
                "CmgCluster.rate_limit=linspace(0.1, 1, 100000)",
            ],
        ),
        ("--runs 1000000000", ["--runs", "1000000000"]),
    ]
    observed, ok = [], True
    with tempfile.TemporaryDirectory() as tmp:
        for label, extra in trials:
            out = Path(tmp) / "c"
            command = [
                *CLI,
                "campaign",
                "scan_pitch",
                "--stop",
                "1",
                "--no-progress",
                "--no-report",
            ]
            command += ["--out", str(out), *extra]
            code, seconds, rss, stderr = _bounded(command, Path(tmp) / "err", 600)
            good = (
                code == 1
                and "a campaign may have" in stderr
                and "Traceback" not in stderr
                and "MemoryError" not in stderr
            )
            ok &= good
            said = (stderr.strip().splitlines() or ["(nothing)"])[-1][:140]
            observed.append(
                f"{label}: exit {code} after {seconds:.1f} s, peak {rss:.0f} MB: {said}"
                + ("" if good else " (!)")
            )
            shutil.rmtree(out, ignore_errors=True)
    return _case(
        "`agilesat campaign scan_pitch` with --vary ...=linspace(0, 1, 1e9), with two "
        "10^5-point grids, with --runs 1000000000",
        "exit 1 from the counts, before any grid is built (held to 3 GiB: no MemoryError), "
        "saying how many runs that is and the most a campaign takes; no traceback",
        "; ".join(observed),
        ok,
    )


def _bounded(command, stderr_file: Path, seconds: float, memory: int = 3 << 30):
    """(exit status, wall seconds, peak RSS in MB, stderr) of ``command``, killed after
    ``seconds`` and held to ``memory`` bytes of address space (a MemoryError, not a
    machine out of memory)."""
    import resource

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))

    start = time.monotonic()
    with stderr_file.open("w") as sink:
        process = subprocess.Popen(
            command, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=sink, preexec_fn=limit
        )
        while True:
            pid, status, usage = os.wait4(process.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() - start > seconds:
                process.kill()
            time.sleep(0.05)
    process.returncode = os.waitstatus_to_exitcode(status)
    return (
        process.returncode,
        time.monotonic() - start,
        usage.ru_maxrss / 1024,
        stderr_file.read_text(),
    )


def nonfinite_dispersions():
    trials = [
        "CmgCluster.h_rotor=normal(1e999, 1)",
        "CmgCluster.h_rotor=*normal(1, 1e999)",
        "CmgCluster.h_rotor=uniform(0, 1e400)",
        "CmgCluster.h_rotor=linspace(0, 1e999, 3)",
    ]
    observed, ok = [], True
    with tempfile.TemporaryDirectory() as tmp:
        file = Path(tmp) / "nan.toml"  # TOML has nan: a [set] value of it
        file.write_text(
            '[vary]\n"SatelliteDynamics.rate0[2]" = "+normal(0, 0.01deg)"\n'
            '[set]\n"CmgCluster.h_rotor" = nan\n'
        )
        for vary in [*trials, f"--dispersions {file.name}"]:
            given = ["--dispersions", str(file)] if vary.startswith("--") else ["--vary", vary]
            result = subprocess.run(
                [*CLI, "campaign", "scan_pitch", "--stop", "1", *given, "--no-progress"]
                + ["--no-report"]
                + ["--out", str(Path(tmp) / "c")],
                cwd=ROOT,
                capture_output=True,
                text=True,
                timeout=600,
            )
            good = (
                result.returncode == 1
                and "CmgCluster.h_rotor" in result.stderr
                and "finite" in result.stderr
                and not (Path(tmp) / "c" / "runs.jsonl").exists()
            )
            ok &= good
            observed.append(f"{vary}: exit {result.returncode}" + ("" if good else " (!)"))
    return _case(
        "--vary with a non-finite distribution parameter: normal(1e999, 1), "
        "*normal(1, 1e999), uniform(0, 1e400), linspace(0, 1e999, 3); a dispersion file "
        "setting CmgCluster.h_rotor = nan",
        "exit 1 naming the dispersion (the file's value) and that it must be finite; nothing run",
        "; ".join(observed),
        ok,
    )


def crashed_warm_up():
    """Every worker process kills itself (SIGKILL) as it starts its warm-up
    (``$AGILESAT_TEST_SIGNAL=SIGKILL@worker:0``): each batch is lost as a crashed run's."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "c"
        result = _campaign(
            "scan_pitch",
            out,
            "--runs",
            "2",
            "--workers",
            "1",
            env={"AGILESAT_TEST_SIGNAL": "SIGKILL@worker:0"},
        )
        try:
            summary = json.loads((out / "campaign.json").read_text())
        except (OSError, ValueError) as exc:
            summary = {"unreadable": str(exc)}
        journal = (out / "runs.jsonl").read_text().splitlines() if out.exists() else []
        statuses = [json.loads(line)["status"] for line in journal]
        runs = summary.get("runs", {})
        ok = (
            result.returncode == 3
            and summary.get("status") == "complete"
            and (runs.get("made"), runs.get("lost")) == (2, 2)
            and statuses == ["lost", "lost"]
            and len(summary.get("lost_workers", [])) >= 1
            and summary.get("warm_up", {}).get("processes") == 0
        )
        return _case(
            "every campaign worker process killed (SIGKILL) as it starts its warm-up, "
            "before its first run",
            "exit 3; campaign.json complete, both runs lost (journaled as such) once Dask "
            "gives up on them, the dead worker reported; no warm-up counted",
            f"exit {result.returncode}; {summary.get('status')}; runs {runs}; journal "
            f"{statuses}; lost workers {len(summary.get('lost_workers', []))}; "
            f"warm-ups {summary.get('warm_up', {}).get('processes')}; {_last(result)}",
            ok,
        )


def _damage_journal_json(out: Path) -> None:
    lines = (out / "runs.jsonl").read_text().splitlines(keepends=True)
    lines[0] = "this is not json\n"
    (out / "runs.jsonl").write_text("".join(lines))


def _damage_journal_index(out: Path) -> None:
    lines = (out / "runs.jsonl").read_text().splitlines(keepends=True)
    record = json.loads(lines[1])
    record["index"] = str(record["index"])
    lines[1] = json.dumps(record) + "\n"
    (out / "runs.jsonl").write_text("".join(lines))


def _damage_journal_twice(out: Path) -> None:
    lines = (out / "runs.jsonl").read_text().splitlines(keepends=True)
    (out / "runs.jsonl").write_text("".join([*lines, lines[0]]))


DAMAGES = {
    "a journal line that is not JSON (line 1)": (_damage_journal_json, "runs.jsonl:1"),
    "a journal line whose index is a string (line 2)": (_damage_journal_index, "runs.jsonl:2"),
    "a journal recording run 0 twice (line 3 repeats line 1)": (
        _damage_journal_twice,
        "runs.jsonl:3",
    ),
    "metrics.json replaced by []": (
        lambda out: (out / "metrics.json").write_text("[]\n"),
        "metrics.json",
    ),
    "campaign.json cut to its first 40 bytes": (
        lambda out: (out / "campaign.json").write_text((out / "campaign.json").read_text()[:40]),
        "campaign.json",
    ),
}


def damaged_campaign_files():
    with tempfile.TemporaryDirectory() as tmp:
        clean = Path(tmp) / "clean"
        first = _campaign("scan_pitch", clean, "--runs", "2", "--workers", "1")
        observed, ok = [], first.returncode in (0, 3)
        for k, (label, (damage, file)) in enumerate(DAMAGES.items()):
            out = shutil.copytree(clean, Path(tmp) / f"c{k}")
            damage(out)
            result = _campaign("scan_pitch", out, "--runs", "3", "--workers", "1", "--resume")
            good = _refused(result, f"{out / file}")
            ok &= good
            observed.append(
                f"{label}: exit {result.returncode}: {_last(result)[:150]}"
                + ("" if good else " (!)")
            )
        return _case(
            "`--resume` of a campaign whose files are damaged: " + "; ".join(DAMAGES),
            "exit 1 with a message naming the file (and line) and what was expected; no traceback",
            "; ".join(observed),
            ok,
        )


def _children(pid: int) -> list[int]:
    found, todo = [], [pid]
    while todo:
        parent = todo.pop()
        for task in Path(f"/proc/{parent}/task").glob("*"):
            try:
                kids = [int(c) for c in (task / "children").read_text().split()]
            except OSError:
                kids = []
            found += kids
            todo += kids
    return found


def _listening(pids) -> list[str]:
    """'address:port' of the TCP sockets in LISTEN state the processes ``pids`` hold."""
    inodes = set()
    for pid in pids:
        for fd in Path(f"/proc/{pid}/fd").glob("*"):
            try:
                target = os.readlink(fd)
            except OSError:
                continue
            if target.startswith("socket:["):
                inodes.add(target[8:-1])
    found = []
    for table, width in (("/proc/net/tcp", 8), ("/proc/net/tcp6", 32)):
        for line in Path(table).read_text().splitlines()[1:]:
            fields = line.split()
            if fields[3] == "0A" and fields[9] in inodes:  # LISTEN
                address, port = fields[1].split(":")
                raw = bytes.fromhex(address)
                words = [raw[i : i + 4][::-1] for i in range(0, len(raw), 4)]
                host = (
                    ".".join(str(b) for b in words[0])
                    if width == 8
                    else ":".join(b"".join(words).hex()[i : i + 4] for i in range(0, 32, 4))
                )
                found.append(f"{host}:{int(port, 16)}")
    return found


def _loopback(address: str) -> bool:
    host = address.rsplit(":", 1)[0]
    return host.startswith("127.") or host == "0000:0000:0000:0000:0000:0000:0000:0001"


def cluster_sockets():
    """The campaign stops itself (SIGSTOP) once its first run is journaled; its listening
    sockets and its workers' are read then; SIGCONT and SIGTERM end it."""
    with tempfile.TemporaryDirectory() as tmp:
        process = subprocess.Popen(
            [*CLI, "campaign", "scan_pitch", *SMALL, "--runs", "40", "--workers", "2"]
            + ["--out", str(Path(tmp) / "c")],
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env={**os.environ, "AGILESAT_TEST_SIGNAL": "SIGSTOP@run:1"},
        )
        deadline = time.monotonic() + 300
        state = ""
        while time.monotonic() < deadline and process.poll() is None:
            state = Path(f"/proc/{process.pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
            if state == "T":
                break
            time.sleep(0.05)
        sockets = _listening([process.pid, *_children(process.pid)]) if state == "T" else []
        os.kill(process.pid, signal.SIGCONT)
        process.send_signal(signal.SIGTERM)
        process.communicate(timeout=300)
        exposed = [s for s in sockets if not _loopback(s)]
        ok = state == "T" and sockets and not exposed and process.returncode == 143
        return _case(
            "the listening sockets of `agilesat campaign scan_pitch --workers 2` (its "
            "LocalCluster: scheduler, nannies, workers) in mid-campaign",
            "every one on the loopback interface, no dashboard (an option asks for either); "
            "SIGTERM then ends it with exit 143",
            f"{len(sockets)} listening, on {sorted({s.rsplit(':', 1)[0] for s in sockets})}; "
            f"not loopback: {exposed}; exit {process.returncode}",
            ok,
        )


def _dask(tmp: Path, *args) -> subprocess.Popen:
    return subprocess.Popen(
        [os.path.join(os.path.dirname(sys.executable), "dask"), *args],
        cwd=tmp,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )


def killed_scheduler():
    """A `dask scheduler` and one worker on 127.0.0.1; the scheduler is killed (SIGKILL)
    once the campaign has journaled 3 runs; then the campaign is resumed on a LocalCluster."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        file = tmp / "scheduler.json"
        started = [
            _dask(
                tmp,
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                str(file),
            )
        ]
        try:
            deadline = time.monotonic() + 60
            while not file.exists() and time.monotonic() < deadline:
                time.sleep(0.2)
            address = json.loads(file.read_text())["address"]
            started.append(
                _dask(
                    tmp,
                    "worker",
                    address,
                    "--nthreads",
                    "1",
                    "--no-nanny",
                    "--no-dashboard",
                    "--host",
                    "127.0.0.1",
                )
            )
            out = tmp / "c"
            campaign = subprocess.Popen(
                [*CLI, "campaign", "scan_pitch", *SMALL, "--runs", "200", "--scheduler", address]
                + ["--out", str(out)],
                cwd=ROOT,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )
            journal = out / "runs.jsonl"
            while campaign.poll() is None and not (
                journal.exists() and journal.read_text().count("\n") >= 3
            ):
                time.sleep(0.05)
            os.killpg(started[0].pid, signal.SIGKILL)
            killed = time.monotonic()
            stdout, stderr = campaign.communicate(timeout=300)
            seconds = time.monotonic() - killed
        finally:
            for process in started:
                if process.poll() is None:
                    os.killpg(process.pid, signal.SIGKILL)
                process.wait()
        summary = json.loads((out / "campaign.json").read_text())
        made = len((out / "runs.jsonl").read_text().splitlines())
        resumed = _campaign("scan_pitch", out, "--runs", "200", "--workers", "1", "--resume")
        after = json.loads((out / "campaign.json").read_text())
        said = [l for l in (stdout + stderr).splitlines() if "scheduler" in l and "lost" in l]
        ok = (
            campaign.returncode == 1
            and said
            and "Traceback" not in stdout + stderr
            and summary.get("status") == "interrupted"
            and resumed.returncode in (0, 3)
            and after["runs"]["made"] == 200
        )
        return _case(
            "`agilesat campaign --scheduler` whose `dask scheduler` is killed (SIGKILL) once "
            "3 runs are journaled; then `--resume` on a LocalCluster",
            "exit 1 saying the scheduler was lost, no traceback of Dask's before it; "
            "campaign.json status 'interrupted' with the runs made; the resume finishes the "
            "200 runs",
            f"exit {campaign.returncode} {seconds:.1f} s after the kill: "
            f"{said[0][:140] if said else _last_line(stdout + stderr)}; "
            f"status {summary.get('status')}, "
            f"{made} runs journaled; resume: exit {resumed.returncode}, "
            f"{after['runs']['made']} made",
            ok,
        )


def _started(out: Path, *extra, env=None) -> subprocess.Popen:
    """`agilesat campaign scan_pitch` of 4 small runs into ``out``, in a session of its
    own (a signal to its process group is a terminal's Ctrl-C)."""
    return subprocess.Popen(
        [*CLI, "campaign", "scan_pitch", *SMALL, "--runs", "4", "--out", str(out), *extra],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, **(env or {})},
        start_new_session=True,
    )


def _stopped(process, timeout: float = 300) -> bool:
    """Wait until ``process`` stopped itself (SIGSTOP: state T); False if it ended first."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        if Path(f"/proc/{process.pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "T":
            return True
        time.sleep(0.05)
    return False


def two_campaigns_one_out():
    """Campaign A stops itself (SIGSTOP) once its first run is journaled; B on the same
    --out, then B with --resume, run while A holds it; then A goes on."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "c"
        a = _started(out, "--workers", "1", env={"AGILESAT_TEST_SIGNAL": "SIGSTOP@run:1"})
        held = _stopped(a)
        before = {p.name: p.read_bytes() for p in out.iterdir()}
        b = _campaign("scan_pitch", out, "--runs", "4", "--workers", "1", "--seed", "7")
        resumed = _campaign("scan_pitch", out, "--runs", "4", "--workers", "1", "--resume")
        untouched = before == {p.name: p.read_bytes() for p in out.iterdir()}
        os.kill(a.pid, signal.SIGCONT)
        a.communicate(timeout=600)
        indices = [
            json.loads(line)["index"] for line in (out / "runs.jsonl").read_text().splitlines()
        ]
        summary = json.loads((out / "campaign.json").read_text())
        refused = [
            r.returncode == 1
            and f"is being written by another run or campaign (process {a.pid}" in r.stderr
            for r in (b, resumed)
        ]
        ok = (
            held
            and refused == [True, True]
            and untouched
            and a.returncode in (0, 3)
            and sorted(indices) == [0, 1, 2, 3]
            and summary.get("status") == "complete"
            and summary.get("spec", {}).get("seed") == 0
        )
        return _case(
            "a second `agilesat campaign scan_pitch` on the --out of one in mid-campaign (its "
            "first run journaled), then the same with --resume",
            "both refused (exit 1) before writing anything, naming the directory and the "
            "process holding it; the first campaign finishes alone: each run journaled once, "
            "campaign.json its own",
            f"second: exit {b.returncode} ({_last(b)[:140]}); --resume: exit "
            f"{resumed.returncode}; files untouched meanwhile: {untouched}; first: exit "
            f"{a.returncode}, journal {indices}, {summary.get('status')}",
            ok,
        )


_CONSTANTS_MISSION = """
from agilesat.orchestration.mission import Metric, Scenario, System
from mission_constants import RATE

SYSTEM = System("constants", step=0.1, stop=0.5)
SYSTEM.add("SatelliteDynamics", rate0=[RATE, 0.0, 0.0])
SCENARIO = Scenario(
    "constants",
    "a mission whose rate comes from a module beside it",
    SYSTEM,
    metrics=[Metric("w1", lambda r: float(r["SatelliteDynamics.w_BI_B[1]"][-1]), unit="rad/s")],
)
"""


def resume_changed_module():
    """A mission that imports a constant from a module beside it; the module edited
    between a campaign and its resume."""
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "mission_constants.py").write_text("RATE = 0.01\n")
        mission = Path(tmp) / "mission.py"
        mission.write_text(_CONSTANTS_MISSION)
        out = Path(tmp) / "c"
        vary = ["--vary", "SatelliteDynamics.rate0[2]=normal(0, 0.001)", "--workers", "1"]

        def campaign(*extra):
            return subprocess.run(
                [*CLI, "campaign", str(mission), *vary, "--out", str(out), "-q", "--no-report"]
                + list(extra),
                cwd=tmp,
                capture_output=True,
                text=True,
                timeout=600,
            )

        first = campaign("--runs", "2")
        (Path(tmp) / "mission_constants.py").write_text("RATE = 0.02\n")
        again = campaign("--runs", "4", "--resume")
        journal = (out / "runs.jsonl").read_text().splitlines() if out.exists() else []
        named = str((Path(tmp) / "mission_constants.py").resolve())
        ok = (
            first.returncode in (0, 3)
            and again.returncode == 1
            and f"{named} changed since the campaign began" in again.stderr
            and len(journal) == 2
        )
        return _case(
            "a campaign of 2 runs of a mission importing RATE from mission_constants.py "
            "beside it, the module then edited (0.01 -> 0.02), then `--resume --runs 4`",
            "exit 1 naming mission_constants.py and that it changed since the campaign began "
            "(the content hash covers the modules the mission imports and the toolkit's "
            "sources); no run added",
            f"exits {first.returncode}, {again.returncode}: {_last(again)[:200]}; journal "
            f"{len(journal)} lines",
            ok,
        )


def ctrl_c_while_the_cluster_starts():
    """SIGINT to the campaign's process group (a terminal's Ctrl-C) 0.1 s after its
    LocalCluster's first processes exist: as the workers' Pythons start (their imports,
    before their preload ignores SIGINT: each printed its KeyboardInterrupt's traceback
    until they inherited SIGINT blocked)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "c"
        process = _started(out, "--workers", "2")
        deadline = time.monotonic() + 300
        while process.poll() is None and time.monotonic() < deadline:
            if len(_children(process.pid)) >= 2:
                break
            time.sleep(0.005)
        time.sleep(0.1)
        starting = len(_children(process.pid))
        os.killpg(process.pid, signal.SIGINT)
        stdout, stderr = process.communicate(timeout=300)
        summary = json.loads((out / "campaign.json").read_text()) if out.exists() else {}
        ok = (
            process.returncode == 130
            and summary.get("status") == "interrupted"
            and "Nanny failed" not in stdout + stderr
            and "Traceback" not in stdout + stderr
        )
        return _case(
            "Ctrl-C (SIGINT to the process group) to `agilesat campaign scan_pitch --workers "
            "2` while its LocalCluster starts (0.1 s after its first processes exist: the "
            "workers' Pythons starting)",
            "exit 130 saying it was interrupted and how to resume; campaign.json "
            "'interrupted' (not Dask's 'Nanny failed to start', exit 1, campaign.json "
            "'running'); no traceback (not a worker's KeyboardInterrupt as its Python starts)",
            f"signalled with {starting} processes of the cluster up: exit {process.returncode}; "
            f"campaign.json {summary.get('status')}; {_last_line(stdout + stderr)[:140]}",
            ok,
        )


_CRASHING_MISSION = """
from agilesat.orchestration.mission import Metric, Scenario, System

SYSTEM = System("crashing", step=0.1, stop=0.5)
SYSTEM.add("Wild", "{fmu}", crash_at=0.2)
SCENARIO = Scenario(
    "crashing",
    "a model that crashes at its nominal values",
    SYSTEM,
    metrics=[Metric("x", lambda r: float(r["Wild.x"][-1]))],
)
"""


def crashing_nominal_run():
    """A user's model that segfaults at its nominal crash_at = 0.2 s; the campaign's
    dispersed runs (crash_at drawn far beyond the stop time) do not crash."""
    import wild_model

    with tempfile.TemporaryDirectory() as tmp:
        mission = Path(tmp) / "mission.py"
        mission.write_text(_CRASHING_MISSION.format(fmu=wild_model.built()))
        out = Path(tmp) / "c"
        result = subprocess.run(
            [*CLI, "campaign", str(mission), "--runs", "2", "--workers", "1", "--vary"]
            + ["Wild.crash_at=uniform(10, 20)", "--out", str(out), "-q", "--no-report"],
            cwd=tmp,
            capture_output=True,
            text=True,
            timeout=600,
        )
        summary = json.loads((out / "campaign.json").read_text()) if out.exists() else {}
        reason = summary.get("nominal", {}).get("reason", "")
        ok = (
            result.returncode == 0
            and summary.get("status") == "complete"
            and summary.get("runs", {}).get("ok") == 2
            and "killed by SIGSEGV" in reason
            and (out / "runs.csv").exists()
        )
        return _case(
            "a campaign of a user's model that segfaults at its nominal values (the dispersed "
            "runs do not): the nominal run the histograms mark crashes",
            "the campaign ends normally (exit 0, its 2 runs ok, runs.csv, campaign.json "
            "complete) and says the nominal run's process was killed by SIGSEGV; it is not "
            "killed itself (exit -11)",
            f"exit {result.returncode}; campaign.json {summary.get('status')}, runs "
            f"{summary.get('runs', {}).get('ok')} ok; nominal: {reason[:140]}",
            ok,
        )


def elementwise_inertia():
    """A new user's dispersion of a whole inertia by an element-wise normal()."""
    observed, ok = [], True
    with tempfile.TemporaryDirectory() as tmp:
        for vary in (
            "SatelliteDynamics.inertia=normal(1, 0.01)",
            "SatelliteDynamics.inertia=*normal(1, 0.01)",
        ):
            result = _campaign(
                "scan_pitch", Path(tmp) / "c", "--runs", "2", "--workers", "1", "--vary", vary
            )
            good = (
                result.returncode == 1
                and "inertia(sd_rel, sd_angle)" in result.stderr
                and not (Path(tmp) / "c" / "runs.jsonl").exists()
            )
            ok &= good
            observed.append(
                f"{vary}: exit {result.returncode}: {_last(result)[:160]}"
                + ("" if good else " (!)")
            )
    return _case(
        "--vary SatelliteDynamics.inertia=normal(1, 0.01) (a forgotten '*') and "
        "=*normal(1, 0.01): a draw per element of a symmetric inertia",
        "exit 1 before anything runs, saying no run's matrix would be symmetric and what "
        "disperses an inertia (inertia(sd_rel, sd_angle), or elements one by one); the "
        "forgotten '*' pointed out (not: every run failing 'inertia must be symmetric')",
        "; ".join(observed),
        ok,
    )


CASES = [
    two_campaigns_one_out,
    resume_changed_module,
    ctrl_c_while_the_cluster_starts,
    crashing_nominal_run,
    elementwise_inertia,
    resume_fewer_runs,
    resume_changed_system,
    oversized,
    nonfinite_dispersions,
    damaged_campaign_files,
    cluster_sockets,
    killed_scheduler,
    crashed_warm_up,
]
