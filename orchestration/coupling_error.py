"""The coupling error an exported package states per class of host (``agilesat export``).

Another host runs the package's FMUs with its own coupling scheme, and its results differ
from our master's by that scheme's coupling error (docs/coupling.md, docs/hosts.md).  Three
classes of host cover the FMI 2.0 importers:

- **held inputs, Jacobi** (libcosim, ECOS): every FMU steps from the inputs of t_n held
  over the step, and the outputs are read right after the steps, direct feedthrough not
  brought to the communication point: every feedthrough link (controller → steering →
  cluster) adds a step of delay.  Our master emulates it (Jacobi, no derivatives, outputs
  read right after the steps: ``RunPlan.read_after_step``).
- **held inputs, Gauss-Seidel** (a host stepping the FMUs one after the other in
  dependency order, each with the newest outputs, held): our master's Gauss-Seidel without
  derivatives.
- **interpolating** (our master, and hosts that send input derivatives: OMSimulator with
  ``--inputExtrapolation``, FMPy with ``set_input_derivatives``): our master's Jacobi with
  derivatives (its most accurate scheme, the shipped scenarios' default),
  the reference the two others are measured against; its own error against a monolithic
  reference of the same sampled-data system is the coupling study's (``STUDY``, for the
  shipped scenarios at their 0.05 s).

Measured on the package's headline quantities: the scenario's metrics (a target that is a
scenario) and the attitude, the largest rotation between the two runs' ``q_BI`` (every
component with that output), over the whole run at the package's step.  Measuring runs the
system three times; the result is kept in the cache (``coupling/`` of the compile cache
root), keyed on the package's bytes and the scenario, and said to come from there.

``--accuracy A`` (an angle) halves the package's step until both held-input classes stay
within A of our master at that step on the attitude (at most :data:`MAX_HALVINGS` times),
and says what it costs: the macro steps and our master's CPU time of a run.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import time
from importlib import metadata
from pathlib import Path

import numpy as np

#: host class -> how our master emulates it (None: our master's own scheme, the reference)
HOST_CLASSES = {
    "held inputs, Jacobi (libcosim, ECOS)": dict(
        algorithm="jacobi", derivatives=False, read_after_step=True
    ),
    "held inputs, Gauss-Seidel (in dependency order)": dict(
        algorithm="gauss-seidel", derivatives=False
    ),
    "interpolating (our master; hosts sending input derivatives)": None,
}
#: the interpolating class's own coupling error at the shipped scenarios' 0.05 s: our
#: master's Jacobi against the monolithic sampled-data references, attitude in degrees
#: (docs/performance-log.md "Coupling accuracy", 2026-12-01,
#: python tests/tools/benchmark_coupling.py --scenario NAME)
STUDY = {"scan_pitch": 0.00053, "payload_sweep": 3.9e-5, "video_sar": 3.7e-6}
MAX_HALVINGS = 6


@dataclasses.dataclass
class Statement:
    """What a package states: per host class, per headline quantity, (difference, unit,
    display unit); the step measured at; where it came from."""

    step: float
    errors: dict[str, dict[str, tuple[float | None, str, str]]]
    provenance: str

    def header(self) -> str:
        at = f" at {self.step:g} s" if self.step else ""
        return f"coupling error per host class{at} ({self.provenance}):"

    def stated(self) -> dict[str, str]:
        """{host class: its differences, as text}."""
        from .output.summary import format_value

        return {
            host: ", ".join(
                f"{name} {'—' if value is None else format_value(value, unit, display)}"
                for name, (value, unit, display) in quantities.items()
            )
            or "not measured"
            for host, quantities in self.errors.items()
        }

    def lines(self) -> list[str]:
        """The statement as export prints it (and the package's documentation holds)."""
        return [self.header()] + [f"  {h}: {text}" for h, text in self.stated().items()]


def state(package: Path, scenario=None, variant: str | None = None) -> Statement:
    """The package's statement (module docstring), from the cache or measured now."""
    key = _key(package, scenario, variant)
    cached = _cache() / f"{key}.json"
    try:
        data = json.loads(cached.read_text())
        return Statement(
            data["step"],
            {h: {q: tuple(v) for q, v in e.items()} for h, e in data["errors"].items()},
            f"measured {data['date']}, from the cache",
        )
    except (OSError, ValueError, KeyError):
        pass
    from .cosim.master import SimulationError
    from .output.recorder import write_text

    began = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    clock = time.perf_counter()
    try:
        step, errors, _ = measure(package, scenario, variant)
    except SimulationError as failure:  # the package is still what was asked for
        why = str(failure).splitlines()[0]
        return Statement(0.0, {host: {} for host in HOST_CLASSES}, f"not measured: {why}")
    said = Statement(
        step, errors, f"measured now by our master, {time.perf_counter() - clock:.0f} s"
    )
    try:
        cached.parent.mkdir(parents=True, exist_ok=True)
        write_text(cached, json.dumps({"step": step, "errors": errors, "date": began}))
    except OSError:
        pass  # an unwritable cache costs the measurement next time, nothing else
    return said


def held_attitude(package: Path, step=None) -> tuple[float | None, float]:
    """(the larger attitude difference of the two held-input classes from our master, in
    rad (None: no attitude), our master's CPU seconds for the run) at the package's step
    (or ``step``)."""
    _, errors, seconds = measure(package, step=step)
    found = [errors[host].get("attitude") for host, how in HOST_CLASSES.items() if how]
    return (None if None in found else max(x[0] for x in found)), seconds


def measure(package: Path, scenario=None, variant: str | None = None, stop=None, step=None):
    """(step, {host class: {quantity: (difference, unit, display unit)}}, our master's CPU
    seconds for its run) of the package run by our master as each host class (module
    docstring), at its step (or ``step``), to its stop time (or ``stop``); the quantities:
    the attitude and the scenario's metrics that have a requirement or a paper's value."""
    from .cosim.master import execute
    from .cosim.plan import plan_run

    plan = plan_run(Path(package), step=step, stop=stop, algorithm="jacobi", derivatives=True)
    runs = {}
    for host, how in HOST_CLASSES.items():
        if how is not None:
            runs[host] = execute(dataclasses.replace(plan, **how))
    began = time.process_time()
    reference = execute(plan)
    seconds = time.process_time() - began
    metrics = [
        m
        for m in (scenario.metrics_for(variant) if scenario is not None else [])
        if m.require is not None or m.paper is not None
    ]
    base = {m.name: m.evaluate(reference) for m in metrics}
    errors = {}
    for host, how in HOST_CLASSES.items():
        if how is None:
            found = {}
            if scenario is not None and scenario.name in STUDY and math.isclose(plan.step, 0.05):
                found["attitude"] = (math.radians(STUDY[scenario.name]), "rad", "deg")
            errors[host] = found
            continue
        found = {}
        attitude = _attitude(runs[host], reference)
        if attitude is not None:
            found["attitude"] = (attitude, "rad", "deg")
        for m in metrics:
            value, ours = m.evaluate(runs[host]), base[m.name]
            difference = None
            if value.value is not None and ours.value is not None:
                difference = abs(value.value - ours.value)
                if difference <= 1e-12 * max(abs(value.value), abs(ours.value)):
                    difference = 0.0  # the last bits
            found[m.name] = (difference, ours.unit, m.display_unit or ours.unit)
        errors[host] = found
    return plan.step, errors, seconds


def documentation(name: str, statement: Statement) -> bytes:
    """The package's documentation/index.html: the statement, and what the classes are."""
    from html import escape

    hosts = "".join(
        f"<li><b>{escape(host)}</b>: {escape(text)}</li>"
        for host, text in statement.stated().items()
    )
    return (
        "<!DOCTYPE html><html><head><meta charset='utf-8'>"
        f"<title>{escape(name)}</title></head><body><h1>{escape(name)}</h1>"
        f"<h2>Coupling error per host class</h2><p>{escape(statement.header())} What "
        "another FMI host gives differs from agilesat's master by its coupling scheme: "
        "the largest attitude difference (rotation between the two q_BI) and the "
        "difference of each headline quantity, over the whole run.</p>"
        f"<ul>{hosts}</ul>"
        "<p>Held inputs, Jacobi: every FMU steps from the inputs of the step's start, the "
        "outputs read right after the step (libcosim, ECOS): each direct-feedthrough link "
        "adds a step of delay. Held inputs, Gauss-Seidel: the FMUs step one after the "
        "other in dependency order with the newest outputs. Interpolating: the inputs "
        "follow FMI input derivatives or the devices' momentum rates across the step, as "
        "agilesat's master does (its own error against a monolithic reference of the "
        "same sampled-data system: the coupling study).  A smaller step makes the first "
        "two smaller: agilesat export --accuracy chooses it.</p></body></html>\n"
    ).encode()


def _attitude(results, reference) -> float | None:
    """The largest rotation (rad) between the two runs' q_BI, over every component
    with that output; None where there is none."""
    names = [n[: -len(".q_BI[1]")] for n in reference.names if n.endswith(".q_BI[1]")]
    worst = None
    for name in names:
        q = [
            np.column_stack([r[f"{name}.q_BI[{i}]"] for i in (1, 2, 3, 4)])
            for r in (results, reference)
        ]
        dot = np.clip(np.abs(np.einsum("ij,ij->i", q[0], q[1])), 0.0, 1.0)
        angle = float(np.max(2.0 * np.arccos(dot)))
        worst = angle if worst is None else max(worst, angle)
    return worst


def _cache() -> Path:
    from ..components.runtime.cache import cache_root

    return cache_root() / "coupling"


def _key(package: Path, scenario, variant) -> str:
    digest = hashlib.sha256(Path(package).read_bytes())
    digest.update(f"{getattr(scenario, 'name', '')}:{variant}".encode())
    digest.update(metadata.version("agilesat").encode())
    digest.update(Path(__file__).read_bytes())
    return digest.hexdigest()[:24]
