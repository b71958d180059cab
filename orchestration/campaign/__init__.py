"""Monte Carlo campaigns and parameter sweeps on Dask.

    from agilesat.orchestration.campaign import campaign
    table = campaign("scan_pitch", runs=200, seed=1,
                     vary=["SatelliteDynamics.inertia=inertia(0.03, 1deg)"],
                     keep=["SatelliteDynamics.w_BO_B[2]"], out_dir="out/mc")
    table["imaging_pitch_rate_mean"], table["met_imaging_pitch_rate_mean"]

The dispersion language is in :mod:`.dispersion`, run indexing in :mod:`.plan`, execution
and files in :mod:`.engine`, statistics, pass rates and figures in :mod:`.report`.
"""

from __future__ import annotations

import collections
import json
import math
import platform
import shlex
import sys
from importlib import metadata
from pathlib import Path

import numpy as np

from ..output.lock import holding
from ..output.recorder import write_text
from . import dispersion, engine, isolated, report
from .files import CampaignFileError, read_object
from .plan import Plan, Spec, time_axis

SHIPPED_DIR = Path(__file__).resolve().parent / "shipped"
__all__ = ["campaign", "Campaign", "Spec", "Plan", "shipped", "replay_arguments"]


class Campaign:
    """What :func:`campaign` leaves: the table, the summary (``campaign.json``) and the
    output directory."""

    def __init__(self, table: np.ndarray, summary: dict, out_dir: Path):
        self.table, self.summary, self.out_dir = table, summary, out_dir

    def frame(self):
        """The table as a pandas DataFrame (pandas must be installed)."""
        import pandas

        return pandas.DataFrame.from_records(self.table)


def shipped(name: str) -> Path:
    """The shipped dispersion file of a scenario (``shipped/<name>.toml``)."""
    path = SHIPPED_DIR / f"{name}.toml"
    if not path.exists():
        raise KeyError(
            f"no shipped campaign {name!r}; shipped: "
            f"{', '.join(p.stem for p in sorted(SHIPPED_DIR.glob('*.toml')))}"
        )
    return path


def shipped_files(target: str) -> list[Path]:
    """The shipped dispersion files of a scenario[:variant]: the scenario's, then the
    variant's additions where it has some (``shipped/<name>.<variant>.toml``: the sensed
    variants' sensor noise)."""
    name, _, variant = target.partition(":")
    extra = SHIPPED_DIR / f"{name}.{variant}.toml"
    return [shipped(name), *([extra] if variant and extra.exists() else [])]


def campaign(
    target: str,
    runs: int = 1,
    *,
    seed: int = 0,
    vary=(),
    files=(),
    set=None,
    keep=(),
    step=None,
    stop=None,
    algorithm=None,
    out_dir=None,
    resume=False,
    workers=None,
    scheduler=None,
    progress=True,
    as_frame=None,
    until_decided: int | bool | None = None,
):
    """Run a campaign; returns the table (a NumPy structured array, or a pandas DataFrame
    when pandas is installed and ``as_frame`` is not False).  ``out_dir`` defaults to
    ``out/campaign-<target>``; everything is also written there (:mod:`.engine`).
    ``until_decided``: True, or the most runs, to add runs in looks (``runs`` the first)
    until every requirement judged over the campaign is decided (:mod:`.sequential`)."""
    spec = Spec(
        target,
        runs,
        seed,
        list(vary),
        [str(f) for f in files],
        dict(set or {}),
        list(keep),
        step,
        stop,
        algorithm,
    )

    def look(spec: Spec, resume: bool) -> Campaign:
        return run_campaign(spec, out_dir, resume, workers, scheduler, progress)

    if until_decided:
        from .sequential import run_until_decided

        most = None if until_decided is True else int(until_decided)
        result = run_until_decided(spec, most, out_dir, resume, look)
    else:
        result = look(spec, resume)
    if as_frame is False:
        return result.table
    try:
        return result.frame()
    except ImportError:
        if as_frame:
            raise
        return result.table


def run_campaign(
    spec: Spec,
    out_dir=None,
    resume=False,
    workers=None,
    scheduler=None,
    progress=True,
    *,
    listen: str = "127.0.0.1",
    dashboard: str | None = None,
) -> Campaign:
    """:func:`campaign` returning a :class:`Campaign` (table, summary, directory).
    ``listen``, ``dashboard``: of the LocalCluster (:func:`.engine.cluster`).  The campaign
    holds ``out_dir`` from before it writes anything to its end (:mod:`..output.lock`):
    another campaign or run on it, ``--resume`` included, is refused meanwhile."""
    for path in spec.files:
        loaded, fixed = dispersion.load(path)
        spec.vary += [d.text for d in loaded]
        spec.set = {**fixed, **spec.set}
    plan = Plan(spec)  # builds the FMUs the target needs: their content is recorded
    out = Path(out_dir or Path("out") / f"campaign-{spec.target.replace(':', '-')}")
    with holding(out):
        return _held(plan, out, resume, workers, scheduler, progress, listen, dashboard)


def _held(plan: Plan, out: Path, resume, workers, scheduler, progress, listen, dashboard):
    """:func:`run_campaign` in its directory, which it holds."""
    spec = plan.spec
    done = engine.open_directory(plan, out, resume)
    metrics: dict = {}
    if done and (out / "metrics.json").exists():
        metrics = read_object(out / "metrics.json", "an object of each metric's unit and text")
        if not all(isinstance(m, dict) for m in metrics.values()):
            raise CampaignFileError(f"{out / 'metrics.json'}: expected an object per metric")
    before = collections.Counter(str(r.get("status")) for r in done.values())
    if len(done) < plan.total:  # before the bar is drawn: not on its line
        print(
            f"campaign {spec.target}: {plan.total} runs ({spec.runs} × {len(plan.grid)} "
            f"grid points), {len(done)} already made in {out}",
            file=sys.stderr,
            flush=True,
        )
    bar = report.Progress(plan.total, len(done), enabled=bool(progress), before=before)
    environment = {"scheduler": scheduler or "LocalCluster", "workers": 0}
    lost, lost_scheduler = [], None
    try:
        with engine.cluster(workers, scheduler, listen, dashboard) as client:
            environment["workers"] = len(client.scheduler_info()["workers"])
            _, lost, _ = engine.execute(plan, out, client, done, bar, metrics)
    except KeyboardInterrupt:
        # Ctrl-C or SIGTERM outside the loop over the runs (``execute`` handles its own):
        # while the cluster starts or closes
        pass
    except engine.SchedulerLost as exc:
        lost_scheduler = exc
    except Exception:
        # a terminal's Ctrl-C reaches the worker processes Dask is starting too, which
        # then fail to start ("Nanny failed to start"): the signal stopped the campaign
        if not engine.INTERRUPTS.signals:
            raise
    finally:
        bar.close()
    # the summary is the journal's: a run written there just as a signal came is in it
    journal = engine.read_journal(out / "runs.jsonl")
    records = {i: r for i, r in journal.items() if i < plan.total}
    if len(journal) > len(records):
        print(
            f"campaign: {len(journal) - len(records)} runs made beyond --runs {spec.runs} are "
            "kept in runs.jsonl and signals.npy, not in this summary",
            file=sys.stderr,
        )
    status = "complete" if len(records) == plan.total else "interrupted"
    said = None if lost_scheduler is None else str(lost_scheduler)
    result = finish(plan, out, records, metrics, lost, status, environment, said)
    if lost_scheduler is not None:
        raise engine.SchedulerLost(
            f"{said}: {out / 'campaign.json'} says 'interrupted'; `--resume` continues it"
        )
    return result


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
    ``interruption``: what stopped the campaign, other than a signal."""
    table = report.table(plan, records, metrics)
    files = report.write_table(table, out)
    counts = {s: int(np.sum(table["status"] == s)) for s in report.STATUSES}
    previous = {}
    if (out / "campaign.json").exists():
        previous = read_object(out / "campaign.json", "a campaign's summary")
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
        "ensemble": _ensemble(plan, out, len(records)),
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
    histograms = plan.spec.runs > 1
    if histograms and len(plan.grid) == 1 and status == "complete":
        summary["nominal"] = nominal_run(plan, previous)
    write_text(out / "campaign.json", json.dumps(summary, indent=2) + "\n")
    nominal = summary.get("nominal", {}).get("metrics", {})
    figures = report.histograms(table, metrics, out, nominal) if histograms else []
    figures += report.sweeps(plan, table, metrics, out)
    if (out / "signals.npy").exists():  # none if no run was made
        from .pointing_figures import campaign_figures

        signals = np.load(out / "signals.npy", mmap_mode="r")[: plan.total]
        kept = signals[:, : len(plan.kept)]
        bounds = _bounds(plan)
        figures += report.envelopes(kept, plan.kept, plan.units, time_axis(plan), out, bounds)
        figures += campaign_figures(
            plan.ensemble, signals, plan.signals, time_axis(plan), summary["ensemble"], out
        )
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


def nominal_run(plan: Plan, before: dict | None = None) -> dict:
    """The run at the nominal values (every random dispersion at the system's value, the
    spec's ``--set`` and the grid point's values applied), whose metrics the histograms
    mark: {"command": the ``agilesat run`` that makes it, "metrics": {name: SI value}}, or
    the reason it has none (said on stderr too).  It runs in a process of its own
    (:mod:`.isolated`).  A signal during it is recorded for the
    command's exit status (130/143) as one while the cluster closes.

    ``before``: campaign.json as the campaign found it (a resumed one's).  Its nominal run
    is kept, not made again, when it has metrics, the same command and the same
    ``versions``: the run would be the same one (a resume has the same spec and system
    content, :func:`.engine.open_directory`); otherwise it is made again, and stderr says
    why."""
    from ..cosim.master import Interrupted

    spec = plan.spec
    grid = {
        name: value
        for name, value in plan.run_values(0).items()
        if any(name == key or name.startswith(key + "[") for key in plan.grid_keys)
    }
    parameters = {**spec.set, **grid}
    command = shlex.join(run_arguments(plan, parameters))
    held = (before or {}).get("nominal")
    if held:
        differs = _not_this_nominal_run(held, command, before.get("versions"))
        if not differs:
            print(
                f"campaign: the nominal run, for the histograms: {command} (kept: "
                "campaign.json has it, made with the same command and versions)",
                file=sys.stderr,
            )
            return {"command": command, "metrics": held["metrics"]}
        print(f"campaign: the nominal run in campaign.json {differs}: made again", file=sys.stderr)
    print(f"campaign: the nominal run, for the histograms: {command}", file=sys.stderr)
    try:  # in a process of its own: an FMU crashing there does not end the campaign
        summary = isolated.run(
            target=spec.target,
            step=spec.step,
            stop=spec.stop,
            algorithm=spec.algorithm,
            parameters=parameters,
            figures=False,
            build=False,
        )
    except (Exception, KeyboardInterrupt) as failure:  # the runs are made: not worth failing
        if isinstance(failure, Interrupted):
            engine.INTERRUPTS.signals.append(failure.signal)
        elif isinstance(failure, KeyboardInterrupt) and not engine.INTERRUPTS.signals:
            raise  # not a signal the campaign's handler took
        reason = f"{type(failure).__name__}: {failure}"
        print(f"campaign: no nominal run ({reason})", file=sys.stderr)
        return {"command": command, "reason": reason}
    values = {k: m["value"] for k, m in summary["metrics"].items() if m["value"] is not None}
    return {"command": command, "metrics": values}


def _not_this_nominal_run(held, command: str, made_with) -> str | None:
    """Why campaign.json's nominal run ``held``, made with the versions ``made_with``, is
    not the one ``command`` makes now, or None."""
    if not isinstance(held, dict) or not isinstance(held.get("metrics"), dict):
        reason = held.get("reason") if isinstance(held, dict) else None
        return "has no metrics" + (f" ({reason})" if reason else "")
    odd = [k for k, v in held["metrics"].items() if not _is_number(v)]
    if odd:
        return f"has metrics that are not numbers ({', '.join(map(str, odd))})"
    if held.get("command") != command:
        return f"was another command ({held.get('command')})"
    now, then = versions(), made_with if isinstance(made_with, dict) else {}
    changed = sorted(k for k in {*now, *then} if now.get(k) != then.get(k))
    return f"was made with other versions ({', '.join(changed)})" if changed else None


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _ensemble(plan: Plan, out: Path, made: int) -> dict:
    """The verdict of each requirement judged over the whole campaign (an ensemble or
    mixed statistic of every run, :mod:`..mission.requirements`)."""
    if not plan.ensemble or not made or not (out / "signals.npy").exists():
        return {}
    signals = np.load(out / "signals.npy", mmap_mode="r")
    result = {}
    for requirement in plan.ensemble:
        index = [plan.signals.index(c) for c in requirement.signals]
        verdict = requirement.evaluate_campaign(np.asarray(signals[:, index]), time_axis(plan))
        result[requirement.name] = ensemble_entry(requirement, verdict)
    return result


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


def replay_arguments(plan: Plan, index: int) -> list[str]:
    """``agilesat run`` arguments that make run ``index`` again, exactly."""
    return run_arguments(plan, plan.parameters(index))


def run_arguments(plan: Plan, parameters: dict) -> list[str]:
    """``agilesat run`` arguments of a run of the campaign's target and settings with
    ``parameters`` set."""
    args = ["agilesat", "run", plan.spec.target]
    for option, value in (
        ("--step", plan.spec.step),
        ("--stop", plan.spec.stop),
        ("--algorithm", plan.spec.algorithm),
    ):
        if value is not None:
            args += [option, repr(value) if isinstance(value, float) else str(value)]
    for key, value in parameters.items():
        args += ["--set", f"{key}={value!r}" if isinstance(value, float) else f"{key}={value}"]
    return args


def replay_template(plan: Plan) -> str:
    return (
        shlex.join(replay_arguments(plan, 0)[:3]) + " [--step/--stop/--algorithm as "
        "the spec] --set KEY=VALUE for every --set of the spec and every dispersed "
        "column of the run's row in runs.csv"
    )


def versions() -> dict:
    result = {"python": platform.python_version(), "platform": platform.platform()}
    for package in ("agilesat", "numpy", "fmpy", "pythonfmu", "dask", "distributed", "scipy"):
        try:
            result[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            result[package] = None
    return result
