"""Run a shipped scenario (or any system file) end to end: build what is stale, simulate,
write results, summary and figures.  The CLI's ``agilesat run`` is a thin layer on this.
"""
from __future__ import annotations

import json
from pathlib import Path

from ..fmus.model_description import UNITS
from . import scenarios
from .master import SimulationError, simulate
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
    (results, summary)."""
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
    try:
        results = simulate(system, step=step, stop=stop, algorithm=algorithm,
                           parameters=overrides, out_dir=out_dir, echo=echo)
    except SimulationError as failure:
        if out_dir is not None and failure.results is not None:
            _write_records(failure.results, out_dir)
        raise
    summary = {
        "scenario": scenario.name if scenario else None,
        "variant": variant,
        "system": str(system),
        "settings": {k: results.meta[k] for k in ("start", "stop", "step", "algorithm")},
        "parameters": overrides,
        "fmu_messages": [str(e) for e in results.meta["log"] if e.status >= 1],
    }
    if scenario is not None:
        summary.update(scenario.metrics(results))
        summary["status"] = "failed" if summary["diagnostics"] else "ok"
    if out_dir is not None:
        _write_records(results, out_dir)
        (out_dir / "summary.json").write_text(json.dumps(summary, indent=2, default=str) + "\n")
        if figures and scenario is not None:
            summary["figures"] = [str(p) for p in scenario.figures(results, out_dir)]
    return results, summary


def _write_records(results: Results, out_dir: Path) -> None:
    """results.npz and log.txt (results.csv is written while the run goes)."""
    results.to_npz(out_dir / "results.npz")
    (out_dir / "log.txt").write_text("".join(f"{e}\n" for e in results.meta["log"]))


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

