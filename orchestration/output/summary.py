"""A run's summary: ``summary.json`` and the lines ``agilesat run`` prints.

``summary.json`` (UTF-8 text): the target and settings, every parameter override with its
FMI type, status, wall time and real-time factor (simulated seconds per wall-clock
second), the metrics (a scenario's, each with unit, display unit, the paper's value and its
requirement where there is one) or, for any other system, min/max/final of every recorded
output and the momentum drift where ``H_I`` is recorded; the figures written.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..provenance import header
from ..system.units import display_factor, join, pretty
from .recorder import write_text
from .results import Results, units_path


def facts(results: Results, wall: float) -> dict:
    meta = results.meta
    settings = {k: meta[k] for k in ("start", "stop", "step", "algorithm")}
    simulated = float(results.time[-1]) - settings["start"] if len(results) else 0.0
    return {
        "settings": settings,
        "rows": len(results),
        "wall_time": wall,
        "real_time_factor": simulated / max(wall, 1e-9),
        "unconnected_optional_inputs": meta["unconnected_optional_inputs"],
        "fmu_messages": [str(e) for e in meta["log"] if e.status >= 1],
    }


def summary_text(summary: dict) -> str:
    """summary.json's text: JSON, which has no Infinity or NaN (a value that is not a
    finite number is null; a metric's says why in its ``reason``)."""
    return json.dumps(_finite(summary), indent=2, default=str, ensure_ascii=False) + "\n"


def _finite(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value


def write_records(results: Results, summary: dict, out_dir: Path) -> None:
    """The units of results.csv, log.txt (the FMUs' messages, then the summary's
    ``errors``) and summary.json (the master writes results.csv row by row and
    results.npz); an OSError names each file not written."""
    problems = []
    for path, text in (
        (
            units_path(out_dir / "results.csv"),
            json.dumps(results.units, indent=1, ensure_ascii=False) + "\n",
        ),
        (
            out_dir / "log.txt",
            header({k: summary[k] for k in ("version", "command", "date") if k in summary})
            + "".join(f"{e}\n" for e in results.meta["log"])
            + "".join(f"error: {e}\n" for e in summary.get("errors", ())),
        ),
        (out_dir / "summary.json", summary_text(summary)),
    ):
        try:
            write_text(path, text)
        except OSError as exc:
            problems.append(str(exc))
    if problems:
        raise OSError("\n".join(problems))


def generic_summary(results: Results) -> dict:
    """Any system: min/max/final of every output, the momentum drift of every recorded
    ``H_I`` (max |H(t) − H(0)| / |H(0)|); status ok (nothing is required of it)."""
    outputs = {}
    for name, column in zip(results.names[1:], results.data[:, 1:].T):
        outputs[name] = {
            "min": float(np.min(column)),
            "max": float(np.max(column)),
            "final": float(column[-1]),
            "unit": results.units.get(name),
        }
    metrics = {}
    for base in sorted(
        {n.rsplit("[", 1)[0] for n in results.names if n.rsplit("[", 1)[0].endswith(".H_I")}
    ):
        metrics[f"{base.split('.')[0]}.momentum_drift"] = {
            "value": relative_drift(results.vector(base)),
            "unit": "1",
            "display_unit": "1",
            "description": f"max |H_I(t) − H_I(0)| / |H_I(0)| of {base}",
        }
    return {"metrics": metrics, "outputs": outputs, "diagnostics": [], "status": "ok"}


def _display(value, unit, display_unit):
    """(value in the display unit, the display unit as people write it); in ``unit`` when
    the display unit does not convert (never a value under another unit's name)."""
    scale = display_factor(unit, display_unit)
    if scale is None:
        return value, pretty(unit)
    return value * scale, pretty(display_unit or unit)


def format_value(value: float, unit: str | None, display_unit: str | None = None) -> str:
    """A value (SI, in ``unit``) as people read it, in ``display_unit``: '0.032°',
    '0.006 °/s', '5 N·m' (four significant digits)."""
    shown, text = _display(value, unit, display_unit)
    return join(f"{shown:.4g}", text)


def requirement_text(requirement, unit, display_unit) -> str:
    """A requirement as text in the display unit: a bound (≤ x), a band [a, b], or
    {"min"/"max": ...} (either may be missing)."""
    if isinstance(requirement, dict):
        low = requirement.get("min", requirement.get("lower"))
        high = requirement.get("max", requirement.get("upper"))
    elif isinstance(requirement, (list, tuple)):
        low, high = requirement
    else:
        low, high = None, requirement
    show = lambda x: f"{_display(x, unit, display_unit)[0]:.4g}"  # noqa: E731
    u = _display(0.0, unit, display_unit)[1]
    if low is not None and high is not None:
        return join(f"in [{show(low)}, {show(high)}]", u)
    if high is not None:
        return join(f"≤ {show(high)}", u)
    return join(f"≥ {show(low)}", u) if low is not None else ""


def format_summary(summary: dict) -> str:
    """The headline numbers beside the paper's and the requirement, in each metric's display
    unit, with each requirement's verdict (a metric without a value says why); for a system
    without a scenario, min/max/final of every output."""
    lines = []
    verdicts = {"met": "PASS", "not met": "FAIL"}
    for name, m in summary.get("metrics", {}).items():
        unit, display = m["unit"], m.get("display_unit")
        u = _display(0.0, unit, display)[1]  # also of the paper's value beside no value
        value = None if m["value"] is None else _display(m["value"], unit, display)[0]
        text = join(f"{value:.6g}", u) if value is not None else "no value"
        if m.get("failed"):  # it raised: a mistake of its own
            text = "not evaluated"
        paper = (
            "paper " + join(f"{_display(m['paper'], unit, display)[0]:.6g}", u)
            if "paper" in m
            else ""
        )
        required = (
            f"required {requirement_text(m['requirement'], unit, display)}"
            if "requirement" in m
            else ""
        )
        verdict = verdicts.get(m.get("verdict", ""), m.get("verdict", ""))
        if verdict == "" and "met" in m:  # a summary written before verdicts
            verdict = {True: "PASS", False: "FAIL"}.get(m["met"], "")
        lines.append(f"  {name:34s} {text:>18s}   {paper:22s} {required:28s} {verdict}".rstrip())
        if m["value"] is None and m.get("reason"):
            lines.append(f"  {'':34s} ({m['reason']})")
    metrics = summary.get("metrics", {})
    for name, r in summary.get("requirements", {}).items():
        if name in metrics and "requirement" in metrics[name]:
            if r["verdict"] == "not judged":
                lines.append(f"  {'':34s} not judged: {r.get('reason', '')}")
            continue
        shown = r.get("text") or f"{r['statement']}: {r['verdict']}"
        reason = f" ({r['reason']})" if r.get("reason") and not r.get("text") else ""
        lines.append(f"  requirement {shown}{reason}")
    outputs = summary.get("outputs", {})
    if outputs:
        lines.append(f"  {'output':40s} {'min':>12s} {'max':>12s} {'final':>12s}  unit")
        for name, o in outputs.items():
            lines.append(
                f"  {name:40s} {o['min']:12.5g} {o['max']:12.5g} {o['final']:12.5g}"
                f"  {pretty(o['unit'])}".rstrip()
            )
    if "wall_time" in summary:
        lines.append(
            f"  status {summary.get('status', '?')}, wall time "
            f"{summary['wall_time']:.2f} s, {summary['real_time_factor']:.3g}× real "
            "time"
        )
    for problem in summary.get("diagnostics", []):
        lines.append(f"  FAILED: {problem}")
    for error in summary.get("errors", []):
        lines.append(f"  ERROR: {error}")
    return "\n".join(lines)


def relative_drift(H: np.ndarray, scale: float = 0.0) -> float:
    """max |H(t) − H(0)| / max(|H(0)|, scale) over the rows of H (N, 3).  ``scale``: the
    largest momentum a part of the system carries, for a system whose total starts at
    zero (at rest in inertial space), where |H(0)| alone would divide rounding by zero."""
    change = float(np.abs(H - H[0]).max())
    norm = max(float(np.linalg.norm(H[0])), scale)
    return change / norm if norm > 0 else (0.0 if change == 0 else math.inf)
