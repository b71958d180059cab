"""An FMU configured with a system's values as its own defaults (``agilesat export``).

An SSP package binds parameter values to each component; a host that applies them (our
master, libcosim, OMSimulator, ECOS given the set's name) runs the system as described,
one that does not (ECOS without a set name, ``fmpy simulate``) runs the FMUs at their
table defaults, silently.  A configured FMU carries the values itself: the start values of
its model description, the model's values at instantiation (``resources/configuration.json``,
which the slave applies: fmus/slave.py), its documentation — all from one mapping — a GUID
of its own (the values' hash beside the code's, which the slave answers) and, where given,
the system's experiment as its ``DefaultExperiment``.  Its code, binaries and compiled
kernels are those of the built FMU; its model description is the built one with those
values written in.

Any FMU ``agilesat build`` made from these sources can be configured: ours
(``fmus/build/<Name>.fmu``) and a user's model (:mod:`.user_models`, wherever its FMU was
written: the model's source is inside it).  Any other is refused with the reason: a third
party's FMU (:class:`NotConfigurable`), or one agilesat built from other sources (another
version of agilesat: :class:`OtherSources`).
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path
from xml.etree.ElementTree import Element, fromstring, tostring

from . import CONFIGURATION, FMUS, configuration_key
from .build import archive_bytes, configured_section, is_current
from .model_description import experiment_attributes, start_text
from .protocol import fmu_guid

_PYTHON = {"Real": float, "Integer": int, "Boolean": bool, "String": str}


class NotConfigurable(ValueError):
    """The FMU is not one agilesat built: a third party's (module docstring)."""


class OtherSources(ValueError):
    """The FMU is one agilesat built from other sources than these: rebuild it."""


def configured_fmu(fmu: Path, values: dict, experiment: tuple | None = None) -> bytes:
    """The FMU ``fmu`` with ``values`` ({scalar name: value}, parameters and inputs) as its
    defaults and ``experiment`` (start, stop, step in s) as its DefaultExperiment, as the
    bytes of an FMU (module docstring).  ValueError naming the FMU and variable for a name
    it does not have or an output; NotConfigurable for a third party's FMU, OtherSources
    for one agilesat built from other sources."""
    with zipfile.ZipFile(fmu) as archive:
        entries = {name: archive.read(name) for name in archive.namelist()}
    name, digest = built_here(Path(fmu), entries)
    root = fromstring(entries["modelDescription.xml"])
    variables = {v.get("name"): v for v in root.iter("ScalarVariable")}
    typed = {}
    for scalar, value in sorted(values.items()):
        v = variables.get(scalar)
        if v is None or v.get("causality") not in ("parameter", "input"):
            raise ValueError(f"{Path(fmu).name}: {scalar!r} is not a parameter or input of {name}")
        typed[scalar] = _PYTHON[_type(v).tag](value)
    text = json.dumps({"values": typed}, indent=1, sort_keys=True)
    for scalar, value in typed.items():
        _type(variables[scalar]).set("start", start_text(_type(variables[scalar]).tag, value))
    root.set("guid", "{" + fmu_guid(name, digest, configuration_key(text.encode())) + "}")
    if experiment is not None:  # every FMU these sources build declares one
        element = root.find("DefaultExperiment")
        element.attrib.clear()
        element.attrib.update(experiment_attributes(*experiment))
    entries["modelDescription.xml"] = tostring(root, encoding="UTF-8", xml_declaration=True)
    entries[f"resources/{CONFIGURATION}"] = text.encode()
    page = entries["documentation/index.html"].decode()
    at = page.index("<h2>Variables</h2>")
    entries["documentation/index.html"] = (
        page[:at] + configured_section(typed) + page[at:]
    ).encode()
    return archive_bytes(entries)


def built_here(fmu: Path, entries: dict[str, bytes]) -> tuple[str, str]:
    """(the FMU's name, the content hash of its code) of an FMU agilesat built from these
    sources, read from its ``entries``; NotConfigurable or OtherSources saying why
    otherwise."""
    entry = entries.get("resources/slavemodule.txt", b"").decode()
    name, _, digest = entry.rpartition("_")
    package = f"resources/agilesat_{digest}/"
    if not name or f"{package}fmus/slave.py" not in entries:
        raise NotConfigurable(f"{fmu}: not an FMU agilesat built")
    user = sorted(path for path in entries if path.startswith(f"{package}user/"))
    if user:
        from .user_models import packed_digest

        current = packed_digest(entries, package)
        module = next(path for path in user if not path.endswith("/__init__.py"))
        what = f"rebuild it from its model, agilesat build {module.rsplit('/')[-1]}"
    else:
        current = digest if name in FMUS and is_current(fmu, name) else ""
        what = f"agilesat build {name}"
    if current != digest:
        raise OtherSources(
            f"{fmu}: built by agilesat from other sources than these (another version of "
            f"agilesat): {what}"
        )
    return name, digest


def _type(variable) -> Element:
    """A ScalarVariable's type element (<Real>, <Integer>, <Boolean>, <String>)."""
    return next(child for child in variable if child.tag in _PYTHON)
