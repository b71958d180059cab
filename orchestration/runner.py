"""Run a shipped scenario (or any system file) end to end: build what is stale, simulate,
write results, summary and figures.  The CLI's ``agilesat run`` is a thin layer on this.

``summary.json`` (UTF-8 text): the target and settings, every parameter override with its
FMI type, status, wall time and real-time factor (simulated seconds per wall-clock
second), the metrics (a scenario's, each with unit, display unit, the paper's value and its
requirement where there is one) or, for any other system, min/max/final of every recorded
output and the momentum drift where ``H_I`` is recorded; the figures written.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import threading
import time
import warnings
from pathlib import Path

import numpy as np
from lxml import etree

from ..fmus.model_description import UNITS
from . import scenarios
from .cosim.fmu import Description
from .cosim.master import Interrupted, SimulationError, simulate, stop_on_signals
from .output.recorder import write_text
from .output.results import Results, units_path
from .system.parameters import did_you_mean, scalar_parameters
from .system.ssp import NS, SystemFile, read_system
from .system.units import pretty
from .system.validation import override


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
    figure_processes: int = 0,
) -> tuple[Results, dict]:
    """Run a scenario[:variant] (a name or a :class:`Scenario`) or a system file; returns
    (results, summary).  ``parameters``: {"Instance.variable": value}, whole arrays or
    elements (:mod:`.parameters`); ``progress`` and ``derivatives``: see :func:`simulate`.

    With ``out_dir``: results.csv (row by row), results.npz, log.txt and summary.json, also
    when the run fails (``status: "error"``) or is interrupted by SIGINT/SIGTERM
    (``status: "interrupted"``); the exception is raised after they are written.  The
    summary lists every input left open with what its default means
    (``unconnected_optional_inputs``).

    ``figures``: the scenario's figures (a system file's: an overview of its outputs) as
    200-dpi PNGs, with ``svg`` an SVG beside each (~25 % more figure time).
    ``figure_processes``: 0 draws the figures in this process; n > 0 in n processes of a
    worker started with the run, which imports matplotlib while the run simulates
    (:mod:`.figure_pool`; the CLI's choice, :func:`.figure_pool.processes_for_figures`).
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
    system = system_file(path)
    typed = typed_overrides(system, overrides)
    if out_dir is not None:
        out_dir = Path(out_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
    summary = {
        "scenario": scenario.name if scenario else None,
        "variant": variant,
        "system": str(path),
        "parameters": {k: {"value": p.value, "type": p.type} for k, p in typed.items()},
    }
    wall = time.perf_counter()
    with (
        stop_on_signals() as signals,
        _figure_pool(figure_processes if figures and out_dir is not None else 0, scenario) as pool,
    ):
        try:
            results = simulate(
                system,
                step=step,
                stop=stop,
                algorithm=algorithm,
                parameters={k: p.value for k, p in typed.items()},
                out_dir=out_dir,
                echo=echo,
                progress=progress,
                derivatives=derivatives,
            )
        except SimulationError as failure:
            if out_dir is not None and failure.results is not None:
                summary.update(
                    _facts(failure.results, time.perf_counter() - wall),
                    error=str(failure),
                    status="interrupted" if isinstance(failure, Interrupted) else "error",
                )
                try:
                    _write_records(failure.results, summary, out_dir)
                except OSError as exc:  # say both
                    failure.args = (f"{failure}\n{exc}",)
            raise
        summary.update(_facts(results, time.perf_counter() - wall))
        if scenario is not None:
            summary.update(scenario.metrics(results))
            summary["status"] = "failed" if summary["diagnostics"] else "ok"
        else:
            summary.update(generic_summary(results))
        if out_dir is not None:
            _write_records(results, summary, out_dir)
            if figures and signals.signal is None:
                from .output import plots

                draw = (lambda f, *a: f(*a)) if pool is None else pool.draw
                with plots.written_as(plots.FORMATS if svg else plots.FORMATS[:1]):
                    paths = draw(
                        scenario.figures if scenario is not None else plots.overview,
                        results,
                        out_dir,
                    )
                    summary["figures"] = [str(p) for path in paths for p in plots.formats(path)]
                write_text(out_dir / "summary.json", _summary_text(summary))
    return results, summary


@contextlib.contextmanager
def _figure_pool(processes: int, scenario):
    """A :class:`.figure_pool.FigurePool` of ``processes`` (None for 0), stopped at the end."""
    if processes <= 0:
        yield None
        return
    from .output.figure_pool import FigurePool

    try:
        pool = FigurePool(processes, (scenario.figures.__module__,) if scenario is not None else ())
    except OSError as exc:  # no process to be had: draw here
        warnings.warn(f"figures drawn in this process: no figure worker ({exc})", stacklevel=3)
        yield None
        return
    with pool:
        yield pool


def _facts(results: Results, wall: float) -> dict:
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


def _summary_text(summary: dict) -> str:
    return json.dumps(summary, indent=2, default=str, ensure_ascii=False) + "\n"


def _write_records(results: Results, summary: dict, out_dir: Path) -> None:
    """The units of results.csv, log.txt and summary.json (the master writes results.csv
    row by row and results.npz); an OSError names each file not written."""
    problems = []
    for path, text in (
        (
            units_path(out_dir / "results.csv"),
            json.dumps(results.units, indent=1, ensure_ascii=False) + "\n",
        ),
        (out_dir / "log.txt", "".join(f"{e}\n" for e in results.meta["log"])),
        (out_dir / "summary.json", _summary_text(summary)),
    ):
        try:
            write_text(path, text)
        except OSError as exc:
            problems.append(str(exc))
    if problems:
        raise OSError("\n".join(problems))


def typed_overrides(system, overrides: dict) -> dict:
    """{"A.x[i]": ParameterValue} of the overrides (whole arrays split, each typed by the
    FMU's variable), checked against the system's model descriptions (``system``: a path or
    a :class:`SystemFile`)."""
    if not overrides:
        return {}
    if not isinstance(system, SystemFile):
        system = read_system(system)  # holds an .ssp's unpacked FMUs while we read
    described = {c.name: Description(c.name, c.source) for c in system.components}
    return {
        k: override(described, k, v) for k, v in scalar_parameters(described, overrides).items()
    }


_systems: dict[tuple, SystemFile] = {}  # content key -> the system read from it
_systems_lock = threading.Lock()
_SYSTEMS_KEPT = 8


def system_file(path) -> SystemFile:
    """:func:`read_system` once per content: a run of a campaign worker (or any repeated
    run) takes the system read before when the file, and every ``.ssv`` file its parameter
    bindings name, hold the same bytes (SHA-256; an edited file is read again).  Reading
    and checking an ``.ssd`` against the SSP schema takes about as long as the first 2 s
    of a scan_pitch run; the systems of the last :data:`_SYSTEMS_KEPT` contents are kept
    (an ``.ssp``'s with its unpacked FMUs)."""
    path = Path(path).resolve()
    key = _content_key(path)
    if key is None:
        return read_system(path)  # which says what is wrong
    with _systems_lock:
        system = _systems.get(key)
    if system is None:
        system = read_system(path)
        with _systems_lock:
            if len(_systems) >= _SYSTEMS_KEPT:
                _systems.pop(next(iter(_systems)))
            _systems[key] = system
    return system


def _content_key(path: Path) -> tuple | None:
    """(path, SHA-256 of its bytes and of each .ssv it binds); None if a file is missing
    or the XML malformed."""
    try:
        data = path.read_bytes()
    except OSError:
        return None
    key = [str(path), hashlib.sha256(data).hexdigest()]
    if path.suffix != ".ssp":  # an .ssp holds its .ssv files
        try:
            root = etree.fromstring(data)
        except etree.XMLSyntaxError:
            return None
        for binding in root.iterfind(".//ssd:ParameterBinding[@source]", NS):
            ssv = (path.parent / binding.get("source")).resolve()
            try:
                key.append(hashlib.sha256(ssv.read_bytes()).hexdigest())
            except OSError:
                return None
    return tuple(key)


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
            "value": scenarios.relative_drift(results.vector(base)),
            "unit": "1",
            "display_unit": "1",
            "description": f"max |H_I(t) − H_I(0)| / |H_I(0)| of {base}",
        }
    return {"metrics": metrics, "outputs": outputs, "diagnostics": [], "status": "ok"}


def _join(number: str, unit: str) -> str:
    """'0.5 rad/s', '2.1°' (no space before a degree sign), '0.57' (no unit)."""
    return number + ("" if not unit or unit.startswith("°") and "/" not in unit else " ") + unit


def _display(value, unit, display_unit):
    """(value in the display unit, the display unit as people write it)."""
    scale = UNITS.get(unit, ({}, {}))[1].get(display_unit, 1.0)
    return value * scale, pretty(display_unit or unit)


def _requirement(requirement, unit, display_unit) -> str:
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
        return _join(f"in [{show(low)}, {show(high)}]", u)
    if high is not None:
        return _join(f"≤ {show(high)}", u)
    return _join(f"≥ {show(low)}", u) if low is not None else ""


def format_summary(summary: dict) -> str:
    """The headline numbers beside the paper's and the requirement, in each metric's display
    unit; for a system without a scenario, min/max/final of every output."""
    lines = []
    for name, m in summary.get("metrics", {}).items():
        unit, display = m["unit"], m.get("display_unit")
        value, u = (None, "") if m["value"] is None else _display(m["value"], unit, display)
        text = "not reached" if value is None else _join(f"{value:.6g}", u)
        paper = (
            "paper " + _join(f"{_display(m['paper'], unit, display)[0]:.6g}", u)
            if "paper" in m
            else ""
        )
        required = (
            f"required {_requirement(m['requirement'], unit, display)}"
            if "requirement" in m
            else ""
        )
        verdict = {True: "PASS", False: "FAIL"}.get(m.get("met"), "")
        lines.append(f"  {name:34s} {text:>18s}   {paper:22s} {required:28s} {verdict}".rstrip())
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
    return "\n".join(lines)
