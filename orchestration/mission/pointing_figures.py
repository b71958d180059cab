"""A run's pointing figures (docs/pointing.md): for each ECSS pointing requirement the
scenario or variant judges, ``pointing_<name>.png``, the index's magnitude against time
with the requirement's bound and the statistic compared to it (the level's quantile
under the requirement's interpretation).  A campaign's are in
:mod:`..campaign.pointing_figures`."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np

from ..output import plots
from ..output.results import ColumnError
from ..pointing import ANGLE_UNITS, NotEvaluable, format_angle
from .requirements import Pointing


def run_figures(scenario, variant, results, out_dir) -> list[Path]:
    """The figure of each pointing requirement ``variant`` judges that the run can show
    (one whose columns were not recorded, or whose index the run is too short for, has
    none: the summary's verdict says why it was not evaluated)."""
    exempt = scenario.variant(variant).exempt()
    paths = []
    for r in scenario.requirements_for(variant):
        if not isinstance(r, Pointing) or r.name in exempt:
            continue
        try:
            error = r.error(results, results.time)
            t, m = r.requirement.magnitudes(error)  # type: ignore[attr-defined]
        except (ColumnError, NotEvaluable):
            continue
        result = r.requirement.judge(t, m)  # type: ignore[attr-defined]
        paths.append(profile(Path(out_dir) / f"pointing_{r.name}.png", r.name, result, t, m[0]))
    return paths


def profile(path: Path, name: str, result, t, m, unit: str = "deg") -> Path:
    """The index's magnitude ``m`` at times ``t`` of one run, with the bound (red dashed)
    and ``result``'s statistic (dash-dotted; the estimate where no value was compared)."""
    r, stat, scale = result.requirement, result.statistic, ANGLE_UNITS[unit]
    marks: dict = {"bottom": 0.0}
    if r.bound is not None:
        marks["limit"] = ((r.bound / scale,), f"requirement {format_angle(r.bound, unit)}")
    shown = f"at {100 * stat.level:g} % ({stat.interpretation})"
    shown += f"{' estimate' * (result.value is None)}: {format_angle(stat.value, unit)}"
    marks["statistic"] = (stat.value / scale, shown)
    title = textwrap.fill(f"{name}: {result.line(unit)}", 90)
    series = {r.label(): np.asarray(m) / scale}
    return plots.lines(path, title, t, series, f"{r.index} [{unit}]", **marks)
