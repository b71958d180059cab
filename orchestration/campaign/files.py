"""A campaign's files: its own read back (``--resume``, the summary), where what is not
what the campaign wrote is an error naming the file (and line) and what was expected,
never a traceback; the content hash of the system a campaign runs and of the code it runs
(the modules the mission imports, the toolkit's own sources), which a resume must match;
and the shipped dispersion files of the scenarios (``shipped/``).
"""

from __future__ import annotations

import hashlib
import json
import site
import sys
import sysconfig
from importlib import metadata
from pathlib import Path

SHIPPED_DIR = Path(__file__).resolve().parent / "shipped"
#: the entry of :func:`code_content` for the toolkit itself
TOOLKIT = "agilesat's own sources"
_SOURCES = (".py", ".c", ".h", ".toml", ".ssd")


class CampaignFileError(ValueError):
    """A campaign file that is not what a campaign writes."""


def read_object(path: Path, what: str, required: tuple[str, ...] = ()) -> dict:
    """The JSON object in ``path`` (``what`` it should hold, for the message), with the
    keys ``required``."""
    try:
        value = json.loads(path.read_text())
    except ValueError as exc:
        raise CampaignFileError(f"{path}: not JSON ({exc}); expected {what}") from None
    if not isinstance(value, dict) or not all(k in value for k in required):
        raise CampaignFileError(
            f"{path}: expected {what}"
            + (f" with {', '.join(required)}" if required else "")
            + f", got a {type(value).__name__}"
            + (f" with {sorted(value)}" if isinstance(value, dict) else "")
        )
    return value


def journal_record(path: Path, number: int, line: str) -> dict:
    """One line of ``runs.jsonl``: a JSON object with a whole non-negative ``index``."""
    try:
        record = json.loads(line)
    except ValueError as exc:
        raise CampaignFileError(
            f"{path}:{number}: not a run record ({exc}); expected one JSON object per line"
        ) from None
    index = record.get("index") if isinstance(record, dict) else None
    if type(index) is not int or index < 0 or not isinstance(record.get("metrics", {}), dict):
        raise CampaignFileError(
            f"{path}:{number}: not a run record: expected a JSON object with a whole "
            f"'index' >= 0 and its 'metrics', got {line.strip()[:120]}"
        )
    return record


def system_content(plan) -> dict[str, str]:
    """{file: SHA-256} of the file that defines the system a campaign runs (a scenario's
    module, an .ssd, an .ssp package) and of the FMU of each component."""
    target = Path(plan.system.path)
    content = {str(Path(target).resolve()): _sha256(target)}
    for c in plan.system.components:
        content[f"the FMU of {c.name} ({Path(c.source).name})"] = _sha256(c.source)
    return content


def _sha256(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def code_content() -> dict[str, str]:
    """{file: SHA-256} of the code a campaign's runs execute besides the system file and
    the FMUs: every module this process has loaded from outside the Python installation
    and the toolkit (a mission's own imports, ``from mission_constants import RATE``), and
    the toolkit's own sources as one entry (:data:`TOOLKIT`: its version and a digest of
    its files).  Taken after the mission is imported (:class:`.plan.Plan`)."""
    content = {TOOLKIT: toolkit_digest()}
    outside = [*_installation(), *_toolkit_dirs()]
    for module in list(sys.modules.values()):
        file = getattr(module, "__file__", None)
        if not isinstance(file, str):
            continue
        path = Path(file).resolve()
        if path.is_file() and not any(path.is_relative_to(d) for d in outside):
            content[str(path)] = _sha256(path)
    return dict(sorted(content.items()))


def code_changed(recorded: dict) -> list[str]:
    """The entries of a :func:`code_content` taken earlier whose file differs now (or is
    gone): what a resume would run differently.  Modules loaded since are not compared:
    they come from what the process did, and a file that imports a new one changed."""
    result = []
    for key, digest in recorded.items():
        try:
            now = toolkit_digest() if key == TOOLKIT else _sha256(key)
        except OSError:
            now = None
        if now != digest:
            result.append(key)
    return sorted(result)


def toolkit_digest() -> str:
    """'VERSION SHA-256': the toolkit's version and a digest of its source files."""
    digest = hashlib.sha256()
    for root in _toolkit_dirs():
        build = root / "build"
        for path in sorted(root.rglob("*")):
            if (
                path.suffix in _SOURCES
                and "__pycache__" not in path.parts
                and not path.is_relative_to(build)
            ):
                digest.update(f"{path.relative_to(root.parent)}\0".encode())
                digest.update(hashlib.sha256(path.read_bytes()).digest())
    try:
        version = metadata.version("agilesat")
    except metadata.PackageNotFoundError:
        version = "(not installed)"
    return f"{version} {digest.hexdigest()}"


def _toolkit_dirs() -> list[Path]:
    import agilesat.components
    import agilesat.fmus
    import agilesat.orchestration

    packages = (agilesat.components, agilesat.fmus, agilesat.orchestration)
    return [Path(p).resolve() for package in packages for p in package.__path__]


def _installation() -> set[Path]:
    """The directories of the Python installation and its packages."""
    places = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix}
    places |= set(sysconfig.get_paths().values()) | set(site.getsitepackages())
    places.add(site.getusersitepackages())
    return {Path(p).resolve() for p in places if p}


def changed(recorded: dict, now: dict) -> list[str]:
    """The files whose content (or presence) differs between two :func:`system_content`."""
    return sorted(f for f in set(recorded) | set(now) if recorded.get(f) != now.get(f))


def shipped(name: str) -> Path:
    """The shipped dispersion file of a scenario (``shipped/<name>.toml``)."""
    path = SHIPPED_DIR / f"{name}.toml"
    if not path.exists():
        raise KeyError(
            f"no shipped campaign {name!r}; shipped: "
            f"{', '.join(p.stem for p in sorted(SHIPPED_DIR.glob('*.toml')))}"
        )
    return path


def shipped_files(target: str) -> list[Path]:
    """The shipped dispersion files of a scenario[:variant]: the scenario's, then the
    variant's additions where it has some (``shipped/<name>.<variant>.toml``: the sensed
    variants' sensor noise)."""
    name, _, variant = target.partition(":")
    extra = SHIPPED_DIR / f"{name}.{variant}.toml"
    return [shipped(name), *([extra] if variant and extra.exists() else [])]
