"""The studies' commands: ``agilesat stare``, ``agilesat mission overlap|walker`` and
``agilesat size-flywheel``.  Nothing heavy is imported here (``agilesat --help`` reads the
parsers): each command imports what it uses."""

from __future__ import annotations

import dataclasses
import datetime
import json
import math
from pathlib import Path

from ..scenarios import constants

DEG = math.pi / 180


def add_parsers(commands, quiet) -> None:
    """Subcommands of the mission and sizing analyses (video_sar passes, payload_sweep's wheel)."""
    stare = commands.add_parser(
        "stare",
        parents=[quiet],
        help="video_sar over a pass of a "
        "real satellite (two-line elements) found for a ground target",
    )
    stare.add_argument(
        "--tle",
        type=Path,
        required=True,
        help="file holding the two-line element set (an optional name line first)",
    )
    stare.add_argument(
        "--target",
        nargs=2,
        type=float,
        metavar=("LAT", "LON"),
        default=(constants.VIDEO_SAR_TARGET_LAT / DEG, constants.VIDEO_SAR_TARGET_LON / DEG),
        help="geodetic target [deg] (default Sasebo)",
    )
    stare.add_argument(
        "--epoch",
        help="start of the search, ISO 8601 UTC: 2030-01-01T06:00:00, or a date alone for "
        "its 00:00 (default: the TLE's epoch)",
    )
    stare.add_argument("--hours", type=float, default=24.0, help="search window [h] (default 24)")
    stare.add_argument(
        "--look",
        type=float,
        help="wanted look angle [deg]: the pass closest to it (default: the first pass)",
    )
    stare.add_argument(
        "--max-look",
        type=float,
        default=60.0,
        help="largest look angle [deg] of a usable pass (default 60)",
    )
    stare.add_argument(
        "--no-yaw-compensation",
        action="store_true",
        help="yaw 0 (eq 11 only): the footprint turns on the ground",
    )
    stare.add_argument(
        "--out", type=Path, default=Path("out/stare"), help="output directory (default out/stare)"
    )

    analysis = commands.add_parser(
        "mission",
        help="video-SAR mission analysis ([Liang 2019]): "
        "frame overlap vs frame rate, Walker constellation size",
    )
    analysis.add_argument(
        "analysis",
        choices=("overlap", "walker"),
        help="overlap: frame overlap vs frame rate (eqs 1-5); walker: constellation size "
        "(eqs 14-20)",
    )
    analysis.add_argument(
        "--frame-rates",
        type=float,
        nargs="+",
        default=(5.0, 25.0),
        help="frame rates to tabulate [Hz] (default 5 25)",
    )
    analysis.add_argument(
        "--altitude",
        type=float,
        default=constants.VIDEO_SAR_ALTITUDE / 1e3,
        help=f"orbit altitude [km] (default {constants.VIDEO_SAR_ALTITUDE / 1e3:g})",
    )
    analysis.add_argument(
        "--angle",
        type=float,
        help="look angle [deg] (overlap, default "
        f"{constants.VIDEO_SAR_LOOK_ANGLE / DEG:g}) or largest angle β "
        f"(walker, default {constants.VIDEO_SAR_MAX_INCIDENCE / DEG:g})",
    )
    analysis.add_argument(
        "--out",
        type=Path,
        default=Path("out/mission"),
        help="directory of the figure (overlap) or the sizing in JSON (walker), each named "
        "by its altitude and angle (default out/mission)",
    )

    size = commands.add_parser(
        "size-flywheel",
        parents=[quiet],
        help="smallest reaction "
        "wheel that meets the payload_sweep pointing requirements "
        "(co-simulation sweep)",
    )
    size.add_argument(
        "--turnaround", type=float, default=1.0, help="payload reversal time [s] (default 1)"
    )
    size.add_argument(
        "--accuracy",
        type=float,
        default=constants.PAYLOAD_SWEEP_ACCURACY / DEG,
        help="pointing accuracy [deg] (default "
        f"{constants.PAYLOAD_SWEEP_ACCURACY / DEG:g}, the paper's)",
    )
    size.add_argument(
        "--stability",
        type=float,
        default=constants.PAYLOAD_SWEEP_STABILITY / DEG,
        help="pointing stability [deg/s] (default "
        f"{constants.PAYLOAD_SWEEP_STABILITY / DEG:g}, the paper's)",
    )
    size.add_argument("--step", type=float, default=0.05, help="macro step [s] (default 0.05)")
    size.add_argument("--stop", type=float, help="run length [s] (default: one pitch sweep)")
    size.add_argument(
        "--out",
        type=Path,
        default=Path("out/size-flywheel"),
        help="output directory (default out/size-flywheel)",
    )


def _stare(args) -> int:
    from ..output.progress import Progress
    from ..runner import run
    from ..studies.stare import pass_scenario, search_start, tle_pass
    from .system import echo_to, run_status

    lines = [line for line in args.tle.read_text().splitlines() if line.strip()]
    if len(lines) not in (2, 3):
        raise ValueError(
            f"{args.tle}: expected two TLE lines (and an optional name line), "
            f"found {len(lines)} lines"
        )
    for option, value, low, high in (
        ("--target LAT", args.target[0], -90.0, 90.0),
        ("--target LON", args.target[1], -360.0, 360.0),
        ("--max-look", args.max_look, 0.0, 90.0),
        ("--look", args.look, 0.0, 90.0),
    ):
        if value is not None and not low <= value <= high:
            raise ValueError(f"{option} must be in [{low:g}°, {high:g}°], got {value:g}°")
    start = search_start(*lines[-2:], args.epoch)
    orbit, chosen, passes = tle_pass(
        *lines[-2:],
        target=(args.target[0] * DEG, args.target[1] * DEG, 0.0),
        epoch=args.epoch,
        hours=args.hours,
        look_angle=None if args.look is None else args.look * DEG,
        max_look_angle=args.max_look * DEG,
    )
    print(f"passes over ({args.target[0]}°, {args.target[1]}°) with look ≤ {args.max_look}°:")
    for g in passes:
        when = start + datetime.timedelta(seconds=g.time)
        print(
            f"  {'→' if g is chosen else ' '} {when.isoformat(sep=' ', timespec='seconds')} UTC  "
            f"look {g.look_angle / DEG:6.2f}°"
            f"  range {g.slant_range / 1e3:7.1f} km  {g.side:5s}  "
            f"{'ascending' if g.ascending else 'descending'}"
        )
    print(f"stare: {orbit['epoch']} UTC + 200 s (zero Doppler at t = 100 s)")
    scenario = pass_scenario(orbit, args.out, not args.no_yaw_compensation)
    with Progress("stare", quiet=args.quiet) as progress:
        _, summary = run(
            scenario,
            out_dir=args.out,
            echo=echo_to(args.out, say=progress.write),
            progress=progress,
        )
    print(f"results in {args.out}/")
    return run_status(summary)


def _mission(args) -> int:
    """``agilesat mission overlap|walker``: the paper's case ([Liang 2019]) at the asked
    altitude and angle."""
    args.out.mkdir(parents=True, exist_ok=True)
    (_overlap if args.analysis == "overlap" else _walker)(args, args.altitude * 1e3)
    return 0


def _overlap(args, altitude: float) -> None:
    """Frame overlap (eqs 1-5) at the asked frame rates, and its figure over 1-30 Hz."""
    import numpy as np

    from ..output import plots
    from ..studies import mission_analysis as mission

    look = constants.VIDEO_SAR_LOOK_ANGLE if args.angle is None else args.angle * DEG
    # the paper's carrier, resolution and target latitude; altitude and look as asked
    case = dict(constants.VIDEO_SAR_OVERLAP, altitude=altitude, look_angle=look)
    table = mission.overlap_ratio(args.frame_rates, **case)
    print(
        f"frame overlap (eqs 1-5): h = {args.altitude:g} km, look {look / DEG:g}°, "
        f"slant range {table.slant_range / 1e3:.1f} km, V = {table.velocity:.1f} m/s "
        f"({table.velocity_model}), λ = {table.wavelength * 100:.3f} cm, "
        f"ρ_a = {table.resolution:g} m"
    )
    for rate, overlap in zip(table.frame_rate, table.overlap):
        print(
            f"  {rate:6.2f} Hz   overlap {100 * overlap:6.2f} %"
            + ("   (negative: the frames leave gaps)" if overlap < 0 else "")
        )
    rates = np.linspace(1.0, 30.0, 146)
    overlap = 100 * mission.overlap_ratio(rates, **case).overlap
    gap = mission.gap_frame_rate(rates[0], rates[-1], **case)
    title = "Frame overlap vs frame rate ([Liang 2019], Fig. 3)" + (
        f"\nh = {args.altitude:g} km, look {look / DEG:g}°"
        + (f"; below {gap:.3g} Hz the frames leave gaps" if gap is not None else "")
    )
    if gap is not None:
        print(f"  overlap 0 at {gap:.4g} Hz: below it the frames leave gaps")
    path = plots.lines(
        args.out / f"overlap_vs_frame_rate_h{args.altitude:g}km_look{look / DEG:g}deg.png",
        title,
        rates,
        {"overlap": np.where(overlap >= 0, overlap, np.nan)},
        "overlap [%]",
        xlabel="frame rate [Hz]",
        bottom=0.0,
    )
    print(f"figure: {path}")


def _walker(args, altitude: float) -> None:
    """Walker sizing (eqs 14-20) under both readings of the paper's β."""
    from ..studies import mission_analysis as mission

    beta = constants.VIDEO_SAR_MAX_INCIDENCE if args.angle is None else args.angle * DEG
    print(f"Walker sizing (eqs 14-20): h = {args.altitude:g} km, β = {beta / DEG:g}°")
    sizings = {}
    for kind, reading in (
        ("incidence", "β = incidence at the ground (eq 14, the paper's words)"),
        ("look", "β = look angle at the satellite"),
    ):
        w = sizings[kind] = mission.walker_sizing(altitude, beta, beta_kind=kind)
        print(
            f"  {reading}: α = {w.central_angle / DEG:.2f}°, T = {w.period / 3600:.3f} h, "
            f"T_v = {w.visibility_time / 60:.2f} min, S = {w.satellites_per_plane}, "
            f"P = {w.planes}, N = {w.satellites}"
        )
    path = args.out / f"walker_h{args.altitude:g}km_beta{beta / DEG:g}deg.json"
    text = {kind: dataclasses.asdict(w) for kind, w in sizings.items()}
    path.write_text(json.dumps(text, indent=2) + "\n", encoding="utf-8")
    print(f"sizing (SI, rad): {path}")


def _size_flywheel(args) -> int:
    from ..studies.sizing import size_flywheel

    print("wheel torque limit [N·m]   accuracy [deg]   stability [deg/s]   momentum [N·m·s]")
    result = size_flywheel(
        args.turnaround,
        args.accuracy * DEG,
        args.stability * DEG,
        args.step,
        args.stop,
        out_dir=args.out,
        progress=lambda p: print(
            f"{p.torque:24.4g} {p.accuracy / DEG:16.4g} "
            f"{p.stability / DEG:19.4g} {p.momentum:18.3g}"
            f"   {'meets' if p.met else 'fails'}"
        ),
    )
    if result.torque is None:
        print(
            f"no wheel up to {max(p.torque for p in result.points):g} N·m meets "
            f"{args.accuracy}° and {args.stability} °/s with {args.turnaround} s reversals"
        )
        return 3
    print(
        f"smallest wheel: {result.torque:.3g} N·m torque, using {result.momentum:.3g} N·m·s "
        f"(reversal {args.turnaround} s, step {args.step} s); {args.out / 'sizing.png'}"
    )
    return 0


#: `agilesat <command>` -> its function
COMMANDS = {"stare": _stare, "mission": _mission, "size-flywheel": _size_flywheel}
