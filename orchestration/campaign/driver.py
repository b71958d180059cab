"""A campaign from its spec to its summary: the dispersion files read, the plan made and
checked, the output directory opened (or resumed), the runs made on a Dask cluster
(:mod:`.engine`) and the summary written from the journal (:mod:`.summary`)."""

from __future__ import annotations

import collections
import sys
from pathlib import Path

from ..output.lock import holding
from . import dispersion, engine, report
from .files import CampaignFileError, read_object
from .plan import Plan, Spec
from .summary import Campaign, finish


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
