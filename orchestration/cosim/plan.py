"""A run, planned and checked before any FMU is loaded: :class:`RunPlan`.

:func:`plan_run` reads what a run needs from its options (:class:`.options.RunOptions`),
the system file and the FMUs' model descriptions alone: the time grid (start, step, number
of macro steps; each component's own step, :mod:`.multirate`), the algorithm, the
parameter values (the system's, then the overrides typed once:
:func:`..system.parameters.typed_parameters`) and the checked wiring
(:func:`..system.validation.check_system`: sources of the inputs, schedules, open inputs).
Every error names the file, component or variable before anything is instantiated.
:func:`.master.execute` runs the plan; :meth:`RunPlan.swapped` is the plan of a run that
only gives some parameters other values (a campaign's runs of one batch).

The check of a system is a function of the system (every field of its
:class:`..system.ssp.SystemFile`), its FMUs (their content, SHA-256) and the parameter
values bound: it is made once per process for each such triple and its result (the
:class:`..system.validation.Wiring`) given again, as fresh containers, to every plan of the
same one (:func:`_checked`; about 2.5 ms of each run of a sensed system, most of it the
two schedules).  A changed file, parameter value or FMU is another key: checked again.
"""

from __future__ import annotations

import dataclasses
import fnmatch
import hashlib
import math
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..system.description import Description
from ..system.parameters import did_you_mean, typed_parameters
from ..system.schedule import Schedule
from ..system.ssp import ParameterValue, SystemFile, SystemFileError, read_system
from ..system.validation import Wiring, check_system
from . import multirate
from .loop import choose as choose_loop
from .options import ALGORITHMS, RunOptions

MAX_STEPS = 10_000_000  # macro steps of one run (about 15 GB of CSV for scan_pitch)
#: bytes a recorded value takes in results.csv (CPython's repr and a comma; measured: a
#: 100 MB CSV of 90 columns for 54,800 rows) and in results.npz (float64)
CSV_BYTES, NPZ_BYTES = 20, 8


@dataclass(frozen=True)
class RunPlan:
    """Everything one run needs, checked: what it was asked (``options``), what to run
    (``system``, its FMUs' ``descriptions``, the ``overrides`` on top of its own parameter
    values, the ``wiring``), on which time grid and how (``loop``: "auto", "compiled" or
    "python"; ``derivatives``: couple through FMI input/output derivatives where
    declared), which outputs are recorded (``record``: their columns, None for all) and at
    which communication points (every ``output_every``-th)."""

    system: SystemFile
    options: RunOptions
    descriptions: dict[str, Description]
    overrides: dict[str, ParameterValue]  # "A.x[i]" -> typed value, on top of the system's
    wiring: Wiring
    start: float
    step: float
    n_steps: int
    algorithm: str
    every: dict[str, int]  # component -> its step in base steps (multirate)
    derivatives: bool = True
    loop: str = "auto"
    record: tuple[str, ...] | None = None
    output_every: int = 1
    outputs: int = 0  # of the FMUs, all recorded unless ``record`` chooses
    #: Jacobi with the outputs read right after the steps, no input set again first: what a
    #: host gets that does not bring direct-feedthrough outputs to the communication point
    #: (libcosim, ECOS; orchestration/coupling_error.py emulates them so)
    read_after_step: bool = False

    @property
    def stop(self) -> float:
        return self.start + self.n_steps * self.step

    @property
    def out_dir(self) -> Path | None:
        return self.options.out_dir

    @property
    def progress(self) -> Callable[[int, int], None] | None:
        return self.options.progress

    def output_bytes(self) -> tuple[int, int]:
        """(bytes of results.csv, of results.npz) the run will write, about."""
        rows = self.n_steps // self.output_every + 1
        values = rows * (1 + (self.outputs if self.record is None else len(self.record)))
        return values * CSV_BYTES, values * NPZ_BYTES

    @property
    def bindings(self) -> list[ParameterValue]:
        """Every parameter value set before initialisation, in the order set."""
        return self.system.parameters + list(self.overrides.values())

    def swapped(self, parameters: dict) -> RunPlan:
        """The plan with other values of parameters it was planned with (a campaign's
        dispersed values), typed and swapped in, in their order.  The check holds: what it
        found depends on which parameters a run sets, not on their values (a value set at
        run time is typed against its variable here, and not held to agree with another
        FMU's, :mod:`..system.agreement`).  A parameter it was not planned with is a
        ValueError."""
        typed = typed_parameters(self.descriptions, parameters)
        new = sorted(set(typed) - set(self.overrides))
        if new:
            raise ValueError(f"not planned with {', '.join(new)}: plan the run again")
        options = dataclasses.replace(
            self.options, parameters={**self.options.parameters, **parameters}
        )
        return dataclasses.replace(self, options=options, overrides={**self.overrides, **typed})


def plan_run(system, options: RunOptions | None = None, /, **keywords) -> RunPlan:
    """The plan of a run of ``system`` (an ``.ssd``/``.ssp`` path or a
    :class:`SystemFile`) with ``options`` (:class:`.options.RunOptions`, or its fields as
    keywords).  Raises ValueError (SystemFileError for the system and its FMUs) saying
    what is wrong."""
    options = RunOptions.given(options, keywords)
    system = system if isinstance(system, SystemFile) else read_system(system)
    start = system.start_time if options.start is None else options.start
    step = system.step_size if options.step is None else options.step
    stop = system.stop_time if options.stop is None else options.stop
    algorithm = options.algorithm or system.algorithm or "gauss-seidel"
    derivatives = options.derivatives
    derivatives = system.derivatives is not False if derivatives is None else derivatives
    n_steps = _steps(system.path, start, step, stop)
    every = multirate.multiples(system, step, n_steps)
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm must be one of {ALGORITHMS}, got {algorithm!r}")
    chosen = choose_loop(options.loop)
    descriptions = {ref.name: _describe(system, ref) for ref in system.components}
    overrides = typed_parameters(descriptions, options.parameters)
    wiring = _checked(system, descriptions, system.parameters + list(overrides.values()))
    columns = [f"{name}.{y}" for name, d in descriptions.items() for y in d.outputs]
    return RunPlan(
        system,
        options,
        descriptions,
        overrides,
        wiring,
        start,
        step,
        n_steps,
        algorithm,
        every,
        derivatives=derivatives,
        loop=chosen,
        record=None if options.record is None else recorded(columns, options.record),
        output_every=_output_every(options.output_interval, step, n_steps),
        outputs=len(columns),
    )


def recorded(columns: list[str], names) -> tuple[str, ...]:
    """The columns ``names`` choose: a column (``SatelliteDynamics.w_BI_B[2]``), a whole
    array by its base name, or a pattern (``SatelliteDynamics.*``); a ValueError naming
    the closest columns for a name that chooses none."""
    bases = {c.rsplit("[", 1)[0] for c in columns}
    chosen: set[str] = set()
    for name in [names] if isinstance(names, str) else names:
        found = [
            c
            for c in columns
            if c == name or c.rsplit("[", 1)[0] == name or fnmatch.fnmatchcase(c, name)
        ]
        if not found:
            raise ValueError(
                f"--record {name}: no output of that name"
                + did_you_mean(name, sorted(bases | set(columns)))
                + " (outputs are recorded; `agilesat info` lists them)"
            )
        chosen.update(found)
    return tuple(c for c in columns if c in chosen)


def _output_every(interval: float | None, step: float, n_steps: int) -> int:
    """Communication points per recorded row: ``interval`` / ``step``, which must be a
    whole number that divides the run."""
    if interval is None:
        return 1
    m = round(interval / step) if math.isfinite(interval) and interval > 0 else 0
    if m < 1 or not math.isclose(m * step, interval, rel_tol=1e-9, abs_tol=0.0):
        raise ValueError(
            f"--output-interval {interval}: it must be a positive multiple of the step {step} s"
        )
    if n_steps % m:
        raise ValueError(
            f"--output-interval {interval}: the run of {n_steps} steps of {step} s does not end "
            "on a recorded point (make the run a multiple of the interval)"
        )
    return m


def _steps(path, start: float, step, stop) -> int:
    """The number of macro steps from start to stop, or a ValueError saying what is wrong."""
    if step is None or not (math.isfinite(step) and step > 0):
        raise ValueError(
            f"{path}: the macro step must be a positive, finite number of "
            f"seconds (got {step}); give one or set it in the system's "
            "org.agilesat.master annotation"
        )
    if stop is None or not math.isfinite(stop) or stop <= start:
        raise ValueError(
            f"{path}: the stop time must be finite and after the start {start} s (got {stop})"
        )
    ratio = (stop - start) / step
    if not ratio <= MAX_STEPS:  # also inf, from a tiny step
        raise ValueError(
            f"{path}: {stop - start} s at a step of {step} s would be "
            f"{ratio:.4g} macro steps, more than the {MAX_STEPS} a run may have"
        )
    n_steps = int(round(ratio))
    if not math.isclose(start + n_steps * step, stop, rel_tol=1e-9, abs_tol=1e-12):
        raise ValueError(f"stop - start = {stop - start} is not a multiple of the step {step}")
    return n_steps


def unreadable(system, ref, exc: Exception) -> SystemFileError:
    """The error for a component whose FMU cannot be read or loaded."""
    return SystemFileError(
        f"{system.path}:{ref.line}: component '{ref.name}': "
        f"{ref.source} is not a readable FMU: {exc}"
    )


def _describe(system, ref) -> Description:
    try:
        return Description(ref.name, ref.source)
    except Exception as exc:  # noqa: BLE001 - any unreadable file: say which
        raise unreadable(system, ref, exc) from None


#: key of a check (:func:`_check_key`) -> its Wiring; at most :data:`_CHECKS_KEPT`, oldest out
_checks: dict[str, Wiring] = {}
_checks_lock = threading.Lock()
#: few: a process runs a few systems again and again; a campaign's runs planned one by one
#: (each its own values, each its own check) must not grow a worker's memory for long
_CHECKS_KEPT = 8
_SCALARS = (float, int, bool, str)  # whose repr is the value exactly


def _checked(system: SystemFile, descriptions: dict, bindings: list) -> Wiring:
    """:func:`..system.validation.check_system` of these, made once per process for each
    key (:func:`_check_key`); a check that finds problems raises each time (not kept)."""
    key = _check_key(system, descriptions, bindings)
    if key is None:
        return check_system(system, descriptions, bindings)
    with _checks_lock:
        wiring = _checks.get(key)
    if wiring is None:
        wiring = check_system(system, descriptions, bindings)
        with _checks_lock:
            if len(_checks) >= _CHECKS_KEPT:
                _checks.pop(next(iter(_checks)))
            _checks[key] = wiring
    return _fresh(wiring)


def _check_key(system: SystemFile, descriptions: dict, bindings: list) -> str | None:
    """What a check reads: every field of the system (its dataclass repr: components with
    their FMU paths and connectors, connections, parameter values with their types and
    origins, the experiment), each FMU by instance name, path and content (SHA-256, the key
    its model description is read by) and the values bound (repr: 1, 1.0 and True differ,
    so do 0.0 and -0.0), kept as the SHA-256 of their text (a few bytes, not the system's
    text, per check kept).  None (not kept) where a value is not a plain scalar, whose repr
    might not tell two values apart (a long numpy array's elides)."""
    if not all(type(p.value) in _SCALARS for p in (*system.parameters, *bindings)):
        return None
    fmus = tuple((name, str(d.path), d.key) for name, d in descriptions.items())
    text = "\0".join((repr(system), repr(fmus), repr(bindings)))
    return hashlib.sha256(text.encode()).hexdigest()


def _fresh(wiring: Wiring) -> Wiring:
    """A copy of a kept Wiring in new containers (a run's results hold its lists): what it
    shares is immutable (tuples, strings)."""
    return Wiring(
        Schedule(list(wiring.steps.step_order), list(wiring.steps.blocks)),
        Schedule(list(wiring.init.step_order), list(wiring.init.blocks)),
        dict(wiring.sources),
        [dict(entry) for entry in wiring.open_inputs],
    )
