"""``agilesat``: build, validate and run the toolkit's FMUs and scenarios.

Exit status: 0 success; 1 bad input or a failed run (the message says what and where);
2 a usage error (unknown option, missing argument); 3 a scenario that ran but did not fly
as required (the summary's diagnostics say why); 130 interrupted by SIGINT (Ctrl-C)
or SIGTERM (everything recorded so far is kept).
"""

from __future__ import annotations

import argparse
import math
import sys
from importlib import metadata
from pathlib import Path

from .scenarios import NAMES, constants

DEG = math.pi / 180
#: `agilesat campaign`'s line in `agilesat --help` (the campaign package, Dask and the
#: master are imported only to run a campaign; a test checks it is the campaign's own)
CAMPAIGN_HELP = "Monte Carlo campaign or parameter sweep of a scenario on Dask"


def main(argv=None) -> int:
    """The command line.  Nothing heavy is imported here: each command imports what it
    uses (``agilesat --help`` and ``agilesat run --no-figures`` load no matplotlib)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    campaign = bool(argv) and argv[0] == "campaign"
    if campaign:
        from .campaign import cli as campaign_cli
    args = _parser(campaign).parse_args(argv)
    try:
        return {
            "list": _list,
            "info": _info,
            "build": _build,
            "validate": _validate,
            "run": _run,
            "plot": _plot,
            "export": _export,
            "stare": _stare,
            "mission": _mission,
            "size-flywheel": _size_flywheel,
            "generate": _generate,
            "campaign": campaign_cli.main if campaign else None,
        }[args.command](args)
    except KeyboardInterrupt as exc:
        print(f"agilesat {args.command}: {exc or 'interrupted'}", file=sys.stderr)
        return 130
    except (KeyError, ValueError, RuntimeError, OSError, ImportError) as exc:
        if _interrupted(exc):
            print(f"agilesat {args.command}: {exc}", file=sys.stderr)
            return 130
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"agilesat {args.command}: error: {message}", file=sys.stderr)
        return 1


def _interrupted(exc: BaseException) -> bool:
    """A run stopped by SIGINT/SIGTERM (master.Interrupted; only a command that imported
    the master can raise one)."""
    master = sys.modules.get(f"{__package__}.master")
    return master is not None and isinstance(exc, master.Interrupted)


def _parser(campaign: bool = True) -> argparse.ArgumentParser:
    """The command line: the options of every subcommand (each one's --help); without
    ``campaign``, `agilesat campaign` is only named (its options need the campaign
    package)."""
    doc = __doc__.split("\n\n")
    parser = argparse.ArgumentParser(
        prog="agilesat",
        description=doc[0],
        epilog=doc[1].strip(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--version", action="version", version=f"agilesat {metadata.version('agilesat')}"
    )
    quiet = argparse.ArgumentParser(add_help=False)
    quiet.add_argument(
        "-q", "--quiet", action="store_true", help="no progress bar or progress lines"
    )
    commands = parser.add_subparsers(dest="command", required=True)
    _system_commands(commands, quiet)
    _analysis_commands(commands, quiet)
    if campaign:
        from .campaign import cli as campaign_cli

        campaign_cli.add_parser(commands)
    else:
        commands.add_parser("campaign", help=CAMPAIGN_HELP)
    return parser


def _system_commands(commands, quiet) -> None:
    """Subcommands on FMUs, scenarios and system files, and the generated files."""
    commands.add_parser("list", help="the scenarios and their variants")
    info = commands.add_parser(
        "info",
        help="components, connections and every settable "
        "parameter of a scenario, system file or FMU",
    )
    info.add_argument("target", help="a scenario, an .ssd/.ssp file, an FMU name or .fmu file")

    build = commands.add_parser("build", parents=[quiet], help="build FMUs into fmus/build/")
    build.add_argument("names", nargs="*", help="FMU names (default: all)")
    build.add_argument("--out", type=Path, help="output directory (default fmus/build)")
    build.add_argument("--force", action="store_true", help="rebuild even if up to date")

    validate = commands.add_parser("validate", help="validate FMUs with fmpy's validator")
    validate.add_argument(
        "fmus", nargs="*", type=Path, help="FMU files (default: every FMU in fmus/build)"
    )

    run = commands.add_parser(
        "run", parents=[quiet], help="run a scenario[:variant] or an .ssd/.ssp file"
    )
    run.add_argument(
        "target", help=f"one of {', '.join(NAMES)} (optionally :variant) or a system file"
    )
    run.add_argument("--step", type=float, help="macro step [s]")
    run.add_argument("--stop", type=float, help="stop time [s]")
    run.add_argument("--algorithm", choices=("gauss-seidel", "jacobi"))
    run.add_argument(
        "--no-derivatives",
        action="store_true",
        help="do not couple through FMI input/output derivatives where no wire passes "
        "them (first-order coupling of those inputs)",
    )
    run.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="INSTANCE.VAR=VALUE",
        help="override a parameter: an element (A.inertia[2,2]=900) or a whole "
        "array (A.inertia=[[900,0,0],[0,900,0],[0,0,900]]); `agilesat info` "
        "lists them",
    )
    run.add_argument("--out", type=Path, help="output directory (default out/<target>)")
    run.add_argument("--no-figures", action="store_true")
    run.add_argument(
        "--svg",
        action="store_true",
        help="also write each figure as SVG (vector, for reports; ~25 %% more figure time)",
    )
    run.add_argument("--mat", action="store_true", help="also write results.mat (MATLAB)")

    plot = commands.add_parser("plot", help="plot recorded variables of one or more runs")
    plot.add_argument(
        "items",
        nargs="+",
        metavar="RESULTS_DIR... VARIABLE...",
        help="run directories (overlaid), then variables: a column "
        "(SatelliteDynamics.w_BI_B[2]) or a whole array (CmgCluster.delta)",
    )
    plot.add_argument("--deg", action="store_true", help="angles in degrees")
    plot.add_argument(
        "--out",
        type=Path,
        help="figure file (.png; an .svg is written beside it; default RESULTS_DIR/plot.png)",
    )

    export = commands.add_parser(
        "export", help="write a scenario[:variant] as a self-contained SSP package (.ssd + FMUs)"
    )
    export.add_argument("target", help=f"one of {', '.join(NAMES)} (optionally :variant)")
    export.add_argument("--out", type=Path, required=True, help="the .ssp file to write")

    generate = commands.add_parser(
        "generate",
        help="write the files generated from the "
        "variable tables and scenarios (.ssd, fmus/INTERFACES.md)",
    )
    generate.add_argument(
        "--check", action="store_true", help="only check that the committed files are up to date"
    )


def _analysis_commands(commands, quiet) -> None:
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
        "--epoch", help="start of the search, ISO 8601 UTC (default: the TLE's epoch)"
    )
    stare.add_argument("--hours", type=float, default=24.0, help="search window [h]")
    stare.add_argument(
        "--look",
        type=float,
        help="wanted look angle [deg]: the pass closest to it (default: the first pass)",
    )
    stare.add_argument(
        "--max-look", type=float, default=60.0, help="largest look angle [deg] of a usable pass"
    )
    stare.add_argument("--no-yaw-compensation", action="store_true")
    stare.add_argument("--out", type=Path, default=Path("out/stare"))

    analysis = commands.add_parser(
        "mission",
        help="video-SAR mission analysis ([Liang 2019]): "
        "frame overlap vs frame rate, Walker constellation size",
    )
    analysis.add_argument("analysis", choices=("overlap", "walker"))
    analysis.add_argument(
        "--frame-rates",
        type=float,
        nargs="+",
        default=(5.0, 25.0),
        help="frame rates to tabulate [Hz]",
    )
    analysis.add_argument(
        "--altitude", type=float, default=constants.VIDEO_SAR_ALTITUDE / 1e3, help="[km]"
    )
    analysis.add_argument(
        "--angle",
        type=float,
        help="look angle [deg] (overlap, default "
        f"{constants.VIDEO_SAR_LOOK_ANGLE / DEG:g}) or largest angle β "
        f"(walker, default {constants.VIDEO_SAR_MAX_INCIDENCE / DEG:g})",
    )
    analysis.add_argument("--out", type=Path, default=Path("out/mission"))

    size = commands.add_parser(
        "size-flywheel",
        parents=[quiet],
        help="smallest reaction "
        "wheel that meets the payload_sweep pointing requirements "
        "(co-simulation sweep)",
    )
    size.add_argument("--turnaround", type=float, default=1.0, help="payload reversal time [s]")
    size.add_argument(
        "--accuracy",
        type=float,
        default=constants.PAYLOAD_SWEEP_ACCURACY / DEG,
        help="pointing accuracy [deg]",
    )
    size.add_argument(
        "--stability",
        type=float,
        default=constants.PAYLOAD_SWEEP_STABILITY / DEG,
        help="pointing stability [deg/s]",
    )
    size.add_argument("--step", type=float, default=0.05, help="macro step [s]")
    size.add_argument("--stop", type=float, help="run length [s] (default: one pitch sweep)")
    size.add_argument("--out", type=Path, default=Path("out/size-flywheel"))


def _list(args) -> int:
    from .info import listing

    print(listing())
    return 0


def _info(args) -> int:
    from .info import info

    print(info(args.target))
    return 0


def _build(args) -> int:
    from ..fmus import FMUS
    from ..fmus.build import BUILD_DIR, build_fmu
    from .progress import Progress

    names = args.names or list(FMUS)
    built = []
    with Progress("build", unit="FMU", quiet=args.quiet) as progress:
        for k, name in enumerate(names):
            target = (args.out or BUILD_DIR) / f"{name}.fmu"
            before = target.stat().st_mtime_ns if target.exists() else None
            path = build_fmu(name, args.out or BUILD_DIR, force=args.force)
            if path.stat().st_mtime_ns != before:
                built.append(path)
            progress(k + 1, len(names))
    for path in built:
        print(path)
    if not built:
        print(
            f"all {len(names)} FMUs up to date in {args.out or BUILD_DIR} (nothing to do; "
            "--force rebuilds)"
        )
    return 0


def _validate(args) -> int:
    from fmpy.validation import validate_fmu

    from ..fmus.build import BUILD_DIR

    paths = args.fmus or sorted(BUILD_DIR.glob("*.fmu"))
    if not paths:
        print("no FMUs to validate: run `agilesat build` first", file=sys.stderr)
        return 1
    bad = 0
    for path in paths:
        problems = validate_fmu(str(path))
        print(f"{path}: {'OK' if not problems else f'{len(problems)} problem(s)'}")
        for problem in problems:
            print(f"  {problem}")
        bad += bool(problems)
    return 1 if bad else 0


def _run(args) -> int:
    from .figure_pool import processes_for_figures
    from .parameters import parse_set
    from .progress import Progress
    from .runner import run

    overrides = parse_set(args.set)
    out = args.out or Path("out") / args.target.replace(":", "-").replace("/", "_")
    with Progress(args.target, quiet=args.quiet) as progress:
        results, summary = run(
            args.target,
            step=args.step,
            stop=args.stop,
            algorithm=args.algorithm,
            parameters=overrides,
            out_dir=out,
            figures=not args.no_figures,
            svg=args.svg,
            echo=_echo(out),
            progress=progress,
            derivatives=not args.no_derivatives,
            figure_processes=processes_for_figures(),
        )
    if args.mat:
        results.to_mat(out / "results.mat")
    settings = summary["settings"]
    print(
        f"{args.target}: {len(results)} communication points, step {settings['step']} s, "
        f"{settings['algorithm']}; results in {out}/"
    )
    return _report(summary)


def _plot(args) -> int:
    from . import plots
    from .results import Results

    runs = [Path(item) for item in args.items if Path(item).is_dir()]
    variables = [item for item in args.items if not Path(item).is_dir()]
    if not runs or not variables:
        raise ValueError(
            "expected RESULTS_DIR... VARIABLE...: one or more run directories, "
            f"then the variables to plot (got directories {list(map(str, runs))}"
            f", variables {variables})"
        )
    loaded = {run.name or str(run): Results.load(run) for run in runs}
    for results in loaded.values():
        for name in variables:
            results.columns(name)  # a wrong name: did you mean ...
    out = args.out or runs[0] / "plot.png"
    if len(loaded) == 1:
        loaded = {"": next(iter(loaded.values()))}  # one run: label the lines by element
    path = plots.signals(out, loaded, variables, deg=args.deg)
    print("\n".join(str(p) for p in plots.formats(path)))
    return 0


def _report(summary) -> int:
    """Print the summary's numbers; the exit status of a run."""
    from .runner import format_summary

    print(format_summary(summary))
    return 3 if summary.get("status") == "failed" else 0


def _export(args) -> int:
    from .export import export_ssp

    print(export_ssp(args.target, args.out))
    return 0


def _stare(args) -> int:
    from .runner import run
    from .scenarios import video_sar

    lines = [line for line in args.tle.read_text().splitlines() if line.strip()]
    if len(lines) not in (2, 3):
        raise ValueError(
            f"{args.tle}: expected two TLE lines (and an optional name line), "
            f"found {len(lines)} lines"
        )
    orbit, chosen, passes = video_sar.tle_pass(
        *lines[-2:],
        target=(args.target[0] * DEG, args.target[1] * DEG, 0.0),
        epoch=args.epoch,
        hours=args.hours,
        look_angle=None if args.look is None else args.look * DEG,
        max_look_angle=args.max_look * DEG,
    )
    print(f"passes over ({args.target[0]}°, {args.target[1]}°) with look ≤ {args.max_look}°:")
    for g in passes:
        print(
            f"  {'→' if g is chosen else ' '} t = {g.time:10.1f} s  "
            f"look {g.look_angle / DEG:6.2f}°"
            f"  range {g.slant_range / 1e3:7.1f} km  {g.side:5s}  "
            f"{'ascending' if g.ascending else 'descending'}"
        )
    print(f"stare: {orbit['epoch']} UTC + 200 s (zero Doppler at t = 100 s)")
    scenario = video_sar.pass_scenario(orbit, args.out, not args.no_yaw_compensation)
    from .progress import Progress

    with Progress("stare", quiet=args.quiet) as progress:
        _, summary = run(scenario, out_dir=args.out, echo=_echo(args.out), progress=progress)
    print(f"results in {args.out}/")
    return _report(summary)


def _mission(args) -> int:
    """``agilesat mission overlap|walker``: the paper's case ([Liang 2019]) at the asked
    altitude and angle."""
    args.out.mkdir(parents=True, exist_ok=True)
    (_overlap if args.analysis == "overlap" else _walker)(args, args.altitude * 1e3)
    return 0


def _overlap(args, altitude: float) -> None:
    """Frame overlap (eqs 1-5) at the asked frame rates, and its figure over 1-30 Hz."""
    import numpy as np

    from ..components.analysis import mission
    from . import plots

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
    gaps = rates[overlap < 0]  # frames leave gaps: no overlap to plot
    title = "Frame overlap vs frame rate ([Liang 2019], Fig. 3)" + (
        f"\nbelow {gaps.max():.3g} Hz the frames leave gaps" if len(gaps) else ""
    )
    path = plots.lines(
        args.out / "overlap_vs_frame_rate.png",
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
    from ..components.analysis import mission

    beta = constants.VIDEO_SAR_MAX_INCIDENCE if args.angle is None else args.angle * DEG
    print(f"Walker sizing (eqs 14-20): h = {args.altitude:g} km, β = {beta / DEG:g}°")
    for kind, reading in (
        ("incidence", "β = incidence at the ground (eq 14, the paper's words)"),
        ("look", "β = look angle at the satellite"),
    ):
        w = mission.walker_sizing(altitude, beta, beta_kind=kind)
        print(
            f"  {reading}: α = {w.central_angle / DEG:.2f}°, T = {w.period / 3600:.3f} h, "
            f"T_v = {w.visibility_time / 60:.2f} min, S = {w.satellites_per_plane}, "
            f"P = {w.planes}, N = {w.satellites}"
        )


def _size_flywheel(args) -> int:
    from .sizing import size_flywheel

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


def _echo(out: Path, limit: int = 5):
    """Print an FMU's first warnings and errors; the rest go to log.txt only."""
    counts: dict[str, int] = {}

    def echo(entry):
        counts[entry.instance] = counts.get(entry.instance, 0) + 1
        if counts[entry.instance] <= limit:
            print(f"  FMU: {entry}", file=sys.stderr)
        elif counts[entry.instance] == limit + 1:
            print(f"  FMU: {entry.instance}: more messages in {out / 'log.txt'}", file=sys.stderr)

    return echo


def _generate(args) -> int:
    from ..fmus.build import generated_files
    from . import scenarios

    files = {scenarios.get(name).ssd: scenarios.get(name).render_ssd for name in NAMES}
    files.update(generated_files())
    stale = []
    for path, render in files.items():
        content = render()
        if args.check:
            if not path.exists() or path.read_bytes() != content:
                stale.append(str(path))
        else:
            path.write_bytes(content)
            print(path)
    if stale:
        print(f"out of date (run `agilesat generate`): {', '.join(stale)}", file=sys.stderr)
        return 1
    return 0
