"""What a run is asked for: :class:`RunOptions`, one object from the command line to the loop.

``agilesat run``'s flags, the keywords of :func:`..runner.run` and :func:`.master.simulate`
and what :func:`.plan.plan_run` reads are the fields of :class:`RunOptions`: each field is
one option, declared with its flag where the command line has one (:func:`flag`: the
flag's names and argparse's keywords), which the command layer adds to a command
(:func:`add_flags`) and reads back into the object (:func:`from_arguments`).  Adding an
option is one field here, with its flag, and its use where it acts (``plan.options.X``).
A campaign's :class:`..campaign.plan.Spec` declares its options the same way.
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

ALGORITHMS = ("gauss-seidel", "jacobi")
#: the flags several commands share (``run``, ``campaign``): argparse's keywords
STEP = dict(type=float, help="macro step [s]")
STOP = dict(type=float, help="stop time [s]")
ALGORITHM = dict(
    choices=ALGORITHMS,
    help="coupling algorithm (default the system's; gauss-seidel if it names none)",
)


def flag(*names: str, default: Any = None, **keywords: Any) -> Any:
    """A field that is also a command-line flag: ``names`` (``"--step"``) and argparse's
    ``keywords`` (``type``, ``action``, ``help``, ...)."""
    return field(default=default, metadata={"flag": (names, keywords)})


def add_flags(parser, options: type) -> None:
    """Add the flags of the fields of ``options`` (a dataclass) to an argparse parser, in
    field order."""
    for f in fields(options):
        if "flag" in f.metadata:
            names, keywords = f.metadata["flag"]
            parser.add_argument(*names, dest=f.name, default=f.default, **keywords)


def from_arguments(options: type, arguments, **given):
    """An ``options`` object (a dataclass) from parsed arguments: every field whose flag
    the command has, and ``given`` in place of any (what the command makes itself)."""
    flagged = {
        f.name: getattr(arguments, f.name)
        for f in fields(options)
        if "flag" in f.metadata and hasattr(arguments, f.name)
    }
    return options(**{**flagged, **given})


def setting(text: str) -> tuple[str, str]:
    """One ``--set INSTANCE.VARIABLE=VALUE``: (key, value text), the value typed later
    against the FMU's variable (:func:`..system.parameters.typed_parameters`)."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"expected INSTANCE.VARIABLE=VALUE, got {text!r}")
    return key.strip(), value.strip()


@dataclass(frozen=True)
class RunOptions:
    """What a run is asked for; None: the system's own (its default experiment and its
    master annotation).

    ``parameters``: {"Instance.variable": value} on top of the system's values (an
    element, ``"A.inertia[1,1]"``, or a whole array, ``"A.inertia"``: 3×3; with a unit
    where the variable is a Real; :mod:`..system.parameters`).  ``derivatives``: couple
    through FMI input/output derivatives where declared (default: as the system says, else
    on).  ``loop``: "auto" (default, or $AGILESAT_LOOP), "compiled" or "python"
    (:mod:`.loop`).  ``record``: the outputs recorded (columns, whole arrays by base name
    or patterns such as ``"SatelliteDynamics.*"``; default all); ``output_interval``:
    record every that many seconds (a multiple of the step).  ``out_dir``: results.csv row
    by row and results.npz there (else the rows are held in memory), and, by
    :func:`..runner.run`, log.txt, summary.json, the figures (``figures``, with ``svg`` an
    SVG beside each PNG) and with ``mat`` results.mat.  ``build``: build the FMUs that are
    stale first (:func:`..runner.run`).  ``progress(steps done, steps)``: called about a
    hundred times over the run; ``echo(log entry)``: each FMU message of status Warning or
    worse; ``notice(text)``: what a run says before it starts (default a warning);
    ``logging_on``: the FMUs' debug logging."""

    step: float | None = flag("--step", **STEP)
    stop: float | None = flag("--stop", **STOP)
    start: float | None = flag("--start", type=float, help="start time [s] (default the system's)")
    algorithm: str | None = flag("--algorithm", **ALGORITHM)
    output_interval: float | None = flag(
        "--output-interval",
        type=float,
        metavar="SECONDS",
        help="record every SECONDS (a multiple of the step; default every step)",
    )
    record: Any = flag(
        "--record",
        action="extend",
        nargs="+",
        metavar="VAR",
        help="record only these outputs: columns, whole arrays by base name, or patterns "
        "(SatelliteDynamics.*); default all",
    )
    derivatives: bool | None = flag(
        "--no-derivatives",
        action="store_const",
        const=False,
        help="do not couple through FMI input/output derivatives where no wire passes "
        "them (first-order coupling of those inputs)",
    )
    parameters: dict[str, Any] = flag(
        "--set",
        action="append",
        type=setting,
        metavar="INSTANCE.VAR=VALUE",
        help="override a parameter: an element (A.inertia[2,2]=900) or a whole "
        "array (A.inertia=[[900,0,0],[0,900,0],[0,0,900]]); with a unit where it converts "
        "(A.attitude0[2]='100 deg'); `agilesat info` lists them",
    )
    out_dir: Path | None = flag(
        "--out", type=Path, metavar="OUT", help="output directory (default out/<target>)"
    )
    figures: bool = flag("--no-figures", default=True, action="store_false", help="draw no figures")
    svg: bool = flag(
        "--svg",
        default=False,
        action="store_true",
        help="also write each figure as SVG (vector, for reports; ~25 %% more figure time)",
    )
    mat: bool = flag(
        "--mat", default=False, action="store_true", help="also write results.mat (MATLAB)"
    )
    loop: str | None = None
    build: bool = True
    logging_on: bool = False
    progress: Callable[[int, int], None] | None = None
    echo: Callable[[Any], None] | None = None
    notice: Callable[[str], None] | None = None

    def __post_init__(self):
        # the command line gives (key, value) pairs, Python a mapping
        object.__setattr__(self, "parameters", dict(self.parameters or {}))
        if self.out_dir is not None:
            object.__setattr__(self, "out_dir", Path(self.out_dir))

    @classmethod
    def given(cls, options: RunOptions | None = None, keywords: dict | None = None) -> RunOptions:
        """``options`` (default all defaults) with ``keywords`` in place of its fields (a
        TypeError names a keyword that is no option)."""
        options = options or cls()
        return dataclasses.replace(options, **keywords) if keywords else options
