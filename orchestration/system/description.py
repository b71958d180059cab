"""What the model description of an FMU in a system says, read without loading the FMU.

:class:`Description`: the variables by name, the output dependencies (at a step and at
initialisation), the derivative declarations, and what our FMUs declare in their
VendorAnnotations: the optional inputs and the SHA-256 of the binaries.  The model
description of each FMU file is read once per process and content (SHA-256 of the file: a
rebuilt FMU is a new one, a copy of the same file is the same one).
"""

from __future__ import annotations

import functools
import os
import threading
import zipfile
from pathlib import Path

from fmpy import read_model_description
from lxml import etree

from ...components.runtime.cache import digest
from .units import declare

AGILESAT_TOOL = "agilesat"
BINARIES_TOOL = "agilesat.binaries"  # fmus/model_description.py writes it
_KEYS_KEPT = 1024
_lock = threading.Lock()
#: content key -> (model description, optional inputs, base units, binaries, _Read)
_descriptions: dict[str, tuple] = {}


class Description:
    """What the model description of an FMU in a system says: variables by name, output
    dependencies, optional inputs.  Nothing is loaded."""

    def __init__(self, name: str, path: Path):
        self.name, self.path = name, Path(path)
        #: the SHA-256 of the file (:func:`content_key`): what everything read from it is keyed by
        self.key = content_key(self.path)
        #: optional input -> what its default means, as our FMUs declare them
        #: (VendorAnnotations; every other input is required); None: not our FMU.
        #: ``binaries``: {file in the FMU: SHA-256} as our FMUs declare them (or {})
        self.md, self.optional_inputs, self.base_units, self.binaries, read = _described(
            self.key, str(path)
        )
        if self.md.coSimulation is None:
            raise ValueError(f"{path}: not a co-simulation FMU")
        declare(self.md.unitDefinitions)  # its display units, for the summaries
        # read once per content, shared by every Description of it: not to be changed
        self.variables = read.variables
        self.feedthrough = read.feedthrough
        self.initial_feedthrough = read.initial_feedthrough
        # FMI 2.0 input/output derivatives (orchestration.cosim.derivatives): the capability
        # flags, and {variable: the variable declared its derivative} (``derivative``)
        self.can_interpolate_inputs = bool(self.md.coSimulation.canInterpolateInputs)
        self.max_output_derivative_order = int(self.md.coSimulation.maxOutputDerivativeOrder or 0)
        self.derivatives = read.derivatives
        #: output names in value-reference order
        self.outputs = read.outputs


class _Read:
    """What a :class:`Description` reads from the model description's variables (once per
    content: a run of a system with many variables rebuilt it each time)."""

    def __init__(self, md):
        self.variables = {v.name: v for v in md.modelVariables}
        self.feedthrough = _dependencies(md.outputs)
        self.initial_feedthrough = _dependencies(md.initialUnknowns)
        self.derivatives = {
            v.derivative.name: v.name for v in md.modelVariables if v.derivative is not None
        }
        self.outputs = [
            v.name
            for v in sorted(md.modelVariables, key=lambda v: v.valueReference)
            if v.causality == "output"
        ]


@functools.lru_cache(maxsize=_KEYS_KEPT)
def _file_digest(path: str, size: int, mtime_ns: int) -> str:
    return digest(path)


def content_key(path: Path) -> str:
    """The SHA-256 of the FMU file (hashed once per path, size and modification time): the
    key of everything read from or made of it once per process."""
    stat = os.stat(path)
    return _file_digest(os.path.abspath(path), stat.st_size, stat.st_mtime_ns)


def _described(key: str, path: str):
    """(model description, optional inputs, base units, binaries, what is read from its
    variables) of the FMU with content ``key``."""
    with _lock:
        described = _descriptions.get(key)
    if described is None:
        root = _root(path)
        try:
            md = read_model_description(path)
        except Exception as exc:  # noqa: BLE001 - fmpy's validation: say what, not a traceback
            said = " ".join(str(exc).split())
            raise FMUFileError(
                f"{path}: its modelDescription.xml is not an FMI 2.0 model description: "
                f"{said[:300]}{'...' * (len(said) > 300)}"
            ) from None
        described = (md, _optional_inputs(root), _base_units(root), _binaries(root), _Read(md))
        with _lock:
            if len(_descriptions) >= _KEYS_KEPT:
                _descriptions.pop(next(iter(_descriptions)))
            _descriptions[key] = described
    return described


class FMUFileError(ValueError):
    """A file that is not an FMU this toolkit runs (the message names it and says why)."""


def _root(path: str):
    """The root element of the FMU's modelDescription.xml, of an FMI 2.0 FMU."""
    try:
        with zipfile.ZipFile(path) as archive:
            text = archive.read("modelDescription.xml")
        root = etree.fromstring(text)
    except (zipfile.BadZipFile, EOFError) as exc:
        raise FMUFileError(
            f"{path}: not an FMU: {exc} (an FMU is a zip archive holding modelDescription.xml; "
            "a cut or damaged file?)"
        ) from None
    except KeyError:
        raise FMUFileError(f"{path}: not an FMU: it holds no modelDescription.xml") from None
    except etree.XMLSyntaxError as exc:
        raise FMUFileError(f"{path}: its modelDescription.xml is not XML: {exc}") from None
    version = root.get("fmiVersion")
    if version != "2.0":
        raise FMUFileError(
            f"{path}: an FMU of FMI {version or '(no fmiVersion)'}: agilesat runs FMI 2.0 "
            "co-simulation FMUs"
        )
    return root


def _dependencies(unknowns) -> dict[str, set[str] | None]:
    """Output name -> names of the variables it depends on (None: depends on all)."""
    result = {}
    for unknown in unknowns:
        deps = unknown.dependencies
        result[unknown.variable.name] = None if deps is None else {d.name for d in deps}
    return result


def _optional_inputs(root) -> dict[str, str] | None:
    """{optional input: what its default means} an agilesat FMU declares (VendorAnnotations);
    None: nothing declared."""
    tool = root.find(f"VendorAnnotations/Tool[@name='{AGILESAT_TOOL}']")
    if tool is None:
        return None
    return {
        e.get("name"): e.get("optional")
        for e in tool.findall("Inputs/Input")
        if e.get("optional") is not None
    }


def _base_units(root) -> dict[str, dict[str, str]]:
    """{unit: the attributes of its BaseUnit, in the order written} of the FMU's
    UnitDefinitions (an SSD's unit definitions copy them)."""
    return {
        unit.get("name"): dict(unit.find("BaseUnit").attrib)
        for unit in root.iterfind("UnitDefinitions/Unit")
        if unit.find("BaseUnit") is not None
    }


def _binaries(root) -> dict[str, str]:
    """{binary: its SHA-256} an agilesat FMU declares (VendorAnnotations), or {}."""
    return {
        e.get("name"): e.get("sha256")
        for e in root.findall(f"VendorAnnotations/Tool[@name='{BINARIES_TOOL}']/Files/File")
    }
