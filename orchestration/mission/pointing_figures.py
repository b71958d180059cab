"""A run's pointing figures (docs/pointing.md): for each ECSS pointing requirement the
scenario or variant judges, ``pointing_<name>.png``, the index's magnitude against time
with the requirement's bound and the statistic compared to it (the level's quantile
under the requirement's interpretation).  A campaign's are in
:mod:`..campaign.pointing_figures`."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from ..output import plots
from ..output.results import ColumnError
from ..pointing import ANGLE_UNITS, NotEvaluable, format_angle
from ..pointing.names import MEANINGS
from .requirements import Pointing


def run_figures(scenario, variant, results, out_dir) -> list[Path]:
    """The figure of each pointing requirement ``variant`` judges that the run can show
    (:func:`shown`), from where its window starts; one judged over a campaign says so."""
    from ..mission.requirements import OVER_CAMPAIGN

    return [
        profile(
            Path(out_dir) / f"pointing_{r.name}.png",
            result,
            t,
            m[0],
            since=float(results.time[0]) if r.start is None else r.start,
            verdict=OVER_CAMPAIGN if r.over_campaign else None,
        )
        for r, result, t, m in shown(scenario, variant, results)
    ]


def shown(scenario, variant, results):
    """(requirement, result, times, magnitudes) of each pointing requirement ``variant``
    judges that the run can show (one whose columns were not recorded, or whose index the
    run is too short for, has none: the summary's verdict says why it was not evaluated).
    One judged over a campaign (ensemble, mixed) is a campaign's verdict: the result is
    what the run shows, its estimate."""
    exempt = scenario.variant(variant).exempt()
    for r in scenario.requirements_for(variant):
        if not isinstance(r, Pointing) or r.name in exempt:
            continue
        requirement = r.requirement
        if r.over_campaign:  # one run: its estimate, no confidence
            requirement = replace(requirement, confidence=None)  # type: ignore[type-var]
        try:
            error = r.error(results, results.time)
            t, m = requirement.magnitudes(error)  # type: ignore[attr-defined]
        except (ColumnError, NotEvaluable):
            continue
        yield r, requirement.judge(t, m), t, m  # type: ignore[attr-defined]


def title(requirement, details: dict, unit: str = "deg", verdict: str | None = None) -> str:
    """A figure's title: the quantity (the index in words, and its label), then the
    verdict in a line (``details``: :meth:`..pointing.PointingResult.to_dict`;
    ``verdict``: said instead of the result's own, "judged over the campaign")."""
    quantity = f"{MEANINGS[requirement.index].capitalize()}, {requirement.label()}"
    return f"{quantity}\n{verdict_line(requirement, details, unit, verdict)}"


def verdict_line(r, details: dict, unit: str = "deg", verdict: str | None = None) -> str:
    """The verdict in one short line: the verdict in a few words (``details["short"]``:
    "met (95 % confidence)", "undecided: about 1109 runs", "met on the estimate"), the
    value compared (or the estimate) and the bound (the level and interpretation are the
    statistic's, in the legend)."""
    value, estimate = details.get("value"), details.get("estimate")
    head = verdict or details.get("short") or details["status"]
    if value is None and estimate is None:
        return head
    text = (
        format_angle(value, unit)
        if value is not None
        else f"estimate {format_angle(estimate, unit)}"
    )
    return f"{head}: {text}" + ("" if r.bound is None else f", bound {format_angle(r.bound, unit)}")


def profile(
    path: Path,
    result,
    t,
    m,
    unit: str = "deg",
    since: float | None = None,
    verdict: str | None = None,
) -> Path:
    """The index's magnitude ``m`` at times ``t`` of one run (t random in Δt: its largest
    over the window's positions), with the bound (red dashed) and ``result``'s statistic
    (dash-dotted; the estimate where no value was compared).  ``since``: where the window
    of the requirement starts; the time before its first value, where a windowed index has
    none, is shaded and drawn empty.  ``verdict``: the title's, instead of the result's."""
    r, stat, scale = result.requirement, result.statistic, ANGLE_UNITS[unit]
    marks: dict = {"bottom": 0.0}
    if r.bound is not None:
        marks["limit"] = ((r.bound / scale,), f"requirement {format_angle(r.bound, unit)}")
    shown = f"at {100 * stat.level:g} % ({stat.interpretation})"
    shown += f"{' estimate' * (result.value is None)}: {format_angle(stat.value, unit)}"
    marks["statistic"] = (stat.value / scale, shown)
    if since is not None and since < t[0]:
        marks["empty"] = (since, t[0], "no value yet")
    m = np.asarray(m)
    label = r.label() + (" (largest over the window's positions)" if m.ndim == 2 else "")
    series = {label: (m.max(axis=1) if m.ndim == 2 else m) / scale}
    return plots.lines(
        path,
        title(r, result.to_dict(), unit, verdict),
        t,
        series,
        f"{r.index} [{unit}]",
        title_size=10,
        **marks,
    )
