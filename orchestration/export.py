"""``agilesat export``: anything that runs, as a self-contained SSP package, a system file
with its FMUs beside it, or one configured FMU.

``--out x.ssp`` writes an SSP package, ``--out x.ssd`` the same SSD as ``x.ssd`` with its
FMUs in ``x.fmus/`` beside it, ``--component NAME --out x.fmu`` the one FMU of component
NAME, configured as the package's would be (what a package holds and how each FMU carries
its values: :mod:`.mission.package`).  The target is a shipped scenario or variant, a
mission file of your own (``mission.py[:variant]``), or an ``.ssd``/``.ssp`` system file;
a variant's and ``--set``'s values are written into the SSD (typed as a run types them,
units converted).  The archives are deterministic: the same sources give the same files.
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
from collections.abc import Callable
from pathlib import Path

from lxml import etree

from ..fmus.build import write_archive
from . import coupling_error
from .mission.package import package_entries, say_on_stderr
from .mission.targets import resolve
from .system.description import Description
from .system.parameters import typed_parameters
from .system.ssp import NS, SystemFile
from .system.units import quantity, to_si
from .system.validation import check_system


def export(
    target,
    out: Path,
    parameters: dict | None = None,
    component: str | None = None,
    accuracy=None,
    say: Callable[[str], None] = say_on_stderr,
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
