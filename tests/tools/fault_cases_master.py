"""Fault cases of the master and its files, each measured for real in fresh processes.

``CASES`` lists functions; each injects one fault, runs the ``agilesat`` command (or a
script) in a separate process and returns ``{"fault", "expected", "observed", "ok"}``.
``tests/orchestration/cosim/test_faults_master.py`` asserts every case;
``tests/tools/fault_matrix.py`` prints them.
A case that cannot run here (disk full needs root for a tmpfs) returns ``"skipped"``.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

from helpers import ROOT, agilesat

SYSTEMS = ROOT / "orchestration" / "systems"
SCAN_PITCH = SYSTEMS / "scan_pitch.ssd"
CLI = [sys.executable, "-m", "agilesat.orchestration"]


def _case(fault, expected, observed, ok, **extra):
    return {"fault": fault, "expected": expected, "observed": observed, "ok": bool(ok), **extra}


def _connection(a, x, b, y):
    return (
        f'<ssd:Connection startElement="{a}" startConnector="{x}" endElement="{b}" '
        f'endConnector="{y}"/>'
    )


def system_copy(directory: Path, edit=lambda text: text, source: Path = SCAN_PITCH) -> Path:
    """A copy of a shipped .ssd in directory (FMU sources made absolute), edited."""
    build = (SYSTEMS / "../../fmus/build").resolve()
    text = source.read_text().replace('source="../../fmus/build/', f'source="{build}/')
    path = Path(directory) / source.name
    path.write_text(edit(text))
    return path


def _summary(out: Path) -> dict:
    try:
        return json.loads((out / "summary.json").read_text())
    except (OSError, ValueError):
        return {}


def _csv_rows(path: Path) -> tuple[int, bool]:
    """(whole rows after the header, every line complete with the header's field count)."""
    text = path.read_text() if path.exists() else ""
    lines = text.split("\n")
    if not text.endswith("\n"):
        return len(lines) - 2, False
    fields = lines[0].count(",")
    body = lines[1:-1]
    return len(body), all(line.count(",") == fields for line in body)


def _refused(result, *said: str) -> bool:
    """The command exited 1 with each of ``said`` on stderr, and no traceback."""
    stderr = result.stderr
    return result.returncode == 1 and all(s in stderr for s in said) and "Traceback" not in stderr


def _stderr_line(result, key: str = "") -> str:
    """The first line of stderr holding key, else the last one."""
    lines = [line.strip() for line in result.stderr.splitlines() if line.strip()]
    chosen = [line for line in lines if key and key in line] or lines[-1:]
    return chosen[0][:160] if chosen else "(nothing on stderr)"


# ---------------------------------------------------------------------------------------
# silent wrong results


def unconnected_required_input():
    with tempfile.TemporaryDirectory() as tmp:
        path = system_copy(
            tmp,
            lambda s: s.replace(
                _connection("OrbitEnvironment", "q_OI[1]", "SatelliteDynamics", "q_OI[1]"), "", 1
            ),
        )
        result = agilesat("run", path, "--stop", "0.1", "--out", Path(tmp) / "out")
        ok = (
            result.returncode == 1
            and str(path) in result.stderr
            and "input SatelliteDynamics.q_OI is partly connected: q_OI[1] open" in result.stderr
            and not (Path(tmp) / "out" / "results.csv").exists()
        )
        return _case(
            "scan_pitch.ssd without the q_OI[1] connection",
            "exit 1 naming the file, SatelliteDynamics and q_OI; nothing run",
            f"exit {result.returncode}: {_stderr_line(result)}",
            ok,
        )


def unconnected_optional_input():
    with tempfile.TemporaryDirectory() as tmp:

        def edit(text):
            for i in (1, 2, 3):
                text = text.replace(
                    _connection(
                        "OrbitEnvironment", f"w_OI_O[{i}]", "SatelliteDynamics", f"w_OI_O[{i}]"
                    ),
                    "",
                    1,
                )
            return text

        out = Path(tmp) / "out"
        result = agilesat("run", system_copy(tmp, edit), "--stop", "0.2", "--out", out)
        listed = [
            e
            for e in _summary(out).get("unconnected_optional_inputs", [])
            if e["input"] == "SatelliteDynamics.w_OI_O"
        ]
        logged = (
            "input SatelliteDynamics.w_OI_O is not connected: zero: O does not rotate"
            in (out / "log.txt").read_text()
            if (out / "log.txt").exists()
            else False
        )
        ok = (
            result.returncode == 0 and listed and listed[0]["meaning"].startswith("zero") and logged
        )
        return _case(
            "scan_pitch.ssd without the three w_OI_O connections (optional input)",
            "runs; summary.json and log.txt list SatelliteDynamics.w_OI_O with "
            "'zero: O does not rotate'",
            f"exit {result.returncode}; listed {listed}; in log.txt: {logged}",
            ok,
        )


_SETTINGS_SCRIPT = """
import contextlib, io, json, sys
from agilesat.orchestration.cli import main
results = []
for option, value in json.loads(sys.argv[2]):
    stderr = io.StringIO()
    with contextlib.redirect_stderr(stderr):
        code = main(["run", sys.argv[1], option, value, "--out", sys.argv[3]])
    results.append((code, stderr.getvalue()))
print(json.dumps(results))
"""


def _bad_settings(settings: list[tuple[str, str, str]]) -> tuple[bool, str]:
    """Run `agilesat run` (its main(), in one fresh process) with each (option, value);
    each must exit 1 with its message."""
    with tempfile.TemporaryDirectory() as tmp:
        pairs = [(option, value) for option, value, _ in settings]
        result = subprocess.run(
            [
                sys.executable,
                "-c",
                _SETTINGS_SCRIPT,
                str(system_copy(tmp)),
                json.dumps(pairs),
                str(Path(tmp) / "out"),
            ],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=300,
        )
        outcomes = json.loads(result.stdout) if result.returncode == 0 else []
        ok = len(outcomes) == len(settings) and all(
            code == 1 and message in stderr and "Traceback" not in stderr
            for (code, stderr), (_, _, message) in zip(outcomes, settings)
        )
        observed = (
            "; ".join(f"{o} {v}: exit {code}" for (o, v), (code, _) in zip(pairs, outcomes))
            or f"script failed: {result.stderr[-300:]}"
        )
        return ok and not (Path(tmp) / "out" / "results.csv").exists(), observed


def step_zero():
    ok, observed = _bad_settings(
        [
            ("--step", "0", "the macro step must be a positive, finite"),
            ("--step", "-0.05", "the macro step must be a positive"),
        ]
    )
    return _case(
        "--step 0, --step -0.05",
        "exit 1: the macro step must be positive and finite; nothing run",
        observed,
        ok,
    )


def absurd_stop():
    ok, observed = _bad_settings(
        [
            ("--stop", "inf", "the stop time must be finite"),
            ("--stop", "nan", "the stop time must be finite"),
            ("--stop", "-1", "after the start"),
            ("--stop", "1e9", "more than the 10000000 a run may have"),
        ]
    )
    return _case(
        "--stop inf, nan, -1, 1e9",
        "exit 1 with a message for each (no traceback, no MemoryError); nothing run",
        observed,
        ok,
    )


def connector_unit():
    with tempfile.TemporaryDirectory() as tmp:
        old = '<ssd:Connector name="r_I[1]" kind="input">\n            <ssc:Real unit="m"/>'
        path = system_copy(tmp, lambda s: s.replace(old, old.replace('"m"', '"m/s"'), 1))
        result = agilesat("run", path, "--stop", "0.1", "--out", Path(tmp) / "out")
        ok = result.returncode == 1 and re.search(
            r"scan_pitch.ssd:\d+: connector SatelliteDynamics.r_I\[1\]: declared unit 'm/s', "
            "the FMU's variable has 'm'",
            result.stderr,
        )
        return _case(
            "SSD connector SatelliteDynamics.r_I[1] declared in m/s (FMU: m)",
            "exit 1 naming file, line, connector and both units",
            f"exit {result.returncode}: {_stderr_line(result)}",
            ok,
        )


# ---------------------------------------------------------------------------------------
# signals, kill -9, fatal


def _start_run(out: Path, *extra, env=None) -> subprocess.Popen:
    return subprocess.Popen(
        [*CLI, "run", "scan_pitch", "--out", str(out), "--no-figures", "--no-report", *extra],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def _wait_rows(out: Path, rows: int, process, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    csv = out / "results.csv"
    while time.monotonic() < deadline and process.poll() is None:
        if csv.exists() and csv.stat().st_size and _csv_rows(csv)[0] >= rows:
            return
        time.sleep(0.05)
    raise TimeoutError(f"{csv}: fewer than {rows} rows after {timeout} s")


def _interrupt(signum: int, tries: int) -> dict:
    """The signal at the progress report of macro step 30, 90, 150 ... of scan_pitch's
    3000 ($AGILESAT_TEST_SIGNAL: at that step, whatever the machine's load)."""
    observed, ok = [], True
    name = signal.Signals(signum).name
    for k in range(tries):
        at = 30 + 60 * k
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "out"
            process = _start_run(
                out, env={**os.environ, "AGILESAT_TEST_SIGNAL": f"{name}@step:{at}"}
            )
            _, stderr = process.communicate(timeout=120)
            rows, whole = _csv_rows(out / "results.csv")
            summary = _summary(out)
            try:
                npz_rows = np.load(out / "results.npz")["data"].shape[0]
            except (OSError, ValueError, KeyError):
                npz_rows = None
            good = (
                process.returncode == 128 + signum
                and whole
                and rows == at + 1
                and npz_rows == rows
                and summary.get("status") == "interrupted"
                and summary.get("rows") == rows
                and (out / "log.txt").exists()
                and "Traceback" not in stderr
            )
            ok &= good
            observed.append(
                f"at step {at}: exit {process.returncode}, {rows} rows (npz {npz_rows}), "
                f"status {summary.get('status')}"
            )
    return _case(
        f"{name} to `agilesat run scan_pitch` mid-run ({tries} tries)",
        f"exit {128 + signum}; results.csv (whole rows, up to the step of the signal), results.npz "
        "with the same rows, log.txt, summary.json status 'interrupted'; no traceback or "
        "segfault",
        "; ".join(observed),
        ok,
    )


def sigint(tries: int = 3):
    return _interrupt(signal.SIGINT, tries)


def sigterm(tries: int = 3):
    return _interrupt(signal.SIGTERM, tries)


def _cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def kill_9(step: int = 30000):
    """Rows reach the file as they are computed (sampled against the run's own CPU time,
    so that a busy machine does not matter), and kill -9 leaves only whole rows: the run
    (60,000 steps) kills itself at macro step ``step`` ($AGILESAT_TEST_SIGNAL, at a
    progress report: every row computed so far is written by then)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        hook = {"AGILESAT_TEST_SIGNAL": f"SIGKILL@step:{step}"}
        process = _start_run(out, "--stop", "3000", env={**os.environ, **hook})
        _wait_rows(out, 2, process)
        samples = []
        while process.poll() is None:
            rows = _csv_rows(out / "results.csv")[0]
            try:
                samples.append((_cpu_seconds(process.pid), rows))
            except OSError:  # gone between the poll and the read
                break
            time.sleep(0.01)
        process.communicate(timeout=60)
        rows, whole = _csv_rows(out / "results.csv")
        # the longest stretch of the run's CPU time during which no row was added
        stall, since = 0.0, samples[0]
        for cpu, count in samples[1:]:
            if count > since[1]:
                since = (cpu, count)
            stall = max(stall, cpu - since[0])
        times = np.loadtxt(out / "results.csv", delimiter=",", skiprows=1, usecols=0, ndmin=1)
        ok = (
            process.returncode == -signal.SIGKILL
            and whole
            and rows == step + 1
            and stall < 0.1
            and np.allclose(np.diff(times), 0.05)
        )
        return _case(
            f"kill -9 of a run at step {step} of 60,000; its CSV sampled every 10 ms before",
            "each row on disk once computed (no stretch of >= 0.1 s of the run's CPU time "
            "without a new row); after the kill whole rows only, every row up to the kill",
            f"exit {process.returncode}, {rows} whole rows after the kill (last sample "
            f"{samples[-1][1]}); longest stretch without a new row {stall:.2f} CPU-s; torn "
            f"row: {not whole}",
            ok,
        )


_STUB_C = r"""
#include <stdio.h>
#include <stdlib.h>
static int steps = 0;
static void note(const char *name) {
    FILE *f = fopen(getenv("STUB_CALLS"), "a"); fprintf(f, "%s\n", name); fclose(f);
}
#define CALL(name) int name() { note(#name); return 0; }
const char *fmi2GetTypesPlatform() { return "default"; }
const char *fmi2GetVersion() { return "2.0"; }
void *fmi2Instantiate() { note("fmi2Instantiate"); return malloc(1); }
void fmi2FreeInstance() { note("fmi2FreeInstance"); }
int fmi2DoStep() { note("fmi2DoStep"); return ++steps >= 3 ? 4 : 0; }
CALL(fmi2SetDebugLogging) CALL(fmi2SetupExperiment) CALL(fmi2EnterInitializationMode)
CALL(fmi2ExitInitializationMode) CALL(fmi2Terminate) CALL(fmi2Reset) CALL(fmi2GetReal)
CALL(fmi2GetInteger) CALL(fmi2GetBoolean) CALL(fmi2GetString) CALL(fmi2SetReal)
CALL(fmi2SetInteger) CALL(fmi2SetBoolean) CALL(fmi2SetString) CALL(fmi2GetFMUstate)
CALL(fmi2SetFMUstate) CALL(fmi2FreeFMUstate) CALL(fmi2SerializedFMUstateSize)
CALL(fmi2SerializeFMUstate) CALL(fmi2DeSerializeFMUstate) CALL(fmi2GetDirectionalDerivative)
CALL(fmi2SetRealInputDerivatives) CALL(fmi2GetRealOutputDerivatives) CALL(fmi2CancelStep)
CALL(fmi2GetStatus) CALL(fmi2GetRealStatus) CALL(fmi2GetIntegerStatus)
CALL(fmi2GetBooleanStatus) CALL(fmi2GetStringStatus)
"""
_STUB_MD = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="stub" guid="{0d2c6ad4-6c0e-4d5e-9a55-0c8f7d0e0001}"
    variableNamingConvention="structured" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="stub" canHandleVariableCommunicationStepSize="true"/>
  <ModelVariables>
    <ScalarVariable name="u" valueReference="0" causality="input" variability="continuous">
      <Real start="0.0"/></ScalarVariable>
    <ScalarVariable name="y" valueReference="1" causality="output" variability="continuous"
        initial="calculated"><Real/></ScalarVariable>
  </ModelVariables>
  <ModelStructure><Outputs><Unknown index="2" dependencies=""/></Outputs></ModelStructure>
</fmiModelDescription>
"""
_STUB_SSD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="1.0" name="stub">
  <ssd:System name="stub">
    <ssd:Elements>
      <ssd:Component name="Stub" source="stub.fmu" type="application/x-fmu-sharedlibrary"/>
    </ssd:Elements>
  </ssd:System>
  <ssd:DefaultExperiment startTime="0.0" stopTime="1.0"/>
</ssd:SystemStructureDescription>
"""


def stub_system(directory: Path) -> Path:
    """A system of one foreign FMU (no agilesat annotation): a C library that records every
    call it gets in $STUB_CALLS and returns fmi2Fatal from its third fmi2DoStep."""
    directory = Path(directory)
    (directory / "stub.c").write_text(_STUB_C)
    library = directory / "stub.so"
    subprocess.run(
        [
            os.environ.get("CC", "cc"),
            "-shared",
            "-fPIC",
            "-w",
            "-o",
            str(library),
            str(directory / "stub.c"),
        ],
        check=True,
    )
    with zipfile.ZipFile(directory / "stub.fmu", "w") as archive:
        archive.writestr("modelDescription.xml", _STUB_MD)
        archive.write(library, "binaries/linux64/stub.so")
    (directory / "stub.ssd").write_text(_STUB_SSD)
    return directory / "stub.ssd"


def fatal_then_nothing():
    with tempfile.TemporaryDirectory() as tmp:
        ssd, calls, out = stub_system(tmp), Path(tmp) / "calls.txt", Path(tmp) / "out"
        result = subprocess.run(
            [*CLI, "run", str(ssd), "--step", "0.1", "--out", str(out)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=120,
            env={**os.environ, "STUB_CALLS": str(calls)},
        )
        names = calls.read_text().split()
        after = names[len(names) - names[::-1].index("fmi2DoStep") :]
        rows, whole = _csv_rows(out / "results.csv")
        ok = (
            result.returncode == 1
            and "fmi2DoStep at t=0.2 s returned fmi2Fatal" in result.stderr
            and after == []
            and rows == 3
            and whole
            and _summary(out).get("status") == "error"
        )
        return _case(
            "a (foreign) FMU returns fmi2Fatal from fmi2DoStep at t=0.2 s",
            "no call at all on it afterwards (not even fmi2FreeInstance); exit 1 "
            "with the message; 3 rows kept; summary status 'error'",
            f"exit {result.returncode}; calls after the Fatal: {after}; {rows} rows",
            ok,
        )


def foreign_open_input():
    with tempfile.TemporaryDirectory() as tmp:
        ssd, out = stub_system(tmp), Path(tmp) / "out"
        result = subprocess.run(
            [*CLI, "run", str(ssd), "--step", "0.1", "--stop", "0.1", "--out", str(out)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=120,
            env={**os.environ, "STUB_CALLS": str(Path(tmp) / "c.txt")},
        )
        listed = _summary(out).get("unconnected_optional_inputs", [])
        ok = (
            result.returncode == 0
            and [e["input"] for e in listed] == ["Stub.u"]
            and not listed[0]["declared"]
            and "Stub.u is not connected" in result.stderr
        )
        return _case(
            "an FMU that is not ours (no annotation) with its input u left open",
            "runs; a warning on stderr and in log.txt; summary lists Stub.u as "
            "'keeps its start value 0.0'",
            f"exit {result.returncode}; listed {[e['input'] for e in listed]}",
            ok,
        )


# ---------------------------------------------------------------------------------------
# files: disk full, parallel builds, .ssp packages


def disk_full():
    if os.geteuid() != 0:
        return _case(
            "disk full while writing results",
            "(needs root for a small tmpfs)",
            "not run: not root",
            False,
            skipped="needs root to mount a tmpfs",
        )
    with tempfile.TemporaryDirectory() as tmp:
        mount = Path(tmp) / "small"
        mount.mkdir()
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(mount)], check=True)
        try:
            out = mount / "out"
            result = agilesat(
                "run", "scan_pitch", "--stop", "30", "--out", out, "--no-figures", "--no-report"
            )
            rows, whole = _csv_rows(out / "results.csv")
            leftovers = [
                p.name
                for p in out.iterdir()
                if p.name not in ("results.csv", "results.npz", "log.txt", "summary.json")
            ]
            npz_ok = (
                not (out / "results.npz").exists()
                or np.load(out / "results.npz")["data"].shape[0] == rows
            )
            ok = (
                result.returncode == 1
                and f"{out / 'results.csv'}: No space left on device" in result.stderr
                and whole
                and rows > 10
                and not leftovers
                and npz_ok
                and "Traceback" not in result.stderr
            )
            return _case(
                "disk full (200 KiB tmpfs) while writing results.csv",
                "exit 1 naming results.csv; every complete row kept, no torn row; "
                "no half-written results.npz or temporary files",
                f"exit {result.returncode}: {_stderr_line(result, 'results.csv')}; "
                f"{rows} whole rows, torn: {not whole}, leftovers {leftovers}",
                ok,
            )
        finally:
            subprocess.run(["umount", str(mount)], check=True)


def parallel_builds(tries: int = 3):
    observed, ok = [], True
    for _ in range(tries):
        with tempfile.TemporaryDirectory() as tmp:
            commands = [
                [*CLI, "build", "--force"],
                [*CLI, "build", "--force"],
                [
                    *CLI,
                    "run",
                    "scan_pitch",
                    "--stop",
                    "1",
                    "--no-figures",
                    "--no-report",
                    "--out",
                    str(Path(tmp) / "out"),
                ],
            ]
            processes = [
                subprocess.Popen(
                    c, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
                )
                for c in commands
            ]
            codes = [(p.wait(timeout=600), p.stderr.read()) for p in processes]
            ok &= all(code == 0 for code, _ in codes)
            observed.append("exits " + ",".join(str(code) for code, _ in codes))
    leftovers = list((ROOT / "fmus" / "build").glob("**/*.partial"))
    ok &= not leftovers
    return _case(
        f"two `agilesat build --force` and a run at once on one tree ({tries} tries)",
        "all exit 0, no .partial files left",
        "; ".join(observed) + f"; leftovers {len(leftovers)}",
        ok,
    )


def _ssp(path: Path, members: dict[str, bytes]) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return path


def ssp_packages():
    """Bombs, escapes and non-zips: each refused with a message, nothing unpacked."""
    ssd = SCAN_PITCH.read_text()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        checks = {
            "unpacks past the limit": (
                _ssp(
                    tmp / "bomb.ssp",
                    {"SystemStructure.ssd": ssd.encode(), "resources/zeros": bytes(2 << 20)},
                ),
                {"AGILESAT_SSP_MAX_BYTES": str(1 << 20)},
                "more than the limit of 1048576",
            ),
            "member '../x'": (
                _ssp(tmp / "dotdot.ssp", {"SystemStructure.ssd": ssd.encode(), "../x": b"x"}),
                {},
                "member '../x' would unpack outside the package",
            ),
            "FMU source outside": (
                _ssp(tmp / "outside.ssp", {"SystemStructure.ssd": ssd.encode()}),
                {},
                "resolves outside the package",
            ),
            "not a zip": ((tmp / "text.ssp"), {}, "not an SSP package (zip)"),
        }
        (tmp / "text.ssp").write_text("hello")
        (tmp / "bad.fmu").write_text("not a zip")
        bad_fmu = system_copy(
            tmp, lambda s: re.sub(r'source="[^"]*CmgCluster.fmu"', f'source="{tmp / "bad.fmu"}"', s)
        )
        checks["FMU source not a zip"] = (bad_fmu, {}, "is not a readable FMU")
        observed, ok = [], True
        for label, (path, env, message) in checks.items():
            result = subprocess.run(
                [*CLI, "run", str(path), "--stop", "0.1", "--out", str(tmp / "out")],
                cwd=ROOT,
                capture_output=True,
                text=True,
                timeout=120,
                env={**os.environ, **env},
            )
            good = (
                result.returncode == 1
                and message in result.stderr
                and "Traceback" not in result.stderr
            )
            ok &= good
            observed.append(f"{label}: exit {result.returncode}{'' if good else ' (!)'}")
        return _case(
            ".ssp: 2 MiB member over a 1 MiB limit, member '../x', FMU source "
            "outside the package, a text file as .ssp, a text file as FMU",
            "exit 1 with a message each, no traceback",
            "; ".join(observed),
            ok,
        )


# ---------------------------------------------------------------------------------------
# resource figures


def _peak_rss(command, seconds: float | None = None) -> tuple[float, int]:
    """(peak resident memory in MB, exit status) of a command; with seconds, it is
    interrupted (SIGINT) after that long."""
    process = subprocess.Popen(
        command, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    if seconds is not None:
        time.sleep(seconds)
        process.send_signal(signal.SIGINT)
    _, status, usage = os.wait4(process.pid, 0)
    process.returncode = os.waitstatus_to_exitcode(status)
    return usage.ru_maxrss / 1024, process.returncode


def _row_cost(rows: int = 2000, columns: int = 76) -> tuple[float, float]:
    """Microseconds per row: the recorder (one os.write per row) and the same text written
    100 rows at a time, measured one after the other on the same data."""
    from agilesat.orchestration.output.recorder import Recorder

    data = np.random.default_rng(0).random((rows, columns))
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        rec = Recorder([f"c{i}" for i in range(columns)], tmp)
        for row in data:
            rec.append(row)
        each = time.perf_counter() - start
        rec.close({})
        start = time.perf_counter()
        with (
            open(Path(tmp) / "batched.csv", "w") as stream,
            open(Path(tmp) / "batched.f64", "wb") as raw,
        ):
            for k in range(0, rows, 100):
                block = data[k : k + 100]
                raw.write(block.tobytes())
                stream.write("".join(",".join(map(repr, r)) + "\n" for r in block.tolist()))
        batched = time.perf_counter() - start
    return each / rows * 1e6, batched / rows * 1e6


def resource_figures(n: int) -> list[tuple[str, str]]:
    """(figure, value): memory of runs n/10 and n macro steps long and of a 4,000,000-step
    run 20 s in, and the cost of writing every row at once."""
    figures = []
    with tempfile.TemporaryDirectory() as tmp:
        for steps in (n // 10, n):
            rss, code = _peak_rss(
                [
                    *CLI,
                    "run",
                    str(SCAN_PITCH),
                    "--stop",
                    str(steps * 0.05),
                    "--out",
                    str(Path(tmp) / f"o{steps}"),
                ]
            )
            figures.append(
                (
                    f"peak RSS, `agilesat run scan_pitch.ssd --stop {steps * 0.05:g}` "
                    f"({steps} steps, exit {code})",
                    f"{rss:.0f} MB",
                )
            )
        rss, code = _peak_rss(
            [*CLI, "run", str(SCAN_PITCH), "--stop", "2e5", "--out", str(Path(tmp) / "long")],
            seconds=20,
        )
        figures.append(
            (
                "peak RSS, `agilesat run scan_pitch.ssd --stop 2e5` (4,000,000 steps) "
                f"20 s in, then Ctrl-C (exit {code})",
                f"{rss:.0f} MB",
            )
        )
    each, batched = _row_cost()
    figures.append(
        (
            "writing a row of 76 columns (CSV + raw): each row at once / 100 rows at a time",
            f"{each:.0f} µs / {batched:.0f} µs per row",
        )
    )
    return figures


CASES = [
    unconnected_required_input,
    unconnected_optional_input,
    step_zero,
    absurd_stop,
    connector_unit,
    sigint,
    sigterm,
    kill_9,
    fatal_then_nothing,
    foreign_open_input,
    disk_full,
    parallel_builds,
    ssp_packages,
]
