"""The shipped scenarios: a system (written as ``systems/<name>.ssd``), variants, metrics
and figures.

A scenario's system is defined here at the level of whole variables and written to SSD
by ``agilesat generate`` (the ``.ssd`` files are committed; a test keeps them in sync).
Running reads only the ``.ssd`` and the FMUs.  A variant is a set of parameter values
applied on top of the system's: ``agilesat run scan_pitch:literal_spin``.
"""

from __future__ import annotations

import importlib
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # NumPy is imported where it is used: the CLI's --help needs none
    import numpy as np

SYSTEMS_DIR = Path(__file__).resolve().parent.parent / "systems"
NAMES = ("scan_pitch", "payload_sweep", "video_sar")


@dataclass
class Scenario:
    name: str
    title: str
    components: tuple[str, ...]  # instance name = FMU name
    connections: tuple[tuple[str, str], ...]  # ("A.output", "B.input"), whole variables
    parameters: dict  # "A.parameter" -> value (scalar or array)
    stop: float
    step: float
    metrics: Callable  # Results -> {"metrics", "diagnostics"}
    figures: Callable  # (Results, out_dir) -> [paths]
    variants: dict = field(default_factory=dict)  # name -> (description, {"A.p": value})
    # Jacobi: the hub extrapolates the devices' momentum over the step with their hdot, a
    # coupling error of second order (tests/orchestration/test_coupling.py, README
    # "Coupling accuracy")
    algorithm: str = "jacobi"
    steps: dict = field(default_factory=dict)  # instance -> its own step (multirate.py)
    system: Path | None = None  # the .ssd, if not the shipped systems/<name>

    @property
    def ssd(self) -> Path:
        return self.system or SYSTEMS_DIR / f"{self.name}.ssd"

    def variant_parameters(self, variant: str | None) -> dict:
        """Scalar-named parameter values of a variant ({} for the default)."""
        if not variant:
            return {}
        if variant not in self.variants:
            raise KeyError(
                f"scenario {self.name} has no variant {variant!r}; variants: "
                f"{', '.join(self.variants) or 'none'}"
            )
        return scalar_values(self.variants[variant][1])

    def render_ssd(self, sources: dict | None = None, variant: str | None = None) -> bytes:
        """The system as SSD.  FMU sources default to ``fmus/build`` relative to
        ``systems/``; a variant's parameter values replace the defaults."""
        from ...components.variables import UNITS
        from ...fmus import model_class
        from ...fmus.build import BUILD_DIR
        from ..system.ssp import render_ssd

        tables = {}
        for name in self.components:
            tables[name] = model_class(name).VARIABLES
        sources = sources or {
            name: Path(os.path.relpath(BUILD_DIR / f"{name}.fmu", SYSTEMS_DIR)).as_posix()
            for name in self.components
        }
        self.variant_parameters(variant)  # unknown variant: KeyError
        parameters = {**self.parameters, **(self.variants[variant][1] if variant else {})}
        title = f"{self.name}:{variant}" if variant else self.name
        return render_ssd(
            title,
            sources,
            tables,
            self.connections,
            parameters,
            UNITS,
            0.0,
            self.stop,
            self.step,
            self.algorithm,
            self.steps,
        )


def get(name: str) -> Scenario:
    if name not in NAMES:
        raise KeyError(f"unknown scenario {name!r}; scenarios: {', '.join(NAMES)}")
    return importlib.import_module(f"{__name__}.{name}").SCENARIO


def summarize(metrics: dict, paper: dict | None = None, requirements: dict | None = None) -> dict:
    """{name: (value, unit, display unit, description)} -> the summary's metric entries,
    with the paper's value beside each one it gives (value None: not reached).

    ``requirements`` maps a metric name to ``{"min": lo, "max": hi}`` (either bound or
    both, a band; SI like the value): its entry gets ``"requirement"`` and ``"met"``
    (lo <= value <= hi; a value not reached does not meet it).  Campaign pass rates count
    ``met`` per run.
    """
    entries = {
        name: {
            "value": None if v is None else float(v),
            "unit": u,
            "display_unit": d,
            "description": text,
            **({"paper": paper[name]} if paper and name in paper else {}),
        }
        for name, (v, u, d, text) in metrics.items()
    }
    for name, bounds in (requirements or {}).items():
        if not bounds or set(bounds) - {"min", "max"}:
            raise ValueError(f"requirement on {name}: expected 'min' and/or 'max', got {bounds}")
        value = entries[name]["value"]
        entries[name]["requirement"] = {k: float(bounds[k]) for k in ("min", "max") if k in bounds}
        entries[name]["met"] = value is not None and bool(
            bounds.get("min", -math.inf) <= value <= bounds.get("max", math.inf)
        )
    return entries


def inertial_momentum(results, inertia, *devices: str) -> np.ndarray:
    """C_BIᵀ (J w + Σ h) per row (N, 3), from the recorded SatelliteDynamics attitude and
    rate and the named devices' momentum columns."""
    import numpy as np

    from ...components.rotations import dcm, rotate_back

    w = results.vector("SatelliteDynamics.w_BI_B")
    body = w @ np.asarray(inertia).T + sum(results.vector(d) for d in devices)
    C = dcm(tuple(results.vector("SatelliteDynamics.q_BI").T))
    return np.array(rotate_back(C, tuple(body.T))).T


def scalar_values(values: dict) -> dict:
    """{"A.x": array} -> {"A.x[1,1]": ..., ...} in FMI structured names (1-based)."""
    import numpy as np

    result = {}
    for key, value in values.items():
        array = np.asarray(value)
        if array.ndim == 0:
            result[key] = value.item() if hasattr(value, "item") else value
            continue
        for index in np.ndindex(array.shape):
            result[f"{key}[{','.join(str(i + 1) for i in index)}]"] = array[index].item()
    return result
