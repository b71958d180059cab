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

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..system.description import Description
from ..system.parameters import typed_parameters
from ..system.ssp import ParameterValue, SystemFile, SystemFileError, read_system
from ..system.validation import Wiring, check_system
from . import multirate
from .loop import choose as choose_loop

ALGORITHMS = ("gauss-seidel", "jacobi")
MAX_STEPS = 10_000_000  # macro steps of one run (about 15 GB of CSV for scan_pitch)


@dataclass(frozen=True)
class RunPlan:
    """Everything one run needs, checked: what to run (``system``, the ``overrides`` on
    top of its own parameter values, the ``wiring``), on which time
    grid and how (``loop``: "auto", "compiled" or "python"; ``derivatives``: couple
    through FMI input/output derivatives where declared), and where its rows go
    (``out_dir``; ``progress(steps done, steps)``, ``echo(log entry)``, ``logging_on``:
    the FMUs' debug logging)."""

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

    @property
    def stop(self) -> float:
        return self.start + self.n_steps * self.step

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
    derivatives: bool = True,
    loop: str | None = None,
    out_dir=None,
    progress=None,
    echo=None,
    logging_on: bool = False,
) -> RunPlan:
    """The plan of a run of ``system`` (an ``.ssd``/``.ssp`` path or a
    :class:`SystemFile`); the keywords as :func:`.master.simulate` takes them.  Raises
    ValueError (SystemFileError for the system and its FMUs) saying what is wrong."""
    system = system if isinstance(system, SystemFile) else read_system(system)
    start = system.start_time
    step = system.step_size if step is None else step
    stop = system.stop_time if stop is None else stop
    algorithm = algorithm or system.algorithm or "gauss-seidel"
    n_steps = _steps(system.path, start, step, stop)
    every = multirate.multiples(system, step, n_steps)
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm must be one of {ALGORITHMS}, got {algorithm!r}")
    chosen = choose_loop(loop)
    descriptions = {ref.name: _describe(system, ref) for ref in system.components}
    overrides = typed_parameters(descriptions, parameters or {})
    wiring = check_system(system, descriptions, system.parameters + list(overrides.values()))
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
    )


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
