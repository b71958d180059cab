"""Repository-level promises: CI runs the README's test command; every model is an FMU."""
import importlib
import re

from agilesat.fmus import FMUS, model_class, slave_class
from helpers import ROOT


def test_ci_runs_the_readme_test_command():
    readme = (ROOT / "README.md").read_text()
    commands = re.findall(r"```\n(python3 -m venv[^\n]*)\n```", readme)
    assert len(commands) == 2, commands   # set up and run; set up and test
    test_command = next(c for c in commands if "pytest" in c)
    assert test_command in (ROOT / ".ci" / "run").read_text().splitlines()


def test_every_component_model_is_an_fmu_named_after_its_module():
    """The registry is read from the sources: it must be what importing them finds."""
    from agilesat.components.model import Model
    found = {}
    for path in sorted((ROOT / "components").glob("*.py")):
        module = importlib.import_module(f"agilesat.components.{path.stem}")
        found.update({name: path.stem for name, obj in vars(module).items()
                      if isinstance(obj, type) and issubclass(obj, Model) and obj is not Model
                      and obj.__module__ == module.__name__})
    assert FMUS == found
    assert all(model_class(name).VARIABLES for name in FMUS)
    assert all(slave_class(name).model_class is model_class(name) for name in FMUS)
