"""``agilesat``: build, validate and run the toolkit's FMUs and scenarios.

Exit status: 0 success; 1 bad input, a failed run, or a run whose metric, requirement
or figure raised (the message says what and where; the run's records are written);
2 a usage error (unknown option, missing argument); 3 a scenario that ran but did not fly
as required, a requirement not met (the summary's diagnostics say why); 4 nothing not
met, but a statistical requirement undecided: its runs show neither compliance nor a
violation at its confidence (campaign, pointing; the verdict says roughly how many runs
would settle it); 130 interrupted by SIGINT (Ctrl-C), 143 by SIGTERM (everything
recorded so far is kept, and the summary says what was not written; a second signal
changes nothing).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from contextlib import nullcontext
from pathlib import Path

from .cosim.signals import interruptible
from .provenance import version
from .studies import cli as study_cli

#: `agilesat campaign`'s line in `agilesat --help` (the campaign package, Dask and the
#: master are imported only to run a campaign; a test checks it is the campaign's own)
CAMPAIGN_HELP = "Monte Carlo campaign or parameter sweep of a scenario on Dask"
#: the --algorithm option of `run` and `campaign`
ALGORITHM = {
    "choices": ("gauss-seidel", "jacobi"),
    "help": "coupling algorithm (default the system's; gauss-seidel if it names none)",
}
#: what TARGET may be (``mission.targets``)
TARGETS = (
    "a scenario[:variant] (`agilesat list`), a mission file path/to/mission.py[:variant], "
    "a module of one, an .ssd/.ssp file, or an FMU (.fmu, or one of ours by name)"
)


def main(argv=None) -> int:
    """The command line.  Nothing heavy is imported here: each command imports what it
    uses (``agilesat --help`` and ``agilesat run --no-figures`` load no matplotlib)."""
    program = argv is None  # the process ends with the command
    try:
        return _main(sys.argv[1:] if program else list(argv), program)
    except KeyboardInterrupt:  # before a command took the signals (arguments, imports)
        print("agilesat: interrupted by SIGINT", file=sys.stderr)
        return 128 + signal.SIGINT
    finally:
        if program:
            # the exit status is decided: a signal while the process exits changes nothing
            # (Python's finalisation would restore the default handlers: killed by it)
            for signum in (signal.SIGINT, signal.SIGTERM):
                signal.signal(signum, signal.SIG_IGN)


def _main(argv: list, program: bool) -> int:
    campaign = bool(argv) and argv[0] == "campaign"
    if campaign:
        from .campaign import cli as campaign_cli
    args = _parser(campaign).parse_args(argv)
    # a signal stops a command at once until a run writes, then is a flag (signals.py);
    # a campaign handles its own (campaign/cli.py)
    with nullcontext() if campaign else interruptible(restore=not program) as signals:
        try:
            code = {
                "list": _list,
                "info": _info,
                "build": _build,
                "validate": _validate,
                "run": _run,
                "plot": _plot,
                "export": _export,
                "generate": _generate,
                **study_cli.COMMANDS,
                "pointing": _pointing,
                "report": _report,
                "export-ephemeris": _export_ephemeris,
                "campaign": campaign_cli.main if campaign else None,
            }[args.command](args)
        except KeyboardInterrupt as exc:
            print(f"agilesat {args.command}: {exc or 'interrupted'}", file=sys.stderr)
            return 128 + getattr(exc, "signal", signal.SIGINT)
        except UsageError as exc:
            print(f"agilesat {args.command}: error: {exc}", file=sys.stderr)
            return 2
        except (KeyError, ValueError, RuntimeError, OSError, ImportError) as exc:
            if _interrupted(exc):
                print(f"agilesat {args.command}: {exc}", file=sys.stderr)
                return 128 + exc.signal
            message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
            if isinstance(exc, OSError) and exc.filename and exc.strerror:  # not [Errno 30]
                message = f"{exc.filename}: {exc.strerror}"
            print(f"agilesat {args.command}: error: {message}", file=sys.stderr)
            return 1
        if signals is not None and signals.signal is not None:  # at the very end
            name = signal.Signals(signals.signal).name
            print(
                f"agilesat {args.command}: {name} at the end: everything was written",
                file=sys.stderr,
            )
            return 128 + signals.signal
        return code


class UsageError(ValueError):
    """A command line argparse cannot judge wrong (exit 2, as argparse's own)."""


def _interrupted(exc: BaseException) -> bool:
    """A run stopped by SIGINT/SIGTERM (master.Interrupted; only a command that imported
    the master can raise one)."""
    master = sys.modules.get(f"{__package__}.cosim.master")
    return master is not None and isinstance(exc, master.Interrupted)


def _parser(campaign: bool = True) -> argparse.ArgumentParser:
    """The command line: the options of every subcommand (each one's --help); without
    ``campaign``, `agilesat campaign` is only named (its options need the campaign
    package)."""
    doc = __doc__.split("\n\n")
    parser = argparse.ArgumentParser(
        prog="agilesat",
        description=doc[0].replace("``", ""),
        epilog=doc[1].strip(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=version())
    quiet = argparse.ArgumentParser(add_help=False)
    quiet.add_argument(
        "-q", "--quiet", action="store_true", help="no progress bar or progress lines"
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    _system_commands(commands, quiet)
    study_cli.add_parsers(commands, quiet)
    from .output import ephemeris_cli, recorded_cli
    from .output.report import cli as report_cli

    recorded_cli.add_parser(commands)
    report_cli.add_parser(commands)
    ephemeris_cli.add_parser(commands)
    if campaign:
        from .campaign import cli as campaign_cli

        campaign_cli.add_parser(commands)
    else:
        commands.add_parser("campaign", help=CAMPAIGN_HELP)
    listed = {c.dest: c.help for c in commands._choices_actions}
    for name, command in commands.choices.items():  # each command's --help says what it does
        command.description = command.description or listed.get(name)
    return parser


def _system_commands(commands, quiet) -> None:
    """Subcommands on FMUs, scenarios and system files, and the generated files."""
    commands.add_parser("list", help="the scenarios and their variants")
    info = commands.add_parser(
        "info",
        help="components, connections and every settable "
        "parameter of a scenario, system file or FMU",
    )
    info.add_argument("target", help=TARGETS)

    build = commands.add_parser(
        "build",
        parents=[quiet],
        help="build FMUs into fmus/build/, or a model file of your own into its build/",
    )
    build.add_argument(
        "names",
        nargs="*",
        help="FMU names (default: all), or model files path/to/model.py[:Class] "
        "(built into build/ beside each, validated)",
    )
    build.add_argument(
        "--out", type=Path, help="output directory (default fmus/build, or build/ beside a model)"
    )
    build.add_argument("--force", action="store_true", help="rebuild even if up to date")

    validate = commands.add_parser("validate", help="validate FMUs with fmpy's validator")
    validate.add_argument(
        "fmus",
        nargs="*",
        help="FMU files, or our FMUs by name (built if stale; default: every FMU in fmus/build)",
    )

    run = commands.add_parser(
        "run", parents=[quiet], help="run a scenario[:variant], a mission file, a system or an FMU"
    )
    run.add_argument("target", help=TARGETS)
    run.add_argument("--step", type=float, help="macro step [s]")
    run.add_argument("--stop", type=float, help="stop time [s]")
    run.add_argument("--start", type=float, help="start time [s] (default the system's)")
    run.add_argument("--algorithm", **ALGORITHM)
    run.add_argument(
        "--output-interval",
        type=float,
        metavar="SECONDS",
        help="record every SECONDS (a multiple of the step; default every step)",
    )
    run.add_argument(
        "--record",
        action="extend",
        nargs="+",
        default=None,
        metavar="VAR",
        help="record only these outputs: columns, whole arrays by base name, or patterns "
        "(SatelliteDynamics.*); default all",
    )
    run.add_argument(
        "--error-estimate",
        action="store_true",
        help="rerun at half and a quarter of the step and state each metric's numerical "
        "error (Richardson, observed order) and the requirements it leaves undecided",
    )
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
        "array (A.inertia=[[900,0,0],[0,900,0],[0,0,900]]); with a unit where it converts "
        "(A.attitude0[2]='100 deg'); `agilesat info` lists them",
    )
    run.add_argument("--out", type=Path, help="output directory (default out/<target>)")
    run.add_argument("--no-figures", action="store_true", help="draw no figures")
    run.add_argument(
        "--svg",
        action="store_true",
        help="also write each figure as SVG (vector, for reports; ~25 %% more figure time)",
    )
    run.add_argument("--mat", action="store_true", help="also write results.mat (MATLAB)")
    from .output.report import cli as report_cli

    report_cli.add_option(run)

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
        "export",
        help="write a scenario[:variant], a mission file or a system file as a "
        "self-contained SSP package (.ssd + FMUs), a system file or one configured FMU",
    )
    export.add_argument("target", help=TARGETS)
    export.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="INSTANCE.VAR=VALUE",
        help="a parameter value written into the package (as `run --set`)",
    )
    export.add_argument(
        "--out",
        type=Path,
        required=True,
        help="the file to write: an .ssp package, an .ssd (its FMUs in OUT_STEM.fmus/ beside "
        "it), or one component's .fmu (with --component)",
    )
    export.add_argument(
        "--accuracy",
        metavar="ANGLE",
        help="choose the package's step (halving it) so that hosts holding the inputs over "
        "a step (libcosim, ECOS) stay within ANGLE of our master on the attitude, e.g. 0.05deg",
    )
    export.add_argument(
        "--component",
        metavar="NAME",
        help="write only this component's FMU, configured with the system's values and step",
    )

    generate = commands.add_parser(
        "generate",  # a developer's command: not in `agilesat --help`
        description="(for developers of agilesat, in a source checkout) write the files "
        "generated from the variable tables and scenarios (.ssd, fmus/INTERFACES.md)",
    )
    generate.add_argument(
        "--check", action="store_true", help="only check that the committed files are up to date"
    )


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
    from ..fmus.build import BUILD_DIR

    models = [n for n in args.names if n.endswith(".py") or ".py:" in n]
    try:
        if models:
            return _build_models(models, args)
        return _build_fmus(args.names or list(FMUS), args.out or BUILD_DIR, args)
    except OSError as exc:  # a read-only or full --out: say where, not a scratch file's name
        where = args.out or ("build/ beside each model" if models else BUILD_DIR)
        raise OSError(
            f"the FMUs cannot be written into {where}: {exc.strerror or exc}"
            + (f" ({exc.filename})" if exc.filename else "")
        ) from None


def _build_fmus(names: list[str], out: Path, args) -> int:
    from ..fmus.build import build_fmu
    from .output.progress import Progress

    built = []
    with Progress("build", unit="FMU", quiet=args.quiet) as progress:
        for k, name in enumerate(names):
            target = out / f"{name}.fmu"
            before = target.stat().st_mtime_ns if target.exists() else None
            path = build_fmu(name, out, force=args.force)
            if path.stat().st_mtime_ns != before:
                built.append(path)
            progress(k + 1, len(names))
    for path in built:
        print(path)
    if not built:
        print(f"all {len(names)} FMUs up to date in {out} (nothing to do; --force rebuilds)")
    return 0


def _build_models(models: list[str], args) -> int:
    """``agilesat build path/to/model.py[:Class] ...``: each model file's classes as FMUs,
    validated (:mod:`..fmus.user_models`)."""
    from ..fmus.user_models import build_model

    others = [n for n in args.names if n not in models]
    if others:
        raise ValueError(f"build either FMU names or model files, not both (got {others})")
    for model in models:
        path, _, cls = model.rpartition(":") if ".py:" in model else (model, "", "")
        for built in build_model(path or model, cls or None, args.out, args.force):
            print(f"{built} (validated)")
    return 0


def _validate(args) -> int:
    from fmpy.validation import validate_fmu

    from ..fmus import FMUS
    from ..fmus.build import BUILD_DIR, build_fmu
    from .system.parameters import did_you_mean

    paths = []
    for given in args.fmus:
        if Path(given).is_file():
            paths.append(Path(given))
        elif given in FMUS:
            paths.append(build_fmu(given))
        else:
            raise ValueError(
                f"no such FMU file {given!r}, nor one of ours by name ({', '.join(FMUS)})"
                + did_you_mean(given, FMUS)
            )
    paths = paths or sorted(BUILD_DIR.glob("*.fmu"))
    if not paths:
        print("no FMUs to validate: run `agilesat build` first", file=sys.stderr)
        return 1
    bad = 0
    for path in paths:
        try:
            problems = validate_fmu(str(path))
        except Exception as exc:  # noqa: BLE001 - fmpy's, on a file that is no FMU
            problems = [f"not a valid FMU: {type(exc).__name__}: {exc}"]
        print(f"{path}: {'OK' if not problems else f'{len(problems)} problem(s)'}")
        for problem in problems:
            print(f"  {problem}")
        bad += bool(problems)
    return 1 if bad else 0


def _run(args) -> int:
    from .output.progress import Progress
    from .runner import run
    from .system.parameters import parse_set

    overrides = parse_set(args.set)
    out = args.out or Path("out") / args.target.replace(":", "-").replace("/", "_")
    with Progress(args.target, quiet=args.quiet) as progress:
        results, summary = run(
            args.target,
            step=args.step,
            stop=args.stop,
            start=args.start,
            algorithm=args.algorithm,
            parameters=overrides,
            out_dir=out,
            figures=not args.no_figures,
            svg=args.svg,
            echo=echo_to(out, say=progress.write),
            progress=progress,
            derivatives=False if args.no_derivatives else None,
            record=args.record,
            output_interval=args.output_interval,
            notice=lambda text: print(f"agilesat run: note: {text}", file=sys.stderr),
        )
    if args.mat:
        results.to_mat(out / "results.mat")
    if args.error_estimate:
        _error_estimate(args, overrides, summary, out)
    from .output.report import cli as report_cli

    report_cli.after(args, out)
    settings = summary["settings"]
    print(
        f"{args.target}: {len(results)} communication points, step {settings['step']} s, "
        f"{settings['algorithm']}; results in {out}/"
    )
    status = report(summary)
    if args.error_estimate:
        from .error_estimate import lines

        print("\n".join(lines(summary["numerical_error"])))
    return status


def _error_estimate(args, overrides, summary: dict, out: Path) -> None:
    """``--error-estimate``: the run again at half and a quarter of its step
    (:mod:`.error_estimate`), into the summary and summary.json."""
    from .error_estimate import estimate
    from .output.recorder import write_text
    from .output.summary import summary_text
    from .runner import run

    def rerun(step):
        return run(
            args.target,
            step=step,
            stop=args.stop,
            start=args.start,
            algorithm=args.algorithm,
            parameters=overrides,
            figures=False,
            derivatives=False if args.no_derivatives else None,
        )[1]

    summary["numerical_error"] = estimate(summary, rerun)
    write_text(out / "summary.json", summary_text(summary))


def _pointing(args) -> int:
    from .output import recorded_cli

    return recorded_cli.main(args)


def _report(args) -> int:
    from .output.report import cli as report_cli

    return report_cli.main(args)


def _export_ephemeris(args) -> int:
    from .output import ephemeris_cli

    return ephemeris_cli.main(args)


def _plot(args) -> int:
    from .output import plots
    from .output.results import ColumnError, Results

    runs = [Path(item) for item in args.items if Path(item).is_dir()]
    variables = [item for item in args.items if not Path(item).is_dir()]
    for item in variables:  # a variable is Instance.name; anything else is a directory
        if "/" in item or os.sep in item or "." not in item:
            raise ValueError(f"no such run directory: {item}")
    if not runs or not variables:
        raise UsageError(
            "expected RESULTS_DIR... VARIABLE...: one or more run directories, "
            f"then the variables to plot (got directories {list(map(str, runs))}"
            f", variables {variables})"
        )
    loaded = {run.name or str(run): Results.load(run) for run in runs}
    for run, results in zip(runs, loaded.values()):
        for name in variables:
            try:
                results.columns(name)
            except ColumnError as exc:  # a wrong name: did you mean ...; what there is
                recorded = dict.fromkeys(n.partition("[")[0] for n in results.names[1:])
                raise ColumnError(
                    f"{run}: {exc}; it recorded {', '.join(recorded)} "
                    "(whole arrays by base name, or elements like X.w_BI_B[2])"
                ) from None
    out = args.out or runs[0] / "plot.png"
    if len(loaded) == 1:
        loaded = {"": next(iter(loaded.values()))}  # one run: label the lines by element
    path = plots.signals(out, loaded, variables, deg=args.deg)
    print("\n".join(str(p) for p in plots.formats(path)))
    return 0


def report(summary) -> int:
    """Print the summary's numbers; the exit status of a run: 1 when a metric,
    requirement or figure raised (status "error": the run's records are written), 3 when
    it did not fly as required."""
    from .output.summary import format_summary

    print(format_summary(summary))
    if summary.get("status") == "error":  # a metric, requirement or figure raised
        return 1
    return exit_status(summary.get("status") == "failed", summary.get("requirements", {}))


def exit_status(failed: bool, verdicts) -> int:
    """3 when something failed or a requirement is not met, else 4 when one is
    undecided, else 0; ``verdicts``: {name: {"verdict": ...}} (a summary's
    ``requirements``, a campaign's ``ensemble``)."""
    statuses = {v.get("verdict") for v in verdicts.values()}
    return 3 if failed or "not met" in statuses else 4 if "undecided" in statuses else 0


def _export(args) -> int:
    from .export import export
    from .system.parameters import parse_set

    print(export(args.target, args.out, parse_set(args.set), args.component, args.accuracy))
    return 0


def echo_to(out: Path, limit: int = 5, say=None):
    """Print an FMU's first warnings and errors; the rest go to log.txt only.  ``say``:
    how a line is printed (a :class:`.output.progress.Progress`'s ``write``: above its
    bar); stderr by default."""
    counts: dict[str, int] = {}
    say = say or (lambda text: print(text, file=sys.stderr))

    def echo(entry):
        counts[entry.instance] = counts.get(entry.instance, 0) + 1
        if counts[entry.instance] <= limit:
            say(f"  FMU: {entry}")
        elif counts[entry.instance] == limit + 1:
            say(f"  FMU: {entry.instance}: more messages in {out / 'log.txt'}")

    return echo


def _generate(args) -> int:
    from ..fmus.build import generated_files
    from .mission.targets import generated_systems

    files = generated_files()  # first: the systems build FMUs, which need protocol.h
    files.update(generated_systems())
    checkout = source_checkout()
    if not checkout and not args.check:
        raise ValueError(
            "generate writes the generated files of a source checkout of agilesat; "
            f"this one is installed ({Path(__file__).parent}): `generate --check` checks it"
        )
    stale = []
    for path, render in files.items():
        if not checkout and not path.exists():
            continue  # not installed with the package (fmus/INTERFACES.md)
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


def source_checkout() -> bool:
    """Whether agilesat runs from a source checkout (an editable install), where the
    generated files all are; an installed package has only those it ships."""
    return (Path(__file__).resolve().parent.parent / "pyproject.toml").is_file()
