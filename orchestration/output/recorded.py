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

from ..pointing import INDICES, PointingRequirement, PointingResult
from ..pointing.errors import recorded_error
from .kept_signals import reached_the_end
from .results import Results

#: the quaternions an index compares when none is named: (attitude, reference) by kind
DEFAULTS = {
    "knowledge": ("AttitudeEstimator.q_BI_est", "SatelliteDynamics.q_BI"),
    "performance": ("SatelliteDynamics.q_BI", None),
}


@dataclass(frozen=True)
class Recorded:
    """A source's ``columns`` ({name: array} or a Results), times ``t``, how many runs
    were ``left_out`` (stopped early), and the ``target`` it ran (None if unknown)."""

    columns: object
    t: np.ndarray
    runs: int
    left_out: int
    target: str | None


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
    """The recorded columns of a run or a campaign (see the module)."""
    if isinstance(source, Results):
        return Recorded(source, source.time, 1, 0, None)
    directory = Path(getattr(source, "out_dir", source))
    if (directory / "campaign.json").exists():
        return _campaign(directory)
    if (directory / "results.npz").exists() or (directory / "results.csv").exists():
        results = Results.load(directory)
        target = None
        if (directory / "summary.json").exists():
            summary = json.loads((directory / "summary.json").read_text())
            target = _target(summary.get("scenario"), summary.get("variant"))
        return Recorded(results, results.time, 1, 0, target)
    raise FileNotFoundError(
        f"{directory}: neither a run directory (results.npz or results.csv) nor a campaign "
        "directory (campaign.json)"
    )


def _target(scenario, variant) -> str | None:
    if not scenario:
        return None
    return f"{scenario}:{variant}" if variant else str(scenario)


def _campaign(directory: Path) -> Recorded:
    summary = json.loads((directory / "campaign.json").read_text())
    kept = summary.get("kept")
    if not kept or not (directory / "signals.npy").exists():
        raise FileNotFoundError(
            f"{directory}: the campaign kept no signals of its runs (signals.npy); run it "
            "again with --keep SatelliteDynamics.q_BI and the other quaternions the index needs"
        )
    signals = np.load(directory / "signals.npy", mmap_mode="r")[: summary["runs"]["planned"]]
    complete = reached_the_end(signals)
    if not complete.any():
        raise ValueError(f"{directory}: no run of the campaign reached the end")
    values = np.asarray(signals[complete])
    columns = {name: values[:, i] for i, name in enumerate(kept["signals"])}
    t = kept["start"] + kept["step"] * np.arange(kept["points"])
    left = int((~complete).sum())
    return Recorded(
        _Kept(columns, directory), t, int(complete.sum()), left, summary["spec"]["target"]
    )


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
    SatelliteDynamics.q_BI against a ``reference`` that must be named) over [start, stop]."""
    kind = INDICES[requirement.index][1]
    attitude = attitude or DEFAULTS[kind][0]
    reference = reference or DEFAULTS[kind][1]
    if reference is None:
        raise ValueError(
            f"{requirement.index} is a performance index: name the reference attitude "
            "(a recorded quaternion: StaringGuidance.q_ref, OrbitEnvironment.q_OI, ...)"
        )
    recorded = recorded or load(source)
    error = recorded_error(recorded.columns, recorded.t, attitude, reference, kind, start, stop)
    return requirement.evaluate(error)
