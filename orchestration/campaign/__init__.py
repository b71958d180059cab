"""Monte Carlo campaigns and parameter sweeps on Dask.

    from agilesat.orchestration.campaign import campaign
    table = campaign("scan_pitch", runs=200, seed=1,
                     vary=["SatelliteDynamics.inertia=inertia(0.03, 1deg)"],
                     keep=["SatelliteDynamics.w_BO_B[2]"], out_dir="out/mc")
    table["imaging_pitch_rate_mean"], table["met_imaging_pitch_rate_mean"]

The dispersion language is in :mod:`.dispersion`, the spec and run indexing in :mod:`.plan`,
the campaign from spec to summary in :mod:`.driver`, the runs on Dask and the journal in
:mod:`.engine` (what a worker runs: :mod:`.worker`), campaign.json in :mod:`.summary` (its
nominal run :mod:`.nominal`, its replay commands :mod:`.replay`), statistics, pass rates and
figures in :mod:`.report`.
"""

from __future__ import annotations

from .driver import run_campaign
from .files import shipped, shipped_files
from .plan import Plan, Spec
from .replay import replay_arguments
from .summary import Campaign

__all__ = [
    "campaign",
    "Campaign",
    "Spec",
    "Plan",
    "run_campaign",
    "replay_arguments",
    "shipped",
    "shipped_files",
]


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
