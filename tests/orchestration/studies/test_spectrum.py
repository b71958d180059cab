"""The strongest slow bin of a zero-padded spectrum by a chirp-z transform is the FFT's
(payload_sweep's envelope period, :mod:`agilesat.orchestration.scenarios.spectrum`)."""

import numpy as np

from agilesat.orchestration.scenarios import spectrum


def fft_bin(x, n, bins):
    return int(np.argmax(np.abs(np.fft.rfft(x, n))[bins]))


def test_the_zoomed_bins_are_the_fft_s():
    rng = np.random.default_rng(1)
    for size, n, first, count in ((1001, 32032, 20, 120), (600, 19200, 0, 7), (97, 3104, 50, 1)):
        x = rng.normal(size=size)
        zoomed = spectrum.zoomed_bins(x, n, first, count)
        wanted = np.abs(np.fft.rfft(x, n))[first : first + count]
        assert np.allclose(zoomed, wanted, rtol=0, atol=1e-11 * np.abs(x).sum())


def test_the_strongest_bin_is_the_fft_s():
    rng = np.random.default_rng(2)
    t = np.arange(2001) * 0.05
    n = 32 * len(t)
    bins = np.arange(33, 54)
    for period in (70.0, 85.0, 97.0):
        x = np.sin(2 * np.pi * t / period) + 0.3 * rng.normal(size=t.size)
        assert spectrum.strongest_bin(x, n, bins) == fft_bin(x, n, bins)


def test_where_it_is_not_certain_the_fft_decides(monkeypatch):
    """A tie (zeros), a value that is no number, and a margin no gap exceeds: each the
    FFT's answer, which the direct sum's rounding could not change."""
    n, bins = 640, np.arange(3, 9)
    spaced = np.array([3, 5, 8])  # not consecutive: the FFT's
    z = np.sin(np.arange(20.0))
    assert spectrum.strongest_bin(z, n, spaced) == fft_bin(z, n, spaced)
    assert spectrum.strongest_bin(np.zeros(20), n, bins) == fft_bin(np.zeros(20), n, bins)
    x = np.arange(20.0)
    x[4] = np.nan
    assert spectrum.strongest_bin(x, n, bins) == fft_bin(x, n, bins) == 0
    used = []
    monkeypatch.setattr(spectrum.np.fft, "rfft", lambda *a: used.append(1) or np.fft.fft(*a))
    monkeypatch.setattr(spectrum, "MARGIN", np.inf)
    y = np.cos(np.arange(20.0))
    assert spectrum.strongest_bin(y, n, bins) == int(np.argmax(np.abs(np.fft.fft(y, n))[bins]))
    assert used == [1]
