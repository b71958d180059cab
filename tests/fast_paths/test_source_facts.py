"""The sources' facts (classes, relative imports) are parsed once per content: a warm
run's staleness check and an FMU's start parse nothing (issue 10, latency)."""

import ast
import hashlib
import json
import types

import pytest

from agilesat.fmus import build, source_facts
from helpers import run_python

SOURCE = "from .model import Model\n\n\nclass Wheel(Model):\n    pass\n"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache directory, read afresh (as by a new process)."""
    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path / "cache"))
    source_facts._memo.cache_clear()
    yield tmp_path / "cache"
    source_facts._memo.cache_clear()


def _no_parsing(monkeypatch):
    def parse(*args, **kwargs):
        raise AssertionError("parsed")

    monkeypatch.setattr(ast, "parse", parse)


def test_a_source_is_parsed_once_per_content_and_remembered(cache, monkeypatch):
    found = source_facts.facts(SOURCE, "wheel.py")
    assert found == {"classes": [["Wheel", ["Model"]]], "imports": [[1, "model", ["Model"]]]}
    assert (cache / "source_facts.json").is_file()
    source_facts._memo.cache_clear()  # a new process
    with monkeypatch.context() as patch:
        _no_parsing(patch)
        assert source_facts.facts(SOURCE, "wheel.py") == found
        with pytest.raises(AssertionError, match="parsed"):  # changed content: parsed again
            source_facts.facts(SOURCE.replace("Wheel", "Gyro"), "wheel.py")
    assert source_facts.facts(SOURCE.replace("Wheel", "Gyro"), "wheel.py")["classes"] == [
        ["Gyro", ["Model"]]
    ]


KEY = hashlib.sha256(SOURCE.encode()).hexdigest()


@pytest.mark.parametrize(
    "content",
    [
        "not json",
        json.dumps([1]),
        json.dumps({"version": "another parser's", "facts": {}}),
        json.dumps({"version": source_facts.VERSION, "facts": "abc"}),
        json.dumps({"version": source_facts.VERSION, "facts": None}),
        json.dumps({"version": source_facts.VERSION, "facts": {KEY: {"imports": []}}}),
        json.dumps({"version": source_facts.VERSION, "facts": {KEY: [1]}}),
        json.dumps(
            {"version": source_facts.VERSION, "facts": {KEY: {"classes": [["X"]], "imports": []}}}
        ),
        json.dumps(
            {
                "version": source_facts.VERSION,
                "facts": {KEY: {"classes": [], "imports": [["1", "model", ["Model"]]]}},
            }
        ),
    ],
)
def test_a_cache_that_is_not_ours_is_parsed_over(cache, content):
    cache.mkdir()
    (cache / "source_facts.json").write_text(content)
    assert source_facts.facts(SOURCE, "wheel.py")["classes"] == [["Wheel", ["Model"]]]
    kept = json.loads((cache / "source_facts.json").read_text())
    assert kept["version"] == source_facts.VERSION and KEY in kept["facts"]


def test_an_unwritable_cache_parses_as_before(tmp_path, monkeypatch):
    (tmp_path / "file").write_text("")
    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path / "file" / "cache"))
    source_facts._memo.cache_clear()
    try:
        assert source_facts.facts(SOURCE, "wheel.py")["imports"] == [[1, "model", ["Model"]]]
    finally:
        source_facts._memo.cache_clear()


def test_the_cache_keeps_the_newest_entries(cache, monkeypatch):
    monkeypatch.setattr(source_facts, "MAX_ENTRIES", 2)
    for k in range(3):
        source_facts.facts(f"x = {k}\n", "x.py")
    kept = json.loads((cache / "source_facts.json").read_text())["facts"]
    assert len(kept) == 2 and source_facts._memo() == kept


def test_a_warm_staleness_check_parses_nothing(cache):
    """In a new process with the cache filled: the same registry and digests, no source
    parsed (``ast.parse`` is refused before the registry is read)."""
    import agilesat.fmus as fmus

    registry = fmus._find_fmus(fmus._COMPONENTS)
    digests = {name: build._sources(name)[1] for name in registry}
    code = (
        "import ast, json, os, sys\n"
        "os.environ['AGILESAT_CACHE_DIR'] = sys.argv[1]\n"
        "def parse(*args, **kwargs):\n"
        "    raise AssertionError('parsed')\n"
        "ast.parse = parse\n"
        "from agilesat.fmus import FMUS, build\n"
        "print(json.dumps({name: build._sources(name)[1] for name in FMUS}))\n"
    )
    result = run_python(code, cache)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout) == digests


def test_a_model_module_named_otherwise_is_found_through_the_registry(cache, tmp_path, monkeypatch):
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
