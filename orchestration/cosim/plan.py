"""A run, planned and checked before any FMU is loaded: :class:`RunPlan`.

:func:`plan_run` reads what a run needs from the system file and the FMUs' model
descriptions alone: the time grid (start, step, number of macro steps; each component's
own step, :mod:`.multirate`), the algorithm, the parameter values (the system's, then the
overrides typed once: :func:`..system.parameters.typed_parameters`) and the checked wiring
(:func:`..system.validation.check_system`: sources of the inputs, schedules, open inputs).
Every error names the file, component or variable before anything is instantiated.
:func:`.master.execute` runs the plan.
"""

from __future__ import annotations

import fnmatch
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..system.description import Description
from ..system.parameters import did_you_mean, typed_parameters
from ..system.ssp import ParameterValue, SystemFile, SystemFileError, read_system
from ..system.validation import Wiring, check_system
from . import multirate
from .loop import choose as choose_loop

ALGORITHMS = ("gauss-seidel", "jacobi")
MAX_STEPS = 10_000_000  # macro steps of one run (about 15 GB of CSV for scan_pitch)
#: bytes a recorded value takes in results.csv (CPython's repr and a comma; measured: a
#: 100 MB CSV of 90 columns for 54,800 rows) and in results.npz (float64)
CSV_BYTES, NPZ_BYTES = 20, 8


@dataclass(frozen=True)
class RunPlan:
    """Everything one run needs, checked: what to run (``system``, the ``overrides`` on
    top of its own parameter values, the ``wiring``), on which time
    grid and how (``loop``: "auto", "compiled" or "python"; ``derivatives``: couple
    through FMI input/output derivatives where declared), and where its rows go
    (``out_dir``; ``progress(steps done, steps)``, ``echo(log entry)``, ``logging_on``:
    the FMUs' debug logging), which outputs are recorded (``record``: their columns, None
    for all) and at which communication points (every ``output_every``-th)."""

    system: SystemFile
    overrides: dict[str, ParameterValue]  # "A.x[i]" -> typed value, on top of the system's
    wiring: Wiring
    start: float
    step: float
    n_steps: int
    algorithm: str
    every: dict[str, int]  # component -> its step in base steps (multirate)
    derivatives: bool = True
    loop: str = "auto"
    out_dir: Path | None = None
    progress: Callable[[int, int], None] | None = None
    echo: Callable[[Any], None] | None = None
    logging_on: bool = False
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

    def output_bytes(self) -> tuple[int, int]:
        """(bytes of results.csv, of results.npz) the run will write, about."""
        rows = self.n_steps // self.output_every + 1
        values = rows * (1 + (self.outputs if self.record is None else len(self.record)))
        return values * CSV_BYTES, values * NPZ_BYTES

    @property
    def bindings(self) -> list[ParameterValue]:
        """Every parameter value set before initialisation, in the order set."""
        return self.system.parameters + list(self.overrides.values())


def plan_run(
    system,
    *,
    step: float | None = None,
    stop: float | None = None,
    algorithm: str | None = None,
    parameters: dict | None = None,
    derivatives: bool | None = None,
    loop: str | None = None,
    out_dir=None,
    progress=None,
    echo=None,
    logging_on: bool = False,
    start: float | None = None,
    record=None,
    output_interval: float | None = None,
) -> RunPlan:
    """The plan of a run of ``system`` (an ``.ssd``/``.ssp`` path or a
    :class:`SystemFile`); the keywords as :func:`.master.simulate` takes them.  Raises
    ValueError (SystemFileError for the system and its FMUs) saying what is wrong."""
    system = system if isinstance(system, SystemFile) else read_system(system)
    start = system.start_time if start is None else start
    step = system.step_size if step is None else step
    stop = system.stop_time if stop is None else stop
    algorithm = algorithm or system.algorithm or "gauss-seidel"
    derivatives = system.derivatives is not False if derivatives is None else derivatives
    n_steps = _steps(system.path, start, step, stop)
    every = multirate.multiples(system, step, n_steps)
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm must be one of {ALGORITHMS}, got {algorithm!r}")
    chosen = choose_loop(loop)
    descriptions = {ref.name: _describe(system, ref) for ref in system.components}
    overrides = typed_parameters(descriptions, parameters or {})
    wiring = check_system(system, descriptions, system.parameters + list(overrides.values()))
    columns = [f"{name}.{y}" for name, d in descriptions.items() for y in d.outputs]
    return RunPlan(
        system,
        overrides,
        wiring,
        start,
        step,
        n_steps,
        algorithm,
        every,
        derivatives=derivatives,
        loop=chosen,
        out_dir=None if out_dir is None else Path(out_dir),
        progress=progress,
        echo=echo,
        logging_on=logging_on,
        record=None if record is None else recorded(columns, record),
        output_every=_output_every(output_interval, step, n_steps),
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
