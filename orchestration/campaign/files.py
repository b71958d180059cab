"""A campaign's files: its own read back (``--resume``, the summary), where what is not
what the campaign wrote is an error naming the file (and line) and what was expected,
never a traceback; the content hash of the system a campaign runs, which a resume must
match; and the shipped dispersion files of the scenarios (``shipped/``).
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

SHIPPED_DIR = Path(__file__).resolve().parent / "shipped"


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
