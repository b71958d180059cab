"""Write the call script of ``fmi2_host.c`` for a system: our master's run
(orchestration/cosim/master.py, Gauss-Seidel or Jacobi, single rate) call for call — the same
calls in the same order with the same values, except that each array get/set of the
master becomes one call per variable — so that the C host's results must equal the
master's bit for bit.

Only model descriptions are read here; no FMU is loaded in this process.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

from agilesat.orchestration.cosim.master import evaluation_sequence, value_layout
from agilesat.orchestration.system.description import Description
from agilesat.orchestration.system.ssp import read_system
from agilesat.orchestration.system.validation import check_system

TYPES = {"Real": "R", "Integer": "I", "Boolean": "B", "String": "S"}


def write_script(system_path, script: Path, unzip_root: Path, stop: float | None = None) -> list:
    """Extract the system's FMUs under ``unzip_root``, write the script; return the
    recorded column names ("Instance.variable", the master's column order)."""
    system = read_system(system_path)
    descriptions = {c.name: Description(c.name, c.source) for c in system.components}
    plan = check_system(system, descriptions, system.parameters)
    start, step = system.start_time, system.step_size
    if any(c.step_size for c in system.components):
        raise NotImplementedError(f"{system_path}: the C host script is single rate")
    stop = system.stop_time if stop is None else stop
    n_steps = round((stop - start) / step)
    ids = {name: k for k, name in enumerate(plan.steps.step_order)}
    slots = value_layout(descriptions, plan.steps.step_order)
    lines, directories = [], {}  # each FMU file extracted once: its components share it
    for name, k in ids.items():
        d = descriptions[name]
        directory = directories.setdefault(Path(d.path).resolve(), unzip_root / name)
        if not directory.exists():
            with zipfile.ZipFile(d.path) as archive:
                archive.extractall(directory)
        lines.append(f"fmu {k} {directory} {d.md.coSimulation.modelIdentifier} {d.md.guid} {name}")
    lines.append(f"slots {len(slots)}")
    lines += [f"column {k} {name}.{output}" for (name, output), k in slots.items()]

    def var(name, variable):
        v = descriptions[name].variables[variable]
        return f"{ids[name]} {TYPES[v.type]} {v.valueReference}"

    def put_inputs(name):
        return [
            f"put {var(name, u)} {slots[plan.sources[(b, u)]]}"
            for (b, u) in plan.sources
            if b == name
        ]

    def get(name, outputs):
        return [f"get {var(name, y)} {slots[(name, y)]}" for y in outputs]

    def evaluate(schedule, stepping):
        calls = []
        for name, block, first in evaluation_sequence(schedule):
            calls += put_inputs(name)
            calls += [f"step {ids[name]}"] if first and stepping else []
            calls += get(name, descriptions[name].outputs if first else block)
        return calls

    components = [c.name for c in system.components]
    for name in ids:
        lines += [f"instantiate {ids[name]}", f"setup {ids[name]} {start!r} {stop!r}"]
    lines += [
        f"set {var(p.component, p.name)} {p.value if p.type == 'String' else repr(float(p.value))}"
        for p in system.parameters
    ]
    lines += [f"enter {ids[name]}" for name in components]
    lines += evaluate(plan.init, stepping=False)
    for name in ids:
        lines += put_inputs(name)
    lines += [f"exit {ids[name]}" for name in components]
    for name in ids:
        lines += get(name, descriptions[name].outputs)
    lines += [
        "record",
        f"loop {n_steps} {start!r} {step!r}",
        *(
            evaluate(plan.steps, True)
            if (system.algorithm or "gauss-seidel") == "gauss-seidel"
            else [  # Jacobi: every FMU steps with the inputs of t_n, then the read-out
                *(call for name in ids for call in [*put_inputs(name), f"step {ids[name]}"]),
                *evaluate(plan.steps, False),
            ]
        ),
        "record",
        "end",
    ]
    lines += [f"terminate {ids[name]}" for name in components]
    Path(script).write_text("\n".join(lines) + "\n")
    return [f"{name}.{output}" for (name, output) in slots]
