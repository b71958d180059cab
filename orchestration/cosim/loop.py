"""The master's macro-step loop compiled (``loop.c``), with the Python loop as fall-back.

:class:`Program` turns a run's schedule into the FMI calls of one macro step, in the order
the Python loop of :mod:`.master` makes them (fmpy's bound functions, the component
pointers, value references, buffers and places in the value vector); :func:`run` has the
C loop run them chunk by chunk (at most :data:`BUDGET` seconds or up to the next progress
report each), records each chunk's rows, reports progress and looks at the signal flag
between chunks, and raises the same :class:`FmiCallError` as the Python loop (through
``Instance.check``) after recording the rows before the failing step.  The results are the
Python loop's bit for bit (same calls, same arithmetic, no FMA contraction).

``loop.c`` is compiled at first use with the C compiler the FMU build uses
(:func:`components.runtime.toolchain.c_compiler`) into a cache keyed by the source, the
compiler, its flags, the machine and the Python version (in ``loop/`` of
:func:`components.runtime.cache.cache_root`;
written under a temporary name and renamed, so that processes may compile at once, with its
SHA-256 beside it, checked before it is loaded: a damaged one is compiled again with a
warning, ``components/runtime/cache.py``), and loaded with ``ctypes.PyDLL``, holding the GIL:
the loop measured the same as through ``CDLL`` (tests/tools/benchmark_master_loop.py;
pythonfmu takes the GIL at every call into a slave either way), and :func:`csv_text` needs
it (it formats the CSV lines with CPython's own ``repr`` of a float, a third faster than in
Python).  Derivative links (:mod:`.derivatives`) are operations of the loop too.
``loop="auto"`` (the default, or ``$AGILESAT_LOOP``) falls back to the Python loop with a
note in the run's log when the compiled one is not available; ``"compiled"`` raises
:class:`LoopUnavailable` naming why; ``"python"`` never compiles.
"""

from __future__ import annotations

import ctypes
import hashlib
import platform
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np

from ...components.runtime.cache import cache_root, damage_of_file, warn, write_digest
from ...components.runtime.switches import value as switch
from ...components.runtime.toolchain import c_compiler, replacing
from .fmu import Log

LOOPS = ("auto", "compiled", "python")
SOURCE = Path(__file__).with_name("loop.c")
FLAGS = ("-shared", "-fPIC", "-O2", "-ffp-contract=off")
BUDGET = 0.005  # seconds of one chunk: Ctrl-C, progress and the CSV stay this close
_KINDS = {"SetReal": 0, "GetReal": 1, "SetInteger": 2, "GetInteger": 3}
_KINDS.update(SetBoolean=2, GetBoolean=3)  # fmi2Boolean is an int, as fmi2Integer
SET_REAL, DO_STEP, AT_STEP, AT_READ = 0, 4, 1, 2
GET_DERIVATIVES, SET_DERIVATIVES, SET_PREVIOUS, KEEP_PREVIOUS = 5, 6, 7, 8


class LoopUnavailable(RuntimeError):
    """The compiled loop cannot run here (says why)."""


class Operation(ctypes.Structure):
    _fields_ = [
        ("kind", ctypes.c_int32),
        ("when", ctypes.c_int32),
        ("every", ctypes.c_int64),
        ("function", ctypes.c_void_p),
        ("component", ctypes.c_void_p),
        ("vrs", ctypes.c_void_p),
        ("n", ctypes.c_int64),
        ("index", ctypes.c_void_p),
        ("buffer", ctypes.c_void_p),
        ("h", ctypes.c_double),
        ("orders", ctypes.c_void_p),
        ("slopes", ctypes.c_void_p),
        ("previous", ctypes.c_void_p),
        ("interpolated", ctypes.c_void_p),
    ]


class ClockLog(Log):
    """A :class:`Log` whose time is a C double, which the compiled loop sets to t_n at
    each step (the FMUs' messages are stamped with it, as with the Python loop)."""

    def __init__(self, echo=None):
        self.clock = ctypes.c_double(0.0)
        super().__init__(echo)

    @property
    def time(self) -> float:
        return self.clock.value

    @time.setter
    def time(self, value: float) -> None:
        self.clock.value = value


def choose(loop: str | None) -> str:
    """The loop asked for: ``loop``, else $AGILESAT_LOOP, else "auto"."""
    chosen = loop or switch("AGILESAT_LOOP") or "auto"
    if chosen not in LOOPS:
        raise ValueError(f"loop must be one of {LOOPS} (or $AGILESAT_LOOP), got {chosen!r}")
    return chosen


_DLL = ctypes.PyDLL  # holding the GIL, which csv_text needs
_loaded: dict[Path, ctypes.CDLL] = {}
_lock = threading.Lock()


def library(source: Path = SOURCE) -> ctypes.CDLL:
    """The compiled loop (compiled into the cache at first use), or LoopUnavailable."""
    compiler = c_compiler()
    if not compiler:
        raise LoopUnavailable("no C compiler (cc or gcc on the PATH, or set CC)")
    code = source.read_bytes()
    key = hashlib.sha256(
        b"\0".join(
            [code, compiler.encode(), " ".join(FLAGS).encode(), b"with its SHA-256"]
            + [s.encode() for s in (sys.platform, platform.machine(), sys.implementation.cache_tag)]
        )
    ).hexdigest()[:16]
    path = cache_root() / "loop" / f"agilesat_loop_{key}.so"
    with _lock:
        if path not in _loaded:
            if path.exists() and (what := damage_of_file(path)):
                warn(path, what, "compiling it again")
                try:
                    path.unlink()
                except OSError as exc:
                    why = f"{path} is damaged and cannot be replaced: {exc}"
                    raise LoopUnavailable(why) from None
            if not path.exists():
                _compile(compiler, source, path)
            try:
                dll = _DLL(str(path))
            except OSError as exc:
                raise LoopUnavailable(f"{path} does not load: {exc}") from None
            function = dll.agilesat_loop
            function.restype = ctypes.c_int64
            function.argtypes = [ctypes.c_void_p, ctypes.c_int64, ctypes.c_void_p]
            function.argtypes += [ctypes.c_int64, ctypes.c_double, ctypes.c_double]
            function.argtypes += [ctypes.c_int64, ctypes.c_int64, ctypes.c_double]
            function.argtypes += [ctypes.c_void_p] * 3
            dll.agilesat_csv.restype = ctypes.c_int64
            dll.agilesat_csv.argtypes = [ctypes.c_void_p, ctypes.c_int64, ctypes.c_int64]
            dll.agilesat_csv.argtypes += [ctypes.c_void_p, ctypes.c_int64]
            _loaded[path] = dll
        return _loaded[path]


def _compile(compiler: str, source: Path, path: Path) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with replacing(path) as partial:
            command = [compiler, *FLAGS, "-o", str(partial), str(source)]
            result = subprocess.run(command, capture_output=True, text=True)
            if result.returncode != 0:
                said = (result.stderr.strip().splitlines() or ["no message"])[-1]
                raise LoopUnavailable(f"compiling {source} with {compiler} failed: {said}")
            write_digest(path, partial)  # checked before every load
    except OSError as exc:
        raise LoopUnavailable(f"cannot compile {source} into {path.parent}: {exc}") from None


def select(loop: str, log: Log):
    """The compiled loop for a run, or None: the Python loop (with a note in the log when
    the compiled one was asked for by "auto" and is not available)."""
    if loop == "python":
        return None
    try:
        return library()
    except LoopUnavailable as exc:
        if loop == "compiled":
            raise
        log.add("master", 0, "master", f"the Python loop runs this: {exc}")
        return None


class Program:
    """The FMI calls of one macro step (:mod:`.master`'s loop, step 3), for ``loop.c``;
    ``calls[k]`` is (instance, FMI call) of operation k, to raise its error.  ``links``:
    the run's :class:`.derivatives.Derivatives`, or None."""

    def __init__(
        self, algorithm: str, nodes: dict, sequence: list, reads: list, step: float, links=None
    ):
        entries: list[dict] = []  # the fields of each Operation, with instance and call

        def ports(node, chosen, when):
            for port in chosen:
                entries.append(
                    dict(_port(port), kind=_KINDS[port.call[4:]], when=when, every=node.every)
                )

        def do_step(node):
            entries.append(
                dict(
                    kind=DO_STEP,
                    when=AT_STEP,
                    every=node.every,
                    instance=node.instance,
                    call="fmi2DoStep",
                    h=step * node.every,
                )
            )

        def step_linked(node, when):
            """couple(), the step, restore() (:mod:`.derivatives`; every == 1)."""
            consumer = None if links is None else links.consumers.get(node.instance.name)
            if consumer is not None and consumer.interpolated.any():
                entries.append(_previous(consumer, SET_PREVIOUS, links))
            if consumer is not None:
                entries.append(_derivatives(consumer, SET_DERIVATIVES, links, step))
            do_step(node)
            if consumer is not None and consumer.interpolated.any() and when & AT_READ:
                entries.append(_previous(consumer, SET_REAL, links))

        if links is not None and links.interpolating:
            entries.append(
                dict(
                    kind=KEEP_PREVIOUS,
                    every=1,
                    n=len(links.previous),
                    previous=links.previous.ctypes.data,
                )
            )
        if algorithm == "jacobi":
            for node in nodes.values():
                ports(node, node.inputs, AT_STEP)
                step_linked(node, AT_STEP)
            for node, chosen, feeds in reads:
                if feeds:
                    ports(node, node.inputs, AT_READ)
                ports(node, chosen, AT_READ)
        else:  # gauss-seidel: a node steps at its first block
            for node, chosen, first in sequence:
                when = (AT_STEP | AT_READ) if first else AT_READ
                ports(node, node.inputs, when)
                if first:
                    step_linked(node, when)
                ports(node, chosen, AT_READ)
        for source in [] if links is None else links.sources:
            entries.append(_derivatives(source, GET_DERIVATIVES, links))
        self.ops = (Operation * len(entries))()
        self.calls = [(entry.get("instance"), entry.get("call")) for entry in entries]
        self._keep = [entry.pop("keep", None) for entry in entries]  # arrays pointed into
        for op, entry in zip(self.ops, entries):
            instance = entry.pop("instance", None)
            if instance is not None:
                op.component = instance.component
                op.function = _address(
                    entry.pop("function", None) or getattr(instance, entry["call"])
                )
            entry.pop("call", None)
            for field, value in entry.items():
                setattr(op, field, value)


def _address(function) -> int | None:
    return ctypes.cast(function, ctypes.c_void_p).value


def _port(port) -> dict:
    index = np.ascontiguousarray(port.index, dtype=np.int64)
    return dict(
        instance=port.instance,
        call=port.call,
        function=port.function,
        vrs=ctypes.addressof(port.vrs),
        n=port.n,
        index=index.ctypes.data,
        buffer=port.buffer.ctypes.data,
        keep=index,
    )


def _derivatives(slopes, kind: int, links, step: float = 0.0) -> dict:
    """Get (an :class:`.derivatives._OutputSlopes`) or set (an ``_InputSlopes``) of
    output/input derivatives."""
    index = np.ascontiguousarray(slopes.index, dtype=np.int64)
    interpolated = np.ascontiguousarray(getattr(slopes, "interpolated", []), dtype=np.uint8)
    call = (
        "fmi2GetRealOutputDerivatives" if kind == GET_DERIVATIVES else "fmi2SetRealInputDerivatives"
    )
    return dict(
        kind=kind,
        every=1,
        instance=slopes.instance,
        call=call,
        function=getattr(slopes.instance.slave.dll, call),
        vrs=ctypes.addressof(slopes.vrs),
        n=slopes.n,
        index=index.ctypes.data,
        buffer=slopes.buffer.ctypes.data,
        h=step,
        orders=ctypes.addressof(slopes.orders),
        slopes=links.slopes.ctypes.data,
        previous=links.previous.ctypes.data,
        interpolated=interpolated.ctypes.data,
        keep=(index, interpolated),
    )


def _previous(consumer, kind: int, links) -> dict:
    """fmi2SetReal of a consumer's interpolated inputs: their values at t_n (SET_PREVIOUS,
    before the step) or their newest (SET_REAL, after it)."""
    index = np.ascontiguousarray(consumer.index[consumer.interpolated], dtype=np.int64)
    return dict(
        kind=kind,
        every=1,
        instance=consumer.instance,
        call="fmi2SetReal",
        function=consumer.instance.slave.dll.fmi2SetReal,
        vrs=ctypes.addressof(consumer.at_start),
        n=len(index),
        index=index.ctypes.data,
        buffer=consumer.start_buffer.ctypes.data,
        previous=links.previous.ctypes.data,
        keep=index,
    )


def run(dll, program: Program, plan, values, recorder, signals, log: ClockLog) -> None:
    """Steps 0 .. n_steps - 1 of a :class:`.plan.RunPlan` in chunks, as the Python loop of
    :mod:`.master` runs them."""
    start, step, n_steps, progress = plan.start, plan.step, plan.n_steps, plan.progress
    report_every = max(1, n_steps // 100) if progress else n_steps  # a chunk ends there
    width = len(values) + 1
    rows = np.empty((max(1, min(report_every, 1024, (1 << 22) // (8 * width))), width))
    failure = (ctypes.c_int64 * 2)()
    text = ctypes.create_string_buffer(rows.size * 25) if recorder.out_dir is not None else None
    pointers = [ctypes.addressof(program.ops), values.ctypes.data, rows.ctypes.data]
    clock = ctypes.addressof(log.clock)
    n = 0
    while n < n_steps:
        if signals.signal is not None:
            return
        last = min(n_steps, n + len(rows), (n // report_every + 1) * report_every)
        failure[0] = -1
        done = dll.agilesat_loop(
            pointers[0],
            len(program.ops),
            pointers[1],
            len(values),
            start,
            step,
            n,
            last,
            BUDGET,
            pointers[2],
            clock,
            failure,
        )
        if done:
            lines = None if text is None else csv_text(dll, rows[:done], text)
            recorder.append_block(rows[:done], lines)
        n += done
        if failure[0] >= 0:
            instance, call = program.calls[failure[0]]
            assert instance is not None  # only KEEP_PREVIOUS has none, and it cannot fail
            instance.check(int(failure[1]), call)
        if progress and n % report_every == 0:
            progress(n, n_steps)
    log.time = start + n_steps * step


def csv_text(dll, rows: np.ndarray, out) -> bytes | None:
    """The CSV lines of rows (C-contiguous float64) as the recorder writes them, formatted
    in C by CPython's repr of a float, into ``out`` (25 bytes per value); None if it
    does not fit."""
    used = dll.agilesat_csv(rows.ctypes.data, len(rows), rows.shape[1], out, len(out))
    return None if used < 0 else ctypes.string_at(out, used)
