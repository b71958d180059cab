"""A campaign's nominal run: every random dispersion at the system's value, whose metrics
the histograms mark (:func:`start`, then :meth:`Nominal.result`)."""

from __future__ import annotations

import math
import shlex
import sys

from . import engine, isolated
from .plan import Plan
from .replay import run_arguments, versions


class Nominal:
    """The nominal run, kept or started (:func:`start`)."""

    def __init__(self, command: str, record: dict | None = None, started=None):
        self.command, self.record, self.started = command, record, started

    def result(self) -> dict:
        """{"command": the ``agilesat run`` that makes it, "metrics": {name: SI value}}, or
        the reason it has none (said on stderr too); waits for the run if it goes on."""
        from ..cosim.master import Interrupted

        if self.record is not None:
            return self.record
        try:
            summary = self.started.result()
        except (Exception, KeyboardInterrupt) as failure:  # the runs are made: not worth failing
            if isinstance(failure, Interrupted):
                engine.INTERRUPTS.signals.append(failure.signal)
            elif isinstance(failure, KeyboardInterrupt) and not engine.INTERRUPTS.signals:
                raise  # not a signal the campaign's handler took
            return self._none(f"{type(failure).__name__}: {failure}")
        values = {k: m["value"] for k, m in summary["metrics"].items() if m["value"] is not None}
        self.record = {"command": self.command, "metrics": values}
        return self.record

    def cancel(self) -> None:
        """Stop the run if it goes on (its result is no longer wanted)."""
        if self.started is not None and self.record is None:
            self.started.cancel()

    def _none(self, reason: str) -> dict:
        print(f"campaign: no nominal run ({reason})", file=sys.stderr)
        self.record = {"command": self.command, "reason": reason}
        return self.record


def start(plan: Plan, before: dict | None = None) -> Nominal:
    """The run at the nominal values (every random dispersion at the system's value, the
    spec's ``--set`` and the grid point's values applied), whose metrics the histograms
    mark, started in a process of its own (:mod:`.isolated`): the campaign's summary is
    written meanwhile.  A signal during it is recorded for the command's exit status
    (130/143) as one while the cluster closes.

    ``before``: campaign.json as the campaign found it (a resumed one's).  Its nominal run
    is kept, not made again, when it has metrics, the same command and the same
    ``versions``: the run would be the same one (a resume has the same spec and system
    content, :func:`.engine.open_directory`); otherwise it is made again, and stderr says
    why."""
    spec = plan.spec
    grid = {
        name: value
        for name, value in plan.run_values(0).items()
        if any(name == key or name.startswith(key + "[") for key in plan.grid_keys)
    }
    parameters = {**spec.set, **grid}
    command = shlex.join(run_arguments(plan, parameters))
    held = (before or {}).get("nominal")
    if held:
        differs = _not_this_nominal_run(held, command, before.get("versions"))
        if not differs:
            print(
                f"campaign: the nominal run, for the histograms: {command} (kept: "
                "campaign.json has it, made with the same command and versions)",
                file=sys.stderr,
            )
            return Nominal(command, {"command": command, "metrics": held["metrics"]})
        print(f"campaign: the nominal run in campaign.json {differs}: made again", file=sys.stderr)
    print(f"campaign: the nominal run, for the histograms: {command}", file=sys.stderr)
    try:  # in a process of its own: an FMU crashing there does not end the campaign
        return Nominal(command, started=isolated.start(spec.target, plan.run_options(grid)))
    except OSError as failure:  # no process to run it in
        nominal = Nominal(command)
        nominal._none(f"{type(failure).__name__}: {failure}")
        return nominal


def _not_this_nominal_run(held, command: str, made_with) -> str | None:
    """Why campaign.json's nominal run ``held``, made with the versions ``made_with``, is
    not the one ``command`` makes now, or None."""
    if not isinstance(held, dict) or not isinstance(held.get("metrics"), dict):
        reason = held.get("reason") if isinstance(held, dict) else None
        return "has no metrics" + (f" ({reason})" if reason else "")
    odd = [k for k, v in held["metrics"].items() if not _is_number(v)]
    if odd:
        return f"has metrics that are not numbers ({', '.join(map(str, odd))})"
    if held.get("command") != command:
        return f"was another command ({held.get('command')})"
    now, then = versions(), made_with if isinstance(made_with, dict) else {}
    changed = sorted(k for k in {*now, *then} if now.get(k) != then.get(k))
    return f"was made with other versions ({', '.join(changed)})" if changed else None


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
