"""The FMUs of an exported package carry the system's values as their own defaults
(orchestration/export.py, fmus/configure.py): the start values of each model description
are the values the package's SSD binds to that component (and ``warnings_return_ok`` true),
the model at instantiation has them (read back in a clean process, nothing set), and each
configured FMU has a GUID of its own."""

import json
import zipfile
from xml.etree import ElementTree

import pytest

from agilesat.orchestration.scenarios import NAMES
from agilesat.orchestration.system.ssp import read_system
from helpers import agilesat, export_elsewhere, run_python

pytestmark = [pytest.mark.slow, pytest.mark.integration]

READ_BACK = """
import json, sys
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
path = sys.argv[1]
md = read_model_description(path)
slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(path),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="x")
slave.instantiate()
slave.setupExperiment(startTime=0.0)
slave.enterInitializationMode()
get = {"Real": slave.getReal, "Integer": slave.getInteger, "Boolean": slave.getBoolean}
values = {v.name: get[v.type]([v.valueReference])[0]
          for v in md.modelVariables if v.causality == "parameter" and v.type in get}
values.update((v.name, bool(values[v.name])) for v in md.modelVariables
              if v.type == "Boolean" and v.name in values)  # parameters, not outputs
print(json.dumps(values))
"""


@pytest.fixture(scope="module")
def packages(fmus, tmp_path_factory):
    return export_elsewhere(tmp_path_factory)


def starts(description: bytes) -> tuple[str, dict]:
    root = ElementTree.fromstring(description)
    found = {}
    for v in root.iter("ScalarVariable"):
        typed = v[0]
        if v.get("causality") == "parameter" and typed.tag != "String":
            text = typed.get("start")
            found[v.get("name")] = text == "true" if typed.tag == "Boolean" else float(text)
    return root.get("guid"), found


@pytest.mark.parametrize("scenario", NAMES)
def test_each_fmu_defaults_to_the_values_the_package_binds_to_it(scenario, packages, fmus):
    system = read_system(packages[scenario])
    with zipfile.ZipFile(packages[scenario]) as archive:
        for component in system.components:
            inner = zipfile.ZipFile(archive.open(f"resources/{component.source.name}"))
            guid, defaults = starts(inner.read("modelDescription.xml"))
            configured = json.loads(inner.read("resources/configuration.json"))["values"]
            bound = {p.name: p.value for p in system.parameters if p.component == component.name}
            assert configured == {"warnings_return_ok": True, **bound}
            for name, value in bound.items():
                if not isinstance(value, str):
                    assert defaults[name] == value, (component.name, name)
            assert defaults["warnings_return_ok"] is True
            model = inner.read("resources/slavemodule.txt").decode().rsplit("_", 1)[0]
            plain = starts(zipfile.ZipFile(fmus[model]).read("modelDescription.xml"))[0]
            assert guid != plain, component.name  # a GUID of its own


def test_the_model_at_instantiation_has_its_model_descriptions_start_values(packages, tmp_path):
    """In a clean process, nothing set: every parameter read back is its start value (the
    scenario's value where the package binds one), for every FMU of scan_pitch."""
    with zipfile.ZipFile(packages["scan_pitch"]) as archive:
        names = [n for n in archive.namelist() if n.endswith(".fmu")]
        archive.extractall(tmp_path)
    for name in names:
        _, defaults = starts(zipfile.ZipFile(tmp_path / name).read("modelDescription.xml"))
        run = run_python(READ_BACK, tmp_path / name)
        assert run.returncode == 0, run.stderr
        read = json.loads(run.stdout.strip().splitlines()[-1])
        assert read == defaults, name


def test_components_of_one_fmu_with_other_values_get_files_of_their_own(tmp_path):
    """One FMU serving three components, two of them with the same values: a configured
    FMU file per component (the same bytes for the same values), each component pointing at
    its own, and the package runs."""
    from agilesat.orchestration.mission import System

    hubs = System("hubs", stop=1.0, step=0.05)
    for name, rate in zip("ABC", (0.01, 0.02, 0.01)):
        hubs.add(name, "SatelliteDynamics", rate0=[rate, 0.0, 0.0])
    hubs.connect("A.H_I", "B.h_wheel")
    hubs.connect("B.H_I", "C.h_wheel")
    with zipfile.ZipFile(hubs.write(tmp_path / "p.ssp")) as archive:
        entries = {item: archive.read(item) for item in archive.namelist()}
    assert sorted(entries) == [
        "SystemStructure.ssd",
        "resources/SatelliteDynamics_A.fmu",
        "resources/SatelliteDynamics_B.fmu",
        "resources/SatelliteDynamics_C.fmu",
    ]
    files = {k: entries[f"resources/SatelliteDynamics_{k}.fmu"] for k in "ABC"}
    assert files["A"] == files["C"] != files["B"]
    system = read_system(tmp_path / "p.ssp")
    assert {c.name: c.source.name for c in system.components} == {
        k: f"SatelliteDynamics_{k}.fmu" for k in "ABC"
    }
    run = agilesat(
        "run", tmp_path / "p.ssp", "--out", tmp_path / "out", "--no-figures", "--no-report"
    )
    assert run.returncode == 0, run.stderr


def test_an_fmu_of_ours_built_from_other_sources_is_an_error_naming_the_rebuild(fmus, tmp_path):
    """One of ours built from other sources (here: another content hash, as a build of
    another version has) may not apply a configuration: an error naming the rebuild, not a
    package that silently runs other values (a third party's FMU: tests/orchestration/
    test_export.py)."""
    from agilesat.fmus.configure import OtherSources
    from agilesat.orchestration.mission import System

    stale = tmp_path / "SatelliteDynamics.fmu"
    with zipfile.ZipFile(fmus["SatelliteDynamics"]) as built, zipfile.ZipFile(stale, "w") as out:
        digest = built.read("resources/slavemodule.txt").decode().rpartition("_")[2]
        for item in built.namelist():
            data = built.read(item)
            if not item.startswith("binaries/"):
                data = data.replace(digest.encode(), b"0123456789ab")
            out.writestr(item.replace(digest, "0123456789ab"), data)
    one = System("one", stop=1.0, step=0.05)
    one.add("A", stale, rate0=[0.01, 0.0, 0.0])
    with pytest.raises(OtherSources, match="built by agilesat from other sources than these"):
        one.write(tmp_path / "one.ssp")
