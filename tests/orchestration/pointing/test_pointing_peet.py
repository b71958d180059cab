"""The time-domain RPE of a linear system against the frequency-domain value: the PSD
weighted by the window's metric, the approach of [Esa 2011] and ESA's PEET.

White noise through a first-order filter (time constant τ, variance σ²) has the two-sided
PSD S(ω) = 2σ²τ/(1 + ω²τ²).  With t at fraction u of a window Δt (u = 1: its end) the RPE
e(t) − (1/Δt) ∫ e over [t − uΔt, t + (1 − u)Δt] is e filtered by
H_u(ω) = 1 − e^{jω(½ − u)Δt} sinc(x), x = ωΔt/2, so (S = stationary, Gaussian)

    RPE(t at u) ~ N(0, σ_u²),  σ_u² = (1/2π) ∫ S(ω) |H_u(ω)|² dω,
    |H_u|² = 1 − 2 sinc(x) cos((1 − 2u) x) + sinc²(x),

(at the centre u = ½: |1 − sinc x|²; at the end: |1 − e^{−jx} sinc x|²).  Averaged over u
uniform in [0, 1] the metric is 1 − sinc²(x), the handbook's windowed variance (RPE with t
random in Δt); that RPE is the mixture of N(0, σ_u²) over u, not a Gaussian.  The sampled
windows (trapezoid means, T = τ/10) change σ_end² by 3e-5 of itself (the exact discrete
sum), far below the sampling uncertainty.
"""

import math

import numpy as np
import pytest
from scipy import integrate, optimize, signal, stats

from agilesat.orchestration.pointing import ErrorHistory, index_series, magnitude, statistic

SIGMA, TAU, WINDOW, DT = 1e-5, 0.1, 1.0, 0.01
RUNS, SAMPLES, BATCHES, LEVEL = 200, 10_000, 20, 0.9973


def psd(w):
    return 2 * SIGMA**2 * TAU / (1 + (w * TAU) ** 2)


#: ω grid (rad/s) of the PSD integrals: 100 points per period of the metric's oscillation
#: (4π/Δt); beyond its end |S (|H|² − 1)| < S (2/x + 1/x²) leaves less than 1e-6 σ²
OMEGA = np.linspace(0.0, 4000.0, 320_001)


def variance(metric) -> float:
    """(1/2π) ∫ S |H|² dω over the real line (even integrand) = σ² + (1/π) ∫₀^∞ S (|H|² − 1)."""
    return SIGMA**2 + integrate.simpson(psd(OMEGA) * (metric(OMEGA) - 1), x=OMEGA) / math.pi


def at_fraction(u):
    def metric(w):
        x = w * WINDOW / 2
        s = np.sinc(x / np.pi)
        return 1 - 2 * s * np.cos((1 - 2 * u) * x) + s * s

    return metric


def filtered_noise(seed=7):
    """Exact samples of the first-order process (a = e^{−T/τ}), started stationary."""
    rng = np.random.default_rng(seed)
    a = math.exp(-DT / TAU)
    first = rng.normal(size=(RUNS, 1)) * SIGMA
    rest = signal.lfilter(
        [SIGMA * math.sqrt(1 - a * a)],
        [1, -a],
        rng.normal(size=(RUNS, SAMPLES - 1)),
        axis=1,
        zi=a * first,
    )[0]
    return ErrorHistory(np.concatenate((first, rest), axis=1)[..., None], np.arange(SAMPLES) * DT)


def quantile(m):
    return statistic(m, LEVEL, "mixed").value


def mean_square(m):
    return float(np.mean(m**2))


def measure(estimator, m):
    """``estimator`` on all runs, and its standard error from independent batches of runs."""
    batches = [estimator(b) for b in np.split(m, BATCHES)]
    return estimator(m), np.std(batches, ddof=1) / math.sqrt(BATCHES)


def test_the_window_metric_against_the_time_domain_variance():
    """At the window's end, σ_end² also follows from the autocovariance σ² e^{−|s|/τ}:
    σ² [1 − 2 r (1 − e^{−1/r}) + 2 r² (1/r − 1 + e^{−1/r})], r = τ/Δt."""
    r = TAU / WINDOW
    direct = SIGMA**2 * (
        1 - 2 * r * (1 - math.exp(-1 / r)) + 2 * r * r * (1 / r - 1 + math.exp(-1 / r))
    )
    assert variance(at_fraction(1.0)) == pytest.approx(direct, rel=1e-8)
    u = np.linspace(0, 1, 41)
    average = integrate.simpson([variance(at_fraction(x)) for x in u], x=u)
    windowed = variance(lambda w: 1 - np.sinc(w * WINDOW / 2 / np.pi) ** 2)
    assert average == pytest.approx(windowed, rel=1e-6)


def test_rpe_quantile_in_the_time_domain_agrees_with_the_frequency_domain():
    error = filtered_noise()
    z = stats.norm.ppf((1 + LEVEL) / 2)

    end = magnitude(index_series(error, "RPE", window=WINDOW, t_in_window="end"))
    sigma_end = math.sqrt(variance(at_fraction(1.0)))
    measured, uncertainty = measure(quantile, end)
    print(f"RPE end: time domain {measured:.5e} ± {uncertainty:.1e}, PSD {z * sigma_end:.5e}")
    assert measured == pytest.approx(z * sigma_end, abs=4 * uncertainty)
    assert uncertainty < 0.01 * measured

    random = magnitude(index_series(error, "RPE", window=WINDOW, t_in_window="random"))
    u = np.linspace(0, 1, 41)
    sigmas = np.sqrt([variance(at_fraction(x)) for x in u])

    def within(q):  # Pr[|RPE| ≤ q] of the mixture over u
        return integrate.simpson(2 * stats.norm.cdf(q / sigmas) - 1, x=u)

    mixture = optimize.brentq(lambda q: within(q) - LEVEL, 0, 10 * SIGMA)
    windowed = variance(lambda w: 1 - np.sinc(w * WINDOW / 2 / np.pi) ** 2)
    measured, uncertainty = measure(quantile, random)
    square, square_uncertainty = measure(mean_square, random)
    print(
        f"RPE random: time domain {measured:.5e} ± {uncertainty:.1e}, PSD mixture "
        f"{mixture:.5e} (Gaussian of the windowed variance: {z * math.sqrt(windowed):.5e}); "
        f"mean square {square:.5e} ± {square_uncertainty:.1e}, PSD {windowed:.5e}"
    )
    assert measured == pytest.approx(mixture, abs=4 * uncertainty)
    assert square == pytest.approx(windowed, abs=4 * square_uncertainty)
