"""components/noise.py: SplitMix64 as published, uniform and normal statistics, independent
streams, and the same bits from the functions compiled by numba."""

import math
import random

import numpy as np
import pytest
from scipy import stats

from agilesat.components import noise

N = 200_000


def test_the_generator_is_splitmix64_as_published():
    """The reference splitmix64.c (Vigna), state 0: its first three outputs."""
    assert [noise.bits(0, n) for n in range(3)] == [
        0xE220A8397B1DCDAF,
        0x6E789E6AA1B965F4,
        0x06C45D188009454F,
    ]


@pytest.fixture(scope="module")
def uniforms():
    key = noise.stream_key(7, 0)
    return np.array([noise.uniform(key, n) for n in range(N)])


@pytest.fixture(scope="module")
def normals():
    key = noise.stream_key(7, 1)
    return np.array([noise.normal(key, n) for n in range(N)])


def test_uniforms_are_uniform_on_the_open_interval(uniforms):
    assert 0.0 < uniforms.min() and uniforms.max() < 1.0
    counts, _ = np.histogram(uniforms, bins=100, range=(0.0, 1.0))
    assert stats.chisquare(counts).pvalue > 1e-3
    assert stats.kstest(uniforms, "uniform").pvalue > 1e-3
    assert abs(uniforms.mean() - 0.5) < 4 * math.sqrt(1 / 12 / N)
    lag1 = np.corrcoef(uniforms[:-1], uniforms[1:])[0, 1]
    assert abs(lag1) < 4 / math.sqrt(N)


def test_normals_are_standard_normal(normals):
    assert stats.kstest(normals, "norm").pvalue > 1e-3
    assert abs(normals.mean()) < 4 / math.sqrt(N)
    chi2 = float(normals @ normals)  # ~ chi2(N) for unit variance
    assert stats.chi2.ppf(1e-4, N) < chi2 < stats.chi2.ppf(1 - 1e-4, N)
    assert abs(stats.skew(normals)) < 4 * math.sqrt(6 / N)
    assert abs(stats.kurtosis(normals)) < 4 * math.sqrt(24 / N)
    tail = np.mean(np.abs(normals) > 3.0)  # 0.0027 for a normal
    p = 2 * stats.norm.sf(3.0)
    assert abs(tail - p) < 4 * math.sqrt(p * (1 - p) / N)


def test_streams_and_seeds_are_uncorrelated():
    def series(seed, stream):
        key = noise.stream_key(seed, stream)
        return np.array([noise.normal(key, n) for n in range(20_000)])

    base = series(3, 0)
    for other in (series(3, 1), series(4, 0), series(-3, 0)):
        assert abs(np.corrcoef(base, other)[0, 1]) < 4 / math.sqrt(base.size)
    assert np.array_equal(base, series(3, 0))  # a pure function of (seed, stream, n)


def test_keys_are_signed_64_bit_integers_and_counters_may_be_negative():
    keys = [noise.stream_key(seed, s) for seed in (-(2**31), -1, 0, 1, 2**31 - 1) for s in range(9)]
    assert all(-(2**63) <= k < 2**63 for k in keys) and len(set(keys)) == len(keys)
    assert noise.bits(keys[0], -1) == noise.bits(keys[0] + 2**64, 2**64 - 1)


def test_the_functions_compiled_by_numba_give_the_same_bits():
    """int64 arithmetic in numba wraps to the masked bits of the Python integers."""
    import numba
    from numba.extending import register_jitable

    for function in (noise.mix, noise.bits, noise.uniform):
        register_jitable(function)
    normal = numba.njit(noise.normal)
    bits = numba.njit(lambda key, n: noise.bits(key, n))
    rng = random.Random(5)
    for _ in range(2000):
        key = noise.stream_key(rng.randrange(-(2**31), 2**31), rng.randrange(20))
        n = rng.randrange(-(10**12), 10**12)
        assert (bits(key, n) - noise.bits(key, n)) % 2**64 == 0
        assert normal(key, n) == noise.normal(key, n)
