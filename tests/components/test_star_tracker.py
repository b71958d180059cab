"""StarTracker against independent truth: the error statistics per sensor axis (chi-square),
the mounting, latency and hold, the exclusion boundaries, the low-frequency error's
amplitude and a noise record independent of the master's step.  Run with -rP to see the
measured numbers."""

import math

import numpy as np
import pytest
from scipy import stats

from agilesat.components.model import ModelError
from agilesat.components.rotations import dcm_from_quat, quat_conj, quat_from_axis_angle, quat_mul
from agilesat.components.sensing import EARTH_RADIUS, quat_exp, rotation_vector
from agilesat.components.star_tracker import StarTracker

ARCSEC = math.pi / 180 / 3600
QUIET = dict(nea_cross=0.0, nea_boresight=0.0, bias_lf=np.zeros(3))


def truth(t, w=(0.01, -0.02, 0.03), q0=(0.8, 0.0, 0.6, 0.0)):
    """A body turning at the constant rate w (in B) from q0: q0 ⊗ exp(w t)."""
    return quat_mul(q0, quat_exp(tuple(x * t for x in w)))


def test_the_error_statistics_match_the_nea_per_sensor_axis_and_the_mounting():
    """4000 samples of a tracker mounted 30° about x_B then 40° about its z: the error
    in S (C_SB error_B) has variances σ_c², σ_c², σ_b² (Σ e²/σ² ~ χ²(n), 99 % interval
    per axis), the error about the body's boresight direction is the σ_b one, and
    q_meas = q_true ⊗ exp(error_B)."""
    nea_c, nea_b = 3 * ARCSEC, 28 * ARCSEC
    x30 = quat_from_axis_angle([1, 0, 0], math.radians(30))
    q_SB = quat_mul(x30, quat_from_axis_angle([0, 0, 1], math.radians(40)))
    model = StarTracker(
        q_SB=q_SB, nea_cross=nea_c, nea_boresight=nea_b, bias_lf=np.zeros(3), latency=0.0, seed=5
    )
    model.start(0.0)
    n, errors = 4000, []
    for k in range(n):
        t = k / 4.0
        model.u.q_BI[:] = truth(t)
        model.output()
        assert model.y.t_meas == t
        errors.append(model.y.error_B.copy())
        measured = rotation_vector(quat_mul(quat_conj(truth(t)), model.y.q_BI_meas))
        assert np.allclose(measured, model.y.error_B, rtol=0, atol=1e-12)
        model.step(t, 0.25)
    error_S = np.array(errors) @ dcm_from_quat(q_SB).T  # C_SB error_B, row by row
    chi2 = (error_S**2).sum(axis=0) / np.array([nea_c, nea_c, nea_b]) ** 2
    low, high = stats.chi2.ppf([0.005, 0.995], n)
    print(f"chi2 per S axis {chi2} (n = {n}, 99 % interval [{low:.0f}, {high:.0f}])")
    assert np.all((low < chi2) & (chi2 < high))
    boresight_B = dcm_from_quat(q_SB)[2]  # z_S in B
    along = np.array(errors) @ boresight_B
    assert np.std(along) == pytest.approx(nea_b, rel=0.05)


def test_latency_and_hold_are_exact():
    """Noise off, a constant-rate body, steps of 0.05 s and of 0.07 s (samples between
    communication points): at t the output is the sample of t_k = ⌊4 (t − 0.2)⌋ / 4, the true
    attitude of t_k, held until the next."""
    for h in (0.05, 0.07):
        model = StarTracker(latency=0.2, rate=4.0, **QUIET).start(0.0)
        for n in range(60):
            t = n * h
            model.u.q_BI[:] = truth(t)
            model.u.w_BI_B[:] = (0.01, -0.02, 0.03)
            model.output()
            t_k = math.floor(4 * (t - 0.2) + 1e-6) / 4
            assert model.y.t_meas == t_k
            assert np.allclose(model.y.q_BI_meas, truth(t_k), rtol=0, atol=1e-12), (h, t)
            model.step(t, h)


def test_without_latency_the_sample_at_a_tick_is_the_current_attitude():
    model = StarTracker(latency=0.0, rate=4.0, **QUIET).start(0.0)
    for n in range(20):
        t = n * 0.05
        model.u.q_BI[:] = truth(t)
        model.output()
        assert model.y.t_meas == math.floor(4 * t + 1e-6) / 4
        if n % 5 == 0:
            assert np.allclose(model.y.q_BI_meas, truth(t), rtol=0, atol=1e-15)
        model.step(t, 0.05)


def valid_at(**inputs):
    model = StarTracker(latency=0.0, **QUIET)
    for name, value in inputs.items():
        model.set(name, value)
    return bool(model.start(0.0).y.valid)


def test_the_sun_exclusion_is_exact_at_its_boundary():
    """Boresight +z_B = +z_I; the Sun at the exclusion angle ± 1e-9 rad from it."""
    edge = math.radians(30.0)
    for delta, valid in ((1e-9, True), (-1e-9, False)):
        a = edge + delta
        assert valid_at(sun_I=(math.sin(a), 0.0, math.cos(a))) is valid
    assert valid_at(sun_I=(0.0, 0.0, 0.0))  # no Sun given: no test


def test_the_earth_exclusion_is_counted_from_the_limb_and_exact_at_its_boundary():
    """At 7000 km the limb is asin(R / r) from the nadir; the boresight (+z) at the
    limb + exclusion ± 1e-9 rad from the nadir."""
    r, edge = 7.0e6, math.asin(EARTH_RADIUS / 7.0e6) + math.radians(20.0)
    for delta, valid in ((1e-9, True), (-1e-9, False)):
        a = edge + delta  # nadir = −r̂ at angle a from +z
        assert valid_at(r_I=(-r * math.sin(a), 0.0, -r * math.cos(a))) is valid


def test_the_rate_limit_is_exact():
    limit = math.radians(3.0)
    axis = np.array([2.0, -1.0, 2.0]) / 3.0
    assert valid_at(w_BI_B=axis * limit * (1 - 1e-12))
    assert not valid_at(w_BI_B=axis * limit * (1 + 1e-9))


def test_the_low_frequency_error_has_its_amplitude_and_period():
    """Noise off: e_i(t)² + e_i(t + P/4)² = amplitude² (a sinusoid of period P)."""
    amplitude = np.array([2.0, 3.0, 7.0]) * ARCSEC
    model = StarTracker(nea_cross=0.0, nea_boresight=0.0, bias_lf=amplitude, lf_period=100.0)
    model.set("latency", 0.0)
    model.start(0.0)
    errors = []
    for k in range(200):  # 50 s at 4 Hz
        model.output()
        errors.append(model.y.error_B.copy())
        model.step(k / 4.0, 0.25)
    errors = np.array(errors)
    assert np.allclose(errors[:100] ** 2 + errors[100:] ** 2, amplitude**2, rtol=1e-9)
    assert not np.allclose(errors[0], errors[1])


def test_the_noise_record_does_not_depend_on_the_master_step():
    runs = {}
    for h in (0.05, 0.25, 0.125):
        model = StarTracker(seed=9).start(0.0)
        out = {}
        for n in range(int(round(5.0 / h))):
            model.advance(n * h, h)
            out[round((n + 1) * h, 9)] = model.y.q_BI_meas.tobytes()
        runs[h] = out
    assert all(runs[0.05][t] == runs[0.25][t] == runs[0.125][t] for t in runs[0.25])


def test_a_latency_queue_longer_than_it_holds_is_refused_at_initialisation():
    with pytest.raises(ModelError, match=r"latency 10000 s at rate 4 Hz is 40003 samples"):
        StarTracker(latency=1e4).start(0.0)
