"""Run a scenario (shipped or your own), a system built in Python, a system file or one FMU
end to end: build what is stale, plan the run (:mod:`.cosim.plan`), simulate, write
results, summary (:mod:`.output.summary`) and figures.  The CLI's ``agilesat run`` is a thin
layer on this; a campaign's worker plans a batch of runs once (:func:`planned`) and swaps
each run's values (:meth:`Planned.swapped`).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import time
import warnings
from contextlib import nullcontext
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from .cosim.master import Interrupted, SimulationError, execute
from .cosim.options import RunOptions
from .cosim.plan import RunPlan, plan_run
from .cosim.signals import signal_at, stop_on_signals
from .mission import reads
from .mission.scenario import defined_at
from .mission.targets import Target, resolve
from .output.lock import holding
from .output.progress import Progress
from .output.recorder import make_directory, write_text
from .output.results import ColumnError, Results
from .output.summary import facts, generic_summary, summary_text, write_records
from .provenance import provenance

#: a run that will write more than this says so before it starts
LARGE_OUTPUT = 2**30


def run(target, options: RunOptions | None = None, /, **keywords) -> tuple[Results, dict]:
    """Run a target (see :func:`.mission.targets.resolve`: "scan_pitch:literal_spin", a
    mission file "path/mission.py[:variant]", a :class:`~.mission.Scenario` or
    :class:`~.mission.System`, an .ssd/.ssp file, an .fmu) with ``options``
    (:class:`.cosim.options.RunOptions`, or its fields as keywords: ``step``, ``stop``,
    ``parameters``, ``out_dir``, ``figures``, ...); returns (results, summary).

    With ``out_dir``: results.csv (row by row), results.npz, log.txt and summary.json, also
    when the run fails (``status: "error"``) or is interrupted by SIGINT/SIGTERM
    (``status: "interrupted"``, and ``interruption``: the signal, while what, what was not
    written; a signal while the results or figures are written stops the figures and is
    said the same way); the exception is raised after they are written.  The run holds
    ``out_dir`` (:mod:`.output.lock`): a second run on it is refused.  The summary lists
    every input left open with what its default means (``unconnected_optional_inputs``).  A
    run that will write more than :data:`LARGE_OUTPUT` bytes says so first, through
    ``notice(text)`` (default: a warning).

    ``figures``: the scenario's figures (any other system's: an overview of its outputs)
    as 200-dpi PNGs, with ``svg`` an SVG beside each (~25 % more figure time).
    """
    wall = time.perf_counter()
    return planned(target, RunOptions.given(options, keywords)).run(wall)


def planned(target, options: RunOptions) -> Planned:
    """``target`` resolved and its run planned (the FMUs built first if ``options.build``)."""
    found = resolve(target)
    system = found.system_file(options.build)
    if found.scenario is not None:  # what its metrics and requirements read: outputs
        reads.check(found.scenario, found.variant, options.build)
    return Planned(found, plan_run(system, options))


@dataclass(frozen=True)
class Planned:
    """A target (:class:`.mission.targets.Target`) and the plan of its run."""

    target: Target
    plan: RunPlan

    def swapped(self, parameters: dict) -> Planned:
        """The same run with other values of parameters it was planned with
        (:meth:`.cosim.plan.RunPlan.swapped`)."""
        return Planned(self.target, self.plan.swapped(parameters))

    def run(self, wall: float | None = None) -> tuple[Results, dict]:
        """Run it (see :func:`run`); ``wall``: when the run began (``time.perf_counter``),
        for its summary's wall time."""
        return _run(self.target, self.plan, time.perf_counter() if wall is None else wall)


def _run(found: Target, plan: RunPlan, wall: float) -> tuple[Results, dict]:
    scenario, variant, options, system = found.scenario, found.variant, plan.options, plan.system
    if isinstance(options.progress, Progress):
        options.progress.simulating(plan.step)  # a person's bar counts simulated seconds
    out_dir = plan.out_dir
    if out_dir is not None:
        make_directory(out_dir)
        _say_size(plan, out_dir, options.notice)
    summary = {
        **provenance(),
        "scenario": scenario.name if scenario else None,
        "variant": variant,
        "target": found.record(),
        "system": str(system.path),
        "parameters": {k: {"value": p.value, "type": p.type} for k, p in plan.overrides.items()},
    }
    figures = options.figures and out_dir is not None
    with stop_on_signals() as signals, holding(out_dir) if out_dir else nullcontext():
        if out_dir is not None:
            _drop_previous_figures(out_dir)
        try:
            results = execute(plan)
        except SimulationError as failure:
            if out_dir is not None and failure.results is not None:
                summary.update(
                    facts(failure.results, time.perf_counter() - wall),
                    error=str(failure),
                    status="interrupted" if isinstance(failure, Interrupted) else "error",
                )
                if isinstance(failure, Interrupted):
                    said = f"the rows after t={failure.results.time[-1]:.6g} s"
                    _interruption(summary, failure.signal, "the run", [said], figures)
                try:
                    write_records(failure.results, summary, out_dir)
                except OSError as exc:  # say both
                    failure.args = (f"{failure}\n{exc}",)
            raise
        summary.update(facts(results, time.perf_counter() - wall))
        if scenario is not None:
            summary.update(scenario.evaluate(results, variant, partial=plan.record is not None))
        else:
            summary.update(generic_summary(results))
        stopped = False  # the figures, by a signal
        if out_dir is not None:
            write_records(results, summary, out_dir)
            if figures and signals.signal is None:
                failed = len(summary.get("errors", ()))
                summary["figures"], stopped = _figures(
                    scenario, variant, results, out_dir, options.svg, summary, signals
                )
                if len(summary.get("errors", ())) > failed:  # log.txt says it too
                    write_records(results, summary, out_dir)
                else:
                    write_text(out_dir / "summary.json", summary_text(summary))
            if options.mat:
                results.to_mat(out_dir / "results.mat")
        if signals.signal is not None:  # after the last macro step: said, and exit 130/143
            during = "the figures" if stopped else "the results"
            _interruption(summary, signals.signal, during, [], figures)
            if out_dir is not None:
                write_text(out_dir / "summary.json", summary_text(summary))
            raise Interrupted(
                f"{Path(system.path).name}: interrupted by {signal.Signals(signals.signal).name} "
                f"while "
                f"writing {during}; the run is complete"
                + (f", what was written is in {out_dir / 'summary.json'}" if out_dir else ""),
                results,
                signals.signal,
            )
    return results, summary


def _drop_previous_figures(out_dir: Path) -> None:
    """Remove the figures an earlier run in ``out_dir`` drew (its summary.json lists
    them, also while they are drawn; nothing else is touched: its summary and records go
    as this run's recording starts, :data:`.output.recorder.REPLACED`): a reused ``--out``
    shows this run's figures only."""
    try:
        listed = json.loads((out_dir / "summary.json").read_text(encoding="utf-8"))["figures"]
    except (OSError, ValueError, KeyError, TypeError):
        return
    for name in listed if isinstance(listed, list) else ():
        (out_dir / Path(str(name)).name).unlink(missing_ok=True)


class _Stopped(Exception):
    """A signal came while the figures were drawn."""


def _figures(
    scenario, variant, results, out_dir: Path, svg: bool, summary: dict, signals
) -> tuple[list[str], bool]:
    """Draw the figures; stop before the next one once a signal came.  (The files
    written, whether it stopped.)  $AGILESAT_TEST_SIGNAL=SIGNAL@figure:K: a signal as the
    K-th starts.  Before each file is written, summary.json lists it with those written
    (a run killed while drawing leaves nothing the next one does not remove).  A figure
    function that raises is said in the summary's ``errors`` (status "error") and the
    others are drawn; figures that need outputs not recorded (``--record``) are not
    drawn, and the summary says why."""
    from .mission import pointing_figures
    from .output import plots

    hook, started = signal_at("figure"), [0]

    def before(paths):
        started[0] += 1
        if hook is not None and started[0] == hook[1]:
            os.kill(os.getpid(), hook[0])
        if signals.signal is not None:
            raise _Stopped
        summary["figures"] = [str(p) for p in (*drawn, *paths)]
        write_text(out_dir / "summary.json", summary_text(summary))

    if scenario is None:
        draws = [("the overview", lambda: plots.overview(results, out_dir))]
    else:
        draws = [
            (
                f"figure {getattr(f, '__qualname__', f)} {defined_at(f)}".rstrip(),
                partial(f, results, out_dir),
            )
            for f in scenario.figures_for(variant)
        ]
        draws.append(
            (
                "the pointing figures",
                partial(pointing_figures.run_figures, scenario, variant, results, out_dir),
            )
        )
    with plots.written_as(plots.FORMATS if svg else plots.FORMATS[:1]):
        with plots.drawing(before) as drawn:
            for what, draw in draws:
                try:
                    draw()
                except _Stopped:
                    return [str(p) for p in drawn], True
                except Exception as exc:  # noqa: BLE001 - said; the other figures drawn
                    recorded = len(results.names) == len(results.meta.get("units", {})) + 1
                    if isinstance(exc, ColumnError) and not recorded:
                        summary.setdefault(
                            "figures_not_drawn", f"they need outputs not recorded ({exc})"
                        )
                        continue
                    summary.setdefault("errors", []).append(
                        f"{what} raised {type(exc).__name__}: {exc}"
                    )
                    summary["status"] = "error"
    return [str(p) for p in drawn], False


def _interruption(summary: dict, signum: int, during: str, lost: list, figures: bool) -> None:
    """Say in the summary that a signal stopped the run (status "interrupted"), while
    what, and what it did not write (the figures not drawn, the rows not computed)."""
    drawn = summary.get("figures")
    if figures and drawn is None:
        lost = [*lost, "the figures (none drawn)"]
    elif figures and during == "the figures":
        lost = [*lost, f"the figures not drawn after these {len(drawn)} files: {drawn}"]
    summary["status"] = "interrupted"
    summary["interruption"] = {
        "signal": signal.Signals(signum).name,
        "during": during,
        "not_written": lost,
    }


def _say_size(plan, out_dir: Path, notice) -> None:
    """Before a run that will write a lot: how much, and the disk's free space."""
    csv, npz = plan.output_bytes()
    if csv + npz <= LARGE_OUTPUT:
        return
    free = shutil.disk_usage(out_dir).free
    text = (
        f"this run will write about {_size(csv + npz)} into {out_dir} (results.csv "
        f"{_size(csv)}, results.npz {_size(npz)}: {plan.n_steps // plan.output_every + 1} rows "
        f"of {1 + (plan.outputs if plan.record is None else len(plan.record))} columns); "
        f"the disk has {_size(free)} free.  --output-interval records fewer rows, "
        "--record fewer columns"
    )
    (notice or (lambda message: warnings.warn(message, stacklevel=3)))(text)


def _size(n: float) -> str:
    for unit in ("bytes", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n:.0f} {unit}" if unit == "bytes" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} GiB"
