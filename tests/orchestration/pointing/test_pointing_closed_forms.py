"""The indices and their statistics against closed forms derived from the definitions
([Ecss 2008] §3.2), not from the code: a bias plus a sinusoid, Gaussian white sequences,
a random walk.

A sinusoid ``R sin θ`` with θ uniform over whole periods: Pr[sin θ ≤ s] = ½ + arcsin(s)/π,
so its P-quantile is ``R sin(π(P − ½))`` and that of its magnitude ``R sin(πP/2)``.  The
mean of ``b + A sin(ωs + ϕ)`` over [t − Δt, t] is ``b + A (cos(ω(t − Δt) + ϕ) − cos(ωt + ϕ))
/(ωΔt) = b + A sinc(x) sin(ω(t − Δt/2) + ϕ)``, x = ωΔt/2, sinc x = sin x / x.
The empirical quantiles here are order statistics: the r-th smallest of n independent
values X has F(X) ~ Beta(r, n − r + 1), mean r/(n + 1) (F the values' distribution).
"""

import math

import numpy as np
import pytest
from scipy import integrate, optimize, stats

from agilesat.orchestration.pointing import ErrorHistory, index_series, magnitude, statistic

PERIOD, A, BIAS, PHASE = 10.0, 1e-4, 3e-4, 0.3
T = 0.01
M = round(PERIOD / T)  # samples per period
OMEGA = 2 * math.pi / PERIOD
PERIODS = 20
LEVELS = (0.5, 0.9, 0.9973)
STEP = 2 * math.pi / M  # one sample's phase: the grid's quantile resolution is R · STEP
TRAPEZOID = (OMEGA * T) ** 2  # relative error bound of the trapezoid window mean


def sinc(x):
    return np.sinc(x / np.pi)


def sinusoid(extra: int):
    """Bias plus sinusoid over ``extra`` samples more than whole periods: the index values
    of windows taking ``extra`` samples then cover whole periods, every phase once per
    period."""
    t = np.arange(extra + PERIODS * M) * T
    return ErrorHistory(BIAS + A * np.sin(OMEGA * t + PHASE), t)


def mean_over(t, window):
    return BIAS + A * (np.cos(OMEGA * (t - window) + PHASE) - np.cos(OMEGA * t + PHASE)) / (
        OMEGA * window
    )


def temporal(series, level):
    return statistic(magnitude(series), level, "temporal").value


@pytest.mark.parametrize("level", LEVELS)
def test_ape_of_bias_plus_sinusoid(level):
    error = sinusoid(0)
    series = index_series(error, "APE")
    assert np.array_equal(series.values, error.values)
    expected = BIAS + A * math.sin(math.pi * (level - 0.5))
    assert temporal(series, level) == pytest.approx(expected, abs=A * STEP)


@pytest.mark.parametrize("window", [2.5, 10.0, 15.0])  # shorter than, one, longer than a period
@pytest.mark.parametrize("level", LEVELS)
def test_mpe_of_bias_plus_sinusoid(window, level):
    n = round(window / T)
    series = index_series(sinusoid(n), "MPE", window=window)
    assert series.values[0, :, 0] == pytest.approx(mean_over(series.t, window), abs=A * TRAPEZOID)
    amplitude = A * abs(sinc(OMEGA * window / 2))
    expected = BIAS + amplitude * math.sin(math.pi * (level - 0.5))
    assert temporal(series, level) == pytest.approx(expected, abs=A * (STEP + TRAPEZOID))
    if window == PERIOD:
        assert temporal(series, level) == pytest.approx(BIAS, abs=A * TRAPEZOID)


@pytest.mark.parametrize("window", [2.5, 15.0])
@pytest.mark.parametrize("level", LEVELS)
def test_rpe_at_the_window_end_of_bias_plus_sinusoid(window, level):
    """e(t) − ē = A Im[e^{j(ωt+ϕ)} (1 − sinc(x) e^{−jx})]: the bias cancels, the amplitude is
    A |1 − sinc(x) e^{−jx}|."""
    n = round(window / T)
    error = sinusoid(n)
    series = index_series(error, "RPE", window=window, t_in_window="end")
    expected_values = error.values[0, n:, 0] - mean_over(series.t, window)
    assert series.values[0, :, 0] == pytest.approx(expected_values, abs=A * TRAPEZOID)
    x = OMEGA * window / 2
    amplitude = A * abs(1 - sinc(x) * np.exp(-1j * x))
    expected = amplitude * math.sin(math.pi * level / 2)
    assert temporal(series, level) == pytest.approx(expected, abs=A * (STEP + TRAPEZOID))


@pytest.mark.parametrize("window", [2.5, 15.0])
def test_rpe_with_t_random_in_the_window_of_a_sinusoid(window):
    """t at fraction u of the window: e(t) − ē = A[sin ψ − sinc(x) sin(ψ + (1 − 2u) x)],
    amplitude R(u) = A (1 − 2 sinc x cos((1 − 2u) x) + sinc² x)^½; with ψ and u uniform,
    Pr[|RPE| ≤ q] = ∫₀¹ (2/π) arcsin(min(1, q/R(u))) du, and the mean square is
    ½ A² (1 − sinc² x): the windowed-variance weighting of [Esa 2011]."""
    n = round(window / T)
    series = index_series(sinusoid(2 * n), "RPE", window=window, t_in_window="random", seed=3)
    values = series.values[0, :, 0]
    count = values.size
    x = OMEGA * window / 2
    s = sinc(x)

    def amplitude(u):
        return A * math.sqrt(1 - 2 * s * math.cos((1 - 2 * u) * x) + s * s)

    def probability(q):
        inside = lambda u: 2 / math.pi * math.asin(min(1.0, q / amplitude(u)))
        return integrate.quad(inside, 0, 1, limit=200)[0]

    mean_square = np.mean(values**2)
    tolerance = 5 * np.std(values**2) / math.sqrt(count) + A**2 / n**2
    assert mean_square == pytest.approx(A**2 / 2 * (1 - s * s), abs=tolerance)
    for level in (0.5, 0.9, 0.99):
        value = statistic(np.abs(values)[None], level, "temporal").value
        sampling = 5 * math.sqrt(level * (1 - level) / count) + 2 / M
        assert probability(value) == pytest.approx(level, abs=sampling)
        q = optimize.brentq(lambda q: probability(q) - level, 0, 3 * A)
        assert np.mean(np.abs(values) <= q) == pytest.approx(level, abs=sampling)


@pytest.mark.parametrize("window,separation", [(2.5, 4.0), (15.0, 17.0)])
@pytest.mark.parametrize("level", LEVELS)
def test_pde_of_bias_plus_sinusoid(window, separation, level):
    """ē(t) − ē(t − Δt_s) = 2 A sinc(x) sin(ωΔt_s/2) cos(ω(t − Δt/2 − Δt_s/2) + ϕ)."""
    n, shift = round(window / T), round(separation / T)
    series = index_series(sinusoid(n + shift), "PDE", window=window, separation=separation)
    expected_values = mean_over(series.t, window) - mean_over(series.t - separation, window)
    assert series.values[0, :, 0] == pytest.approx(expected_values, abs=2 * A * TRAPEZOID)
    amplitude = 2 * A * abs(sinc(OMEGA * window / 2) * math.sin(OMEGA * separation / 2))
    expected = amplitude * math.sin(math.pi * level / 2)
    assert temporal(series, level) == pytest.approx(expected, abs=A * (2 * STEP + TRAPEZOID))


def beta_moments(rank, count):
    """Mean and standard deviation of Beta(r, n − r + 1): F at the r-th smallest of n."""
    mean = rank / (count + 1)
    return mean, math.sqrt(mean * (1 - mean) / (count + 2))


def test_white_noise_temporal_ensemble_and_mixed_quantiles():
    """Half the runs with σ₁, half with σ₂ = 2σ₁, white in time.  Temporal: each run's
    quantile is that of |N(0, σ_r²)|, the worst run one with σ₂; ensemble and mixed: the
    quantile of the mixture ½|N(0, σ₁²)| + ½|N(0, σ₂²)|."""
    runs, samples, level = 400, 2000, 0.9
    sigma = np.repeat([1e-5, 2e-5], runs // 2)
    rng = np.random.default_rng(4)
    m = np.abs(rng.normal(size=(runs, samples)) * sigma[:, None])
    folded = lambda q, s: 2 * stats.norm.cdf(q / s) - 1
    mixture = lambda q: 0.5 * folded(q, 1e-5) + 0.5 * folded(q, 2e-5)

    per_run = statistic(m, level, "temporal")
    mean, sd = beta_moments(math.ceil(level * samples), samples)
    probabilities = folded(per_run.profile, sigma)
    assert probabilities.mean() == pytest.approx(mean, abs=5 * sd / math.sqrt(runs))
    assert sigma[per_run.worst] == 2e-5
    assert folded(per_run.value, 2e-5) == pytest.approx(mean, abs=5 * sd)

    per_time = statistic(m, level, "ensemble")
    mean, sd = beta_moments(math.ceil(level * runs), runs)
    assert mixture(per_time.profile).mean() == pytest.approx(mean, abs=5 * sd / math.sqrt(samples))

    mixed = statistic(m, level, "mixed")
    mean, sd = beta_moments(math.ceil(level * m.size), m.size)
    assert mixture(mixed.value) == pytest.approx(mean, abs=5 * sd)
    assert per_run.value > 1.2 * mixed.value  # the worst member against the whole ensemble
    assert per_run.profile.size == runs and per_time.profile.size == samples


@pytest.mark.parametrize(
    "index,separation,variance",
    [  # trapezoid weights (½, 1, …, 1, ½)/N on N + 1 independent samples, N = 4
        ("MPE", None, (4 - 0.5) / 16),
        ("RPE", None, (1 - 1 / 8) ** 2 + 1 / 64 + 3 / 16),
        ("PDE", 1.0, 2 * (4 - 0.5) / 16),  # two disjoint windows
    ],
)
def test_white_noise_window_indices_have_the_variance_of_their_weights(index, separation, variance):
    runs, samples, sigma = 400, 2000, 1e-5
    t = np.arange(samples) * 0.1
    e = ErrorHistory(np.random.default_rng(5).normal(size=(runs, samples, 1)) * sigma, t)
    values = index_series(e, index, window=0.4, separation=separation).values
    # the mean square at one time has a relative sd of (2/runs)^½; averaging over
    # times does not make it larger
    assert np.mean(values**2) == pytest.approx(variance * sigma**2, rel=5 * math.sqrt(2 / runs))


def test_random_walk_drift_grows_as_the_square_root_of_the_window():
    """e a Wiener process of intensity q (Var e(t) = q t).  The two window means differ by
    ∫ h dW, h rising linearly over the first window, 1 between them, falling over the
    second: Var PDE = q (Δt_s − Δt/3); contiguous windows (Δt_s = Δt): (2/3) q Δt."""
    runs, samples, dt, q = 4000, 400, 0.1, 1e-10
    rng = np.random.default_rng(6)
    walk = np.cumsum(rng.normal(size=(runs, samples)) * math.sqrt(q * dt), axis=1)
    error = ErrorHistory(walk[..., None], np.arange(samples) * dt)
    level = 0.95
    windows = (1.0, 4.0, 16.0)
    spreads = []
    for window, separation in [(w, w) for w in windows] + [(1.0, 10.0)]:
        series = index_series(error, "PDE", window=window, separation=separation)
        variance = q * (separation - window / 3)
        tolerance = 5 * math.sqrt(2 / runs)
        assert np.mean(series.values**2) == pytest.approx(variance, rel=tolerance)
        mixed = statistic(magnitude(series), level, "mixed").value
        probability = 2 * stats.norm.cdf(mixed / math.sqrt(variance)) - 1
        assert probability == pytest.approx(level, abs=5 * math.sqrt(level * (1 - level) / runs))
        if window == separation:
            spreads.append(math.sqrt(np.mean(series.values**2)))
    slope = np.polyfit(np.log(windows), np.log(spreads), 1)[0]
    assert slope == pytest.approx(0.5, abs=0.03)
