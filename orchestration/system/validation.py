"""Checks of a system against its FMUs, and the dependency orders the master runs in.

:func:`check_system` reports, each naming the file, line, element and variable: unknown
component or variable, causality, type and unit mismatch (of a connection, and of an SSD
connector against the FMU's variable), an input driven twice, an input left open that may
not be, a parameter value for something that is not a parameter, an algebraic loop (found
while computing the schedules, :mod:`.schedule`); the first :data:`MAX_PROBLEMS_SHOWN`,
then how many more.

Open inputs, the rule: every input of every component is connected, or given a value in
the system's parameter values, or declared optional by its FMU (our FMUs' VendorAnnotations
say what the default of each optional input means).  An open optional input is listed in
``Wiring.open_inputs`` with that meaning (the master logs it, the runner's summary lists it);
an array input is connected as a whole or not at all.  Any other open input of our FMUs is an
error.  An FMU that is not ours declares nothing: its open inputs are listed too, as keeping
their start value, and logged as warnings.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .agreement import disagreements
from .description import Description
from .schedule import Schedule, schedule
from .ssp import ParameterValue, SystemFile, SystemFileError

#: problems a check prints at most (then how many more): 600,000 duplicated connections
#: must not print 600,000 lines
MAX_PROBLEMS_SHOWN = 20


@dataclass
class Wiring:
    """What the checks give the master: who feeds each input, and in which orders."""

    steps: Schedule  # stepping: step order and output evaluation blocks
    init: Schedule  # initialisation
    sources: dict[tuple[str, str], tuple[str, str]]  # (B, input) -> (A, output)
    #: open inputs allowed to be open: {"input": "B.u", "meaning": ..., "declared": bool}
    open_inputs: list[dict] = field(default_factory=list)


def check_system(
    system: SystemFile, instances: dict[str, Description], bindings: list[ParameterValue]
) -> Wiring:
    """Check connections and parameters against the FMUs; return the schedules.

    Every problem is collected first (connections, parameter values, SSD connectors, open
    inputs, parameters that must agree between FMUs), then all are raised together."""
    where = str(system.path)
    problems: list[str] = []
    sources = _connections(system, instances, problems)
    problems += _binding_problems(instances, bindings)
    problems += _connector_problems(system, instances)
    open_inputs = _open_inputs(system, instances, sources, bindings, problems)
    problems += disagreements(instances, bindings, sources)
    if problems:
        shown = problems[:MAX_PROBLEMS_SHOWN]
        more = len(problems) - len(shown)
        raise SystemFileError(
            f"{where}: {len(problems)} problem(s):\n  "
            + "\n  ".join(shown)
            + (f"\n  ... and {more} more of these kinds" if more else "")
        )
    return Wiring(
        schedule(instances, sources, "feedthrough", where),
        schedule(instances, sources, "initial_feedthrough", where),
        sources,
        open_inputs,
    )


def _connections(system, instances, problems) -> dict[tuple[str, str], tuple[str, str]]:
    """The connections that check out, as {(B, input): (A, output)}; the others go to
    problems.  The rule: both components and variables exist, an output drives an input,
    types agree, units agree where both sides declare one, no input is driven twice."""
    sources: dict[tuple[str, str], tuple[str, str]] = {}
    for c in system.connections:
        at = f"{system.path}:{c.line}: connection {c}"
        a, b = instances.get(c.start_element), instances.get(c.end_element)
        for element, inst in ((c.start_element, a), (c.end_element, b)):
            if inst is None:
                problems.append(
                    f"{at}: unknown component '{element}' (components: {', '.join(instances)})"
                )
        if a is None or b is None:
            continue
        va, vb = a.variables.get(c.start_connector), b.variables.get(c.end_connector)
        if va is None:
            problems.append(f"{at}: {a.name} ({a.path.name}) has no variable '{c.start_connector}'")
        if vb is None:
            problems.append(f"{at}: {b.name} ({b.path.name}) has no variable '{c.end_connector}'")
        if va is None or vb is None:
            continue
        problems += variable_pair_problems(at, a, va, b, vb)
        key = (b.name, vb.name)
        if key in sources:
            problems.append(
                f"{at}: input {b.name}.{vb.name} is already driven by {'.'.join(sources[key])}"
            )
        sources[key] = (a.name, va.name)
    return sources


def variable_pair_problems(at: str, a, va, b, vb) -> list[str]:
    """One connection's ends: an output of ``a`` to an input of ``b``, same type and unit."""
    problems = []
    if va.causality != "output":
        problems.append(f"{at}: '{va.name}' of {a.name} is {_a(va.causality)}, expected an output")
    if vb.causality != "input":
        problems.append(f"{at}: '{vb.name}' of {b.name} is {_a(vb.causality)}, expected an input")
    if va.type != vb.type:
        problems.append(f"{at}: type mismatch, {va.type} -> {vb.type}")
    elif va.type == "Real" and va.unit and vb.unit and va.unit != vb.unit:
        # a Real without a unit (FMI 2.0: optional; e.g. pythonfmu 0.7 writes none) is
        # unspecified, not dimensionless: checked only where both sides declare one
        problems.append(f"{at}: unit mismatch, '{va.unit}' -> '{vb.unit}'")
    return problems


def _binding_problems(instances, bindings) -> list[str]:
    """Parameter values; the rule: each names a variable of a known component that is a
    parameter or an input (not a constant), and has that variable's type; two variables
    that are one in the FMU (the same value reference and type: aliases, FMI 2.0 section
    2.2.7) are not given two values."""
    problems = []
    last = {(value.component, value.name): value for value in bindings}  # the value set last
    aliases: dict[tuple, ParameterValue] = {}
    for value in last.values():
        var = getattr(instances.get(value.component), "variables", {}).get(value.name)
        if var is None:
            continue
        key = (value.component, var.type, var.valueReference)
        other = aliases.setdefault(key, value)
        if other is not value and other.value != value.value:
            problems.append(
                f"{value.origin} and {other.origin}: {value.component}.{value.name}="
                f"{value.value} and {other.name}={other.value}: the FMU has them as one "
                f"variable (value reference {var.valueReference}: aliases), which cannot "
                "take two values"
            )
    for value in bindings:
        inst = instances.get(value.component)
        if inst is None:
            problems.append(f"{value.origin}: parameter for unknown component '{value.component}'")
            continue
        var = inst.variables.get(value.name)
        if var is None:
            problems.append(
                f"{value.origin}: {inst.name} ({inst.path.name}) has no variable '{value.name}'"
            )
        elif var.causality not in ("parameter", "input") or var.variability == "constant":
            problems.append(
                f"{value.origin}: {inst.name}.{value.name} is {_a(var.causality)}, "
                "expected a parameter"
            )
        elif var.type != value.type:
            problems.append(
                f"{value.origin}: {inst.name}.{value.name} is {var.type}, the value is {value.type}"
            )
    return problems


def _open_inputs(system, instances, sources, bindings, problems) -> list[dict]:
    """The open inputs that may be open (see the module's rule); the others go to problems."""
    where, result = str(system.path), []
    given = set(sources) | {(b.component, b.name) for b in bindings}
    for inst in instances.values():
        at = f"{where}:{system.component(inst.name).line}: component {inst.name}"
        inputs = [v for v in inst.md.modelVariables if v.causality == "input"]
        open_ = [v for v in inputs if (inst.name, v.name) not in given]
        if inst.optional_inputs is None:  # not our FMU: nothing declared
            result += [
                {
                    "input": f"{inst.name}.{v.name}",
                    "declared": False,
                    "meaning": f"keeps its start value {v.start} (the FMU declares no "
                    "optional inputs)",
                }
                for v in open_
            ]
            continue
        groups: dict[str, list] = {}
        members_of: dict[str, list[str]] = {}  # variable -> the names of its scalars
        for v in inputs:
            members_of.setdefault(v.name.partition("[")[0], []).append(v.name)
        for v in open_:
            if v.name in inst.optional_inputs:
                groups.setdefault(v.name.partition("[")[0], []).append(v.name)
            else:
                problems.append(
                    f"{at}: required input {inst.name}.{v.name} is not connected "
                    "(connect it or give it a parameter value)"
                )
        for variable, names in groups.items():
            members = members_of[variable]
            rows = {variable: names} if len(names) == len(members) else _open_rows(names, members)
            if rows is None:
                given_ = [m for m in members if m not in names]
                problems.append(
                    f"{at}: input {inst.name}.{variable} is partly connected: "
                    f"{', '.join(names)} open, {', '.join(given_)} connected or "
                    "set (connect all of it or none"
                    + (", or whole rows of it)" if "," in members[0] else ")")
                )
                continue
            result += [
                {
                    "input": f"{inst.name}.{part}",
                    "declared": True,
                    "meaning": inst.optional_inputs[open_part[0]],
                }
                for part, open_part in rows.items()
            ]
    return result


def _open_rows(names: list[str], members: list[str]) -> dict[str, list[str]] | None:
    """{"x[2]": its open scalars} of a matrix input ``members`` whose open scalars
    ``names`` make whole rows (a table of slots is fed row by row); None otherwise."""
    if "," not in members[0]:
        return None
    rows: dict[str, list[str]] = {}
    for member in members:
        rows.setdefault(member.partition(",")[0] + "]", []).append(member)
    open_rows = {row: scalars for row, scalars in rows.items() if scalars[0] in names}
    whole = all(set(scalars) <= set(names) for scalars in open_rows.values())
    return open_rows if whole and sum(map(len, open_rows.values())) == len(names) else None


def _connector_problems(system, instances) -> list[str]:
    """SSD connectors that disagree with the FMU's variable (kind, type, unit)."""
    problems = []
    for ref in system.components:
        inst = instances.get(ref.name)
        for c in ref.connectors if inst is not None else ():
            at = f"{system.path}:{c.line}: connector {ref.name}.{c.name}"
            var = inst.variables.get(c.name)
            if var is None:
                problems.append(f"{at}: {ref.name} ({inst.path.name}) has no variable '{c.name}'")
                continue
            if c.kind in ("input", "output", "parameter") and c.kind != var.causality:
                problems.append(
                    f"{at}: declared {c.kind}, the FMU's variable is {_a(var.causality)}"
                )
            if c.type is not None and c.type != var.type:
                problems.append(f"{at}: declared {c.type}, the FMU's variable is {var.type}")
            elif c.unit is not None and var.type == "Real" and c.unit != (var.unit or ""):
                problems.append(
                    f"{at}: declared unit '{c.unit}', the FMU's variable has '{var.unit or ''}'"
                )
    return problems


def _a(noun: str) -> str:
    """'an output', 'an input', 'a parameter'."""
    return f"{'an' if noun[:1] in 'aeiou' else 'a'} {noun}"
