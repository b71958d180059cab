"""``modelDescription.xml`` (FMI 2.0 co-simulation) generated from a model's variable table.

pythonfmu's own generator declares no units, no InitialUnknowns and makes every output
depend on every input; this one writes UnitDefinitions (SI base-unit exponents, with
display units), a description and start value for every variable, and the true
dependencies: an output depends on the inputs its table row lists in ``depends``; at
initialisation also on the inputs the initial state reads and on the parameters.  A
``DefaultExperiment`` from the model's ``DEFAULT_STEP`` and ``DEFAULT_STOP`` (a host that is
given no step and stop runs it so: ``agilesat run Gyro``, ``fmpy simulate Gyro.fmu``).

Derivatives.  A model that interpolates its inputs (``INTERPOLATES_INPUTS``) declares
``canInterpolateInputs``, one that answers its outputs' derivatives (``OUTPUT_DERIVATIVES``)
``maxOutputDerivativeOrder="1"`` (components/model.py).  A table row's ``derivative_of``
gives the derivative variable's ``<Real>`` FMI 2.0's ``derivative`` attribute (the index of
the variable it is the derivative of: "if an input or an output is the derivative of
another input or output", FMI 2.0.4 section 2.2.7; such variables need not be states, so
``<Derivatives>`` stays empty); a model declaring such an input (output) must have the
capability.
"""

from __future__ import annotations

import hashlib
import math
from xml.etree.ElementTree import Element, SubElement, indent, tostring

from ..components.variables import UNITS, Layout

#: the vendor annotation that lists the SHA-256 of the FMU's binaries
BINARIES_TOOL = "agilesat.binaries"
LOG_CATEGORIES = {
    "logStatusWarning": "Messages with status fmi2Warning",
    "logStatusError": "Messages with status fmi2Error",
    "logAll": "All messages",
}


def model_description(
    name: str,
    model_class,
    guid: str,
    description: str,
    generation_tool: str,
    binaries: dict[str, bytes] | None = None,
) -> bytes:
    """The model description; ``binaries``: {path in the FMU: content} of its shared
    libraries, whose SHA-256 a master checks before loading them
    (:func:`_binaries_annotation`)."""
    layout = Layout(model_class.VARIABLES)
    for causality, capable in (
        ("input", model_class.INTERPOLATES_INPUTS),
        ("output", model_class.OUTPUT_DERIVATIVES),
    ):
        stated = [v.name for v in layout.group(causality) if v.derivative_of]
        if stated and not capable:
            raise ValueError(
                f"{name}: {stated} are declared derivatives of {causality}s, but the model "
                "does not "
                + (
                    "interpolate its inputs"
                    if causality == "input"
                    else "answer output derivatives"
                )
            )
    root = Element(
        "fmiModelDescription",
        {
            "fmiVersion": "2.0",
            "modelName": name,
            "guid": "{" + guid + "}",
            "description": description,
            "generationTool": generation_tool,
            "variableNamingConvention": "structured",
            "numberOfEventIndicators": "0",
        },
    )
    SubElement(
        root,
        "CoSimulation",
        {
            "modelIdentifier": name,
            "needsExecutionTool": "true",  # a Python 3 interpreter with numpy
            "canHandleVariableCommunicationStepSize": "true",
            "canInterpolateInputs": "true" if model_class.INTERPOLATES_INPUTS else "false",
            "maxOutputDerivativeOrder": "1" if model_class.OUTPUT_DERIVATIVES else "0",
            "canBeInstantiatedOnlyOncePerProcess": "false",
            "canNotUseMemoryManagementFunctions": "true",
            "canGetAndSetFMUstate": "true",
            "canSerializeFMUstate": "true",
        },
    )
    _unit_definitions(root, layout)
    categories = SubElement(root, "LogCategories")
    for category, text in LOG_CATEGORIES.items():
        SubElement(categories, "Category", {"name": category, "description": text})
    SubElement(root, "DefaultExperiment", experiment_attributes(
        0.0, model_class.DEFAULT_STOP, model_class.DEFAULT_STEP
    ))  # fmt: skip
    _binaries_annotation(_input_annotation(root, layout), binaries or {})
    _model_variables(root, layout)
    _model_structure(root, layout, model_class.INITIAL_STATE_DEPENDS)
    indent(root)
    return tostring(root, encoding="UTF-8", xml_declaration=True)


def experiment_attributes(start: float, stop: float, step: float) -> dict[str, str]:
    """The attributes of FMI 2.0's ``<DefaultExperiment>``: start, stop, step (s)."""
    return {
        "startTime": repr(float(start)),
        "stopTime": repr(float(stop)),
        "stepSize": repr(float(step)),
    }


def _unit_definitions(root, layout):
    used = sorted({v.unit for v in layout.variables if v.type == "Real"})
    unknown = [u for u in used if u not in UNITS]
    if unknown:
        raise ValueError(f"units {unknown} are not in components/variables.py UNITS")
    definitions = SubElement(root, "UnitDefinitions")
    for unit in used:
        exponents, display_units = UNITS[unit]
        element = SubElement(definitions, "Unit", {"name": unit})
        SubElement(element, "BaseUnit", {k: str(e) for k, e in exponents.items()})
        for display, factor in display_units.items():
            SubElement(element, "DisplayUnit", {"name": display, "factor": repr(factor)})


def _input_annotation(root, layout):
    """Every input, for masters that read it (ours does): ``<Input name=.../>`` a system
    must connect, ``<Input name=... optional="what the default means"/>`` it may leave open
    (one element under Tool: the FMI 2.0 schema allows no more)."""
    annotations = SubElement(root, "VendorAnnotations")
    tool = SubElement(annotations, "Tool", {"name": "agilesat"})
    inputs = SubElement(tool, "Inputs")
    for var in layout.group("input"):
        for name in var.scalar_names():
            SubElement(
                inputs,
                "Input",
                {"name": name} if var.required else {"name": name, "optional": var.optional},
            )
    return annotations


def _binaries_annotation(annotations, binaries: dict[str, bytes]) -> None:
    """``<Tool name="agilesat.binaries"><Files><File name=... sha256=.../>``: the SHA-256
    of each shared library, which our master checks before loading it: a damaged binary
    is refused with a message instead of crashing the host (``orchestration/cosim/fmu.py``)."""
    if binaries:
        files = SubElement(SubElement(annotations, "Tool", {"name": BINARIES_TOOL}), "Files")
        for path, data in sorted(binaries.items()):
            SubElement(files, "File", {"name": path, "sha256": hashlib.sha256(data).hexdigest()})


def _model_variables(root, layout):
    variables = SubElement(root, "ModelVariables")
    index = {name: i for i, (_, name) in enumerate(layout.scalars, start=1)}
    for vr, (var, scalar_name) in enumerate(layout.scalars):
        attributes = {
            "name": scalar_name,
            "valueReference": str(vr),
            "description": var.description,
            "causality": var.causality,
        }
        continuous = var.type == "Real" and var.causality != "parameter"
        attributes["variability"] = {"parameter": "fixed"}.get(
            var.causality, "continuous" if continuous else "discrete"
        )
        if var.causality == "parameter":
            attributes["initial"] = "exact"
        elif var.causality == "output":
            attributes["initial"] = "calculated"
        element = SubElement(variables, "ScalarVariable", attributes)
        type_attributes = {}
        if var.type == "Real":
            type_attributes["unit"] = var.unit
            if var.display_unit:
                type_attributes["displayUnit"] = var.display_unit
            if var.derivative_of:
                base = scalar_name.replace(var.name, var.derivative_of, 1)
                type_attributes["derivative"] = str(index[base])
        if var.causality != "output":
            at = vr - layout.offset[var.name]
            type_attributes["start"] = _start_text(var, at)
        SubElement(element, var.type, type_attributes)


def _start_text(var, element_index: int) -> str:
    return start_text(
        var.type, var.start if var.type == "String" else var.start_array()[element_index]
    )


def start_text(type_name: str, value) -> str:
    """A start value as modelDescription.xml writes a value of that type."""
    if type_name == "String":
        return str(value)
    if type_name == "Boolean":
        return "true" if value else "false"
    if type_name == "Integer":
        return str(int(value))
    return xs_double(float(value))


def xs_double(x: float) -> str:
    """x as XML Schema's xs:double writes it: ``repr`` (which reads back the same), and
    INF, -INF, NaN for the values that are not numbers of Python's spelling."""
    return repr(x) if math.isfinite(x) else "NaN" if math.isnan(x) else "INF" if x > 0 else "-INF"


def _model_structure(root, layout, initial_state_depends):
    index = {}  # variable name -> 1-based indices of its scalars in ModelVariables
    for position, (var, _) in enumerate(layout.scalars, start=1):
        index.setdefault(var.name, []).append(position)
    parameters = [i for v in layout.group("parameter") for i in index[v.name]]
    structure = SubElement(root, "ModelStructure")
    outputs = SubElement(structure, "Outputs")
    initial = SubElement(structure, "InitialUnknowns")
    for var in layout.group("output"):
        step_inputs = sorted(i for name in var.depends for i in index[name])
        init_inputs = sorted(
            set(step_inputs)
            | {i for name in initial_state_depends for i in index[name]}
            | set(parameters)
        )
        for position in index[var.name]:
            SubElement(
                outputs,
                "Unknown",
                {"index": str(position), "dependencies": " ".join(map(str, step_inputs))},
            )
            SubElement(
                initial,
                "Unknown",
                {"index": str(position), "dependencies": " ".join(map(str, init_inputs))},
            )
