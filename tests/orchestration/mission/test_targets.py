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


@pytest.mark.parametrize(
    "source, message",
    [
        (
            "import sys\nsys.exit(0)\n",
            r"importing it called sys.exit\(0\), so it defines no scenario",
        ),
        (
            "x = 1\ny = x + undefined\n",
            r"importing it raised NameError: .* \(line 2: y = x \+ undefined\)",
        ),
        ("x = (\n", r"importing it raised SyntaxError: .* \(line 1: x = \("),
    ],
)
def test_a_mission_file_that_fails_as_it_is_imported_is_a_message(tmp_path, source, message):
    """sys.exit(0) at import made `agilesat run` exit 0 with nothing run; an exception was
    a traceback: each is a MissionError naming the file (and the mission's line)."""
    path = tmp_path / f"failing{len(source)}.py"
    path.write_text(source)
    with pytest.raises(targets.MissionError, match=rf"{path}: {message}"):
        targets.resolve(str(path))
    assert not any(
        name.startswith("agilesat_mission_") and sys.modules[name].__file__ == str(path)
        for name in list(sys.modules)
    )


def test_a_file_that_is_no_fmi_2_fmu_is_a_message(tmp_path, fmus):
    """Not a zip, a zip cut short, a model description cut short, an FMI 3.0 one: each
    a message naming the file (they were library tracebacks)."""
    import zipfile

    from agilesat.orchestration.system.description import FMUFileError

    gyro = fmus["Gyro"].read_bytes()
    (tmp_path / "text.fmu").write_text("hello")
    (tmp_path / "cut.fmu").write_bytes(gyro[: len(gyro) // 2])

    def edited(name, edit):
        with zipfile.ZipFile(fmus["Gyro"]) as source, zipfile.ZipFile(tmp_path / name, "w") as copy:
            for info in source.infolist():
                data = source.read(info)
                copy.writestr(
                    info.filename, edit(data) if info.filename == "modelDescription.xml" else data
                )

    edited("cutmd.fmu", lambda data: data[: len(data) // 2])
    edited("fmi3.fmu", lambda data: data.replace(b'fmiVersion="2.0"', b'fmiVersion="3.0"'))
    edited("bad.fmu", lambda data: data.replace(b"causality=", b"causalty="))
    for name, message in [
        ("text.fmu", "not an FMU: File is not a zip file"),
        ("cut.fmu", "not an FMU"),
        ("cutmd.fmu", "its modelDescription.xml is not XML"),
        ("fmi3.fmu", "an FMU of FMI 3.0: agilesat runs FMI 2.0 co-simulation FMUs"),
        ("bad.fmu", "its modelDescription.xml is not an FMI 2.0 model description"),
    ]:
        with pytest.raises(FMUFileError, match=f"{tmp_path / name}: {message}"):
            targets.resolve(str(tmp_path / name))
