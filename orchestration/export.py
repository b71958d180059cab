"""``agilesat export``: anything that runs, as a self-contained SSP package, a system file
with its FMUs beside it, or one configured FMU.

An ``.ssp`` file (SSP 1.0, §5 "SSP package") is a zip archive holding
``SystemStructure.ssd`` and, here, every FMU it uses under ``resources/``; the SSD names
them by relative URI (``resources/SatelliteDynamics.fmu``), so the package runs wherever it
is copied: in our master (``agilesat run FILE.ssp``), in libcosim
(``CosimExecution.from_ssp_file``) or in any SSP importer.  ``--out x.ssd`` writes the same
SSD as ``x.ssd`` with its FMUs in ``x.fmus/`` beside it; ``--component NAME --out x.fmu``
the one FMU of component NAME, configured as the package's would be.  The target is a
shipped scenario or variant, a mission file of your own (``mission.py[:variant]``), or an
``.ssd``/``.ssp`` system file; a variant's and ``--set``'s values are written into the
SSD (typed as a run types them, units converted).  The archives are deterministic: the
same sources give the same files.

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

import dataclasses
import math
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

from lxml import etree

from ..fmus.build import write_archive
from ..fmus.configure import NotConfigurable, configured_fmu
from . import coupling_error
from .mission.system import package_entries
from .mission.targets import resolve
from .system.description import Description
from .system.parameters import typed_parameters
from .system.ssp import NS, SystemFile, read_system
from .system.units import quantity, to_si
from .system.validation import check_system

#: defaults every exported FMU gets unless the system binds them otherwise
EXPORT_DEFAULTS = {"warnings_return_ok": True}


def _stderr(text: str) -> None:
    print(text, file=sys.stderr)


def export(
    target,
    out: Path,
    parameters: dict | None = None,
    component: str | None = None,
    accuracy=None,
    say: Callable[[str], None] = _stderr,
    tell: Callable[[str], None] = print,
) -> Path:
    """Write ``target`` (see :func:`.mission.targets.resolve`) with ``parameters``
    ({"Instance.variable": value}, as ``--set`` gives them) as ``out``: an SSP package
    (``.ssp``), an SSD with its FMUs in ``<stem>.fmus/`` (``.ssd``), or the configured FMU
    of ``component`` (``.fmu``).  A system's coupling error per host class
    (:mod:`.coupling_error`) goes to ``tell`` and into its documentation
    (``documentation/index.html`` of the package, ``<stem>.html`` beside an SSD);
    ``accuracy`` (an angle, ``"0.05 deg"``) chooses its step so that the held-input hosts
    meet it, which ``tell`` is told with its cost.  ``say`` is told what is packed
    unconfigured."""
    out = Path(out)
    if (component is not None) != (out.suffix == ".fmu"):
        raise ValueError(
            f"--out {out}: export a system as .ssp or .ssd, one component with "
            "--component NAME as .fmu"
        )
    if out.suffix not in (".ssp", ".ssd", ".fmu"):
        raise ValueError(f"--out {out}: an .ssp package, an .ssd system or one .fmu")
    found = resolve(target)
    system, described = _system(found, parameters)
    out.parent.mkdir(parents=True, exist_ok=True)
    folder = f"{out.stem}.fmus" if out.suffix == ".ssd" else "resources"
    if component is not None:
        entries = package_entries(system, described, say, folder)
        sources = {
            e.get("name"): e.get("source")
            for e in etree.fromstring(entries["SystemStructure.ssd"]).iterfind(
                ".//ssd:Component", NS
            )
        }
        if component not in sources:
            raise KeyError(
                f"--component {component}: {target} has no such component; its "
                f"components: {', '.join(sources)}"
            )
        out.write_bytes(entries[sources[component]])
        return out
    scenario, variant = found.scenario, found.variant
    if accuracy is not None:
        system = _step_for(accuracy, system, described, folder, say, tell)
    entries = package_entries(system, described, say, folder)
    with tempfile.TemporaryDirectory(prefix="agilesat_export_") as scratch:
        measured = write_archive(Path(scratch) / "package.ssp", entries)
        statement = coupling_error.state(measured, scenario, variant)
    for line in statement.lines():
        tell(line)
    page = coupling_error.documentation(system.name, statement)
    if out.suffix == ".ssp":
        entries["documentation/index.html"] = page
        return write_archive(out, entries)
    ssd = entries.pop("SystemStructure.ssd")
    for uri, data in entries.items():
        (out.parent / uri).parent.mkdir(parents=True, exist_ok=True)
        (out.parent / uri).write_bytes(data)
    out.with_suffix(".html").write_bytes(page)
    out.write_bytes(ssd)
    return out


def _step_for(accuracy, system, described, folder, say, tell) -> SystemFile:
    """The system at the first of its step, its half, its quarter, ... at which both
    held-input host classes stay within ``accuracy`` of our master on the attitude, with
    what it costs said (:mod:`.coupling_error`)."""
    limit = to_si(quantity(accuracy) or quantity(f"{accuracy} rad"), "rad")
    base, step, costs = system.step_size, system.step_size, []
    for halvings in range(coupling_error.MAX_HALVINGS + 1):
        trial = dataclasses.replace(system, step_size=step)
        with tempfile.TemporaryDirectory(prefix="agilesat_export_") as scratch:
            package = write_archive(
                Path(scratch) / "package.ssp", package_entries(trial, described, say, folder)
            )
            worst, seconds = coupling_error.held_attitude(package)
        costs.append(seconds)
        if worst is None:
            raise ValueError("--accuracy: the system has no attitude (q_BI) to hold to it")
        if worst <= limit:
            sampled = [c.name for c in system.components if c.step_size is None]
            tell(
                f"--accuracy {accuracy}: step {step:g} s, the held-input hosts within "
                f"{math.degrees(worst):.3g}°; it costs {2**halvings}× the macro steps of "
                f"{base:g} s (our master's run: {seconds:.2g} s CPU, {costs[0]:.2g} s at "
                f"{base:g} s)"
                + (
                    f"; {', '.join(sampled)} step at it too (a component's own step, "
                    "Scenario.steps, keeps its sample period)"
                    if halvings and sampled
                    else ""
                )
            )
            return trial
        step /= 2
    raise ValueError(
        f"--accuracy {accuracy}: not met at {step * 2:g} s ({coupling_error.MAX_HALVINGS} "
        f"halvings of {base:g} s): the held-input hosts are {math.degrees(worst):.3g}° off"
    )


def _system(found, parameters) -> tuple[SystemFile, dict]:
    """The target's system with ``parameters`` written in, checked, and its components'
    descriptions."""
    system = found.system_file(build=True)
    described = {c.name: Description(c.name, c.source) for c in system.components}
    given = typed_parameters(described, dict(parameters or {}))
    if given:
        keys = {(p.component, p.name) for p in given.values()}
        values = [p for p in system.parameters if (p.component, p.name) not in keys]
        system = dataclasses.replace(system, parameters=values + list(given.values()))
        check_system(system, described, system.parameters)
    return system, described


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
            (say or _stderr)(
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
