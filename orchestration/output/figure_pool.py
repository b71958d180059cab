"""A run's figures drawn in worker processes while the run is still simulating.

``agilesat run`` spends most of its time on figures when there is a spare core: importing
matplotlib (~0.7 s) and drawing each figure (0.2–0.5 s, Python-bound: one core each).  A
:class:`FigurePool` starts one fresh interpreter when the run starts; it imports
matplotlib, the plots and the scenario's module while the run simulates on the other core,
then waits.  :meth:`FigurePool.draw` sends it the figure function and its arguments
(pickled: the scenario's ``figures(results, out_dir)``).

The worker first runs the figure function once with :data:`.plots.recording` on: each
figure it makes is recorded (a :class:`.plots.Drawing`), not drawn, and anything it draws
itself is drawn then, once.  It then forks into ``processes`` (it is single-threaded: BLAS
threads are off in it, so forking is safe), and they share the recorded figures out,
heaviest first (:attr:`.plots.Drawing.cost`), each taking the next one nobody has taken
(:class:`Claims`): the longest figures do not come last, when the other processes would
wait for them.  The files are the ones the same call writes in one process.

An exception in the figure code is raised in the caller as in one process (a figure's
that failed to draw first, in the order the figure function made them; then the figure
function's own); if the worker cannot be used (it died, or the call cannot be pickled),
the figures are drawn in the calling process instead, with a warning saying why.
"""

from __future__ import annotations

import os
import pickle
import signal
import struct
import subprocess
import sys
import traceback
import warnings

#: environment of the worker: one BLAS thread (a forked process holds only the thread
#: that forked), the non-interactive backend
_ENV = {
    "OPENBLAS_NUM_THREADS": "1",
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "MPLBACKEND": "Agg",
}


#: free cores (cores less the 1-minute load average) a worker needs to pay
FREE_CORES = 0.5
#: the most array data (a run's ``Results.data``) sent to the worker: a longer run's
#: figures are drawn in the calling process (sending copies the rows twice, pickled and
#: in the worker: a 10^6-step run of 100 columns is 800 MB)
MAX_SENT_BYTES = 64 << 20


def processes_for_figures() -> int:
    """Drawing processes worth starting here: $AGILESAT_FIGURE_PROCESSES if set (0: draw
    in the calling process), else the cores this process may use, at most 8, if at least
    :data:`FREE_CORES` of them are idle (as ``make -l`` reads the load average); else 0.
    A worker costs ~0.5 s of CPU more than drawing here (its own interpreter) and only
    pays with a core to draw on: on a saturated machine it slows the run."""
    if os.environ.get("AGILESAT_FIGURE_PROCESSES"):
        return max(0, int(os.environ["AGILESAT_FIGURE_PROCESSES"]))
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        cores = os.cpu_count() or 1
    try:
        free = cores - os.getloadavg()[0]
    except (AttributeError, OSError):  # no load average: assume idle
        free = cores
    return min(cores, 8) if cores >= 2 and free >= FREE_CORES else 0


class FigurePool:
    """One worker interpreter, started now, that draws in ``processes`` processes;
    ``preload``: modules it imports while waiting (the scenario's)."""

    def __init__(self, processes: int, preload: tuple[str, ...] = ()):
        self.processes, self.sent = processes, False
        self.worker = subprocess.Popen(
            [sys.executable, "-m", __name__, str(processes), *preload],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            env={**os.environ, **_ENV},
        )

    def draw(self, function, *args):
        """``function(*args)`` (it draws figures with :mod:`.plots` and returns their
        paths), its figures drawn by the worker's processes (here if the arguments hold
        more than :data:`MAX_SENT_BYTES` of array data)."""
        from . import plots

        if sum(getattr(getattr(a, "data", None), "nbytes", 0) for a in args) > MAX_SENT_BYTES:
            self.close()
            return function(*args)
        try:  # with the formats this process writes
            job = pickle.dumps((plots.written(), function, args), protocol=pickle.HIGHEST_PROTOCOL)
        except Exception as exc:  # noqa: BLE001 - a closure, an open file: draw here
            return self._here(f"the figure call cannot be sent to it ({exc})", function, args)
        self.sent = True
        try:
            self.worker.stdin.write(job)
            self.worker.stdin.close()
            status, value = pickle.load(self.worker.stdout)
        except (OSError, EOFError, pickle.UnpicklingError) as exc:
            return self._here(f"it stopped ({exc!r}, exit status {self.close()})", function, args)
        if status == "error":
            raise value
        return value

    def _here(self, why: str, function, args):
        warnings.warn(
            f"figures drawn in this process: the figure worker failed: {why}", stacklevel=3
        )
        self.close()
        return function(*args)

    def __enter__(self) -> FigurePool:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> int | None:
        """Stop the worker (at once if it was sent nothing: the run failed or was
        interrupted); its exit status."""
        if not self.sent:
            self.worker.kill()
        if self.worker.stdin and not self.worker.stdin.closed:
            try:
                self.worker.stdin.close()
            except OSError:
                pass
        try:
            return self.worker.wait(timeout=60)
        except subprocess.TimeoutExpired:
            self.worker.kill()
            return self.worker.wait()
        finally:
            self.worker.stdout.close()


class Claims:
    """Figures shared out among forked processes as they go: each process walks through
    the same figures in the same order and draws figure k if no process has taken it.  A
    pipe holds the index of the first figure nobody has taken: reading it takes the lock,
    writing it back releases it."""

    def __init__(self):
        self._read, self._write = os.pipe()
        os.write(self._write, struct.pack("q", 0))
        self.seen = 0

    def __call__(self) -> bool:
        k, self.seen = self.seen, self.seen + 1
        (first,) = struct.unpack("q", os.read(self._read, 8))
        take = k >= first
        os.write(self._write, struct.pack("q", k + 1 if take else first))
        return take


def _record(function, args) -> tuple[tuple, list]:
    """Run ``function(*args)`` once with :data:`.plots.recording` on: (("ok", its value)
    or ("error", its exception), the figures it made, not drawn)."""
    from . import plots

    plots.recording = drawings = []
    try:
        return ("ok", function(*args)), drawings
    except Exception as exc:  # noqa: BLE001 - reported to the caller
        return ("error", _error_of(exc)), drawings
    finally:
        plots.recording = None


def heaviest_first(drawings) -> list[int]:
    """The indices of the drawings by falling :attr:`.plots.Drawing.cost` (ties in the
    order they were made)."""
    return sorted(range(len(drawings)), key=lambda k: drawings[k].cost, reverse=True)


def _draw_taken(drawings, order, claims) -> list[tuple[int, BaseException]]:
    """Draw, in ``order``, each drawing no other process has taken; (index, exception)
    of those that failed (the others are drawn still)."""
    failures = []
    for k in order:
        if claims():
            try:
                drawings[k]()
            except Exception as exc:  # noqa: BLE001 - reported to the caller
                failures.append((k, _error_of(exc)))
    return failures


def _error_of(exc: BaseException):
    """The exception if it pickles and unpickles (raised as it is in the caller: a class
    whose ``__init__`` takes other arguments than its ``args`` does not), else its
    traceback."""
    try:
        pickle.loads(pickle.dumps(exc))
        return exc
    except Exception:  # noqa: BLE001
        return RuntimeError("".join(traceback.format_exception(exc)))


def _serve(processes: int, reply) -> None:
    """The worker: read one job from stdin, draw it in ``processes`` processes, reply on
    ``reply`` (the original stdout)."""
    data = sys.stdin.buffer.read()
    if not data:  # the run ended without figures
        return
    formats, function, args = pickle.loads(data)
    from . import plots

    with plots.written_as(formats):
        result = _draw(processes, function, args)
    pickle.dump(result, reply, protocol=pickle.HIGHEST_PROTOCOL)
    reply.close()


def _draw(processes: int, function, args) -> tuple:
    """Record ``function(*args)``, draw its figures in ``processes`` processes (this one
    and forks); ("ok", its value) or ("error", the exception to raise)."""
    result, drawings = _record(function, args)
    order, claims = heaviest_first(drawings), Claims()
    children = []
    sys.stdout.flush()
    sys.stderr.flush()
    for _ in range(min(processes, len(drawings)) - 1):
        read, write = os.pipe()
        try:
            pid = os.fork()
        except OSError:  # no process to be had (EAGAIN, ENOMEM): draw in those there are
            os.close(read), os.close(write)
            break
        if pid == 0:
            os.close(read)
            code = 0
            try:
                failures = _draw_taken(drawings, order, claims)
            except BaseException as exc:  # noqa: BLE001 - reported to the caller
                failures, code = [(len(drawings), _error_of(exc))], 1
            try:
                with os.fdopen(write, "wb") as stream:
                    pickle.dump(failures, stream)
            finally:
                os._exit(code)
        os.close(write)
        children.append((pid, read))
    failures = _draw_taken(drawings, order, claims)
    died = None
    for pid, read in children:
        with os.fdopen(read, "rb") as stream:
            said = stream.read()
        _, status = os.waitpid(pid, 0)
        if said:
            failures += pickle.loads(said)
        elif status != 0:
            died = RuntimeError(f"a figure process died ({_status(status)})")
    if failures:  # the first in the figure function's order, as in one process
        result = ("error", min(failures, key=lambda failure: failure[0])[1])
    elif died is not None:
        result = ("error", died)
    return result


def _status(status: int) -> str:
    if os.WIFSIGNALED(status):
        return f"signal {signal.Signals(os.WTERMSIG(status)).name}"
    return f"exit status {os.WEXITSTATUS(status)}"


if __name__ == "__main__":
    # Ctrl-C reaches the whole process group: the run decides (it closes our input)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # the reply has stdout to itself: whatever else prints (an import too) goes to stderr
    reply = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    import importlib
    import io

    from matplotlib.figure import Figure

    from ..cosim import fmu  # noqa: F401 - what a pickled run's Results refers to
    from . import plots

    # matplotlib, its fonts and every format's backend, while the run simulates
    axes = Figure().subplots()
    axes.plot([0.0, 1.0], label="warm-up")
    axes.legend()
    for suffix in plots.FORMATS:
        axes.figure.savefig(io.BytesIO(), format=suffix[1:])
    for module in sys.argv[2:]:
        importlib.import_module(module)
    _serve(int(sys.argv[1]), reply)
    # done (every file written and closed): no interpreter teardown, which takes ~0.2 s
    # with matplotlib loaded and which the run waits for (FigurePool.close)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)
