"""What a TARGET is (orchestration/mission/targets.py): the shipped scenarios found from
their modules, a mission file anywhere, a module on sys.path, a package's entry point, a
variant checked by name; the registry is nothing hard-coded."""

import sys
import textwrap
from importlib import metadata

import pytest

from agilesat.orchestration.mission import Scenario, targets

MISSION = """
from agilesat.orchestration.mission import Scenario, System, Variant
from helper_beside import TITLE  # a module beside the mission file

SYSTEM = System("mine", step=0.1, stop=1.0).add("Flywheel")
FAST = Variant("faster", parameters={"Flywheel.torque_limit": 1.0})
SCENARIO = Scenario("mine", TITLE, SYSTEM, variants={"fast": FAST})
"""


@pytest.fixture
def mission_dir(tmp_path, monkeypatch):
    (tmp_path / "mission.py").write_text(textwrap.dedent(MISSION))
    (tmp_path / "helper_beside.py").write_text("TITLE = 'a mission of mine'\n")
    monkeypatch.setattr(sys, "path", list(sys.path))  # the mission's directory goes on it
    return tmp_path


def test_the_shipped_scenarios_are_the_modules_that_define_one():
    assert targets.shipped() == ("payload_sweep", "scan_pitch", "video_sar")
    assert isinstance(targets.scenario("scan_pitch"), Scenario)


def test_a_mission_file_anywhere_with_its_variant(mission_dir, monkeypatch):
    monkeypatch.chdir(mission_dir.parent)
    found = targets.resolve(f"{mission_dir.name}/mission.py:fast")
    assert found.scenario.title == "a mission of mine" and found.variant == "fast"
    assert found.label == "mine:fast"
    assert targets.resolve(str(mission_dir / "mission.py")).scenario is found.scenario  # once
    with pytest.raises(KeyError, match="no variant 'fats'; did you mean fast"):
        targets.resolve(f"{mission_dir}/mission.py:fats")


def test_a_module_on_the_path_and_an_entry_point(mission_dir, monkeypatch):
    package = mission_dir / "team_missions"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "detumble.py").write_text(textwrap.dedent(MISSION))
    monkeypatch.syspath_prepend(str(mission_dir))
    assert targets.resolve("team_missions.detumble:fast").scenario.name == "mine"
    point = metadata.EntryPoint("ours", "team_missions.detumble:SCENARIO", targets.GROUP)
    monkeypatch.setattr(
        targets.metadata,
        "entry_points",
        lambda group: [point] if group == targets.GROUP else [],
    )
    assert "ours" in targets.names()
    assert targets.resolve("ours").scenario.title == "a mission of mine"


def test_anything_else_is_named_with_what_a_target_may_be():
    with pytest.raises(KeyError, match=r"did you mean scan_pitch\?"):
        targets.resolve("scan_pich")
    with pytest.raises(KeyError, match="no mission file"):
        targets.resolve("nowhere/mission.py")


def test_a_module_with_two_scenarios_must_name_one(tmp_path):
    path = tmp_path / "two.py"
    path.write_text(
        "from agilesat.orchestration.mission import Scenario, System\n"
        "A = Scenario('a', 'a', System('a'))\nB = Scenario('b', 'b', System('b'))\n"
    )
    with pytest.raises(KeyError, match=r"defines 2 scenarios \(a, b\): name the one to run"):
        targets.resolve(str(path))


def test_info_of_a_variant_marks_what_it_changes_and_lists_the_outputs(fmus):
    from agilesat.orchestration.info import info

    text = info("scan_pitch:literal_spin")
    assert "> variant :literal_spin" in text
    changed = [line for line in text.splitlines() if line.startswith(" !")]
    assert [line.split()[0] for line in changed] == [
        "!CmgCluster.spin_ref[6×3]",
        "!CmgSteering.spin_ref[6×3]",
    ]
    assert "imaging_pitch_rate_mean in [-0.82, -0.78] °/s" in text
    assert "jacobi; input/output derivatives where both FMUs declare them: 0 link(s)" in text
    attitude = next(line for line in text.splitlines() if "SatelliteDynamics.attitude0" in line)
    assert "[0,2.0944,0] ([0,120,0])" in attitude  # rad, and degrees beside
    assert " SatelliteDynamics.w_BI_B[3]" in text.split("outputs (recorded")[1]
    with pytest.raises(KeyError, match="did you mean literal_spin"):
        info("scan_pitch:literal")
