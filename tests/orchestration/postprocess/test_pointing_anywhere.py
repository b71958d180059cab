"""``agilesat pointing DIR`` from any folder, on the records it can trust: the target a
run or campaign was made of is found by its absolute path and digest (moved or edited, it
says so and takes ``--mission``); a window the records do not cover is refused; files
that are cut, short or not ours are said, naming the file."""

import json
import math
import re
import shutil

import numpy as np
import pytest

from agilesat.orchestration.cli import main
from agilesat.orchestration.mission.targets import resolve
from agilesat.orchestration.output.results import Results, ResultsFileError

DT = 0.05
T = np.arange(1201) * DT  # 60 s
IDENTITY = np.tile([1.0, 0.0, 0.0, 0.0], (T.size, 1))
NAMES = [
    f"{base}[{i}]"
    for base in ("SatelliteDynamics.q_BI", "OrbitEnvironment.q_OI")
    for i in (1, 2, 3, 4)
]
ANGLE = 1e-4 * (1 + np.sin(2 * math.pi * T / 10.0))  # rad about z: at most 2e-4

#: a mission whose variant judges the APE about z against a bound the angle exceeds
MISSION = """\
import math

from agilesat.orchestration.mission import Pointing, Scenario, System, Variant
from agilesat.orchestration.pointing import PointingRequirement

SYSTEM = System("two", step=0.05, stop=60.0)
SYSTEM.add("OrbitEnvironment")
SYSTEM.add("SatelliteDynamics")


def ape(bound):
    r = PointingRequirement("APE", bound, 0.9973, "temporal", axis=(0, 0, 1))
    return Pointing("ape", r, reference="OrbitEnvironment.q_OI")


SCENARIO = Scenario(
    "eo_roll_slew",
    "a mission of the user's",
    SYSTEM,
    variants={"sensed": Variant("judged", requirements=[ape(1.5e-4)])},
)
"""


def about_z(angle):
    zero = np.zeros_like(angle)
    return np.stack((np.cos(angle / 2), zero, zero, np.sin(angle / 2)), axis=-1)


def write_run(directory, target, stop=60.0, rows=T.size):
    """A run of ``target`` as `agilesat run` leaves it: its results (``rows`` of them) and
    its summary (run until ``stop``)."""
    directory.mkdir(parents=True)
    data = np.column_stack((T, about_z(ANGLE), IDENTITY))[:rows]
    Results(["time", *NAMES], data).to_npz(directory / "results.npz")
    found = resolve(target)
    summary = {
        "scenario": found.scenario.name,
        "variant": found.variant,
        "target": found.record(),
        "settings": {"start": 0.0, "stop": stop, "step": DT, "algorithm": "jacobi"},
        "rows": rows,
    }
    (directory / "summary.json").write_text(json.dumps(summary))
    return directory


@pytest.fixture
def made(tmp_path, monkeypatch):
    """A mission file in a/, a run of its variant in runs/, and a folder elsewhere/ where
    `agilesat pointing` is run."""
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "mission.py").write_text(MISSION)
    monkeypatch.chdir(tmp_path / "a")
    run = write_run(tmp_path / "runs" / "r", "mission.py:sensed")
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    return tmp_path, run


def pointing(*argv, capsys):
    code = main(["pointing", *map(str, argv)])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_a_run_of_a_mission_files_variant_is_judged_from_another_folder(made, capsys):
    """The run's summary names the mission file by its absolute path with its SHA-256;
    from another folder its variant's requirement is judged: max |angle| 2e-4 rad (at
    99.73 % of the time, within the largest values) against 1.5e-4: not met, exit 3."""
    tmp_path, run = made
    target = json.loads((run / "summary.json").read_text())["target"]
    assert target["path"] == str(tmp_path / "a" / "mission.py")
    assert target["kind"] == "mission file" and target["variant"] == "sensed"
    assert len(target["sha256"]) == 64
    code, out, err = pointing(run, capsys=capsys)
    assert code == 3, err
    assert "ape: APE about (0, 0, 1) at 99.73 % (temporal): 0.01146°" in out
    assert out.rstrip().endswith("(requirement 0.008594°): not met")


def test_moved_or_edited_it_says_so_and_takes_mission(made, capsys):
    tmp_path, run = made
    shutil.move(tmp_path / "a", tmp_path / "b")
    code, _, err = pointing(run, capsys=capsys)
    assert code == 1
    assert (
        f"was made of the mission file {tmp_path / 'a' / 'mission.py'}, which is no longer "
        "there (moved or deleted): give --mission PATH" in err
    )
    code, out, err = pointing(run, "--mission", tmp_path / "b" / "mission.py", capsys=capsys)
    assert code == 3 and "not met" in out and err == ""  # the same file, moved
    with (tmp_path / "b" / "mission.py").open("a") as mission:
        mission.write("# edited\n")
    shutil.move(tmp_path / "b", tmp_path / "a")
    code, _, err = pointing(run, capsys=capsys)
    assert code == 1 and "which has changed since (SHA-256 " in err
    assert f"--mission {tmp_path / 'a' / 'mission.py'} judges it by the file as it is now" in err
    code, out, err = pointing(run, "--mission", tmp_path / "a" / "mission.py", capsys=capsys)
    assert code == 3 and "not met" in out
    assert err.startswith(f"note: {tmp_path / 'a' / 'mission.py'} is not what ")


def test_a_campaign_is_judged_from_another_folder(made, capsys):
    tmp_path, _ = made
    campaign = tmp_path / "runs" / "c"
    campaign.mkdir()
    signals = np.stack([np.column_stack((about_z(ANGLE * k), IDENTITY)).T for k in (1, 0.5)])
    np.save(campaign / "signals.npy", signals)
    record = resolve(str(tmp_path / "a" / "mission.py") + ":sensed").record()
    summary = {
        "spec": {"target": "mission.py:sensed"},
        "target": record,
        "runs": {"planned": 2},
        "kept": {"signals": NAMES, "start": 0.0, "step": DT, "points": T.size},
    }
    (campaign / "campaign.json").write_text(json.dumps(summary))
    code, out, _ = pointing(campaign, capsys=capsys)
    assert code == 3 and out.startswith(f"{campaign}: eo_roll_slew:sensed, 2 run(s)")


def test_a_window_the_records_do_not_cover_is_refused(made, capsys):
    """A run to 120 s whose records end at 60 s (it stopped early): an index over the run
    as planned, or past its records, is refused; within them it is computed."""
    tmp_path, _ = made
    run = write_run(tmp_path / "runs" / "short", str(tmp_path / "a" / "mission.py"), stop=120.0)
    ape = ("--index", "APE", "--reference", "OrbitEnvironment.q_OI", "--axis", "0", "0", "1")
    code, out, err = pointing(run, *ape, capsys=capsys)
    assert code == 1 and "APE at" not in out
    assert out.startswith(
        f"{run}: eo_roll_slew, 1 run(s); the records end at 60 s, before the run's end 120 s"
    )
    assert err.strip().endswith(f"{run}: the records end at 60 s, before the window's end 120 s")
    code, _, err = pointing(run, *ape, "--start", "-5", "--stop", "30", capsys=capsys)
    assert code == 1 and "the records begin at 0 s, after the window's start -5 s" in err
    code, out, _ = pointing(run, *ape, "--stop", "30", capsys=capsys)
    assert code == 0 and "APE about (0, 0, 1) at 99.73 % (temporal): " in out
    code, _, err = pointing(run, "--mission", tmp_path / "a" / "mission.py", capsys=capsys)
    assert code == 1 and "the records end at 60 s, before the run's end 120 s: the req" in err


def test_cut_short_and_foreign_records_are_said_naming_the_file(tmp_path, capsys):
    """No library traceback, never a short series: a cut results.npz, one with fewer rows
    than summary.json says, time that does not increase, a cut results.csv; another
    tool's results and campaign.json."""
    whole = write_run(tmp_path / "whole", "scan_pitch")
    npz = (whole / "results.npz").read_bytes()
    cases = {}
    for name, edit in {
        "cut": lambda d: (d / "results.npz").write_bytes(npz[: len(npz) // 2]),
        "short": lambda d: Results(
            ["time", *NAMES], np.zeros((5, 9)) + np.arange(5)[:, None]
        ).to_npz(d / "results.npz"),
        "back": lambda d: Results(["time", *NAMES], np.zeros((T.size, 9))).to_npz(
            d / "results.npz"
        ),
    }.items():
        shutil.copytree(whole, tmp_path / name)
        edit(tmp_path / name)
        cases[name] = tmp_path / name / "results.npz"
    csv = tmp_path / "csv"
    csv.mkdir()
    Results(["time", *NAMES], np.column_stack((T, about_z(ANGLE), IDENTITY))).to_csv(
        csv / "results.csv"
    )
    text = (csv / "results.csv").read_text()
    (csv / "results.csv").write_text(text[: len(text) // 2])
    said = {
        "cut": "not a whole results file (BadZipFile: ",
        "short": f"5 rows, but {tmp_path / 'short' / 'summary.json'} says the run recorded 1201",
        "back": "time does not increase from row 1 to 2 (t = 0 s, then 0 s)",
    }
    for name, path in cases.items():
        with pytest.raises(ResultsFileError, match="^" + re.escape(f"{path}: {said[name]}")):
            Results.load(path.parent)
    with pytest.raises(ResultsFileError, match="results.csv: not a whole results file"):
        Results.load(csv)
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "results.csv").write_text("t,x\n0,1\n")
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "campaign.json").write_text("[1, 2]")
    for folder, message in (
        (theirs, "its first column is 't', not 'time': not the results of an agilesat run"),
        (tmp_path / "other", "not a campaign's summary of agilesat's (a JSON list)"),
        (cases["cut"].parent, "not a whole results file"),
    ):
        code, _, err = pointing(folder, "--index", "AKE", capsys=capsys)
        assert code == 1 and message in err and "Traceback" not in err


@pytest.mark.slow
@pytest.mark.integration
def test_a_mission_run_in_one_folder_is_judged_from_another(tmp_path, fmus, capsys, monkeypatch):
    """As a user does it: `agilesat run mission.py:sensed` in the mission's folder, then
    `agilesat pointing` from another; the mission moved, then edited."""
    from helpers import agilesat

    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "mission.py").write_text(MISSION)
    made = agilesat("run", "mission.py:sensed", "--stop", "10", "--no-figures", "--out",
                    "../runs/r", cwd=tmp_path / "a")  # fmt: skip
    assert made.returncode in (0, 3), made.stderr
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    code, out, err = pointing("../runs/r", capsys=capsys)
    assert code == made.returncode and "ape: APE about (0, 0, 1) at 99.73 % (temporal)" in out
    shutil.move(tmp_path / "a", tmp_path / "b")
    assert pointing("../runs/r", capsys=capsys)[0] == 1
    assert pointing("../runs/r", "--mission", "../b/mission.py", capsys=capsys)[:2] == (code, out)
    (tmp_path / "c").mkdir()  # edited (a file this process has not loaded yet)
    (tmp_path / "c" / "mission.py").write_text(MISSION.replace("1.5e-4", "1.0"))
    code, out, err = pointing("../runs/r", "--mission", "../c/mission.py", capsys=capsys)
    assert code == 0 and "(requirement 57.3°): met" in out and err.startswith("note: ")
