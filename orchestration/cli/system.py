"""``agilesat list|info|build|validate|run|plot|export|generate``: the commands on FMUs,
scenarios, mission files and system files, and the generated files."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from ..cosim.options import RunOptions, add_flags, from_arguments, setting
from . import report

#: what TARGET may be (``mission.targets``)
TARGETS = (
    "a scenario[:variant] (`agilesat list`), a mission file path/to/mission.py[:variant], "
    "a module of one, an .ssd/.ssp file, or an FMU (.fmu, or one of ours by name)"
)


class UsageError(ValueError):
    """A command line argparse cannot judge wrong (exit 2, as argparse's own)."""


def add_parsers(commands, quiet) -> None:
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
    add_flags(run, RunOptions)
    run.add_argument(
        "--error-estimate",
        action="store_true",
        help="rerun at half and a quarter of the step and state each metric's numerical "
        "error (Richardson, observed order) and the requirements it leaves undecided",
    )
    report.add_option(run)

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
        type=setting,
        dest="parameters",
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
    from ..info import listing

    print(listing())
    return 0


def _info(args) -> int:
    from ..info import info

    print(info(args.target))
    return 0


def _build(args) -> int:
    from ...fmus import FMUS
    from ...fmus.build import BUILD_DIR

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
    from ...fmus.build import build_fmu
    from ..output.progress import Progress

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
    from ...fmus.user_models import build_model

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

    from ...fmus import FMUS
    from ...fmus.build import BUILD_DIR, build_fmu
    from ..system.parameters import did_you_mean

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
    from ..output.progress import Progress
    from ..runner import run

    out = args.out_dir or Path("out") / args.target.replace(":", "-").replace("/", "_")
    with Progress(args.target, quiet=args.quiet) as progress:
        options = from_arguments(
            RunOptions,
            args,
            out_dir=out,
            progress=progress,
            echo=echo_to(out, say=progress.write),
            notice=lambda text: print(f"agilesat run: note: {text}", file=sys.stderr),
        )
        results, summary = run(args.target, options)
    if args.error_estimate:
        _error_estimate(args.target, options, summary, out)
    report.after(args, out)
    settings = summary["settings"]
    print(
        f"{args.target}: {len(results)} communication points, step {settings['step']} s, "
        f"{settings['algorithm']}; results in {out}/"
    )
    status = run_status(summary)
    if args.error_estimate:
        from ..error_estimate import lines

        print("\n".join(lines(summary["numerical_error"])))
    return status


def _error_estimate(target, options: RunOptions, summary: dict, out: Path) -> None:
    """``--error-estimate``: the run again at half and a quarter of its step, nothing
    written (:mod:`..error_estimate`), into the summary and summary.json."""
    from ..error_estimate import estimate
    from ..output.recorder import write_text
    from ..output.summary import summary_text
    from ..runner import run

    def rerun(step):
        again = RunOptions(
            step=step,
            stop=options.stop,
            start=options.start,
            algorithm=options.algorithm,
            parameters=options.parameters,
            derivatives=options.derivatives,
            figures=False,
        )
        return run(target, again)[1]

    summary["numerical_error"] = estimate(summary, rerun)
    write_text(out / "summary.json", summary_text(summary))


def _plot(args) -> int:
    from ..output import plots
    from ..output.results import ColumnError, Results

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


def run_status(summary) -> int:
    """Print the summary's numbers; the exit status of a run: 1 when a metric,
    requirement or figure raised (status "error": the run's records are written), else
    :func:`exit_status`."""
    from ..output.summary import format_summary

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
    from ..export import export

    print(export(args.target, args.out, dict(args.parameters or ()), args.component, args.accuracy))
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
    from ...fmus.build import generated_files
    from ..mission.targets import generated_systems

    files = generated_files()  # first: the systems build FMUs, which need protocol.h
    files.update(generated_systems())
    checkout = source_checkout()
    if not checkout and not args.check:
        raise ValueError(
            "generate writes the generated files of a source checkout of agilesat; "
            f"this one is installed ({Path(__file__).parents[1]}): `generate --check` checks it"
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
    return (Path(__file__).resolve().parents[2] / "pyproject.toml").is_file()


COMMANDS = {
    "list": _list,
    "info": _info,
    "build": _build,
    "validate": _validate,
    "run": _run,
    "plot": _plot,
    "export": _export,
    "generate": _generate,
}
