"""One FMU instance in a co-simulation, on fmpy's ``FMU2Slave``.

fmpy loads the binary, binds the FMI functions and instantiates; the master's hot loop
calls the bound ctypes functions directly on preallocated buffers and checks every
returned status itself (:meth:`Instance.check`).  The FMU's log messages go to the run's
:class:`Log`, so that an error names the component, the call, the time and what the FMU
said.
"""
from __future__ import annotations

import shutil
import sys
import zipfile
from dataclasses import dataclass
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import (FMU2Slave, calloc, fmi2CallbackAllocateMemoryTYPE,
                       fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                       fmi2CallbackLoggerTYPE, free)
from lxml import etree

STATUS = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")
AGILESAT_TOOL = "agilesat"


class FmiCallError(RuntimeError):
    """An FMI call returned Discard, Error or Fatal."""

    def __init__(self, instance: str, call: str, time: float, status: int, messages):
        self.instance, self.call, self.time, self.status = instance, call, time, status
        said = "".join(f"\n  {m}" for m in messages) or "\n  (the FMU logged nothing)"
        super().__init__(f"{instance}: {call} at t={time:.6g} s returned "
                         f"fmi2{STATUS[status]}; the FMU said:{said}")


@dataclass
class LogEntry:
    time: float
    instance: str
    status: int
    category: str
    message: str

    def __str__(self):
        return f"t={self.time:.6g} s {self.instance} [{STATUS[self.status]}] {self.message}"


class Log:
    """All messages of a run's FMUs, with the simulation time they were logged at."""

    def __init__(self, echo=None):
        self.entries: list[LogEntry] = []
        self.time = 0.0
        self.echo = echo  # called with each entry of status Warning or worse

    def add(self, instance, status, category, message):
        entry = LogEntry(self.time, instance, status, category, message)
        self.entries.append(entry)
        if self.echo and status >= 1:
            self.echo(entry)

    def of(self, instance, since: int = 0) -> list[str]:
        return [e.message for e in self.entries[since:] if e.instance == instance]


class Description:
    """What the model description of an FMU in a system says: variables by name, output
    dependencies, optional inputs.  Nothing is loaded."""

    def __init__(self, name: str, path: Path):
        self.name, self.path = name, Path(path)
        self.md = read_model_description(str(path))
        if self.md.coSimulation is None:
            raise ValueError(f"{path}: not a co-simulation FMU")
        self.variables = {v.name: v for v in self.md.modelVariables}
        #: optional input -> what its default means, as our FMUs declare them
        #: (VendorAnnotations; every other input is required); None: not our FMU
        self.optional_inputs = _optional_inputs(path)
        self.feedthrough = _dependencies(self.md.outputs, self.md.modelVariables)
        self.initial_feedthrough = _dependencies(self.md.initialUnknowns, self.md.modelVariables)
        #: output names in value-reference order
        self.outputs = [v.name for v in sorted(self.md.modelVariables,
                                               key=lambda v: v.valueReference)
                        if v.causality == "output"]


class Instance(Description):
    """An FMU instance: its description, the loaded binary, raw FMI calls."""

    def __init__(self, name: str, path: Path, log: Log):
        super().__init__(name, path)
        self.log = log
        self.unzip_dir = extract(str(path))
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzip_dir,
                               modelIdentifier=self.md.coSimulation.modelIdentifier,
                               instanceName=name)
        dll = self.slave.dll
        self.fmi2DoStep = dll.fmi2DoStep
        self.fmi2GetReal, self.fmi2SetReal = dll.fmi2GetReal, dll.fmi2SetReal
        self.fmi2GetInteger, self.fmi2SetInteger = dll.fmi2GetInteger, dll.fmi2SetInteger
        self.fmi2GetBoolean, self.fmi2SetBoolean = dll.fmi2GetBoolean, dll.fmi2SetBoolean
        self.component = None
        self.fatal = False   # after fmi2Fatal nothing more is called (FMI 2.0 §2.1.3)
        self._log_mark = 0

    def instantiate(self, logging_on: bool = False) -> None:
        def logger(_env, _name, status, category, message):
            self.log.add(self.name, status, (category or b"").decode(errors="replace"),
                         (message or b"").decode(errors="replace"))

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self._callbacks = callbacks  # keep alive while the FMU lives
        self._mark()
        try:
            self.slave.instantiate(callbacks=callbacks, loggingOn=logging_on)
        except Exception:
            raise FmiCallError(self.name, "fmi2Instantiate", self.log.time, 4,
                               self.log.of(self.name, self._log_mark)) from None
        self.component = self.slave.component

    def call(self, name: str, *args) -> int:
        """Call an FMI function of this instance (component first) and check its status."""
        if self.fatal:
            raise FmiCallError(self.name, name, self.log.time, 4,
                               ["not called: the FMU returned fmi2Fatal before"])
        self._mark()
        status = getattr(self.slave.dll, name)(self.component, *args)
        self.check(status, name)
        return status

    def check(self, status: int, call: str) -> None:
        if status > 1:
            self.fatal = self.fatal or status == 4
            raise FmiCallError(self.name, call, self.log.time, status,
                               self.log.of(self.name, self._log_mark))

    def _mark(self):
        self._log_mark = len(self.log.entries)

    def free(self) -> None:
        """Free the instance and delete the extracted FMU (never raises).

        pythonfmu puts the FMU's resources directory first on ``sys.path`` and leaves it
        there; it is taken out again, or the host would import the FMU's copies (of
        pythonfmu, for one) from a deleted directory.
        """
        try:
            if not self.fatal:  # after fmi2Fatal: not even freed, the library stays loaded
                if self.component is not None:
                    self.slave.fmi2FreeInstance(self.component)
                    self.component = None
                self.slave.freeLibrary()
        except Exception:  # noqa: BLE001 - cleanup after an FMU failure
            pass
        resources = str(Path(self.unzip_dir) / "resources")
        sys.path[:] = [entry for entry in sys.path if entry.rstrip("/") != resources]
        sys.path_importer_cache.pop(resources, None)
        shutil.rmtree(self.unzip_dir, ignore_errors=True)


def _dependencies(unknowns, variables) -> dict[str, set[str] | None]:
    """Output name -> names of the variables it depends on (None: depends on all)."""
    result = {}
    for unknown in unknowns:
        deps = unknown.dependencies
        result[unknown.variable.name] = None if deps is None else {d.name for d in deps}
    return result


def _optional_inputs(path: Path) -> dict[str, str] | None:
    """{optional input: what its default means} an agilesat FMU declares (VendorAnnotations);
    None: nothing declared."""
    with zipfile.ZipFile(path) as archive:
        root = etree.fromstring(archive.read("modelDescription.xml"))
    tool = root.find(f"VendorAnnotations/Tool[@name='{AGILESAT_TOOL}']")
    if tool is None:
        return None
    return {e.get("name"): e.get("optional") for e in tool.findall("Inputs/Input")
            if e.get("optional") is not None}

