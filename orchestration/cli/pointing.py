"""``agilesat pointing DIR``: ECSS pointing indices of a recorded run or campaign.

With ``--index``, that index (the options of :class:`..pointing.PointingRequirement`);
without, the pointing requirements the run's or campaign's scenario states
(:class:`..mission.Pointing`; in a run, one judged over a campaign says so and what the run
shows).  Exit 0, 3 when a requirement is not met, 4 when none is but one is undecided
(neither compliance nor a violation shown at its confidence).
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

from ..pointing.names import ANGLE_UNITS, INDICES, INTERPRETATIONS

_ANGLE = re.compile(r"^\s*([-+]?[\d.]+(?:[eE][-+]?\d+)?)\s*([a-zµ]*)\s*$")


def angle(text: str) -> float:
    """``0.05deg``, ``3 arcsec``, ``1e-5`` (rad) in rad."""
    match = _ANGLE.match(text)
    unit = match.group(2) if match else ""
    if not match or unit and unit not in ANGLE_UNITS:
        raise ValueError(
            f"--bound {text!r}: expected a number with an angle unit "
            f"({', '.join(ANGLE_UNITS)}; none: rad), e.g. 0.05deg"
        )
    return float(match.group(1)) * ANGLE_UNITS[unit or "rad"]


def add_parsers(commands, quiet) -> None:
    p = commands.add_parser(
        "pointing",
        help="ECSS-E-ST-60-10C pointing indices (APE, RPE, ... AKE, RKE, ...) of a recorded "
        "run or campaign directory",
        description=__doc__.split("\n\n")[0] + "  See docs/pointing.md.",
        epilog="Exit status: 0 every requirement met (or computed, without --bound); 3 one "
        "not met; 4 none not met, but one undecided (its runs show neither compliance nor a "
        "violation at its confidence; the line says roughly how many runs would settle it); "
        "1 bad input.",
    )
    p.add_argument("directory", type=Path, help="a run's or a campaign's output directory")
    p.add_argument("--index", choices=list(INDICES), help="default: the scenario's requirements")
    p.add_argument("--window", type=float, help="Δt [s] (all but APE/AKE)")
    p.add_argument("--separation", type=float, help="Δt_s [s] (PDE/PRE/KDE/KRE)")
    p.add_argument(
        "--t-in-window",
        choices=("end", "random"),
        default="end",
        help="the time in the window the index is taken at (ECSS-E-ST-60-10C: end or random; "
        "default end)",
    )
    p.add_argument("--level", type=float, default=0.9973, help="probability (default 0.9973)")
    p.add_argument(
        "--interpretation",
        choices=INTERPRETATIONS,
        help="default: ensemble for a campaign, temporal for a run",
    )
    p.add_argument("--confidence", type=float, help="of the ensemble statistic (e.g. 0.95)")
    p.add_argument("--bound", type=angle, help="the requirement (0.05deg, 3arcsec; none: computed)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--axis", type=float, nargs=3, metavar=("X", "Y", "Z"), help="about it")
    where.add_argument(
        "--boresight", type=float, nargs=3, metavar=("X", "Y", "Z"), help="its half-cone"
    )
    p.add_argument(
        "--attitude",
        help="quaternion: default SatelliteDynamics.q_BI (performance), "
        "AttitudeEstimator.q_BI_est (knowledge)",
    )
    p.add_argument(
        "--reference",
        help="quaternion: the reference (performance; required), "
        "default SatelliteDynamics.q_BI (knowledge)",
    )
    p.add_argument("--start", type=float, help="[s] (default: the run's start)")
    p.add_argument("--stop", type=float, help="[s] (default: the run's planned stop)")
    p.add_argument(
        "--mission",
        metavar="PATH",
        help="the mission file (or scenario) to judge the requirements by, where the one "
        "the run was made of has moved or changed",
    )
    p.add_argument(
        "--unit", choices=list(ANGLE_UNITS), default="deg", help="of the printout (default deg)"
    )
    p.add_argument("--json", type=Path, help="also write the records to this file")
    p.add_argument(
        "--figure",
        type=Path,
        help="also draw each index's profile (per time: ensemble; per run: temporal) with "
        "its requirement into this .png",
    )


def main(args) -> int:
    from ..mission.requirements import Pointing
    from ..output.results import Results
    from ..pointing import NotEvaluable, PointingRequirement
    from ..postprocess.recorded import evaluate, load

    recorded = load(args.directory)
    what = f"{recorded.runs} run(s)" + (
        f", {recorded.left_out} that stopped early left out" if recorded.left_out else ""
    )
    short = recorded.shortfall()
    print(
        f"{args.directory}: {recorded.target or 'a run'}, {what}" + (f"; {short}" if short else "")
    )
    records, results = [], []
    if args.index:
        requirement = PointingRequirement(
            args.index,
            args.bound,
            args.level,
            args.interpretation or ("ensemble" if recorded.runs > 1 else "temporal"),
            args.window,
            args.separation,
            args.t_in_window,
            args.axis,
            args.boresight,
            args.confidence,
        )
        try:
            result = evaluate(
                None,
                requirement,
                attitude=args.attitude,
                reference=args.reference,
                start=args.start,
                stop=args.stop,
                recorded=recorded,
            )
        except NotEvaluable as reason:  # a window its records do not cover
            raise ValueError(f"{args.directory}: {reason}") from None
        print(f"  {result.line(args.unit)}")
        if INDICES[args.index][1] == "knowledge" and args.start is None:
            print(
                "  (over the whole record: the estimator's start-up included; --start T "
                "judges it after it, docs/sensing.md)"
            )
        records.append(result.to_dict())
        results.append((requirement.label(), result))
    else:
        if short:
            raise ValueError(
                f"{args.directory}: {short}: the requirements are stated over the whole run "
                "(--index with --start and --stop gives an index over what it recorded)"
            )
        target, note = recorded.find_target(args.directory, args.mission)
        if note:
            print(note, file=sys.stderr)
        if target is None or target.scenario is None:
            raise ValueError(f"{args.directory}: no scenario recorded: give --index ...")
        stated = [
            r for r in target.scenario.requirements_for(target.variant) if isinstance(r, Pointing)
        ]
        if not stated:
            raise ValueError(f"{recorded.target} states no pointing requirement: give --index")
        exempt = target.scenario.variant(target.variant).exempt()
        a_run = isinstance(recorded.columns, Results)
        for r in stated:
            if r.name in exempt:  # the variant does not judge it: as the run's summary
                print(f"  {r.name}: not judged ({exempt[r.name]})")
                continue
            if a_run and r.over_campaign:  # one verdict per scope: the campaign's
                verdict = r.evaluate(recorded.columns, {})
                print(f"  {r.name}: {verdict.text}")
                records.append({"name": r.name, "status": verdict.status, "text": verdict.text})
                continue
            try:
                error = r.error(recorded.columns, recorded.t)  # type: ignore[attr-defined]
            except NotEvaluable as reason:  # a window the run does not reach, as its summary
                print(f"  {r.name}: not evaluated ({reason})")
                records.append({"name": r.name, "status": "not evaluated", "met": None})
                continue
            result = r.requirement.evaluate(error)  # type: ignore[attr-defined]
            print(f"  {r.name}: {result.line(args.unit)}")
            records.append({"name": r.name, **result.to_dict()})
            results.append((r.name, result))
    if args.json:
        args.json.write_text(json.dumps(records, indent=2) + "\n")
    if args.figure:
        print(figure(args.figure, str(args.directory), results, args.unit))
    from .system import exit_status

    return exit_status(False, {str(i): {"verdict": r["status"]} for i, r in enumerate(records)})


def figure(path: Path, title: str, results: list, unit: str) -> Path:
    """One row per index with a profile: its value at the level against time (ensemble)
    or run (temporal), with the requirement; mixed statistics have none (left out)."""
    import numpy as np

    from ..output import plots

    scale, rows, axes = ANGLE_UNITS[unit], [], set()
    for name, result in results:
        stat = result.statistic
        if stat is None or stat.profile is None:
            continue
        per_time = stat.interpretation == "ensemble"
        axes.add("time [s]" if per_time else "run")
        x = result.t if per_time else np.arange(len(stat.profile))
        bound = result.requirement.bound
        marks = {} if bound is None else {"limit": ((bound / scale,), "requirement")}
        label = f"{name} at {100 * stat.level:g} %" + (
            " (estimate)" if result.value is None else ""
        )
        rows.append((x, {label: stat.profile / scale}, f"[{unit}]", marks))
    if not rows:
        raise ValueError("no index with a profile to draw (a mixed statistic has none)")
    return plots.panels(path, title, rows, xlabel=" or ".join(sorted(axes, reverse=True)))


COMMANDS = {"pointing": main}
