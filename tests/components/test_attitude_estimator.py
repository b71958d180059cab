"""AttitudeEstimator (MEKF) against independent truth: NEES and NIS of a Monte Carlo inside
their chi-square bands, bias convergence, Farrenkopf's steady state in closed form, and the
late-measurement handling equal to a filter without latency.  Run with -rP to see the
measured numbers."""

import math

import numpy as np
import pytest
from scipy import stats

from agilesat.components.attitude_estimator import AttitudeEstimator
from agilesat.components.gyro import Gyro
from agilesat.components.model import ModelError
from agilesat.components.rotations import dcm_from_quat as dcm
from agilesat.components.rotations import quat_conj, quat_mul
from agilesat.components.sensing import quat_exp, rotation_vector
from agilesat.components.star_tracker import StarTracker

# the filter's own model: white ARW, random-walk bias, white star-tracker noise
ARW, RRW, NEA_C, NEA_B, SIGMA_B0 = 1e-5, 1e-6, 1e-5, 5e-5, 1e-4
H, ST_RATE, LATENCY = 0.05, 4.0, 0.2
RUNS, DURATION = 50, 150.0
RATE = (0.01, -0.02, 0.005)  # rad/s, the body's constant rate


def loop(seed, duration, w=RATE, latency=LATENCY, first_sample=-math.inf):
    """Gyro, star tracker and estimator in a loop around a body turning at w; per step the
    time, the error state x = (δθ, b − b̂) and P of the latest cycle, the NIS, the count of
    updates and the outputs sigma_att, sigma_bias, q_BI_est.  Star-tracker samples taken
    before ``first_sample`` are flagged invalid."""
    rng = np.random.default_rng(seed)
    gyro = Gyro(
        arw=ARW,
        rrw=RRW,
        bias_instability=0.0,
        bias0=rng.normal(0.0, SIGMA_B0, 3),
        scale_factor=np.zeros(3),
        misalignment=np.zeros((3, 3)),
        quantization=0.0,
        rate=1 / H,
        seed=seed,
    )
    tracker = StarTracker(
        nea_cross=NEA_C,
        nea_boresight=NEA_B,
        bias_lf=np.zeros(3),
        rate=ST_RATE,
        latency=latency,
        seed=seed + 10_000,
    )
    filter_ = AttitudeEstimator(
        arw=ARW, rrw=RRW, nea_cross=NEA_C, nea_boresight=NEA_B, sigma_bias0=SIGMA_B0, rate=1 / H
    )
    for model in (gyro, tracker, filter_):
        model.start(0.0)
    rows = []
    for k in range(int(round(duration / H)) + 1):
        t = k * H
        q = quat_exp(tuple(x * t for x in w))
        tracker.u.q_BI[:] = q
        tracker.u.w_BI_B[:] = w
        gyro.u.w_BI_B[:] = w
        gyro.output()
        tracker.output()
        u = filter_.u
        u.w_meas_B[:] = gyro.y.w_meas_B
        u.q_BI_meas[:] = tracker.y.q_BI_meas
        u.meas_valid = tracker.y.valid and tracker.y.t_meas >= first_sample
        u.t_meas = tracker.y.t_meas
        filter_.output()
        for model in (gyro, tracker, filter_):
            model.step(t, H)
        _, _, q_est, b_est, P = filter_.records[-1]  # the cycle at t (None: not initialised)
        x = None
        if q_est is not None:
            dtheta = rotation_vector(quat_mul(quat_conj(q_est), q))
            x = np.concatenate((dtheta, gyro.y.bias_B - b_est))
        y = filter_.y
        rows.append(
            (
                t,
                x,
                P,
                y.nis,
                y.n_updates,
                y.sigma_att.copy(),
                y.sigma_bias.copy(),
                y.q_BI_est.copy(),
            )
        )
    return rows


@pytest.fixture(scope="module")
def monte_carlo():
    return [loop(seed, DURATION) for seed in range(RUNS)]


def band(dof, runs, confidence=0.95):
    """The two-sided chi-square band of the mean of ``runs`` chi2(dof) variables."""
    return stats.chi2.ppf([(1 - confidence) / 2, (1 + confidence) / 2], dof * runs) / runs


@pytest.mark.slow
def test_nees_and_nis_are_consistent_with_the_filter_covariance(monte_carlo):
    """The NEES over the runs (6 dof) at every 0.5 s from 2 s on, and the NIS (3 dof) of
    every update, inside their 95 % chi-square bands at least 90 % of the time (95 %
    expected), and their grand means inside the band of all samples."""
    times = range(int(2.0 / H), len(monte_carlo[0]), 10)
    nees = np.array(
        [
            [x @ np.linalg.solve(P, x) for _, x, P, *_ in (run[i] for i in times)]
            for run in monte_carlo
        ]
    )
    mean_nees = nees.mean(axis=0)
    low, high = band(6, RUNS)
    inside = np.mean((low < mean_nees) & (mean_nees < high))
    updates = []
    for run in monte_carlo:  # the NIS at each new update
        counts = [row[4] for row in run]
        updates.append([run[i][3] for i in range(1, len(run)) if counts[i] > counts[i - 1]])
    n = min(len(u) for u in updates)
    nis = np.array([u[:n] for u in updates])
    mean_nis = nis.mean(axis=0)
    nis_low, nis_high = band(3, RUNS)
    nis_inside = np.mean((nis_low < mean_nis) & (mean_nis < nis_high))
    print(
        f"NEES: mean {nees.mean():.3f} (6 expected), {inside:.1%} of {len(times)} times in "
        f"[{low:.2f}, {high:.2f}]; NIS: mean {nis.mean():.3f} (3 expected), {nis_inside:.1%} "
        f"of {n} updates in [{nis_low:.2f}, {nis_high:.2f}]"
    )
    assert inside >= 0.9 and nis_inside >= 0.9
    grand = band(6, nees.size, 0.99)
    assert grand[0] < nees.mean() * 1.0 < grand[1] * 1.05  # correlated in time: a 5 % margin
    assert band(3, nis.size, 0.99)[0] < nis.mean() < band(3, nis.size, 0.99)[1] * 1.05


@pytest.mark.slow
def test_the_bias_converges(monte_carlo):
    """From σ_b0 = 1e-4 rad/s to the steady state: the errors over the runs at the end
    match the filter's sigma_bias (chi-square, 95 %), which is 25 times smaller or less."""
    final = np.array([run[-1][1][3:] for run in monte_carlo])
    sigma = np.array([run[-1][6] for run in monte_carlo])
    chi2 = float(((final / sigma) ** 2).sum())
    low, high = stats.chi2.ppf([0.025, 0.975], final.size)
    rms = np.sqrt((final**2).mean())
    print(f"bias error at {DURATION:.0f} s: rms {rms:.3e} rad/s; sigma_bias {sigma.mean():.3e}; "
          f"chi2 {chi2:.1f} in [{low:.1f}, {high:.1f}]")  # fmt: skip
    assert low < chi2 < high
    assert sigma.max() < SIGMA_B0 / 25


def farrenkopf(sigma_n, dt=1 / ST_RATE, sigma_v=ARW, sigma_u=RRW):
    """Steady state of the single-axis filter updated every dt ([Farrenkopf 1978];
    [Markley 2014] ch. 6): the pre-update attitude and bias variances, from
    S_u = σ_u Δt^{3/2}/σ_n, S_v = σ_v Δt^{1/2}/σ_n, ξ + 1/ξ = S_u/2 + √(S_u²/12 + S_v² + 4)."""
    su, sv = sigma_u * dt**1.5 / sigma_n, sigma_v * dt**0.5 / sigma_n
    y = su / 2 + math.sqrt(su**2 / 12 + sv**2 + 4)
    xi = (y + math.sqrt(y * y - 4)) / 2
    attitude = sigma_n**2 * (xi * xi - 1)
    bias = sigma_n**2 / dt**2 * (su * (xi - 1 / xi - su / 2) + su**2)
    return attitude, bias


@pytest.mark.slow
def test_the_steady_state_is_farrenkopfs():
    """A body at rest, 200 s: at the star tracker's sample times (the covariance just
    before the next update) sigma_att and sigma_bias equal Farrenkopf's closed form per
    axis."""
    rows = loop(3, 200.0, w=(0.0, 0.0, 0.0))
    attitude = [farrenkopf(s)[0] for s in (NEA_C, NEA_C, NEA_B)]
    bias = [farrenkopf(s)[1] for s in (NEA_C, NEA_C, NEA_B)]
    for t, _, _, _, _, sigma_att, sigma_bias, _ in rows[int(150 / H) :: 5]:  # every 0.25 s
        assert sigma_att == pytest.approx(np.sqrt(attitude), rel=1e-6), t
        assert sigma_bias == pytest.approx(np.sqrt(bias), rel=1e-6), t
    worst = max(abs(row[5] / np.sqrt(attitude) - 1).max() for row in rows[int(150 / H) :: 5])
    print(f"steady state: sigma_att {rows[-1][5]} vs Farrenkopf {np.sqrt(attitude)}: {worst:.1e}")


@pytest.mark.slow
def test_the_attitude_errors_have_farrenkopfs_steady_state_spread(monte_carlo):
    """The Monte Carlo's attitude errors at the star tracker's sample times from 50 s on:
    their rms per axis is Farrenkopf's pre-update sigma within 10 %."""
    rows = [row for run in monte_carlo for row in run[int(50 / H) :: 5]]  # every 0.25 s
    errors = np.array([row[1][:3] for row in rows])
    rms = np.sqrt((errors**2).mean(axis=0))
    expected = np.sqrt([farrenkopf(s)[0] for s in (NEA_C, NEA_C, NEA_B)])
    print(f"attitude error rms {rms} vs Farrenkopf {expected}: ratio {rms / expected}")
    assert rms == pytest.approx(expected, rel=0.1)


def test_a_late_measurement_gives_the_filter_without_latency():
    """Latency 0.2 s with t_meas connected: 0.2 s after each sample time t_k, when the late
    filter has processed the sample, its estimate and covariance are those of a filter
    given the samples without latency (the same samples from t = 0 on, the same gyro)."""
    late = loop(7, 10.0, latency=LATENCY, first_sample=0.0)
    prompt = loop(7, 10.0, latency=0.0, first_sample=0.0)
    assert late[-1][4] == prompt[-1][4] - 1 > 30  # updates: the last sample still pending
    for i in range(4, len(late), 5):  # t = t_k + 0.2
        assert np.allclose(late[i][7], prompt[i][7], rtol=0, atol=1e-12), late[i][0]
        assert np.allclose(late[i][2], prompt[i][2], rtol=1e-9, atol=0), late[i][0]


def test_initialisation_and_invalid_measurements():
    """The first valid measurement initialises (q̂ = q_meas, sigma_att = the NEA); invalid
    ones leave the filter propagating (no update, the uncertainty grows); a measurement held
    over several cycles is used once."""
    model = AttitudeEstimator(rate=20.0)
    model.set("meas_valid", False)
    model.start(0.0)
    assert not model.y.valid and np.all(model.y.sigma_att == math.pi)
    q = quat_exp((0.1, -0.2, 0.3))
    model.set("q_BI_meas", q)
    model.set("meas_valid", True)
    model.output()  # the cycle at t = 0 sees it
    assert model.y.valid and model.y.n_updates == 0
    assert np.allclose(model.y.q_BI_est, q, atol=1e-15)
    nea = [model.p.nea_cross, model.p.nea_cross, model.p.nea_boresight]
    assert model.y.sigma_att == pytest.approx(nea, rel=1e-12)
    model.step(0.0, 0.05)
    for k in range(1, 5):  # the same measurement, held: no update
        model.advance(k * 0.05, 0.05)
    assert model.y.n_updates == 0
    model.set("q_BI_meas", quat_exp((0.1, -0.2, 0.3 + 1e-6)))
    model.advance(0.25, 0.05)
    assert model.y.n_updates == 1
    before = model.y.sigma_att.copy()
    model.set("q_BI_meas", q)
    model.set("meas_valid", False)
    for k in range(6, 20):
        model.advance(k * 0.05, 0.05)
    assert model.y.n_updates == 1 and np.all(model.y.sigma_att > before)
    assert model.warnings == []
    model.set("meas_valid", True)
    for k, t_meas in enumerate((-5.0, -4.0), start=20):  # older than history (1 s)
        model.set("t_meas", t_meas)
        model.advance(k * 0.05, 0.05)
    assert model.y.n_updates == 1 and len(model.warnings) == 1
    assert "older than history (1.0 s) and is ignored" in model.warnings[0]


def test_the_orbit_frame_outputs_are_the_estimate_seen_from_o():
    """q_BO_est and w_BO_B_est against direction cosines: C_BO = C_BI C_OIᵀ, and the rate
    of B relative to O is the rate relative to I less that of O, both in B; unconnected,
    O is the inertial frame."""
    model = AttitudeEstimator(rate=20.0)
    q_BI, q_OI = quat_exp((0.4, -0.1, 0.9)), quat_exp((-1.2, 0.3, 0.5))
    w_meas, w_OI_O = np.array([0.01, -0.02, 0.03]), np.array([0.0, -1.1e-3, 0.0])
    model.set("q_BI_meas", q_BI)
    model.set("w_meas_B", w_meas)
    model.start(0.0)
    assert np.array_equal(model.y.q_BO_est, model.y.q_BI_est)
    assert np.array_equal(model.y.w_BO_B_est, model.y.w_BI_B_est)
    model.set("q_OI", q_OI)
    model.set("w_OI_O", w_OI_O)
    model.output()
    C_BI, C_OI, C_BO = dcm(model.y.q_BI_est), dcm(q_OI), dcm(model.y.q_BO_est)
    assert np.allclose(C_BO, C_BI @ C_OI.T, rtol=0, atol=1e-15)
    assert np.allclose(model.y.w_BO_B_est, w_meas - C_BO @ w_OI_O, rtol=0, atol=1e-18)
    model.set("q_OI", [1.0, 0.0, 0.0, 0.1])
    with pytest.raises(ModelError, match="q_OI must be a unit quaternion"):
        model.output()


def test_a_history_longer_than_it_keeps_is_refused_at_initialisation():
    """2·10⁴ s at 20 Hz is 400,005 records (it took 3.3 GB): refused, saying why."""
    with pytest.raises(ModelError, match=r"history 20000 s at rate 20 Hz is 400005 filter records"):
        AttitudeEstimator(history=2e4).start(0.0)
