"""Running a campaign on Dask, and what it leaves in its directory.

Runs go to a ``distributed`` cluster: a ``LocalCluster`` of single-threaded worker
processes on this machine, or any running cluster by its scheduler address.  Runs go in
batches of a few seconds of work (one Dask task each, :func:`batch_size`), each run still
its own record; at most two batches per worker are in flight (``as_completed`` refilled
as they finish), so the client's memory stays bounded whatever N is.  A worker that dies
is noticed by the scheduler, which runs the batches it held on the others (up to
``distributed.scheduler.allowed-failures`` times, then those runs' outcome is ``lost``);
the campaign reports the workers it lost and the runs they held.

Files in the output directory, written as runs finish:

- ``runs.jsonl`` — the journal: one line per finished run (index, values, outcome,
  metrics), flushed as each batch is back; ``--resume`` and extensions skip the runs it holds.
- ``metrics.json`` — each metric's unit, description and bound, and each requirement's
  statement (``{"metrics": ..., "requirements": ...}``, from the first run with them).
- ``signals.npy`` — the ``--keep`` signals, float64 (runs, signals, points), NaN where a
  run has not been made or stopped early (``np.load(..., mmap_mode="r")``).
- ``magnitudes/`` — each run's index magnitudes of the pointing requirements judged over
  the campaign, as its worker computed them (:mod:`.magnitudes`).
- at the end (and on an interruption): ``runs.csv`` (+ ``runs.parquet`` with pyarrow),
  ``campaign.json`` and the figures (:mod:`.report`).
"""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import sys
import time
import uuid
import warnings
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..cosim.signals import signal_at
from ..output.recorder import file_error, write_text
from .files import (
    CampaignFileError,
    changed,
    code_changed,
    code_content,
    journal_record,
    read_object,
    system_content,
)
from .magnitudes import Store
from .plan import Plan, Spec
from .worker import quiet_closed_connections, run_batch

IN_FLIGHT_PER_WORKER = 2  # batches queued per worker: the next is there when one ends
BATCH_SECONDS = 2.0
MAX_TASKS_PER_SECOND = 20  # the client + scheduler's ~15 ms per task: ~1/3 of a core
MAX_BATCH = 50
#: Settings of the LocalCluster we start (a cluster given by its address keeps its own).
#: Dask's periodic work, at its defaults, costs about 50 ms of CPU per second in each of
#: the worker, nanny and client processes, taken from the runs: the worker's statistical
#: profiler (a stack sample every 10 ms on its event loop, for the dashboard's profile
#: page), the event-loop watchdog tick every 20 ms (it only warns when the loop is blocked
#: for more than 3 s), the system monitor every 0.5 s and the memory monitor (spill,
#: pause, terminate) every 0.1 s (idle Dask processes using CPU: dask/distributed#5000,
#: #5062).  With these, 5-10 ms/s (tests/tools/benchmark_campaign.py).  And the nanny spawns its
#: worker with MALLOC_TRIM_THRESHOLD_=65536 (for workers holding large data): setting it
#: turns off glibc's dynamic mmap threshold, so every NumPy array over 128 KiB a run makes
#: is mapped and unmapped again, ~500 page faults per scan_pitch run instead of ~30; our
#: workers hold no data (their memory is flat without it, see the benchmark), and None
#: unsets it (the nanny would also set it in this process's environment for good).
LOCAL_CLUSTER_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "500ms",
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
    # Ctrl-C in a terminal signals the whole process group: the workers ignore it (no
    # tracebacks), the campaign process stops the campaign and closes the cluster
    "distributed.worker.preload": [f"{__package__}.worker"],
}


class Interrupts:
    """``agilesat campaign``'s handler of SIGINT and SIGTERM (:data:`INTERRUPTS`): each
    signal recorded in ``signals``; a KeyboardInterrupt before the cluster starts, a flag
    while it is up (:func:`cluster`), which the loop over the runs looks at every 50 ms.
    (An exception raised in a signal handler lands wherever the main thread is; in a
    finaliser or a garbage-collector callback, of which Dask has some, Python prints it
    and drops it.)"""

    def __init__(self):
        self.signals: list[int] = []
        self.deferred = False

    def __call__(self, signum, frame):
        self.signals.append(signum)
        if not self.deferred:
            raise KeyboardInterrupt


INTERRUPTS = Interrupts()


class CampaignExistsError(ValueError):
    pass


class SchedulerLost(RuntimeError):
    """The client lost its Dask scheduler: the runs in flight were cancelled, not made."""


def read_journal(path: Path) -> dict[int, dict]:
    """Finished runs by index; a last line cut short by a kill is dropped, any other line
    that is not a run record (:func:`.files.journal_record`), or records a run again, is an
    error naming it."""
    records, lines = {}, {}
    if path.exists():
        for number, line in enumerate(path.read_text().splitlines(keepends=True), start=1):
            if not line.endswith("\n"):
                break
            record = journal_record(path, number, line)
            index = record["index"]
            if index in records:  # two outcomes of one run: which is it?
                raise CampaignFileError(
                    f"{path}:{number}: run {index} is recorded again (first on line "
                    f"{lines[index]}); a campaign journals each run once"
                )
            records[index], lines[index] = record, number
    return records


def open_directory(plan: Plan, out: Path, resume: bool) -> dict[int, dict]:
    """Check ``out`` against the plan (the spec, the content of the system and its FMUs,
    ``system_sha256``, and of the code the runs execute, ``code_sha256``: the modules the
    mission imports and the toolkit's sources); the runs already finished there.  A
    directory that holds a campaign (its campaign.json or journal) is opened only to
    resume it."""
    journal, summary = out / "runs.jsonl", out / "campaign.json"
    content = system_content(plan)
    if not journal.exists() and not summary.exists():
        out.mkdir(parents=True, exist_ok=True)
        # the spec first: a campaign killed before it finishes can still be resumed
        first = {
            "status": "running",
            "spec": plan.spec.to_dict(),
            "system_sha256": content,
            "code_sha256": code_content(),
        }
        write_text(summary, json.dumps(first, indent=2) + "\n")
        return {}
    if not resume:
        raise CampaignExistsError(
            f"{out} already holds a campaign ({(journal if journal.exists() else summary).name}):"
            " --resume to finish or extend it, or choose another --out"
        )
    saved = read_object(summary, "a campaign's summary", ("spec",))
    try:
        spec = Spec(**saved["spec"])
    except TypeError as exc:
        raise CampaignFileError(f"{summary}: its spec is not one: {exc}") from None
    differences = plan.spec.differences(spec)
    if differences:
        raise CampaignExistsError(
            f"--resume {out}: the campaign there differs: " + "; ".join(differences)
        )
    edited = changed(saved.get("system_sha256") or content, content)
    code = saved.get("code_sha256")
    if isinstance(code, dict):
        edited += code_changed(code)
    if edited:
        raise CampaignExistsError(
            f"--resume {out}: {', '.join(edited)} changed since the campaign began (its "
            "content hash is in campaign.json): its runs and new ones would mix two systems; "
            "choose another --out"
        )
    for key, what in (("system_sha256", "the system"), ("code_sha256", "the code it runs")):
        if key not in saved:
            print(
                f"campaign: {summary} records no content hash of {what} (an older "
                "campaign): not checked",
                file=sys.stderr,
            )
    saved["system_sha256"] = content
    saved.setdefault("code_sha256", code_content())
    # running again (the rest of the last summary, lost workers included, is kept)
    saved.update(status="running", spec=plan.spec.to_dict())
    write_text(summary, json.dumps(saved, indent=2) + "\n")
    # a truncated last line would be glued to the next record: rewrite the journal clean
    records = read_journal(journal)
    write_text(journal, "".join(json.dumps(r) + "\n" for r in records.values()))
    return {i: r for i, r in records.items() if i < plan.total}


def signals_file(plan: Plan, out: Path):
    """The (runs, signals, points) memory map, grown if the campaign was extended."""
    if not plan.signals:
        return None
    path = out / "signals.npy"
    shape = (plan.total, len(plan.signals), plan.points)
    if path.exists():
        old = np.load(path, mmap_mode="r")
        if old.shape[1:] != shape[1:]:
            raise CampaignExistsError(f"{path}: shape {old.shape} does not fit {shape}")
        if old.shape[0] >= shape[0]:  # never shrunk: runs beyond --runs keep their signals
            return np.load(path, mmap_mode="r+")
        data = np.array(old)
        del old
    else:
        data = None
    need, free = 8 * math.prod(shape), shutil.disk_usage(out).free
    if need - (0 if data is None else data.nbytes) > free:
        raise CampaignExistsError(
            f"{path} would take {need / 2**30:.3g} GiB, {free / 2**30:.3g} GiB are free "
            "there: keep fewer signals, or make fewer runs"
        )
    memory = np.lib.format.open_memmap(path, mode="w+", dtype=np.float64, shape=shape)
    filled(path, memory.offset, memory.nbytes)
    if data is not None:
        memory[: len(data)] = data
    return memory


#: bytes of NaN written at once by :func:`filled`
FILL_CHUNK = 2**26


def filled(path: Path, offset: int, size: int) -> None:
    """``size`` bytes of float64 NaN written into ``path`` from ``offset``, by plain
    writes of a block at a time: faster than through a memory map of the file, whose every
    page is first faulted in and zeroed (docs/performance-log.md), and not in this
    process's resident memory."""
    block = np.full(FILL_CHUNK // 8, np.nan).tobytes()
    view = memoryview(block)
    with path.open("r+b") as stream:
        for start in range(0, size, FILL_CHUNK):
            stream.seek(offset + start)
            stream.write(view[: min(FILL_CHUNK, size - start)])


@contextmanager
def cluster(
    workers: int | None = None,
    scheduler: str | None = None,
    listen: str = "127.0.0.1",
    dashboard: str | None = None,
):
    """A ``distributed.Client``: on the cluster at ``scheduler``, or on a LocalCluster of
    ``workers`` single-threaded processes (default: one per core) listening on ``listen``
    (the scheduler, the nannies and the workers; by default loopback only), with a
    dashboard at ``dashboard`` ("host:port") only if asked."""
    import logging

    import dask
    from distributed import Client, LocalCluster

    # the scheduler's HTTP server (health, metrics; no dashboard unless asked) takes
    # another port when Dask's default is taken, and need not say so
    warnings.filterwarnings("ignore", r"Port \d+ is already in use", UserWarning, "distributed")
    quiet_closed_connections()
    INTERRUPTS.deferred = True
    try:
        if scheduler:
            with Client(scheduler, timeout="30s") as client:
                yield client
            return
        with dask.config.set(LOCAL_CLUSTER_CONFIG):
            with _sigint_held():
                local = LocalCluster(
                    n_workers=workers,
                    threads_per_worker=1,
                    processes=True,
                    host=listen,
                    dashboard_address=dashboard,
                    silence_logs=logging.ERROR,
                )
            with local, Client(local) as client:
                yield client
    finally:
        INTERRUPTS.deferred = False


@contextmanager
def _sigint_held():
    """SIGINT blocked in this thread while a LocalCluster starts: the threads and the
    worker processes it starts inherit the block, so a terminal's Ctrl-C as a worker's
    Python starts (before its preload ignores SIGINT) is no KeyboardInterrupt traceback of
    that worker; this process takes one that came meanwhile as it unblocks it.
    multiprocessing's resource tracker is started first: starting it unblocks SIGINT in
    the thread that does (the cluster's, which starts the workers)."""
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()
    before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


def batch_size(run_seconds: float | None, remaining: int, workers: int) -> int:
    """Runs per Dask task: enough that a task lasts about ``BATCH_SECONDS`` (Dask's round
    trip, some 30 ms of CPU in the client, scheduler, worker and nanny, then costs
    about 1.5 %), longer on a large cluster so that the client and scheduler get at most
    ``MAX_TASKS_PER_SECOND``; at most ``MAX_BATCH`` runs (what a dead worker loses and the
    progress bar waits for), and no more than an even share of what is left (the workers
    finish together).  One run per task until a run's duration is known."""
    if not run_seconds:
        return 1
    workers = max(1, workers)
    seconds = max(BATCH_SECONDS, workers / MAX_TASKS_PER_SECOND)
    share = -(-remaining // (IN_FLIGHT_PER_WORKER * workers))
    return max(1, min(round(seconds / run_seconds), MAX_BATCH, share))


def execute(
    plan: Plan, out: Path, client, done: dict, progress, metrics: dict
) -> tuple[dict, list, str]:
    """Run what is not in ``done`` on ``client``; returns (records by index, lost workers,
    "complete" or "interrupted").  Runs go in batches (:func:`batch_size`), each run its
    own record; every run is in the journal as soon as its batch is back; ``metrics``
    ({"metrics": ..., "requirements": ...}) collects each metric's unit, description and
    bound and each requirement's statement (:func:`catalog`)."""
    from distributed import as_completed
    from distributed.client import FutureCancelledError
    from distributed.scheduler import KilledWorker

    records = dict(done)
    signals = signals_file(plan, out)
    magnitudes = Store(out, plan.ensemble, plan.total)
    todo = [i for i in range(plan.total) if i not in records][::-1]  # popped from the end
    watcher = WorkerWatch(client)
    futures = {}  # future -> the indices of its runs
    values = {}  # of the runs in flight (drawn once)
    timed = [0.0, 0]  # seconds and number of the runs made here, for the batch size
    token = uuid.uuid4().hex[:8]  # keys unique on a shared scheduler
    hook = signal_at("run")
    options = plan.run_options()  # each run's values on top (worker.run_batch)

    def submit():
        workers = len(watcher.workers)
        size = batch_size(timed[0] / timed[1] if timed[1] else None, len(todo), workers)
        batch = [todo.pop() for _ in range(min(size, len(todo)))]
        if not batch:
            return None
        for index in batch:
            values[index] = plan.run_values(index)
        future = client.submit(
            run_batch,
            [(index, values[index]) for index in batch],
            plan.target,
            options,
            plan.signals,
            plan.points,
            -(-plan.total // max(1, workers)),  # the runs each worker makes
            key=f"agilesat-runs-{batch[0]}-{len(batch)}-{token}",
            pure=False,
        )
        futures[future] = batch
        return future

    def in_flight():
        return IN_FLIGHT_PER_WORKER * max(1, len(watcher.workers))

    pending = as_completed([f for f in (submit() for _ in range(in_flight())) if f is not None])
    status = "complete"
    try:
        with (out / "runs.jsonl").open("a") as journal:
            for future in _completed(pending):
                batch = futures.pop(future)
                try:
                    made = future.result()
                except FutureCancelledError as exc:  # nothing is cancelled here but on a signal
                    raise SchedulerLost(
                        f"the Dask scheduler {client.scheduler.address} was lost "
                        f"({exc.reason}) with {len(records)} runs made"
                    ) from None
                except KilledWorker as exc:
                    made = [
                        _failed(
                            index,
                            "lost",
                            "every worker that ran it died (Dask gives up "
                            f"after distributed.scheduler.allowed-failures): {exc}",
                        )
                        for index in batch
                    ]
                except Exception as exc:  # the task itself could not run there
                    made = [_failed(i, "error", f"{type(exc).__name__}: {exc}") for i in batch]
                for record in made:
                    index = record["index"]
                    magnitudes.put(index, record.pop("magnitudes", {}))  # before the signals
                    signal = record.pop("signals", None)
                    if signals is not None and signal is not None:
                        signals[index] = signal
                    if "seconds" in record:
                        timed[0] += record["seconds"]
                        timed[1] += 1
                    record.update(
                        seed=plan.spec.seed,
                        values=values.pop(index),
                        grid=index % len(plan.grid),
                        batch=batch[0],  # the first run of its Dask task
                    )
                    if catalog(metrics, record):
                        write_text(out / "metrics.json", json.dumps(metrics, indent=1) + "\n")
                    record["metrics"] = {
                        k: {
                            "value": m["value"],
                            **({"reason": m["reason"]} if "reason" in m else {}),
                        }
                        for k, m in record["metrics"].items()
                    }
                    record["requirements"] = {
                        k: r["verdict"] for k, r in record.get("requirements", {}).items()
                    }
                    journaled(journal, json.dumps(record) + "\n")
                    records[index] = record
                    progress.update(record["status"])
                journaled(journal, "")
                if hook is not None and len(records) - len(done) >= hook[1]:
                    os.kill(os.getpid(), hook[0])  # $AGILESAT_TEST_SIGNAL=SIGNAL@run:K
                    hook = None
                watcher.check(futures)
                # keep IN_FLIGHT_PER_WORKER batches per worker there is now
                while len(futures) < in_flight():
                    nxt = submit()
                    if nxt is None:
                        break
                    pending.add(nxt)
        watcher.check(futures, force=True)  # a worker lost within the last second
    except KeyboardInterrupt:
        status = "interrupted"
        client.cancel(list(futures))
    finally:
        magnitudes.flush()
        if signals is not None:
            signals.flush()
    return records, watcher.lost, status


def journaled(journal, line: str) -> None:
    """``line`` appended to the open journal and flushed; an OSError (a full disk) names
    the file."""
    try:
        journal.write(line)
        journal.flush()
    except OSError as exc:
        raise file_error(Path(journal.name), exc, "; the runs journaled before are kept") from None


def _completed(pending):
    """The futures of ``pending`` (an ``as_completed``) as they complete, until none is
    left; a KeyboardInterrupt within 50 ms of a signal :data:`INTERRUPTS` recorded."""
    while not pending.is_empty():
        if INTERRUPTS.signals:
            raise KeyboardInterrupt
        if pending.has_ready():
            yield next(pending)
        else:
            time.sleep(0.05)


def catalog(known: dict, record: dict) -> bool:
    """Add what a run's summary says of its metrics (unit, display unit, description,
    bound) and requirements (statement, and why not judged) to ``known``; True if any was
    new."""
    metrics = known.setdefault("metrics", {})
    requirements = known.setdefault("requirements", {})
    new = False
    for name, m in record["metrics"].items():
        if name not in metrics:
            drop = ("value", "met", "verdict", "reason")
            metrics[name] = {k: v for k, v in m.items() if k not in drop}
            new = True
    for name, r in record.get("requirements", {}).items():
        if name not in requirements:
            keep = ("statement", "unit", "display_unit", "judged_over")
            requirements[name] = {k: r[k] for k in keep if k in r}
            if r["verdict"] == "not judged":
                requirements[name]["not_judged"] = r.get("reason", "")
            new = True
    return new


def _failed(index: int, status: str, message: str) -> dict:
    return {"index": index, "status": status, "metrics": {}, "requirements": {}, "message": message}


class WorkerWatch:
    """Which workers left while runs were in flight, and which runs they held."""

    def __init__(self, client):
        self.client = client
        self.workers = set(client.scheduler_info()["workers"])
        self.processing = {}
        self.lost = []
        self.last = 0.0

    def check(self, futures: dict, force: bool = False) -> None:
        """Note the workers gone since the last check (at most one a second, unless
        ``force``: the campaign's end, else a worker lost in its last second went
        unsaid)."""
        now = time.monotonic()
        if now - self.last < 1.0 and not force:
            return
        self.last = now
        info = self.client.scheduler_info()
        if "workers" not in info:  # the client has no scheduler any more
            raise SchedulerLost(f"the Dask scheduler {self.client.scheduler.address} was lost")
        workers = set(info["workers"])
        keys = {f.key: batch for f, batch in futures.items()}
        for address in sorted(self.workers - workers):
            held = sorted(i for k in self.processing.get(address, ()) for i in keys.get(k, ()))
            self.lost.append({"worker": address, "runs_in_flight": held})
            print(
                f"campaign: worker {address} left; Dask re-runs the runs it held "
                f"({held or 'none seen in flight'}) on the others",
                file=sys.stderr,
            )
        self.workers = workers
        self.processing = self.client.processing()
