"""A run's pointing figures (docs/pointing.md): for each ECSS pointing requirement the
scenario or variant judges, ``pointing_<name>.png``, the index's magnitude against time
with the requirement's bound and the statistic compared to it (the level's quantile
under the requirement's interpretation).  A campaign's are in :mod:`..campaign.pointing_figures`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..pointing import ANGLE_UNITS, NotEvaluable, format_angle
from ..pointing.names import MEANINGS
from . import plots
from .results import ColumnError


def run_figures(scenario, variant, results, out_dir) -> list[Path]:
    """The figure of each pointing requirement ``variant`` judges that the run can show
    (:func:`shown`), from where its window starts."""
    return [
        profile(
            Path(out_dir) / f"pointing_{r.name}.png",
            result,
            t,
            m[0],
            since=float(results.time[0]) if r.start is None else r.start,
        )
        for r, result, t, m in shown(scenario, variant, results)
    ]


def shown(scenario, variant, results):
    """(requirement, result, times, magnitudes) of each pointing requirement ``variant``
    judges that the run can show (one whose columns were not recorded, or whose index the
    run is too short for, has none: the summary's verdict says why it was not evaluated)."""
    from ..mission.requirements import Pointing

    exempt = scenario.variant(variant).exempt()
    for r in scenario.requirements_for(variant):
        if not isinstance(r, Pointing) or r.name in exempt:
            continue
        try:
            error = r.error(results, results.time)
            t, m = r.requirement.magnitudes(error)  # type: ignore[attr-defined]
        except (ColumnError, NotEvaluable):
            continue
        yield r, r.requirement.judge(t, m), t, m  # type: ignore[attr-defined]


def title(requirement, details: dict, unit: str = "deg") -> str:
    """A figure's title: the quantity (the index in words, and its label), then the
    verdict in a line (``details``: :meth:`..pointing.PointingResult.to_dict`)."""
    quantity = f"{MEANINGS[requirement.index].capitalize()}, {requirement.label()}"
    return f"{quantity}\n{verdict_line(requirement, details, unit)}"


def verdict_line(r, details: dict, unit: str = "deg") -> str:
    """The verdict in one short line: the status, the value compared (or the estimate)
    and the bound (the level and interpretation are the statistic's, in the legend); a
    campaign too small for the confidence says how many runs it has of those needed."""
    value, estimate = details.get("value"), details.get("estimate")
    head = details["status"]
    if value is None and details.get("runs_needed"):
        head += (
            f" with {100 * r.confidence:g} % confidence ({details['runs']} of the "
            f"{details['runs_needed']} runs needed)"
        )
    if value is None and estimate is None:
        return head
    text = (
        format_angle(value, unit)
        if value is not None
        else f"estimate {format_angle(estimate, unit)}"
    )
    return f"{head}: {text}" + ("" if r.bound is None else f", bound {format_angle(r.bound, unit)}")


def profile(path: Path, result, t, m, unit: str = "deg", since: float | None = None) -> Path:
    """The index's magnitude ``m`` at times ``t`` of one run, with the bound (red dashed)
    and ``result``'s statistic (dash-dotted; the estimate where no value was compared).
    ``since``: where the window of the requirement starts; the time before its first
    value, where a windowed index has none, is shaded and drawn empty."""
    r, stat, scale = result.requirement, result.statistic, ANGLE_UNITS[unit]
    marks: dict = {"bottom": 0.0}
    if r.bound is not None:
        marks["limit"] = ((r.bound / scale,), f"requirement {format_angle(r.bound, unit)}")
    shown = f"at {100 * stat.level:g} % ({stat.interpretation})"
    shown += f"{' estimate' * (result.value is None)}: {format_angle(stat.value, unit)}"
    marks["statistic"] = (stat.value / scale, shown)
    if since is not None and since < t[0]:
        marks["empty"] = (since, t[0], "no value yet")
    series = {r.label(): np.asarray(m) / scale}
    return plots.lines(
        path,
        title(r, result.to_dict(), unit),
        t,
        series,
        f"{r.index} [{unit}]",
        title_size=10,
        **marks,
    )
