"""Run a shipped scenario (or any system file) end to end: build what is stale, plan the
run (:mod:`.cosim.plan`), simulate, write results, summary (:mod:`.output.summary`) and
figures.  The CLI's ``agilesat run`` is a thin layer on this.
"""

from __future__ import annotations

import os
import signal
import time
from contextlib import nullcontext
from pathlib import Path

from . import scenarios
from .cosim.master import Interrupted, SimulationError, execute
from .cosim.plan import plan_run
from .cosim.signals import signal_at, stop_on_signals
from .output.lock import holding
from .output.recorder import write_text
from .output.results import Results
from .output.summary import facts, generic_summary, summary_text, write_records
from .system.cached import system_file
from .system.parameters import did_you_mean


def parse_target(target):
    """'scan_pitch:literal_spin' -> (Scenario, 'literal_spin'); a Scenario -> (it, None);
    a file path -> (None, None)."""
    if isinstance(target, scenarios.Scenario):
        return target, None
    name, _, variant = str(target).partition(":")
    if name in scenarios.NAMES:
        scenario = scenarios.get(name)
        if variant and variant not in scenario.variants:
            raise KeyError(
                f"scenario {name} has no variant {variant!r}"
                + did_you_mean(variant, scenario.variants)
                + f" (variants: {', '.join(scenario.variants) or 'none'})"
            )
        return scenario, variant or None
    if Path(target).suffix in (".ssd", ".ssp"):
        return None, None
    raise KeyError(
        f"{target!r} is neither a scenario ({', '.join(scenarios.NAMES)}) nor an "
        ".ssd/.ssp file" + did_you_mean(name, scenarios.NAMES)
    )


def run(
    target,
    *,
    step=None,
    stop=None,
    algorithm=None,
    parameters=None,
    out_dir=None,
    figures: bool = True,
    svg: bool = False,
    echo=None,
    build: bool = True,
    progress=None,
    derivatives: bool = True,
) -> tuple[Results, dict]:
    """Run a scenario[:variant] (a name or a :class:`Scenario`) or a system file; returns
    (results, summary).  ``parameters``: {"Instance.variable": value}, whole arrays or
    elements (:mod:`.system.parameters`); ``progress`` and ``derivatives``: see
    :func:`.cosim.master.simulate`.

    With ``out_dir``: results.csv (row by row), results.npz, log.txt and summary.json, also
    when the run fails (``status: "error"``) or is interrupted by SIGINT/SIGTERM
    (``status: "interrupted"``, and ``interruption``: the signal, while what, what was not
    written; a signal while the results or figures are written stops the figures and is
    said the same way); the exception is raised after they are written.  The run holds
    ``out_dir`` (:mod:`.output.lock`): a second run on it is refused.  The summary lists
    every input left open with what its default means (``unconnected_optional_inputs``).

    ``figures``: the scenario's figures (a system file's: an overview of its outputs) as
    200-dpi PNGs, with ``svg`` an SVG beside each (~25 % more figure time).
    """
    scenario, variant = parse_target(target)
    overrides = dict(parameters or {})
    if scenario is not None:
        if build:
            from ..fmus.build import build_all

            build_all(names=scenario.components)
        path = scenario.ssd
        overrides = {**scenario.variant_parameters(variant), **overrides}
    else:
        path = Path(target)
    wall = time.perf_counter()
    plan = plan_run(
        system_file(path),
        step=step,
        stop=stop,
        algorithm=algorithm,
        parameters=overrides,
        derivatives=derivatives,
        out_dir=out_dir,
        progress=progress,
        echo=echo,
    )
    out_dir = plan.out_dir
    summary = {
        "scenario": scenario.name if scenario else None,
        "variant": variant,
        "system": str(path),
        "parameters": {k: {"value": p.value, "type": p.type} for k, p in plan.overrides.items()},
    }
    figures = figures and out_dir is not None
    with stop_on_signals() as signals, holding(out_dir) if out_dir else nullcontext():
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
            summary.update(scenario.metrics(results))
            summary["status"] = "failed" if summary["diagnostics"] else "ok"
        else:
            summary.update(generic_summary(results))
        stopped = False  # the figures, by a signal
        if out_dir is not None:
            write_records(results, summary, out_dir)
            if figures and signals.signal is None:
                summary["figures"], stopped = _figures(scenario, results, out_dir, svg, signals)
                write_text(out_dir / "summary.json", summary_text(summary))
        if signals.signal is not None:  # after the last macro step: said, and exit 130/143
            during = "the figures" if stopped else "the results"
            _interruption(summary, signals.signal, during, [], figures)
            if out_dir is not None:
                write_text(out_dir / "summary.json", summary_text(summary))
            raise Interrupted(
                f"{path.name}: interrupted by {signal.Signals(signals.signal).name} while "
                f"writing {during}; the run is complete"
                + (f", what was written is in {out_dir / 'summary.json'}" if out_dir else ""),
                results,
                signals.signal,
            )
    return results, summary


class _Stopped(Exception):
    """A signal came while the figures were drawn."""


def _figures(scenario, results, out_dir: Path, svg: bool, signals) -> tuple[list[str], bool]:
    """Draw the figures; stop before the next one once a signal came.  (The files
    written, whether it stopped.)  $AGILESAT_TEST_SIGNAL=SIGNAL@figure:K: a signal as the
    K-th starts."""
    from .output import plots

    draw = scenario.figures if scenario is not None else plots.overview
    hook, started = signal_at("figure"), [0]

    def before():
        started[0] += 1
        if hook is not None and started[0] == hook[1]:
            os.kill(os.getpid(), hook[0])
        if signals.signal is not None:
            raise _Stopped

    with plots.written_as(plots.FORMATS if svg else plots.FORMATS[:1]):
        with plots.drawing(before) as drawn:
            try:
                draw(results, out_dir)
            except _Stopped:
                return [str(p) for p in drawn], True
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
