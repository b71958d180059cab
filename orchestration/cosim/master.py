"""The co-simulation master: FMI 2.0 co-simulation FMUs wired by an SSP system description.

Run (:func:`simulate`, or :func:`execute` of a :class:`.plan.RunPlan`):

1. Plan the run from the system file and the model descriptions (:mod:`.plan`): the time
   grid, the parameter values typed, the system checked
   (:func:`..system.validation.check_system`, which also gives the dependency orders);
   then load every FMU.
2. Instantiate, set up the experiment, set the parameters, enter initialisation mode;
   propagate the connected inputs in dependency order (FMI 2.0 ``InitialUnknowns``), then
   set every input once more and exit initialisation mode.
3. Fixed macro step H, time t_n = t0 + n H from the integer step counter n.
   The outputs are read block by block in the order of :mod:`..system.schedule` (each block after
   setting that FMU's inputs from the newest outputs).  Gauss-Seidel: an FMU steps at its
   first block, so it sees the outputs of the FMUs before it at t_{n+1}.  Jacobi: every FMU
   has all its inputs set from the outputs of t_n and steps, then the blocks are read (an
   input was last set at its FMU's block, before the FMUs of later blocks had their t_n
   outputs: setting them again before the step keeps it from lagging a step; after the
   steps only blocks whose outputs depend on inputs directly have them set; those whose
   sources were all read before them hold their values at the next step and are not set
   again: :func:`.loop._drop_repeated_sets`).  Either way
   the recorded outputs at t_{n+1} are consistent with each other (feedthrough outputs see
   the inputs of t_{n+1}).  A component with its own step m H (:mod:`.multirate`) steps
   over m H at every m-th communication point and holds its outputs in between.
   Input and output derivatives (FMI 2.0 section 4.2.1; :mod:`.derivatives`): an input
   whose FMU declares its derivative (``canInterpolateInputs`` and the ``derivative``
   attribute), fed by an output whose FMU declares its derivative
   (``maxOutputDerivativeOrder`` ≥ 1 and the attribute), with no connection to the
   derivative input itself, both at the base step, gets its first derivative by
   ``fmi2SetRealInputDerivatives`` before each step: Jacobi extrapolates with the source's
   ``fmi2GetRealOutputDerivatives`` at t_n; Gauss-Seidel, for a source that already
   stepped, interpolates, value y_n and slope (y_{n+1} − y_n)/H (else it extrapolates as
   Jacobi).  ``derivatives=False`` turns this off.
4. Every FMI status is checked; Discard, Error or Fatal stop the run with the component,
   call, time and the FMU's own messages, and the rows recorded so far are kept (on disk,
   when an output directory is given: :mod:`..output.recorder`).  After fmi2Fatal nothing more is
   called on that FMU.  The run holds its output directory (:mod:`..output.lock`): a
   second run on it is refused before it writes anything.
5. SIGINT (Ctrl-C) and SIGTERM only set a flag while a run goes
   (:func:`.signals.stop_on_signals`):
   the run stops between two macro steps (between two chunks of a few milliseconds of
   the loop), terminates and frees the FMUs, keeps its rows and raises
   :class:`Interrupted`.  A KeyboardInterrupt is raised inside an FMU only by the
   watchdog, in a call that did not return within its grace of the signal
   (:mod:`.signals`; pythonfmu answers it fmi2Fatal).

The system is checked against the model descriptions before any FMU is instantiated; open
inputs follow the rule of :mod:`..system.validation` and the allowed ones are logged (and listed
in ``Results.meta["unconnected_optional_inputs"]``).  The step must be positive and finite,
the stop time finite and after the start, and the run at most :data:`.plan.MAX_STEPS` macro
steps.

The macro steps are one program of FMI calls (:mod:`.loop`), run in C, or in Python (the
same operations, the results bit for bit): with ``loop="python"``, or where the C loop
cannot be compiled; ``Results.meta["loop"]`` says which.  ``Results.meta["parameters"]`` holds
every Real parameter's value as the run set it (figures draw the limits of the run).
"""

from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import signal

import numpy as np

from ..output.lock import holding
from ..output.recorder import Recorder
from ..output.results import Results
from . import loop
from .derivatives import Derivatives
from .fmu import FmiCallError, Instance
from .options import RunOptions
from .plan import RunPlan, plan_run, unreadable
from .signals import at_step, stop_on_signals

_CTYPE: dict[str, type[ctypes.c_double] | type[ctypes.c_int]] = {
    "Real": ctypes.c_double,
    "Integer": ctypes.c_int,
    "Boolean": ctypes.c_int,
}


class SimulationError(RuntimeError):
    """A run stopped early; ``results`` holds everything recorded up to the failure."""

    def __init__(self, message: str, results: Results | None):
        super().__init__(message)
        self.results = results


class Interrupted(SimulationError):
    """A run stopped by SIGINT or SIGTERM between two macro steps (``signal`` says which)."""

    def __init__(self, message: str, results: Results | None, signum: int):
        super().__init__(message, results)
        self.signal = signum


TYPES = ("Real", "Integer", "Boolean")  # of the values the master passes on


def value_layout(descriptions: dict, order) -> dict[tuple[str, str], int]:
    """(instance, output) -> its index in the master's value vector: FMU by FMU in
    ``order``, within one by type (:data:`TYPES`), then by value reference."""
    layout = {}
    for name in order:
        d = descriptions[name]
        for type_ in TYPES:
            for y in d.outputs:
                if d.variables[y].type == type_:
                    layout[(name, y)] = len(layout)
    return layout


def evaluation_sequence(schedule) -> list[tuple[str, tuple[str, ...], bool]]:
    """(instance, outputs read, first block of that instance?) for each block of a
    schedule; an FMU steps at its first block."""
    seen, result = set(), []
    for name, block in schedule.blocks:
        result.append((name, block, name not in seen))
        seen.add(name)
    return result


class _Port:
    """Variables of one type of one instance and their places in the value vector:
    value references, buffer, the bound FMI call."""

    def __init__(
        self, instance: Instance, type_: str, names: list[str], direction: str, index: list[int]
    ):
        self.instance, self.call = instance, f"fmi2{direction}{type_}"
        self.n = len(names)
        self.buffer = np.zeros(self.n, dtype=np.float64 if type_ == "Real" else np.int32)
        self.vrs = (ctypes.c_uint * self.n)(*(instance.variables[n].valueReference for n in names))
        self.ptr = self.buffer.ctypes.data_as(ctypes.POINTER(_CTYPE[type_]))
        self.function = getattr(instance, self.call)
        self.index = np.array(index, dtype=np.intp)
        contiguous = index == list(range(index[0], index[0] + self.n))
        self.where = slice(index[0], index[0] + self.n) if contiguous else self.index

    def transfer(self) -> None:
        status = self.function(self.instance.component, self.vrs, self.n, self.ptr)
        if status > 1:
            self.instance.check(status, self.call)

    def read(self, values: np.ndarray) -> None:
        self.transfer()
        values[self.where] = self.buffer

    def write(self, values: np.ndarray) -> None:
        np.take(values, self.index, out=self.buffer)
        self.transfer()


def _ports(instance: Instance, names, direction: str, index: dict) -> list[_Port]:
    """One port per type over ``names`` (order kept); ``index`` maps a name to its place."""
    ports = []
    for type_ in TYPES:
        chosen = [n for n in names if instance.variables[n].type == type_]
        if chosen:
            ports.append(_Port(instance, type_, chosen, direction, [index[n] for n in chosen]))
    return ports


class _Node:
    """One instance: its output ports, its connected-input ports and its step in base
    steps (``every``)."""

    def __init__(self, instance: Instance, layout: dict, sources: dict, every: int = 1):
        self.instance, self.every = instance, every
        self.position = {y: layout[(instance.name, y)] for y in instance.outputs}
        self.outputs = _ports(instance, instance.outputs, "Get", self.position)
        connected = sorted(
            (u for (b, u) in sources if b == instance.name),
            key=lambda u: instance.variables[u].valueReference,
        )
        self.inputs = _ports(
            instance, connected, "Set", {u: layout[sources[(instance.name, u)]] for u in connected}
        )

    def set_inputs(self, values: np.ndarray) -> None:
        for port in self.inputs:
            port.write(values)

    def get_outputs(self, values: np.ndarray) -> None:
        for port in self.outputs:
            port.read(values)


def simulate(system, options: RunOptions | None = None, /, **keywords) -> Results:
    """Run a system (an ``.ssd``/``.ssp`` path or a :class:`SystemFile`) with ``options``
    (:class:`.options.RunOptions`, or its fields as keywords: ``step``, ``stop``,
    ``parameters``, ``out_dir``, ``record``, ...).

    With ``out_dir``, ``results.csv`` is written there row by row and ``results.npz`` at
    the end, and the Results returned map their rows from disk (memory independent of the
    run length); without, the rows are held in memory.  Returns :class:`Results`
    (``meta`` holds the settings, the units of the columns, the FMU log and the open
    inputs); raises :class:`SimulationError` (:class:`Interrupted` on SIGINT/SIGTERM) with
    the rows so far.  The same as ``execute(plan_run(system, options))`` (:mod:`.plan`).
    """
    return execute(plan_run(system, RunOptions.given(options, keywords)))


def execute(plan: RunPlan) -> Results:
    """Run a :class:`RunPlan`: load its FMUs, initialise, step, record; as
    :func:`simulate`."""
    hooked = at_step(plan.progress)  # $AGILESAT_TEST_SIGNAL (tests of interruptions)
    if hooked is not plan.progress:
        plan = dataclasses.replace(plan, options=dataclasses.replace(plan.options, progress=hooked))
    held = holding(plan.out_dir) if plan.out_dir is not None else contextlib.nullcontext()
    with held, stop_on_signals() as signals:
        log = loop.ClockLog(echo=plan.options.echo)
        log.time = plan.start
        instances = {}
        try:
            for ref in plan.system.components:
                instances[ref.name] = _load(plan, ref, log)
            for entry in plan.wiring.open_inputs:
                log.add(
                    entry["input"].partition(".")[0],
                    0 if entry["declared"] else 1,
                    "master",
                    f"input {entry['input']} is not connected: {entry['meaning']}",
                )
            with signals.watching():
                return _run(plan, instances, log, signals)
        finally:
            for instance in instances.values():
                instance.free()


def _load(plan: RunPlan, ref, log) -> Instance:
    try:
        return Instance(ref.name, ref.source, log)
    except Exception as exc:  # noqa: BLE001 - any unreadable file: say which
        raise unreadable(plan.system, ref, exc) from None


def _run(plan: RunPlan, instances: dict[str, Instance], log, signals) -> Results:
    wiring, step, n_steps = plan.wiring, plan.step, plan.n_steps
    layout = value_layout(instances, wiring.steps.step_order)
    nodes = {
        name: _Node(instances[name], layout, wiring.sources, plan.every[name])
        for name in wiring.steps.step_order
    }
    columns = ["time"] + [f"{name}.{output}" for name, output in layout]
    sequence = _sequence(wiring.steps, nodes)
    init_sequence = _sequence(wiring.init, nodes)
    jacobi_reads = _fed_reads(sequence, wiring.sources)
    if plan.read_after_step:
        jacobi_reads = [(node, reads, False) for node, reads, _ in jacobi_reads]
    links = Derivatives(nodes, wiring.sources, layout, plan.algorithm) if plan.derivatives else None
    if links is not None and not links.consumers:
        links = None

    values = np.zeros(len(layout))
    row = np.zeros(len(layout) + 1)
    meta = {
        "system": str(plan.system.path),
        "step": step,
        "start": plan.start,
        "stop": plan.stop,
        "algorithm": plan.algorithm,
        "component_steps": {name: m * step for name, m in plan.every.items() if m > 1},
        "log": log.entries,
        "order": wiring.steps.step_order,
        "unconnected_optional_inputs": wiring.open_inputs,
        "units": {
            f"{name}.{y}": instances[name].variables[y].unit
            for name, y in layout
            if plan.record is None or f"{name}.{y}" in plan.record
        },
    }
    meta["parameters"] = _parameter_values(plan, instances)
    if links is not None:
        meta["derivatives"] = links.described
    dll = loop.select(plan.loop, log)
    meta["loop"] = "python" if dll is None else "compiled"
    chosen = None if plan.record is None else set(plan.record)
    keep = None if chosen is None else [0] + [k for k, c in enumerate(columns) if c in chosen]
    expected = n_steps // plan.output_every + 1  # rows 0, every, 2 every, ... <= n_steps
    recorder = Recorder(columns, plan.out_dir, keep, plan.output_every, expected)
    if plan.output_every > 1:
        meta["output_interval"] = plan.output_every * step
    failure = None
    try:
        _initialize(plan, instances, nodes, init_sequence, values, log)
        if links is not None:
            links.read()
        row[0], row[1:] = plan.start, values
        recorder.append(row)
        program = loop.Program.macro_step(
            plan.algorithm, nodes, sequence, jacobi_reads, step, links
        )
        loop.run(dll, program, plan, values, recorder, signals, log)
        for inst in instances.values():
            inst.call("fmi2Terminate")
    except (FmiCallError, OSError) as exc:
        failure = str(exc)
    results, problems = recorder.close(meta)
    kept = [
        f"Kept {recorder.rows} recorded rows"
        + (f" in {recorder.csv.path}" if plan.out_dir is not None else "")
    ] + problems
    name = plan.system.path.name
    stuck = failure is not None and signals.overdue is not None  # the watchdog's doing
    if (failure is None or stuck) and signals.signal is not None and recorder.rows < n_steps + 1:
        signame = signal.Signals(signals.signal).name
        said = [f"{name}: interrupted by {signame} after t={results.time[-1]:.6g} s"]
        if stuck:
            said.append(
                f"an FMU call did not return within {signals.overdue:g} s of the signal "
                f"(AGILESAT_STEP_GRACE): stopped inside it; {failure}"
            )
        raise Interrupted("\n".join(said + kept), results, signals.signal)
    if failure is not None or problems:
        raise SimulationError("\n".join([f"{name}: {failure or 'results lost'}"] + kept), results)
    return results


def _sequence(schedule, nodes) -> list:
    """(node, output ports to read, first block?) for each block of a schedule."""
    return [
        (
            nodes[name],
            nodes[name].outputs
            if first
            else _ports(nodes[name].instance, block, "Get", nodes[name].position),
            first,
        )
        for name, block, first in evaluation_sequence(schedule)
    ]


def _fed_reads(sequence, sources) -> list:
    """(node, output ports, do its outputs depend directly on a connected input?) for each
    block of a sequence."""
    result = []
    for node, reads, _ in sequence:
        instance = node.instance
        connected = {u for (b, u) in sources if b == instance.name}
        outputs = [y for port in reads for y in _port_names(port, node)]
        feeds = any(
            instance.feedthrough.get(y) is None or instance.feedthrough[y] & connected
            for y in outputs
        )
        result.append((node, reads, feeds))
    return result


def _port_names(port: _Port, node: _Node) -> list[str]:
    by_place = {place: y for y, place in node.position.items()}
    return [by_place[int(i)] for i in port.index]


def _parameter_values(plan: RunPlan, instances) -> dict[str, object]:
    """{"Instance.variable[i]": value} of every Real parameter as the run sets it: the
    value the system or the command line gave, else the model description's start."""
    values: dict[str, object] = {
        f"{name}.{variable}": start
        for name, inst in instances.items()
        for variable, start in _real_parameter_starts(inst)
    }
    values.update({f"{p.component}.{p.name}": p.value for p in plan.bindings})
    return values


_starts: dict[str, list[tuple[str, float]]] = {}  # content key -> Real parameter starts


def _real_parameter_starts(inst: Instance) -> list[tuple[str, float]]:
    """(name, start) of every Real parameter with a start value of an FMU, in
    model-description order; read once per FMU content."""
    starts = _starts.get(inst.key)
    if starts is None:
        if len(_starts) >= 256:
            _starts.pop(next(iter(_starts)), None)
        starts = _starts[inst.key] = [
            (v.name, float(v.start))
            for v in inst.variables.values()
            if v.causality == "parameter" and v.type == "Real" and v.start is not None
        ]
    return starts


def _initialize(plan: RunPlan, instances, nodes, init_sequence, values, log) -> None:
    """Instantiate, set up, set the parameters (one call per instance and type,
    :func:`_binding_calls`); in initialisation mode, bring the outputs to t0 block by block
    in ``init_sequence`` (FMI 2.0 ``InitialUnknowns``), then set every input once more."""
    log.time = plan.start
    for node in nodes.values():
        inst = node.instance
        inst.instantiate(plan.options.logging_on)
        inst.call("fmi2SetupExperiment", 0, 0.0, plan.start, 1, plan.stop)
    for inst, type_, vrs, bound in _binding_calls(plan.bindings, instances):
        _set_values(inst, type_, vrs, bound)
    for inst in instances.values():
        inst.call("fmi2EnterInitializationMode")
    for node, reads, _ in init_sequence:
        node.set_inputs(values)
        for port in reads:
            port.read(values)
    for node in nodes.values():
        node.set_inputs(values)
    for inst in instances.values():
        inst.call("fmi2ExitInitializationMode")
    for node in nodes.values():
        node.get_outputs(values)


def _binding_calls(bindings, instances) -> list[tuple[Instance, str, list[int], list]]:
    """The parameter values as one set per instance and type: (instance, type, value
    references ascending, values), each value reference once with the value bound last (as
    setting them one by one in order leaves it)."""
    grouped: dict[tuple[str, str], dict[int, object]] = {}
    for value in bindings:
        vr = instances[value.component].variables[value.name].valueReference
        grouped.setdefault((value.component, value.type), {})[vr] = value.value
    return [
        (instances[name], type_, sorted(by_vr), [by_vr[vr] for vr in sorted(by_vr)])
        for (name, type_), by_vr in grouped.items()
    ]


def _set_values(inst: Instance, type_: str, vrs: list[int], values: list) -> None:
    """One fmi2Set<type_> of ``values`` at value references ``vrs``."""
    n = len(vrs)
    refs = (ctypes.c_uint * n)(*vrs)
    if type_ == "Real":
        inst.call("fmi2SetReal", refs, n, (ctypes.c_double * n)(*map(float, values)))
    elif type_ in ("Integer", "Boolean"):
        inst.call(f"fmi2Set{type_}", refs, n, (ctypes.c_int * n)(*map(int, values)))
    else:
        encoded = [str(v).encode() for v in values]
        inst.call("fmi2SetString", refs, n, (ctypes.c_char_p * n)(*encoded))
