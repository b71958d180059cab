"""Compilable equivalents of CPython functions numba lacks or computes otherwise, bit for
bit (tests/test_kernels_models.py), for the models' step/output kernels.

Those kernels (components/jit.py) are one function each on the model's value array
(:mod:`.variables`: parameters, inputs, outputs at the offsets of its table, named by
module constants) and a small float64 state array of the model; they read both through
:func:`.jit.floats`, write outputs and state by index and return a status code, from
which the model's Python wrapper raises its ModelError or issues its warning, so that the
messages are those of the readable code.
"""

from __future__ import annotations

import math

from .jit import jitable


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
