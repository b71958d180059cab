"""``agilesat export``: a scenario as a self-contained SSP package.

An ``.ssp`` file (SSP 1.0, §5 "SSP package") is a zip archive holding
``SystemStructure.ssd`` and, here, every FMU it uses under ``resources/``; the SSD names
them by relative URI (``resources/SatelliteDynamics.fmu``), so the package runs wherever it
is copied: in our master (``agilesat run FILE.ssp``), in libcosim
(``CosimExecution.from_ssp_file``) or in any SSP importer.  A variant's parameter values
are written into the package's SSD.  The archive is deterministic: the same sources give
the same file.

Each component's FMU carries the values the SSD binds to it as its own defaults
(fmus/configure.py: start values, the model's values, a GUID of its own), beside the SSD's
parameter sets: a host that applies no parameter set (ECOS without a set name) runs the
system as described.  They also default ``warnings_return_ok`` to true: the FMUs' warnings
(limits, saturation) reach every host's log at category ``logStatusWarning`` with status
fmi2OK, so that hosts that stop on fmi2Warning (OMSimulator) run to the end.  One FMU file
per FMU and set of values: ``resources/<FMU>.fmu``, or ``resources/<FMU>_<component>.fmu``
where components of one FMU have different values.  An FMU that is not one of ours as
built from these sources (a third party's) is packed as it is, with a warning: its values
are in the SSD's parameter sets only.
"""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

from lxml import etree

from ..fmus.build import build_all, write_archive
from ..fmus.configure import NotConfigurable, configured_fmu
from .runner import parse_target
from .system.ssp import NS, read_system

#: defaults every exported FMU gets unless the system binds them otherwise
EXPORT_DEFAULTS = {"warnings_return_ok": True}


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
    ssd = scenario.render_ssd(sources, variant)
    out.parent.mkdir(parents=True, exist_ok=True)
    return write_archive(out, package(ssd, {sources[path.stem]: path for path in fmus}))


def package(ssd: bytes, fmus: dict[str, Path]) -> dict[str, bytes]:
    """The entries of the SSP package of ``ssd``, whose components name their FMUs by the
    URIs of ``fmus`` ({URI: built FMU}): each component's FMU configured with the values
    the SSD binds to it (module docstring), the SSD pointing at them."""
    tree = etree.fromstring(ssd)
    sources = {e.get("name"): e.get("source") for e in tree.iterfind(".//ssd:Component", NS)}
    with tempfile.TemporaryDirectory(prefix="agilesat_export_") as folder:
        root = Path(folder)  # the SSD read as a package would be: its bindings, resolved
        (root / "SystemStructure.ssd").write_bytes(ssd)
        for uri, path in fmus.items():
            (root / uri).parent.mkdir(parents=True, exist_ok=True)
            (root / uri).symlink_to(Path(path).resolve())
        parameters = read_system(root / "SystemStructure.ssd").parameters
    configured: dict[str, tuple[str, bytes]] = {}  # component -> (FMU name, bytes)
    for component, uri in sources.items():
        values = {**EXPORT_DEFAULTS}
        values.update((p.name, p.value) for p in parameters if p.component == component)
        path = Path(fmus[uri])
        try:
            configured[component] = (path.stem, configured_fmu(path, values))
        except NotConfigurable as exc:
            warnings.warn(
                f"{exc}: packed as it is, its values in the parameter sets only", stacklevel=2
            )
            configured[component] = (path.stem, path.read_bytes())
    entries = {}
    for element in tree.iterfind(".//ssd:Component", NS):
        component = element.get("name")
        name, data = configured[component]
        shared = len({d for n, d in configured.values() if n == name}) == 1
        uri = f"resources/{name}.fmu" if shared else f"resources/{name}_{component}.fmu"
        entries[uri] = data
        element.set("source", uri)
    entries["SystemStructure.ssd"] = etree.tostring(
        tree, pretty_print=True, xml_declaration=True, encoding="UTF-8"
    )
    return entries
