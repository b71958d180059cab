"""The sources' facts (classes, relative imports) are parsed once per content and process:
the staleness check of every FMU reads the shared modules once."""

import ast
import types

import pytest

from agilesat.fmus import build, source_facts
from helpers import run_python

SOURCE = "from .model import Model\n\n\nclass Wheel(Model):\n    pass\n"


def test_a_source_is_parsed_once_per_content(monkeypatch):
    found = source_facts.facts(SOURCE, "wheel.py")
    assert found == {"classes": [["Wheel", ["Model"]]], "imports": [[1, "model", ["Model"]]]}
    parsed = []
    monkeypatch.setattr(ast, "parse", lambda *args: parsed.append(args) or ast.Module([], []))
    assert source_facts.facts(SOURCE, "wheel.py") == found and parsed == []
    source_facts.facts(SOURCE.replace("Wheel", "Gyro"), "wheel.py")  # changed: parsed again
    assert len(parsed) == 1


def test_the_staleness_check_of_every_fmu_parses_each_module_once(monkeypatch):
    import agilesat.fmus as fmus

    source_facts.facts.cache_clear()
    parse, parsed = ast.parse, []
    monkeypatch.setattr(ast, "parse", lambda source, name: parsed.append(name) or parse(source))
    for name in fmus._find_fmus(fmus._COMPONENTS):
        build._sources(name)
    assert parsed and len(parsed) == len(set(parsed))


def test_a_model_module_named_otherwise_is_found_through_the_registry(tmp_path, monkeypatch):
    """``sensor_3d.py`` defines ``Sensor3d``, whose snake case is ``sensor3d``."""
    import agilesat.fmus as fmus

    class Model:
        pass

    class Sensor3d(Model):
        pass

    (tmp_path / "sensor_3d.py").write_text("class Sensor3d(Model):\n    pass\n")
    monkeypatch.setattr(fmus, "_COMPONENTS", tmp_path)
    monkeypatch.delitem(vars(fmus), "FMUS", raising=False)  # the registry read afresh
    imported = []

    def import_module(name):
        imported.append(name)
        return types.SimpleNamespace(Sensor3d=Sensor3d)

    monkeypatch.setattr(fmus.importlib, "import_module", import_module)
    assert fmus.model_class("Sensor3d") is Sensor3d
    assert imported == ["agilesat.components.sensor_3d"]
    with pytest.raises(KeyError, match="unknown FMU 'Sensor3D'; FMUs: Sensor3d"):
        fmus.model_class("Sensor3D")


@pytest.mark.slow  # a fresh interpreter loading an FMU: over 1 s
def test_an_fmu_starts_without_reading_the_registry(fmus):
    """The FMU's slave class comes from its module by the naming rule: the FMU's copy of
    ``fmus`` never reads ``FMUS`` (every component module parsed, at each start)."""
    code = (
        "import sys\n"
        "from fmpy import extract, read_model_description\n"
        "from fmpy.fmi2 import FMU2Slave\n"
        "md = read_model_description(sys.argv[1])\n"
        "instance = FMU2Slave(guid=md.guid, unzipDirectory=extract(sys.argv[1]),\n"
        "                     modelIdentifier=md.coSimulation.modelIdentifier, instanceName='a')\n"
        "instance.instantiate()\n"
        "registries = [m for name, m in sys.modules.items()\n"
        "              if name.startswith('agilesat_') and name.endswith('.fmus')]\n"
        "assert registries and not [m for m in registries if 'FMUS' in vars(m)], registries\n"
        "instance.freeInstance()\n"
    )
    result = run_python(code, fmus["CmgCluster"])
    assert result.returncode == 0, result.stderr
