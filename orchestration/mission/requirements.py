"""Requirements on a run, and their verdicts.

A requirement is an object with a ``name`` and one method, ``evaluate(results, metrics)``
-> :class:`Verdict` (``metrics``: the run's {name: :class:`.metrics.MetricValue`}), and a
``statement()`` for people.  Its verdict is one of

- ``met``, ``not met``: shown (at the stated confidence, where one is stated: a
  statistical requirement judged over a campaign; docs/pointing.md);
- ``undecided``: a statistical requirement whose runs show neither (the verdict says what
  they show and roughly how many runs would settle it); ``agilesat`` exits 4;
- ``not evaluated``: the run cannot answer (the metric has no value, the run ended before
  the window); never counted as met, never as a failure of the run;
- ``not judged``: the variant run is not meant to meet it (:class:`.scenario.Variant`'s
  ``not_judged``), and says why;
- ``judged over the campaign``: in a run (and in a campaign's table of runs), a
  requirement on a campaign's runs together (an ensemble or mixed statistic), which
  ``agilesat campaign`` judges once over them: one verdict per requirement and scope.

:class:`Bound` bounds a metric (``at_most``, ``at_least``, ``within`` make one, as a
metric's ``require=``).  :class:`Pointing` states an ECSS pointing requirement
(:class:`..pointing.PointingRequirement`) on a run's attitude quaternions.  Anything with
the same ``name``/``evaluate``/``statement`` is a requirement: ``agilesat run`` exits 3
when one is not met, campaigns give each one's pass rate, ``assert_requirements_met``
checks them from pytest.

A requirement may also judge a whole campaign (an ensemble statistic): it then has
``signals`` (the recorded columns it needs of every run, kept by the campaign) and
``evaluate_campaign(signals, t)`` -> :class:`Verdict` (``signals`` (runs, len(signals),
points)); :class:`Pointing` does, for its ensemble and mixed interpretations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..output.kept_signals import reached_the_end
from ..output.results import Results
from ..output.summary import requirement_text
from ..pointing.errors import quaternion_columns, recorded_error
from ..system.units import CONVERSIONS, quantity, to_si
from .system import where_written

MET, NOT_MET, UNDECIDED = "met", "not met", "undecided"
NOT_EVALUATED, NOT_JUDGED = "not evaluated", "not judged"
OVER_CAMPAIGN = "judged over the campaign"
VERDICTS = (MET, NOT_MET, UNDECIDED, NOT_EVALUATED, NOT_JUDGED, OVER_CAMPAIGN)
#: why a requirement judged over a campaign has no verdict in a run
OVER_CAMPAIGN_REASON = (
    "a statement about a campaign's runs together (an ensemble or mixed statistic): "
    "`agilesat campaign` judges it once over them"
)


@dataclass(frozen=True)
class Verdict:
    """``status`` (one of :data:`VERDICTS`), the ``value`` compared (SI; None if none) and
    the ``reason`` where not evaluated or not judged."""

    status: str
    value: float | None = None
    reason: str = ""
    text: str = ""  # the verdict in a line, where the requirement words it itself
    details: dict | None = None  # a JSON-ready record, where the requirement keeps one

    def __post_init__(self):
        if self.status not in VERDICTS:
            raise ValueError(f"verdict {self.status!r}: expected one of {VERDICTS}")

    @property
    def met(self) -> bool | None:
        """True, False, or None (undecided, not evaluated, not judged, judged over the
        campaign)."""
        return {MET: True, NOT_MET: False}.get(self.status)


class Requirement:
    """The protocol (see the module); subclasses set ``name``."""

    name: str

    def statement(self, unit: str | None = None, display_unit: str | None = None) -> str:
        """The requirement for people (``unit``, ``display_unit``: of its metric, if any)."""
        return self.name

    def evaluate(self, results, metrics: dict) -> Verdict:
        raise NotImplementedError


@dataclass(frozen=True)
class Bound(Requirement):
    """``min`` ≤ the metric ``metric`` ≤ ``max`` (either may be None; SI numbers, or with a
    unit: ``deg(0.032)``, ``"0.006 deg/s"``).  ``name``: default the metric's."""

    min: object = None
    max: object = None
    metric: str | None = None
    name: str = ""  # type: ignore[assignment]
    origin: str = field(default="", compare=False)  # "file:line" where it was written

    def __post_init__(self):
        if self.min is None and self.max is None:
            raise ValueError("a bound needs min, max or both")
        given = {
            k: _bound_si(k, getattr(self, k))
            for k in ("min", "max")
            if getattr(self, k) is not None
        }
        if len(given) == 2:
            (low, low_unit), (high, high_unit) = given["min"], given["max"]
            if None not in (low_unit, high_unit) and low_unit != high_unit:
                raise ValueError(
                    f"a bound in [{self.min}, {self.max}]: its ends are not in one unit"
                )
            if low > high:
                raise ValueError(
                    f"a bound in [{self.min}, {self.max}]: its lower end is above its upper "
                    "end, so no value meets it"
                )
        if not self.name and self.metric:
            object.__setattr__(self, "name", self.metric)
        if not self.origin:
            object.__setattr__(self, "origin", where_written())

    def on(self, metric: str) -> Bound:
        """This bound on ``metric`` (a metric's ``require=``)."""
        return Bound(self.min, self.max, metric, self.name or metric, self.origin)

    def limits(self, unit: str | None) -> dict[str, float]:
        """{"min": ..., "max": ...} (those given) in ``unit`` (SI)."""
        result = {}
        for key in ("min", "max"):
            value = getattr(self, key)
            if value is not None:
                given = quantity(value)
                result[key] = float(value if given is None else to_si(given, unit))
        return result

    def statement(self, unit: str | None = None, display_unit: str | None = None) -> str:
        """'pointing_accuracy ≤ 0.032°', 'rate in [-0.82, -0.78] °/s' in the metric's
        ``unit`` (SI) shown in ``display_unit``, as the summaries write it; without the
        metric's unit, as the bound is given."""
        if unit is not None:
            return f"{self.metric} {requirement_text(self.limits(unit), unit, display_unit)}"
        limits = {k: getattr(self, k) for k in ("min", "max") if getattr(self, k) is not None}
        show = lambda x: str(x) if quantity(x) is not None else f"{x:g} (SI)"  # noqa: E731
        if "min" in limits and "max" in limits:
            return f"{self.metric} in [{show(limits['min'])}, {show(limits['max'])}]"
        if "max" in limits:
            return f"{self.metric} ≤ {show(limits['max'])}"
        return f"{self.metric} ≥ {show(limits['min'])}"

    def evaluate(self, results, metrics: dict) -> Verdict:
        if self.metric not in metrics:
            raise KeyError(f"requirement {self.name}: no metric {self.metric!r}")
        m = metrics[self.metric]
        if m.value is None:
            return Verdict(NOT_EVALUATED, None, f"{self.metric} has no value: {m.reason}")
        limits = self.limits(m.unit)
        ok = limits.get("min", -math.inf) <= m.value <= limits.get("max", math.inf)
        return Verdict(MET if ok else NOT_MET, m.value)


def _bound_si(key: str, value) -> tuple[float, str | None]:
    """(the SI number, its SI unit or None for a bare number) of a bound's ``min`` or
    ``max``; a ValueError unless it is a finite number (SI, or with a unit)."""
    given = quantity(value)
    number = value if given is None else given.value
    try:
        finite = isinstance(number, (int, float, np.number)) and math.isfinite(number)
    except TypeError:
        finite = False
    if not finite or isinstance(number, bool):
        raise ValueError(
            f"a bound's {key} must be a finite number (SI, or with a unit such as "
            f'"0.5 deg"), got {value!r}'
        )
    if given is None:
        return float(number), None
    unit = CONVERSIONS[given.unit][0] if given.unit in CONVERSIONS else given.unit
    return float(to_si(given, unit)), unit


def at_most(value) -> Bound:
    """A metric's requirement: ≤ ``value`` (SI, or with a unit)."""
    return Bound(max=value)


def at_least(value) -> Bound:
    """A metric's requirement: ≥ ``value``."""
    return Bound(min=value)


def within(low, high) -> Bound:
    """A metric's requirement: in [``low``, ``high``]."""
    return Bound(min=low, max=high)


@dataclass(frozen=True)
class Pointing(Requirement):
    """An ECSS-E-ST-60-10C pointing requirement (:class:`..pointing.PointingRequirement`,
    docs/pointing.md) on a run's attitude: the performance error of ``attitude`` (q_BI)
    against ``reference`` (q_RI), or with ``kind="knowledge"`` the knowledge error of the
    estimate ``attitude`` against the truth ``reference``; over [``start``, ``stop``] (s).

    ``reference`` is a recorded quaternion (its base name), or a function of the recorded
    columns ``reference_signals`` that gives q_RI: ``reference(columns)`` with
    ``columns[name]`` an array (..., points), returning (..., points, 4) (a planned attitude
    that no component outputs, scan_pitch's).

    A temporal one is judged on each run (its own time).  An ensemble or mixed one is a
    statement about a campaign's runs together: in a run it is "judged over the campaign"
    and the run says what it shows (its estimate); :meth:`evaluate_campaign` judges it over
    every run's error history (met, not met or undecided at its confidence, or on the
    estimate where it states none)."""

    name: str  # type: ignore[misc]
    requirement: object
    attitude: str = "SatelliteDynamics.q_BI"
    reference: object = "StaringGuidance.q_ref"
    kind: str = "performance"
    start: float | None = None
    stop: float | None = None
    reference_signals: tuple = ()
    signals: tuple = field(init=False, default=())
    origin: str = field(default="", compare=False)  # "file:line" where it was written

    def __post_init__(self):
        if not self.origin:
            object.__setattr__(self, "origin", where_written())
        if self.kind not in ("performance", "knowledge"):
            raise ValueError(f"kind must be 'performance' or 'knowledge', got {self.kind!r}")
        if getattr(self.requirement, "bound", None) is None:
            raise ValueError(f"requirement {self.name}: the pointing requirement needs a bound")
        if callable(self.reference) == (not self.reference_signals):
            raise ValueError(
                "a reference function needs reference_signals (the columns it reads), "
                "a recorded reference quaternion none"
            )
        columns = quaternion_columns(self.attitude)
        columns += tuple(self.reference_signals) or quaternion_columns(self.reference)  # type: ignore[arg-type]
        object.__setattr__(self, "signals", columns)

    @property
    def over_campaign(self) -> bool:
        """An ensemble or mixed statistic: a campaign judges it over all its runs, not
        run by run (no pass rate)."""
        return self.requirement.interpretation != "temporal"  # type: ignore[attr-defined]

    def statement(self, unit=None, display_unit=None) -> str:
        r = self.requirement
        from ..pointing import format_angle

        return f"{r.label()} {r.probability()} ≤ {format_angle(r.bound)}"  # type: ignore[attr-defined]

    def error(self, columns, t: np.ndarray):
        """The error history over [start, stop] of the recorded ``columns``
        (:func:`..pointing.errors.recorded_error`)."""
        return recorded_error(
            columns, t, self.attitude, self.reference, self.kind, self.start, self.stop
        )

    def _verdict(self, columns, t, requirement=None, keep: dict | None = None) -> Verdict:
        from ..pointing import NotEvaluable

        try:
            error = self.error(columns, t)
        except NotEvaluable as reason:
            return Verdict(NOT_EVALUATED, None, str(reason))
        return self._judged(error, requirement, keep)

    def _run_error(self, results):
        """A run's error history, computed once per results (the run's other pointing
        requirements on the same error read it too)."""
        return _once(results, self._error_key(), lambda: self.error(results, results.time))

    def _error_key(self) -> tuple:
        return ("recorded_error", self.attitude, self.reference, self.kind, self.start, self.stop)

    def _run_verdict(self, results, requirement=None) -> Verdict:
        """The verdict on a run's ``results``."""
        from ..pointing import NotEvaluable

        try:
            error = self._run_error(results)
        except NotEvaluable as reason:
            return Verdict(NOT_EVALUATED, None, str(reason))
        return self._judged(error, requirement)

    def run_magnitudes(self, results) -> tuple[np.ndarray, np.ndarray]:
        """(t, m[1, time]): the index's magnitudes on a run's ``results``, computed once
        per results (what the run shows of a requirement judged over the campaign, and
        what the campaign's workers keep for the verdict over it,
        :mod:`..campaign.magnitudes`); :class:`..pointing.NotEvaluable` where the run
        cannot give them."""
        r = self.requirement
        index = repr((r.index, r.window, r.separation, r.t_in_window, r.axis, r.boresight))  # type: ignore[attr-defined]
        key = ("magnitudes", index, *self._error_key())
        return _once(results, key, lambda: r.magnitudes(self._run_error(results)))  # type: ignore[attr-defined]

    def _judged(self, error, requirement=None, keep: dict | None = None) -> Verdict:
        result = (requirement or self.requirement).evaluate(error, keep=keep)  # type: ignore[attr-defined]
        return self._as_verdict(result)

    @staticmethod
    def _as_verdict(result) -> Verdict:
        status = result.status if result.status in (MET, NOT_MET, UNDECIDED) else NOT_EVALUATED
        value = result.value if result.value is not None else result.estimate
        return Verdict(status, value, result.reason or "", result.line(), result.to_dict())

    def evaluate(self, results, metrics: dict) -> Verdict:
        if not self.over_campaign:
            return self._run_verdict(results)
        # what the run shows, for people: its estimate (no confidence: one run)
        from ..pointing import NotEvaluable, format_angle

        try:
            estimate = replace(self.requirement, confidence=None)  # type: ignore[type-var]
            shown = estimate.judge(*self.run_magnitudes(results))
            value = shown.value if shown.value is not None else shown.estimate
            reason = shown.reason
        except NotEvaluable as exc:
            value, reason = None, str(exc)
        seen = format_angle(value) if value is not None else reason
        text = f"{self.statement()}: {OVER_CAMPAIGN} (this run: {seen})"
        return Verdict(OVER_CAMPAIGN, value, OVER_CAMPAIGN_REASON, text)

    def evaluate_campaign(
        self, signals: np.ndarray, t: np.ndarray, keep: dict | None = None, stored=None
    ) -> Verdict:
        """Over every run: ``signals`` (runs, len(:attr:`signals`), points) holds
        :attr:`signals` (NaN where a run stopped early: those runs are left out, and said).
        ``keep``: given, it receives the index's magnitudes judged, ``keep["magnitudes"]``
        = (t, m[run, time]) of the runs that reached the end (none if not evaluated).
        ``stored``: given, a function of the boolean per run "reached the end" that
        gives those runs' m[run, time] as their workers computed them
        (:meth:`..campaign.magnitudes.Store.stacked`), or None: judged as they are where
        the first run's are what its signals give, else computed from ``signals``."""
        complete = reached_the_end(signals)
        if not complete.any():
            return Verdict(NOT_EVALUATED, None, "no run reached the end")
        kept = signals if complete.all() else signals[complete]  # all: no copy of a memory map
        columns = {c: kept[:, i] for i, c in enumerate(self.signals)}
        stacked = None if stored is None else stored(complete)
        if stacked is None:
            verdict = self._verdict(columns, t, keep=keep)
        else:
            verdict = self._stacked_verdict(columns, t, stacked, keep)
        left = int((~complete).sum())
        if left:
            note = f"{left} run(s) that stopped early left out"
            reason = "; ".join(filter(None, (verdict.reason, note)))
            return replace(verdict, reason=reason, text=f"{verdict.text} ({note})")
        return verdict

    def _stacked_verdict(self, columns, t, stacked: np.ndarray, keep: dict | None) -> Verdict:
        """The verdict on the runs' ``stacked`` magnitudes (:meth:`evaluate_campaign`), the
        times and the first run's row checked against its ``columns`` first."""
        from ..pointing import NotEvaluable

        try:
            times, first = self.requirement.magnitudes(self.error(_first(columns), t))  # type: ignore[attr-defined]
        except NotEvaluable as reason:
            return Verdict(NOT_EVALUATED, None, str(reason))
        if first.shape[1:] != stacked.shape[1:] or not np.array_equal(first[0], stacked[0]):
            return self._verdict(columns, t, keep=keep)
        if keep is not None:
            keep["magnitudes"] = (times, stacked)
        result = self.requirement.judge(times, stacked)  # type: ignore[attr-defined]
        return self._as_verdict(result)


def _once(results, key: tuple, compute):
    """``compute()``, kept on ``results`` under ``key`` where they are a Results."""
    return results.derived(key, compute) if isinstance(results, Results) else compute()


def _first(columns: dict) -> dict:
    """The first run's of ``columns`` {name: (runs, points)}, as (1, points) arrays."""
    return {c: np.asarray(v[:1]) for c, v in columns.items()}


def judged_over_campaign(requirement) -> bool:
    """Does a campaign judge ``requirement`` over all its runs (an ``evaluate_campaign``
    and, where it says, ``over_campaign``), not run by run?"""
    return hasattr(requirement, "evaluate_campaign") and getattr(requirement, "over_campaign", True)
