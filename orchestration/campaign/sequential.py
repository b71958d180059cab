"""``agilesat campaign … --until-decided [--max-runs N]``: runs added in looks until every
requirement judged over the campaign is met or not met (docs/pointing.md).

Each look is the campaign extended to more runs (:func:`.run_campaign` with ``--resume``:
the runs made stay, the journal and ``signals.npy`` grow), then judged.  The verdicts are
anytime-valid (:mod:`..pointing.verdicts`): looking after every look, and choosing the next
look from what was seen, keeps their risks; so the next look is what the undecided
requirements would need if the runs to come were like those made
(:func:`..pointing.verdicts.next_look`), and the campaign stops when none is undecided or
at ``max_runs``.  ``campaign.json``'s ``until_decided`` says the looks, each one's verdicts,
how many runs it took and why it stopped; ``--resume`` continues from the look that was
being made.
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace
from pathlib import Path

from ..output.lock import holding
from ..output.recorder import write_text
from . import dispersion
from .files import read_object
from .plan import Spec, over_campaign

#: the most runs by default: this many times the most any requirement needs (none above)
DEFAULT_FACTOR = 5


def default_max_runs(requirements: list) -> int:
    """:data:`DEFAULT_FACTOR` times the most runs any of the requirements needs with none
    above its bound (those without a confidence need none)."""
    needed = [
        r.requirement.runs_needed() or 1
        for r in requirements
        if hasattr(getattr(r, "requirement", None), "runs_needed")
    ]
    return DEFAULT_FACTOR * max(needed or [1])


def run_until_decided(spec: Spec, max_runs: int | None, out_dir, resume: bool, run):
    """Looks of ``spec``'s campaign in ``out_dir`` until decided (module docstring);
    ``run(spec, resume)`` makes one look (:func:`.run_campaign` with the cluster's
    options) and returns its :class:`.Campaign`.  ``spec.runs`` is the first look."""
    from ..mission.targets import resolve

    found = resolve(spec.target)
    requirements = over_campaign(found.scenario, found.variant)
    if not requirements:
        raise ValueError(
            f"--until-decided: {spec.target} judges no requirement over the campaign (an "
            "ensemble or mixed statistic, docs/pointing.md): there is nothing to decide"
        )
    texts = list(spec.vary) + [d.text for f in spec.files for d in dispersion.load(f)[0]]
    grids = [t for t in texts if dispersion.parse(t).is_grid]
    if grids:
        raise ValueError(
            f"--until-decided: a sweep's runs are not one ensemble ({', '.join(grids)}): "
            "decide each grid point's campaign on its own"
        )
    max_runs = max_runs or default_max_runs(requirements)
    out = Path(out_dir or Path("out") / f"campaign-{spec.target.replace(':', '-')}")
    looks, runs = [], spec.runs
    if resume and (out / "campaign.json").exists():
        saved = read_object(out / "campaign.json", "a campaign's summary")
        looks = list(saved.get("until_decided", {}).get("looks", []))
        runs = max(runs, int(saved.get("spec", {}).get("runs", runs)))  # the look being made
    if runs > max_runs:
        raise ValueError(f"--until-decided: --runs {runs} is more than --max-runs {max_runs}")
    with holding(out):  # between the looks too: no other campaign takes the directory
        return _looks(spec, runs, looks, max_runs, out, resume, run)


def _looks(spec: Spec, runs: int, looks: list, max_runs: int, out: Path, resume: bool, run):
    """The looks of :func:`run_until_decided`, from one of ``runs`` on."""
    from ..pointing.verdicts import next_look

    while True:
        result = run(replace(spec, runs=runs, vary=list(spec.vary), set=dict(spec.set)), resume)
        resume = True  # the next looks extend it
        summary = result.summary
        if summary["status"] != "complete":  # interrupted: --resume continues this look
            return result
        verdicts = {n: e["verdict"] for n, e in summary["ensemble"].items()}
        undecided = {n: e for n, e in summary["ensemble"].items() if e["verdict"] == "undecided"}
        needed = [(e.get("details") or {}).get("runs_to_decide") for e in undecided.values()]
        if looks and looks[-1]["runs"] == runs:  # a resumed look, made again
            looks.pop()
        looks.append({"runs": runs, "verdicts": verdicts})
        stopped = None
        if not undecided:
            stopped = "every requirement judged over the campaign is decided"
        elif runs >= max_runs:
            stopped = f"--max-runs {max_runs} reached with {', '.join(undecided)} undecided"
        summary["until_decided"] = {
            "max_runs": max_runs,
            "runs": runs,
            "looks": looks,
            "stopped": stopped,
            "rule": "anytime-valid verdicts, looked at after each look (docs/pointing.md)",
        }
        write_text(out / "campaign.json", json.dumps(summary, indent=2) + "\n")
        if stopped:
            return result
        following = next_look(runs, needed, max_runs)
        said = ", ".join(
            f"{n} undecided" + (f" (about {k} runs would settle it)" if k else "")
            for n, k in zip(undecided, needed)
        )
        print(
            f"until decided: {runs} runs: {said}; the next look: {following} runs",
            file=sys.stderr,
            flush=True,
        )
        runs = following


def format_until_decided(summary: dict) -> str:
    """The printed line of a campaign run until decided, or nothing."""
    done = summary.get("until_decided")
    if not done:
        return ""
    looks = ", ".join(str(look["runs"]) for look in done["looks"])
    return (
        f"until decided: {done['runs']} runs in {len(done['looks'])} look(s) ({looks}): "
        f"{done['stopped']}"
    )
