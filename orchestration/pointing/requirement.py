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
import warnings
from dataclasses import dataclass, replace

import numpy as np

from ..system.units import join, pretty
from .errors import BLOCK, ErrorHistory, describe, direction
from .indices import (
    NotEvaluable,
    check_index,
    index_series,
    magnitude,
    position_weights,
    samples_in,
    window_positions,
)
from .names import ANGLE_UNITS, INDICES
from .statistics import Statistic, check_statistic, percent, statistic, upper_value
from .statistics import runs_needed as fewest_runs
from .verdicts import MET, NOT_MET, UNDECIDED, Decision, allowed_above, decide

COMPUTED, NOT_EVALUATED = "computed", "not evaluated"
#: the most index values (runs × times × window positions) "t random in Δt" holds at once
MIXTURE_LIMIT = 5 * 10**7


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
    error history takes neither.  ``confidence`` (ensemble, mixed): the value compared to
    the bound is then the value the runs show the level's quantile stays under.
    ``bound`` None: the index is computed, not judged (status "computed").

    The verdict (:meth:`judge`): with a ``confidence`` (ensemble, mixed), met, not met or
    undecided by the anytime-valid tests of :mod:`.verdicts`; without one, on the
    estimate (the empirical quantile), and it says so; temporal: each run's own time (a
    run above the bound is a violation, shown), met when every run made meets it.
    "t random in Δt": every window position of every time, weighted (the exact mixture;
    no random draw).
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

    def magnitudes(self, error: ErrorHistory, seed=None) -> tuple[np.ndarray, np.ndarray]:
        """(t, m): the index's magnitude ``m[run, time]`` on ``error`` at times ``t`` (what
        the statistic is taken of); t random in Δt: ``m[run, time, position]`` over the
        window's positions (:func:`.indices.window_positions`, weighted by
        :func:`.indices.position_weights`).  :class:`NotEvaluable` if the history holds no
        run or is too short for the index (or, t random, too large to hold at once).
        ``seed``: no longer used (no random draw); say so once."""
        _no_seed(seed)
        if error.runs == 0:
            raise NotEvaluable("no run to evaluate (none reached the end)")
        random = self.t_in_window == "random"
        if random:
            n = samples_in(self.window, error.dt, "window Δt")  # type: ignore[arg-type]
            size = error.runs * max(0, error.t.size - 2 * n) * (n + 1)
            if size > MIXTURE_LIMIT:
                raise NotEvaluable(
                    f"t random in Δt: {error.runs} runs × {error.t.size - 2 * n} times × "
                    f"{n + 1} window positions are {size:.3g} values, more than the "
                    f"{MIXTURE_LIMIT:.3g} held at once: fewer runs or a shorter record"
                )
        parts = []
        for start in range(0, error.runs, BLOCK):
            block = self.signal(error.runs_between(start, start + BLOCK))
            if random:
                series = window_positions(block, self.index, self.window)  # type: ignore[arg-type]
            else:
                series = index_series(block, self.index, self.window, self.separation)
            parts.append(magnitude(series))
        return series.t, np.concatenate(parts)

    def evaluate(self, error: ErrorHistory, seed=None, keep: dict | None = None) -> PointingResult:
        """The verdict on ``error`` (a temporal requirement with t random in Δt: run by
        run, in blocks that hold at most :data:`MIXTURE_LIMIT` values).  ``seed``: no
        longer used.  ``keep``: given, it receives the (t, m) judged (:meth:`magnitudes`)
        as ``keep["magnitudes"]``, for a figure of them."""
        _no_seed(seed)
        try:
            if self.t_in_window == "random" and self.interpretation == "temporal":
                return self._temporal_in_blocks(error)
            t, m = self.magnitudes(error)
        except NotEvaluable as reason:
            needed = self.runs_needed()
            return PointingResult(self, NOT_EVALUATED, error.runs, needed, reason=str(reason))
        if keep is not None:
            keep["magnitudes"] = (t, m)
        return self.judge(t, m)

    def _temporal_in_blocks(self, error: ErrorHistory) -> PointingResult:
        """:meth:`judge` of a temporal requirement, each run's statistic on its own."""
        n = samples_in(self.window, error.dt, "window Δt")  # type: ignore[arg-type]
        rows = max(1, MIXTURE_LIMIT // max(1, (error.t.size - 2 * n) * (n + 1)))
        profiles = []
        for start in range(0, max(1, error.runs), rows):
            t, m = self.magnitudes(error.runs_between(start, start + rows))
            profiles.append(
                statistic(m, self.level, "temporal", weights=position_weights(n)).profile
            )
        profile = np.concatenate(profiles)  # type: ignore[arg-type]
        worst = int(np.argmax(profile))
        value = float(profile[worst])
        shown = Statistic("temporal", self.level, value, value, profile, worst)
        return self._temporal(shown, dict(runs=error.runs, runs_needed=None, estimate=value, t=t))

    def _temporal(self, shown: Statistic, common: dict) -> PointingResult:
        """Each run on its own time: no statistics (a run above the bound is a violation)."""
        if self.bound is None:
            return PointingResult(self, COMPUTED, value=shown.value, statistic=shown, **common)
        failing = float(np.sum(shown.profile > self.bound))  # type: ignore[operator]
        status = MET if shown.value <= self.bound else NOT_MET
        return PointingResult(
            self, status, value=shown.value, above=failing, basis="runs", statistic=shown, **common
        )

    def judge(self, t: np.ndarray, m: np.ndarray) -> PointingResult:
        """The verdict on the index's magnitudes ``m[run, time]`` (or ``m[run, time,
        position]``) at times ``t`` (:meth:`magnitudes`)."""
        weights = position_weights(m.shape[2] - 1) if m.ndim == 3 else None
        shown = statistic(m, self.level, self.interpretation, weights=weights)
        common = dict(runs=len(m), runs_needed=self.runs_needed(), estimate=shown.value, t=t)
        if self.interpretation == "ensemble":
            common["estimate_at"] = shown.worst
        if self.interpretation == "temporal":
            return self._temporal(shown, common)
        if self.bound is None:
            return self._computed(m, weights, shown, common)
        x = self.shares(m, self.bound, weights)
        if self.confidence is None:  # on the estimate, as the requirement states no confidence
            status = MET if shown.value <= self.bound else NOT_MET
            counts = x.sum(axis=0)
            above = float(counts.max() if x.ndim == 2 else counts)
            return PointingResult(
                self,
                status,
                value=shown.value,
                above=above,
                basis="estimate",
                statistic=shown,
                **common,
            )
        decision = decide(x, self.level, self.confidence)
        bounded = self._bounded(m, weights, shown)
        stat = bounded or shown
        if stat.profile is not None and decision.above > 0:  # dated at the time that decides
            stat = replace(stat, worst=decision.stream)
        return PointingResult(
            self,
            decision.status,
            value=None if bounded is None else bounded.value,
            above=decision.above,
            basis="confidence",
            decision=decision,
            statistic=stat,
            **common,
        )

    def shares(self, m: np.ndarray, bound: float, weights=None) -> np.ndarray:
        """How much of each run lies above ``bound``: ensemble, ``x[run, time]`` (bool, or
        the share of the window's positions); mixed, ``x[run]``, the share of its time."""
        above = m > bound
        x = above if weights is None else above @ weights
        return x if self.interpretation == "ensemble" else np.mean(x, axis=1)

    def _bounded(self, m, weights, shown: Statistic) -> Statistic | None:
        """The statistic bounded with the confidence: the least value the runs show the
        level's quantile stays under (the order statistic with the most runs above it that
        still show compliance; by bisection for shares), or None when the campaign is too
        small to show any."""
        runs = len(m)
        confidence = self.confidence
        if self.interpretation == "ensemble" and weights is None:
            allowed = allowed_above(runs, self.level, confidence)  # type: ignore[arg-type]
            if allowed is None:
                return None
            profile = upper_value(m, allowed, 0)
            worst = int(np.argmax(profile))
            value = float(profile[worst])
            return Statistic(
                "ensemble", self.level, value, shown.value, profile, worst, confidence, allowed
            )

        def complies(bound: float) -> bool:
            x = self.shares(m, bound, weights)
            return decide(x, self.level, confidence).status == MET  # type: ignore[arg-type]

        low, high = float(np.min(m)), float(np.max(m))
        if not complies(high):
            return None
        for _ in range(40):
            middle = 0.5 * (low + high)
            low, high = (low, middle) if complies(middle) else (middle, high)
        return replace(shown, value=high, confidence=confidence)

    def _computed(self, m, weights, shown: Statistic, common: dict) -> PointingResult:
        """No bound: the index computed (with a confidence, the value the runs show the
        quantile stays under, where they are enough)."""
        bounded = self._bounded(m, weights, shown) if self.confidence is not None else None
        if self.confidence is not None and bounded is None:
            reason = (
                f"a bound with {percent(self.confidence)} confidence needs at least "
                f"{common['runs_needed']} runs; there are {common['runs']}"
            )
            return PointingResult(self, COMPUTED, reason=reason, statistic=shown, **common)
        stat = bounded or shown
        return PointingResult(self, COMPUTED, value=stat.value, statistic=stat, **common)


def _no_seed(seed) -> None:
    if seed is not None:
        warnings.warn(
            "PointingRequirement: seed is no longer used: t random in Δt is the exact "
            "mixture over the window's positions, with no random draw",
            DeprecationWarning,
            stacklevel=3,
        )


@dataclass(frozen=True, eq=False)
class PointingResult:
    """The verdict: ``status`` "met", "not met", "undecided" (with a confidence: neither
    shown), "computed" (no bound) or "not evaluated" (then ``reason``).

    ``basis``: "confidence" (the anytime-valid tests of :mod:`.verdicts`; ``decision``
    holds the evidences), "estimate" (no confidence stated: the empirical quantile
    against the bound) or "runs" (temporal: each run's own time).  ``value`` (rad) is the
    statistic: with a confidence, the value the runs show the level's quantile stays under
    (None if the campaign is too small to show any), ``estimate`` the empirical quantile.
    ``above``: ensemble, the most runs above the bound at one time (the worst time;
    shares of the window's positions summed for t random in Δt); mixed, the runs' shares
    of their time above it, summed; temporal, the runs above it.  ``runs_needed`` the
    fewest runs the stated confidence takes (none above); ``statistic`` holds the profile
    (per run or per time ``t``), for figures; ensemble, ``estimate_at`` the index in ``t``
    of the estimate.  Values that do not exist are None.
    """

    requirement: PointingRequirement
    status: str
    runs: int
    runs_needed: int | None
    value: float | None = None
    estimate: float | None = None
    above: float | None = None
    basis: str | None = None
    decision: Decision | None = None
    reason: str | None = None
    statistic: Statistic | None = None
    t: np.ndarray | None = None
    estimate_at: int | None = None

    @property
    def estimate_time(self) -> float | None:
        """Ensemble: the time of :attr:`estimate`, the largest empirical quantile over
        time (the value compared and the deciding time may lie at others)."""
        if self.estimate_at is None or self.t is None:
            return None
        return float(self.t[self.estimate_at])

    @property
    def met(self) -> bool | None:
        return {MET: True, NOT_MET: False}.get(self.status)

    @property
    def exceedances(self) -> float | None:
        """The former name of :attr:`above`."""
        return self.above

    @property
    def confidence_achieved(self) -> float | None:
        """The highest confidence at which compliance is shown (with a confidence)."""
        return None if self.decision is None else self.decision.compliance_confidence

    @property
    def violation_confidence(self) -> float | None:
        """The highest confidence at which a violation is shown (with a confidence)."""
        return None if self.decision is None else self.decision.violation_confidence

    @property
    def runs_to_decide(self) -> int | None:
        """Undecided: roughly the runs that would settle it if the share above stayed."""
        return None if self.decision is None else self.decision.runs_to_decide()

    @property
    def worst_time(self) -> float | None:
        stat = self.statistic
        if stat is None or stat.worst is None or stat.interpretation != "ensemble":
            return None
        return None if self.t is None else float(self.t[stat.worst])

    def _seen(self) -> str:
        """What the runs show against the bound."""
        r, above = self.requirement, self.above or 0.0
        if not above:
            return f"none of the {self.runs} run(s) above it at any time"
        if r.interpretation == "mixed":
            return f"{100 * above / self.runs:.3g} % of the runs' values above it"
        when = "" if self.worst_time is None else f", t = {self.worst_time:g} s"
        return f"{above:g} of {self.runs} run(s) above it at worst{when}"

    def _settles(self) -> str:
        needed = self.runs_to_decide
        if needed is not None:
            return f"about {needed} runs would settle it"
        share = (self.above or 0.0) / self.runs
        if math.isclose(share, 1 - self.requirement.level, rel_tol=1e-9):
            return "the share above is the level's own: more runs settle it only if it moves"
        return f"more than {10**7} runs would settle it"

    def line(self, unit: str = "deg") -> str:
        """The verdict in a line, with its evidence: ``RPE(1 s) about (0, 0, 1) at 99.73 %
        (ensemble) with 95 % confidence: 0.0007° (requirement 0.001°): met (0 of 1200 run(s)
        above it at worst, t = 3.2 s; compliance shown with 95 % confidence)``."""
        r = self.requirement
        head = f"{r.label()} {r.probability()}"
        if self.status == NOT_EVALUATED:
            return f"{head}: not evaluated ({self.reason})"
        if self.status == COMPUTED:
            if self.value is None:
                return f"{head}: estimate {format_angle(self.estimate, unit)} ({self.reason})"  # type: ignore[arg-type]
            if r.confidence is None:
                return f"{head}: {format_angle(self.value, unit)}"
            quantile = format_angle(self.estimate, unit)  # type: ignore[arg-type]
            return f"{head}: {format_angle(self.value, unit)} (empirical quantile {quantile})"
        shown = self.value if self.basis == "runs" or self.status == MET else self.estimate
        what = "estimate " if shown is not self.value else ""
        return (
            f"{head}: {what}{format_angle(shown, unit)} (requirement "  # type: ignore[arg-type]
            f"{format_angle(r.bound, unit)}): {self.status}{self._evidence()}"  # type: ignore[arg-type]
        )

    def _evidence(self) -> str:
        """What the verdict rests on, after its status in :meth:`line`."""
        if self.basis == "runs":
            if self.runs == 1:
                return ""
            if self.status == MET:
                return f" in each of the {self.runs} runs"
            worst = self.statistic.worst  # type: ignore[union-attr]
            return f" (worst run {worst}; {self.above:g} of {self.runs} runs above it)"
        if self.basis == "estimate":
            return f" on the estimate (no confidence stated; {self._seen()})"
        confidence = percent(self.requirement.confidence)  # type: ignore[arg-type]
        if self.status == MET:
            return f" ({self._seen()}; compliance shown with {confidence} confidence)"
        if self.status == NOT_MET:
            tests = self.decision.tests  # type: ignore[union-attr]
            over = "" if tests == 1 else f", over {tests} evaluated times"
            return f" ({self._seen()}; a violation shown with {confidence} confidence{over})"
        return (
            f" ({self._seen()}; neither compliance nor a violation shown with {confidence} "
            f"confidence: {self._settles()})"
        )

    def short(self) -> str:
        """The verdict in a few words, for a figure: "met (95 % confidence)", "undecided:
        about 1109 runs", "met on the estimate"."""
        r = self.requirement
        if self.basis == "estimate":
            return f"{self.status} on the estimate"
        if self.basis != "confidence":
            return self.status
        if self.status == UNDECIDED:
            needed = self.runs_to_decide
            return UNDECIDED + ("" if needed is None else f": about {needed} runs")
        return f"{self.status} ({percent(r.confidence)} confidence)"  # type: ignore[arg-type]

    def to_dict(self) -> dict:
        """JSON-ready record (SI: rad, s)."""
        r, stat, decision = self.requirement, self.statistic, self.decision
        worst: dict = {}
        if self.worst_time is not None:
            worst = {"worst_time": self.worst_time, "estimate_time": self.estimate_time}
        elif stat is not None and stat.worst is not None:
            worst = {"worst_run": stat.worst}
        evidence = None
        if decision is not None:
            ten = math.log(10)
            evidence = {  # decimal logarithms of the e-values and of what they must reach
                "log10_compliance": decision.log_compliance / ten,
                "log10_compliance_needed": math.log10(decision.needed_compliance),
                "log10_violation": decision.log_violation / ten,
                "log10_violation_needed": math.log10(decision.needed_violation),
                "tests": decision.tests,
                "rule": "anytime-valid e-processes (docs/pointing.md)",
            }
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
            "short": self.short(),
            "status": self.status,
            "met": self.met,
            "basis": self.basis,
            "value": self.value,
            "estimate": self.estimate,
            "runs": self.runs,
            "runs_needed": self.runs_needed,
            "runs_to_decide": self.runs_to_decide,
            "above": self.above,
            "confidence_achieved": self.confidence_achieved,
            "violation_confidence": self.violation_confidence,
            "evidence": evidence,
            "reason": self.reason,
            **worst,
        }
