"""One FMU instance in a co-simulation, on fmpy's ``FMU2Slave``.

fmpy loads the binary, binds the FMI functions and instantiates; the master's hot loop
calls the bound ctypes functions directly on preallocated buffers and checks every
returned status itself (:meth:`Instance.check`).  The FMU's log messages go to the run's
:class:`Log`, so that an error names the component, the call, the time and what the FMU
said.

Each FMU is unpacked and its binary loaded once per process, keyed by the content of the
file (SHA-256; a rebuilt FMU is a new one, a copy of the same file is the same one), and
every run instantiates its instances on it.  It is unpacked into agilesat's cache
(``fmus/<SHA-256>/`` under :func:`components.runtime.cache.cache_root`) once per content, its Python
compiled there at once (``__pycache__``), so that a new process takes the unpacked files
and the compiled code instead of unpacking and compiling them again: about 0.3 s of a
scan_pitch run (:func:`_extraction`).  Unpacking it again for each run would map
another copy of the binary each time that is never unmapped: pythonfmu's binary cannot be
unloaded (its GNU-unique C++ symbols make it NODELETE), so a campaign of thousands of runs
in one process would run out of memory mappings.  A run's components are reset and kept
for the next run with the same FMU and instance name, with fmpy's ``FMU2Slave`` and its
bound FMI functions (see :meth:`Instance.free`).
"""

from __future__ import annotations

import atexit
import compileall
import contextlib
import ctypes
import os
import shutil
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from fmpy import extract, platform, sharedLibraryExtension
from fmpy.fmi2 import (
    FMU2Slave,
    calloc,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    free,
)

from ...components.runtime.cache import cache_root, damage_of_tree, digest, warn, write_manifest
from ..system.description import Description

STATUS = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")


class FmiCallError(RuntimeError):
    """An FMI call returned Discard, Error or Fatal."""

    def __init__(self, instance: str, call: str, time: float, status: int, messages):
        self.instance, self.call, self.time, self.status = instance, call, time, status
        said = "".join(f"\n  {m}" for m in messages) or "\n  (the FMU logged nothing)"
        super().__init__(
            f"{instance}: {call} at t={time:.6g} s returned "
            f"fmi2{STATUS[status]}; the FMU said:{said}"
        )


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


class Instance(Description):
    """An FMU instance: its description, the loaded binary, raw FMI calls."""

    def __init__(self, name: str, path: Path, log: Log):
        super().__init__(name, path)
        self.log = log
        self._key = self.key
        self.unzip_dir = _unpacked(
            self._key, str(path), self.md.coSimulation.modelIdentifier, self.binaries
        )
        self.slave = _take_slave(self._key, name, self.md, self.unzip_dir)
        dll = self.slave.dll
        self.fmi2DoStep = dll.fmi2DoStep
        self.fmi2GetReal, self.fmi2SetReal = dll.fmi2GetReal, dll.fmi2SetReal
        self.fmi2GetInteger, self.fmi2SetInteger = dll.fmi2GetInteger, dll.fmi2SetInteger
        self.fmi2GetBoolean, self.fmi2SetBoolean = dll.fmi2GetBoolean, dll.fmi2SetBoolean
        self.component = None
        self.failed = False  # a call failed: the component is freed, not reused
        self.fatal = False  # after fmi2Fatal nothing more is called (FMI 2.0 §2.1.3)
        self._log_mark = 0

    def instantiate(self, logging_on: bool = False) -> None:
        """Instantiate, or take an idle component of this FMU and instance name that an
        earlier run left reset (fmi2Reset: as if just instantiated, FMI 2.0 section 2.1.6)."""
        self._mark()
        record = _take_idle(self._key, self.name)
        if record is not None:
            record.user = self
            self._record = record
            self.component = self.slave.component = record.pointer
            self.call("fmi2SetDebugLogging", int(logging_on), 0, None)
            return
        record = _Component(self)
        try:
            self.slave.instantiate(callbacks=record.callbacks, loggingOn=logging_on)
        except Exception:
            self.failed = True
            raise FmiCallError(
                self.name,
                "fmi2Instantiate",
                self.log.time,
                4,
                self.log.of(self.name, self._log_mark),
            ) from None
        self._record = record
        self.component = record.pointer = self.slave.component

    def call(self, name: str, *args) -> int:
        """Call an FMI function of this instance (component first) and check its status."""
        if self.fatal:
            raise FmiCallError(
                self.name, name, self.log.time, 4, ["not called: the FMU returned fmi2Fatal before"]
            )
        self._mark()
        status = getattr(self.slave.dll, name)(self.component, *args)
        self.check(status, name)
        return status

    def check(self, status: int, call: str) -> None:
        if status > 1:
            self.failed = True
            self.fatal = self.fatal or status == 4
            raise FmiCallError(
                self.name, call, self.log.time, status, self.log.of(self.name, self._log_mark)
            )

    def _mark(self):
        self._log_mark = len(self.log.entries)

    def free(self) -> None:
        """Free the instance (never raises); the unpacked FMU stays loaded for the next run,
        and a component whose calls all succeeded is reset and kept for it (pythonfmu 0.7.0
        leaks about 1 KB of Python objects per fmi2Instantiate in its findClass; see
        NTNU-IHB/PythonFMU#229).

        pythonfmu puts the FMU's resources directory first on ``sys.path`` at every
        instantiation and leaves it there; it is taken out again, or ``sys.path`` would grow
        with every run and the host would import the FMU's copies (of pythonfmu, for one).
        """
        try:
            if self.fatal:  # after fmi2Fatal: not even freed, the library stays loaded
                self.component = None
            elif self.component is not None:
                component, self.component = self.component, None
                if self.failed or not _keep_idle(
                    self._key, self.name, self._record, self.slave.dll.fmi2Reset
                ):
                    self.slave.fmi2FreeInstance(component)
            if not self.fatal:
                _keep_slave(self._key, self.name, self.slave)
        except Exception:  # noqa: BLE001 - cleanup after an FMU failure
            pass
        resources = str(Path(self.unzip_dir) / "resources")
        sys.path[:] = [entry for entry in sys.path if entry.rstrip("/") != resources]
        sys.path_importer_cache.pop(resources, None)


# -- components kept for the next run ---------------------------------------------------
class _Component:
    """An instantiated component, its callbacks, and the Instance now using it."""

    def __init__(self, user: Instance):
        self.user, self.pointer = user, None
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._logger)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)

    def _logger(self, _env, _name, status, category, message):
        user = self.user
        if user is not None:
            user.log.add(
                user.name,
                status,
                (category or b"").decode(errors="replace"),
                (message or b"").decode(errors="replace"),
            )


_idle: dict[tuple[str, str], list[_Component]] = {}  # (content key, name) -> reset ones
_IDLE_PER_NAME = 4


def _take_idle(key: str, name: str) -> _Component | None:
    with _lock:
        idle = _idle.get((key, name))
        return idle.pop() if idle else None


def _keep_idle(key: str, name: str, record: _Component, reset) -> bool:
    """Reset the component and keep it for a later run; False if it is not kept."""
    with _lock:
        if len(_idle.get((key, name), ())) >= _IDLE_PER_NAME:
            return False
    record.user = None
    if reset(record.pointer) != 0:
        return False
    with _lock:
        _idle.setdefault((key, name), []).append(record)
    return True


# fmpy binds each of the ~70 FMI functions of a new FMU2Slave through inspect.signature
# (~1.5 ms per FMU); a slave holds nothing of a run but its component pointer, so it is kept
# for the next Instance of the same FMU and name (its reference to the library with it).
_slaves: dict[tuple[str, str], list[FMU2Slave]] = {}


def _take_slave(key: str, name: str, md, unzip_dir: str) -> FMU2Slave:
    with _lock:
        kept = _slaves.get((key, name))
        if kept:
            return kept.pop()
    return FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzip_dir,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName=name,
    )


def _keep_slave(key: str, name: str, slave: FMU2Slave) -> None:
    slave.component = slave.callbacks = None
    with _lock:
        kept = _slaves.setdefault((key, name), [])
        if len(kept) < _IDLE_PER_NAME:
            kept.append(slave)
            return
    slave.freeLibrary()


# -- one load per FMU file content, per process -----------------------------------------
_lock = threading.Lock()
_unpacked_dirs: dict[str, str] = {}  # content key -> extraction directory
_pinned: list = []  # one handle per loaded binary: never unloaded
_temporary: list[str] = []  # extractions outside the cache, removed at exit
_EXTRACTIONS_KEPT = 64  # in the cache, the most recently used


def _unpacked(key: str, path: str, model_identifier: str, binaries: dict) -> str:
    """The extraction directory of the FMU with content ``key``; its binary stays loaded.
    ``binaries``: {file: SHA-256} the FMU declares (:func:`_check_binaries`)."""
    with _lock:
        directory = _unpacked_dirs.get(key)
        if directory is None:
            directory = _extraction(key, path, binaries)
            library = Path(
                directory, "binaries", platform, model_identifier + sharedLibraryExtension
            )
            if library.exists():
                _pinned.append(ctypes.CDLL(str(library)))
            _unpacked_dirs[key] = directory
        return directory


def _extraction(key: str, path: str, binaries: dict) -> str:
    """The FMU with content ``key`` unpacked in the cache: unpacked under a temporary name
    and renamed, so that a directory there is always complete (of two processes unpacking
    at once, the second takes the first one's), with a manifest of every file's SHA-256
    (its binaries checked against the FMU's own list first, :func:`_check_binaries`).
    A directory there is checked against its manifest before anything is loaded from it: a
    damaged one (a binary cut short or zeroed, bytecode or a source changed) is unpacked
    again, with a warning naming it.  Where the cache cannot be written, a temporary
    directory removed at exit, as fmpy unpacks."""
    root = cache_root() / "fmus"
    target = root / key
    try:
        if target.is_dir() and (what := damage_of_tree(target)):
            warn(target, what, "unpacking the FMU again")
            aside = root / f".{key}.damaged.{os.getpid()}"
            with contextlib.suppress(FileNotFoundError):  # another process moved it first
                os.rename(target, aside)
            shutil.rmtree(aside, ignore_errors=True)
        if not target.is_dir():
            root.mkdir(parents=True, exist_ok=True)
            partial = tempfile.mkdtemp(prefix=f".{key}.", dir=root)
            try:
                extract(path, partial)
                _check_binaries(path, partial, binaries)
                # compiled here, as Python would beside the sources at the first import
                # (unless PYTHONDONTWRITEBYTECODE: this is our cache, not a source tree)
                compileall.compile_dir(Path(partial, "resources"), quiet=2, workers=1)
                write_manifest(Path(partial))
            except BaseException:
                shutil.rmtree(partial, ignore_errors=True)
                raise
            try:
                os.rename(partial, target)
            except OSError:  # another process renamed its own first
                shutil.rmtree(partial, ignore_errors=True)
                if not target.is_dir():
                    raise
            _prune(root)
        os.utime(target)  # most recently used
        return str(target)
    except OSError as exc:
        if target.is_dir():
            warn(target, str(exc), "unpacking the FMU in a temporary directory")
        directory = extract(path)
        _check_binaries(path, directory, binaries)
        _temporary.append(str(directory))
        return str(directory)


class DamagedFmuError(RuntimeError):
    """A binary of an FMU is not what its modelDescription.xml says it is."""


def _check_binaries(path: str, directory: str, binaries: dict) -> None:
    """DamagedFmuError if a binary the FMU lists ({file: SHA-256}, our FMUs' vendor
    annotation) does not have that content: loading a damaged shared library crashes
    the process."""
    for name, recorded in binaries.items():
        file = Path(directory, name)
        if not file.is_file() or digest(file) != recorded:
            shutil.rmtree(directory, ignore_errors=True)
            raise DamagedFmuError(
                f"{name} in {path} does not match the SHA-256 its modelDescription.xml "
                "records: the FMU is damaged (build or export it again); not loaded"
            )


def _prune(root: Path) -> None:
    """Remove all but the :data:`_EXTRACTIONS_KEPT` most recently used extractions, and
    the partial ones of processes killed an hour ago or more."""
    try:
        entries = sorted(root.iterdir(), key=lambda p: p.stat().st_mtime, reverse=True)
    except OSError:
        return
    now = time.time()
    complete = [p for p in entries if not p.name.startswith(".")]
    stale = [p for p in entries if p.name.startswith(".") and now - p.stat().st_mtime > 3600]
    for old in complete[_EXTRACTIONS_KEPT:] + stale:
        if str(old) not in _unpacked_dirs.values():
            shutil.rmtree(old, ignore_errors=True)


@atexit.register
def _remove_unpacked() -> None:
    for directory in _temporary:
        shutil.rmtree(directory, ignore_errors=True)
