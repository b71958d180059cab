"""The FMUs: one per component model, found in ``components/``; nothing here per FMU.

An FMU is a component module ``components/<snake_name>.py`` that defines the model class
``<CamelName>(Model)`` (``cmg_cluster.py`` -> ``CmgCluster``); the FMU, its modelIdentifier
and its class are named after it.  ``FMUS`` maps each FMU name to that module, read from
the sources (nothing imported); :func:`slave_class` makes the pythonfmu slave,
``class <CamelName>(ModelSlave): model_class = <CamelName>``, which the build writes into
each FMU's entry module.  Adding an FMU = adding its component module (and a row in the
README's table).  Nothing here imports pythonfmu at import time.
"""

from __future__ import annotations

import functools
import importlib
import re
from pathlib import Path

_COMPONENTS = Path(__file__).resolve().parent.parent / "components"
#: the file in an exported FMU's resources holding the defaults it was configured with
#: (written by configure.py, applied by the slave)
CONFIGURATION = "configuration.json"
FMUS: dict[str, str]  # see __getattr__


def configuration_key(data: bytes) -> str:
    """The hash of a configuration file's bytes that the configured FMU's GUID carries
    (fmus/protocol.py ``fmu_guid``)."""
    import hashlib

    return hashlib.sha256(data).hexdigest()[:12]


def _camel(snake: str) -> str:
    return "".join(part.capitalize() for part in snake.split("_"))


def _snake(camel: str) -> str:
    return re.sub(r"(?<!^)(?=[A-Z])", "_", camel).lower()


def _find_fmus(directory: Path) -> dict[str, str]:
    """{FMU name: component module} for every module defining ``class <Camel>(Model)``
    (the sources read, nothing imported: :mod:`.source_facts`)."""
    from .source_facts import facts

    found = {}
    for path in sorted(directory.glob("*.py")):
        name = _camel(path.stem)
        classes = facts(path.read_text(encoding="utf-8"), str(path))["classes"]
        if any(cls == name and "Model" in bases for cls, bases in classes):
            found[name] = path.stem
    return found


def _registry() -> dict[str, str]:
    """``FMUS``, read once per process."""
    if "FMUS" not in globals():
        globals()["FMUS"] = _find_fmus(_COMPONENTS)
    return globals()["FMUS"]


def __getattr__(name: str):
    """``FMUS``: FMU name (= modelIdentifier = class name) -> module in ``components`` of
    its model, read on first use (an FMU's own import of this package never needs it)."""
    if name == "FMUS":
        return _registry()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def model_class(name: str):
    """The component model class of the FMU ``name``: class ``<Name>`` of
    ``components/<snake_name>.py``, a direct subclass of ``Model``, found by that naming
    rule without reading other modules (an FMU's start), else by ``FMUS`` (a module named
    otherwise, ``sensor_3d.py`` for ``Sensor3d``)."""
    module = _snake(name)
    if _camel(module) != name or not (_COMPONENTS / f"{module}.py").is_file():
        module = _registry().get(name, module)
    found = None
    if (_COMPONENTS / f"{module}.py").is_file():
        package = __name__.rsplit(".", 1)[0]
        found = getattr(importlib.import_module(f"{package}.components.{module}"), name, None)
    if not (isinstance(found, type) and "Model" in [base.__name__ for base in found.__bases__]):
        raise KeyError(f"unknown FMU {name!r}; FMUs: {', '.join(_registry())}")
    return found


@functools.cache
def slave_class(name: str):
    """The pythonfmu slave class of the FMU ``name``: a :class:`.slave.ModelSlave` on its
    model (one class per name and process)."""
    from .slave import ModelSlave

    model = model_class(name)
    return type(
        name,
        (ModelSlave,),
        {
            "model_class": model,
            "__module__": __name__,
            "__doc__": f"FMU ``{name}``: {model.__doc__ or ''}",
        },
    )
