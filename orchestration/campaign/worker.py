"""What a Dask worker runs: one campaign run, as ``agilesat run`` would make it.

Outcomes: ``ok``; ``failed`` — the scenario ran but did not fly as required (exit 3 of
``run``; the message is its diagnostics); ``error`` — the run stopped (a failed FMI call,
bad values; the message says where).  Nothing raised here ends a campaign.  The worker
process keeps its loaded FMUs between runs (``orchestration.cosim.fmu``).
"""

from __future__ import annotations

import logging
import os
import signal
import time

import numpy as np

from ..cosim.signals import signal_at

_started = 0  # runs this process started


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
        from distributed.comm.core import CommClosedError

        error = record.exc_info[1] if record.exc_info else None
        return not isinstance(error, CommClosedError)


def quiet_closed_connections() -> None:
    """Dask logs a traceback of every connection a closing cluster cuts while a worker,
    nanny or client still used it (a heartbeat, CommClosedError): those log records are
    dropped by Dask's log handlers in this process (any other is printed)."""
    for handler in logging.getLogger("distributed").handlers:
        if not any(isinstance(f, _ClosedConnection) for f in handler.filters):
            handler.addFilter(_ClosedConnection())


def run_one(
    index: int,
    target: str,
    parameters: dict,
    step,
    stop,
    algorithm,
    signals: list[str],
    points: int,
) -> dict:
    from ..cosim.master import SimulationError
    from ..runner import run

    global _started
    _started += 1
    hook = signal_at("worker")
    if hook is not None and _started >= hook[1]:
        os.kill(os.getpid(), hook[0])  # $AGILESAT_TEST_SIGNAL=SIGNAL@worker:K
    began = time.perf_counter()
    record = {
        "index": index,
        "status": "ok",
        "message": "",
        "metrics": {},
        "requirements": {},
        "worker": _worker(),
        "pid": os.getpid(),
    }
    results = None
    try:
        results, summary = run(
            target,
            step=step,
            stop=stop,
            algorithm=algorithm,
            parameters=parameters,
            figures=False,
            build=False,
        )
        record["metrics"] = summary.get("metrics", {})
        record["requirements"] = summary.get("requirements", {})
        if summary.get("status") == "failed":
            record["status"] = "failed"
            record["message"] = "; ".join(summary["diagnostics"])
    except SimulationError as failure:
        record.update(status="error", message=str(failure))
        results = failure.results
    except Exception as exc:  # a bad value for one run is that run's outcome
        record.update(status="error", message=f"{type(exc).__name__}: {exc}")
    record["signals"] = _signals(results, signals, points)
    record["seconds"] = time.perf_counter() - began
    return record


def run_batch(
    runs: list[tuple[int, dict]],
    target: str,
    step,
    stop,
    algorithm,
    signals,
    points,
    share: int = 1,
) -> list[dict]:
    """Several runs in one Dask task (one round trip through the scheduler for all), each
    with its own record: ``runs`` is [(index, parameters), ...].  ``share``: the runs this
    worker is expected to make, which, from its first run, lets the models' kernels run
    compiled where that pays (AGILESAT_JIT_RUNS, components/jit.py; read as the FMUs load,
    unless set)."""
    if not _started:
        os.environ.setdefault("AGILESAT_JIT_RUNS", str(max(1, share)))
    return [
        run_one(index, target, parameters, step, stop, algorithm, signals, points)
        for index, parameters in runs
    ]


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


def _worker() -> str:
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return "local"
