"""The flat arrays of the models' step/output kernels (components/jit.py), and compilable
equivalents of CPython functions numba lacks or computes otherwise, bit for bit
(tests/test_kernels_models.py).

Those kernels are one function each on the model's value array (:mod:`.variables`:
parameters, inputs, outputs at the offsets of its table, named by module constants) and a
small float64 state array of the model, laid out by a :class:`StateTable`; they read both
through :func:`.jit.floats`, write outputs and state by index and return a status code,
from which the model's Python wrapper raises its ModelError or issues its warning, so that
the messages are those of the readable code.
"""

from __future__ import annotations

import math

import numpy as np

from .jit import jitable


class StateTable:
    """A kernel's state array: named rows of given sizes, one after the other, as the
    variable table lays out the value array.  ``offsets`` in row order (the kernels' module
    constants), ``offset[name]``, ``size``; ``zeros()`` a state array."""

    def __init__(self, **sizes: int):
        self.offset: dict[str, int] = {}
        at = 0
        for name, size in sizes.items():
            self.offset[name] = at
            at += size
        self.offsets = tuple(self.offset.values())
        self.size = at

    def zeros(self) -> np.ndarray:
        return np.zeros(self.size)


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
