"""What ``agilesat run|info|export|campaign TARGET`` runs: :func:`resolve`.

TARGET is, optionally with ``:variant`` after a scenario:

- a scenario by name: a shipped one (a module of ``agilesat.orchestration.scenarios`` that
  defines ``SCENARIO``) or one a package registers under the entry point group
  ``agilesat.scenarios`` (``name = "my_team.missions.detumble"``, or ``module:attribute``);
- a mission file, ``path/to/mission.py``: the module's ``SCENARIO`` (or its only
  :class:`~.scenario.Scenario`); its directory is put on ``sys.path``, so it may import the
  modules beside it;
- a module on ``sys.path`` by its dotted name, ``my_team.missions.detumble``;
- an ``.ssd`` / ``.ssp`` system file;
- one FMU, an ``.fmu`` file or one of ours by name: run alone at its defaults (inputs
  held at their start values unless given with ``--set``).
"""

from __future__ import annotations

import ast
import functools
import hashlib
import importlib
import importlib.util
import sys
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

from ..system.parameters import did_you_mean
from ..system.ssp import read_system
from .scenario import Scenario
from .system import System

GROUP = "agilesat.scenarios"
SHIPPED_PACKAGE = "agilesat.orchestration.scenarios"
SHIPPED_DIR = Path(__file__).resolve().parent.parent / "scenarios"


@dataclass
class Target:
    """A resolved target: a scenario and variant, a system (built in Python), or a system
    file (``path``)."""

    text: str
    scenario: Scenario | None = None
    variant: str | None = None
    system: System | None = None
    path: Path | None = None
    #: how it was named ("scenario", "mission file", "module", "system file", "FMU") and
    #: the file that defines it, if there is one
    kind: str = ""
    source: Path | None = None

    def system_file(self, build: bool = True):
        """The :class:`..system.ssp.SystemFile` it runs."""
        if self.scenario is not None:
            return self.scenario.system_file(self.variant, build)
        if self.system is not None:
            return self.system.system_file(build)
        return read_system(self.path)

    @property
    def label(self) -> str:
        if self.scenario is not None:
            return self.scenario.name + (f":{self.variant}" if self.variant else "")
        return self.text

    def record(self) -> dict:
        """What summary.json and campaign.json keep of it, to find it again from any folder
        (:func:`found_again`): the target as given, how it was named, the scenario and
        variant, the absolute path of the file that defines it and the SHA-256 of that
        file's content."""
        source = self.source if self.source is not None and self.source.is_file() else None
        return {
            "text": self.text,
            "kind": self.kind,
            "scenario": self.scenario.name if self.scenario is not None else None,
            "variant": self.variant,
            "path": None if source is None else str(source),
            "sha256": None if source is None else sha256(source),
        }


@functools.cache
def shipped() -> tuple[str, ...]:
    """The shipped scenarios: modules of the scenarios package that define ``SCENARIO``
    (read from the sources once per process, nothing imported)."""
    names = []
    for path in sorted(SHIPPED_DIR.glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        if any(
            isinstance(node, ast.Assign)
            and any(getattr(target, "id", None) == "SCENARIO" for target in node.targets)
            for node in tree.body
        ):
            names.append(path.stem)
    return tuple(names)


def registered() -> dict[str, metadata.EntryPoint]:
    """The scenarios packages register (entry point group ``agilesat.scenarios``)."""
    return {e.name: e for e in metadata.entry_points(group=GROUP)}


def names() -> list[str]:
    """Every scenario by name: the shipped ones, then the registered ones."""
    found = shipped()
    return [*found, *(n for n in registered() if n not in found)]


def scenario(name: str) -> Scenario:
    """A scenario by name (shipped or registered; the package's entry points are read only
    for a name that is not shipped)."""
    if name in shipped():
        return _scenario_of(importlib.import_module(f"{SHIPPED_PACKAGE}.{name}"), name)
    entries = registered()
    if name in entries:
        loaded = entries[name].load()
        return loaded if isinstance(loaded, Scenario) else _scenario_of(loaded, name)
    raise KeyError(
        f"unknown scenario {name!r}"
        + did_you_mean(name, names())
        + f" (scenarios: {', '.join(names())})"
    )


def resolve(target) -> Target:
    """A target (see the module) as a :class:`Target`; a KeyError with the closest names
    for one that is none of them, or a variant the scenario does not have."""
    if isinstance(target, Target):
        return target
    if isinstance(target, Scenario):  # made in Python: its system's file, if one
        return Target(target.name, scenario=target, kind="mission file", source=_file(target))
    if isinstance(target, System):
        return Target(target.name, system=target, kind="system")
    text = str(target)
    name, variant = _split(text)
    suffix = Path(name).suffix
    if suffix in (".ssd", ".ssp") and not variant:
        return Target(text, path=Path(text), kind="system file", source=Path(text).resolve())
    if suffix == ".fmu" and not variant:
        return Target(text, system=single(Path(text)), kind="FMU", source=Path(text).resolve())
    if suffix == ".py":
        kind, source = "mission file", Path(name).resolve()
        found = load_file(source)
    elif name in shipped() or name in registered():
        found = scenario(name)
        kind, source = "scenario", _module_file(name)
    elif "." in name and _importable(name):
        found = _scenario_of(importlib.import_module(name), name)
        kind, source = "module", _origin_of(name)
    elif not variant and _ours(name):
        return Target(text, system=single(name), kind="FMU")
    else:
        from ...fmus import FMUS

        known = names()
        raise KeyError(
            f"{text!r} is not a scenario ({', '.join(known)}), a mission file (.py), a "
            "module, a system file (.ssd/.ssp) or an FMU (.fmu, or one of ours by name: "
            f"{', '.join(FMUS)})" + did_you_mean(name, [*known, *FMUS])
        )
    found.variant(variant)  # a variant it does not have: KeyError
    return Target(text, found, variant or None, kind=kind, source=source)


def sha256(path: Path) -> str:
    """The SHA-256 of a file's content."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _file(found: Scenario) -> Path | None:
    """The file a scenario made in Python was built in: its system's."""
    path = Path(found.system.file)
    return path.resolve() if path.suffix == ".py" and path.is_file() else None


def _module_file(name: str) -> Path | None:
    """The module file of a scenario by name (shipped, or a package's entry point)."""
    if name in shipped():
        return SHIPPED_DIR / f"{name}.py"
    return _origin_of(registered()[name].module)


def _origin_of(module: str) -> Path | None:
    try:
        spec = importlib.util.find_spec(module)
    except (ImportError, ValueError):
        return None
    return Path(spec.origin) if spec is not None and spec.origin else None


class TargetMoved(KeyError):
    """A run's or campaign's target cannot be found again as it was (moved, edited)."""

    def __str__(self):
        return str(self.args[0])


def found_again(record: dict, where, mission: str | None = None) -> tuple[Target, str]:
    """The scenario a run or campaign in ``where`` was made of (its :meth:`Target.record`),
    found from any folder; ``mission``: the target to judge it by instead (its file moved,
    or as it is now).  (The target, a note to print or "".)  :class:`TargetMoved` when
    the file that defined it is no longer there or has changed since (SHA-256)."""
    variant, kind = record.get("variant"), record.get("kind") or "target"
    path, made = record.get("path"), record.get("sha256")
    if mission is not None:
        found = resolve(
            mission if ":" in Path(mission).name or not variant else f"{mission}:{variant}"
        )
        if not made or found.source is not None and sha256(found.source) == made:
            return found, ""
        return found, (
            f"note: {found.source or mission} is not what {where} was made of (the {kind} {path}, "
            f"SHA-256 {made[:12]}…): judged by it as it is now"
        )
    if path and not Path(path).is_file():
        raise TargetMoved(
            f"{where} was made of the {kind} {path}, which is no longer there (moved or "
            "deleted): give --mission PATH, where it is now"
        )
    if path and made and sha256(Path(path)) != made:
        raise TargetMoved(
            f"{where} was made of the {kind} {path}, which has changed since (SHA-256 "
            f"{made[:12]}… then, {sha256(Path(path))[:12]}… now): its requirements may not be "
            f"those it was judged by; --mission {path} judges it by the file as it is now"
        )
    text = record.get("text") or ""
    if kind == "mission file" or kind == "module" and not _importable(_split(text)[0]):
        if not path:
            raise TargetMoved(
                f"{where} was made of the scenario {record.get('scenario')}, made in Python "
                "in no file of its own: give --mission PATH, the file that defines it"
            )
        text = f"{path}:{variant}" if variant else path  # by its absolute path
    return resolve(text), ""


def _split(text: str) -> tuple[str, str]:
    """'scan_pitch:literal_spin' -> ('scan_pitch', 'literal_spin'); 'a/b.py:x' likewise."""
    if ".py:" in text:
        name, _, variant = text.rpartition(":")
        return name, variant
    if Path(text).suffix in (".ssd", ".ssp", ".fmu", ".py"):
        return text, ""
    name, _, variant = text.partition(":")
    return name, variant


def _importable(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):
        return False


def _ours(name: str) -> bool:
    from ...fmus import FMUS

    return name in FMUS


def load_file(path: Path) -> Scenario:
    """The scenario of a mission file (imported once per process and path)."""
    path = Path(path).resolve()
    if not path.is_file():
        raise KeyError(f"no mission file {path}")
    module_name = f"agilesat_mission_{hashlib.sha256(str(path).encode()).hexdigest()[:8]}"
    module = sys.modules.get(module_name)
    if module is None:
        folder = str(path.parent)
        if folder not in sys.path:
            sys.path.insert(0, folder)
        spec = importlib.util.spec_from_file_location(module_name, path)
        module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
        sys.modules[module_name] = module
        try:
            spec.loader.exec_module(module)  # type: ignore[union-attr]
        except SystemExit as exc:  # not the end of agilesat's command: no scenario to run
            del sys.modules[module_name]
            raise MissionError(
                f"{path}: importing it called sys.exit({exc.code!r}), so it defines no scenario "
                "to run (a mission file defines SCENARIO; run code only under "
                "`if __name__ == '__main__':`)"
            ) from None
        except Exception as exc:
            del sys.modules[module_name]
            raise MissionError(f"{path}: importing it raised {_where(exc, path)}") from exc
        except BaseException:
            del sys.modules[module_name]
            raise
    return _scenario_of(module, str(path))


class MissionError(ValueError):
    """A mission file that could not be imported (the message names it and the line)."""


def _where(exc: BaseException, path: Path) -> str:
    """'ValueError: ... (line 12: the line's code)' at the mission file's last line in the
    traceback (the user's mistake is there, not in the toolkit below it)."""
    import traceback

    frames = [f for f in traceback.extract_tb(exc.__traceback__) if Path(f.filename) == path]
    if isinstance(exc, SyntaxError) and exc.lineno and Path(str(exc.filename)) == path:
        return f"SyntaxError: {exc.msg} (line {exc.lineno}: {(exc.text or '').strip()})"
    text = f"{type(exc).__name__}: {exc}"
    if frames:
        text += f" (line {frames[-1].lineno}: {frames[-1].line})"
    return text


def _scenario_of(module, where: str) -> Scenario:
    """A module's ``SCENARIO``, or its only Scenario."""
    found = getattr(module, "SCENARIO", None)
    if isinstance(found, Scenario):
        return found
    candidates = [v for v in vars(module).values() if isinstance(v, Scenario)]
    if len(candidates) == 1:
        return candidates[0]
    raise KeyError(
        f"{where} defines "
        + (
            f"{len(candidates)} scenarios ({', '.join(c.name for c in candidates)})"
            if candidates
            else "no scenario"
        )
        + ": name the one to run SCENARIO = Scenario(...)"
    )


def single(fmu) -> System:
    """One FMU (an .fmu path, or one of ours by name) as a system of its own, at its
    defaults: every input held at its start value (``--set`` gives it another), its default
    experiment's start, stop and step where it declares them."""
    from ..system.description import Description
    from ..system.parameters import variables
    from .system import fmu_file

    path = fmu_file(str(Path(fmu).resolve()) if str(fmu).endswith(".fmu") else str(fmu))
    described = Description(path.stem, path)
    name = described.md.coSimulation.modelIdentifier
    experiment = described.md.defaultExperiment
    settings = {}
    if experiment is not None:
        for key, value in (
            ("start", experiment.startTime),
            ("stop", experiment.stopTime),
            ("step", experiment.stepSize),
        ):
            if value is not None:
                settings[key] = float(value)
    system = System(name, **settings)
    system.file = str(path)
    system.add(name, str(path))
    for variable in variables(described).values():
        if variable.first.causality == "input" and variable.first.start is not None:
            system._set(f"{name}.{variable.name}", variable.start(), 0)
    return system


def generated_systems() -> dict:
    """{SSD file: its bytes, made on demand} that ``agilesat generate`` writes: each
    shipped scenario's system (and each variant's that changes the system), its FMU
    sources relative to the file (``fmus/build``)."""
    import os

    from ...fmus.build import BUILD_DIR

    files = {}
    for name in shipped():
        found = scenario(name)
        if found.systems_dir is None:
            continue
        for variant in [None, *(v for v, x in found.variants.items() if x.system is not None)]:
            path = found.systems_dir / f"{name}{'.' + variant if variant else ''}.ssd"
            system = found.system_for(variant)
            sources = {
                c: Path(os.path.relpath(BUILD_DIR / f"{system.fmu(c)}.fmu", path.parent)).as_posix()
                for c in system.components
            }
            files[path] = lambda s=system, f=sources: s.ssd(f)
    return files
