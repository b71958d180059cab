"""A model's C entries: its step and output kernels (components/runtime/jit.py, "The kernel
convention") as C functions, for the shim's C step path (``fast_paths.py``).

A step entry is ``int32 (double *values, int64 n_values, double *state, int64 n_state,
double t, double dt)``, an output entry the same without ``dt``: a numba ``cfunc`` that
calls the kernel's compiled function on the two arrays (t: the model's time) and returns
its status: 0 when it did everything the
method does but advance ``t``, anything else to leave the call to the method (which then
raises or warns with the readable message).  The same machine code as the compiled kernel,
no second copy of the physics.  An FMU built by ``agilesat build`` carries them compiled
ahead of time (``native.py``): they exist from the first call.  Else an entry exists once
its kernel has switched to its compiled tier (``address`` is None before, and without
numba).  An exception inside (a
``ZeroDivisionError`` under numba's Python error model) is caught and returns -1, so the
caller falls back to the Python, which raises it with its message (numba's cfunc wrapper
would only print it and return an undefined value).  The cfuncs are cached beside the
kernels (jit.py, "Compile cache"), under the kernel's module, name and line.
"""

from __future__ import annotations

import functools
import warnings
from typing import NamedTuple

from ..components.runtime import jit
from . import native


class CEntry:
    """A step or output kernel as a C function (module docstring)."""

    def __init__(self, kernel: jit.Kernel, role: str, native: int | None = None):
        self.kernel = kernel
        self.role = role  # "step" or "output"
        self._address = native  # the FMU's library's (native.py), from the first call

    @property
    def address(self) -> int | None:
        """The C function's address: the FMU's ahead-of-time library's, else numba's once
        the kernel runs compiled, else None."""
        if self._address is None and jit.runs_compiled(self.kernel):
            self._address = self._cfunc.address
        return self._address

    @functools.cached_property
    def _cfunc(self):
        return cfunc(self.kernel, self.role, self.kernel.compiled, cache=True)


def cfunc(kernel: jit.Kernel, role: str, compiled, cache: bool):
    """The numba ``cfunc`` of ``role`` calling ``compiled`` (the kernel's compiled
    function), compiled now; ``cache``: with the compile cache (jit.py)."""
    numba = jit._numba()
    from numba.core.ccallback import CFunc

    py_func, name = kernel.py_func, kernel.__name__ + "_c"
    template = _step_template if role == "step" else _output_template
    names = {"co_name": name}
    if hasattr(template.__code__, "co_qualname"):  # Python 3.11 on
        names["co_qualname"] = kernel.__qualname__ + "_c"
    code = template.__code__.replace(
        co_filename=py_func.__code__.co_filename,
        co_firstlineno=py_func.__code__.co_firstlineno,
        **names,
    )
    namespace = {"__name__": py_func.__module__, "carray": numba.carray, "kernel": compiled}
    entry = type(template)(code, namespace, name)
    entry.__module__ = py_func.__module__
    compiling = CFunc(entry, signature(numba, role), locals={}, options={})
    if cache:
        try:
            compiling._cache = jit.content_cache(entry)
        except (OSError, RuntimeError, AttributeError) as exc:
            warnings.warn(
                f"agilesat: no compile cache for {name} ({exc}): compiling it in every process",
                stacklevel=2,
            )
    compiling.compile()
    return compiling


def _step_template(values, n_values, state, n_state, t, dt):
    """The body of every step entry (``kernel`` and ``carray`` are its globals)."""
    try:
        return kernel(carray(values, n_values), carray(state, n_state), t, dt)  # noqa: F821
    except Exception:  # noqa: BLE001 - the caller runs the Python, which raises it
        return -1


def _output_template(values, n_values, state, n_state, t):
    """The body of every output entry (``kernel`` and ``carray`` are its globals)."""
    try:
        return kernel(carray(values, n_values), carray(state, n_state), t)  # noqa: F821
    except Exception:  # noqa: BLE001 - the caller runs the Python, which raises it
        return -1


def signature(numba, role: str) -> tuple:
    """(argument types, return type) of a C entry of ``role`` ("step" or "output")."""
    double, double_p = numba.types.float64, numba.types.CPointer(numba.types.float64)
    i64 = numba.types.int64
    times = (double, double) if role == "step" else (double,)
    return (double_p, i64, double_p, i64, *times), numba.types.int32


class Entries(NamedTuple):
    """A model's C entries: step and output (None: the method's), whether its step
    changes nothing but ``t`` (``STATELESS``), and whether they are the FMU's library's
    (``native.py``: compiled from the first call)."""

    step: CEntry | None
    output: CEntry | None
    stateless: bool
    native: bool = False

    @property
    def any(self) -> bool:
        return bool(self.step or self.output or self.stateless)


@functools.cache
def of(model_class) -> Entries:
    """The C entries of ``model_class`` (one per kernel and process)."""
    step, output = jit.declared(model_class)
    found = native.entries(model_class) if step or output else {}
    return Entries(
        CEntry(step, "step", found.get("step")) if step else None,
        CEntry(output, "output", found.get("output")) if output else None,
        bool(getattr(model_class, "STATELESS", False)),
        bool(found),
    )
