"""Run a shipped scenario (or any system file) end to end: build what is stale, simulate,
write results, summary and figures.  The CLI's ``agilesat run`` is a thin layer on this.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

from ..fmus.model_description import UNITS
from . import scenarios
from .master import Interrupted, SimulationError, simulate, stop_on_signals
from .recorder import file_error
from .results import Results


def parse_target(target):
    """'scan_pitch:literal_spin' -> (Scenario, 'literal_spin'); a Scenario -> (it, None);
    a file path -> (None, None)."""
    if isinstance(target, scenarios.Scenario):
        return target, None
    name, _, variant = target.partition(":")
    if name in scenarios.NAMES:
        scenario = scenarios.get(name)
        scenario.variant_parameters(variant or None)  # unknown variant: KeyError now
        return scenario, variant or None
    if Path(target).suffix in (".ssd", ".ssp"):
        return None, None
    raise KeyError(f"{target!r} is neither a scenario ({', '.join(scenarios.NAMES)}) nor an "
                   ".ssd/.ssp file")


def run(target, *, step=None, stop=None, algorithm=None, parameters=None, out_dir=None,
        figures: bool = True, echo=None, build: bool = True) -> tuple[Results, dict]:
    """Run a scenario[:variant] (a name or a :class:`Scenario`) or a system file; returns
    (results, summary).

    With ``out_dir``: results.csv (row by row), results.npz, log.txt and summary.json, also
    when the run fails (``status: "error"``) or is interrupted by SIGINT/SIGTERM
    (``status: "interrupted"``); the exception is raised after they are written.  The
    summary lists every input left open with what its default means
    (``unconnected_optional_inputs``).
    """
    scenario, variant = parse_target(target)
    overrides = dict(parameters or {})
    if scenario is not None:
        if build:
            from ..fmus.build import build_all
            build_all(names=scenario.components)
        system = scenario.ssd
        overrides = {**scenario.variant_parameters(variant), **overrides}
    else:
        system = Path(target)
    if out_dir is not None:
        out_dir = Path(out_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
    summary = {"scenario": scenario.name if scenario else None, "variant": variant,
               "system": str(system), "parameters": overrides}
    with stop_on_signals() as signals:
        try:
            results = simulate(system, step=step, stop=stop, algorithm=algorithm,
                               parameters=overrides, out_dir=out_dir, echo=echo)
        except SimulationError as failure:
            if out_dir is not None and failure.results is not None:
                summary.update(_facts(failure.results), error=str(failure),
                               status="interrupted" if isinstance(failure, Interrupted)
                               else "error")
                try:
                    _write_records(failure.results, summary, out_dir)
                except OSError as exc:   # say both
                    failure.args = (f"{failure}\n{exc}",)
            raise
        summary.update(_facts(results))
        if scenario is not None:
            summary.update(scenario.metrics(results))
            summary["status"] = "failed" if summary["diagnostics"] else "ok"
        if out_dir is not None:
            _write_records(results, summary, out_dir)
            if figures and scenario is not None and signals.signal is None:
                summary["figures"] = [str(p) for p in scenario.figures(results, out_dir)]
    return results, summary


def _facts(results: Results) -> dict:
    meta = results.meta
    return {"settings": {k: meta[k] for k in ("start", "stop", "step", "algorithm")},
            "rows": len(results),
            "unconnected_optional_inputs": meta["unconnected_optional_inputs"],
            "fmu_messages": [str(e) for e in meta["log"] if e.status >= 1]}


def _write_records(results: Results, summary: dict, out_dir: Path) -> None:
    """log.txt and summary.json, each under a temporary name then renamed (the master
    writes results.csv row by row and results.npz); an OSError names each file not written."""
    problems = []
    for name, text in (("log.txt", "".join(f"{e}\n" for e in results.meta["log"])),
                       ("summary.json", json.dumps(summary, indent=2, default=str) + "\n")):
        path = out_dir / name
        temporary = path.with_name(f".{name}.{os.getpid()}.partial")
        try:
            temporary.write_text(text)
            os.replace(temporary, path)
        except OSError as exc:
            temporary.unlink(missing_ok=True)
            problems.append(str(file_error(path, exc, "; not written")))
    if problems:
        raise OSError("\n".join(problems))


def format_summary(summary: dict) -> str:
    """The headline numbers beside the paper's, in each metric's display unit."""
    lines = []
    for name, m in summary.get("metrics", {}).items():
        scale = UNITS.get(m["unit"], ({}, {}))[1].get(m.get("display_unit"), 1.0)
        unit = m.get("display_unit") or m["unit"]
        value = "not reached" if m["value"] is None else f"{m['value'] * scale:.6g} {unit}"
        paper = f"paper {m['paper'] * scale:.6g} {unit}" if "paper" in m else ""
        lines.append(f"  {name:34s} {value:>22s}   {paper}")
    for problem in summary.get("diagnostics", []):
        lines.append(f"  FAILED: {problem}")
    return "\n".join(lines)

