"""``agilesat campaign``: the command-line layer on :func:`run_campaign`.

Exit status: 0 every run met every requirement judged run by run and every requirement
judged over the campaign is met; 3 the campaign finished but some run failed, stopped or
missed a requirement, or a requirement judged over the campaign is not met (campaign.json
says which); 4 nothing of that, but a requirement judged over the campaign is undecided
(its runs show neither compliance nor a violation at its confidence: the verdict says
roughly how many runs would settle it; ``--until-decided`` makes them); 1 bad input; 130
interrupted by SIGINT, 143 by SIGTERM (``--resume`` continues).
"""

from __future__ import annotations

import json
import signal
from pathlib import Path

from ..campaign import Spec, engine, run_campaign, shipped_files
from ..campaign.report import display, group_pass_rates
from ..campaign.sequential import format_until_decided, run_until_decided
from ..cosim.options import RunOptions, add_flags, from_arguments
from ..error_estimate import sample, sample_lines
from . import CAMPAIGN_HELP, report


def add_parsers(commands, quiet) -> None:
    p = commands.add_parser(
        "campaign",
        help=CAMPAIGN_HELP,
        description="Run TARGET many times with dispersed parameters.  DIST: normal(mean,sd), "
        "uniform(lo,hi), choice(a,b,...), integers(lo,hi) (seeds), rotate(sd) (unit "
        "vectors), inertia(sd_rel,sd_angle) "
        "(3×3 inertia), linspace(lo,hi,n), values(a,b,...) (grids: full factorial); a "
        "leading + or * applies it to the nominal value; SI, 'deg' after a number for "
        "degrees.  Without --vary or --dispersions a scenario's shipped dispersions are used.",
        epilog="Exit status: 0 every requirement met (run by run, and over the campaign); "
        "3 a run failed or stopped, or a requirement is not met; 4 none of that, but a "
        "requirement judged over the campaign is undecided (its runs show neither compliance "
        "nor a violation at its confidence; the line says roughly how many runs would settle "
        "it: --until-decided makes them); 1 bad input; 130/143 interrupted (--resume "
        "continues).",
    )
    p.add_argument("target", help="scenario[:variant] or .ssd/.ssp file")
    add_flags(p, Spec)
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, help="local worker processes (default: cores)")
    where.add_argument(
        "--scheduler", metavar="ADDRESS", help="a running Dask scheduler, e.g. tcp://10.0.0.5:8786"
    )
    p.add_argument(
        "--listen",
        default="127.0.0.1",
        metavar="HOST",
        help="the interface the LocalCluster's scheduler and workers listen on "
        "(default 127.0.0.1: this machine only)",
    )
    p.add_argument(
        "--dashboard",
        metavar="HOST:PORT",
        help="serve Dask's dashboard of the LocalCluster there, e.g. 127.0.0.1:8787 "
        "(default: none)",
    )
    p.add_argument(
        "--until-decided",
        action="store_true",
        help="add runs in looks (--runs the first) until every requirement judged over the "
        "campaign is met or not met (anytime-valid verdicts: looking keeps their risks), "
        "or --max-runs",
    )
    p.add_argument(
        "--max-runs",
        type=int,
        metavar="N",
        help="with --until-decided, the most runs (default: 5 times the most any such "
        "requirement needs with none above its bound)",
    )
    p.add_argument(
        "--error-estimate",
        type=int,
        metavar="N",
        default=0,
        help="rerun the first N runs that succeeded at half and a quarter of the step and "
        "state each metric's numerical error (Richardson) and the runs a requirement is "
        "not decided by",
    )
    p.add_argument(
        "--group-by",
        action="append",
        default=[],
        metavar="INSTANCE.VAR[=EDGES]",
        help="pass rates per group of runs by a dispersed parameter: per value, or with "
        "EDGES 'a,b,c' per interval [a, b), [b, c) (a fault time: inf, 'never', is its own "
        "group); repeat for more",
    )
    p.add_argument("--out", type=Path, help="output directory (default out/campaign-TARGET)")
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue (or extend with a larger --runs) the campaign in --out",
    )
    report.add_option(p)
    p.add_argument(
        "-q",
        "--quiet",
        "--no-progress",
        dest="quiet",
        action="store_true",
        help="no progress bar or progress lines (--no-progress: the same)",
    )


def main(args) -> int:
    spec = from_arguments(Spec, args, target=args.target)
    if not spec.vary and not spec.files:
        try:
            spec.files = [str(path) for path in shipped_files(args.target)]
        except KeyError:
            raise ValueError(
                f"campaign {args.target}: nothing to vary: give --vary or --dispersions"
            ) from None
        print(f"dispersions: {', '.join(spec.files)} (the shipped campaign)")
    if args.max_runs is not None and not args.until_decided:
        raise ValueError("--max-runs is the most runs of --until-decided: give it too")
    groups = [_grouping(text) for text in args.group_by]  # before any run is made
    engine.INTERRUPTS.signals.clear()
    for signum in (signal.SIGINT, signal.SIGTERM):  # a batch system's stop: as Ctrl-C
        signal.signal(signum, engine.INTERRUPTS)

    def look(spec: Spec, resume: bool):
        return run_campaign(
            spec,
            args.out,
            resume,
            args.workers,
            args.scheduler,
            progress=not args.quiet,
            listen=args.listen,
            dashboard=args.dashboard,
        )

    try:
        if args.until_decided:
            result = run_until_decided(spec, args.max_runs, args.out, args.resume, look)
        else:
            result = look(spec, args.resume)
    except KeyboardInterrupt:
        # before the cluster started, or while the summary was written
        print(f"interrupted by {_first().name}: the runs made are in runs.jsonl; {RESUME}")
        return 128 + _first()
    if result.summary["status"] == "interrupted":
        runs = result.summary["runs"]
        print(
            f"interrupted by {_first().name}: {runs['made']} of {runs['planned']} runs kept in "
            f"{result.out_dir}/ (runs.csv, campaign.json); {RESUME}"
        )
        return 128 + _first()
    if args.error_estimate:
        _error_estimate(args, spec, result)
    if groups:
        _group(groups, result)
    report.after(args, result.out_dir)
    print(format_campaign(result.summary))
    if "until_decided" in result.summary:
        print(format_until_decided(result.summary))
    if args.error_estimate:
        print("\n".join(sample_lines(result.summary["numerical_error"])))
    print(f"results in {result.out_dir}/")
    if engine.INTERRUPTS.signals:  # as the cluster closed
        print(f"{_first().name} as the cluster closed: every run was made and written")
        return 128 + _first()
    return campaign_status(result.summary)


def campaign_status(summary: dict) -> int:
    """The exit status of a campaign's summary (module docstring)."""
    from .system import exit_status

    runs = summary["runs"]
    unmet = any(r["not_met"] for r in summary["pass_rates"].values())
    return exit_status(runs["planned"] != runs["ok"] or unmet, summary["ensemble"])


def _error_estimate(args, spec, result) -> None:
    """``--error-estimate N`` (orchestration/error_estimate.py), into campaign.json."""
    from ..output.recorder import write_text
    from ..runner import run

    journal = engine.read_journal(result.out_dir / "runs.jsonl")
    chosen = [r for _, r in sorted(journal.items()) if r["status"] == "ok"][: args.error_estimate]
    settings = result.summary["settings"]

    def rerun(values, step):
        again = RunOptions(
            step=step,
            stop=settings["stop"],
            algorithm=spec.algorithm,
            parameters={**spec.set, **values},
            figures=False,
        )
        return run(spec.target, again)[1]

    result.summary["numerical_error"] = sample(chosen, settings["step"], rerun)
    write_text(result.out_dir / "campaign.json", json.dumps(result.summary, indent=2) + "\n")


def _grouping(text: str) -> tuple[str, list[float]]:
    """``--group-by KEY[=EDGES]``: (KEY, the increasing edges)."""
    key, _, edges = text.partition("=")
    try:
        bounds = [float(x) for x in edges.split(",")] if edges.strip() else []
    except ValueError:
        raise ValueError(f"--group-by {text}: the edges are numbers, '10,27.5,40'") from None
    if not all(a < b for a, b in zip(bounds, bounds[1:])):
        raise ValueError(f"--group-by {text}: the edges must increase")
    return key.strip(), bounds


def _group(groups: list[tuple[str, list[float]]], result) -> None:
    """Each ``--group-by``'s pass rates per group of runs, into campaign.json."""
    from ..output.recorder import write_text

    metrics = {"requirements": result.summary.get("requirements", {})}
    result.summary["group_pass_rates"] = {
        key: group_pass_rates(result.table, metrics, key, edges) for key, edges in groups
    }
    write_text(result.out_dir / "campaign.json", json.dumps(result.summary, indent=2) + "\n")


RESUME = "the same command with --resume continues it"


def _first() -> signal.Signals:
    return signal.Signals((engine.INTERRUPTS.signals or [signal.SIGINT])[0])


#: the failed runs the campaign's report lists (campaign.json has the first 100)
SHOWN = 5


def format_campaign(summary: dict) -> str:
    runs = summary["runs"]
    lines = [
        f"runs: {runs['made']}/{runs['planned']} made: {runs['ok']} ok, "
        f"{runs['failed']} failed (diagnosed), {runs['error']} stopped, "
        f"{runs['lost']} lost with their workers"
    ]
    for lost in summary["lost_workers"]:
        held = lost["runs_in_flight"]
        lines.append(
            f"  worker {lost['worker']} died; Dask re-ran runs {held} elsewhere"
            if held
            # the watch samples the workers' runs once a second: a run just started is unseen
            else f"  worker {lost['worker']} left; no run of it was seen in flight (Dask "
            "re-runs any it held)"
        )
    warm = summary.get("warm_up")
    if warm and warm["processes"]:
        each = ", ".join(f"{w['seconds']:.2f}" for w in warm["workers"])
        lines.append(
            f"  workers' warm-up: {warm['seconds']:.1f} s in {warm['processes']} worker "
            f"process(es) ({each} s), {warm['cpu_seconds']:.1f} s CPU; not in the runs' seconds"
        )
        for w in warm["workers"]:
            if "error" in w:
                lines.append(f"  the warm-up of worker {w['worker']} raised: {w['error'][:200]}")
    lines.append(
        f"  {'metric':32s} {'mean':>11s} {'sd':>10s} {'1 %':>11s} {'median':>11s} "
        f"{'99 %':>11s}  unit"
    )
    for name, s in summary["statistics"].items():
        if s["count"]:
            scale, unit = display(s)
            p = s["percentiles"]
            lines.append(
                f"  {name:32s} {s['mean'] * scale:11.5g} {s['sd'] * scale:10.3g} "
                f"{p['1'] * scale:11.5g} {p['50'] * scale:11.5g} {p['99'] * scale:11.5g}"
                f"  {unit}"
            )
        if s.get("missing"):
            why = "; ".join(f"{k} ({n})" for k, n in s.get("reasons", {}).items())
            lines.append(
                f"  {name if not s['count'] else '':32s} {s['missing']} of "
                f"{s['count'] + s['missing']} runs without a value"
                + (f": {why}" if why else "")
                + (" (left out of the statistics)" if s["count"] else "")
            )
    statements = {n: r.get("statement", n) for n, r in summary.get("requirements", {}).items()}
    for name, r in summary["pass_rates"].items():
        low, high = r["ci95"]
        what = (
            "all requirements judged run by run"
            if name == "all"
            else f"requirement {statements.get(name, name)}"
        )
        others = ", ".join(
            f"{r[k]} {k.replace('_', ' ')}" for k in ("not_met", "not_evaluated", "stopped") if r[k]
        )
        lines.append(
            f"  {what}: met in {r['met']}/{r['runs']} runs, "
            f"{100 * r['rate']:.2f} % (95 % CI {100 * low:.2f}–{100 * high:.2f} %, "
            f"{r['method']})" + (f"; {others}" if others else "")
            if r["runs"]
            else f"  {what}: no runs"
        )
    for name, why in summary.get("not_judged", {}).items():
        lines.append(f"  requirement {statements.get(name, name)}: not judged ({why})")
    for name, r in summary.get("ensemble", {}).items():
        lines.append(
            f"  over the campaign: {name}: {r.get('text') or r['statement']}"
            + ("" if r.get("text") else f": {r['verdict']}")
            + (f" ({r['reason']})" if r.get("reason") and not r.get("text") else "")
        )
    for point in summary["grid_pass_rates"]:
        rates = point["pass_rates"]
        met = rates.get("all") or next(iter(rates.values()), None)
        if met:
            values = ", ".join(
                f"{k}={v:.6g}" if isinstance(v, float) else f"{k}={v}"
                for k, v in point["values"].items()
            )
            lines.append(f"  {values}: {met['met']}/{met['runs']} met")
    for key, groups in summary.get("group_pass_rates", {}).items():
        for group in groups:
            rates = group["pass_rates"]
            met = rates.get("all") or next(iter(rates.values()), None)
            if met and met["runs"]:
                low, high = met["ci95"]
                lines.append(
                    f"  runs with {key} {_grouped(group['group'])}: met in {met['met']}/"
                    f"{met['runs']}, {100 * met['rate']:.1f} % (95 % CI {100 * low:.1f}–"
                    f"{100 * high:.1f} %)"
                )
    for failure in summary["failures"][:SHOWN]:
        lines.append(f"  run {failure['index']} {failure['status']}: {failure['message'][:200]}")
    failed = runs["made"] - runs["ok"]
    if failed > SHOWN:
        lines.append(f"  and {failed - SHOWN} more (runs.csv: the status and message of every run)")
    if summary["failures"]:
        lines.append('  (campaign.json "failures" has the `agilesat run` command replaying each)')
    return "\n".join(lines)


def _grouped(label: str) -> str:
    """'= 15', 'in [10, 28)', '= inf (never)' for a group's label."""
    if label.startswith(("[", "<", ">")):
        return ("in " if label.startswith("[") else "") + label
    return f"= {label}" + (" (never)" if label == "inf" else "")


COMMANDS = {"campaign": main}
