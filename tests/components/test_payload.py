"""Payload gimbals and sweep planner ([Chang 2015]) against closed forms and first principles."""

import math

import numpy as np
import pytest

from agilesat.components.model import ModelError
from agilesat.components.payload_gimbals import PayloadGimbals, payload_momentum
from agilesat.components.rotations import rot1, rot2
from agilesat.components.sweep_planner import SweepAxis, SweepPlanner

DEG = math.pi / 180
JX, JY, JZ = 45.5, 35.8, 36.7  # [Chang 2015] §2, each payload, kg·m²
J = np.diag([JX, JY, JZ])
ROLL_A, ROLL_R, PITCH_A, PITCH_R = 15 * DEG, 6 * DEG, 45 * DEG, 0.6 * DEG  # §1.2
COMMANDS = ("roll_cmd", "pitch_cmd", "roll_rate_cmd", "pitch_rate_cmd")


def paper_R_mb(phi, theta):
    """R_mb = R_mr R_rb as printed in eq. (2) (homogeneous parts dropped)."""
    c, s = math.cos(theta), math.sin(theta)
    R_mr = np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])
    c, s = math.cos(phi), math.sin(phi)
    R_rb = np.array([[1, 0, 0], [0, c, s], [0, -s, c]])
    return R_mr @ R_rb


def yaw_closed_form(phi, theta, phi_dot, theta_dot, phi_ddot, theta_ddot):
    """(h_z, ḣ_z) of the symmetric pair, derived by hand from h_b = R_mbᵀ J Ω."""
    sf, cf, s, c = math.sin(phi), math.cos(phi), math.sin(theta), math.cos(theta)
    h_z = 2 * (JY * theta_dot * sf + (JZ - JX) * phi_dot * s * c * cf)
    hdot_z = 2 * (
        JY * (theta_ddot * sf + phi_dot * theta_dot * cf)
        + (JZ - JX)
        * (
            phi_ddot * s * c * cf
            + phi_dot * theta_dot * math.cos(2 * theta) * cf
            - phi_dot**2 * s * c * sf
        )
    )
    return h_z, hdot_z


def trajectory(t):
    """A smooth, generic gimbal motion: (φ, θ, φ̇, θ̇, φ̈, θ̈) at t."""
    return (
        0.3 * math.sin(0.7 * t) + 0.1,
        0.8 * math.cos(0.3 * t) - 0.2,
        0.21 * math.cos(0.7 * t),
        -0.24 * math.sin(0.3 * t),
        -0.147 * math.sin(0.7 * t),
        -0.072 * math.cos(0.3 * t),
    )


def gimbals(commands=None, **parameters):
    model = PayloadGimbals(**parameters)
    for name, value in (commands or {}).items():
        model.set(name, value)
    return model.start()


def feed(model, planner):
    for name in COMMANDS + ("roll_accel_cmd", "pitch_accel_cmd"):
        model.set(name, planner.get(name))


def accelerations(planner, t):
    return planner.roll(t)[2], planner.pitch(t)[2]


def sweep(t_end, dt, t0=0.0, turnaround=1.0, **gimbal_parameters):
    """Planner driving the gimbals (Gauss-Seidel) from t0; yields (t, planner, gimbals)."""
    planner = SweepPlanner(turnaround_time=turnaround).start(t0)
    model = PayloadGimbals(**gimbal_parameters)
    feed(model, planner)
    model.start(t0)
    yield t0, planner, model
    for k in range(int(round((t_end - t0) / dt))):
        t = t0 + k * dt
        planner.advance(t, dt)
        model.step(t, dt)
        feed(model, planner)
        model.output()
        yield t0 + (k + 1) * dt, planner, model


# -- geometry and momentum (eqs 1–3) ---------------------------------------------------
@pytest.mark.parametrize("phi, theta", [(0.3, -1.1), (-15 * DEG, 45 * DEG), (2.0, 0.4)])
def test_R_mb_is_the_papers_matrix_and_rot2_times_rot1(phi, theta):
    R = rot2(theta) @ rot1(phi)
    assert np.allclose(R, paper_R_mb(phi, theta), atol=1e-15)
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-15) and np.linalg.det(R) == pytest.approx(1)
    # roll first about body x, then pitch about the support's (rolled) y axis
    assert np.allclose(R.T @ [0, 1, 0], [0, math.cos(phi), math.sin(phi)], atol=1e-15)


@pytest.mark.parametrize("t", [0.0, 1.3, 7.9])
def test_eq1_angular_velocity_follows_from_differentiating_R_mb(t):
    """Ṙ_mb = −[Ω×] R_mb with Ω = (φ̇ cos θ, θ̇, φ̇ sin θ) in payload axes."""
    R = lambda x: paper_R_mb(*trajectory(x)[:2])
    dt = 1e-6
    W = -(R(t + dt) - R(t - dt)) / (2 * dt) @ R(t).T
    assert np.allclose(W, -W.T, atol=1e-9)
    phi, theta, phi_dot, theta_dot = trajectory(t)[:4]
    omega = [phi_dot * math.cos(theta), theta_dot, phi_dot * math.sin(theta)]
    assert np.allclose([W[2, 1], W[0, 2], W[1, 0]], omega, atol=1e-9)


@pytest.mark.parametrize("t", [0.0, 2.2, 5.5])
def test_momentum_is_R_mb_transposed_J_Omega_and_boresight_is_payload_z(t):
    phi, theta, phi_dot, theta_dot, phi_ddot, theta_ddot = trajectory(t)
    h, _, los = payload_momentum((JX, JY, JZ), *trajectory(t))
    R = paper_R_mb(phi, theta)
    omega = [phi_dot * math.cos(theta), theta_dot, phi_dot * math.sin(theta)]
    assert np.allclose(h, R.T @ J @ omega, atol=1e-13)
    assert np.allclose(los, R.T @ [0, 0, 1], atol=1e-15)


@pytest.mark.parametrize("t", [0.0, 3.1, 9.4])
def test_hdot_is_the_time_derivative_of_h_including_the_transport_term(t):
    dt = 1e-5
    h = lambda x: np.array(payload_momentum((JX, JY, JZ), *trajectory(x))[0])
    numeric = (h(t + dt) - h(t - dt)) / (2 * dt)
    hdot = np.array(payload_momentum((JX, JY, JZ), *trajectory(t))[1])
    assert np.allclose(hdot, numeric, rtol=0, atol=1e-9)
    # the paper's eq. (2), R_mbᵀ J Ω̇, misses R_mbᵀ (Ω × JΩ)
    phi, theta, phi_dot, theta_dot, phi_ddot, theta_ddot = trajectory(t)
    c, s = math.cos(theta), math.sin(theta)
    omega = np.array([phi_dot * c, theta_dot, phi_dot * s])
    omega_dot = [
        phi_ddot * c - phi_dot * theta_dot * s,
        theta_ddot,
        phi_ddot * s + phi_dot * theta_dot * c,
    ]
    R = paper_R_mb(phi, theta)
    assert np.allclose(R.T @ J @ omega_dot + R.T @ np.cross(omega, J @ omega), numeric, atol=1e-9)
    assert np.linalg.norm(R.T @ J @ omega_dot - numeric) > 1e-3


@pytest.mark.parametrize(
    "roll, pitch, boresight",
    [
        (0.0, 0.0, (0, 0, 1)),  # nadir
        (15 * DEG, 0.0, (0, -math.sin(15 * DEG), math.cos(15 * DEG))),  # +roll looks to −y
        (0.0, 45 * DEG, (math.sin(45 * DEG), 0, math.cos(45 * DEG))),  # +pitch looks to +x
    ],
)
def test_boresight_of_each_payload(roll, pitch, boresight):
    model = gimbals({"roll_cmd": [roll, -roll], "pitch_cmd": [pitch, -pitch]})
    los = model.get("los_B")
    assert np.allclose(los[0], boresight, atol=1e-15)
    assert np.allclose(los[1], np.array(boresight) * [-1, -1, 1], atol=1e-15)  # (−φ, −θ)


# -- symmetric pair ------------------------------------------------------------------
def test_symmetric_pair_cancels_roll_and_pitch_momentum_and_torque():
    worst = 0.0
    for t, planner, model in sweep(40.0, 0.05):
        h, hdot = model.get("h"), model.get("hdot")
        worst = max(worst, abs(h[0]), abs(h[1]), abs(hdot[0]), abs(hdot[1]))
    assert worst <= 1e-15


@pytest.mark.parametrize("seed", range(5))
def test_symmetric_pair_momentum_matches_the_yaw_closed_form(seed):
    state = np.random.default_rng(seed).uniform(-1.5, 1.5, 6)
    h1, d1, _ = payload_momentum((JX, JY, JZ), *state)
    h2, d2, _ = payload_momentum((JX, JY, JZ), *(-state))
    h, hdot = np.add(h1, h2), np.add(d1, d2)
    assert np.allclose(h[:2], 0, atol=1e-15) and np.allclose(hdot[:2], 0, atol=1e-15)
    assert (h[2], hdot[2]) == pytest.approx(yaw_closed_form(*state), rel=1e-12, abs=1e-15)


@pytest.mark.slow
def test_swept_pair_follows_the_yaw_closed_forms():
    """Component driven by the planner, ideal tracking, against h_z and ḣ_z by hand."""
    dt, checked = 0.05, 0
    for t, planner, model in sweep(330.0, dt):
        phi, phi_dot, phi_ddot = planner.roll(t)
        theta, theta_dot, theta_ddot = planner.pitch(t)
        h_z, hdot_z = yaw_closed_form(phi, theta, phi_dot, theta_dot, phi_ddot, theta_ddot)
        assert model.get("h")[2] == pytest.approx(h_z, rel=1e-12, abs=1e-13)
        # ideal tracking differences the rate command over the last step: exact when the
        # commanded acceleration was constant across it
        if t > 0 and all(
            accelerations(planner, t - dt * f) == accelerations(planner, t)
            for f in (0.999, 0.5, 0.001)
        ):
            assert model.get("hdot")[2] == pytest.approx(hdot_z, rel=1e-9, abs=1e-12)
            checked += 1
    assert checked > 6000


def test_acceleration_commands_make_hdot_exact_through_the_reversals():
    """With the planner's accelerations (accel_inputs) ḣ_z is exact at every sample."""
    reversals = 0
    for t, planner, model in sweep(40.0, 0.05, accel_inputs=True):
        phi, phi_dot, phi_ddot = planner.roll(t)
        theta, theta_dot, theta_ddot = planner.pitch(t)
        hdot_z = yaw_closed_form(phi, theta, phi_dot, theta_dot, phi_ddot, theta_ddot)[1]
        assert model.get("hdot")[2] == pytest.approx(hdot_z, rel=1e-12, abs=1e-13)
        reversals += phi_ddot != 0.0
    assert reversals > 50


def test_ideal_reversal_is_a_yaw_momentum_jump_delivered_in_one_step():
    """τ = 0: at the roll reversal t = 5 s (φ = −A) φ̇ jumps from −r to +r, so h_z jumps by
    4 (Jz − Jx) r sin θ cos θ cos A; ideal tracking spreads it over one step: torque ∝ 1/dt."""
    planner = SweepPlanner(turnaround_time=0.0).start()
    theta = PITCH_A - PITCH_R * 5.0
    jump = 4 * (JZ - JX) * ROLL_R * math.sin(theta) * math.cos(theta) * math.cos(ROLL_A)
    for dt in (0.1, 0.01):
        model = PayloadGimbals()
        planner.t = 5.0 - dt
        planner.output()
        feed(model, planner)
        model.start(5.0 - dt)
        before = model.get("h")[2]
        planner.t = 5.0
        planner.output()
        model.step(5.0 - dt, dt)
        feed(model, planner)
        model.output()
        assert model.get("roll")[0] == pytest.approx(-ROLL_A)
        assert model.get("h")[2] - before == pytest.approx(jump, rel=0.02)
        assert model.get("hdot")[2] * dt == pytest.approx(jump, rel=0.02)


# -- ideal tracking and servo ----------------------------------------------------------
def test_ideal_tracking_outputs_are_the_commands_exactly():
    commands = {
        "roll_cmd": [0.2, -0.3],
        "pitch_cmd": [0.7, -0.1],
        "roll_rate_cmd": [0.05, -0.02],
        "pitch_rate_cmd": [0.01, 0.03],
    }
    model = gimbals(commands)
    for name, value in commands.items():
        assert model.get(name.replace("_cmd", "")).tolist() == value
    model.set("roll_cmd", [0.25, -0.35])
    model.advance(0.0, 0.1)
    assert model.get("roll").tolist() == [0.25, -0.35]


def test_declared_dependencies_are_the_true_feedthrough():
    """Each output changes with exactly the inputs its row names (ideal tracking)."""
    base = {
        "roll_cmd": [0.2, -0.3],
        "pitch_cmd": [0.7, -0.1],
        "roll_rate_cmd": [0.05, -0.02],
        "pitch_rate_cmd": [0.01, 0.03],
    }
    model = gimbals(base)
    model.advance(0.0, 0.1)
    reference = {v.name: model.get(v.name) for v in model.layout.group("output")}
    for name in COMMANDS:
        model.set(name, np.array(base[name]) + 0.01)
        model.output()
        changed = {
            out for out, value in reference.items() if not np.array_equal(model.get(out), value)
        }
        declared = {v.name for v in model.layout.group("output") if name in v.depends}
        assert changed == declared, name
        model.set(name, base[name])


def step_response(zeta, w, t):
    """Unit step response of θ̈ + 2ζω θ̇ + ω² θ = ω² from rest: (θ, θ̇) (textbook)."""
    if zeta < 1:
        wd = w * math.sqrt(1 - zeta**2)
        e = math.exp(-zeta * w * t)
        return (
            1 - e * (math.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * math.sin(wd * t)),
            w / math.sqrt(1 - zeta**2) * e * math.sin(wd * t),
        )
    if zeta == 1:
        return 1 - math.exp(-w * t) * (1 + w * t), w * w * t * math.exp(-w * t)
    s1, s2 = -zeta * w + w * math.sqrt(zeta**2 - 1), -zeta * w - w * math.sqrt(zeta**2 - 1)
    return (
        1 - (s2 * math.exp(s1 * t) - s1 * math.exp(s2 * t)) / (s2 - s1),
        -s1 * s2 * (math.exp(s1 * t) - math.exp(s2 * t)) / (s2 - s1),
    )


@pytest.mark.parametrize("zeta", [0.3, 1.0 - 1e-9, 1.0, 1.0 + 1e-9, 2.5, 40.0])
@pytest.mark.parametrize("dt", [0.7, 0.01])
def test_servo_step_response_is_the_damped_second_order_closed_form(zeta, dt):
    w, size = 2.0, (0.1, -0.2)
    model = gimbals(bandwidth=w, damping=zeta)  # parked at zero
    model.set("roll_cmd", size)
    model.set("pitch_cmd", [0.3, 0.05])
    # near ζ = 1 the textbook forms cancel badly: compare with the critical one, to O(ζ − 1)
    reference, tol = (1.0, 1e-9) if abs(zeta - 1) < 1e-6 else (zeta, 1e-12)
    t = 0.0
    while t < 7.0 - 1e-9:
        model.advance(t, dt)
        t += dt
        theta, rate = step_response(reference, w, t)
        assert model.get("roll") == pytest.approx(np.multiply(size, theta), abs=tol)
        assert model.get("roll_rate") == pytest.approx(np.multiply(size, rate), abs=tol)
        assert model.get("pitch")[0] == pytest.approx(0.3 * theta, abs=tol)


def test_servo_tracks_a_commanded_ramp_without_error():
    model = gimbals(
        {
            "roll_cmd": [0.2, -0.2],
            "roll_rate_cmd": [0.05, -0.05],
            "pitch_cmd": [0.4, -0.4],
            "pitch_rate_cmd": [-0.01, 0.01],
        },
        bandwidth=3.0,
        damping=0.7,
    )
    for k in range(50):
        t = 0.3 * (k + 1)
        model.advance(0.3 * k, 0.3)
        model.set("roll_cmd", [0.2 + 0.05 * t, -0.2 - 0.05 * t])
        model.set("pitch_cmd", [0.4 - 0.01 * t, -0.4 + 0.01 * t])
        model.output()
        assert model.get("roll") == pytest.approx([0.2 + 0.05 * t, -0.2 - 0.05 * t], abs=1e-13)
        assert model.get("pitch_rate") == pytest.approx([-0.01, 0.01], abs=1e-13)


def test_servo_hdot_is_the_derivative_of_h():
    """A transient of the servo (commands on a ramp, state displaced): central differences."""
    model = gimbals(
        {
            "roll_cmd": [0.1, 0.3],
            "pitch_cmd": [0.5, -0.2],
            "roll_rate_cmd": [0.08, -0.05],
            "pitch_rate_cmd": [0.02, 0.01],
        },
        bandwidth=1.5,
        damping=0.6,
    )
    start = {"roll_cmd": [0.1, 0.3], "pitch_cmd": [0.5, -0.2]}
    model.set("roll_cmd", [0.3, 0.1])  # a step on top of the ramp
    model.output()
    dt, h, hdot = 1e-4, [], []
    for k in range(3000):
        t = (k + 1) * dt
        model.advance(k * dt, dt)
        model.set("roll_cmd", np.array([0.3, 0.1]) + np.array([0.08, -0.05]) * t)
        model.set("pitch_cmd", np.array(start["pitch_cmd"]) + np.array([0.02, 0.01]) * t)
        model.output()
        h.append(model.get("h"))
        hdot.append(model.get("hdot"))
    h, hdot = np.array(h), np.array(hdot)
    numeric = (h[2:] - h[:-2]) / (2 * dt)
    assert np.abs(hdot).max() > 0.1
    assert np.allclose(hdot[1:-1], numeric, rtol=0, atol=1e-7)


def test_ideal_tracking_hdot_is_the_derivative_of_h_inside_a_reversal():
    """Middle of the first roll reversal after t = 0 (t = 5.5 s, τ = 1 s): central differences."""
    dt = 1e-4
    samples = {}
    for t, planner, model in sweep(5.502, dt, t0=5.49):
        if abs(t - 5.5) < 1.5 * dt:
            samples[round((t - 5.5) / dt)] = (model.get("h"), model.get("hdot"))
    numeric = (samples[1][0] - samples[-1][0]) / (2 * dt)
    assert abs(numeric[2]) > 1.0
    assert np.allclose(samples[0][1], numeric, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize(
    "parameters, message",
    [
        ({"J_payload": [45.5, 0.0, 36.7]}, "J_payload"),
        ({"J_payload": [90.0, 35.8, 36.7]}, "sum of the other two"),
        ({"bandwidth": -1.0}, "bandwidth must be >= 0"),
        ({"damping": 0.0}, "damping must be > 0"),
    ],
)
def test_bad_gimbal_parameters_are_rejected(parameters, message):
    with pytest.raises(ModelError, match=message):
        PayloadGimbals(**parameters).start()


# -- sweep planner ------------------------------------------------------------------
def planner_at(t, **parameters):
    planner = SweepPlanner(**parameters).start()
    planner.t = t
    planner.output()
    return planner


@pytest.mark.parametrize(
    "t, roll, pitch, roll_rate, pitch_rate",
    [
        (0.0, 15, 45, -6, -0.6),  # payload 1 starts at (+15°, +45°) toward negative
        (2.5, 0, 43.5, -6, -0.6),
        (5.0, -15, 42, 6, -0.6),
        (7.5, 0, 40.5, 6, -0.6),
        (10.0, 15, 39, -6, -0.6),  # roll period 10 s
        (75.0, -15, 0, 6, -0.6),
        (150.0, 15, -45, -6, 0.6),
        (225.0, -15, 0, 6, 0.6),
        (300.0, 15, 45, -6, -0.6),  # pitch period 300 s
    ],
)
def test_zero_turnaround_is_the_papers_triangle_wave(t, roll, pitch, roll_rate, pitch_rate):
    planner = planner_at(t, turnaround_time=0.0)
    got = [planner.get(n)[0] / DEG for n in COMMANDS]
    assert got == pytest.approx([roll, pitch, roll_rate, pitch_rate], abs=1e-9)


@pytest.mark.parametrize("tau", [0.5, 1.0, 4.0, 10.0])
def test_reversal_at_constant_acceleration_keeps_the_amplitude(tau):
    axis = SweepAxis(ROLL_A, ROLL_R, tau)
    period = 4 * ROLL_A / ROLL_R + tau
    assert axis.period == pytest.approx(period)
    # turning points at t = 0 and P/2, at exactly ±A and at rest
    assert axis(0.0)[:2] == (ROLL_A, 0.0)
    assert axis(period / 2)[0] == pytest.approx(-ROLL_A, abs=1e-15)
    assert axis(period / 2)[1] == pytest.approx(0.0, abs=1e-15)
    # rate ramps linearly from +r to −r over τ centred on the turning point
    for t0, sign in ((period, 1.0), (period / 2, -1.0)):
        for f in (-0.5, -0.25, 0.25, 0.5):
            assert axis(t0 + f * tau)[1] == pytest.approx(-sign * 2 * f * ROLL_R, abs=1e-12)
            if f < 0.5:  # a ramp begins at -τ/2 and ends before +τ/2 (right limits)
                assert axis(t0 + f * tau)[2] == pytest.approx(-sign * 2 * ROLL_R / tau)
            elif tau < 4 * ROLL_A / ROLL_R:  # (no constant rate at τ = 4A/r: the next ramp)
                assert axis(t0 + f * tau)[2] == 0.0
    t = np.linspace(0, 3 * period, 20001)
    angles = np.array([axis(x)[0] for x in t])
    assert angles.max() <= ROLL_A + 1e-15 and angles.min() >= -ROLL_A - 1e-15
    assert np.allclose(
        [axis(x + period)[:2] for x in t[:500]], [axis(x)[:2] for x in t[:500]], atol=1e-12
    )


@pytest.mark.parametrize("tau", [0.0, 1.0, 10.0])
def test_rate_and_acceleration_are_the_derivatives_of_the_angle(tau):
    axis, h = SweepAxis(ROLL_A, ROLL_R, tau), 1e-6
    half = (4 * ROLL_A / ROLL_R + tau) / 2
    kinks = [n * half + d for n in range(10) for d in (-tau / 2, tau / 2)]
    for t in np.linspace(0.013, 40.0, 1500):
        if min(abs(t - k) for k in kinks) < 2 * h:
            continue
        angle, rate, accel = axis(t)
        assert (axis(t + h)[0] - axis(t - h)[0]) / (2 * h) == pytest.approx(rate, abs=1e-8)
        assert (axis(t + h)[1] - axis(t - h)[1]) / (2 * h) == pytest.approx(accel, abs=1e-7)


@pytest.mark.parametrize("offset", [0.0, 1e-12, -1e-12, 3e-11])
@pytest.mark.parametrize("amplitude, rate", [(ROLL_A, ROLL_R), (PITCH_A, PITCH_R)])
def test_a_sample_on_a_switch_holds_the_piece_ahead(amplitude, rate, offset):
    """At (or within rounding of) the start of an arriving ramp the acceleration is the
    ramp's, and at the end of a leaving ramp the constant rate's: what a zero-order hold
    over the next step must carry.  The pitch axis' switch at 150 s is hit by the scenario's
    0.05 s grid; before the fix its sample there gave 0."""
    axis = SweepAxis(amplitude, rate, 1.0)
    half = axis.period / 2
    for k in range(4):
        arriving, leaving = k * half + half - 0.5, k * half + 0.5
        sign = 1.0 if k % 2 == 0 else -1.0
        assert axis(arriving + offset)[2] == pytest.approx(sign * 2 * rate / 1.0, rel=1e-12)
        assert axis(leaving + offset)[2] == 0.0
    assert SweepAxis(PITCH_A, PITCH_R, 1.0)(150.0)[2] == pytest.approx(2 * PITCH_R)


def test_rate_is_continuous_with_a_turnaround():
    axis, dt = SweepAxis(PITCH_A, PITCH_R, 1.0), 0.002
    rates = np.array([axis(x)[1] for x in np.arange(0, 305, dt)])
    assert np.abs(np.diff(rates)).max() <= 2 * PITCH_R / 1.0 * dt * (1 + 1e-9)


@pytest.mark.parametrize("symmetric, sign", [(True, -1.0), (False, 1.0)])
def test_payload_2_mirrors_or_follows_payload_1(symmetric, sign):
    for t in (0.0, 3.3, 123.4):
        planner = planner_at(t, symmetric=symmetric)
        for name in COMMANDS:
            first, second = planner.get(name)
            assert second == sign * first


def test_default_turnaround_and_periods():
    planner = SweepPlanner().start()
    assert planner.p.turnaround_time > 0
    assert planner.roll.period == pytest.approx(10.0 + planner.p.turnaround_time)
    assert planner.pitch.period == pytest.approx(300.0 + planner.p.turnaround_time)


def test_a_zero_amplitude_parks_the_axis():
    planner = planner_at(12.0, pitch_amplitude=0.0, pitch_rate=0.0)
    assert planner.get("pitch_cmd").tolist() == [0.0, 0.0]
    assert planner.get("pitch_rate_cmd").tolist() == [0.0, 0.0]


@pytest.mark.parametrize(
    "parameters, message",
    [
        (
            {"turnaround_time": 10.5},
            r"turnaround_time 10.5 s is too long for the roll sweep.*= 10 s",
        ),
        ({"turnaround_time": -1.0}, "turnaround_time must be finite and >= 0"),
        ({"roll_rate": 0.0}, "roll_rate must be finite and > 0"),
        ({"pitch_amplitude": -0.1}, "pitch_amplitude must be finite and >= 0"),
    ],
)
def test_bad_planner_parameters_are_rejected(parameters, message):
    with pytest.raises(ModelError, match=message):
        SweepPlanner(**parameters).start()
