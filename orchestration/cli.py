"""``agilesat``: build, validate and run the toolkit's FMUs and scenarios.

Exit status: 0 success; 1 bad input or a failed run (the message says what and where);
3 a scenario that ran but did not fly as required (the summary's diagnostics say why).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import scenarios


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="agilesat", description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)

    build = commands.add_parser("build", help="build FMUs into fmus/build/")
    build.add_argument("names", nargs="*", help="FMU names (default: all)")
    build.add_argument("--out", type=Path, help="output directory (default fmus/build)")
    build.add_argument("--force", action="store_true", help="rebuild even if up to date")

    validate = commands.add_parser("validate", help="validate FMUs with fmpy's validator")
    validate.add_argument("fmus", nargs="*", type=Path,
                          help="FMU files (default: every FMU in fmus/build)")

    run = commands.add_parser("run", help="run a scenario[:variant] or an .ssd/.ssp file")
    run.add_argument("target", help=f"one of {', '.join(scenarios.NAMES)} (optionally "
                     ":variant) or a system file")
    run.add_argument("--step", type=float, help="macro step [s]")
    run.add_argument("--stop", type=float, help="stop time [s]")
    run.add_argument("--algorithm", choices=("gauss-seidel", "jacobi"))
    run.add_argument("--set", action="append", default=[], metavar="INSTANCE.VAR=VALUE",
                     help="override a parameter (scalar names, e.g. A.inertia[1,1]=900)")
    run.add_argument("--out", type=Path, help="output directory (default out/<target>)")
    run.add_argument("--no-figures", action="store_true")

    export = commands.add_parser("export", help="write a scenario[:variant] as a "
                                 "self-contained SSP package (.ssd + FMUs)")
    export.add_argument("target", help=f"one of {', '.join(scenarios.NAMES)} (optionally "
                        ":variant)")
    export.add_argument("--out", type=Path, required=True, help="the .ssp file to write")

    size = commands.add_parser("size-flywheel", help="smallest reaction wheel that meets the "
                               "payload_sweep pointing requirements (co-simulation sweep)")
    size.add_argument("--turnaround", type=float, default=1.0, help="payload reversal time [s]")
    size.add_argument("--accuracy", type=float, default=0.032, help="pointing accuracy [deg]")
    size.add_argument("--stability", type=float, default=0.006, help="pointing stability [deg/s]")
    size.add_argument("--step", type=float, default=0.05, help="macro step [s]")
    size.add_argument("--stop", type=float, help="run length [s] (default: one pitch sweep)")
    size.add_argument("--out", type=Path, default=Path("out/size-flywheel"))

    generate = commands.add_parser("generate", help="write the files generated from the "
                                   "variable tables and scenarios (.ssd, fmus/INTERFACES.md)")
    generate.add_argument("--check", action="store_true",
                          help="only check that the committed files are up to date")

    args = parser.parse_args(argv)
    try:
        return {"build": _build, "validate": _validate, "run": _run, "export": _export,
                "size-flywheel": _size_flywheel, "generate": _generate}[args.command](args)
    except (KeyError, ValueError, RuntimeError, OSError) as exc:
        print(f"agilesat {args.command}: error: {exc}", file=sys.stderr)
        return 1


def _build(args) -> int:
    from ..fmus.build import BUILD_DIR, build_all
    for path in build_all(args.out or BUILD_DIR, args.names or None, force=args.force):
        print(path)
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
    from .runner import format_summary, run
    overrides = {}
    for item in args.set:
        key, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"--set {item}: expected INSTANCE.VARIABLE=VALUE")
        overrides[key.strip()] = value.strip()
    out = args.out or Path("out") / args.target.replace(":", "-").replace("/", "_")
    results, summary = run(args.target, step=args.step, stop=args.stop,
                           algorithm=args.algorithm, parameters=overrides, out_dir=out,
                           figures=not args.no_figures, echo=_echo(out))
    settings = summary["settings"]
    print(f"{args.target}: {len(results)} communication points, step {settings['step']} s, "
          f"{settings['algorithm']}; results in {out}/")
    print(format_summary(summary))
    return 3 if summary.get("status") == "failed" else 0


def _export(args) -> int:
    from .export import export_ssp
    print(export_ssp(args.target, args.out))
    return 0


def _size_flywheel(args) -> int:
    import math
    from ..fmus.build import build_all
    from .sizing import size_flywheel
    deg = math.pi / 180
    build_all(names=scenarios.get("payload_sweep").components)
    print(f"wheel torque limit [N·m]   accuracy [deg]   stability [deg/s]   momentum [N·m·s]")
    result = size_flywheel(args.turnaround, args.accuracy * deg, args.stability * deg,
                           args.step, args.stop, out_dir=args.out, progress=lambda p: print(
                               f"{p.torque:24.4g} {p.accuracy / deg:16.4g} "
                               f"{p.stability / deg:19.4g} {p.momentum:18.3g}"
                               f"   {'meets' if p.met else 'fails'}"))
    if result.torque is None:
        print(f"no wheel up to {max(p.torque for p in result.points):g} N·m meets "
              f"{args.accuracy}° and {args.stability} °/s with {args.turnaround} s reversals")
        return 3
    print(f"smallest wheel: {result.torque:.3g} N·m torque, using {result.momentum:.3g} N·m·s "
          f"(reversal {args.turnaround} s, step {args.step} s); {args.out / 'sizing.png'}")
    return 0


def _echo(out: Path, limit: int = 5):
    """Print an FMU's first warnings and errors; the rest go to log.txt only."""
    counts: dict[str, int] = {}

    def echo(entry):
        counts[entry.instance] = counts.get(entry.instance, 0) + 1
        if counts[entry.instance] <= limit:
            print(f"  FMU: {entry}", file=sys.stderr)
        elif counts[entry.instance] == limit + 1:
            print(f"  FMU: {entry.instance}: more messages in {out / 'log.txt'}",
                  file=sys.stderr)
    return echo


def _generate(args) -> int:
    from ..fmus.build import FMUS_DIR, interfaces_markdown
    files = {scenarios.get(name).ssd: scenarios.get(name).render_ssd
             for name in scenarios.NAMES}
    files[FMUS_DIR / "INTERFACES.md"] = lambda: interfaces_markdown().encode()
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
