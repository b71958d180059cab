"""Counter-based random numbers: a pure function of (seed, stream, index), no generator state.

The sensor models draw their noise from this module so that a run is reproducible from an
Integer ``seed`` parameter alone: the n-th number of a stream is computed from (seed,
stream, n) directly, never from a generator object that would have to be stored in the FMU
state.  So the FMU state is plain data, a restored state continues bit for bit, and a
sensor with its own sample rate draws sample k's noise from index k whatever the master's
step size.

Generator: SplitMix64 [Steele 2014], whose n-th output for the state s is a bijective
64-bit mix of s + n γ (γ = 0x9E3779B97F4A7C15, the golden ratio in 64 bits)::

    mix(z):  z ← (z ⊕ (z ≫ 30)) · 0xBF58476D1CE4E5B9
             z ← (z ⊕ (z ≫ 27)) · 0x94D049BB133111EB
             z ← z ⊕ (z ≫ 31)                                    (all mod 2⁶⁴)
    key(seed, stream) = mix(mix(seed) + stream γ)                 (one key per stream)
    bits(key, n)      = mix(key + (n + 1) γ)                      (SplitMix64's n-th output)

(counters may be negative: they are taken mod 2⁶⁴).  Uniform in the open interval (0, 1)
from the top 53 bits, u = (⌊bits / 2¹¹⌋ + ½) 2⁻⁵³, and a standard normal by the
Box–Muller transform of the uniforms 2n and 2n + 1 (its cosine branch)::

    z = √(−2 ln u₁) cos(2π u₂)

The integer arithmetic is masked to 64 bits and written so that the same functions
compiled by numba on int64 give the same bits (the multipliers in their signed form, right
shifts masked); keys are signed 64-bit integers (:func:`stream_key`), which an FMU state
and a compiled kernel hold.  The floating-point part uses
log, sqrt and cos of the platform's C library (IEEE-754 double; results are identical
across hosts with the same libm, as for every model of the toolkit).  tests/components/
test_noise.py checks the uniform and normal statistics.
"""

from __future__ import annotations

import math

from .runtime.jit import jitable

MASK = 0xFFFFFFFFFFFFFFFF
_SIGNED = 1 << 64  # the constants below are the signed (two's complement) forms, so that
#: int64 arithmetic (numba) wraps to the same bits as Python's masked integers
GAMMA = 0x9E3779B97F4A7C15 - _SIGNED
_M1 = 0xBF58476D1CE4E5B9 - _SIGNED
_M2 = 0x94D049BB133111EB - _SIGNED
#: logical right shifts written as a shift and a mask (an int64 shift is arithmetic)
_LOW34, _LOW37, _LOW33, _LOW53 = (1 << 34) - 1, (1 << 37) - 1, (1 << 33) - 1, (1 << 53) - 1
_SCALE = 2.0**-53
TWO_PI = 2.0 * math.pi


@jitable
def mix(z: int) -> int:
    """SplitMix64's finaliser: a bijection of 64-bit integers (z ≫ k written as a masked
    arithmetic shift, so that signed 64-bit integers give the same bits)."""
    z &= MASK
    z = ((z ^ ((z >> 30) & _LOW34)) * _M1) & MASK
    z = ((z ^ ((z >> 27) & _LOW37)) * _M2) & MASK
    return z ^ ((z >> 31) & _LOW33)


def stream_key(seed: int, stream: int) -> int:
    """The key of one stream of a seed, as a signed 64-bit integer."""
    key = mix((mix(seed) + stream * GAMMA) & MASK)
    return key - _SIGNED if key >> 63 else key


def key_halves(key: int) -> tuple[float, float]:
    """A signed 64-bit key as two floats, each exact (high half signed, low half
    unsigned), for a kernel's state array (:func:`joined_key`)."""
    return float(key >> 32), float(key & 0xFFFFFFFF)


@jitable
def joined_key(high: float, low: float) -> int:
    """The key :func:`key_halves` split."""
    return (int(high) << 32) | int(low)


@jitable
def bits(key: int, n: int) -> int:
    """The n-th 64-bit output of the stream ``key`` (mod 2⁶⁴: signed or not)."""
    return mix((key + (n + 1) * GAMMA) & MASK)


@jitable
def uniform(key: int, n: int) -> float:
    """The n-th uniform number of the stream ``key``, in the open interval (0, 1)."""
    return (((bits(key, n) >> 11) & _LOW53) + 0.5) * _SCALE


@jitable
def normal(key: int, n: int) -> float:
    """The n-th standard normal number of the stream ``key`` (Box–Muller)."""
    u1 = uniform(key, 2 * n)
    u2 = uniform(key, 2 * n + 1)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(TWO_PI * u2)
