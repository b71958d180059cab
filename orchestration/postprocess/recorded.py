"""ECSS pointing indices of recorded runs and campaigns, after the fact (docs/pointing.md).

A *source* is a run (:class:`.results.Results`, or its directory: results.npz/.csv) or a
campaign (:class:`..campaign.Campaign`, or its directory: campaign.json and the signals
every run kept, signals.npy).  :func:`columns` gives its recorded columns as arrays,
(points,) for a run and (runs, points) for a campaign (the runs that reached the end; the
others are counted and said), which :func:`..pointing.errors.recorded_error` turns into an
error history; :func:`evaluate` judges a :class:`..pointing.PointingRequirement` on it.

``agilesat pointing DIR`` (:func:`main`) and ``assert_pointing`` (:mod:`.checks`) are
written on these.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..output.kept_signals import reached_the_end
from ..output.results import Results
from ..pointing import INDICES, PointingRequirement, PointingResult
from ..pointing.errors import not_covered, recorded_error

#: the quaternions an index compares when none is named: (attitude, reference) by kind
DEFAULTS = {
    "knowledge": ("AttitudeEstimator.q_BI_est", "SatelliteDynamics.q_BI"),
    "performance": ("SatelliteDynamics.q_BI", None),
}


@dataclass(frozen=True)
class Recorded:
    """A source's ``columns`` ({name: array} or a Results), times ``t``, how many runs
    were ``left_out`` (stopped early), the ``target`` it ran (None if unknown), the record
    of it (``made_of``, :meth:`..mission.targets.Target.record`; None in files written
    before there was one) and the times the run was to cover, ``span`` (start, stop;
    None if unknown): the records of a run that stopped early end before it."""

    columns: object
    t: np.ndarray
    runs: int
    left_out: int
    target: str | None
    made_of: dict | None = None
    span: tuple[float, float] | None = None

    def find_target(self, where, mission: str | None = None):
        """(The :class:`..mission.targets.Target` the records were made of, a note to
        print or ""), found from any folder (:func:`..mission.targets.found_again`;
        ``mission``: the target to judge them by instead); None if it has no scenario."""
        from ..mission.targets import TargetMoved, found_again, resolve

        if self.made_of is not None and (self.made_of.get("scenario") or mission):
            return found_again(self.made_of, where, mission)
        if mission is None and not self.target:
            return None, ""
        try:
            return resolve(mission or self.target), ""
        except KeyError as exc:  # written before the target was recorded whole
            raise TargetMoved(
                f"{where} names its target {self.target!r} only, which is not found from here"
                f" ({exc}): give --mission PATH, the mission file it was made of"
            ) from None

    def shortfall(self) -> str:
        """What the records do not cover of the run's span (it stopped early), or ""."""
        return "" if self.span is None else not_covered(self.t, *self.span, what="the run")


class _Kept(dict):
    """A campaign's kept columns; a missing one says what was kept and how to keep it."""

    def __init__(self, values: dict, where: Path):
        super().__init__(values)
        self.where = where

    def __missing__(self, name: str):
        base = name.partition("[")[0]
        raise KeyError(
            f"{self.where}: the campaign did not keep {name} (it kept "
            f"{', '.join(self) or 'nothing'}); run it again with --keep {base}"
        )


def load(source) -> Recorded:
    """The recorded columns of a run or a campaign (see the module).  A directory that
    is neither, or whose files are not what a run or a campaign writes, is a ValueError
    naming the file and what was expected."""
    if isinstance(source, Results):
        span = (source.meta["start"], source.meta["stop"]) if "stop" in source.meta else None
        return Recorded(source, source.time, 1, 0, None, None, span)
    directory = Path(getattr(source, "out_dir", source))
    if (directory / "campaign.json").exists():
        return _campaign(directory)
    if (directory / "results.npz").exists() or (directory / "results.csv").exists():
        results = Results.load(directory)
        summary = (
            _object(directory / "summary.json", "a run's summary")
            if (directory / "summary.json").exists()
            else {}
        )
        settings = summary.get("settings") or {}
        span = (settings["start"], settings["stop"]) if "stop" in settings else None
        target = _target(summary.get("scenario"), summary.get("variant"))
        return Recorded(results, results.time, 1, 0, target, summary.get("target"), span)
    raise FileNotFoundError(
        f"{directory}: neither a run directory of `agilesat run` (results.npz or results.csv) "
        "nor a campaign directory of `agilesat campaign` (campaign.json)"
    )


def _object(path: Path, what: str) -> dict:
    """The JSON object of one of our files; a ValueError naming it if it is not one."""
    try:
        value = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ValueError(f"{path}: not {what} of agilesat's ({exc})") from None
    if not isinstance(value, dict):
        raise ValueError(f"{path}: not {what} of agilesat's (a JSON {type(value).__name__})")
    return value


def _target(scenario, variant) -> str | None:
    if not scenario:
        return None
    return f"{scenario}:{variant}" if variant else str(scenario)


def _campaign(directory: Path) -> Recorded:
    summary = _object(directory / "campaign.json", "a campaign's summary")
    kept, runs = summary.get("kept"), summary.get("runs")
    fields = ("signals", "start", "step", "points")
    if not (_has(runs, ("planned",)) and (kept is None or _has(kept, fields))):
        raise ValueError(
            f"{directory / 'campaign.json'}: not a campaign's summary of agilesat's (expected "
            "'runs' with 'planned' and 'kept' with the signals, start, step and points)"
        )
    if not kept or not (directory / "signals.npy").exists():
        raise FileNotFoundError(
            f"{directory}: the campaign kept no signals of its runs (signals.npy); run it "
            "again with --keep SatelliteDynamics.q_BI and the other quaternions the index needs"
        )
    shape = (runs["planned"], len(kept["signals"]), kept["points"])
    try:
        signals = np.load(directory / "signals.npy", mmap_mode="r")
    except (OSError, ValueError) as exc:
        raise ValueError(f"{directory / 'signals.npy'}: not a whole signals file ({exc})") from None
    if signals.ndim != 3 or signals.shape[0] < shape[0] or signals.shape[1:] != shape[1:]:
        raise ValueError(
            f"{directory / 'signals.npy'}: holds {signals.shape}, not the (runs ≥ {shape[0]}, "
            f"signals, points) = {shape} campaign.json says it kept: cut, or another campaign's"
        )
    signals = signals[: shape[0]]
    complete = reached_the_end(signals)
    if not complete.any():
        raise ValueError(f"{directory}: no run of the campaign reached the end")
    values = np.asarray(signals[complete])
    columns = {name: values[:, i] for i, name in enumerate(kept["signals"])}
    t = kept["start"] + kept["step"] * np.arange(kept["points"])
    left = int((~complete).sum())
    made_of = summary.get("target") or {}
    return Recorded(
        _Kept(columns, directory),
        t,
        int(complete.sum()),
        left,
        _target(made_of.get("scenario"), made_of.get("variant"))
        or (summary.get("spec") or {}).get("target"),
        summary.get("target"),
        (float(t[0]), float(t[-1])),
    )


def _has(value, keys) -> bool:
    return isinstance(value, dict) and all(k in value for k in keys)


def evaluate(
    source,
    requirement: PointingRequirement,
    *,
    attitude: str | None = None,
    reference: str | None = None,
    start: float | None = None,
    stop: float | None = None,
    recorded: Recorded | None = None,
) -> PointingResult:
    """``requirement`` on the error of ``attitude`` against ``reference`` (recorded
    quaternions; by default, for a knowledge index the estimate AttitudeEstimator.q_BI_est
    against the truth SatelliteDynamics.q_BI, for a performance index the truth
    SatelliteDynamics.q_BI against a ``reference`` that must be named) over [start, stop]
    (default: what the run was to cover; a window its records do not cover is
    :class:`..pointing.NotEvaluable`)."""
    kind = INDICES[requirement.index][1]
    attitude = attitude or DEFAULTS[kind][0]
    reference = reference or DEFAULTS[kind][1]
    if reference is None:
        raise ValueError(
            f"{requirement.index} is a performance index: name the reference attitude "
            "(a recorded quaternion: StaringGuidance.q_ref, OrbitEnvironment.q_OI, ...)"
        )
    recorded = recorded or load(source)
    if recorded.span is not None:  # the window the run was to cover, not what it recorded
        start = recorded.span[0] if start is None else start
        stop = recorded.span[1] if stop is None else stop
    error = recorded_error(recorded.columns, recorded.t, attitude, reference, kind, start, stop)
    return requirement.evaluate(error)
