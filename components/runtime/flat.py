"""The flat arrays of the models' kernels (:mod:`.jit`), reached by name, and compilable
equivalents of CPython functions numba lacks or computes otherwise, bit for bit
(tests/fast_paths/test_kernels_models.py): ``math.remainder``, ``math.fmod``,
``math.hypot``.

A kernel is one function on the model's value array (parameters, inputs and outputs at the
offsets of its variable table, components/variables.py) and a small float64 state array of
the model; it reads both through :func:`.jit.floats`, writes outputs and state by index and
returns a status code, from which the model's Python wrapper raises its ModelError or
issues its warning, so that the messages are those of the readable code.

It reaches every place by name, as the Modelica Reference-FMUs' ``M(x)`` macro does: the
offsets are integer constants generated from the tables, one namespace per table
(:func:`offsets`): ``values[U.tau_cmd + 1]`` is input ``tau_cmd[2]``, ``state[S.omega + k]``
row ``omega`` of the state table, element k.  A namespace is a module object: numba reads
a module's attribute as a constant (``U.tau_cmd`` compiles to the same machine code as the
literal offset), CPython with one specialised module attribute access more than a global
(the kernels' Python within a few percent of hand-written constants:
docs/performance-log.md).  :func:`state_table` lays out a state array as the variable table
lays out the value array: named rows, one after the other.
"""

from __future__ import annotations

import math
import types

import numpy as np

from .jit import jitable


def offsets(label: str, at: dict[str, int]) -> types.ModuleType:
    """A namespace of integer constants, ``at``'s names (module docstring); ``label`` says
    whose in messages ('Flywheel inputs')."""
    namespace = types.ModuleType(label)
    for name, offset in at.items():
        if not name.isidentifier() or hasattr(namespace, name):
            raise ValueError(f"{label}: {name!r} cannot be a name of an offset")
        setattr(namespace, name, int(offset))
    return namespace


def relative(namespace: types.ModuleType, origin: int) -> types.ModuleType:
    """``namespace``'s offsets less ``origin``: the places in a slice of the array that
    starts there (a kernel that converts only its inputs, ``values[U.tau_cmd : ...]``)."""
    return offsets(
        f"{namespace.__name__} from {origin}",
        {name: at - origin for name, at in vars(namespace).items() if type(at) is int},
    )


def state_table(label: str, **sizes: int) -> types.ModuleType:
    """A kernel's state array: named rows of the given sizes, one after the other; the
    namespace of their offsets (:func:`offsets`), with ``size`` the array's length,
    ``zeros()`` a new state array and ``at(base)`` the namespace of the same rows in a copy
    of the table that starts at ``base`` of a larger one (so no row may be called ``size``,
    ``zeros`` or ``at``)."""
    if {"size", "zeros", "at"} & set(sizes):
        raise ValueError(f"{label}: a state row cannot be called size, zeros or at")
    start, rows = 0, {}
    for name, size in sizes.items():
        rows[name] = start
        start += size
    size = start
    table = offsets(label, {**rows, "size": size})
    vars(table).update(
        zeros=lambda: np.zeros(size),
        at=lambda base: offsets(f"{label} at {base}", {n: base + r for n, r in rows.items()}),
    )
    return table


@jitable
def vector(a, at: int) -> tuple:
    """The 3-vector at ``at`` of a flat array (``vector(v, U.w_BI_B)``)."""
    return a[at], a[at + 1], a[at + 2]


@jitable
def quaternion(a, at: int) -> tuple:
    """The 4-vector at ``at`` of a flat array."""
    return a[at], a[at + 1], a[at + 2], a[at + 3]


@jitable
def matrix(a, at: int) -> tuple:
    """The row-major 3×3 at ``at`` of a flat array, as a tuple of rows."""
    return vector(a, at), vector(a, at + 3), vector(a, at + 6)


@jitable
def all_zero(a, start: int, stop: int) -> bool:
    """Whether a[start:stop] are all zero (−0.0 is, NaN is not) of an array: a check that
    must cost little where nothing is connected (NumPy's count in C)."""
    return np.count_nonzero(a[start:stop]) == 0


@jitable
def put(array, at: int, x) -> None:
    """array[at : at + len(x)] = x."""
    for i in range(len(x)):
        array[at + i] = x[i]


@jitable
def remainder(x: float, y: float) -> float:
    """IEEE 754 remainder x − n y, n the integer nearest x / y (even on a tie): CPython's
    ``math.remainder`` (Modules/mathmodule.c, m_remainder) step for step, which numba does
    not provide.  Every step is exact (``%`` of non-negative numbers is fmod)."""
    if math.isfinite(x) and math.isfinite(y):
        if y == 0.0:
            return math.nan
        absx, absy = abs(x), abs(y)
        m = absx % absy
        c = absy - m
        if m < c:
            r = m
        elif m > c:
            r = -c
        else:  # half-way: n is even
            r = m - 2.0 * ((0.5 * (absx - m)) % absy)
        return math.copysign(1.0, x) * r
    if math.isnan(x):
        return x
    if math.isnan(y):
        return y
    if math.isinf(x):
        return math.nan
    return x


@jitable
def fmod(x: float, y: float) -> float:
    """C's ``fmod`` (``math.fmod``), which numba does not provide: x − n y with n = x / y
    truncated, exact; |x| % |y| of non-negative numbers is fmod, the sign is x's.  NaN
    where ``math.fmod`` raises (x infinite, y zero)."""
    if math.isnan(x) or math.isnan(y) or math.isinf(x) or y == 0.0:
        return math.nan
    if math.isinf(y):
        return x
    return math.copysign(abs(x) % abs(y), x)


@jitable
def hypot(x: float, y: float) -> float:
    """CPython's ``math.hypot(x, y)`` (Modules/mathmodule.c, vector_norm: lossless scaling
    by a power of two, exact squares, compensated sum, one differential correction of the
    square root) step for step, which numba computes with the C library's hypot instead
    (1 ulp apart at times).  The exact squares are Dekker's product (``_two_product``),
    which gives the error term CPython takes from ``fma``."""
    x, y = abs(x), abs(y)
    biggest = 0.0
    for v in (x, y):
        if v > biggest:
            biggest = v
    if math.isinf(biggest):
        return biggest
    if math.isnan(x) or math.isnan(y):
        return math.nan
    if biggest == 0.0:
        return biggest
    if math.frexp(biggest)[1] < -1023:  # 2**-e would overflow: divided by the largest
        csum, frac = 1.0, 0.0
        for v in (x, y):
            v /= biggest
            v *= v
            total = csum + v
            frac += (csum - total) + v
            csum = total
        return biggest * math.sqrt(csum - 1.0 + frac)
    return _vector_norm(x, y, biggest)


_SPLITTER = 134217729.0  # 2**27 + 1: Veltkamp's split of a double into two halves


@jitable
def _two_product(a: float, b: float) -> tuple[float, float]:
    """(a b rounded, its exact error) by Dekker's product (no fma)."""
    p = a * b
    c = _SPLITTER * a
    a_hi = c - (c - a)
    a_lo = a - a_hi
    c = _SPLITTER * b
    b_hi = c - (c - b)
    b_lo = b - b_hi
    return p, ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo


@jitable
def _vector_norm(x: float, y: float, biggest: float) -> float:
    scale = math.ldexp(1.0, -math.frexp(biggest)[1])
    csum, frac1, frac2 = 1.0, 0.0, 0.0
    for v in (x, y):
        v *= scale  # lossless
        hi, lo = _two_product(v, v)  # lossless squaring
        total = csum + hi  # lossless addition (|csum| >= |hi|)
        frac2 += (csum - total) + hi
        csum = total
        frac1 += lo
    h = math.sqrt(csum - 1.0 + (frac1 + frac2))
    hi, lo = _two_product(-h, h)
    total = csum + hi
    frac2 += (csum - total) + hi
    csum = total
    frac1 += lo
    h += (csum - 1.0 + (frac1 + frac2)) / (2.0 * h)  # differential correction
    return h / scale
