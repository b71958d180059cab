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

import ast
import functools
import importlib
from pathlib import Path

_COMPONENTS = Path(__file__).resolve().parent.parent / "components"


def _camel(snake: str) -> str:
    return "".join(part.capitalize() for part in snake.split("_"))


def _find_fmus(directory: Path) -> dict[str, str]:
    """{FMU name: component module} for every module defining ``class <Camel>(Model)``."""
    found = {}
    for path in sorted(directory.glob("*.py")):
        name = _camel(path.stem)
        for node in ast.parse(path.read_text(encoding="utf-8"), str(path)).body:
            if (
                isinstance(node, ast.ClassDef)
                and node.name == name
                and any(isinstance(base, ast.Name) and base.id == "Model" for base in node.bases)
            ):
                found[name] = path.stem
    return found


#: FMU name (= modelIdentifier = class name) -> module in ``components`` of its model
FMUS: dict[str, str] = _find_fmus(_COMPONENTS)


def model_class(name: str):
    """The component model class (``components``) of the FMU ``name``."""
    if name not in FMUS:
        raise KeyError(f"unknown FMU {name!r}; FMUs: {', '.join(FMUS)}")
    package = __name__.rsplit(".", 1)[0]
    return getattr(importlib.import_module(f"{package}.components.{FMUS[name]}"), name)


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
