"""A pointing requirement as a contract states it, and its verdict on an error history.

    PointingRequirement("RPE", bound=math.radians(0.001), level=0.9973,
                        interpretation="ensemble", window=1.0, axis=(0, 0, 1),
                        confidence=0.95).evaluate(error)

reads "the relative performance error over Δt = 1 s about the body z axis stays within
0.001° for 99.73 % of the runs at every time, shown with 95 % confidence".  Everything is
SI (rad, s); only :meth:`PointingResult.line` takes a display unit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..system.units import join, pretty
from .errors import BLOCK, ErrorHistory, describe, direction
from .indices import NotEvaluable, check_index, index_series, magnitude
from .names import ANGLE_UNITS, INDICES
from .statistics import (
    Statistic,
    check_statistic,
    confidence_achieved,
    percent,
    statistic,
)
from .statistics import runs_needed as fewest_runs


def format_angle(value: float, unit: str = "deg") -> str:
    """``value`` (rad) in ``unit``, four significant digits: "0.001°", "3.6 arcsec"."""
    if unit not in ANGLE_UNITS:
        raise ValueError(f"unknown angle unit {unit!r}: expected one of {', '.join(ANGLE_UNITS)}")
    return join(f"{value / ANGLE_UNITS[unit]:.4g}", pretty(unit))


def _unit(v, name: str) -> tuple[float, float, float] | None:
    if v is None:
        return None
    x, y, z = direction(v, name)
    return (float(x), float(y), float(z))


def _seconds(value: float) -> str:
    return f"{value:g} s"


@dataclass(frozen=True)
class PointingRequirement:
    """``index`` (APE … KRE) within ``bound`` (rad) at probability ``level`` under
    ``interpretation`` (temporal, ensemble, mixed).

    ``window`` Δt (s) for all but APE/AKE; ``separation`` Δt_s (s, start to start) for
    PDE/PRE/KDE/KRE; ``t_in_window`` ("end" or "random") for RPE/RKE.  The error signal:
    about ``axis``, the half-cone of ``boresight``, or (neither) the 3-axis angle; a scalar
    error history takes neither.  ``confidence`` (ensemble only): the value compared to
    the bound is then the order statistic that bounds the level's quantile with it.
    ``bound`` None: the index is computed, not judged (status "computed").
    """

    index: str
    bound: float | None
    level: float
    interpretation: str
    window: float | None = None
    separation: float | None = None
    t_in_window: str = "end"
    axis: tuple[float, float, float] | None = None
    boresight: tuple[float, float, float] | None = None
    confidence: float | None = None

    def __post_init__(self):
        check_index(self.index, self.window, self.separation, self.t_in_window)
        if self.bound is not None and not (math.isfinite(self.bound) and self.bound > 0.0):
            raise ValueError(f"bound must be a positive angle (rad), got {self.bound}")
        check_statistic(self.level, self.interpretation, self.confidence)
        if self.axis is not None and self.boresight is not None:
            raise ValueError("give an axis or a boresight, not both")
        object.__setattr__(self, "axis", _unit(self.axis, "axis"))
        object.__setattr__(self, "boresight", _unit(self.boresight, "boresight"))

    def label(self) -> str:
        """The index and its signal: ``RPE(1 s) about (0, 0, 1)``, ``PDE(10 s, Δt_s 60 s)``."""
        arguments = []
        if self.window is not None:
            arguments.append(_seconds(self.window))
        if self.separation is not None:
            arguments.append(f"Δt_s {_seconds(self.separation)}")
        if self.t_in_window == "random":
            arguments.append("t random in Δt")
        text = self.index + (f"({', '.join(arguments)})" if arguments else "")
        if self.axis is not None:
            text += f" about {describe(self.axis)}"
        if self.boresight is not None:
            text += f" half-cone of {describe(self.boresight)}"
        return text

    def probability(self) -> str:
        """The probability: ``at 99.73 % (ensemble) with 95 % confidence``."""
        text = f"at {percent(self.level)} ({self.interpretation})"
        if self.confidence is not None:
            text += f" with {percent(self.confidence)} confidence"
        return text

    def runs_needed(self) -> int | None:
        """The fewest runs that can show the requirement at its confidence (none above)."""
        return None if self.confidence is None else fewest_runs(self.level, self.confidence)

    def signal(self, error: ErrorHistory) -> ErrorHistory:
        """The error the index is computed on: about the axis, the line of sight, or as is."""
        if self.axis is not None:
            return error.about(self.axis)
        if self.boresight is not None:
            return error.line_of_sight(self.boresight)
        return error

    def magnitudes(self, error: ErrorHistory, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """(t, m): the index's magnitude ``m[run, time]`` on ``error`` at times ``t`` (what
        the statistic is taken of; ``seed``: the draw of t in the window, if random);
        :class:`NotEvaluable` if the history holds no run or is too short for the index."""
        if error.runs == 0:
            raise NotEvaluable("no run to evaluate (none reached the end)")
        rng = np.random.default_rng(seed)
        parts = []
        for start in range(0, error.runs, BLOCK):  # the same draw as all runs at once
            block = self.signal(error.runs_between(start, start + BLOCK))
            args = (self.index, self.window, self.separation, self.t_in_window, rng)
            series = index_series(block, *args)
            parts.append(magnitude(series))
        return series.t, np.concatenate(parts)

    def evaluate(self, error: ErrorHistory, seed: int = 0) -> PointingResult:
        """The verdict on ``error`` (``seed``: the draw of t in the window, if random)."""
        try:
            t, m = self.magnitudes(error, seed)
        except NotEvaluable as reason:
            needed = self.runs_needed()
            return PointingResult(self, "not evaluable", error.runs, needed, reason=str(reason))
        return self.judge(t, m)

    def judge(self, t: np.ndarray, m: np.ndarray) -> PointingResult:
        """The verdict on the index's magnitudes ``m[run, time]`` at times ``t``
        (:meth:`magnitudes`)."""
        needed, runs = self.runs_needed(), len(m)
        exceedances = achieved = None
        if self.interpretation == "ensemble" and self.bound is not None:
            exceedances = int((m > self.bound).sum(axis=0).max())
            achieved = confidence_achieved(runs, exceedances, self.level)
        try:
            stat = statistic(m, self.level, self.interpretation, self.confidence)
        except NotEvaluable as reason:  # too few runs for the confidence: say what they show
            shown = statistic(m, self.level, self.interpretation)
            return PointingResult(
                self,
                "not evaluable",
                runs,
                needed,
                estimate=shown.value,
                confidence_achieved=achieved,
                exceedances=exceedances,
                reason=str(reason),
                statistic=shown,
                t=t,
            )
        return PointingResult(
            self,
            "computed" if self.bound is None else "met" if stat.value <= self.bound else "not met",
            runs,
            needed,
            value=stat.value,
            estimate=stat.estimate,
            confidence_achieved=achieved,
            exceedances=exceedances,
            statistic=stat,
            t=t,
        )


@dataclass(frozen=True, eq=False)
class PointingResult:
    """The verdict: ``status`` "met", "not met", "computed" (no bound) or "not evaluable"
    (then ``reason``).

    ``value`` (rad) is what was compared to the bound, ``estimate`` the empirical quantile
    (equal to ``value`` without a confidence).  Ensemble: ``exceedances`` is the most runs
    above the bound at one time, ``confidence_achieved`` the confidence that at least the
    level's fraction of runs is within the bound (at the worst time); ``runs_needed`` the
    fewest runs the stated confidence takes.  ``statistic`` holds the profile (per run or
    per time ``t``), for figures.  Values that do not exist are None.  A campaign too
    small for the stated confidence is "not evaluable" with no ``value``, but its
    ``estimate``, ``exceedances``, ``confidence_achieved`` and the estimate's ``statistic``
    (what it does show).
    """

    requirement: PointingRequirement
    status: str
    runs: int
    runs_needed: int | None
    value: float | None = None
    estimate: float | None = None
    confidence_achieved: float | None = None
    exceedances: int | None = None
    reason: str | None = None
    statistic: Statistic | None = None
    t: np.ndarray | None = None

    @property
    def met(self) -> bool | None:
        return {"met": True, "not met": False}.get(self.status)

    def line(self, unit: str = "deg") -> str:
        """The verdict in a line: ``RPE(1 s) about (0, 0, 1) at 99.73 % (ensemble) with 95 %
        confidence: 0.0007° (requirement 0.001°): met``."""
        r = self.requirement
        head = f"{r.label()} {r.probability()}"
        if self.value is None and self.estimate is None:
            return f"{head}: {self.status} ({self.reason})"
        if self.value is None:  # a campaign too small for the confidence
            text = f"{head}: {self.status} ({self.reason}); estimate "
            text += format_angle(self.estimate, unit)  # type: ignore[arg-type]
            if r.bound is None:
                return text
            return (
                f"{text} (requirement {format_angle(r.bound, unit)}), "
                f"{self.exceedances} of {self.runs} run(s) above it: "
                f"{100 * self.confidence_achieved:.3g} % confidence"
            )
        value = format_angle(self.value, unit)
        if r.bound is None:
            return f"{head}: {value}"
        return f"{head}: {value} (requirement {format_angle(r.bound, unit)}): {self.status}"

    def to_dict(self) -> dict:
        """JSON-ready record (SI: rad, s)."""
        r, stat = self.requirement, self.statistic
        worst: dict = {}
        if stat is not None and stat.worst is not None:
            if stat.interpretation == "ensemble" and self.t is not None:
                worst = {"worst_time": float(self.t[stat.worst])}
            else:
                worst = {"worst_run": stat.worst}
        return {
            "requirement": {
                "index": r.index,
                "bound": r.bound,
                "level": r.level,
                "interpretation": r.interpretation,
                "window": r.window,
                "separation": r.separation,
                "t_in_window": r.t_in_window if INDICES[r.index][0] == "relative" else None,
                "axis": None if r.axis is None else list(r.axis),
                "boresight": None if r.boresight is None else list(r.boresight),
                "confidence": r.confidence,
            },
            "text": self.line("deg"),
            "status": self.status,
            "met": self.met,
            "value": self.value,
            "estimate": self.estimate,
            "runs": self.runs,
            "runs_needed": self.runs_needed,
            "exceedances": self.exceedances,
            "confidence_achieved": self.confidence_achieved,
            "reason": self.reason,
            **worst,
        }
