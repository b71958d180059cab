"""Fault cases of what a run is given: ``--set`` values, system files and packages, each
measured in fresh processes (``CASES``, as in ``fault_cases_master``)."""

from __future__ import annotations

import os
import re
import subprocess
import tempfile
import zipfile
from pathlib import Path

from fault_cases_master import CLI, SCAN_PITCH, _case, _refused, _stderr_line, system_copy

from helpers import ROOT

#: a system of one Gyro, its input bound to a constant: an Integer parameter (seed) to set
_GYRO_SSD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="1.0" name="gyro">
  <ssd:System name="gyro">
    <ssd:Elements>
      <ssd:Component name="Gyro" source="{source}" type="application/x-fmu-sharedlibrary">
        <ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues>
          <ssv:ParameterSet version="1.0" name="gyro"><ssv:Parameters>
            <ssv:Parameter name="w_BI_B[1]"><ssv:Real value="0.01"/></ssv:Parameter>
            <ssv:Parameter name="w_BI_B[2]"><ssv:Real value="0.0"/></ssv:Parameter>
            <ssv:Parameter name="w_BI_B[3]"><ssv:Real value="0.0"/></ssv:Parameter>{extra}
          </ssv:Parameters></ssv:ParameterSet>
        </ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings>
      </ssd:Component>
    </ssd:Elements>
  </ssd:System>
  <ssd:DefaultExperiment startTime="0.0" stopTime="0.5">
    <ssd:Annotations><ssc:Annotation type="org.agilesat.master">
      <agilesat:Master xmlns:agilesat="http://agilesat.org/ssp/master" stepSize="0.05"/>
    </ssc:Annotation></ssd:Annotations>
  </ssd:DefaultExperiment>
</ssd:SystemStructureDescription>
"""


def gyro_system(directory: Path, extra: str = "") -> Path:
    path = Path(directory) / "gyro.ssd"
    source = (ROOT / "fmus" / "build" / "Gyro.fmu").resolve()
    path.write_text(_GYRO_SSD.format(source=source, extra=extra))
    return path


def _run(path, *extra, env=None, out=None):
    with tempfile.TemporaryDirectory() as tmp:
        return subprocess.run(
            [*CLI, "run", str(path), "--stop", "0.5", "--no-figures", "--no-report"]
            + ["--out", str(out or Path(tmp) / "out"), *map(str, extra)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=600,
            env={**os.environ, **(env or {})},
        )


def set_values():
    """Each value in a fresh `agilesat run`: exit 1, the message naming the parameter and
    what it takes, nothing run."""
    with tempfile.TemporaryDirectory() as tmp:
        scan, gyro = system_copy(tmp), gyro_system(tmp)
        trials = [
            (scan, "SatelliteDynamics.gravity_gradient=flase", "expected a Boolean"),
            (scan, "SatelliteDynamics.gravity_gradient=2", "expected a Boolean"),
            (scan, "SatelliteDynamics.gravity_gradient=on", "expected a Boolean"),
            (scan, "OrbitEnvironment.j2=maybe", "expected a Boolean"),
            (scan, "SatelliteDynamics.rate0[1]=1_000", "expected a finite Real"),
            (scan, "SatelliteDynamics.mu=inf", "expected a finite Real"),
            (gyro, "Gyro.seed=4294967296", "expected an Integer from -2147483648"),
            (gyro, "Gyro.seed=-2147483649", "expected an Integer from -2147483648"),
            (gyro, "Gyro.seed=1_000", "expected an Integer"),
        ]
        observed, ok = [], True
        for system, setting, message in trials:
            result = _run(system, "--set", setting, out=Path(tmp) / "out")
            key = setting.partition("=")[0]
            good = (
                result.returncode == 1
                and message in result.stderr
                and key in result.stderr
                and "Traceback" not in result.stderr
                and not (Path(tmp) / "out" / "results.csv").exists()
            )
            ok &= good
            observed.append(f"{setting}: exit {result.returncode}" + ("" if good else " (!)"))
        return _case(
            "--set SatelliteDynamics.gravity_gradient=flase, =2, =on, OrbitEnvironment.j2=maybe, "
            "SatelliteDynamics.rate0[1]=1_000, SatelliteDynamics.mu=inf; a Gyro's "
            "seed=4294967296, =-2147483649, =1_000",
            "exit 1 each, naming the parameter and what it takes (true/false/1/0; a finite "
            "Real; an Integer of fmi2Integer's 32 bits); nothing run",
            "; ".join(observed),
            ok,
        )


def bound_twice():
    with tempfile.TemporaryDirectory() as tmp:
        path = gyro_system(
            tmp,
            '\n            <ssv:Parameter name="seed"><ssv:Integer value="3"/></ssv:Parameter>'
            '\n            <ssv:Parameter name="seed"><ssv:Integer value="4"/></ssv:Parameter>',
        )
        result = _run(path)
        ok = result.returncode == 1 and re.search(
            r"gyro.ssd:\d+: parameter 'seed' is bound twice in one parameter set \(first at "
            r"line \d+\)",
            result.stderr,
        )
        return _case(
            "a parameter set binding Gyro.seed twice (3, then 4)",
            "exit 1 naming the file, the line of each binding and the parameter",
            f"exit {result.returncode}: {_stderr_line(result, 'seed')}",
            ok,
        )


def annotation_step():
    with tempfile.TemporaryDirectory() as tmp:
        path = system_copy(
            tmp, lambda s: re.sub(r'(<agilesat:Master[^>]*stepSize=)"[^"]*"', r'\1"abc"', s)
        )
        result = _run(path)
        ok = (
            result.returncode == 1
            and re.search(
                r"scan_pitch.ssd:\d+: the org.agilesat.master annotation's stepSize "
                "is 'abc'",
                result.stderr,
            )
            and "Traceback" not in result.stderr
        )
        return _case(
            'the master annotation of scan_pitch.ssd with stepSize="abc"',
            "exit 1 naming the file, the line, stepSize and what it takes; no traceback",
            f"exit {result.returncode}: {_stderr_line(result, 'stepSize')}",
            ok,
        )


def switch_value():
    result = _run(SCAN_PITCH, env={"AGILESAT_JIT_AFTER": "soon"})
    lines = result.stderr.strip().splitlines()
    ok = (
        result.returncode == 1
        and len(lines) == 1
        and "AGILESAT_JIT_AFTER='soon': expected a whole number" in lines[0]
    )
    return _case(
        "AGILESAT_JIT_AFTER=soon",
        "exit 1 with one line naming the variable and what it takes",
        f"exit {result.returncode}: {_stderr_line(result)}",
        ok,
    )


def duplicate_connections(copies: int = 50_000):
    """``copies`` more of one connection (the issue's 600,000 printed 106 MB)."""
    with tempfile.TemporaryDirectory() as tmp:
        line = re.search(r"\n(\s*<ssd:Connection [^\n]*/>)", SCAN_PITCH.read_text()).group(1)
        path = system_copy(tmp, lambda s: s.replace(line, line * (copies + 1), 1))
        result = _run(path)
        ok = (
            result.returncode == 1
            and len(result.stderr) < 20_000
            and f"... and {copies - 20} more" in result.stderr
            and "is already driven by" in result.stderr
        )
        return _case(
            f"scan_pitch.ssd with {copies:,} copies of one connection",
            "exit 1, the first problems and how many more: a bounded report",
            f"exit {result.returncode}, {len(result.stderr):,} bytes of stderr in "
            f"{result.stderr.count(chr(10)):,} lines",
            ok,
        )


def _export(path: Path) -> None:
    """scan_pitch exported as an .ssp package to ``path``."""
    export = subprocess.run(
        [*CLI, "export", "scan_pitch", "--out", str(path)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert export.returncode == 0, export.stderr


def ssp_nested_fmu(padding: int = 64 << 20, limit: int = 32 << 20):
    """An exported scan_pitch package whose CmgCluster.fmu carries ``padding`` zero bytes
    (a few kB packed), run with a limit of ``limit`` bytes on a fresh cache."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        _export(tmp / "clean.ssp")
        with zipfile.ZipFile(tmp / "clean.ssp") as package:
            members = {i.filename: package.read(i) for i in package.infolist()}
        name = next(n for n in members if n.endswith("CmgCluster.fmu"))
        with zipfile.ZipFile(tmp / "CmgCluster.fmu", "w", zipfile.ZIP_DEFLATED) as fmu:
            with zipfile.ZipFile(tmp / "clean.ssp") as package, package.open(name) as inner:
                with zipfile.ZipFile(inner) as original:
                    for info in original.infolist():
                        fmu.writestr(info, original.read(info))
            fmu.writestr("resources/padding.bin", bytes(padding))
        members[name] = (tmp / "CmgCluster.fmu").read_bytes()
        with zipfile.ZipFile(tmp / "bomb.ssp", "w", zipfile.ZIP_DEFLATED) as package:
            for member, data in members.items():
                package.writestr(member, data)
        cache = tmp / "cache"
        result = _run(
            tmp / "bomb.ssp",
            env={"AGILESAT_SSP_MAX_BYTES": str(limit), "AGILESAT_CACHE_DIR": str(cache)},
        )
        grown = sum(p.stat().st_size for p in cache.rglob("*") if p.is_file())
        ok = (
            result.returncode == 1
            and f"more than the limit of {limit} bytes" in result.stderr
            and "CmgCluster.fmu" in result.stderr
            and grown < 1 << 20
        )
        return _case(
            f"an exported scan_pitch .ssp ({(tmp / 'bomb.ssp').stat().st_size >> 10} KiB) whose "
            f"CmgCluster.fmu unpacks to {padding >> 20} MiB more, under a limit of "
            f"{limit >> 20} MiB",
            "exit 1: the limit covers what the FMUs inside unpack to, naming the FMU; "
            "nothing unpacked into the cache",
            f"exit {result.returncode}: {_stderr_line(result, 'limit')}; the cache grew by "
            f"{grown >> 10} KiB",
            ok,
        )


def _fmu_copy(directory: Path, name: str, edit) -> Path:
    """Gyro.fmu copied to ``name`` with its modelDescription.xml edited (``edit(bytes)``)."""
    path = Path(directory) / name
    with zipfile.ZipFile(ROOT / "fmus" / "build" / "Gyro.fmu") as source:
        with zipfile.ZipFile(path, "w") as copy:
            for info in source.infolist():
                data = source.read(info)
                copy.writestr(
                    info.filename, edit(data) if info.filename == "modelDescription.xml" else data
                )
    return path


def bad_fmu_files():
    """`agilesat run X.fmu` on files that are no FMI 2.0 FMU this toolkit runs."""
    gyro = (ROOT / "fmus" / "build" / "Gyro.fmu").read_bytes()
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "text.fmu").write_text("hello\n")
        (Path(tmp) / "cut.fmu").write_bytes(gyro[: len(gyro) // 2])
        trials = {
            "a text file": (Path(tmp) / "text.fmu", "not an FMU"),
            "a zip cut in half": (Path(tmp) / "cut.fmu", "not an FMU"),
            "a model description cut in half": (
                _fmu_copy(tmp, "cutmd.fmu", lambda data: data[: len(data) // 2]),
                "its modelDescription.xml is not XML",
            ),
            "an FMI 3.0 FMU": (
                _fmu_copy(
                    tmp,
                    "fmi3.fmu",
                    lambda data: data.replace(b'fmiVersion="2.0"', b'fmiVersion="3.0"'),
                ),
                "an FMU of FMI 3.0: agilesat runs FMI 2.0",
            ),
        }
        observed, ok = [], True
        for label, (path, message) in trials.items():
            result = _run(path, "--step", "0.05")
            good = _refused(result, f"{path}: {message}")
            ok &= good
            observed.append(
                f"{label}: exit {result.returncode}: {_stderr_line(result, 'error')}"
                + ("" if good else " (!)")
            )
    return _case(
        "`agilesat run X.fmu` of a text file, a zip cut in half, an FMU whose "
        "modelDescription.xml is cut in half, an FMI 3.0 FMU",
        "exit 1 each with a message naming the file and what it is not; no library traceback",
        "; ".join(observed),
        ok,
    )


def aliases():
    """A Gyro.fmu whose model description gives rrw the value reference of arw (aliases,
    FMI 2.0 section 2.2.7), both set."""
    with tempfile.TemporaryDirectory() as tmp:
        path = _fmu_copy(
            tmp,
            "Gyro.fmu",
            lambda data: data.replace(
                b'name="rrw" valueReference="1"', b'name="rrw" valueReference="0"'
            ),
        )
        result = _run(path, "--step", "0.05", "--set", "Gyro.arw=1e-5", "--set", "Gyro.rrw=2e-8")
        ok = (
            result.returncode == 1
            and "Gyro.rrw=2e-08 and arw=1e-05" in result.stderr
            and "value reference 0" in result.stderr
        )
        return _case(
            "an FMU declaring two parameters at one value reference (arw and rrw: aliases), "
            "`--set` to two values",
            "exit 1 naming both parameters, their values and the value reference; nothing run",
            f"exit {result.returncode}: {_stderr_line(result, 'value reference')}",
            ok,
        )


def integer_beyond_32_bits():
    with tempfile.TemporaryDirectory() as tmp:
        path = gyro_system(
            tmp,
            '\n            <ssv:Parameter name="seed">'
            '<ssv:Integer value="4294967296"/></ssv:Parameter>',
        )
        result = _run(path)
        ok = result.returncode == 1 and re.search(
            r"gyro.ssd:\d+: .*bad Integer value '4294967296': an Integer is from -2147483648",
            result.stderr,
        )
        return _case(
            '<ssv:Integer value="4294967296"/> for Gyro.seed in an .ssd',
            "exit 1 naming the file, the line and the range of fmi2Integer (it wrapped to 0 "
            "and ran)",
            f"exit {result.returncode}: {_stderr_line(result, 'Integer')}",
            ok,
        )


def impossible_bodies():
    with tempfile.TemporaryDirectory() as tmp:
        scan = system_copy(tmp)
        trials = [
            (
                "SatelliteDynamics.inertia=[[100,0,0],[0,100,0],[0,0,300]]",
                "SatelliteDynamics 'SatelliteDynamics'",
                "no rigid body has it",
            ),
            (
                "OrbitEnvironment.semi_major_axis=6000000",
                "OrbitEnvironment 'OrbitEnvironment'",
                "the orbit passes inside the Earth",
            ),
        ]
        observed, ok = [], True
        for setting, who, message in trials:
            result = _run(scan, "--set", setting, out=Path(tmp) / "out")
            good = result.returncode == 1 and who in result.stderr and message in result.stderr
            ok &= good
            observed.append(f"{setting}: exit {result.returncode}" + ("" if good else " (!)"))
        return _case(
            "--set SatelliteDynamics.inertia=[[100,0,0],[0,100,0],[0,0,300]] (300 > 100 + "
            "100), OrbitEnvironment.semi_major_axis=6000000 (a circular orbit 378 km inside "
            "the Earth)",
            "exit 1 each, the FMU naming what is impossible (the triangle inequality of "
            "principal moments; the perigee below the Earth's polar radius)",
            "; ".join(observed),
            ok,
        )


def ssp_members(extra: int = 20_000):
    """An exported scan_pitch package with ``extra`` empty members more."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        _export(tmp / "clean.ssp")
        with zipfile.ZipFile(tmp / "clean.ssp", "a") as package:
            for k in range(extra):
                package.writestr(f"resources/empty{k}", b"")
            members = len(package.infolist())
        result = _run(tmp / "clean.ssp")
        ok = result.returncode == 1 and f"a zip archive of {members} members" in result.stderr
        return _case(
            f"an exported scan_pitch .ssp with {extra} empty members more",
            "exit 1 before unpacking, naming the package, its member count and the most it may "
            "have (10,000)",
            f"exit {result.returncode}: {_stderr_line(result, 'members')}",
            ok,
        )


def estimator_history():
    """scan_pitch:sensed with the estimator's history at 2·10^4 s (it took 3.3 GB and over
    three minutes for 20 steps), held to 3 GiB of address space."""
    from fault_cases_campaign import _bounded

    with tempfile.TemporaryDirectory() as tmp:
        command = [*CLI, "run", "scan_pitch:sensed", "--stop", "0.5", "--no-figures", "-q"]
        command += ["--no-report"]
        command += ["--set", "AttitudeEstimator.history=20000", "--out", str(Path(tmp) / "out")]
        code, seconds, rss, stderr = _bounded(command, Path(tmp) / "err", 600)
        ok = (
            code == 1
            and "history 20000 s at rate 20 Hz is 400005 filter records, more than the 10000"
            in stderr
            and "MemoryError" not in stderr
        )
        said = [line for line in stderr.splitlines() if "history" in line][:1] or [stderr[-160:]]
        return _case(
            "`agilesat run scan_pitch:sensed --set AttitudeEstimator.history=20000`",
            "exit 1 at initialisation naming the estimator, its history, the records it would "
            "take and the most it keeps; no MemoryError",
            f"exit {code} after {seconds:.1f} s, peak {rss:.0f} MB: {said[0].strip()[:200]}",
            ok,
        )


CASES = [
    set_values,
    bound_twice,
    annotation_step,
    switch_value,
    duplicate_connections,
    ssp_nested_fmu,
    bad_fmu_files,
    aliases,
    integer_beyond_32_bits,
    impossible_bodies,
    ssp_members,
    estimator_history,
]
