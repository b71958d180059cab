"""What a campaign leaves at its end (and on an interruption): runs.csv (+ Parquet),
campaign.json and the figures (:func:`finish`), from the records so far; the table, the
summary and the directory as a :class:`Campaign`."""

from __future__ import annotations

import functools
import json
import shlex
from pathlib import Path

import numpy as np

from ..output.recorder import write_text
from . import report
from .files import read_object
from .magnitudes import Store
from .nominal import start as start_nominal
from .plan import Plan, time_axis
from .replay import replay_arguments, replay_template, versions


class Campaign:
    """What :func:`campaign` leaves: the table, the summary (``campaign.json``) and the
    output directory."""

    def __init__(self, table: np.ndarray, summary: dict, out_dir: Path):
        self.table, self.summary, self.out_dir = table, summary, out_dir

    def frame(self):
        """The table as a pandas DataFrame (pandas must be installed)."""
        import pandas

        return pandas.DataFrame.from_records(self.table)


def finish(
    plan: Plan,
    out: Path,
    records: dict,
    metrics: dict,
    lost: list,
    status: str,
    environment: dict,
    interruption: str | None = None,
) -> Campaign:
    """runs.csv (+ Parquet), campaign.json and the figures, from the records so far.
    ``metrics``: {"metrics": ..., "requirements": ...} (:func:`.engine.catalog`);
    ``interruption``: what stopped the campaign, other than a signal.  The nominal run the
    histograms mark goes on in its own process meanwhile (:mod:`.nominal`)."""
    previous = {}
    if (out / "campaign.json").exists():
        previous = read_object(out / "campaign.json", "a campaign's summary")
    histograms = plan.spec.runs > 1
    nominal = None
    if histograms and len(plan.grid) == 1 and status == "complete":
        nominal = start_nominal(plan, previous)
    try:
        return _finish(
            plan, out, records, metrics, lost, status, environment, interruption, previous, nominal
        )
    finally:
        if nominal is not None:
            nominal.cancel()


def _finish(
    plan, out, records, metrics, lost, status, environment, interruption, previous, nominal
):
    """:func:`finish` once the nominal run is started (None: no such run)."""
    table = report.table(plan, records, metrics)
    ensemble, magnitudes = _ensemble(plan, out, len(records))
    files = report.write_table(table, out)
    counts = {s: int(np.sum(table["status"] == s)) for s in report.STATUSES}
    summary = {
        "status": status,
        **({"interruption": interruption} if interruption else {}),
        "spec": plan.spec.to_dict(),
        "target": plan.target_record,
        "runs": {"planned": plan.total, "made": len(records), **counts},
        "grid": {"keys": plan.grid_keys, "points": len(plan.grid)},
        "system": str(plan.system.path),
        "system_sha256": previous.get("system_sha256"),
        "code_sha256": previous.get("code_sha256"),
        "settings": {
            "start": plan.start,
            "stop": plan.stop,
            "step": plan.step,
            "algorithm": plan.spec.algorithm or plan.system.algorithm,
        },
        "replay": replay_template(plan),
        "versions": versions(),
        "cluster": environment,
        "lost_workers": previous.get("lost_workers", []) + lost,
        # the looks of a campaign run until decided (:mod:`.sequential`), kept through each
        **({"until_decided": previous["until_decided"]} if "until_decided" in previous else {}),
        "warm_up": report.warm_ups(records),
        "requirements": metrics.get("requirements", {}),
        "statistics": report.statistics(table, metrics, records),
        "pass_rates": report.pass_rates(table, metrics),
        "not_judged": {
            name: r["not_judged"]
            for name, r in metrics.get("requirements", {}).items()
            if "not_judged" in r
        },
        "ensemble": ensemble,
        "grid_pass_rates": report.grid_pass_rates(plan, table, metrics),
        "failures": [
            {
                "index": int(r["index"]),
                "status": str(r["status"]),
                "message": str(r["message"]),
                "replay": shlex.join(replay_arguments(plan, int(r["index"]))),
            }
            for r in table[table["status"] != "ok"][:100]
        ],
        "kept": {
            "file": "signals.npy",
            "signals": plan.signals,
            "start": plan.start,
            "step": plan.step,
            "points": plan.points,
        }
        if plan.signals
        else None,
        "files": [p.name for p in files],
    }
    write_text(out / "campaign.json", json.dumps(summary, indent=2) + "\n")
    drawn = []  # the figures that do not mark the nominal run: while it goes on
    if (out / "signals.npy").exists():  # none if no run was made
        from .pointing_figures import campaign_figures

        signals = np.load(out / "signals.npy", mmap_mode="r")[: plan.total]
        kept = signals[:, : len(plan.kept)]
        bounds = _bounds(plan)
        drawn += report.envelopes(kept, plan.kept, plan.units, time_axis(plan), out, bounds)
        drawn += campaign_figures(
            plan.ensemble, signals, plan.signals, time_axis(plan), ensemble, out, magnitudes
        )
    histograms = plan.spec.runs > 1
    if nominal is not None:
        summary["nominal"] = nominal.result()
        write_text(out / "campaign.json", json.dumps(summary, indent=2) + "\n")
    marks = summary.get("nominal", {}).get("metrics", {})
    figures = report.histograms(table, metrics, out, marks) if histograms else []
    figures += report.sweeps(plan, table, metrics, out) + drawn
    summary["figures"] = [p.name for p in figures]
    write_text(out / "campaign.json", json.dumps(summary, indent=2) + "\n")
    return Campaign(table, summary, out)


def _bounds(plan: Plan) -> list:
    """The scenario's signal bounds the envelopes draw: not a limit whose parameter the
    campaign sets or disperses (the system's value would be the wrong line)."""
    if plan.scenario is None:
        return []
    changed = {key.partition("[")[0] for key in [*plan.spec.set, *plan.grid_keys]}
    changed |= {d.key.partition("[")[0] for d in plan.dispersions}
    return [b for b in plan.scenario.bounds_for(plan.variant) if b.parameter not in changed]


def _ensemble(plan: Plan, out: Path, made: int) -> tuple[dict, dict]:
    """The verdict of each requirement judged over the whole campaign (an ensemble or
    mixed statistic of every run, :mod:`..mission.requirements`), and of each that
    judged an index's magnitudes, those (t, m[run, time]), which its figure draws."""
    if not plan.ensemble or not made or not (out / "signals.npy").exists():
        return {}, {}
    signals = np.load(out / "signals.npy", mmap_mode="r")[: plan.total]  # not runs beyond
    store = Store(out, plan.ensemble, plan.total)
    result, magnitudes = {}, {}
    for requirement in plan.ensemble:
        index = [plan.signals.index(c) for c in requirement.signals]
        if index == list(range(index[0], index[0] + len(index))):
            columns = signals[:, index[0] : index[0] + len(index)]  # read block by block
        else:
            columns = np.asarray(signals[:, index])
        keep: dict = {}
        stacked = functools.partial(store.stacked, requirement.name)
        verdict = requirement.evaluate_campaign(columns, time_axis(plan), keep, stacked)
        result[requirement.name] = ensemble_entry(requirement, verdict)
        if "magnitudes" in keep:
            magnitudes[requirement.name] = keep["magnitudes"]
    return result, magnitudes


def ensemble_entry(requirement, verdict) -> dict:
    """campaign.json's record of ``requirement``'s :class:`..mission.requirements.Verdict`
    over the campaign (its ``ensemble``; the pointing figures draw from it)."""
    return {
        "statement": requirement.statement(),
        "verdict": verdict.status,
        "value": verdict.value,
        **({"reason": verdict.reason} if verdict.reason else {}),
        **({"text": verdict.text} if verdict.text else {}),
        **({"details": verdict.details} if verdict.details else {}),
    }
