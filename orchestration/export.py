"""``agilesat export``: a scenario as a self-contained SSP package.

An ``.ssp`` file (SSP 1.0, §5 "SSP package") is a zip archive holding
``SystemStructure.ssd`` and, here, every FMU it uses under ``resources/``; the SSD names
them by relative URI (``resources/SatelliteDynamics.fmu``), so the package runs wherever it
is copied: in our master (``agilesat run FILE.ssp``), in libcosim
(``CosimExecution.from_ssp_file``) or in any SSP importer.  A variant's parameter values
are written into the package's SSD.  The archive is deterministic: the same sources give
the same file.
"""

from __future__ import annotations

from pathlib import Path

from ..fmus.build import build_all, write_archive
from .runner import parse_target


def export_ssp(target: str, out: Path) -> Path:
    """Write ``scenario[:variant]`` as the SSP package ``out``; return its path."""
    scenario, variant = parse_target(target)
    if scenario is None:
        raise KeyError(f"export takes a scenario[:variant], not a file: {target!r}")
    out = Path(out)
    if out.suffix != ".ssp":
        raise ValueError(f"--out {out}: an SSP package is a .ssp file")
    fmus = build_all(names=scenario.components)
    sources = {path.stem: f"resources/{path.name}" for path in fmus}
    entries = {f"resources/{path.name}": path.read_bytes() for path in fmus}
    entries["SystemStructure.ssd"] = scenario.render_ssd(sources, variant)
    out.parent.mkdir(parents=True, exist_ok=True)
    return write_archive(out, entries)
