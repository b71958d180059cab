"""``agilesat export``: anything that runs, as a self-contained SSP package.

An ``.ssp`` file (SSP 1.0, §5 "SSP package") is a zip archive holding
``SystemStructure.ssd`` and, here, every FMU it uses under ``resources/``; the SSD names
them by relative URI (``resources/SatelliteDynamics.fmu``), so the package runs wherever it
is copied: in our master (``agilesat run FILE.ssp``), in libcosim
(``CosimExecution.from_ssp_file``) or in any SSP importer.  The target is a shipped
scenario or variant, a mission file of your own (``mission.py[:variant]``), or an
``.ssd``/``.ssp`` system file; a variant's and ``--set``'s values are written into the
package's SSD (typed as a run types them, units converted).  The archive is deterministic:
the same sources give the same file.

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

import dataclasses
import tempfile
import warnings
from pathlib import Path

from lxml import etree

from ..fmus.configure import NotConfigurable, configured_fmu
from .mission.system import write_package
from .mission.targets import resolve
from .system.description import Description
from .system.parameters import typed_parameters
from .system.ssp import NS, read_system
from .system.validation import check_system

#: defaults every exported FMU gets unless the system binds them otherwise
EXPORT_DEFAULTS = {"warnings_return_ok": True}


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
