"""A run's output directory read back, for the commands that read one afterwards (``agilesat
report``, ``agilesat export-ephemeris``): its summary, its results, the target it ran, and
what the run's system said of its variables (descriptions) and parameters (values as the
run had them: the run's ``--set`` over the system's values over the FMU's start values).
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

from ..output.results import Results


class RunDirectory:
    """``agilesat run``'s output directory ``path`` (summary.json and results)."""

    def __init__(self, path):
        self.path = Path(path)
        summary = self.path / "summary.json"
        if not summary.is_file():
            raise FileNotFoundError(
                f"{self.path}: not a run directory (no summary.json; `agilesat run ... --out "
                f"{self.path}` writes one)"
            )
        self.summary = json.loads(summary.read_text(encoding="utf-8"))
        self.results = Results.load(self.path)

    @property
    def label(self) -> str:
        """What ran: "scenario:variant", or the system file's name."""
        scenario, variant = self.summary.get("scenario"), self.summary.get("variant")
        if scenario:
            return f"{scenario}:{variant}" if variant else str(scenario)
        return Path(str(self.summary.get("system", self.path.name))).name

    @functools.cached_property
    def target(self):
        """The resolved target (:func:`..mission.targets.resolve`) of a scenario run, or
        None (a system file, or a scenario this installation does not have)."""
        from ..mission.targets import resolve

        if not self.summary.get("scenario"):
            return None
        try:
            return resolve(self.label)
        except (KeyError, ValueError, ImportError):
            return None

    @property
    def scenario(self):
        return None if self.target is None else self.target.scenario

    @property
    def variant(self) -> str | None:
        return self.summary.get("variant")

    @functools.cached_property
    def system(self):
        """The run's :class:`..system.ssp.SystemFile` (FMUs not built), or None if it can
        no longer be read."""
        try:
            if self.target is not None:
                return self.target.system_file(build=False)
            from ..system.ssp import read_system

            return read_system(Path(self.summary["system"]))
        except (KeyError, ValueError, OSError):
            return None

    @functools.cached_property
    def _variables(self):
        return variables_of(self.system)

    def variable(self, column: str):
        """The model variable of a column ("A.x[2]") as the FMU's model description has it
        (its ``description``, ``start``, ``unit``), or None."""
        return self._variables(column)

    def description(self, column: str) -> str | None:
        found = self.variable(column)
        return getattr(found, "description", None) or None

    def parameter(self, name: str):
        """A parameter's value ("A.x[2]") as the run had it: its ``--set``, else the
        system's, else the FMU's start value; None if none is known."""
        overrides = self.summary.get("parameters") or {}
        if name in overrides:
            return overrides[name]["value"]
        instance, _, variable = name.partition(".")
        for p in self.system.parameters if self.system is not None else ():
            if p.component == instance and p.name == variable:
                return p.value
        found = self.variable(name)
        return None if found is None else found.start


def variables_of(system):
    """A function of a column ("A.x[2]") giving its model variable as the FMU's model
    description in ``system`` (a :class:`..system.ssp.SystemFile`, or None) has it, or
    None.  The model descriptions are read without loading the FMUs."""
    from ..system.description import Description

    found = {}
    for component in system.components if system is not None else ():
        try:
            found[component.name] = Description(component.name, component.source).variables
        except (OSError, ValueError):
            continue

    def variable(column: str):
        instance, _, name = column.partition(".")
        return found.get(instance, {}).get(name)

    return variable
