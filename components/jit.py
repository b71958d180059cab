"""Compiled kernels: the models' own hot functions, compiled by numba where it is installed.

A hot loop of a model is written once, as a plain Python function on floats and tuples, in
the model's module, with its equations; ``@kernel`` marks it and ``@jitable`` the plain
functions it calls.  With numba importable (and ``AGILESAT_JIT`` not ``0``) a kernel is
that same function compiled by numba in nopython mode without fastmath: IEEE double
arithmetic in the order written, the same libm, so its results are those of the Python
(bit for bit, tested in tests/test_kernels.py); otherwise it is the function itself.
``kernel.py_func`` is always the readable Python.  ``@jitable`` leaves the function as it
is for Python callers (``numba.extending.register_jitable``).

Compile cache.  numba's own cache (``cache=True``) is keyed on the source file's path and
modification time (numba/core/caching.py, ``_SourceFileBackedLocatorMixin``,
``get_suitable_cache_subpath``), and FMI hosts unpack an FMU into a new temporary folder
each time: every load would compile again (seconds per FMU).  Our locator keys it on
content instead: ``<root>/<key>/``, key = SHA-256 of the module's name and of every
``.py`` file beside its source (the kernel and everything it calls from its package),
root = ``AGILESAT_CACHE_DIR`` or ``$XDG_CACHE_HOME/agilesat/numba`` (``~/.cache``).  Inside
an FMU the module is ``agilesat_<content hash>.components.<name>``, so a rebuilt FMU gets
new entries and two extractions of one FMU share them; ``agilesat build`` fills the cache
by loading each built FMU once (``fmus/build.py``).  numba's index key adds the
signature, the CPU and the bytecode.  An unwritable cache directory costs a compile per
process, nothing else (a warning says so).
"""

from __future__ import annotations

import functools
import hashlib
import os
import warnings
from pathlib import Path

ENABLED = os.environ.get("AGILESAT_JIT", "1") != "0"

try:
    if not ENABLED:
        raise ImportError("AGILESAT_JIT=0")
    import numba
    from numba.core import caching as _caching
    from numba.extending import overload as _overload
    from numba.extending import register_jitable as _register_jitable
except ImportError:
    numba = None  # type: ignore[assignment]
    ENABLED = False


def cache_root() -> Path:
    """Where compiled kernels are kept (see the module docstring)."""
    root = os.environ.get("AGILESAT_CACHE_DIR")
    if root:
        return Path(root)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base, "agilesat", "numba")


@functools.cache
def content_key(module: str, source: str) -> str:
    """SHA-256 of the module name and of the ``.py`` files in the source's directory."""
    digest = hashlib.sha256(module.encode() + b"\0")
    for path in sorted(Path(source).resolve().parent.glob("*.py")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:24]


def jitable(function):
    """A plain function that kernels may call (unchanged for Python callers)."""
    return _register_jitable(function) if ENABLED else function


def kernel(function):
    """``function`` compiled (nopython, no fastmath, content-keyed cache) or itself."""
    if not ENABLED:
        return function
    dispatcher = numba.njit(function)
    try:
        dispatcher._cache = _ContentCache(function)  # what enable_caching() does
    except (OSError, RuntimeError, NameError) as exc:  # NameError: numba's API moved
        warnings.warn(
            f"agilesat: no compile cache for {function.__qualname__} ({exc}): "
            "compiling it in every process",
            stacklevel=2,
        )
    return dispatcher


def kernels(module) -> dict:
    """{name: compiled kernel} of a module (empty without numba)."""
    if not ENABLED:
        return {}
    return {
        name: obj
        for name, obj in vars(module).items()
        if isinstance(obj, numba.core.registry.CPUDispatcher)
    }


if ENABLED and hasattr(_caching, "_CacheLocator") and hasattr(_caching, "FunctionCache"):

    class _ContentLocator(_caching._CacheLocator):
        """numba cache locator keyed on content, not on path and mtime."""

        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._key = content_key(py_func.__module__, py_file)

        def get_cache_path(self):
            return str(cache_root() / self._key)

        def get_source_stamp(self):
            return self._key

        def get_disambiguator(self):
            return str(self._lineno)

        @classmethod
        def from_function(cls, py_func, py_file):
            locator = cls(py_func, py_file)
            locator.ensure_cache_path()  # OSError: not writable
            return locator

    class _ContentCacheImpl(_caching.CompileResultCacheImpl):
        _locator_classes = [_ContentLocator]

    class _ContentCache(_caching.FunctionCache):
        _impl_class = _ContentCacheImpl


if ENABLED:

    def _identity_for_sequences(x):
        """``rotations._floats`` (ndarray -> list) is the identity on tuples in a kernel."""
        if isinstance(x, numba.types.BaseTuple):
            return lambda x: x
        return None

    def register_floats(function) -> None:
        """Let kernels call ``function`` (a to-floats converter) on tuples."""
        _overload(function)(_identity_for_sequences)

else:

    def register_floats(function) -> None:
        del function
