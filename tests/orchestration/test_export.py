"""``agilesat export`` of what users build (orchestration/export.py, fmus/configure.py): a
model of their own exported with ``--set`` carries the set value in its FMU, whether the
mission names the model's ``.py`` or the FMU ``agilesat build`` wrote (anywhere); a model
FMU another version of agilesat built is an error naming the rebuild; a third party's FMU is
packed as it is with one plain note (no Python warning); ``--out x.ssd`` and
``--component NAME --out x.fmu``; every exported FMU has the system's DefaultExperiment.
The FMUs run as users get them: copied out, in fmpy's ``simulate_fmu`` in a clean process,
at their defaults."""

import json
import math
import shutil
import zipfile

import pytest
from fmpy import read_model_description

from agilesat.orchestration.output.results import Results
from helpers import agilesat, pythonfmu_damper, run_python

pytestmark = [pytest.mark.slow, pytest.mark.integration]

GUIDANCE = '''
from agilesat.components.model import Model
from agilesat.components.variables import output, parameter


class Guidance(Model):
    """A roll reference held at a parameter."""

    VARIABLES = (
        parameter("roll", 0.4363323129985824, "rad", "roll to hold", display_unit="deg"),
        output("roll_ref", "rad", "roll reference", display_unit="deg"),
    )

    def step(self, t, dt):
        self.t = t + dt

    def output(self):
        self.y.roll_ref = self.p.roll
'''
MISSION = """
from agilesat.orchestration.mission import Scenario, System

SYSTEM = System("guided", step=0.1, stop=2.0)
SYSTEM.add("Guidance", "{source}")
SYSTEM.add("SatelliteDynamics")
SCENARIO = Scenario(SYSTEM.name, "a test", SYSTEM)
"""
SIMULATE = """
import json, sys
from fmpy import simulate_fmu
result = simulate_fmu(sys.argv[1])
print(json.dumps({"roll_ref": [float(x) for x in result["roll_ref"]],
                  "time": [float(x) for x in result["time"]]}))
"""


@pytest.fixture(scope="module")
def user(tmp_path_factory, fmus):
    """A user's folder: guidance.py, built into build/ (as `agilesat build` does) and into
    elsewhere/ (`--out`), and a mission naming each."""
    folder = tmp_path_factory.mktemp("user")
    (folder / "guidance.py").write_text(GUIDANCE)
    for args in ((), ("--out", folder / "elsewhere")):
        built = agilesat("build", folder / "guidance.py", *args)
        assert built.returncode == 0, built.stderr
    (folder / "by_source.py").write_text(MISSION.format(source="guidance.py"))
    (folder / "by_fmu.py").write_text(MISSION.format(source="elsewhere/Guidance.fmu"))
    return folder


def _inner(package, member):
    with zipfile.ZipFile(package) as archive:
        return archive.read(member)


@pytest.mark.parametrize("mission", ["by_source.py", "by_fmu.py"])
def test_a_users_model_exported_with_set_runs_its_set_value(user, tmp_path, mission):
    run = agilesat(
        "export", user / mission, "--set", "Guidance.roll=30 deg", "--out", tmp_path / "m.ssp"
    )
    assert run.returncode == 0, run.stderr
    assert "Warning" not in run.stderr and "packed as it is" not in run.stderr, run.stderr
    fmu = tmp_path / "out" / "Guidance.fmu"  # as a user gets it: copied out of the package
    fmu.parent.mkdir()
    fmu.write_bytes(_inner(tmp_path / "m.ssp", "resources/Guidance.fmu"))
    shutil.rmtree(user / "elsewhere" / ".shim", ignore_errors=True)
    found = run_python(SIMULATE, fmu, cwd=tmp_path)
    assert found.returncode == 0, found.stderr
    result = json.loads(found.stdout.strip().splitlines()[-1])
    assert set(result["roll_ref"]) == {math.radians(30.0)}  # not the model's 25°
    assert result["time"][-1] == 2.0 and len(result["time"]) == 21  # the system's experiment
    md = read_model_description(str(fmu))
    built = read_model_description(str(user / "build" / "Guidance.fmu"))
    assert md.guid != built.guid  # a GUID of its own


def test_a_model_fmu_another_agilesat_built_is_an_error_naming_the_rebuild(user, tmp_path):
    """Its code is not these sources' (here: its content hash changed, as another
    version's is): its slave may not apply a configuration; rebuilding makes it one of
    these."""
    folder = tmp_path / "older"
    shutil.copytree(user, folder)
    fmu = folder / "elsewhere" / "Guidance.fmu"
    with zipfile.ZipFile(fmu) as archive:
        entries = {n: archive.read(n) for n in archive.namelist()}
    digest = entries["resources/slavemodule.txt"].decode().rpartition("_")[2]
    with zipfile.ZipFile(fmu, "w") as archive:
        for name, data in entries.items():
            if not name.startswith("binaries/"):
                data = data.replace(digest.encode(), b"0" * len(digest))
            archive.writestr(name.replace(digest, "0" * len(digest)), data)
    run = agilesat("export", folder / "by_fmu.py", "--out", tmp_path / "m.ssp")
    assert run.returncode == 1
    assert "built by agilesat from other sources than these" in run.stderr, run.stderr
    assert "agilesat build guidance.py" in run.stderr and "Traceback" not in run.stderr


def test_a_third_party_fmu_is_packed_as_it_is_with_a_note(fmus, tmp_path):
    pythonfmu_damper(tmp_path)
    (tmp_path / "mission.py").write_text(
        "from agilesat.orchestration.mission import System\n"
        "SYSTEM = System('damped', step=0.1, stop=1.0)\n"
        "SYSTEM.add('Damper', 'Damper.fmu', gain=2.0)\n"
        "SYSTEM.add('SatelliteDynamics')\n"
        "SYSTEM.connect('SatelliteDynamics.w_BI_B', 'Damper.w_BI_B')\n"
        "from agilesat.orchestration.mission import Scenario\n"
        "SCENARIO = Scenario(SYSTEM.name, 'a test', SYSTEM)\n"
    )
    run = agilesat("export", tmp_path / "mission.py", "--out", tmp_path / "d.ssp")
    assert run.returncode == 0, run.stderr
    lines = [line for line in run.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "UserWarning" not in run.stderr, run.stderr
    assert "not an FMU agilesat built (component Damper): packed as it is" in lines[0]
    assert "its values (gain) are in the package's parameter set only" in lines[0]
    assert (
        _inner(tmp_path / "d.ssp", "resources/Damper.fmu") == (tmp_path / "Damper.fmu").read_bytes()
    )


def test_an_ssd_with_its_fmus_beside_it_runs_as_the_package(fmus, tmp_path):
    for out in ("p.ssp", "s.ssd"):
        run = agilesat("export", "scan_pitch", "--out", tmp_path / out)
        assert run.returncode == 0, run.stderr
    assert sorted(p.name for p in (tmp_path / "s.fmus").iterdir()) == sorted(
        n.removeprefix("resources/")
        for n in zipfile.ZipFile(tmp_path / "p.ssp").namelist()
        if n.startswith("resources/")
    )
    runs = {}
    for out in ("p.ssp", "s.ssd"):
        run = agilesat(
            "run",
            tmp_path / out,
            "--stop",
            2,
            "--no-figures",
            "--no-report",
            "--out",
            tmp_path / f"r_{out}",
        )
        assert run.returncode == 0, run.stderr
        runs[out] = Results.load(tmp_path / f"r_{out}")
    assert runs["p.ssp"].names == runs["s.ssd"].names
    for name in runs["p.ssp"].names:
        assert (runs["p.ssp"][name] == runs["s.ssd"][name]).all(), name


def test_one_component_exported_runs_with_the_systems_values_and_step(fmus, tmp_path):
    fmu = tmp_path / "hub.fmu"
    run = agilesat(
        "export",
        "scan_pitch",
        "--component",
        "SatelliteDynamics",
        "--set",
        "SatelliteDynamics.rate0=[0, 0.5, 0] deg/s",
        "--out",
        fmu,
    )
    assert run.returncode == 0, run.stderr
    experiment = read_model_description(str(fmu)).defaultExperiment
    assert (float(experiment.stopTime), float(experiment.stepSize)) == (150.0, 0.05)
    alone = agilesat(
        "run", fmu, "--stop", 1, "--no-figures", "--no-report", "--out", tmp_path / "run"
    )
    assert alone.returncode == 0, alone.stderr
    results = Results.load(tmp_path / "run")
    settings = json.loads((tmp_path / "run" / "summary.json").read_text())["settings"]
    assert settings["step"] == 0.05
    # the scenario's start: pitch 120°, pitch rate 0.5 °/s relative to the orbit frame
    assert math.degrees(results["SatelliteDynamics.euler_BO[2]"][0]) == pytest.approx(120.0)
    assert math.degrees(results["SatelliteDynamics.w_BO_B[2]"][0]) == pytest.approx(0.5)


# -- the coupling error a package states (orchestration/coupling_error.py) -------------------
def test_a_package_states_its_coupling_error_per_host_class(fmus, tmp_path):
    """Printed by export and in the package's documentation; measured once, then from the
    cache (keyed on the package).  That it is what libcosim gives: tests/interop/
    test_libcosim.py."""
    runs = [agilesat("export", "scan_pitch", "--out", tmp_path / f"{k}.ssp") for k in (1, 2)]
    for run in runs:
        assert run.returncode == 0, run.stderr
    first, again = (run.stdout.splitlines()[:-1] for run in runs)  # then the package's path
    assert first[0].startswith("coupling error per host class at 0.05 s (measured ")
    assert again[0].endswith("from the cache):") and first[1:] == again[1:]
    stated = {line.split(":")[0].strip(): line for line in first[1:]}
    assert set(stated) == {
        "held inputs, Jacobi (libcosim, ECOS)",
        "held inputs, Gauss-Seidel (in dependency order)",
        "interpolating (our master; hosts sending input derivatives)",
    }
    assert "attitude " in stated["held inputs, Jacobi (libcosim, ECOS)"]
    page = _inner(tmp_path / "1.ssp", "documentation/index.html").decode()
    for host, line in stated.items():
        assert f"<b>{host}</b>: {line.split(': ', 1)[1]}" in page.replace("&#x27;", "'")


def test_accuracy_chooses_the_step_at_which_held_input_hosts_meet_it(fmus, tmp_path):
    """scan_pitch's held-input Jacobi host is 1.38° from our master at 0.05 s: for 1° the
    package's step halves (once), and export says what that costs."""
    from agilesat.orchestration.coupling_error import held_attitude
    from agilesat.orchestration.system.ssp import read_system

    run = agilesat("export", "scan_pitch", "--accuracy", "1deg", "--out", tmp_path / "a.ssp")
    assert run.returncode == 0, run.stderr
    said = [line for line in run.stdout.splitlines() if line.startswith("--accuracy")]
    assert len(said) == 1 and "step 0.025 s" in said[0] and "2× the macro steps" in said[0]
    assert read_system(tmp_path / "a.ssp").step_size == 0.025
    assert held_attitude(tmp_path / "a.ssp")[0] <= math.radians(1.0)
    assert held_attitude(tmp_path / "a.ssp", step=0.05)[0] > math.radians(1.0)
