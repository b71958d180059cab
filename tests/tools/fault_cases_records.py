"""Fault cases of what a run leaves and what reads it back: ``agilesat pointing`` over a
window the records do not cover, on cut results and on folders that are not ours; a
metric or a figure that raises; figures an earlier run left; the mission API's first
mistakes.  Each measured in fresh processes (``CASES``, as in ``fault_cases_master``)."""

from __future__ import annotations

import json
import os
import re
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from fault_cases_master import CLI, _case, _stderr_line, _summary

from helpers import ROOT

#: a small mission of our FMUs: variants with a metric and a figure that raise
MISSION = """\
from agilesat.orchestration.mission import Metric, Scenario, System, Variant, lines
from agilesat.orchestration.mission import metrics as m

SYSTEM = System("faulty", step=0.1, stop=2.0)
SYSTEM.add("OrbitEnvironment")
SYSTEM.add("SatelliteDynamics", rate0="[1, 0, 0] deg/s")
SYSTEM.connect("OrbitEnvironment.r_I", "SatelliteDynamics.r_I")
SYSTEM.connect("OrbitEnvironment.q_OI", "SatelliteDynamics.q_OI")
SYSTEM.connect("OrbitEnvironment.w_OI_O", "SatelliteDynamics.w_OI_O")


def broken(results):
    return 1 / 0  # the metric's own mistake


def rates(results, out_dir):
    w = results.get("SatelliteDynamics.w_BI_B", deg=True)
    return lines(out_dir / "rates.png", "Body rates", results.time, {"x": w[:, 0]}, "[deg/s]")


def broken_figure(results, out_dir):
    raise RuntimeError("the figure's own mistake")


SCENARIO = Scenario(
    "faulty",
    "a metric and a figure that raise",
    SYSTEM,
    metrics=[m.max_abs("SatelliteDynamics.w_BI_B", norm=True, name="max_rate")],
    variants={
        "metric": Variant("a metric that raises", metrics=[Metric("broken", broken, "1")]),
        "figure": Variant("a figure that raises", figures=[broken_figure]),
    },
    figures=[rates],
)
"""


def _agilesat(*args, env=None, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [*CLI, *map(str, args)],
        cwd=cwd or ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        env={**os.environ, **(env or {})},
    )


def _clean(result) -> bool:
    """A message, not a library's traceback."""
    return "Traceback" not in result.stderr and result.stderr.strip() != ""


def _pointing(directory, *options) -> subprocess.CompletedProcess:
    return _agilesat("pointing", directory, "--index", "APE", *options)


def uncovered_window():
    """A run interrupted at 4 s of 20 s (SIGINT at macro step 80), then APE over [0, 20] s
    and over the run as planned: refused, naming where its records end."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        run = _agilesat(
            "run", "scan_pitch", "--stop", "20", "--no-figures", "-q", "--out", out,
            env={"AGILESAT_TEST_SIGNAL": "SIGINT@step:80"},
        )  # fmt: skip
        reference = ("--reference", "OrbitEnvironment.q_OI")
        over = _pointing(out, *reference, "--start", "0", "--stop", "20")
        planned = _pointing(out, *reference)
        ended = re.compile(r"the records end at 4 s, before the window's end 20 s")
        ok = run.returncode == 130 and all(
            r.returncode == 1 and ended.search(r.stderr) and "APE at" not in r.stdout and _clean(r)
            for r in (over, planned)
        )
        return _case(
            "`agilesat pointing` of a scan_pitch run interrupted at 4 s of 20 s: APE over "
            "--start 0 --stop 20, and over the run as planned",
            "exit 1 each, saying the records end at 4 s, before the window's end; no index "
            "printed as if over [0, 20] s",
            f"run exit {run.returncode}; --stop 20: exit {over.returncode}: "
            f"{_stderr_line(over)}; planned: exit {planned.returncode}",
            ok,
        )


def cut_results():
    """A whole run's directory with results.npz cut to half its bytes, with a results.npz
    of its first 50 rows (summary.json says 101), and with results.csv cut in mid-row (no
    npz): `agilesat pointing` on each, `agilesat plot` on the short one."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        run = _agilesat(
            "run", "scan_pitch", "--stop", "5", "--no-figures", "-q", "--out", tmp / "a"
        )
        b, c = tmp / "b", tmp / "c"
        for copy in (b, c):
            copy.mkdir()
            for f in (tmp / "a").iterdir():
                (copy / f.name).write_bytes(f.read_bytes())
        npz = (tmp / "a" / "results.npz").read_bytes()
        (tmp / "a" / "results.npz").write_bytes(npz[: len(npz) // 2])
        with np.load(b / "results.npz") as archive:
            kept = {k: archive[k] for k in archive.files}
        kept["data"] = kept["data"][:50]
        np.savez_compressed(b / "results.npz", **kept)
        (c / "results.npz").unlink()
        text = (c / "results.csv").read_text()
        (c / "results.csv").write_text(text[: len(text) // 2])
        trials = []
        for directory, file, said in (
            (tmp / "a", "results.npz", "not a whole results file"),
            (b, "results.npz", "50 rows, but"),
            (c, "results.csv", "not a whole results file"),
        ):
            results = [_pointing(directory, "--reference", "OrbitEnvironment.q_OI")]
            if directory == b:  # what plots it reads the same
                results.append(_agilesat("plot", directory, "SatelliteDynamics.q_BI"))
            for result in results:
                good = (
                    result.returncode == 1
                    and f"{directory / file}: {said}" in result.stderr
                    and _clean(result)
                )
                trials.append((f"{directory.name}/{file}", result, good))
        return _case(
            "a scan_pitch run's results.npz cut to half its bytes; a results.npz of its "
            "first 50 of 101 rows; results.csv cut in mid-row (no npz): `agilesat pointing` "
            "on each, `agilesat plot` on the short one",
            "exit 1 each, naming the file and what is wrong (cut, or fewer rows than "
            "summary.json says); no traceback, never a short series",
            f"run exit {run.returncode}; "
            + "; ".join(
                f"{name}: exit {r.returncode}" + ("" if good else f" (!) {_stderr_line(r)}")
                for name, r, good in trials
            ),
            run.returncode == 0 and all(good for _, _, good in trials),
        )


def foreign_folders():
    """`agilesat pointing` on a folder holding another tool's results.csv, one holding a
    campaign.json that is not a campaign's, and an empty one."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        theirs, other, empty = tmp / "theirs", tmp / "other", tmp / "empty"
        for folder in (theirs, other, empty):
            folder.mkdir()
        (theirs / "results.csv").write_text("t,x\n0,1\n0.1,2\n")
        (other / "campaign.json").write_text('{"name": "another tool"}\n')
        trials = [
            (theirs, "not the results of an agilesat run"),
            (other, "not a campaign's summary of agilesat's"),
            (empty, "neither a run directory of `agilesat run`"),
        ]
        observed, ok = [], True
        for folder, said in trials:
            result = _pointing(folder)
            good = result.returncode == 1 and said in result.stderr and _clean(result)
            ok &= good
            observed.append(f"{folder.name}: exit {result.returncode}: {_stderr_line(result)}")
        return _case(
            "`agilesat pointing` on a folder of another tool's results.csv (columns t, x), "
            "on one with a campaign.json that is not a campaign's, on an empty one",
            "exit 1 each, saying what it expected (the results of an agilesat run, a "
            "campaign's summary, a run or campaign directory); no traceback",
            "; ".join(observed),
            ok,
        )


def _run_mission(directory: Path, variant: str):
    """(the mission file, its --out, the run of ``variant``, its summary) in ``directory``."""
    mission, out = directory / "mission.py", directory / "out"
    mission.write_text(MISSION)
    result = _agilesat("run", f"{mission}:{variant}", "--out", out, cwd=directory)
    return mission, out, result, _summary(out)


def _log(out: Path) -> str:
    return (out / "log.txt").read_text() if (out / "log.txt").exists() else ""


def metric_raises():
    """A mission variant whose metric raises ZeroDivisionError after a whole run."""
    with tempfile.TemporaryDirectory() as tmp:
        mission, out, result, summary = _run_mission(Path(tmp), "metric")
        broken = summary.get("metrics", {}).get("broken", {})
        ok = (
            result.returncode == 1
            and "Traceback" not in result.stderr
            and summary.get("status") == "error"
            and broken.get("value") is None
            and broken.get("failed") is True
            and "ZeroDivisionError" in broken.get("reason", "")
            and f"{mission}:" in broken.get("reason", "")
            and summary.get("metrics", {}).get("max_rate", {}).get("value") is not None
            and "ZeroDivisionError" in _log(out)
            and (out / "rates.png").exists()
        )
        return _case(
            "a mission's metric that raises ZeroDivisionError after a whole run",
            "exit 1; summary.json status 'error', the metric not evaluated with the reason "
            "(the exception, where the metric was written), the other metrics' values; "
            "log.txt says it; the figures drawn; no traceback",
            f"exit {result.returncode}; summary status {summary.get('status')!r}, broken: "
            f"{broken.get('reason', '(none)')[-80:]}; log says it: "
            f"{'ZeroDivisionError' in _log(out)}; rates.png: {(out / 'rates.png').exists()}",
            ok,
        )


def figure_raises():
    """A mission variant whose second figure raises RuntimeError."""
    with tempfile.TemporaryDirectory() as tmp:
        _, out, result, summary = _run_mission(Path(tmp), "figure")
        errors = " ".join(summary.get("errors", []))
        ok = (
            result.returncode == 1
            and "Traceback" not in result.stderr
            and summary.get("status") == "error"
            and "broken_figure" in errors
            and "RuntimeError: the figure's own mistake" in errors
            and "broken_figure" in _log(out)
            and [Path(f).name for f in summary.get("figures", [])] == ["rates.png"]
            and (out / "rates.png").exists()
        )
        return _case(
            "a mission's figure function that raises RuntimeError (after another figure)",
            "exit 1; summary.json status 'error' naming the figure function and the "
            "exception, the other figure written and listed; log.txt says it",
            f"exit {result.returncode}; summary status {summary.get('status')!r}, errors "
            f"{errors[:100]!r}, figures {summary.get('figures')}",
            ok,
        )


def earlier_run_files():
    """A run killed (SIGKILL) as it starts its third figure, then a run without figures
    on the same --out killed at macro step 40: what the directory then holds is the
    second run's."""
    from agilesat.orchestration.output.results import Results

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        first = _agilesat(
            "run", "scan_pitch", "--stop", "5", "-q", "--out", out,
            env={"AGILESAT_TEST_SIGNAL": "SIGKILL@figure:3"},
        )  # fmt: skip
        drawn = sorted(p.name for p in out.glob("*.png"))
        second = _agilesat(
            "run", "scan_pitch", "--stop", "5", "-q", "--no-figures", "--out", out,
            env={"AGILESAT_TEST_SIGNAL": "SIGKILL@step:40"},
        )  # fmt: skip
        left = sorted(p.name for p in out.glob("*.png"))
        rows = (out / "results.csv").read_text().count("\n") - 1
        try:
            read = f"{len(Results.load(out))} rows"
        except (OSError, ValueError) as exc:
            read = f"{type(exc).__name__}: {exc}"
        ok = (
            first.returncode == second.returncode == -9
            and len(drawn) == 2
            and not left
            and not (out / "summary.json").exists()
            and 40 <= rows < 101
            and read == f"{rows} rows"
        )
        return _case(
            "a scan_pitch run killed (SIGKILL) as it starts its third figure, then one "
            "without figures on the same --out killed at macro step 40",
            "the directory holds the second run's records only: no figure, summary.json or "
            "results.npz of the first; its results read back are the second run's rows",
            f"exits {first.returncode}, {second.returncode}; first drew {drawn}; left "
            f"{left}, summary.json {(out / 'summary.json').exists()}; results.csv {rows} "
            f"rows, read back {read}",
            ok,
        )


def new_user_names():
    """A mission that adds "Flywhel" and connects "Flywheel.h"; ``--set
    CmgCluster.deltadot=1`` (an output's near-namesake)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "typo.py"
        path.write_text(
            "from agilesat.orchestration.mission import Scenario, System\n"
            'SYSTEM = System("typo", step=0.1, stop=1.0)\n'
            'SYSTEM.add("SatelliteDynamics")\n'
            'SYSTEM.add("Flywhel")\n'
            'SYSTEM.connect("Flywheel.h", "SatelliteDynamics.h_wheel")\n'
            'SCENARIO = Scenario("typo", "a misspelt FMU", SYSTEM)\n'
        )
        added = _agilesat("info", path)
        setting = _agilesat(
            "run", "scan_pitch", "--set", "CmgCluster.deltadot=1", "--out", Path(tmp) / "o"
        )
        meant = re.search(r"did you mean ([^?]*)\?", setting.stderr)
        suggested = meant.group(1).split(", ") if meant else []
        outputs = {"delta", "delta_dot", "h", "hdot", "singularity"}  # CmgCluster's
        ok = (
            added.returncode == 1
            and f"{path}:4: component 'Flywhel': unknown FMU 'Flywhel'; did you mean Flywheel?"
            in added.stderr
            and "did you mean Flywhel" not in added.stderr
            and setting.returncode == 1
            and suggested
            and not outputs & set(suggested)
        )
        return _case(
            'a mission with system.add("Flywhel") (line 4) then connect("Flywheel.h", ...); '
            "`run scan_pitch --set CmgCluster.deltadot=1`",
            "the misspelt FMU said at its add() line, suggesting Flywheel (not the typo); "
            "--set suggests parameters, no output",
            f"info: exit {added.returncode}: {_stderr_line(added, 'Flywhel')}; --set: exit "
            f"{setting.returncode}, suggests {suggested}",
            ok,
        )


CASES = [
    uncovered_window,
    cut_results,
    foreign_folders,
    metric_raises,
    figure_raises,
    earlier_run_files,
    new_user_names,
]


if __name__ == "__main__":  # each case's row, as the fault matrix prints it
    for case in CASES:
        print(json.dumps(case(), indent=1))
