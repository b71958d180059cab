"""An SSP package of a system: the SSD and every FMU it uses, configured with its values.

An ``.ssp`` file (SSP 1.0, §5 "SSP package") is a zip archive holding
``SystemStructure.ssd`` and, here, every FMU it uses under ``resources/``; the SSD names
them by relative URI (``resources/SatelliteDynamics.fmu``), so the package runs wherever it
is copied: in our master (``agilesat run FILE.ssp``), in libcosim
(``CosimExecution.from_ssp_file``) or in any SSP importer (``agilesat export``,
:mod:`..export`, which also writes the SSD with its FMUs beside it, or one of them;
:meth:`.system.System.write`).  The archives are deterministic: the same sources give the
same files.

Each component's FMU carries the values the SSD binds to it as its own defaults
(fmus/configure.py: start values, the model's values, a GUID of its own) and the system's
experiment as its ``DefaultExperiment`` (its start and stop, the component's step), beside
the SSD's parameter sets: a host that applies no parameter set (ECOS without a set name,
``fmpy simulate`` of one FMU) runs the system as described.  They also default
``warnings_return_ok`` to true: the FMUs' warnings (limits, saturation) reach every host's
log at category ``logStatusWarning`` with status fmi2OK, so that hosts that stop on
fmi2Warning (OMSimulator) run to the end.  One FMU file per FMU and set of values:
``resources/<FMU>.fmu``, or ``resources/<FMU>_<component>.fmu`` where components of one FMU
have different values.  Every FMU ``agilesat build`` made from these sources is configured,
ours and a user's models; a third party's is packed as it is and ``say`` is told (its
values are in the SSD's parameter sets only); one agilesat built from other sources
(another version) is an error naming what to rebuild.
"""

from __future__ import annotations

import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

from lxml import etree

from ...fmus.build import write_archive
from ...fmus.configure import NotConfigurable, configured_fmu
from ..system.ssp import NS, SystemFile, read_system, render_ssd

#: defaults every exported FMU gets unless the system binds them otherwise
EXPORT_DEFAULTS = {"warnings_return_ok": True}


def say_on_stderr(text: str) -> None:
    """What an export says: a line on stderr."""
    print(text, file=sys.stderr)


def write_package(system: SystemFile, described: dict, path, say=None) -> Path:
    """An SSP package (SSP 1.0 §5) of ``system`` written as ``path``: ``SystemStructure.ssd``
    and every FMU under ``resources/`` (:func:`package_entries`); deterministic (the same
    system gives the same file)."""
    return write_archive(Path(path), package_entries(system, described, say))


def package_entries(
    system: SystemFile, described: dict, say=None, folder: str = "resources"
) -> dict[str, bytes]:
    """The files of the SSP package of ``system``: ``SystemStructure.ssd`` and every FMU
    under ``folder``, named by relative URI, so it runs wherever it is copied, each FMU
    configured with the values the system binds to it (:func:`package`, which tells
    ``say`` of an FMU it packs unconfigured)."""
    fmus: dict[str, bytes] = {}
    sources, files = {}, {}
    for ref in system.components:
        member = _member(Path(ref.source), fmus)
        fmus.setdefault(member, Path(ref.source).read_bytes())
        sources[ref.name], files[member] = member, Path(ref.source)
    ssd = render_ssd(system, described, sources)
    return package(ssd, files, say, folder)


def _member(fmu: Path, entries: dict) -> str:
    """The package member of an FMU: ``resources/<file name>``, numbered if another FMU
    has that name."""
    member, k = f"resources/{fmu.name}", 1
    while member in entries and entries[member] != fmu.read_bytes():
        k += 1
        member = f"resources/{fmu.stem}_{k}{fmu.suffix}"
    return member


def package(
    ssd: bytes,
    fmus: dict[str, Path],
    say: Callable[[str], None] | None = None,
    folder: str = "resources",
) -> dict[str, bytes]:
    """The entries of the SSP package of ``ssd``, whose components name their FMUs by the
    URIs of ``fmus`` ({URI: built FMU}): each component's FMU configured with the values
    the SSD binds to it and the system's experiment (module docstring), under ``folder``,
    the SSD pointing at them; ``say`` is told of an FMU packed as it is."""
    tree = etree.fromstring(ssd)
    sources = {e.get("name"): e.get("source") for e in tree.iterfind(".//ssd:Component", NS)}
    with tempfile.TemporaryDirectory(prefix="agilesat_export_") as scratch:
        root = Path(scratch)  # the SSD read as a package would be: its bindings, resolved
        (root / "SystemStructure.ssd").write_bytes(ssd)
        for uri, path in fmus.items():
            (root / uri).parent.mkdir(parents=True, exist_ok=True)
            (root / uri).symlink_to(Path(path).resolve())
        system = read_system(root / "SystemStructure.ssd")
    steps = {c.name: c.step_size or system.step_size for c in system.components}
    configured: dict[str, tuple[str, bytes]] = {}  # component -> (FMU name, bytes)
    for component, uri in sources.items():
        values = {**EXPORT_DEFAULTS}
        values.update((p.name, p.value) for p in system.parameters if p.component == component)
        path = Path(fmus[uri])
        experiment = None
        if system.stop_time is not None and steps[component] is not None:
            experiment = (system.start_time, system.stop_time, steps[component])
        try:
            configured[component] = (path.stem, configured_fmu(path, values, experiment))
        except NotConfigurable as exc:
            bound = sorted(p.name for p in system.parameters if p.component == component)
            (say or say_on_stderr)(
                f"{exc} (component {component}): packed as it is"
                + (
                    f"; its values ({', '.join(bound)}) are in the package's parameter set "
                    "only, which a host that applies none does not see"
                    if bound
                    else ""
                )
            )
            configured[component] = (path.stem, path.read_bytes())
    entries = {}
    for element in tree.iterfind(".//ssd:Component", NS):
        component = element.get("name")
        name, data = configured[component]
        shared = len({d for n, d in configured.values() if n == name}) == 1
        uri = f"{folder}/{name}.fmu" if shared else f"{folder}/{name}_{component}.fmu"
        entries[uri] = data
        element.set("source", uri)
    entries["SystemStructure.ssd"] = etree.tostring(
        tree, pretty_print=True, xml_declaration=True, encoding="UTF-8"
    )
    return entries
