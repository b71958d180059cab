"""What ``agilesat list`` and ``agilesat info`` print: the scenarios and their variants; a
scenario's metrics, requirements and variants; a system's settings (algorithm, step,
input/output derivative links), components, connections (whole variables), every settable
parameter with unit, value and description, and every output; an FMU's interface.  Arrays
are shown as arrays, and addressed as whole arrays or elements (:mod:`.system.parameters`);
angles in degrees beside radians."""

from __future__ import annotations

import numpy as np

from .cosim.derivatives import derivative_links, describe
from .mission import reads, targets
from .system.description import Description
from .system.parameters import variables
from .system.ssp import read_system
from .system.units import join, pretty, to_degrees
from .system.validation import check_system


def listing() -> str:
    lines = []
    for name in targets.names():
        scenario = targets.scenario(name)
        lines.append(f"{name:16s} {scenario.title}")
        for variant, v in scenario.variants.items():
            lines.append(f"  :{variant:22s} {v.description}")
    lines.append(
        "\nrun one with `agilesat run SCENARIO[:VARIANT]` (or a mission file of your own, "
        "`agilesat run path/to/mission.py`); `agilesat info SCENARIO` lists its parameters"
    )
    return "\n".join(lines)


def info(target: str) -> str:
    """A scenario[:variant], a mission file, an .ssd/.ssp file, an FMU name or .fmu file."""
    found = targets.resolve(target)
    if found.scenario is None and found.system is not None and not found.system.connections:
        system = found.system  # one FMU
        return fmu_info(system.descriptions()[system.components[0]])
    if found.path is not None:
        system = read_system(found.path)
        described = {c.name: Description(c.name, c.source) for c in system.components}
        return system_info(system, described)
    if found.scenario is None:
        system = found.system  # type: ignore[assignment]
        return system_info(system.system_file(), system.descriptions())
    return scenario_info(found.scenario, found.variant)


def scenario_info(scenario, variant: str | None) -> str:
    """A scenario (or one of its variants): what it is held to, its variants, its system."""
    reads.check(scenario, variant)  # what its metrics and requirements read: outputs
    lines = [f"{scenario.name}: {scenario.title}"]
    for name, v in scenario.variants.items():
        lines.append(f"  {'>' if name == variant else ' '} variant :{name} — {v.description}")
    chosen = scenario.variant(variant)
    system = scenario.system_for(variant)
    described = system.descriptions()
    if variant:
        lines.append(f"variant :{variant} (marked '!' below where it changes the system):")
        lines += [
            f"  {key} = {_given(value, _unit(key, described))}"
            for key, value in chosen.parameters.items()
        ]
        if chosen.system is not None:
            lines.append(f"  and its system edited by {chosen.system.__name__}()")
        lines += [f"  not judged: {n} ({why})" for n, why in chosen.exempt().items()]
    units = {m.name: m.unit or _unit_of(m.signal, described) for m in scenario.metrics_for(variant)}
    lines.append("metrics (summary.json; [display unit]):")
    for m in scenario.metrics_for(variant):
        unit = pretty(m.display_unit or units[m.name]) or "-"
        lines.append(f"  {m.name:34s} [{unit}] {m.description}")
    requirements = scenario.requirements_for(variant)
    if requirements:
        lines.append("requirements:")
        for r in requirements:
            metric = {m.name: m for m in scenario.metrics_for(variant)}.get(
                getattr(r, "metric", None)
            )
            shown = (
                r.statement(units[metric.name], metric.display_unit) if metric else r.statement()
            )
            lines.append(f"  {r.name:34s} {shown}")
    changed = set(chosen.parameters) | (
        set(system.parameters) - set(scenario.system.parameters)
        if chosen.system is not None
        else set()
    )
    return (
        "\n".join(lines) + "\n" + system_info(system.system_file(), system.descriptions(), changed)
    )


def _unit_of(signal: str | None, described: dict) -> str | None:
    """The unit of a recorded output ("A.x", "A.x[2]" or a whole array), from its FMU's
    model description."""
    if signal is None:
        return None
    component, _, name = signal.partition(".")
    variables = described[component].variables if component in described else {}
    found = variables.get(name) or next(
        (v for n, v in variables.items() if n.partition("[")[0] == name), None
    )
    return None if found is None else found.unit


def system_info(system, described: dict, changed=frozenset()) -> str:
    """A :class:`.system.ssp.SystemFile` with the Descriptions of its FMUs; ``changed``:
    the parameters ("A.p") a variant sets, marked '!'."""
    bound = {(p.component, p.name): p.value for p in system.parameters}
    wiring = check_system(system, described, system.parameters)
    lines = [
        f"system {system.path}: start {system.start_time:g} s, stop {_g(system.stop_time)} s"
        f", step {_g(system.step_size)} s",
        "  " + _scheme(system, described, wiring),
        "components:",
    ]
    lines += [f"  {c.name:24s} {c.source}" for c in system.components]
    lines.append("connections (whole variables):")
    seen = []
    for c in system.connections:
        wire = (
            f"{c.start_element}.{c.start_connector.split('[')[0]}",
            f"{c.end_element}.{c.end_connector.split('[')[0]}",
        )
        if wire not in seen:
            seen.append(wire)
    lines += [f"  {a} -> {b}" for a, b in seen]
    lines.append(
        "parameters (--set Instance.variable=VALUE; arrays whole, e.g. x=[1,2,3], or "
        "by element, x[2]=5; angles also in degrees, x='120 deg'; '*' = set by the system, "
        "'!' = by the variant, else the FMU's default):"
    )
    for name, d in described.items():
        for var in variables(d).values():
            if var.first.causality != "parameter" or var.first.variability == "constant":
                continue
            values = [bound.get((name, v.name), v.start) for v in var.scalars]
            mark = " "
            if any((name, v.name) in bound for v in var.scalars):
                mark = "!" if f"{name}.{var.name}" in changed else "*"
            lines.append(_row(f"{name}.{var.name}", var, values, mark))
    lines.append("outputs (recorded; `--record`, `agilesat plot`, `campaign --keep` take them):")
    for name, d in described.items():
        outputs = [v for v in variables(d).values() if v.first.causality == "output"]
        lines += [_row(f"{name}.{var.name}", var, None) for var in outputs]
    return "\n".join(lines)


def _g(value) -> str:
    return "-" if value is None else f"{value:g}"


def _scheme(system, described: dict, wiring) -> str:
    """The coupling scheme in words, with the input/output derivative links it makes."""
    algorithm = system.algorithm or "gauss-seidel"
    if system.derivatives is False:
        return f"{algorithm}; input/output derivatives off"
    every = {
        c.name: round(c.step_size / system.step_size) if c.step_size and system.step_size else 1
        for c in system.components
    }
    order = {name: described[name] for name in wiring.steps.step_order}
    links = describe(derivative_links(order, wiring.sources, every, algorithm))
    text = f"{algorithm}; input/output derivatives where both FMUs declare them: "
    text += f"{len(links)} link(s)" + "".join(f"\n    {link}" for link in links)
    if algorithm == "jacobi":
        text += "\n  (Jacobi with derivatives: the master's most accurate scheme, docs/coupling.md)"
    return text


def fmu_info(d: Description) -> str:
    md = d.md
    lines = [
        f"{d.name} ({d.path}): {md.description or ''}".rstrip(),
        f"  FMI {md.fmiVersion}, generated by {md.generationTool}",
    ]
    for causality in ("parameter", "input", "output"):
        rows = [var for var in variables(d).values() if var.first.causality == causality]
        if rows:
            lines.append(f"{causality}s:")
            lines += [
                _row(
                    var.name, var, None if causality == "output" else [v.start for v in var.scalars]
                )
                for var in rows
            ]
    return "\n".join(lines)


def _row(name: str, var, values, mark: str = " ") -> str:
    shape = f"[{'×'.join(map(str, var.shape))}]" if var.shape else ""
    value = "" if values is None else "= " + _format(values, var.shape)
    unit = pretty(var.first.unit) if var.first.type == "Real" else var.first.type
    factor, degrees = to_degrees(var.first.unit) if var.first.type == "Real" else (1.0, None)
    if values is not None and degrees != var.first.unit and degrees is not None:
        value += " (" + _format([_scaled(v, factor) for v in values], var.shape) + ")"
        unit = f"{unit} ({pretty(degrees)})"
    return f" {mark}{name + shape:44s} {unit:13s} {value:30s} {var.first.description or ''}"


def _unit(key: str, described: dict) -> str | None:
    """The unit of parameter ``key`` ("A.x" or "A.x[i]") in its FMU's model description."""
    component, _, name = key.partition(".")
    found = variables(described[component]).get(name.partition("[")[0])
    return None if found is None else found.first.unit


def _given(value, unit: str | None) -> str:
    """A variant's value as it gave it: numbers (arrays too) to 6 digits with their unit,
    in degrees too where it is an angle; text (a value with its unit) as it is."""
    if isinstance(value, str):
        return value
    array = np.asarray(value, dtype=object)
    text = _format(list(array.ravel()), array.shape)
    factor, degrees = to_degrees(unit)
    if degrees != unit and array.dtype != bool and not isinstance(value, bool):
        scaled = [_scaled(v, factor) for v in array.ravel()]
        return f"{join(text, pretty(unit))} ({join(_format(scaled, array.shape), pretty(degrees))})"
    return join(text, pretty(unit))


def _scaled(value, factor):
    try:
        return float(value) * factor
    except (TypeError, ValueError):
        return value


def _format(values, shape) -> str:
    def one(v):
        if v is None:
            return "-"
        if isinstance(v, bool) or v in ("true", "false"):
            return str(v).lower()
        try:
            return f"{float(v):.6g}"
        except (TypeError, ValueError):
            return repr(v)

    if not shape:
        return one(values[0])
    array = np.array([one(v) for v in values], dtype=object).reshape(shape)
    return str(array.tolist()).replace("'", "").replace(" ", "")
