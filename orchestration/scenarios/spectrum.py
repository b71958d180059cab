"""The strongest of a few bins of a long zero-padded spectrum, without the whole FFT.

``payload_sweep``'s envelope period is the strongest bin of |rfft(x, n)| among the slow
ones: n = 32 × len(x) (zero-padded), whose FFT costs ~0.1 s a run (n has large prime
factors) for the ~300 bins read.  :func:`zoomed_bins` computes only those, the K bins
k = k₀ … k₀ + K − 1 of

    X_k = Σ_j x_j w^{jk},  w = e^{−2πi/n},  j = 0 … N − 1,

as a chirp-z transform (Bluestein's identity jk = (j² + k'² − (k' − j)²)/2 with
k = k₀ + k'):

    X_{k₀+k'} = w^{k'²/2} Σ_j a_j b_{k'−j},  a_j = x_j w^{j k₀ + j²/2},  b_l = w^{−l²/2},

a linear convolution over l = −(N − 1) … K − 1, by FFTs of a power of two ≥ N + K − 1
(no wrap-around reaches the K outputs).  Each phase is taken from its exact integer
(2jk₀ + j² mod 2n, l² mod 2n), so a term is within a few ulp; the convolution's rounding is
of order log₂(L) √L ulp of Σ|x_j| (a few 1e-13 of it at these sizes).

:func:`strongest_bin` takes its result only where that is certain: the largest |X_k| must
exceed the next by more than :data:`MARGIN` Σ|x_j|, far above the rounding of either
computation.  Otherwise (near-ties, zeros, values that are no numbers, bins that are not
consecutive) it takes the FFT, so that the bin is always the one
``np.argmax(np.abs(np.fft.rfft(x, n))[bins])`` gives.
"""

from __future__ import annotations

import math

import numpy as np

#: how much the strongest bin must exceed the next, relative to Σ|x_j|, to be taken
#: from the chirp-z transform (the rounding of both computations is ~1e-13 of it)
MARGIN = 1e-9


def _chirp(squares: np.ndarray, n: int, sign: float) -> np.ndarray:
    """e^{sign·πi (squares mod 2n)/n} from exact integers."""
    return np.exp((squares % (2 * n)) * (sign * 1j * math.pi / n))


def zoomed_bins(x: np.ndarray, n: int, first: int, count: int) -> np.ndarray:
    """|X_k| of the n-point DFT of ``x`` (zero-padded) at k = first … first + count − 1,
    by the chirp-z transform (module)."""
    x = np.asarray(x, dtype=float)
    size = len(x)
    j = np.arange(size, dtype=np.int64)
    a = x * _chirp(2 * j * first + j * j, n, -1.0)
    lags = np.arange(-(size - 1), count, dtype=np.int64)
    b = _chirp(lags * lags, n, 1.0)
    length = 1 << (size + count - 2).bit_length()
    convolved = np.fft.ifft(np.fft.fft(a, length) * np.fft.fft(b, length))
    k = np.arange(count, dtype=np.int64)
    return np.abs(_chirp(k * k, n, -1.0) * convolved[size - 1 : size - 1 + count])


def strongest_bin(x: np.ndarray, n: int, bins: np.ndarray) -> int:
    """The position in ``bins`` (integers) of the largest |rfft(x, n)[bins]| (the first of
    equals): the chirp-z transform's where certain, else the FFT's (module)."""
    x = np.asarray(x, dtype=float)
    bins = np.asarray(bins)
    consecutive = len(bins) > 1 and bool(np.all(np.diff(bins) == 1))
    if consecutive and np.isfinite(x).all():
        size = zoomed_bins(x, n, int(bins[0]), len(bins))
        best = int(np.argmax(size))
        runner_up = np.max(np.delete(size, best))
        if size[best] - runner_up > MARGIN * np.sum(np.abs(x)):
            return best
    return int(np.argmax(np.abs(np.fft.rfft(x, n))[bins]))
