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

# The command layer: each module adds its commands' parsers (``add_parsers``) and names
# the function of each (``COMMANDS``): system.py the commands on FMUs, targets and runs,
# campaign.py `agilesat campaign`, studies.py the papers' analyses, pointing.py
# `agilesat pointing`, report.py `agilesat report` (and --no-report), ephemeris.py
# `agilesat export-ephemeris`.  A run's and a campaign's options are declared with their flags
# where they are read (cosim/options.py RunOptions, campaign/plan.py Spec).

from __future__ import annotations

import argparse
import signal
import sys
from contextlib import nullcontext

from ...components.runtime.switches import check_all
from ..cosim.signals import interruptible
from ..provenance import version
from . import ephemeris, pointing, report, studies, system
from .system import UsageError, echo_to, exit_status, run_status

__all__ = ["main", "UsageError", "echo_to", "exit_status", "run_status"]

#: `agilesat campaign`'s line in `agilesat --help` (the campaign package, Dask and the
#: master are imported only to run a campaign; cli/campaign.py gives it its parser)
CAMPAIGN_HELP = "Monte Carlo campaign or parameter sweep of a scenario on Dask"


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
    commands = {**system.COMMANDS, **studies.COMMANDS, **pointing.COMMANDS}
    commands.update(report.COMMANDS, **ephemeris.COMMANDS)
    if campaign:
        from . import campaign as campaign_cli

        commands.update(campaign_cli.COMMANDS)
    args = _parser(campaign).parse_args(argv)
    # a signal stops a command at once until a run writes, then is a flag (signals.py);
    # a campaign handles its own (cli/campaign.py)
    with nullcontext() if campaign else interruptible(restore=not program) as signals:
        try:
            check_all()
            code = commands[args.command](args)
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


def _interrupted(exc: BaseException) -> bool:
    """A run stopped by SIGINT/SIGTERM (master.Interrupted; only a command that imported
    the master can raise one)."""
    master = sys.modules.get(f"{__package__.rpartition('.')[0]}.cosim.master")
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
    system.add_parsers(commands, quiet)
    studies.add_parsers(commands, quiet)
    pointing.add_parsers(commands, quiet)
    report.add_parsers(commands, quiet)
    ephemeris.add_parsers(commands, quiet)
    if campaign:
        from . import campaign as campaign_cli

        campaign_cli.add_parsers(commands, quiet)
    else:
        commands.add_parser("campaign", help=CAMPAIGN_HELP)
    listed = {c.dest: c.help for c in commands._choices_actions}
    for name, command in commands.choices.items():  # each command's --help says what it does
        command.description = command.description or listed.get(name)
    return parser
