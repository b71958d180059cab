"""The master's macro-step loop: one program of FMI calls, run by C (``loop.c``) or Python.

:class:`Program` turns a run's schedule into the operations of one macro step (fmpy's bound
FMI functions, the component pointers, value references, buffers and places in the value
vector; :mod:`.master`'s docstring, step 3), once; ``loop.c`` runs them, and where it
cannot, the Python loop runs the same operations (:meth:`Op.python`: ``loop.c``'s
arithmetic, the results bit for bit).  :func:`run` has either run them chunk by chunk (at
most :data:`BUDGET` seconds or up to the next progress report each), records each chunk's
rows, reports progress and looks at the signal flag between chunks, and raises the
failing call's :class:`FmiCallError` (through ``Instance.check``) after recording the rows
before the failing step.

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
import functools
import hashlib
import platform
import subprocess
import sys
import threading
import time
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
#: the operations (loop.c's enum) and when an operation of a multi-rate component is due
SET_REAL, GET_REAL, SET_INTEGER, GET_INTEGER, DO_STEP = 0, 1, 2, 3, 4
GET_DERIVATIVES, SET_DERIVATIVES, SET_PREVIOUS, KEEP_PREVIOUS = 5, 6, 7, 8
AT_STEP, AT_READ = 1, 2
AT_START = 4  # only at the run's first step (:func:`_drop_repeated_sets`)
_KINDS = {"SetReal": SET_REAL, "GetReal": GET_REAL, "SetInteger": SET_INTEGER}
_KINDS.update(GetInteger=GET_INTEGER)
_KINDS.update(SetBoolean=SET_INTEGER, GetBoolean=GET_INTEGER)  # an fmi2Boolean is an int


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


class Op:
    """One operation of a macro step: the fields of ``loop.c``'s ``struct operation``, as
    Python objects (the buffers and value-reference arrays it points into), and the
    instance and FMI call it is (to raise its error)."""

    def __init__(self, kind: int, every: int = 1, when: int = AT_STEP | AT_READ, **fields):
        self.kind, self.every, self.when = kind, every, when
        self.instance = fields.pop("instance", None)
        self.call: str | None = fields.pop("call", None)
        self.function = fields.pop("function", None)
        self.vrs = fields.pop("vrs", None)  # ctypes array of value references
        index = fields.pop("index", None)  # places in the value vector
        self.index = None if index is None else np.ascontiguousarray(index, dtype=np.int64)
        self.buffer: np.ndarray | None = fields.pop("buffer", None)
        self.h: float = fields.pop("h", 0.0)
        self.orders = fields.pop("orders", None)
        self.slopes: np.ndarray | None = fields.pop("slopes", None)
        self.previous: np.ndarray | None = fields.pop("previous", None)
        interpolated = fields.pop("interpolated", None)
        self.interpolated = (
            None if interpolated is None else np.ascontiguousarray(interpolated, dtype=np.uint8)
        )
        self.n: int = fields.pop("n", 0 if self.index is None else len(self.index))
        assert not fields, fields

    def due(self, n: int) -> bool:
        """Whether it runs at step n (``loop.c``'s ``due``)."""
        if self.when == AT_START:
            return n == 0
        if self.every == 1:
            return True
        stepping = bool(self.when & AT_STEP) and n % self.every == 0
        return stepping or bool(self.when & AT_READ) and (n + 1) % self.every == 0

    def struct(self) -> dict:
        """Its ``struct operation`` fields (addresses of what it points into; those it has
        not stay null)."""
        fields: dict[str, object] = dict(
            kind=self.kind, when=self.when, every=self.every, n=self.n, h=self.h
        )
        if self.instance is not None:
            fields.update(component=self.instance.component, function=_address(self.function))
        for name in ("vrs", "orders"):
            if getattr(self, name) is not None:
                fields[name] = ctypes.addressof(getattr(self, name))
        for name in ("index", "buffer", "slopes", "previous", "interpolated"):
            if getattr(self, name) is not None:
                fields[name] = getattr(self, name).ctypes.data
        return fields

    def python(self):
        """The operation in Python: a function (values, t) -> its FMI status, with
        ``loop.c``'s ``run`` arithmetic (the same results, bit for bit)."""
        kind, function, vrs, n, index = self.kind, self.function, self.vrs, self.n, self.index
        component = None if self.instance is None else self.instance.component
        buffer, slopes, previous, h = self.buffer, self.slopes, self.previous, self.h
        if kind == KEEP_PREVIOUS:
            assert previous is not None

            def keep(values, t):
                previous[:n] = values[:n]
                return 0

            return keep
        if kind == DO_STEP:
            return lambda values, t: function(component, t, h, 1)
        assert buffer is not None
        pointer = buffer.ctypes.data_as(ctypes.POINTER(_CTYPES[buffer.dtype.char]))
        where = _where(index)
        if kind in (SET_REAL, SET_INTEGER, SET_PREVIOUS):
            source = previous if kind == SET_PREVIOUS else None

            def put(values, t):
                np.take(values if source is None else source, index, out=buffer)
                return function(component, vrs, n, pointer)

            return put
        if kind in (GET_REAL, GET_INTEGER):

            def get(values, t):
                status = function(component, vrs, n, pointer)
                if status <= 1:
                    values[where] = buffer
                return status

            return get
        orders = self.orders
        assert slopes is not None
        if kind == GET_DERIVATIVES:

            def get_slopes(values, t):
                status = function(component, vrs, n, orders, pointer)
                if status <= 1:
                    slopes[where] = buffer
                return status

            return get_slopes
        assert kind == SET_DERIVATIVES and previous is not None
        assert index is not None and self.interpolated is not None
        inner = self.interpolated.astype(bool)
        moved = index[inner] if inner.any() else None

        def set_slopes(values, t):
            np.take(slopes, index, out=buffer)
            if moved is not None:
                buffer[inner] = (values[moved] - previous[moved]) / h
            return function(component, vrs, n, orders, pointer)

        return set_slopes


_CTYPES = {"d": ctypes.c_double, "i": ctypes.c_int}


def _where(index: np.ndarray):
    """A slice for contiguous places (a faster scatter), else the places."""
    if len(index) and np.array_equal(index, np.arange(index[0], index[0] + len(index))):
        return slice(int(index[0]), int(index[0]) + len(index))
    return index


def _address(function) -> int | None:
    return ctypes.cast(function, ctypes.c_void_p).value


class Program:
    """The FMI calls of one macro step (:mod:`.master`'s docstring, step 3), written once:
    ``loop.c`` runs them (``ops``, a ``struct operation`` array) and so does the Python
    loop (:meth:`python_chunk`).  ``steps``: each :class:`Op`, whose instance and call
    name an error.  :meth:`macro_step` builds it from a run's schedule."""

    def __init__(self, steps: list[Op]):
        self.steps = steps

    @functools.cached_property
    def ops(self) -> ctypes.Array:
        """The operations as ``loop.c``'s ``struct operation`` array."""
        ops = (Operation * len(self.steps))()
        for op, step in zip(ops, self.steps):
            for field, value in step.struct().items():
                setattr(op, field, value)
        return ops

    @classmethod
    def macro_step(
        cls, algorithm: str, nodes: dict, sequence: list, reads: list, step: float, links=None
    ) -> Program:
        """Gauss-Seidel: block by block in ``sequence``, each FMU stepping at its first
        block; Jacobi: every FMU steps (in ``nodes``' order), then the blocks of ``reads``
        are read.  ``links``: the run's :class:`.derivatives.Derivatives`, or None."""
        steps: list[Op] = []

        def ports(node, chosen, when):
            steps.extend(_port(port, node.every, when) for port in chosen)

        def step_linked(node, when):
            """The input derivatives, the step, the interpolated inputs set back to
            t_{n+1} (:mod:`.derivatives`; every == 1)."""
            consumer = None if links is None else links.consumers.get(node.instance.name)
            if consumer is not None and consumer.interpolated.any():
                steps.append(_previous(consumer, SET_PREVIOUS, links))
            if consumer is not None:
                steps.append(_derivatives(consumer, SET_DERIVATIVES, links, step))
            steps.append(
                Op(
                    DO_STEP,
                    node.every,
                    AT_STEP,
                    instance=node.instance,
                    call="fmi2DoStep",
                    function=node.instance.fmi2DoStep,
                    h=step * node.every,
                )
            )
            if consumer is not None and consumer.interpolated.any() and when & AT_READ:
                steps.append(_previous(consumer, SET_REAL, links))

        if links is not None and links.interpolating:
            steps.append(Op(KEEP_PREVIOUS, n=len(links.previous), previous=links.previous))
        if algorithm == "jacobi":
            for node in nodes.values():
                ports(node, node.inputs, AT_STEP)
                step_linked(node, AT_STEP)
            for node, chosen, feeds in reads:
                if feeds:
                    ports(node, node.inputs, AT_READ)
                ports(node, chosen, AT_READ)
            _drop_repeated_sets(steps)
        else:  # gauss-seidel: a node steps at its first block
            for node, chosen, first in sequence:
                when = (AT_STEP | AT_READ) if first else AT_READ
                ports(node, node.inputs, when)
                if first:
                    step_linked(node, when)
                ports(node, chosen, AT_READ)
        for source in [] if links is None else links.sources:
            steps.append(_derivatives(source, GET_DERIVATIVES, links))
        return cls(steps)

    @functools.cached_property
    def _python(self) -> list:
        """(the operation in Python, due at every step?, the operation) of each (made when
        the Python loop first runs the program)."""
        return [
            (step.python(), step.every == 1 and step.when != AT_START, step) for step in self.steps
        ]

    def python(self, values: np.ndarray, n: int, t: float) -> tuple[int, int]:
        """Run step n (at t) in Python: (-1, 0), or at the first call that returns more
        than fmi2Warning (the index of its operation, its status)."""
        for k, (action, always, op) in enumerate(self._python):
            if always or op.due(n):
                status = action(values, t)
                if status > 1:
                    return k, status
        return -1, 0

    def python_chunk(
        self, start: float, step: float, first: int, last: int, budget: float, rows, values, log
    ):
        """``loop.c``'s ``agilesat_loop`` in Python: steps first .. last - 1, their rows
        into ``rows``; (steps completed, failure: (operation, status) or None)."""
        began = time.perf_counter()
        for n in range(first, last):
            t = start + n * step
            log.time = t
            k, status = self.python(values, n, t)
            if k >= 0:
                return n - first, (k, status)
            row = rows[n - first]
            row[0] = start + (n + 1) * step
            row[1:] = values
            if time.perf_counter() - began >= budget:
                return n + 1 - first, None
        return last - first, None

    def raise_failure(self, k: int, status: int) -> None:
        """The FmiCallError of operation k's ``status`` (:meth:`Instance.check`)."""
        op = self.steps[k]
        assert op.instance is not None  # only KEEP_PREVIOUS has none, and it cannot fail
        op.instance.check(status, op.call)


def _drop_repeated_sets(steps: list[Op]) -> None:
    """Jacobi sets a feedthrough FMU's inputs after the steps (to read its outputs at
    t_{n+1}) and again before its next step, from the same places of the value vector.
    Where nothing in between writes one of those places (a get after the first set, or
    before the second: its inputs' sources are all read before it) or does anything else
    to those inputs (its step, which may move an input, input derivatives), the second set
    would give the FMU the values it already has: it is made due at the run's first step
    only (AT_START; the first set has not run then).  Only sets due at every step."""
    for at, op in enumerate(steps):
        if op.kind not in (SET_REAL, SET_INTEGER) or op.every != 1 or op.when != AT_STEP:
            continue
        same = [
            k
            for k, other in enumerate(steps)
            if k > at
            and other.kind == op.kind
            and other.every == 1
            and other.instance is op.instance
            and other.vrs is op.vrs
            and other.index is not None
            and op.index is not None
            and np.array_equal(other.index, op.index)
        ]
        if same and not any(_touches(other, op) for other in steps[same[-1] + 1 :] + steps[:at]):
            op.when = AT_START


def _places(op: Op) -> set:
    """The places of the value vector ``op`` reads or writes."""
    return set() if op.index is None else set(op.index.tolist())


def _touches(other: Op, op: Op) -> bool:
    """Could ``other``, run between two sets ``op``, change what the second one sets or
    what the FMU holds of it?"""
    if other.kind in (GET_REAL, GET_INTEGER):  # writes the value vector
        return bool(_places(op) & _places(other))
    if other.instance is not op.instance:
        return False
    if other.kind in (SET_REAL, SET_INTEGER):  # its other ports
        return bool(set(op.vrs) & set(other.vrs))
    return True  # its step or its input derivatives


def _port(port, every: int, when: int) -> Op:
    return Op(
        _KINDS[port.call[4:]],
        every,
        when,
        instance=port.instance,
        call=port.call,
        function=port.function,
        vrs=port.vrs,
        index=port.index,
        buffer=port.buffer,
    )


def _derivatives(slopes, kind: int, links, step: float = 0.0) -> Op:
    """Get (an :class:`.derivatives._OutputSlopes`) or set (an ``_InputSlopes``) of
    output/input derivatives."""
    call = (
        "fmi2GetRealOutputDerivatives" if kind == GET_DERIVATIVES else "fmi2SetRealInputDerivatives"
    )
    return Op(
        kind,
        instance=slopes.instance,
        call=call,
        function=getattr(slopes.instance.slave.dll, call),
        vrs=slopes.vrs,
        index=slopes.index,
        buffer=slopes.buffer,
        h=step,
        orders=slopes.orders,
        slopes=links.slopes,
        previous=links.previous,
        interpolated=getattr(slopes, "interpolated", ()),
    )


def _previous(consumer, kind: int, links) -> Op:
    """fmi2SetReal of a consumer's interpolated inputs: their values at t_n (SET_PREVIOUS,
    before the step) or their newest (SET_REAL, after it)."""
    return Op(
        kind,
        instance=consumer.instance,
        call="fmi2SetReal",
        function=consumer.instance.slave.dll.fmi2SetReal,
        vrs=consumer.at_start,
        index=consumer.index[consumer.interpolated],
        buffer=consumer.start_buffer,
        previous=links.previous,
    )


def run(dll, program: Program, plan, values, recorder, signals, log: ClockLog) -> None:
    """Steps 0 .. n_steps - 1 of a :class:`.plan.RunPlan` in chunks: by ``loop.c`` (``dll``),
    or by the Python loop (``dll`` None: :meth:`Program.python_chunk`)."""
    start, step, n_steps, progress = plan.start, plan.step, plan.n_steps, plan.progress
    report_every = max(1, n_steps // 100) if progress else n_steps  # a chunk ends there
    width = len(values) + 1
    rows = np.empty((max(1, min(report_every, 1024, (1 << 22) // (8 * width))), width))
    compiled = dll is not None
    text = ctypes.create_string_buffer(rows.size * 25) if recorder.out_dir and compiled else None
    failure = (ctypes.c_int64 * 2)()
    pointers = [ctypes.addressof(program.ops), values.ctypes.data, rows.ctypes.data]
    clock = ctypes.addressof(log.clock)

    def chunk(n: int, last: int):
        if not compiled:
            return program.python_chunk(start, step, n, last, BUDGET, rows, values, log)
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
        return done, None if failure[0] < 0 else (failure[0], failure[1])

    n = 0
    while n < n_steps:
        if signals.signal is not None:
            return
        done, failed = chunk(n, min(n_steps, n + len(rows), (n // report_every + 1) * report_every))
        if done:
            lines = None if text is None else csv_text(dll, rows[:done], text)
            recorder.append_block(rows[:done], lines)
        n += done
        if failed is not None:
            program.raise_failure(int(failed[0]), int(failed[1]))
        if progress and n % report_every == 0:
            progress(n, n_steps)
    log.time = start + n_steps * step


def csv_text(dll, rows: np.ndarray, out) -> bytes | None:
    """The CSV lines of rows (C-contiguous float64) as the recorder writes them, formatted
    in C by CPython's repr of a float, into ``out`` (25 bytes per value); None if it
    does not fit."""
    used = dll.agilesat_csv(rows.ctypes.data, len(rows), rows.shape[1], out, len(out))
    return None if used < 0 else ctypes.string_at(out, used)
