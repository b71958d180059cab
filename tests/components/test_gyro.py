"""Gyro against independent truth: the Allan deviation of long stationary records (IEEE Std
952-1997 Annex C closed forms), the error matrix in closed form, exact quantisation and
saturation, the rate-integrating average, and a noise record independent of the master's
step.  Run with -rP to see the measured numbers."""

import math

import numpy as np
import pytest

from agilesat.components.gyro import GAUSS_MARKOV_ALLAN_PEAK, Gyro

QUIET = dict(
    arw=0.0,
    rrw=0.0,
    bias_instability=0.0,
    bias0=np.zeros(3),
    scale_factor=np.zeros(3),
    misalignment=np.zeros((3, 3)),
    quantization=0.0,
)


def record(n, rate, w=(0.0, 0.0, 0.0), step=None, **parameters):
    """n samples of a gyro at rest (or turning at w), stepped at ``step`` (default: one
    sample period): (w_meas_B, bias_B) at each communication point, shape (n, 3)."""
    gyro = Gyro(rate=rate, **parameters)
    gyro.u.w_BI_B[:] = w
    gyro.start(0.0)
    h = step or 1.0 / rate
    measured, bias = np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        gyro.advance(k * h, h)
        measured[k], bias[k] = gyro.y.w_meas_B, gyro.y.bias_B
    return measured, bias


def allan_deviation(rates, period, m):
    """Overlapping Allan deviation at τ = m T of a rate record (IEEE Std 952 Annex C, on
    the integrated angle θ_k = Σ ω_i T)."""
    theta = np.concatenate(([0.0], np.cumsum(rates * period)))
    d = theta[2 * m :] - 2 * theta[m:-m] + theta[: -2 * m]
    tau = m * period
    return math.sqrt(np.mean(d * d) / (2 * tau * tau))


def gauss_markov_allan(sigma, tc, tau):
    """IEEE Std 952 Annex C: Allan deviation of a first-order Gauss–Markov process."""
    x = tau / tc
    return sigma * math.sqrt((2 * x - 3 + 4 * math.exp(-x) - math.exp(-2 * x)) / (x * x))


def test_the_gauss_markov_allan_peak_constant_is_the_maximum_of_the_closed_form():
    from scipy.optimize import minimize_scalar

    best = minimize_scalar(
        lambda x: -gauss_markov_allan(1.0, 1.0, x), bounds=(0.5, 5.0), method="bounded"
    )
    assert GAUSS_MARKOV_ALLAN_PEAK == pytest.approx(-best.fun, rel=1e-9)
    assert best.x == pytest.approx(1.8926, abs=1e-3)


@pytest.mark.slow
def test_allan_deviation_recovers_the_angle_random_walk():
    """ARW alone: σ_A(τ) = N / √τ, slope −½, σ_A(1 s) = N."""
    arw = 2e-4
    rates, _ = record(100_000, 10.0, **{**QUIET, "arw": arw})
    taus = [1.0, 2.0, 5.0, 10.0, 20.0, 50.0]
    adev = [allan_deviation(rates[:, 0], 0.1, round(tau * 10)) for tau in taus]
    slope = np.polyfit(np.log(taus), np.log(adev), 1)[0]
    print(f"ARW: sigma_A(1 s) = {adev[0]:.4e} for N = {arw:.4e}; slope {slope:.3f}")
    assert adev[0] == pytest.approx(arw, rel=0.1)
    assert slope == pytest.approx(-0.5, abs=0.05)
    for axis in (1, 2):
        assert allan_deviation(rates[:, axis], 0.1, 10) == pytest.approx(arw, rel=0.1)


@pytest.mark.slow
def test_allan_deviation_recovers_the_bias_instability_floor():
    """Bias instability alone: the Allan deviation peaks at B (the parameter), at
    τ = 1.89 T_c, and follows the Gauss–Markov closed form."""
    b, tc = 3e-5, 20.0
    rates, _ = record(200_000, 1.0, **{**QUIET, "bias_instability": b, "bias_correlation_time": tc})
    sigma = b / GAUSS_MARKOV_ALLAN_PEAK
    taus = [2, 5, 10, 20, 38, 60, 100, 200]
    measured = np.array([[allan_deviation(rates[:, i], 1.0, t) for t in taus] for i in range(3)])
    expected = np.array([gauss_markov_allan(sigma, tc, t) for t in taus])
    peak = measured.max(axis=1)
    print(f"bias instability: Allan peaks {peak} for B = {b:.3e}; ratio to the closed form")
    print(np.round(measured / expected, 3))
    assert peak == pytest.approx([b] * 3, rel=0.1)
    assert np.all(np.abs(measured / expected - 1) < 0.1)


@pytest.mark.slow
def test_allan_deviation_recovers_the_rate_random_walk():
    """RRW alone: σ_A(τ) = K √(τ/3), slope +½, σ_A(3 s) = K."""
    rrw = 1e-5
    rates, _ = record(100_000, 1.0, **{**QUIET, "rrw": rrw})
    taus = [3, 10, 30, 100]
    adev = np.array([[allan_deviation(rates[:, i], 1.0, t) for t in taus] for i in range(3)])
    slope = np.polyfit(np.log(taus), np.log(adev[0]), 1)[0]
    print(f"RRW: sigma_A(3 s) = {adev[:, 0]} for K = {rrw:.3e}; slope {slope:.3f}")
    assert adev[:, 0] == pytest.approx([rrw] * 3, rel=0.1)
    assert slope == pytest.approx(0.5, abs=0.05)


@pytest.mark.slow
def test_allan_deviation_of_all_terms_is_the_sum_of_the_closed_forms():
    """σ_A² = N²/τ + σ_A,GM²(τ) + K² τ / 3 (independent terms add)."""
    arw, b, tc, rrw = 1e-4, 2e-5, 30.0, 2e-7
    parameters = {**QUIET, "arw": arw, "rrw": rrw, "bias_instability": b}
    rates, _ = record(200_000, 1.0, bias_correlation_time=tc, **parameters)
    sigma = b / GAUSS_MARKOV_ALLAN_PEAK
    taus = [1, 3, 10, 30, 57, 100, 300, 1000]
    ratio = [
        allan_deviation(rates[:, 0], 1.0, t)
        / math.sqrt(arw**2 / t + gauss_markov_allan(sigma, tc, t) ** 2 + rrw**2 * t / 3)
        for t in taus
    ]
    print(f"all terms: measured / closed form at tau = {taus}: {np.round(ratio, 3)}")
    assert np.all(np.abs(np.array(ratio) - 1) < 0.1)


def test_scale_factor_and_misalignment_in_closed_form():
    """Noise off: w_meas = (I + diag(scale_factor) + M) w + bias0, exactly."""
    sf = np.array([1e-3, -2e-3, 5e-4])
    M = np.array([[0.0, 1e-3, -2e-3], [3e-4, 0.0, 1e-3], [-1e-3, 2e-3, 0.0]])
    bias0 = np.array([1e-5, -2e-5, 3e-5])
    w = np.array([0.1, -0.05, 0.2])
    parameters = {**QUIET, "scale_factor": sf, "misalignment": M, "bias0": bias0}
    measured, bias = record(5, 20.0, w=w, **parameters)
    expected = (np.eye(3) + np.diag(sf) + M) @ w + bias0
    assert np.allclose(measured, expected, rtol=0, atol=1e-16)
    assert np.array_equal(bias, np.tile(bias0, (5, 1)))


def test_quantisation_carries_the_remainder_exactly():
    """A rate of 2.375 LSB: each output a whole number of LSB, the cumulative count after
    sample k the rounded cumulative angle, floor(2.375 (k + 1) + ½) (a dyadic rate and
    sample period: every sum is exact, ties included)."""
    q = 2.0**-12
    gyro = Gyro(rate=16.0, **{**QUIET, "quantization": q})
    gyro.u.w_BI_B[:] = (2.375 * q, -0.625 * q, 0.0)
    counts = [gyro.start(0.0).y.w_meas_B / q]  # sample 0, at t0
    for k in range(40):
        counts.append(gyro.advance(k / 16.0, 1 / 16.0).y.w_meas_B / q)
    counts = np.array(counts)
    assert np.array_equal(counts, np.round(counts))
    cumulative = np.cumsum(counts, axis=0)
    k = np.arange(41)
    assert np.array_equal(cumulative[:, 0], np.floor(2.375 * (k + 1) + 0.5))
    assert np.array_equal(cumulative[:, 1], np.floor(-0.625 * (k + 1) + 0.5))
    assert np.array_equal(cumulative[:, 2], np.zeros(41))


def test_saturation_clips_exactly_and_warns_once_per_axis():
    gyro = Gyro(rate=16.0, saturation=1.0, **QUIET)
    gyro.u.w_BI_B[:] = (1.5, -3.0, 0.5)
    gyro.start(0.0)
    for k in range(3):
        gyro.advance(k / 16.0, 1 / 16.0)
        assert gyro.y.w_meas_B.tolist() == [1.0, -1.0, 0.5]
    assert len(gyro.warnings) == 2
    assert "axis 1 saturated" in gyro.warnings[0] and "axis 2 saturated" in gyro.warnings[1]


def test_the_output_is_the_average_rate_over_the_sample_interval():
    """A rate ramp w = a t, sampled at 20 Hz, stepped at 0.05 s or at 0.0125 s: sample k is
    a (t_k − T/2), the average over (t_k − T, t_k] (before t0 the rate of t0)."""
    a = np.array([0.02, -0.01, 0.005])
    for h in (0.05, 0.0125):
        gyro = Gyro(rate=20.0, **QUIET).start(0.0)
        for n in range(int(round(1.0 / h)) + 1):
            t = n * h
            gyro.u.w_BI_B[:] = a * t
            gyro.output()
            k = math.floor(t * 20.0 + 1e-6)
            expected = a * (k / 20.0 - 0.025) if k > 0 else np.zeros(3)
            assert np.allclose(gyro.y.w_meas_B, expected, rtol=1e-12, atol=1e-17), (h, t)
            gyro.step(t, h)


def test_the_noise_record_does_not_depend_on_the_master_step():
    """Same seed: the samples at common times are the same bits at steps of 0.05, 0.1 and
    0.0125 s (the noise of sample k is drawn from index k)."""
    parameters = dict(rate=20.0, seed=11)  # the default noise terms and errors
    runs = {}
    for h in (0.05, 0.1, 0.0125):
        gyro = Gyro(**parameters).start(0.0)
        out = {}
        for n in range(int(round(2.0 / h)) + 1):
            gyro.advance(n * h, h)
            out[round((n + 1) * h, 9)] = gyro.y.w_meas_B.tobytes()
        runs[h] = out
    common = [round(0.1 * j, 9) for j in range(1, 21)]
    assert all(runs[0.05][t] == runs[0.1][t] == runs[0.0125][t] for t in common)
    other = Gyro(rate=20.0, seed=12).start(0.0).advance(0.0, 0.1)
    assert other.y.w_meas_B.tobytes() != runs[0.1][0.1]


def test_parameters_are_checked():
    from agilesat.components.model import ModelError

    with pytest.raises(ModelError, match="rate must be > 0"):
        Gyro(rate=0.0).start(0.0)
    with pytest.raises(ModelError, match="arw must be >= 0"):
        Gyro(arw=-1.0).start(0.0)
