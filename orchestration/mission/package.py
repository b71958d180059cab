"""An SSP package of a system: the SSD and every FMU it uses, configured with its values.

An ``.ssp`` file (SSP 1.0, §5 "SSP package") is a zip archive holding
``SystemStructure.ssd`` and, here, every FMU it uses under ``resources/``; the SSD names
them by relative URI (``resources/SatelliteDynamics.fmu``), so the package runs wherever it
is copied: in our master (``agilesat run FILE.ssp``), in libcosim
(``CosimExecution.from_ssp_file``) or in any SSP importer (``agilesat export``,
:mod:`..export`; :meth:`.system.System.write`).  The archive is deterministic: the same
sources give the same file.

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

from ...fmus.build import write_archive
from ...fmus.configure import NotConfigurable, configured_fmu
from ..system.ssp import NS, SystemFile, read_system, render_ssd

#: defaults every exported FMU gets unless the system binds them otherwise
EXPORT_DEFAULTS = {"warnings_return_ok": True}


def write_package(system: SystemFile, described: dict, path) -> Path:
    """An SSP package (SSP 1.0 §5): ``SystemStructure.ssd`` and every FMU under
    ``resources/``, named by relative URI, so it runs wherever it is copied, each FMU
    configured with the values the system binds to it (:func:`package`); deterministic
    (the same system gives the same file)."""
    fmus: dict[str, bytes] = {}
    sources, files = {}, {}
    for ref in system.components:
        member = _member(Path(ref.source), fmus)
        fmus.setdefault(member, Path(ref.source).read_bytes())
        sources[ref.name], files[member] = member, Path(ref.source)
    ssd = render_ssd(system, described, sources)
    return write_archive(Path(path), package(ssd, files))


def _member(fmu: Path, entries: dict) -> str:
    """The package member of an FMU: ``resources/<file name>``, numbered if another FMU
    has that name."""
    member, k = f"resources/{fmu.name}", 1
    while member in entries and entries[member] != fmu.read_bytes():
        k += 1
        member = f"resources/{fmu.stem}_{k}{fmu.suffix}"
    return member


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
