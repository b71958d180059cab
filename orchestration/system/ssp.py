"""System descriptions in the SSP 1.0 standard: read ``.ssd`` / ``.ssp`` files, write ``.ssd``.

Read: components with their FMU sources, connections, and parameter values bound with
``ssd:ParameterBindings`` (inline ``ssv:ParameterSet`` or an ``.ssv`` file), the default
experiment (start, stop) and our master's settings (step size, algorithm) from an
annotation of type ``org.agilesat.master``.  The file is first checked against the SSP XSD
schemas that fmpy ships, then every error names the file, line, element and variable.
The check against the FMUs themselves (variables, causality, type, unit, also of the
declared connectors) is :func:`validation.check_system`, which needs the model descriptions.

An ``.ssp`` package is unpacked into a temporary directory, refusing members with absolute
paths or ``..`` and more than ``max_unpacked`` bytes in total, counting what its FMUs unpack
to when they run (default :data:`MAX_UNPACKED_BYTES`, 256 MiB, or the environment variable
``AGILESAT_SSP_MAX_BYTES``) or more than :data:`MAX_MEMBERS` members (in it or in an FMU
in it); its component and parameter-binding sources must resolve inside the package.  A
parameter bound twice in one parameter set is refused.

Write: :func:`render_ssd` writes a :class:`SystemFile` (read from a file, or made in Python
by :class:`..mission.System`) as an SSD: each component's connectors, types and units as its
FMU's model description declares them, the parameter values, the connections, the SSP unit
definitions (copied from the FMUs') and the settings.
"""

from __future__ import annotations

import math
import tempfile
import zipfile
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

from lxml import etree

from ...components.runtime.switches import value as switch
from .steps import read_step, write_step

NS = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
}
MASTER_ANNOTATION = "org.agilesat.master"
MASTER_NAMESPACE = "http://agilesat.org/ssp/master"
OSP_ANNOTATION = "com.opensimulationplatform"
OSP_NAMESPACE = "https://opensimulationplatform.com/SSP/1.0"
OMS_ANNOTATION = "org.openmodelica"
OMS_NAMESPACE = "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd"
_PREFIXES = {**NS, "agilesat": MASTER_NAMESPACE, "osp": OSP_NAMESPACE, "oms": OMS_NAMESPACE}
_TYPES = ("Real", "Integer", "Boolean", "String")
#: fmi2Integer is a 32-bit int (FMI 2.0 section 2.1.2)
INTEGER_RANGE = (-(2**31), 2**31 - 1)
MAX_UNPACKED_BYTES = 256 * 2**20
#: the most members an .ssp package, or an FMU inside it, may have
MAX_MEMBERS = 10_000


class SystemFileError(ValueError):
    """A system description is malformed or inconsistent with its FMUs."""


@dataclass
class ConnectorRef:
    name: str
    kind: str
    type: str | None  # Real, Integer, Boolean, String; None: not declared
    unit: str | None  # of a Real; None: not declared
    line: int


@dataclass
class ComponentRef:
    name: str
    source: Path  # absolute path of the FMU
    line: int
    connectors: list[ConnectorRef] = field(default_factory=list)
    step_size: float | None = None  # its own communication step (steps.py), if any


@dataclass
class ConnectionRef:
    start_element: str
    start_connector: str
    end_element: str
    end_connector: str
    line: int

    def __str__(self):
        return (
            f"{self.start_element}.{self.start_connector} -> "
            f"{self.end_element}.{self.end_connector}"
        )


@dataclass
class ParameterValue:
    component: str
    name: str
    type: str
    value: object
    origin: str  # "file:line" where the value was given


@dataclass
class SystemFile:
    path: Path
    name: str
    components: list[ComponentRef]
    connections: list[ConnectionRef]
    parameters: list[ParameterValue]
    start_time: float = 0.0
    stop_time: float | None = None
    step_size: float | None = None
    algorithm: str | None = None
    derivatives: bool | None = None  # couple through input/output derivatives (None: yes)
    _tempdir: object = field(default=None, repr=False)

    def component(self, name: str) -> ComponentRef:
        for c in self.components:
            if c.name == name:
                return c
        raise KeyError(name)


def read_system(path, *, max_unpacked: int | None = None) -> SystemFile:
    """Read an ``.ssd`` file, or the ``SystemStructure.ssd`` of an ``.ssp`` package
    (unpacking at most ``max_unpacked`` bytes)."""
    path = Path(path).resolve()
    if not path.exists():
        raise SystemFileError(f"{path}: no such file")
    if path.suffix == ".ssp":
        tempdir = tempfile.TemporaryDirectory(prefix="agilesat_ssp_")
        root = Path(tempdir.name).resolve()
        _unpack(path, root, max_unpacked)
        ssd = root / "SystemStructure.ssd"
        if not ssd.exists():
            raise SystemFileError(f"{path}: the package has no SystemStructure.ssd")
        system = _read_ssd(ssd, display=f"{path.name}!SystemStructure.ssd", package=root)
        system._tempdir = tempdir
        return system
    return _read_ssd(path, display=str(path))


def _unpack(path: Path, root: Path, limit: int | None) -> None:
    """Unpack an SSP package into root: no member outside it, at most limit bytes."""
    if limit is None:
        limit = switch("AGILESAT_SSP_MAX_BYTES") or MAX_UNPACKED_BYTES
    _count_members(path, path)
    try:
        with zipfile.ZipFile(path) as archive:
            members = archive.infolist()
            for info in members:
                parts = PurePosixPath(info.filename.replace("\\", "/")).parts
                if (
                    info.filename.startswith(("/", "\\"))
                    or ".." in parts
                    or (parts and ":" in parts[0])
                ):
                    raise SystemFileError(
                        f"{path}: member '{info.filename}' would unpack "
                        "outside the package: refused"
                    )
            declared = sum(info.file_size for info in members)
            if declared > limit:
                raise SystemFileError(
                    f"{path}: unpacks to {declared} bytes, more than the "
                    f"limit of {limit} (raise it with "
                    "AGILESAT_SSP_MAX_BYTES or max_unpacked=)"
                )
            total = 0
            for info in members:
                target = root.joinpath(*PurePosixPath(info.filename).parts)
                if info.is_dir():
                    target.mkdir(parents=True, exist_ok=True)
                    continue
                target.parent.mkdir(parents=True, exist_ok=True)
                with archive.open(info) as source, target.open("wb") as sink:
                    while chunk := source.read(1 << 20):
                        total += len(chunk)
                        if total > limit:
                            raise SystemFileError(
                                f"{path}: unpacks to more than the limit of {limit} bytes"
                            )
                        sink.write(chunk)
    except (zipfile.BadZipFile, EOFError) as exc:
        raise SystemFileError(f"{path}: not an SSP package (zip): {exc}") from None
    _nested_fmus(path, root, total, limit)


def _count_members(path: Path, what) -> None:
    """At most :data:`MAX_MEMBERS` members in the zip archive ``path``, counted from its end
    of central directory record before anything reads the directory (zipfile holds an
    object of some hundred bytes per member: a million empty members would take a
    gigabyte before the size limit is looked at).  Not a zip: left to zipfile to say."""
    try:
        with open(path, "rb") as file:
            file.seek(0, 2)
            size = file.tell()
            file.seek(max(0, size - (1 << 16) - 22))
            tail = file.read()
            at = tail.rfind(b"PK\x05\x06")
            if at < 0 or len(tail) < at + 22:
                return
            count = int.from_bytes(tail[at + 10 : at + 12], "little")
            locator = at - 20
            if count == 0xFFFF and locator >= 0 and tail[locator : locator + 4] == b"PK\x06\x07":
                file.seek(int.from_bytes(tail[locator + 8 : locator + 16], "little"))
                record = file.read(56)
                if record[:4] == b"PK\x06\x06":
                    count = int.from_bytes(record[32:40], "little")
    except OSError:
        return
    if count > MAX_MEMBERS:
        raise SystemFileError(
            f"{what}: a zip archive of {count} members, more than the {MAX_MEMBERS} a "
            "package (or an FMU in it) may have: refused before unpacking"
        )


def _nested_fmus(path: Path, root: Path, total: int, limit: int) -> None:
    """The bound covers what the package's FMUs unpack to when they are run (each one is
    unpacked by the master: ``cosim/fmu.py``), by their declared sizes, which unpacking
    holds them to (zipfile stops at a member's declared size: its CRC then fails)."""
    for fmu in sorted(root.rglob("*.fmu")):
        _count_members(fmu, f"{path}: {fmu.relative_to(root)}")
        try:
            with zipfile.ZipFile(fmu) as archive:
                size = sum(info.file_size for info in archive.infolist())
        except (zipfile.BadZipFile, OSError):
            continue  # not a zip: the run says so when it reads it
        total += size
        if total > limit:
            raise SystemFileError(
                f"{path}: unpacks, with its FMUs, to more than the limit of {limit} bytes "
                f"({fmu.relative_to(root)} alone unpacks to {size} bytes; raise the limit "
                "with AGILESAT_SSP_MAX_BYTES or max_unpacked=)"
            )


def _inside(source: Path, package: Path | None, where: str, what: str) -> None:
    if package is not None and not source.is_relative_to(package):
        raise SystemFileError(f"{where}: {what} resolves outside the package ({source}): refused")


def _read_ssd(path: Path, display: str, package: Path | None = None) -> SystemFile:
    """One ``.ssd`` file, schema-checked: its components (with their parameter bindings),
    the system-level bindings, the connections and the default experiment."""
    tree = _parse(path, display)
    _validate_schema(tree, "SystemStructureDescription.xsd", display)
    root = tree.getroot()
    system = root.find("ssd:System", NS)
    components, parameters = _read_components(system, path, display, package)
    for binding in system.findall("ssd:ParameterBindings/ssd:ParameterBinding", NS):
        parameters += _read_binding(binding, None, path, display, package)
    connections = _read_connections(system, display)
    result = SystemFile(path, root.get("name"), components, connections, parameters)
    _read_experiment(root, result, display)
    return result


def _read_components(
    system, path: Path, display: str, package: Path | None
) -> tuple[list[ComponentRef], list[ParameterValue]]:
    """The system's elements and their parameter values.  The rule: every element is a
    ``<Component>`` of type ``application/x-fmu-sharedlibrary`` with a unique name and an
    FMU source that exists (inside the package, for an ``.ssp``)."""
    components: list[ComponentRef] = []
    parameters: list[ParameterValue] = []
    for element in system.findall("ssd:Elements/*", NS):
        tag = etree.QName(element).localname
        where = f"{display}:{element.sourceline}"
        if tag != "Component":
            raise SystemFileError(
                f"{where}: <{tag}> elements are not supported (flat systems of FMU components only)"
            )
        name = element.get("name")
        kind = element.get("type", "application/x-fmu-sharedlibrary")
        if kind != "application/x-fmu-sharedlibrary":
            raise SystemFileError(
                f"{where}: component '{name}' has type '{kind}'; only FMUs "
                "(application/x-fmu-sharedlibrary) are supported"
            )
        if any(c.name == name for c in components):
            raise SystemFileError(f"{where}: component name '{name}' is used twice")
        source = (path.parent / element.get("source")).resolve()
        _inside(source, package, where, f"component '{name}': FMU source '{element.get('source')}'")
        if not source.is_file():
            raise SystemFileError(
                f"{where}: component '{name}': FMU source "
                f"'{element.get('source')}' not found (looked at {source})"
            )
        components.append(
            ComponentRef(
                name,
                source,
                element.sourceline,
                _read_connectors(element),
                read_step(element, where),
            )
        )
        for binding in element.findall("ssd:ParameterBindings/ssd:ParameterBinding", NS):
            parameters += _read_binding(binding, name, path, display, package)
    return components, parameters


def _read_connections(system, display: str) -> list[ConnectionRef]:
    """The connections; the rule: both ends are components (no system-level connectors)."""
    connections = [
        ConnectionRef(
            c.get("startElement"),
            c.get("startConnector"),
            c.get("endElement"),
            c.get("endConnector"),
            c.sourceline,
        )
        for c in system.findall("ssd:Connections/ssd:Connection", NS)
    ]
    for c in connections:
        if not c.start_element or not c.end_element:
            raise SystemFileError(
                f"{display}:{c.line}: connection {c}: connections to the "
                "system's own connectors are not supported"
            )
    return connections


def _read_experiment(root, result: SystemFile, display: str) -> None:
    """Start and stop time from ``ssd:DefaultExperiment``; step size and algorithm from
    its ``org.agilesat.master`` annotation (other hosts' annotations are ignored)."""
    experiment = root.find("ssd:DefaultExperiment", NS)
    if experiment is None:
        return
    result.start_time = float(experiment.get("startTime", 0.0))
    if experiment.get("stopTime") is not None:
        result.stop_time = float(experiment.get("stopTime"))
    for annotation in experiment.findall("ssd:Annotations/ssc:Annotation", NS):
        if annotation.get("type") == MASTER_ANNOTATION and len(annotation):
            settings = annotation[0]
            text = settings.get("stepSize")
            if text is not None:
                try:
                    result.step_size = float(text)
                except ValueError:
                    raise SystemFileError(
                        f"{display}:{settings.sourceline}: the {MASTER_ANNOTATION} annotation's "
                        f"stepSize is {text!r}: expected the macro step in seconds, like 0.05"
                    ) from None
            result.algorithm = settings.get("algorithm")
            if settings.get("derivatives") is not None:
                result.derivatives = settings.get("derivatives") == "true"


def _read_connectors(element) -> list[ConnectorRef]:
    """A component's declared connectors: name, kind and, when given, type and unit."""
    result = []
    for c in element.findall("ssd:Connectors/ssd:Connector", NS):
        typed = [t for t in c if etree.QName(t).localname in _TYPES]
        kind = etree.QName(typed[0]).localname if typed else None
        unit = typed[0].get("unit") if typed else None
        result.append(ConnectorRef(c.get("name"), c.get("kind"), kind, unit, c.sourceline))
    return result


def _read_binding(
    binding, component, ssd_path: Path, display: str, package: Path | None = None
) -> list[ParameterValue]:
    """The values of one ``ssd:ParameterBinding`` (of ``component``, or system-level when
    None).  The rule: each parameter has exactly one typed value; a system-level name is
    ``Component.variable``; the binding's ``prefix`` is put before every name."""
    prefix = binding.get("prefix", "")
    parameter_set, ssv_display = _parameter_set(binding, ssd_path, display, package)
    values = []
    lines: dict[str, int] = {}  # name -> the line it is bound at
    for parameter in parameter_set.findall("ssv:Parameters/ssv:Parameter", NS):
        name = prefix + parameter.get("name")
        origin = f"{ssv_display}:{parameter.sourceline}"
        if name in lines:
            raise SystemFileError(
                f"{origin}: parameter '{name}' is bound twice in one parameter set "
                f"(first at line {lines[name]}): which value holds would be a guess"
            )
        lines[name] = parameter.sourceline
        owner = component
        if owner is None:  # system-level binding: "Component.variable"
            owner, _, name = name.partition(".")
            if not name:
                raise SystemFileError(
                    f"{origin}: system-level parameter "
                    f"'{parameter.get('name')}' must be 'Component.variable'"
                )
        typed = [child for child in parameter if etree.QName(child).localname in _TYPES]
        if len(typed) != 1:
            raise SystemFileError(f"{origin}: parameter '{name}' needs exactly one of {_TYPES}")
        kind = etree.QName(typed[0]).localname
        values.append(
            ParameterValue(owner, name, kind, _parse_value(kind, typed[0], origin), origin)
        )
    return values


def _parameter_set(binding, ssd_path: Path, display: str, package: Path | None):
    """(``ssv:ParameterSet`` element, file it is in) of a binding: from its ``source``
    ``.ssv`` file (schema-checked, inside the package), else inline."""
    source = binding.get("source")
    if not source:
        parameter_set = binding.find("ssd:ParameterValues/ssv:ParameterSet", NS)
        if parameter_set is None:
            raise SystemFileError(
                f"{display}:{binding.sourceline}: parameter binding without "
                "source or inline ssv:ParameterSet"
            )
        return parameter_set, display
    ssv_path = (ssd_path.parent / source).resolve()
    _inside(
        ssv_path, package, f"{display}:{binding.sourceline}", f"parameter binding source '{source}'"
    )
    if not ssv_path.exists():
        raise SystemFileError(
            f"{display}:{binding.sourceline}: parameter binding source "
            f"'{source}' not found (looked at {ssv_path})"
        )
    tree = _parse(ssv_path, str(ssv_path))
    _validate_schema(tree, "SystemStructureParameterValues.xsd", str(ssv_path))
    return tree.getroot(), str(ssv_path)


def _parse_value(kind, element, origin):
    text = element.get("value")
    if text is None:
        raise SystemFileError(f"{origin}: missing value attribute")
    try:
        if kind == "Real":
            value = float(text)
            if not math.isfinite(value):
                raise ValueError("not finite")
            return value
        if kind == "Integer":
            value = int(text)
            if not INTEGER_RANGE[0] <= value <= INTEGER_RANGE[1]:  # it would wrap
                raise ValueError(
                    f"an Integer is from {INTEGER_RANGE[0]} to {INTEGER_RANGE[1]} (32 bits)"
                )
            return value
        if kind == "Boolean":
            if text not in ("true", "false", "1", "0"):
                raise ValueError("expected true or false")
            return text in ("true", "1")
        return text
    except ValueError as exc:
        raise SystemFileError(f"{origin}: bad {kind} value '{text}': {exc}") from None


def _parse(path: Path, display: str):
    try:
        return etree.parse(str(path))
    except etree.XMLSyntaxError as exc:
        raise SystemFileError(f"{display}: not well-formed XML: {exc}") from None


def _validate_schema(tree, schema_name: str, display: str) -> None:
    schema = _schema(schema_name)
    if not schema.validate(tree):
        problems = "; ".join(f"line {e.line}: {e.message}" for e in schema.error_log)
        raise SystemFileError(f"{display}: does not follow the SSP 1.0 schema: {problems}")


_schemas: dict[str, etree.XMLSchema] = {}


def _schema(name: str) -> etree.XMLSchema:
    if name not in _schemas:
        import fmpy.ssp  # the SSP 1.0 XSDs ship with fmpy

        directory = Path(fmpy.ssp.__file__).parent / "schema"
        _schemas[name] = etree.XMLSchema(file=str(directory / name))
    return _schemas[name]


# ---------------------------------------------------------------------------------------
# writing


def render_ssd(system: SystemFile, descriptions: dict, sources: dict | None = None) -> bytes:
    """An SSD (schema-checked bytes) of ``system``.

    ``descriptions`` maps each component to its :class:`.description.Description` (its
    connectors, their types and units, and the unit definitions come from there);
    ``sources`` maps a component to its FMU source as written in the SSD (a URI relative to
    the SSD; default: the component's absolute path).

    For third-party hosts: every component's parameter set is named after the system (ECOS
    applies only the one set named at its init); String connectors without a bound value
    are left out (hosts that cannot set Strings); the step is also written in the
    annotations that libcosim (Open Simulation Platform, on the default experiment) and
    OMSimulator (OpenModelica, on the system; it refuses a system without one) read.  A
    component's own communication step is written as :mod:`.steps` says.
    """
    E = _Maker()
    name = system.name
    root = E("ssd:SystemStructureDescription", version="1.0", name=name, generationTool="agilesat")
    element = E.sub(root, "ssd:System", name=name)
    elements = E.sub(element, "ssd:Elements")
    bound: dict[str, dict] = {}
    for value in system.parameters:
        bound.setdefault(value.component, {})[value.name] = (value.type, _text(value))
    used_units: dict[str, dict] = {}
    for ref in system.components:
        source = (sources or {}).get(ref.name) or str(ref.source)
        _write_component(
            E,
            elements,
            ref.name,
            source,
            descriptions[ref.name],
            bound.get(ref.name, {}),
            name,
            ref.step_size,
            used_units,
        )
    if system.connections:  # the schema wants a Connections element to hold one or more
        wires = E.sub(element, "ssd:Connections")
    if system.step_size is not None:
        _oms_annotation(E, element, system.step_size)
    for c in system.connections:
        E.sub(
            wires,
            "ssd:Connection",
            startElement=c.start_element,
            startConnector=c.start_connector,
            endElement=c.end_element,
            endConnector=c.end_connector,
        )
    _write_units(E, root, used_units)
    _write_experiment(E, root, system)
    tree = etree.ElementTree(root)
    _validate_schema(tree, "SystemStructureDescription.xsd", f"generated {name}.ssd")
    return etree.tostring(tree, pretty_print=True, xml_declaration=True, encoding="UTF-8")


_KINDS = ("parameter", "calculatedParameter", "input", "output")


def _write_component(
    E, elements, instance, source, described, values: dict, set_name, step, used_units
) -> None:
    """One ``ssd:Component``: a scalar connector per parameter, input and output of its
    model description (a Real with its unit where the FMU defines that unit; a String
    only when it is given a value), then its bound values in one inline
    ``ssv:ParameterSet`` named ``set_name``, then its own communication step, if it has
    one (:func:`.steps.write_step`).  Adds the units it uses to ``used_units``."""
    component = E.sub(
        elements,
        "ssd:Component",
        name=instance,
        source=source,
        type="application/x-fmu-sharedlibrary",
    )
    connectors = E.sub(component, "ssd:Connectors")
    for v in described.md.modelVariables:
        if v.causality not in _KINDS or v.type not in _TYPES:
            continue
        if v.type == "String" and v.name not in values:
            continue
        connector = E.sub(connectors, "ssd:Connector", name=v.name, kind=v.causality)
        unit = v.unit if v.type == "Real" and v.unit in described.base_units else None
        if unit is not None:
            used_units.setdefault(unit, described.base_units[unit])
        E.sub(connector, f"ssc:{v.type}", **({"unit": unit} if unit is not None else {}))
    if values:
        bindings = E.sub(component, "ssd:ParameterBindings")
        binding = E.sub(bindings, "ssd:ParameterBinding")
        holder = E.sub(binding, "ssd:ParameterValues")
        parameter_set = E.sub(holder, "ssv:ParameterSet", version="1.0", name=set_name)
        listing = E.sub(parameter_set, "ssv:Parameters")
        for scalar, (kind, text) in values.items():
            parameter = E.sub(listing, "ssv:Parameter", name=scalar)
            E.sub(parameter, f"ssv:{kind}", value=text)
    write_step(component, step)


def _text(value: ParameterValue) -> str:
    """A typed parameter value as SSV writes it (a Real by ``repr``: it reads back the
    same; an infinite one as xs:double spells it, INF or -INF)."""
    if value.type == "Real":
        x = float(value.value)  # type: ignore[arg-type]
        return repr(x) if math.isfinite(x) else "INF" if x > 0 else "-INF"
    if value.type == "Integer":
        return str(int(value.value))  # type: ignore[call-overload]
    if value.type == "Boolean":
        return "true" if value.value else "false"
    return str(value.value)


def _write_units(E, root, used_units: dict[str, dict]) -> None:
    """``ssd:Units``: each unit used by a connector, sorted by name, with the base-unit
    attributes of the FMU's unit definition."""
    unit_list = E.sub(root, "ssd:Units")
    for unit in sorted(used_units):
        element = E.sub(unit_list, "ssc:Unit", name=unit)
        E.sub(element, "ssc:BaseUnit", **used_units[unit])


def _write_experiment(E, root, system: SystemFile) -> None:
    """``ssd:DefaultExperiment`` with our master's settings and libcosim's step annotation.

    libcosim's SSP loader reads the step from the Open Simulation Platform's annotation.
    Its parser (libcosim 0.10, boost property_tree) matches the literal prefix "osp:" and
    takes any attribute of <osp:Algorithm>, xmlns included, for an unknown algorithm: so
    the namespace is declared on the annotation."""
    times = {"startTime": repr(float(system.start_time))}
    if system.stop_time is not None:
        times["stopTime"] = repr(float(system.stop_time))
    experiment = E.sub(root, "ssd:DefaultExperiment", **times)
    settings = {}
    if system.step_size is not None:
        settings["stepSize"] = repr(float(system.step_size))
    if system.algorithm is not None:
        settings["algorithm"] = system.algorithm
    if system.derivatives is False:
        settings["derivatives"] = "false"
    if not settings:
        return
    annotations = E.sub(experiment, "ssd:Annotations")
    annotation = E.sub(annotations, "ssc:Annotation", type=MASTER_ANNOTATION)
    E.sub(annotation, "agilesat:Master", nsmap={"agilesat": MASTER_NAMESPACE}, **settings)
    if system.step_size is not None:
        osp = E.sub(
            annotations, "ssc:Annotation", nsmap={"osp": OSP_NAMESPACE}, type=OSP_ANNOTATION
        )
        E.sub(
            E.sub(osp, "osp:Algorithm"),
            "osp:FixedStepAlgorithm",
            baseStepSize=repr(float(system.step_size)),
        )


def _oms_annotation(E, system, step: float) -> None:
    """OMSimulator's fixed-step master on the system (written and read by OMSimulator as
    ssd:Annotations/ssc:Annotation type="org.openmodelica"/oms:Annotations/
    oms:SimulationInformation/oms:FixedStepMaster, e.g. its testsuite's exported SSDs);
    after ssd:Connections, where the SSD schema puts a system's annotations."""
    annotation = E.sub(
        E.sub(system, "ssd:Annotations"),
        "ssc:Annotation",
        nsmap={"oms": OMS_NAMESPACE},
        type=OMS_ANNOTATION,
    )
    information = E.sub(E.sub(annotation, "oms:Annotations"), "oms:SimulationInformation")
    E.sub(information, "oms:FixedStepMaster", description="oms-ma", stepSize=repr(float(step)))


class _Maker:
    """Tiny helper for namespaced lxml elements: E("ssd:System", name=...)."""

    def __call__(self, tag, **attributes):
        return etree.Element(self._qname(tag), {k: str(v) for k, v in attributes.items()}, nsmap=NS)

    def sub(self, parent, tag, nsmap=None, **attributes):
        """A child element; ``nsmap`` declares further namespaces on it."""
        attributes = {k: str(v) for k, v in attributes.items()}
        return etree.SubElement(parent, self._qname(tag), attributes, nsmap=nsmap)

    @staticmethod
    def _qname(tag):
        prefix, local = tag.split(":")
        return f"{{{_PREFIXES[prefix]}}}{local}"
