"""Fault cases of a mission of a user's own (docs/own-mission.md): what its file does at
import, what its values and requirements say, what its metrics give, and the pytest
plugin's failures.  Each measured in fresh processes (``CASES``, as in
``fault_cases_master``)."""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np
from fault_cases_master import CLI, _case, _refused, _stderr_line

#: a mission of one SatelliteDynamics, 1 s at 0.1 s; {lines}: the scenario's own
MISSION = """
import math
from agilesat.orchestration.mission import Metric, Scenario, System, at_most, within
from agilesat.orchestration.mission import metrics as m

SYSTEM = System("probe", step=0.1, stop=1.0)
SYSTEM.add("SatelliteDynamics", rate0=[0.02, -0.01, 0.005])
{lines}
"""


def _mission(directory, lines: str, name: str = "mission.py") -> Path:
    path = Path(directory) / name
    path.write_text(MISSION.format(lines=textwrap.dedent(lines)))
    return path


def _run(path: Path, out: Path, *extra):
    return subprocess.run(
        [*CLI, "run", str(path), "--no-figures", "--no-report", "-q", "--out", str(out), *extra],
        cwd=path.parent,
        capture_output=True,
        text=True,
        timeout=600,
    )


def _line(path: Path, text: str) -> int:
    return next(k for k, line in enumerate(path.read_text().splitlines(), 1) if text in line)


def import_faults():
    """A mission file that calls sys.exit(0), and one that raises, as they are imported."""
    with tempfile.TemporaryDirectory() as tmp:
        exits = _mission(tmp, "import sys\nsys.exit(0)", "exits.py")
        raises = _mission(tmp, "SCENARIO = Scenario('probe', 'p', SYSTM)", "raises.py")
        trials = {
            "sys.exit(0) at import": (
                exits,
                "called sys.exit(0), so it defines no scenario to run",
            ),
            "a NameError at import": (
                raises,
                f"raised NameError: name 'SYSTM' is not defined (line {_line(raises, 'SYSTM')}:",
            ),
        }
        observed, ok = [], True
        for label, (path, message) in trials.items():
            result = _run(path, Path(tmp) / "out")
            good = _refused(result, f"{path}: importing it {message}")
            ok &= good
            observed.append(
                f"{label}: exit {result.returncode}: {_stderr_line(result, 'error')}"
                + ("" if good else " (!)")
            )
        return _case(
            "`agilesat run mission.py` of a mission file that calls sys.exit(0), and of one "
            "with a NameError, at import",
            "exit 1 each naming the file (and the line): no scenario to run (not exit 0 with "
            "nothing run), no traceback",
            "; ".join(observed),
            ok,
        )


def value_messages():
    """Mission values of the wrong type or unit, and requirements no value can meet."""
    with tempfile.TemporaryDirectory() as tmp:
        trials = {
            'SYSTEM.set("SatelliteDynamics.gravity_gradient", "1 deg")': (
                "SatelliteDynamics.gravity_gradient=1 deg: expected a Boolean"
            ),
            'SYSTEM.set("SatelliteDynamics.mu", "5 kg")': (
                "SatelliteDynamics.mu=5 kg: expected a finite Real number (like 0.01 or 1e-3), "
                "or one with a unit: unit mismatch: 5.0 kg is [kg]"
            ),
            'm.max_abs("SatelliteDynamics.w_BI_B", require=within(5, 1))': (
                "a bound in [5, 1]: its lower end is above its upper end"
            ),
            'm.max_abs("SatelliteDynamics.w_BI_B", require=at_most(math.nan))': (
                "a bound's max must be a finite number"
            ),
        }
        observed, ok = [], True
        for k, (line, message) in enumerate(trials.items()):
            scenario = "SCENARIO = Scenario('probe', 'p', SYSTEM, metrics=[{}])"
            code = line if line.startswith("SYSTEM") else ""
            metric = "" if code else line
            path = _mission(tmp, f"{code}\n" + scenario.format(metric or "Metric('w', len)"))
            result = _run(path, Path(tmp) / f"out{k}")
            n = _line(path, line)
            where = f"{path}:{n}" in result.stderr or f"(line {n}:" in result.stderr
            good = _refused(result, message) and where and "is no unit" not in result.stderr
            ok &= good
            observed.append(
                f"{line}: exit {result.returncode}: {_stderr_line(result, message[:12])}"
                + ("" if good else " (!)")
            )
        return _case(
            "a mission setting SatelliteDynamics.gravity_gradient to '1 deg' and mu to '5 kg'; "
            "requirements within(5, 1) and at_most(nan)",
            "exit 1 each naming the file and line, the parameter and its value, and what it "
            "takes (a Boolean; a Real, the units mu converts from: not \"'kg' is no unit\"); "
            "a bound no value meets refused; nothing run",
            "; ".join(observed),
            ok,
        )


def infinite_metric():
    """A mission metric that gives inf."""
    with tempfile.TemporaryDirectory() as tmp:
        path = _mission(
            tmp,
            """
            SCENARIO = Scenario(
                "probe", "p", SYSTEM, metrics=[Metric("blows_up", lambda results: math.inf)]
            )
            """,
        )
        out = Path(tmp) / "out"
        result = _run(path, out)

        def strict(constant):
            raise ValueError(f"{constant} is no JSON")

        try:
            summary = json.loads((out / "summary.json").read_text(), parse_constant=strict)
            metric = summary["metrics"]["blows_up"]
        except (OSError, ValueError, KeyError) as exc:
            summary, metric = None, {"error": str(exc)}
        ok = (
            result.returncode == 0
            and summary is not None
            and metric.get("value") is None
            and "inf" in metric.get("reason", "")
        )
        return _case(
            "a mission metric that gives inf (`Metric('blows_up', lambda results: math.inf)`)",
            "summary.json is JSON (no Infinity): the metric has no value (null) and its reason "
            "says it was not a finite number",
            f"exit {result.returncode}; blows_up: {metric}",
            ok,
        )


def settling_norm(bound: float = 0.015):
    """settling_time of a coasting body's w_BI_B = (0.01, 0.01, 0.01) rad/s (each axis
    inside the bound, the norm 0.0173 rad/s outside), per axis and of its norm, against
    the same read from the run's results.csv."""
    from agilesat.orchestration.output.results import Results

    with tempfile.TemporaryDirectory() as tmp:
        path = _mission(
            tmp,
            f"""
            SCENARIO = Scenario(
                "probe",
                "p",
                SYSTEM,
                metrics=[
                    m.settling_time("SatelliteDynamics.w_BI_B", {bound}, name="axes"),
                    m.settling_time(
                        "SatelliteDynamics.w_BI_B", {bound}, norm=True, name="norm"
                    ),
                ],
            )
            """,
        )
        out = Path(tmp) / "out"
        result = _run(path, out, "--set", "SatelliteDynamics.rate0=[0.01, 0.01, 0.01]")
        try:
            metrics = json.loads((out / "summary.json").read_text())["metrics"]
            got = {k: metrics[k].get("value", metrics[k].get("reason")) for k in ("axes", "norm")}
            got = {k: metrics[k]["reason"] if v is None else v for k, v in got.items()}
        except (OSError, ValueError, KeyError) as exc:
            got = {"error": str(exc)}
        expected = {}
        if (out / "results.csv").exists():
            results = Results.from_csv(out / "results.csv")
            w = results["SatelliteDynamics.w_BI_B"].reshape(len(results.time), 3)
            for name, size in (("axes", np.abs(w)), ("norm", np.linalg.norm(w, axis=1)[:, None])):
                outside = np.flatnonzero((size > bound).any(axis=1))
                if not len(outside):
                    expected[name] = float(results.time[0])
                elif outside[-1] == len(w) - 1:
                    expected[name] = "not settled"
                else:
                    expected[name] = float(results.time[outside[-1] + 1])
        ok = (
            result.returncode == 0
            and len(expected) == 2
            and expected["axes"] != expected["norm"]
            and all(
                str(got.get(k)).startswith(v) if isinstance(v, str) else got.get(k) == v
                for k, v in expected.items()
            )
        )
        return _case(
            f"settling_time within {bound} rad/s of a body coasting at w_BI_B = (0.01, 0.01, "
            "0.01) rad/s: per axis, and of the vector's norm (norm=True)",
            "per axis: settled from the start (each |w_i| ≤ bound); of the norm: not settled "
            "(‖w‖ = 0.0173 rad/s), each as results.csv says",
            f"exit {result.returncode}; summary {got}; from results.csv {expected}",
            ok,
        )


PLUGIN_TEST = """
from agilesat.orchestration import assert_requirements_met, assert_within


def test_requirement(agilesat_run):
    _, summary = agilesat_run("scan_pitch", stop=20.0)
    assert_requirements_met(summary)


def test_signal(agilesat_run):
    results, _ = agilesat_run("scan_pitch", stop=20.0)
    assert_within(results, "SatelliteDynamics.w_BO_B", high=1e-6)


def test_run(agilesat_run):
    agilesat_run("scan_pitch", stop=0.1, parameters={"SatelliteDynamics.mu": "5 kg"})
"""


def plugin_failures():
    """A user's pytest file whose three tests fail: a requirement not shown met (the run
    too short to evaluate it), a signal out of bounds, a run refused."""
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "test_mission.py").write_text(PLUGIN_TEST)
        result = subprocess.run(
            [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_mission.py"],
            cwd=tmp,
            capture_output=True,
            text=True,
            timeout=600,
        )
        ours = [
            line
            for line in result.stdout.splitlines()
            if "orchestration/output/" in line or "__tracebackhide__" in line or "raise " in line
        ]
        ok = (
            result.returncode == 1
            and "3 failed" in result.stdout
            and "requirement not evaluated: imaging_pitch_rate_mean" in result.stdout
            and "SatelliteDynamics.w_BO_B is above" in result.stdout
            and "agilesat_run('scan_pitch'): --set SatelliteDynamics.mu=5 kg" in result.stdout
            and not ours
        )
        return _case(
            "a user's pytest file with the agilesat plugin: a requirement not evaluated (the "
            "run too short), a signal out of its bounds, a run with a value in the wrong unit",
            "3 failures, each the test's own line and the plugin's message; none of the "
            "plugin's source lines",
            f"exit {result.returncode}; {len(result.stdout.splitlines())} lines of report; "
            f"the plugin's own lines shown: {len(ours)} {ours[:2]}",
            ok,
        )


CASES = [import_faults, value_messages, infinite_metric, settling_norm, plugin_failures]
