"""What a Dask worker runs: one campaign run, as ``agilesat run`` would make it.

Outcomes: ``ok``; ``failed`` — the scenario ran but did not fly as required (exit 3 of
``run``; the message is its diagnostics); ``error`` — the run stopped (a failed FMI call,
bad values; the message says where).  Nothing raised here ends a campaign.  The worker
process keeps its loaded FMUs between runs (``orchestration.cosim.fmu``).

A worker process warms up once, inside its first batch, before its first run
(:func:`warm_up`): the first macro steps of the batch's first run, which load what every
run uses (the FMUs, the models' compiled kernels, the master's compiled loop, the
metrics' and the pointing statistics' modules), so that the runs themselves cost what a
run costs.  It is part of that batch: an exception is said in the batch's first record
(``warm_up_error``) and the run then makes its own outcome; a crash loses the batch's
runs, as a crash in a run does.  Its time is in that record (``warm_up_seconds``,
``warm_up_cpu_seconds``); each run's own in ``seconds`` (wall) and ``cpu_seconds`` (the
CPU of the thread that ran it, which other processes on the machine do not inflate).
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import os
import signal
import time

import numpy as np

from ..cosim.signals import signal_at

_started = 0  # runs this process started (0: its warm-up is next)
_warmed: set[str] = set()  # the targets this process has warmed up for (a scheduler's
# workers outlive a campaign: the next one, of another target, warms up for its own)
#: macro steps of a worker's warm-up, at least (measured: docs/performance-log.md)
WARM_UP_STEPS = 5
#: the warm-up is at most this fraction of a run's macro steps
WARM_UP_FRACTION = 0.1


def dask_setup(worker) -> None:
    """Run in each worker process of a LocalCluster as it starts (the cluster's
    ``distributed.worker.preload``): SIGINT ignored.  Ctrl-C in a terminal signals the
    whole process group; the campaign process takes it, keeps what was made and closes
    the cluster, and the workers print no tracebacks.  And their log says nothing of the
    connections the closing cluster closes (:func:`quiet_closed_connections`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    quiet_closed_connections()


class _ClosedConnection(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        from asyncio import CancelledError

        from distributed.comm.core import CommClosedError

        error = record.exc_info[1] if record.exc_info else None
        return not isinstance(error, (CommClosedError, CancelledError))


def quiet_closed_connections() -> None:
    """Dask logs a traceback of every connection a closing cluster cuts while a worker,
    nanny or client still used it (a heartbeat, CommClosedError), and of the client's
    attempts to reconnect to a scheduler that is gone, cancelled as the campaign closes it
    (CancelledError; the campaign says the scheduler was lost): those log records are
    dropped by Dask's log handlers in this process (any other is printed)."""
    for handler in logging.getLogger("distributed").handlers:
        if not any(isinstance(f, _ClosedConnection) for f in handler.filters):
            handler.addFilter(_ClosedConnection())


def run_one(index: int, target: str, options, signals: list[str], points: int) -> dict:
    """Run ``index`` of a campaign, ``target`` with ``options``
    (:class:`..cosim.options.RunOptions`), as ``agilesat run`` would make it; its record."""
    from ..runner import planned

    return _made(index, lambda: planned(target, options), signals, points)


def _made(index: int, planned, signals: list[str], points: int) -> dict:
    """The record of run ``index``: ``planned`` is a function that gives its
    :class:`..runner.Planned` run (or raises the error that is its outcome)."""
    from ..cosim.master import SimulationError

    global _started
    _started += 1
    _hook()
    began, cpu = time.perf_counter(), time.thread_time()
    record = {
        "index": index,
        "status": "ok",
        "message": "",
        "metrics": {},
        "requirements": {},
        "worker": _worker(),
        "pid": os.getpid(),
    }
    results = made = None
    try:
        made = planned()
        results, summary = made.run(began)
        record["metrics"] = summary.get("metrics", {})
        record["requirements"] = summary.get("requirements", {})
        if summary.get("status") == "error":  # a metric or requirement raised
            record.update(status="error", message="; ".join(summary["errors"]))
        elif summary.get("status") == "failed":
            record["status"] = "failed"
            record["message"] = "; ".join(summary["diagnostics"])
    except SimulationError as failure:
        record.update(status="error", message=str(failure))
        results = failure.results
    except Exception as exc:  # a bad value for one run is that run's outcome
        record.update(status="error", message=f"{type(exc).__name__}: {exc}")
    record["signals"] = _signals(results, signals, points)
    if made is not None and results is not None and len(results) == points:
        record["magnitudes"] = _magnitudes(made.target, results)
    record["seconds"] = time.perf_counter() - began
    record["cpu_seconds"] = time.thread_time() - cpu
    return record


def _hook() -> None:
    """``$AGILESAT_TEST_SIGNAL=SIGNAL@worker:K``: the signal as this process starts its
    K-th run (K = 0: its warm-up)."""
    hook = signal_at("worker")
    if hook is not None and _started >= hook[1]:
        os.kill(os.getpid(), hook[0])


def warm_up_steps(steps: int, share: int) -> int:
    """The macro steps of a warm-up before runs of ``steps`` macro steps, ``share`` of them
    expected in this process.  A model's kernels run compiled from a run's first step when
    the calls expected of them in the process (steps × runs) reach jit.PAYS_AFTER: the
    warm-up makes enough steps that its expectation (its steps × ``share``) reaches it
    where the runs' does, so that it loads the compiled kernels the runs use, unless that
    is more than :data:`WARM_UP_FRACTION` of a run (then the first run decides for itself,
    as without a warm-up); and at least :data:`WARM_UP_STEPS` (or the whole run, if it is
    shorter), which load the FMUs and the modules every run uses."""
    from ...components.runtime.jit import PAYS_AFTER

    needed = max(WARM_UP_STEPS, math.ceil(PAYS_AFTER / max(1, share)))
    if needed > WARM_UP_FRACTION * steps:
        needed = WARM_UP_STEPS
    return max(1, min(needed, steps))


def warm_up(target: str, options, points: int, share: int):
    """The first macro steps of a run (:func:`warm_up_steps`) of ``target`` with
    ``options`` (:class:`..cosim.options.RunOptions`), nothing kept: (wall seconds, CPU
    seconds of this thread, the error it raised or None)."""
    from ..runner import planned

    _hook()
    began, cpu = time.perf_counter(), time.thread_time()
    error = None
    try:
        steps = points - 1
        start = options.stop - steps * options.step
        stop = start + warm_up_steps(steps, share) * options.step
        planned(target, dataclasses.replace(options, stop=stop)).run()
    except Exception as exc:  # the batch's first run makes its own outcome
        error = f"{type(exc).__name__}: {exc}"
    return time.perf_counter() - began, time.thread_time() - cpu, error


def run_batch(
    runs: list[tuple[int, dict]], target: str, options, signals, points, share: int = 1
) -> list[dict]:
    """Several runs in one Dask task (one round trip through the scheduler for all), each
    with its own record: ``runs`` is [(index, its dispersed values), ...], on top of
    ``options`` (:class:`..cosim.options.RunOptions`: the campaign's settings and
    ``--set``).  The batch plans its runs once (:class:`Batch`).  ``share``: the runs
    this worker is expected to make, which, from its first run, lets the models' kernels
    run compiled where that pays (AGILESAT_JIT_RUNS, components/runtime/jit.py; read as
    the FMUs load, unless set).  The process's first batch of ``target`` starts with its
    warm-up (module docstring), with the values of the batch's first run."""
    warmed = None
    if not _started:
        os.environ.setdefault("AGILESAT_JIT_RUNS", str(max(1, share)))
    if target not in _warmed and runs:
        _warmed.add(target)
        warmed = warm_up(target, _with(options, runs[0][1]), points, share)
    batch = Batch(target, options)
    records = [
        _made(index, functools.partial(batch.planned, values), signals, points)
        for index, values in runs
    ]
    if warmed is not None:
        seconds, cpu, error = warmed
        records[0].update(warm_up_seconds=seconds, warm_up_cpu_seconds=cpu)
        if error is not None:
            records[0]["warm_up_error"] = error
    return records


class Batch:
    """The runs of a batch, planned once: the target resolved and the run planned with the
    values of the first run that plans, then the values of each run that sets the same
    parameters (every run of a campaign does) swapped in
    (:meth:`..runner.Planned.swapped`); a run that sets others is planned on its own.  A
    run whose values do not plan fails alone."""

    def __init__(self, target: str, options):
        self.target, self.options = target, options
        self.base = None  # (the planned run, its values)

    def planned(self, values: dict):
        """The :class:`..runner.Planned` run of ``values``."""
        from ..runner import planned

        if self.base is not None and self.base[1].keys() == values.keys():
            return self.base[0].swapped(values)
        made = planned(self.target, _with(self.options, values))
        if self.base is None:
            self.base = (made, values)
        return made


def _with(options, values: dict):
    """``options`` with ``values`` set on top of its parameters."""
    return dataclasses.replace(options, parameters={**options.parameters, **values})


def _signals(results, names, points) -> np.ndarray | None:
    """(len(names), points) float64; NaN where the run did not get to."""
    if not names:
        return None
    out = np.full((len(names), points), np.nan)
    if results is not None:
        n = min(len(results), points)
        for row, name in enumerate(names):
            out[row, :n] = results[name][:n]
    return out


def _magnitudes(target, results) -> dict:
    """{name: m[time]}: the run's index magnitudes of the requirements judged over the
    campaign (:mod:`.magnitudes`), for the verdict over the campaign."""
    from .magnitudes import run_rows
    from .plan import over_campaign

    return run_rows(over_campaign(target.scenario, target.variant), results)


def _worker() -> str:
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return "local"
