"""Checks of a system against its FMUs, and the dependency orders the master runs in.

:func:`check_system` reports, each naming the file, line, element and variable: unknown
component or variable, causality, type and unit mismatch, an input driven twice, a required
input left open, a parameter value for something that is not a parameter, an algebraic loop
(found while computing the schedules, :mod:`.schedule`).
"""
from __future__ import annotations

from dataclasses import dataclass

from .fmu import Description
from .schedule import Schedule, schedule
from .ssp import ParameterValue, SystemFile, SystemFileError


@dataclass
class Plan:
    steps: Schedule           # stepping: step order and output evaluation blocks
    init: Schedule            # initialisation
    sources: dict[tuple[str, str], tuple[str, str]]  # (B, input) -> (A, output)


def check_system(system: SystemFile, instances: dict[str, Description],
                 bindings: list[ParameterValue]) -> Plan:
    """Check connections and parameters against the FMUs; return the schedules."""
    problems = []
    where = str(system.path)
    sources = {}
    for c in system.connections:
        at = f"{where}:{c.line}: connection {c}"
        a, b = instances.get(c.start_element), instances.get(c.end_element)
        for element, inst in ((c.start_element, a), (c.end_element, b)):
            if inst is None:
                problems.append(f"{at}: unknown component '{element}' (components: "
                                f"{', '.join(instances)})")
        if a is None or b is None:
            continue
        va, vb = a.variables.get(c.start_connector), b.variables.get(c.end_connector)
        if va is None:
            problems.append(f"{at}: {a.name} ({a.path.name}) has no variable "
                            f"'{c.start_connector}'")
        if vb is None:
            problems.append(f"{at}: {b.name} ({b.path.name}) has no variable "
                            f"'{c.end_connector}'")
        if va is None or vb is None:
            continue
        if va.causality != "output":
            problems.append(f"{at}: '{va.name}' of {a.name} is a {va.causality}, expected an "
                            "output")
        if vb.causality != "input":
            problems.append(f"{at}: '{vb.name}' of {b.name} is a {vb.causality}, expected an "
                            "input")
        if va.type != vb.type:
            problems.append(f"{at}: type mismatch, {va.type} -> {vb.type}")
        elif va.type == "Real" and va.unit and vb.unit and va.unit != vb.unit:
            # a Real without a unit (FMI 2.0: optional; e.g. pythonfmu 0.7 writes none) is
            # unspecified, not dimensionless: checked only where both sides declare one
            problems.append(f"{at}: unit mismatch, '{va.unit}' -> '{vb.unit}'")
        key = (b.name, vb.name)
        if key in sources:
            problems.append(f"{at}: input {b.name}.{vb.name} is already driven by "
                            f"{'.'.join(sources[key])}")
        sources[key] = (a.name, va.name)
    for value in bindings:
        inst = instances.get(value.component)
        if inst is None:
            problems.append(f"{value.origin}: parameter for unknown component "
                            f"'{value.component}'")
            continue
        var = inst.variables.get(value.name)
        if var is None:
            problems.append(f"{value.origin}: {inst.name} ({inst.path.name}) has no variable "
                            f"'{value.name}'")
        elif var.causality not in ("parameter", "input") or var.variability == "constant":
            problems.append(f"{value.origin}: {inst.name}.{value.name} is a {var.causality}, "
                            "expected a parameter")
        elif var.type != value.type:
            problems.append(f"{value.origin}: {inst.name}.{value.name} is {var.type}, the "
                            f"value is {value.type}")
    for inst in instances.values():
        line = system.component(inst.name).line
        for name in sorted(inst.required_inputs or ()):
            if (inst.name, name) not in sources:
                problems.append(f"{where}:{line}: component {inst.name}: required input "
                                f"{inst.name}.{name} is not connected")
    if problems:
        raise SystemFileError(f"{where}: {len(problems)} problem(s):\n  " + "\n  ".join(problems))
    return Plan(schedule(instances, sources, "feedthrough", where),
                schedule(instances, sources, "initial_feedthrough", where), sources)


def override(instances, key: str, value) -> ParameterValue:
    """A ``--set Instance.variable=value`` override, typed by the FMU's variable."""
    name, _, variable = key.partition(".")
    if name not in instances or not variable:
        raise SystemFileError(f"--set {key}: expected Instance.variable with an instance of "
                              f"{', '.join(instances)}")
    var = instances[name].variables.get(variable)
    kind = var.type if var is not None else "Real"
    if kind == "Boolean" and isinstance(value, str):
        value = value.lower() in ("1", "true", "yes")
    elif kind in ("Real", "Integer"):
        try:
            value = float(value) if kind == "Real" else int(value)
        except ValueError:
            raise SystemFileError(f"--set {key}={value}: expected a {kind}") from None
    return ParameterValue(name, variable, kind, value, f"--set {key}")
