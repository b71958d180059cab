"""Repository-level promises: CI runs the README's test command; every model is an FMU; the
public names, the command and the pytest plugin are where users find them."""

import importlib
import re

from agilesat.fmus import FMUS, model_class, slave_class
from helpers import ROOT


def test_ci_runs_the_readme_test_command():
    """The README's test command is CI's set-up and then ``.venv/bin/python -m pytest``;
    .ci/run runs that set-up verbatim and the two layers the whole ``pytest`` is made of:
    ``-m "not slow"`` (stage 1, with the checks) and ``-m slow`` (stage 2)."""
    readme = (ROOT / "README.md").read_text()
    commands = re.findall(r"```\n((?:apt-get [^\n]*&& )?python3 -m venv[^\n]*)\n```", readme)
    test_command = next(c for c in commands if "pytest" in c)
    setup, _, pytest_command = test_command.rpartition(" && ")
    assert pytest_command == ".venv/bin/python -m pytest", test_command
    lines = [line.strip() for line in (ROOT / ".ci" / "run").read_text().splitlines()]
    assert setup in lines
    stages = [line for line in lines if line.startswith(pytest_command)]
    assert stages == [f'{pytest_command} -m "not slow"', f"{pytest_command} -m slow"]


def test_the_public_api_the_command_and_the_plugin_resolve():
    """``from agilesat.orchestration import ...`` (each name of ``__all__``), the
    ``agilesat`` command and the ``agilesat`` pytest plugin, as installed."""
    from importlib import metadata

    import agilesat.orchestration as api

    for name in api.__all__:
        assert getattr(api, name).__name__ == name
    (script,) = metadata.entry_points(group="console_scripts", name="agilesat")
    assert script.load() is importlib.import_module("agilesat.orchestration.cli").main
    (plugin,) = metadata.entry_points(group="pytest11", name="agilesat")
    assert hasattr(plugin.load(), "agilesat_run")


def test_every_component_model_is_an_fmu_named_after_its_module():
    """The registry is read from the sources: it must be what importing them finds."""
    from agilesat.components.model import Model

    found = {}
    for path in sorted((ROOT / "components").glob("*.py")):
        module = importlib.import_module(f"agilesat.components.{path.stem}")
        found.update(
            {
                name: path.stem
                for name, obj in vars(module).items()
                if isinstance(obj, type)
                and issubclass(obj, Model)
                and obj is not Model
                and obj.__module__ == module.__name__
            }
        )
    assert FMUS == found
    assert all(model_class(name).VARIABLES for name in FMUS)
    assert all(slave_class(name).model_class is model_class(name) for name in FMUS)


def _tracked_text_files():
    import subprocess

    names = subprocess.run(
        ["git", "ls-files", "*.py", "*.md", "*.c", "*.toml"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    return {
        name: (ROOT / name).read_text(encoding="utf-8") for name in names if (ROOT / name).is_file()
    }


def test_references_resolve_inside_the_repository():
    """Papers are cited by the keys DESIGN.md's References define, design sections by
    headings DESIGN.md has; nothing points at files outside the repository."""
    design = (ROOT / "DESIGN.md").read_text(encoding="utf-8")
    references = design.split("\n## References\n", 1)[1]
    keys = set(re.findall(r"\*\*\[([A-Z][a-z]+ \d{4})\]\*\*", references))
    assert keys == {
        "Zhao 2016",
        "Chang 2015",
        "Liang 2019",
        "Ecss 2008",
        "Esa 2011",
        "Wilks 1941",
        "Clopper 1934",
        "Ville 1939",
        "Howard 2021",
        "Ramdas 2023",
        "Hoeffding 1963",
        "Berger 1982",
        "Likins 1971",
        "Hablani 1982",
        "Blevins 1979",
        "Das 1988",
        "Mos 1985",
        "Buckingham 1975",
        "Masterson 2002",
        "Alken 2021",
        "Biagiotti 2008",
        "Camillo 1980",
        "Crassidis 2012",
        "Farrenkopf 1978",
        "Kopp 2011",
        "Lefferts 1982",
        "Markley 2014",
        "Meeus 1998",
        "Steele 2014",
        "Vallado 2013",
        "Wertz 1978",
    }
    sections = set(re.findall(r"^#+ (\d+(?:\.\d+)?)\.? ", design, re.M))
    for name, text in _tracked_text_files().items():
        if name != "tests/test_repository.py":  # which spells them out
            assert not re.search(r"\.\./shared|/work/|\bseeds? ?\d{3}", text), name
        for key in re.findall(r"\[([A-Z][a-z]+ (?:19|20)\d\d)\]", text):
            assert key in keys, f"{name}: [{key}] is not in DESIGN.md's References"
        for section in re.findall(r"DESIGN(?:\.md)?(?:'s)? §(\d+(?:\.\d+)?)", text):
            assert section in sections, f"{name}: DESIGN.md has no §{section}"
