"""Compiled kernels: the models' own hot functions, compiled by numba once a run is long.

A hot loop of a model is written once, as a plain Python function on floats and tuples, in
the model's module, with its equations; ``@kernel`` marks it and ``@jitable`` the plain
functions it calls.  A kernel runs that Python for its first ``AGILESAT_JIT_AFTER`` calls
(default 50,000), then the same function compiled by numba in nopython
mode without fastmath: IEEE double arithmetic in the order written, the same libm, so the
results are those of the Python bit for bit (tests/fast_paths/test_kernels_models.py) and
switching midway
changes nothing.  The threshold is measured, not guessed: importing numba and loading the
compiled kernels costs about a second per process, which the kernels win back only after
tens of thousands of calls (docs/performance.md); short runs never import numba, long runs
and campaign workers do.  ``AGILESAT_JIT=0`` (or numba not installed) keeps the Python;
``AGILESAT_JIT_AFTER=0`` compiles at the first call.  ``kernel.py_func`` is the Python,
``kernel.compiled`` the compiled function (the Python without numba, or where numba cannot
compile the kernel: it then says so in a warning at the switch).

A kernel works on a model's whole value array and a state array of its own: it reads them
through :func:`floats` (in its Python a list of Python floats, which index and compute
several times faster than NumPy scalars; compiled, the array itself) at the offsets the
tables name (:mod:`.flat`: ``values[U.tau_cmd]``, ``state[S.omega + k]``), and writes
into them.

Compile cache.  numba's own cache (``cache=True``) is keyed on the source file's path and
modification time (numba/core/caching.py, ``_SourceFileBackedLocatorMixin``,
``get_suitable_cache_subpath``), and FMI hosts unpack an FMU into a new temporary folder
each time: every load would compile again (seconds per FMU).  Our locator keys it on
content instead: ``<root>/numba/<key>/``, key = SHA-256 of the module's name and of every
``.py`` file beside its source and below (the kernel and everything it calls from its
package and the runtime),
root = :func:`cache_root` (the master's compiled loop is kept there too).  Inside
an FMU the module is ``agilesat_<content hash>.components.<name>``, so a rebuilt FMU gets
new entries and two extractions of one FMU share them; ``agilesat build`` fills the cache
by loading each built FMU once (``fmus/build.py``).  Every index and data file carries
its SHA-256 (:mod:`.cache`): a damaged one is compiled again, with a warning,
instead of being unpickled or loaded.  numba's index key adds the
signature, the CPU and the bytecode.  An unwritable cache directory costs a compile per
process, nothing else (a warning says so).

The kernel convention.  A model whose ``step`` or ``output`` is, but for ``t``, one kernel
on its value array and a float64 state array, ``(values, state, t, dt) -> status`` (t: the
model's time at the step's start) or ``(values, state, t) -> status``, declares it with
``@step_kernel(Model)`` / ``@output_kernel(Model)``;
a model whose step changes nothing but ``t`` says ``STATELESS = True``.  Status 0: the
kernel did everything the method does; anything else: the method has more to do (raise
or warn with the readable message, a case the Python handles), so a caller that ran the
kernel alone puts the arrays back and calls the method.  Everything the kernel changes
lives in the two arrays (a flag the method warns from, too).  The FMU derives C functions
from the declared kernels (fmus/c_entries.py) and steps the model in C once they run
compiled; a model declaring nothing is stepped by its methods, as any.
"""

from __future__ import annotations

import functools
import hashlib
import io
import pickle
import sys
import warnings
from pathlib import Path

import numpy as np

from .cache import cache_root, seal, unseal, warn
from .switches import value

ENABLED = value("AGILESAT_JIT")
#: calls of a kernel before it is compiled (see the module docstring)
AFTER = value("AGILESAT_JIT_AFTER")
#: the runs this process expects to make of each model (a campaign worker's share)
RUNS = value("AGILESAT_JIT_RUNS")
#: the calls a process must be expected to make of kernels whose compiled code is cached
#: for them to run compiled from a run's start: importing numba and loading the kernels
#: costs about 0.75 s per process, a macro step in C saves 180-260 µs of a shipped
#: scenario's (break-even at 2,900-4,200 steps; docs/performance-log.md)
PAYS_AFTER = 3_500
_JITABLE: list = []  # functions kernels may call
_FLOATS: list = []  # to-floats converters, the identity on tuples in a kernel
_TWINS: list = []  # (function, the factory of its compiled twin)
_REGISTERED: set = set()  # those of them numba was told about
_SET_UP = False  # numba imported (then a function declared later is registered at once)
#: a kernel has switched to its compiled tier in this process (a long run)
compiled_tier = False


@functools.cache
def content_key(module: str, source: str) -> str:
    """SHA-256 of the module name and of the ``.py`` files in the source's directory and
    below it (the models' package and the runtime their kernels call)."""
    digest = hashlib.sha256(module.encode() + b"\0")
    folder = Path(source).resolve().parent
    for path in sorted(folder.rglob("*.py")):
        name = path.relative_to(folder).as_posix()
        digest.update(name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:24]


def jitable(function):
    """A plain function that kernels may call (unchanged for Python callers)."""
    _JITABLE.append(function)
    if _SET_UP:  # a module imported after the first compile
        _set_up()
    return function


def compiled_twin(factory):
    """Decorator: a function kernels may call whose compiled form is not its Python but
    ``factory(numba)``, a numba intrinsic of the same signature (a call through a C
    function pointer, which no Python is); its Python is the decorated function, which
    must compute the same bits."""

    def register(function):
        _TWINS.append((function, factory))
        if _SET_UP:
            _set_up()
        return function

    return register


def register_floats(function) -> None:
    """Let kernels call ``function`` (a to-floats converter) on tuples and arrays, as the
    identity."""
    _FLOATS.append(function)
    if _SET_UP:
        _set_up()


def floats(x):
    """``x.tolist()`` for an ndarray, else ``x``; in a compiled kernel the identity (on
    tuples and arrays)."""
    return x.tolist() if isinstance(x, np.ndarray) else x


register_floats(floats)


class Kernel:
    """A hot function: its Python for the first ``after`` calls, then compiled."""

    def __init__(self, function, after: int):
        functools.update_wrapper(self, function)
        self.py_func = function
        self._left = after
        self.calls = 0  # of its Python, counted (the compiled tier counts nothing)
        self._run = self._count if ENABLED else function

    def __call__(self, *args):
        return self._run(*args)

    def _count(self, *args):
        self._left -= 1
        self.calls += 1
        if self._left < 0:
            return self._switch(*args)
        return self.py_func(*args)

    def _switch(self, *args):
        """The first compiled call.  A kernel numba cannot compile here (another numba
        version, say: ``agilesat build`` compiles every kernel, so ours do with the
        numba they were built with) keeps running its Python, with a warning."""
        if self.compiled is self.py_func:  # without numba
            self._run = self.py_func
            return self.py_func(*args)
        from numba.core.errors import NumbaError

        try:
            result = self.compiled(*args)
        except NumbaError as exc:
            said = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
            warnings.warn(
                f"agilesat: {self.py_func.__qualname__} could not be compiled "
                f"({type(exc).__name__}: {said}); its Python runs",
                stacklevel=3,
            )
            self.__dict__["compiled"] = self._run = self.py_func
            return self.py_func(*args)
        global compiled_tier
        self._run, compiled_tier = self.compiled, True
        return result

    @functools.cached_property
    def compiled(self):
        """numba's compiled function (with our cache), or the Python without numba."""
        numba = _numba()
        if numba is None:
            return self.py_func
        dispatcher = numba.njit(self.py_func)
        try:
            dispatcher._cache = content_cache(self.py_func)  # what enable_caching() does
        except (OSError, RuntimeError, AttributeError) as exc:  # AttributeError: API moved
            warnings.warn(
                f"agilesat: no compile cache for {self.py_func.__qualname__} ({exc}): "
                "compiling it in every process",
                stacklevel=2,
            )
        return dispatcher


def expect(module, steps: float) -> None:
    """A run of the model of ``module`` expects ``steps`` more steps (an FMU at its first
    step: its stop time and step size).  With the calls its kernels (those it declared:
    not a metric's, :func:`expect_rows`) made in this process
    before (a notebook's earlier runs) and RUNS runs (a campaign worker's), the calls
    expected of them; they switch to compiled now where that pays: from PAYS_AFTER calls
    when their compiled code is cached, from AFTER otherwise (compiling costs seconds a
    kernel).  Either way the results are the same bits."""
    found = [
        kernel
        for model, roles in _DECLARED.items()
        if model.__module__ == module.__name__
        for kernel in roles.values()
    ]
    _expect(found, steps)


def expect_rows(kernel: Kernel, rows: int) -> None:
    """``kernel`` is about to loop over ``rows`` rows of a run's history at once (a
    metric's): the rows count as :func:`expect` counts a model's steps."""
    _expect([kernel], rows)


def _expect(found, steps: float) -> None:
    if not ENABLED or not found:
        return
    expected = steps * max(RUNS, 1) + max(kernel.calls for kernel in found)
    if expected < min(PAYS_AFTER, AFTER):
        return
    if expected >= AFTER or all(map(cached, found)):
        for kernel in found:
            kernel._left = min(kernel._left, 0)


def cached(kernel: Kernel) -> bool:
    """Is the kernel's compiled code in the compile cache (for this Python)?  Looked up by
    the name numba gives its index (``<module>.<qualname>-<line>.pyXY.nbi``) in the
    content-keyed folder, without importing numba."""
    code = kernel.py_func.__code__
    folder = cache_root() / "numba" / content_key(kernel.py_func.__module__, code.co_filename)
    major, minor = sys.version_info[:2]
    name = f"{kernel.py_func.__module__.rsplit('.', 1)[-1]}.{kernel.py_func.__qualname__}"
    return (folder / f"{name}-{code.co_firstlineno}.py{major}{minor}.nbi").is_file()


def runs_compiled(kernel: Kernel) -> bool:
    """Has ``kernel`` switched to its compiled tier (with numba)?"""
    compiled = kernel.__dict__.get("compiled")
    return compiled is not None and kernel._run is compiled is not kernel.py_func


def kernel(function) -> Kernel:
    return Kernel(function, AFTER)


_DECLARED: dict[type, dict[str, Kernel]] = {}


def step_kernel(model: type):
    """Decorator: the kernel ``(values, state, t, dt) -> status`` is ``model``'s step
    (module docstring, "The kernel convention")."""
    return lambda function: _declare(model, "step", function)


def output_kernel(model: type):
    """Decorator: the kernel ``(values, state, t) -> status`` is ``model``'s output."""
    return lambda function: _declare(model, "output", function)


def _declare(model: type, role: str, function) -> Kernel:
    declared = kernel(function)
    _DECLARED.setdefault(model, {})[role] = declared
    return declared


def declared(model: type) -> tuple[Kernel | None, Kernel | None]:
    """(step kernel, output kernel) that ``model`` declared (None: none)."""
    roles = _DECLARED.get(model, {})
    return roles.get("step"), roles.get("output")


def kernels(module) -> dict[str, Kernel]:
    """{name: kernel} of a module."""
    return {name: obj for name, obj in vars(module).items() if isinstance(obj, Kernel)}


@functools.cache
def _numba():
    """numba, imported and told about our jitable functions at the first compile."""
    global _SET_UP
    if not ENABLED:
        return None
    try:
        import numba
    except ImportError:
        return None
    _SET_UP = True
    _set_up()
    return numba


def _set_up() -> None:
    """Register every jitable function and converter with numba (each once)."""
    import numba
    from numba.extending import overload, register_jitable

    def identity(x):
        if isinstance(x, (numba.types.BaseTuple, numba.types.Array)):
            return lambda x: x
        return None

    for function in _FLOATS:
        if function not in _REGISTERED:
            _REGISTERED.add(function)
            overload(function)(identity)
    for function in _JITABLE:
        if function not in _REGISTERED:
            _REGISTERED.add(function)
            register_jitable(function)
    for function, factory in _TWINS:
        if function not in _REGISTERED:
            _REGISTERED.add(function)
            twin = factory(numba)
            overload(function, strict=False)(lambda *args, twin=twin: lambda *args: twin(*args))


def content_cache(py_func):
    """numba's cache of ``py_func``, keyed on content (module docstring)."""
    return _content_cache_class()(py_func)


@functools.cache
def _content_cache_class():
    """numba's FunctionCache with a locator keyed on content (numba.core.caching)."""
    from numba.core import caching

    class ContentLocator(caching._CacheLocator):
        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._key = content_key(py_func.__module__, py_file)

        def get_cache_path(self):
            return str(cache_root() / "numba" / self._key)

        def get_source_stamp(self):
            return self._key

        def get_disambiguator(self):
            return str(self._lineno)

        @classmethod
        def from_function(cls, py_func, py_file):
            locator = cls(py_func, py_file)
            locator.ensure_cache_path()  # OSError: not writable
            return locator

    class ContentCacheImpl(caching.CompileResultCacheImpl):
        _locator_classes = [ContentLocator]

    class SealedCacheFile(caching.IndexDataCacheFile):
        """numba's index and data files, each sealed with its SHA-256 (:mod:`.cache`): a
        damaged one is compiled again with a warning, never unpickled or loaded."""

        def _load_index(self):
            try:
                with open(self._index_path, "rb") as stream:
                    body = unseal(stream.read())
            except FileNotFoundError:
                return {}
            if body is None:
                warn(self._index_path, "it does not match its SHA-256", "compiling again")
                return {}
            stream = io.BytesIO(body)
            if pickle.load(stream) != self._version:
                return {}
            stamp, overloads = pickle.loads(stream.read())
            return overloads if stamp == self._source_stamp else {}

        def _save_index(self, overloads):
            body = pickle.dumps(self._version, protocol=-1)
            body += self._dump((self._source_stamp, overloads))
            with self._open_for_write(self._index_path) as stream:
                stream.write(seal(body))

        def _load_data(self, name):
            path = self._data_path(name)
            with open(path, "rb") as stream:
                body = unseal(stream.read())
            if body is None:
                warn(path, "it does not match its SHA-256", "compiling again")
                raise OSError(f"{path} is damaged")  # numba's load: compile again
            return pickle.loads(body)

        def _save_data(self, name, data):
            with self._open_for_write(self._data_path(name)) as stream:
                stream.write(seal(self._dump(data)))

    class ContentCache(caching.FunctionCache):
        _impl_class = ContentCacheImpl

        def __init__(self, py_func):
            super().__init__(py_func)
            self._cache_file = SealedCacheFile(
                self._cache_path, self._impl.filename_base, self._impl.locator.get_source_stamp()
            )

    return ContentCache
