"""Run a shipped scenario (or any system file) end to end: build what is stale, plan the
run (:mod:`.cosim.plan`), simulate, write results, summary (:mod:`.output.summary`) and
figures.  The CLI's ``agilesat run`` is a thin layer on this.
"""

from __future__ import annotations

import time
from pathlib import Path

from . import scenarios
from .cosim.master import Interrupted, SimulationError, execute
from .cosim.plan import plan_run
from .cosim.signals import stop_on_signals
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
    (``status: "interrupted"``); the exception is raised after they are written.  The
    summary lists every input left open with what its default means
    (``unconnected_optional_inputs``).

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
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
    summary = {
        "scenario": scenario.name if scenario else None,
        "variant": variant,
        "system": str(path),
        "parameters": {k: {"value": p.value, "type": p.type} for k, p in plan.overrides.items()},
    }
    with stop_on_signals() as signals:
        try:
            results = execute(plan)
        except SimulationError as failure:
            if out_dir is not None and failure.results is not None:
                summary.update(
                    facts(failure.results, time.perf_counter() - wall),
                    error=str(failure),
                    status="interrupted" if isinstance(failure, Interrupted) else "error",
                )
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
        if out_dir is not None:
            write_records(results, summary, out_dir)
            if figures and signals.signal is None:
                from .output import plots

                draw = scenario.figures if scenario is not None else plots.overview
                with plots.written_as(plots.FORMATS if svg else plots.FORMATS[:1]):
                    paths = draw(results, out_dir)
                    summary["figures"] = [str(p) for path in paths for p in plots.formats(path)]
                write_text(out_dir / "summary.json", summary_text(summary))
    return results, summary
