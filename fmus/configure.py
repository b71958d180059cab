"""An FMU configured with a system's values as its own defaults (``agilesat export``).

An SSP package binds parameter values to each component; a host that applies them (our
master, libcosim, OMSimulator, ECOS given the set's name) runs the system as described,
one that does not (ECOS without a set name) runs the FMUs at their table defaults,
silently.  A configured FMU carries the values itself: the start values of its model
description, the model's values at instantiation (``resources/configuration.json``, which
the slave applies: fmus/slave.py), its documentation — all from one mapping — and a GUID of
its own (the values' hash beside the code's).  Its code, binaries and compiled kernels are
those of the built FMU.  Only an FMU built from these sources can be configured (its model
description is written again from the variable table); any other is :class:`NotConfigurable`.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

from . import CONFIGURATION, FMUS, configuration_key, model_class
from .build import archive_bytes, description_xml, documentation, is_current
from .model_description import start_text

_PYTHON = {"Real": float, "Integer": int, "Boolean": bool, "String": str}


class NotConfigurable(ValueError):
    """The FMU is not one agilesat built from these sources (a third party's, or older)."""


def configured_fmu(fmu: Path, values: dict) -> bytes:
    """The built FMU ``fmu`` with ``values`` ({scalar name: value}, parameters and inputs)
    as its defaults, as the bytes of an FMU (module docstring).  ValueError naming the
    FMU and variable for a name it does not have or an output; NotConfigurable for an FMU
    not built from these sources."""
    with zipfile.ZipFile(fmu) as archive:
        entries = {name: archive.read(name) for name in archive.namelist()}
    entry = entries.get("resources/slavemodule.txt", b"").decode()
    name, _, digest = entry.rpartition("_")
    if name not in FMUS or not is_current(fmu, name):
        raise NotConfigurable(f"{fmu}: not an FMU agilesat built from these sources")
    model = model_class(name)
    variables = {scalar: v for v, scalar in model.table_layout().scalars}
    typed = {}
    for scalar, value in sorted(values.items()):
        v = variables.get(scalar)
        if v is None or v.causality == "output":
            raise ValueError(f"{fmu.name}: {scalar!r} is not a parameter or input of {name}")
        typed[scalar] = _PYTHON[v.type](value)
    text = json.dumps({"values": typed}, indent=1, sort_keys=True)
    key = configuration_key(text.encode())
    starts = {scalar: start_text(variables[scalar].type, x) for scalar, x in typed.items()}
    binaries = {path: data for path, data in entries.items() if path.startswith("binaries/")}
    entries["modelDescription.xml"] = description_xml(name, digest, starts, key, binaries=binaries)
    entries[f"resources/{CONFIGURATION}"] = text.encode()
    entries["documentation/index.html"] = documentation(name, model, typed).encode()
    return archive_bytes(entries)
