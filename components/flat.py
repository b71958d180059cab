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
def quat_of_rows(c00, c01, c02, c10, c11, c12, c20, c21, c22):
    """q (scalar first, q0 ≥ 0) of the rotation matrix with rows (c00, c01, c02), ...:
    Shepperd's method, the largest of 1 + trace, 1 + 2 c_kk − trace chosen (the first on a
    tie), as :func:`.rotations.quat_from_dcm`, bit for bit (tests/test_kernels_models.py)."""
    trace = c00 + c11 + c22
    k, largest = 0, trace
    for j, c in ((1, c00), (2, c11), (3, c22)):
        if c > largest:
            k, largest = j, c
    if k == 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = (0.25 * s, (c12 - c21) / s, (c20 - c02) / s, (c01 - c10) / s)
    elif k == 1:
        s = 2.0 * math.sqrt(1.0 + 2 * c00 - trace)
        q = ((c12 - c21) / s, 0.25 * s, (c01 + c10) / s, (c02 + c20) / s)
    elif k == 2:
        s = 2.0 * math.sqrt(1.0 + 2 * c11 - trace)
        q = ((c20 - c02) / s, (c01 + c10) / s, 0.25 * s, (c12 + c21) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + 2 * c22 - trace)
        q = ((c01 - c10) / s, (c02 + c20) / s, (c12 + c21) / s, 0.25 * s)
    norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    sign = -1.0 if q[0] < 0.0 else 1.0
    return (sign * q[0] / norm, sign * q[1] / norm, sign * q[2] / norm, sign * q[3] / norm)


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
