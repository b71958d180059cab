"""Metrics of a run: :class:`Metric`, and the ones an AOCS engineer reaches for.

A metric is a name, a function of the run's :class:`~agilesat.orchestration.Results`, its
unit (SI, as the model descriptions write it), the unit it is shown in, a description and,
optionally, a requirement (:func:`.requirements.at_most` ...) and a reference value
(``paper``: what a paper or a specification gives, shown beside it).  A value that does
not exist is *no value* (None, null in JSON), never a sentinel number: a metric raises
:class:`NotEvaluable` with the reason ("not settled", "the run ends before the window"),
and a campaign counts and says those runs instead of averaging a made-up number.

A signal is a recorded column or array by name (``"AttitudeController.att_error"``, its
unit from the run) or a function of the results returning an (N,) or (N, k) array (give
the metric's ``unit``, or set the function's ``unit`` attribute, as :func:`pointing_angle`
does).  Bounds and limits take a unit (``deg(0.01)``, ``"0.01 deg/s"``;
a plain number is SI).  ``start``/``stop`` select a window of the run (s).

Library (each returns a :class:`Metric`): :func:`settling_time`, :func:`max_abs`,
:func:`rms`, :func:`pointing_error` (:func:`pointing_angle` is its signal),
:func:`rate_error`, :func:`saturation_fraction`, :func:`momentum_margin`,
:func:`singularity_measure`, :func:`momentum_drift`, and :func:`minimum`, :func:`maximum`,
:func:`mean`, :func:`final_value`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..output.results import ColumnError, Results
from ..output.summary import format_value, relative_drift
from ..pointing.errors import not_covered, performance_error
from ..pointing.indices import NotEvaluable
from ..system.units import quantity, to_degrees, to_si
from .system import where_written

__all__ = [
    "Metric",
    "MetricValue",
    "NotEvaluable",
    "final_value",
    "max_abs",
    "maximum",
    "mean",
    "minimum",
    "momentum_drift",
    "momentum_margin",
    "pointing_angle",
    "pointing_error",
    "rate_error",
    "rms",
    "saturation_fraction",
    "settling_time",
    "singularity_measure",
]


@dataclass(frozen=True)
class MetricValue:
    """A metric of one run: ``value`` (SI; None: no value, ``reason`` says why;
    ``failed``: the metric raised, a mistake of its own, not a run without a value)."""

    value: float | None
    unit: str
    reason: str = ""
    failed: bool = False


@dataclass(frozen=True)
class Metric:
    """``compute(results)`` -> a number in ``unit`` (SI), or raises :class:`NotEvaluable`.
    ``unit`` None: the unit of the signal (set by the library's metrics); ``display_unit``
    the unit it is printed in (``deg`` for ``rad``); ``require`` a bound on it
    (:func:`.requirements.at_most`, :func:`~.requirements.within`, ...); ``paper`` a
    reference value (SI) shown beside it.  ``origin``: "file:line" where it was written
    (set from the caller: the messages about it name it)."""

    name: str
    compute: Callable
    unit: str | None = "1"
    display_unit: str | None = None
    description: str = ""
    require: object = None
    paper: float | None = None
    #: the recorded output it is computed from, if one (its unit is the metric's)
    signal: str | None = None
    origin: str = field(default="", compare=False)

    def __post_init__(self):
        if not self.name.isidentifier():
            raise ValueError(f"metric name {self.name!r} must be an identifier")
        if not self.origin:
            object.__setattr__(self, "origin", where_written())

    def evaluate(self, results, partial: bool = False) -> MetricValue:
        """The value on ``results`` (None with the reason when it cannot be had);
        ``partial``: the run recorded some outputs only, so a missing one makes the metric
        not evaluable.  A metric that raises anything else is not evaluated either, and
        ``failed``: the reason names the exception and where the metric was written."""
        try:
            value, unit = self.compute(results), self.unit
            if isinstance(value, tuple):  # the library's: (value, unit of the signal)
                value, unit = value
        except NotEvaluable as reason:
            return MetricValue(None, self.unit or "1", str(reason))
        except ColumnError as missing:
            if not partial:
                return MetricValue(None, self.unit or "1", self.raised(missing), True)
            return MetricValue(None, self.unit or "1", f"not recorded: {missing}")
        except Exception as exc:  # noqa: BLE001 - the metric's mistake: said, the run kept
            return MetricValue(None, self.unit or "1", self.raised(exc), True)
        unit = unit or "1"
        if value is None:
            return MetricValue(None, unit, "no value")
        value = float(value)
        if not math.isfinite(value):  # a value JSON cannot hold, nor a histogram
            why = "not a number" if math.isnan(value) else f"{value} (not a finite number)"
            return MetricValue(None, unit, why)
        return MetricValue(value, unit)

    def raised(self, exc: Exception) -> str:
        """The reason of a metric that raised ``exc``."""
        where = f" ({self.origin})" if self.origin else ""
        return f"metric {self.name}{where} raised {type(exc).__name__}: {exc}"


# -- signals ------------------------------------------------------------------------------


def _signal(results, signal, start=None, stop=None) -> tuple[np.ndarray, np.ndarray, str | None]:
    """(t, values (N, k), unit) of a signal over [start, stop]; :class:`NotEvaluable` if the
    run's records do not cover the window (to the nearest sample)."""
    t = results.time
    if callable(signal):  # its unit: its ``unit`` attribute, if it has one
        values, unit = np.asarray(signal(results), dtype=float), getattr(signal, "unit", None)
    else:
        values, unit = np.asarray(results[signal], dtype=float), results.unit(signal)
    values = values.reshape(len(t), -1)
    rows = np.ones(len(t), bool)
    if start is not None:
        rows &= t >= start - 1e-12
    if stop is not None:
        rows &= t <= stop + 1e-12
    gap = not_covered(t, start, stop)
    if gap:
        raise NotEvaluable(gap)
    if not rows.any():
        raise NotEvaluable(
            f"no sample in [{start if start is not None else t[0]:g}, "
            f"{stop if stop is not None else t[-1]:g}] s (the run covers "
            f"{t[0]:g} … {t[-1]:g} s)"
        )
    return t[rows], values[rows], unit


def _si(value, unit: str | None):
    """A bound or limit in SI: a plain number as it is, one with a unit converted."""
    given = quantity(value)
    return value if given is None else to_si(given, unit)


def _label(signal) -> str:
    return signal if isinstance(signal, str) else getattr(signal, "__name__", "signal")


def _base(signal) -> str:
    return _label(signal).split(".")[-1].split("[")[0]


def _metric(name, compute, unit, display_unit, description, require, paper, signal=None):
    return Metric(name, compute, unit, display_unit, description, require, paper, signal)


# -- the library --------------------------------------------------------------------------


def settling_time(
    signal,
    bound,
    *,
    after: float | None = None,
    norm: bool = False,
    name: str = "settling_time",
    display_unit: str | None = "s",
    description: str | None = None,
    require=None,
    paper: float | None = None,
) -> Metric:
    """The time from which the signal is within ``bound`` to the end of the run: every
    element, |x_i| ≤ bound (per axis, the default), or with ``norm`` the vector's
    Euclidean norm, ‖x‖ ≤ bound (a 3-axis rate or pointing error as one).  The first
    sample after the last one outside, or ``after`` (the run's start if None) when none is
    outside from then on.  No value ("not settled") when the last sample is outside; not
    evaluable when the run ends before ``after``."""
    label = f"‖{_label(signal)}‖" if norm else f"|{_label(signal)}|"

    def compute(results):
        t, x, unit = _signal(results, signal, after)
        limit = _si(bound, unit)
        size = np.linalg.norm(x, axis=1, keepdims=True) if norm else np.abs(x)
        outside = np.flatnonzero((size > limit).any(axis=1))
        if not len(outside):
            return (after if after is not None else float(t[0])), "s"
        if outside[-1] == len(t) - 1:
            shown = format_value(limit, unit, to_degrees(unit)[1])  # 0.01 °/s, not 1.745e-4
            raise NotEvaluable(
                f"not settled: {label} > {shown} at the end of the run (t = {t[-1]:g} s)"
            )
        return float(t[outside[-1] + 1]), "s"

    text = description or f"from then on {label} ≤ {bound}"
    return _metric(name, compute, "s", display_unit, text, require, paper)


def _statistic(function, what: str, signal, start, stop, norm: bool, name: str, options):
    """A metric of ``function`` of the signal over the window (its norm, if ``norm``);
    ``options``: the :class:`Metric`'s unit, display_unit, description, require, paper."""
    unit = options.get("unit")

    def compute(results):
        _, x, recorded = _signal(results, signal, start, stop)
        values = np.linalg.norm(x, axis=1) if norm else x
        return function(values), unit or recorded

    window = "" if start is None and stop is None else f" over [{start or 0:g}, {stop or '…'}] s"
    label = f"|{_label(signal)}|" if norm else _label(signal)
    return Metric(
        name,
        compute,
        unit,
        options.get("display_unit"),
        options.get("description") or f"{what} {label}{window}",
        options.get("require"),
        options.get("paper"),
        signal if isinstance(signal, str) and unit is None else None,
    )


def max_abs(signal, *, start=None, stop=None, norm=False, name=None, **options) -> Metric:
    """max |x| over the window: of every element, or (``norm``) of the vector's norm.
    ``options``: ``unit`` (of a function signal), ``display_unit``, ``description``,
    ``require``, ``paper`` (:class:`Metric`); so for the others."""
    name = name or f"max_abs_{_base(signal)}"
    return _statistic(
        lambda x: np.abs(x).max(), "max |·| of", signal, start, stop, norm, name, options
    )


def rms(signal, *, start=None, stop=None, norm=True, name=None, **options) -> Metric:
    """Root mean square over the window, of the vector's norm (``norm``, the default:
    √(mean |x|²)) or of every element."""
    name = name or f"rms_{_base(signal)}"
    return _statistic(
        lambda x: math.sqrt(np.mean(np.square(x))), "RMS of", signal, start, stop, norm, name,
        options,
    )  # fmt: skip


def minimum(signal, *, start=None, stop=None, name=None, **options) -> Metric:
    """The smallest value of any element over the window."""
    name = name or f"min_{_base(signal)}"
    return _statistic(np.min, "min of", signal, start, stop, False, name, options)


def maximum(signal, *, start=None, stop=None, name=None, **options) -> Metric:
    """The largest value of any element over the window."""
    name = name or f"max_{_base(signal)}"
    return _statistic(np.max, "max of", signal, start, stop, False, name, options)


def mean(signal, *, start=None, stop=None, name=None, **options) -> Metric:
    """The mean of a scalar signal over the window."""
    name = name or f"mean_{_base(signal)}"
    return _statistic(np.mean, "mean of", signal, start, stop, False, name, options)


def final_value(signal, *, name=None, **options) -> Metric:
    """The value of a scalar signal at the end of the run."""
    name = name or f"final_{_base(signal)}"
    return _statistic(lambda x: x[-1, 0], "final", signal, None, None, False, name, options)


def _quaternions(results, q) -> np.ndarray:
    """(N, 4) quaternions: a recorded array by name, or one constant quaternion."""
    if isinstance(q, str):
        return results.vector(q)
    return np.broadcast_to(np.asarray(q, dtype=float), (len(results), 4))


def _hashable(value):
    """A name or None as it is; numbers (a constant quaternion, a boresight) as a tuple."""
    if value is None or isinstance(value, str):
        return value
    return tuple(np.asarray(value, dtype=float).ravel().tolist())


def pointing_angle(
    attitude: str = "SatelliteDynamics.q_BI", reference="StaringGuidance.q_ref", *, boresight=None
) -> Callable:
    """A signal for the metrics and figures: the angle (rad, per sample) of the true
    attitude ``attitude`` from ``reference`` (a recorded quaternion or a constant one):
    with ``boresight`` (body axes) the half-cone angle between where it points and where it
    should, else the 3-axis rotation angle."""

    def computed(results) -> np.ndarray:
        error = performance_error(
            results.vector(attitude), _quaternions(results, reference), results.time
        )
        if boresight is not None:
            error = error.line_of_sight(boresight)
        return np.linalg.norm(error.values[0], axis=1)

    key = ("pointing_angle", attitude, _hashable(reference), _hashable(boresight))

    def angle(results) -> np.ndarray:  # once per results: every metric of it reads it
        if not isinstance(results, Results):
            return computed(results)
        return results.derived(key, lambda: computed(results))

    angle.__name__ = f"angle of {attitude} from {_label(reference)}"
    angle.unit = "rad"  # type: ignore[attr-defined]
    return angle


def pointing_error(
    attitude: str = "SatelliteDynamics.q_BI",
    reference="StaringGuidance.q_ref",
    *,
    boresight=None,
    statistic: str = "max",
    start=None,
    stop=None,
    name: str = "pointing_error",
    display_unit: str = "deg",
    description: str | None = None,
    require=None,
    paper=None,
) -> Metric:
    """The angle of the true attitude ``attitude`` (q_BI) from the ``reference`` (q_RI; a
    recorded quaternion or a constant one), its ``statistic`` ("max" or "rms") over the
    window: with ``boresight`` (body axes) the half-cone angle between where it points and
    where it should (the line-of-sight error), else the 3-axis rotation angle
    (:func:`..pointing.performance_error`)."""
    if statistic not in ("max", "rms"):
        raise ValueError(f"statistic must be 'max' or 'rms', got {statistic!r}")
    angle = pointing_angle(attitude, reference, boresight=boresight)

    def compute(results):
        _, x, _ = _signal(results, angle, start, stop)
        a = x[:, 0]
        return (a.max() if statistic == "max" else math.sqrt(np.mean(a * a))), "rad"

    what = f"half-cone angle of boresight {tuple(boresight)}" if boresight is not None else "angle"
    text = description or f"{statistic} {what} of {attitude} from {_label(reference)}"
    return _metric(name, compute, "rad", display_unit, text, require, paper)


def rate_error(
    rate: str = "SatelliteDynamics.w_BI_B",
    reference=None,
    *,
    statistic: str = "max",
    start=None,
    stop=None,
    name: str = "rate_error",
    display_unit: str = "deg/s",
    description: str | None = None,
    require=None,
    paper=None,
) -> Metric:
    """|rate − reference| (vector norm; the reference a recorded rate in the same axes, a
    constant vector, or None: zero), its ``statistic`` ("max" or "rms") over the window."""

    def difference(results):
        w = results.vector(rate)
        if reference is None:
            return w
        given = results.vector(reference) if isinstance(reference, str) else reference
        return w - np.asarray(_si(given, results.unit(rate)), dtype=float)

    function = np.max if statistic == "max" else (lambda a: math.sqrt(np.mean(a * a)))
    against = "" if reference is None else f" − {_label(reference)}"
    text = description or f"{statistic} |{rate}{against}|"
    options = dict(unit="rad/s", display_unit=display_unit, description=text)
    return _statistic(
        function,
        statistic,
        difference,
        start,
        stop,
        True,
        name,
        options | dict(require=require, paper=paper),
    )


def saturation_fraction(
    signal, limit=None, *, start=None, stop=None, name=None, description=None, require=None
) -> Metric:
    """The fraction of the window's samples with an actuator at its limit: a recorded
    Boolean flag (any element true), or |signal| ≥ ``limit`` (any element)."""

    def compute(results):
        _, x, unit = _signal(results, signal, start, stop)
        hit = x != 0 if limit is None else np.abs(x) >= _si(limit, unit)
        return float(hit.any(axis=1).mean()), "1"

    what = f"|{_label(signal)}| ≥ {limit}" if limit is not None else f"{_label(signal)} set"
    text = description or f"fraction of the time with {what}"
    return _metric(name or f"saturated_{_base(signal)}", compute, "1", "1", text, require, None)


def momentum_margin(
    h,
    capacity,
    *,
    start=None,
    stop=None,
    name: str = "momentum_margin",
    description: str | None = None,
    require=None,
) -> Metric:
    """min over the window of capacity − |h|: how far the devices' momentum ``h`` (a
    recorded 3-vector) stays inside their capacity (N·m·s, a number, or a function of the
    unit direction of h for a cluster whose envelope depends on it; samples with h = 0,
    which have no direction, are then left out).  Negative: beyond."""

    def compute(results):
        _, x, unit = _signal(results, h, start, stop)
        size = np.linalg.norm(x, axis=1)
        if callable(capacity):  # h = 0 has no direction: those samples are left out
            x, size = x[size > 0], size[size > 0]
            if not len(size):
                raise NotEvaluable(f"{_label(h)} is zero throughout: no direction")
            room = np.array([capacity(d) for d in x / size[:, None]])
        else:
            room = float(_si(capacity, unit))
        return float(np.min(room - size)), unit

    text = description or f"min (capacity − |{_label(h)}|)"
    signal = h if isinstance(h, str) else None
    return _metric(name, compute, None, None, text, require, None, signal)


def singularity_measure(
    signal: str = "CmgCluster.singularity",
    *,
    start=None,
    stop=None,
    name: str = "min_singularity",
    description: str = "min singularity measure det(A Aᵀ) of the cluster",
    require=None,
    paper=None,
) -> Metric:
    """The smallest singularity measure of a CMG cluster over the window (its recorded
    det(A Aᵀ), A the torque axes: 0 at a singular gimbal set)."""
    return minimum(
        signal,
        start=start,
        stop=stop,
        name=name,
        unit="1",
        display_unit="1",
        description=description,
        require=require,
        paper=paper,
    )


def momentum_drift(
    H="SatelliteDynamics.H_I",
    *,
    scale=None,
    name: str = "momentum_drift",
    description: str | None = None,
    require=None,
) -> Metric:
    """max |H(t) − H(0)| / max(|H(0)|, scale) of an inertial angular momentum (a recorded
    3-vector, or a function of the results): a conservation check where no external
    torque acts.  ``scale``: a function of the results giving the largest momentum a part
    carries, for a total that starts at zero."""

    def compute(results):
        _, x, _ = _signal(results, H)
        return relative_drift(x, scale(results) if scale else 0.0), "1"

    text = description or f"max |H(t) − H(0)| / |H(0)| of {_label(H)}"
    return _metric(name, compute, "1", "1", text, require, None)
