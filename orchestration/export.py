"""``agilesat export``: anything that runs, as a self-contained SSP package.

The target is a shipped scenario or variant, a mission file of your own
(``mission.py[:variant]``), or an ``.ssd``/``.ssp`` system file; a variant's and
``--set``'s values are written into the package's SSD (typed as a run types them, units
converted), and each component's FMU carries them as its own defaults
(:mod:`.mission.package`).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from .mission.package import write_package
from .mission.targets import resolve
from .system.description import Description
from .system.parameters import typed_parameters
from .system.validation import check_system


def export_ssp(target, out: Path, parameters: dict | None = None) -> Path:
    """Write ``target`` (see :func:`.mission.targets.resolve`) with ``parameters``
    ({"Instance.variable": value}, as ``--set`` gives them) as the SSP package ``out``."""
    out = Path(out)
    if out.suffix != ".ssp":
        raise ValueError(f"--out {out}: an SSP package is a .ssp file")
    found = resolve(target)
    system = found.system_file(build=True)
    described = {c.name: Description(c.name, c.source) for c in system.components}
    given = typed_parameters(described, dict(parameters or {}))
    if given:
        keys = {(p.component, p.name) for p in given.values()}
        values = [p for p in system.parameters if (p.component, p.name) not in keys]
        system = dataclasses.replace(system, parameters=values + list(given.values()))
        check_system(system, described, system.parameters)
    out.parent.mkdir(parents=True, exist_ok=True)
    return write_package(system, described, out)
