"""``agilesat report DIR``: the interactive report of a run or a campaign
(:mod:`..postprocess.report`), and
the ``--no-report`` option of ``agilesat run`` and ``agilesat campaign``, which write it by
default."""

from __future__ import annotations

from pathlib import Path

HELP = "write the interactive HTML report (plots, 3-D view) of a run or campaign directory"


def add_parsers(commands, quiet) -> None:
    p = commands.add_parser(
        "report",
        help=HELP,
        description=HELP[0].upper()
        + HELP[1:]
        + (
            ": one self-contained page, opened from disk (plotly.js inside; nothing fetched).  "
            "See docs/running.md."
        ),
    )
    p.add_argument("directory", type=Path, help="a run's or a campaign's output directory")
    p.add_argument("--out", type=Path, help="the page (default DIR/report.html)")


def add_option(parser) -> None:
    """``--no-report`` on ``agilesat run`` and ``agilesat campaign``."""
    parser.add_argument(
        "--no-report",
        action="store_true",
        help="write no report.html (the interactive report; `agilesat report DIR` writes it later)",
    )


def main(args) -> int:
    from ..postprocess.report import write_report

    if not args.directory.is_dir():
        raise ValueError(f"no such run or campaign directory: {args.directory}")
    print(write_report(args.directory, args.out))
    return 0


def after(args, directory) -> None:
    """What ``run`` and ``campaign`` do after their figures: the report, unless
    ``--no-report`` (then a report an earlier run left in ``directory`` is removed: it
    would show that run as this one)."""
    from ..postprocess.report import NAME, write_report

    if args.no_report:
        (Path(directory) / NAME).unlink(missing_ok=True)
    else:
        write_report(directory)


COMMANDS = {"report": main}
