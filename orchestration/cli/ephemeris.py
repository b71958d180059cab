"""``agilesat export-ephemeris DIR``: a run's attitude as a CCSDS AEM and its orbit as an
OEM, KVN and XML (:mod:`..postprocess.ephemeris`, docs/ephemerides.md)."""

from __future__ import annotations

from pathlib import Path

HELP = "write a run's attitude as a CCSDS AEM and its orbit as an OEM (KVN and XML)"


def add_parsers(commands, quiet) -> None:
    p = commands.add_parser(
        "export-ephemeris",
        help=HELP,
        description=HELP[0].upper()
        + HELP[1:]
        + ": CCSDS 504.0-B-2 and 502.0-B-3, UTC, frame TEME of the epoch.  "
        "See docs/ephemerides.md.",
    )
    p.add_argument("directory", type=Path, help="a run's output directory (`agilesat run`)")
    p.add_argument("--out", type=Path, help="directory of the messages (default DIR)")
    p.add_argument(
        "--epoch",
        metavar="YYYY-MM-DDTHH:MM:SS",
        help="UTC date of t = 0, for a run without an epoch of its own",
    )
    p.add_argument(
        "--format",
        choices=("kvn", "xml"),
        action="append",
        dest="formats",
        help="kvn or xml (repeat for both; default both)",
    )
    p.add_argument("--object-name", help="OBJECT_NAME (default the run's target)")
    p.add_argument(
        "--object-id",
        default="UNKNOWN",
        help="OBJECT_ID, e.g. the international designator 2016-001A (default UNKNOWN)",
    )


def main(args) -> int:
    from ..postprocess.ephemeris import FORMATS, export

    for path in export(
        args.directory,
        args.out,
        args.epoch,
        args.formats or FORMATS,
        args.object_name,
        args.object_id,
    ):
        print(path)
    return 0


COMMANDS = {"export-ephemeris": main}
