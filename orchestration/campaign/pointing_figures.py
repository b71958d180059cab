"""A campaign's pointing figures (docs/pointing.md): for each ECSS pointing requirement
judged over the campaign (ensemble or mixed: a temporal one is judged run by run),
``pointing_<name>.png``, the distribution of the values its statistic is taken of, as the
fraction of them above each value (log scale: the tail a 99.73 % level lives in), with the
bound, the value compared, the empirical quantile and the level, titled with the verdict.
The values (:func:`values`):

- ensemble: each run's index at the worst time (the statistic's time);
- mixed: every run's index at every time.

The level's quantile, the ⌈P n⌉-th smallest of the n values, is the smallest value with
at most a fraction 1 − P above it: where the curve first reaches 1 − P or below.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np

from ..output.kept import reached_the_end
from ..pointing import ANGLE_UNITS, NotEvaluable, format_angle


def values(result, t: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, str]:
    """(values, what they are) of ``result``'s statistic on magnitudes ``m[run, time]``."""
    stat, index = result.statistic, result.requirement.index
    if stat.interpretation == "ensemble":
        return m[:, stat.worst], f"each run's {index} at t = {t[stat.worst]:g} s (worst time)"
    return m.ravel(), f"{index} of every run at every time"


def campaign_figures(
    requirements, signals, names: list[str], t: np.ndarray, ensemble: dict, out: Path
) -> list[Path]:
    """The figure of each pointing requirement of ``requirements`` (those judged over the
    campaign) on the runs of ``signals`` (runs, ``names``, points) that reached the end;
    ``ensemble``: campaign.json's verdicts, whose text titles each."""
    from ..mission.requirements import Pointing

    paths = []
    for r in requirements:
        if not isinstance(r, Pointing):
            continue
        kept = np.asarray(signals[:, [names.index(c) for c in r.signals]])
        kept = kept[reached_the_end(kept)]
        try:
            error = r.error({c: kept[:, i] for i, c in enumerate(r.signals)}, t)
            times, m = r.requirement.magnitudes(error)  # type: ignore[attr-defined]
        except NotEvaluable:
            continue  # no run reached the end, or too short a history: the verdict says
        result = r.requirement.judge(times, m)  # type: ignore[attr-defined]
        text = ensemble.get(r.name, {}).get("text") or result.line()
        path = out / f"pointing_{r.name}.png"
        paths.append(distribution(path, f"{r.name}: {text}", result, *values(result, times, m)))
    return paths


def distribution(path: Path, title: str, result, x: np.ndarray, what: str) -> Path:
    """The fraction of ``x`` above each value, with ``result``'s marks (module)."""
    from ..output.plots import plt
    from .report import _save

    r, stat, unit = result.requirement, result.statistic, "deg"
    scale, n = ANGLE_UNITS[unit], len(x)
    fig, ax = plt.subplots(figsize=(7, 4.2))
    above = (n - 1 - np.arange(n)) / n  # on [x_i, x_i+1): of the sorted x
    ax.step(np.sort(x) / scale, above, where="post", color="tab:blue", label=f"{n} values")
    ax.set_yscale("log", nonpositive="mask")  # the largest value: where the curve ends
    ax.set_ylim(0.5 * min(1 / n, 1 - stat.level), 1.5)  # the level shown with few runs
    tail = 1 - stat.level
    ax.axhline(tail, color="0.35", linestyle=":", label=f"1 − level ({tail:.3g})")
    marks = [
        (r.bound, "tab:red", "--", "requirement"),
        (result.value, "black", "-.", "value compared"),
        (result.estimate, "tab:green", ":", "empirical quantile"),
    ]
    if result.value == result.estimate:
        marks.pop()  # one line: the value is the empirical quantile
    for value, colour, style, label in marks:
        if value is not None:
            shown = f"{label} {format_angle(value, unit)}"
            ax.axvline(value / scale, color=colour, linestyle=style, linewidth=1.2, label=shown)
    ax.set_xlabel(f"{what} [{unit}]")
    ax.set_ylabel("fraction above")
    ax.set_title(textwrap.fill(title, 90), fontsize=9)
    ax.legend(fontsize=8)
    return _save(fig, ax, path)
