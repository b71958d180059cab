"""A campaign's pointing figures (docs/pointing.md): for each ECSS pointing requirement
judged over the campaign (ensemble or mixed: a temporal one is judged run by run),
``pointing_<name>.png``, the distribution of the values its statistic is taken of, as the
fraction of them above each value (log scale: the tail a 99.73 % level lives in), with the
bound, the value compared, the empirical quantile and the level, titled with the verdict.
The verdict is the campaign's own (campaign.json's ``ensemble``: its value, estimate and
the estimate's time); the figure computes only the values it draws.  The values
(:func:`values`):

- ensemble: each run's index at the estimate's time, where the empirical quantile is
  largest (the value compared, bounded with the confidence, and the time that decides may
  lie at others: campaign.json's ``worst_time`` is the latter);
- mixed: every run's index at every time.

The level's quantile, the ⌈P n⌉-th smallest of the n values, is the smallest value with
at most a fraction 1 − P above it: where the curve first reaches 1 − P or below.

A mixed requirement has millions of values, more than the figure has pixel columns: the
curve drawn keeps (:func:`step_points`) every value from the last one below the level's
quantile on (the tread onto the quantile and the tail, exact), and before it, of the
values in each of :data:`COLUMNS` equal slices of their range, the first and the last:
the staircase drawn through those differs from the full one only inside a slice (a drop
drawn as one vertical line where there were several steps narrower than a pixel column),
since each kept first value starts its slice at the height the previous slice's last
value ended it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..mission.pointing_figures import title as figure_title
from ..output.kept_signals import reached_the_end
from ..pointing import ANGLE_UNITS, format_angle

#: slices of the values' range a curve with more points is thinned to (module): 40 per
#: pixel column of the PNG's 7 in at 200 dpi, so fine that the PNG differs from the full
#: curve's by at most 32 of 255 levels on a few hundred antialiased pixels (measured on
#: 4.4 M values; at 4 per column, the short treads drew a visibly bolder line)
COLUMNS = 40 * 7 * 200


def step_points(
    x: np.ndarray, above: np.ndarray, tail: float, columns: int = COLUMNS
) -> np.ndarray:
    """The indices of the sorted values ``x`` (``above``: the fraction above each, falling)
    a step curve of them keeps (module): all if there are at most ``columns``; else every
    one from the last value below the first at or below ``tail`` (the quantile) on, and
    before that the first and last of each of ``columns`` equal slices of [x₀, x_last]."""
    n = len(x)
    if n <= columns:
        return np.arange(n)
    reached = above <= tail
    start = n
    if reached.any():  # the tread onto the quantile: from the last value below it
        start = max(int(np.searchsorted(x, x[np.argmax(reached)], side="left")) - 1, 0)
    span = x[-1] - x[0]
    if not span > 0:
        column = np.zeros(n, np.int64)
    else:
        column = np.minimum(((x - x[0]) / span * columns).astype(np.int64), columns - 1)
    change = column[1:] != column[:-1]
    keep = np.r_[True, change] | np.r_[change, True]
    keep[start:] = True
    return np.flatnonzero(keep)


def values(requirement, verdict: dict, t: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, str]:
    """(values, what they are) of ``requirement``'s statistic on magnitudes ``m[run, time]``
    at times ``t``: ensemble, at the ``verdict``'s estimate time (its details), so that its
    empirical quantile lies on the curve drawn."""
    index = requirement.index
    if m.ndim == 3:  # t random in Δt: every window position (the ends weigh half in the verdict)
        index += " at every window position"
    if requirement.interpretation == "ensemble":
        at = int(np.argmin(np.abs(t - verdict["estimate_time"])))
        what = f"each run's {index} at t = {t[at]:g} s (largest quantile)"
        return m[:, at].ravel(), what
    if requirement.interpretation == "mixed":
        return m.ravel(), f"{index} of every run at every time"
    raise ValueError(
        f"{requirement.label()}: a {requirement.interpretation} statistic is judged run by "
        "run, not over the campaign"
    )


def campaign_figures(
    requirements,
    signals,
    names: list[str],
    t: np.ndarray,
    ensemble: dict,
    out: Path,
    magnitudes: dict | None = None,
) -> list[Path]:
    """The figure of each pointing requirement of ``requirements`` (those judged over the
    campaign) on the runs of ``signals`` (runs, ``names``, points) that reached the end;
    ``ensemble``: the campaign's verdicts (campaign.json's,
    :func:`..campaign.ensemble_entry`), whose value and estimate each draws and whose text
    titles it.  None where the verdict has neither (no run reached the end, too short a
    history: the verdict says why).  ``magnitudes``: {name: (t, m)} the verdicts judged
    (``evaluate_campaign``'s ``keep``), drawn as they are; a requirement not in it has
    them computed again from ``signals``."""
    from ..mission.requirements import Pointing

    paths = []
    for r in requirements:
        entry = ensemble.get(r.name, {})
        verdict = entry.get("details") or {}
        if not isinstance(r, Pointing) or verdict.get("estimate") is None:
            continue
        if r.name in (magnitudes or {}):
            times, m = magnitudes[r.name]  # type: ignore[index]
        else:
            kept = np.asarray(signals[:, [names.index(c) for c in r.signals]])
            kept = kept[reached_the_end(kept)]
            error = r.error({c: kept[:, i] for i, c in enumerate(r.signals)}, t)
            times, m = r.requirement.magnitudes(error)  # type: ignore[attr-defined]
        title = figure_title(r.requirement, verdict)
        x, what = values(r.requirement, verdict, times, m)
        paths.append(
            distribution(out / f"pointing_{r.name}.png", title, r.requirement, verdict, x, what)
        )
    return paths


def distribution(path: Path, title: str, r, verdict: dict, x: np.ndarray, what: str) -> Path:
    """The fraction of ``x`` above each value, with the marks of requirement ``r`` and of its
    ``verdict`` (module)."""
    from ..output.plots import plt
    from .report import _save

    unit = "deg"
    scale, n = ANGLE_UNITS[unit], len(x)
    fig, ax = plt.subplots(figsize=(7, 4.2))
    above = (n - 1 - np.arange(n)) / n  # on [x_i, x_i+1): of the sorted x
    tail = 1 - r.level
    x = np.sort(x)
    kept = step_points(x, above, tail, COLUMNS)
    ax.step(x[kept] / scale, above[kept], where="post", color="tab:blue", label=f"{n} values")
    ax.set_yscale("log", nonpositive="mask")  # the largest value: where the curve ends
    ax.set_ylim(0.5 * min(1 / n, tail), 1.5)  # the level shown with few runs
    ax.axhline(tail, color="0.35", linestyle=":", label=f"1 − level ({tail:.3g})")
    marks = [
        (r.bound, "tab:red", "--", "requirement"),
        (verdict["value"], "black", "-.", "value compared"),
        (verdict["estimate"], "tab:green", ":", "empirical quantile"),
    ]
    if verdict["value"] == verdict["estimate"]:
        marks.pop()  # one line: the value is the empirical quantile
    for value, colour, style, label in marks:
        if value is not None:
            shown = f"{label} {format_angle(value, unit)}"
            ax.axvline(value / scale, color=colour, linestyle=style, linewidth=1.2, label=shown)
    ax.set_xlabel(f"{what} [{unit}]")
    ax.set_ylabel("fraction above")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)
    return _save(fig, ax, path)
