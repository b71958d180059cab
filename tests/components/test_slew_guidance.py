"""SlewGuidance against closed forms and independent geometry: the least time of a rate-
and acceleration-limited rest-to-rest slew (θ/ω + ω/α, 2√(θ/α)), the jerk-limited one
(+ α/j), the rotation vector's kinematics by central differences, continuity of q, ω, ω̇
measured across every switch of a nadir → stare → stare → nadir timeline over the video_sar
pass (OrbitEnvironment, the paper's target and a second one), the boresight on each target
(line of sight from OrbitEnvironment's r_I and the target's WGS-84 position) and the
footprint's ground azimuth held by the yaw compensation."""

import math

import numpy as np
import pytest

from agilesat.components import slew
from agilesat.components.model import ModelError
from agilesat.components.orbit_environment import OrbitEnvironment, geodetic_to_ecef
from agilesat.components.rotations import dcm_from_quat, quat_mul
from agilesat.components.slew_guidance import N_SEGMENTS, NADIR, SLEW, STARE, SlewGuidance
from agilesat.components.staring_guidance import footprint_azimuth
from agilesat.orchestration.mission import deg, inertial, nadir, stare, timeline
from agilesat.orchestration.scenarios.video_sar import ORBIT

DEG = math.pi / 180
RATE, ACCEL, JERK = 2.0 * DEG, 0.5 * DEG, 0.5 * DEG
ORBIT_INPUTS = ("r_I", "v_I", "q_OI", "w_OI_O", "earth_angle")
OUTPUTS = ("q_ref", "w_ref", "dw_ref", "mode", "segment", "slewing")
TARGET_A = (ORBIT["target_lat"], ORBIT["target_lon"])
TARGET_B = (TARGET_A[0] + 0.4 * DEG, TARGET_A[1] + 0.5 * DEG)
PASS = timeline(
    nadir(0.0), stare(10.0, *TARGET_A), stare(110.0, *TARGET_B), nadir(190.0)
)  # fmt: skip


def run(model, times, orbit=None) -> dict:
    """The outputs at ``times`` (any steps), the orbit's inputs fed at each."""
    rows = []
    for k, t in enumerate(times):
        if orbit is not None:
            orbit.advance(0.0, t)  # a pure function of time
            for name in ORBIT_INPUTS:
                model.set(name, orbit.get(name))
        model.start(t) if k == 0 else model.advance(times[k - 1], t - times[k - 1])
        rows.append([model.get(name) for name in OUTPUTS])
    out = {name: np.array([row[i] for row in rows]) for i, name in enumerate(OUTPUTS)}
    out["time"] = np.asarray(times)
    return out


def rotation_vector(q) -> np.ndarray:
    q = np.asarray(q) * (1.0 if q[0] >= 0 else -1.0)
    s = np.linalg.norm(q[1:])
    return 2.0 * math.atan2(s, q[0]) * q[1:] / s if s > 0 else np.zeros(3)


# -- rest-to-rest: the closed forms ----------------------------------------------------------
def closed_form(angle, rate, accel, jerk=math.inf):
    """DESIGN.md §3.2 (bang-coast-bang); with a jerk limit reached with both others,
    + α/j ([Biagiotti 2008] §3.4)."""
    if math.isfinite(jerk):
        assert angle >= rate * (rate / accel + accel / jerk) and rate >= accel**2 / jerk
        return angle / rate + rate / accel + accel / jerk
    if angle >= rate**2 / accel:
        return angle / rate + rate / accel
    return 2.0 * math.sqrt(angle / accel)


@pytest.mark.parametrize(
    "angle, jerk",
    [(60 * DEG, math.inf), (3 * DEG, math.inf), (60 * DEG, JERK)],
    ids=["coast", "no-coast", "jerk-limited"],
)
def test_a_rest_to_rest_slew_takes_the_closed_form_least_time(angle, jerk):
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    q0 = np.array([0.8, 0.2, -0.4, 0.4]) / np.linalg.norm([0.8, 0.2, -0.4, 0.4])
    target = quat_mul(q0, np.concatenate(([math.cos(angle / 2)], math.sin(angle / 2) * axis)))
    dt, start = 0.04, 5.0
    expected = closed_form(angle, RATE, ACCEL, jerk)
    guidance = SlewGuidance(
        q_initial=q0, q_target=target, slew_start=start, rate_limit=RATE,
        accel_limit=ACCEL, jerk_limit=jerk,
    )  # fmt: skip
    out = run(guidance, np.arange(int(round((start + expected + 1.0) / dt)) + 1) * dt)
    t, slewing = out["time"], out["slewing"].astype(bool)
    assert (
        t[slewing][0] == start and t[slewing][-1] < start + expected <= t[~slewing & (t > start)][0]
    )
    assert np.all(out["mode"][slewing] == SLEW) and np.all(out["mode"][~slewing] == 1)
    assert np.allclose(out["q_ref"][-1], target, atol=1e-12)
    w, dw = np.linalg.norm(out["w_ref"], axis=1), np.linalg.norm(out["dw_ref"], axis=1)
    assert w.max() <= RATE * (1 + 1e-12) and dw.max() <= ACCEL * (1 + 1e-12)
    peak = RATE if angle >= RATE**2 / ACCEL else math.sqrt(angle * ACCEL)  # no coast: √(θα)
    assert peak - ACCEL * dt <= w.max() and dw.max() == pytest.approx(ACCEL)  # sampled
    # an eigenaxis slew: every reference is q0 turned about the one axis
    turned = np.array([rotation_vector(quat_mul(q0 * [1, -1, -1, -1], q)) for q in out["q_ref"]])
    assert np.allclose(np.cross(turned, axis), 0.0, atol=1e-12)
    assert np.all(turned @ axis >= -1e-15)
    if math.isfinite(jerk):  # the acceleration changes at most by j per unit time
        assert np.abs(np.diff(out["dw_ref"], axis=0)).max() <= JERK * dt * (1 + 1e-9)


def test_the_angle_profile_reaches_its_angle_within_every_limit():
    rng = np.random.default_rng(3)
    for _ in range(40):
        angle, rate, accel = rng.uniform(1e-3, 3.0), rng.uniform(0.01, 0.1), rng.uniform(1e-3, 0.02)
        jerk = rng.choice([math.inf, rng.uniform(1e-3, 0.05)])
        phases = slew.profile(angle, rate, accel, jerk)
        T = slew.duration(phases)
        tau = np.linspace(0.0, T, 501)
        p, v, a = np.array([slew.at(phases, x) for x in tau]).T
        assert p[-1] == pytest.approx(angle, rel=1e-12) and v[-1] == pytest.approx(0.0, abs=1e-12)
        assert np.all(np.diff(p) >= -1e-15) and v.max() <= rate * (1 + 1e-12)
        assert np.abs(a).max() <= accel * (1 + 1e-12)
        # the least time: no faster than the limits allow one by one
        assert T >= angle / rate and T >= 2 * math.sqrt(angle / accel) * (1 - 1e-12)
        if math.isfinite(jerk):
            assert T >= (32 * angle / jerk) ** (1 / 3) * (1 - 1e-12)
            assert np.abs(np.diff(a)).max() <= jerk * T / 500 * (1 + 1e-9)


# -- the blend of two moving frames: kinematics by central differences -----------------------
def moving(q0, axis, c1, c2, t):
    """q0 turned about a fixed body axis by c1 t + c2 t²: (q, ω, ω̇) in its own axes."""
    n = np.asarray(axis) / np.linalg.norm(axis)
    angle = c1 * t + c2 * t * t
    q = quat_mul(q0, np.concatenate(([math.cos(angle / 2)], math.sin(angle / 2) * n)))
    return tuple(q), tuple((c1 + 2 * c2 * t) * n), tuple(2 * c2 * n)


QA = np.array([0.9, 0.1, -0.3, 0.2]) / np.linalg.norm([0.9, 0.1, -0.3, 0.2])
QB = np.array([0.2, 0.7, 0.3, -0.4]) / np.linalg.norm([0.2, 0.7, 0.3, -0.4])


def blended(t):
    a, b = moving(QA, (1, 2, 3), 0.05, 0.01, t), moving(QB, (-1, 0.5, 2), -0.03, 0.02, t)
    q_D = quat_mul(np.array(a[0]) * [1, -1, -1, -1], b[0])
    L, dL, ddL = slew.relative(a, b, tuple(q_D if q_D[0] >= 0 else -q_D))
    return slew.blend(a, L, dL, ddL, 0.3 + 0.2 * t + 0.1 * t * t, 0.2 + 0.2 * t, 0.2), a, b


@pytest.mark.parametrize("t", [0.0, 0.7, 1.5])
def test_the_blend_rate_and_acceleration_are_the_derivatives_of_its_attitude(t):
    h = 1e-5
    (q, w, dw), _, _ = blended(t)
    dq = (np.array(blended(t + h)[0][0]) - np.array(blended(t - h)[0][0])) / (2 * h)
    assert np.allclose(2 * quat_mul(np.array(q) * [1, -1, -1, -1], dq)[1:], w, atol=1e-9)
    dw_fd = (np.array(blended(t + h)[0][1]) - np.array(blended(t - h)[0][1])) / (2 * h)
    assert np.allclose(dw_fd, dw, atol=1e-9)


def test_the_blend_is_frame_a_at_its_start_and_frame_b_at_its_end():
    a, b = moving(QA, (1, 2, 3), 0.05, 0.01, 0.4), moving(QB, (-1, 0.5, 2), -0.03, 0.02, 0.4)
    q_D = quat_mul(np.array(a[0]) * [1, -1, -1, -1], b[0])
    L, dL, ddL = slew.relative(a, b, tuple(q_D))
    for s, frame in ((0.0, a), (1.0, b)):
        for got, want in zip(slew.blend(a, L, dL, ddL, s, 0.0, 0.0), frame):
            assert np.allclose(got, want, atol=1e-15)


@pytest.mark.parametrize("size", [1e-6, 0.1, 0.19, 0.21, 1.0, 3.0])
def test_the_jacobian_its_inverse_and_its_rate(size):
    """J⁻¹ inverts J; J̇ v is the central difference of J along ψ̇ (series and closed
    forms, either side of where they meet)."""
    psi = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8]) * size
    v, d, h = np.array([0.2, 0.4, -0.1]), np.array([0.05, -0.02, 0.07]), 1e-5
    back = slew.jacobian_inverse(tuple(psi), slew.jacobian(tuple(psi), tuple(v)))
    assert np.allclose(back, v, atol=1e-15)
    fd = (np.array(slew.jacobian(psi + h * d, v)) - np.array(slew.jacobian(psi - h * d, v))) / (
        2 * h
    )
    assert np.allclose(slew.jacobian_rate(tuple(psi), tuple(d), tuple(v)), fd, atol=1e-11)


# -- a four-segment pass: nadir → stare A → stare B → nadir ---------------------------------
EPSILON = 1e-4  # s either side of a switch


def pass_run(step=0.5, stop=260.0, extra=(), **parameters):
    times = np.union1d(np.arange(int(stop / step) + 1) * step, extra)
    guidance = SlewGuidance(**PASS, **parameters)
    ends = []
    original = guidance._plan

    def remember(t):  # the slews' end times, to place points around them
        plan = original(t)
        ends.append(plan.end)
        return plan

    guidance._plan = remember
    return run(guidance, times, OrbitEnvironment(**ORBIT).start(0.0)), ends


def at(times, t) -> int:
    """The index of time t."""
    return int(np.flatnonzero(np.isclose(times, t, atol=1e-9, rtol=0))[0])


@pytest.fixture(scope="module")
def four_segments():
    """The pass on a 0.5-s grid with points ε either side of every switch (the slews'
    ends found by a first run: the plans are made at the segments' starts, on the grid)."""
    _, ends = pass_run()
    starts = [10.0, 110.0, 190.0]
    switches = sorted(starts + ends)
    out, again = pass_run(extra=[s + e for s in switches for e in (-EPSILON, EPSILON)])
    assert again == ends
    return out, switches


def test_the_pass_enters_every_segment_in_turn(four_segments):
    out, switches = four_segments
    t, mode, segment = out["time"], out["mode"], out["segment"]
    for (low, high), kind, number in zip(
        zip([0.0] + switches, switches + [t[-1] + 1]),
        [NADIR, SLEW, STARE, SLEW, STARE, SLEW, NADIR],
        [1, 2, 2, 3, 3, 4, 4],
    ):
        inside = (t >= low) & (t < high)
        assert np.all(mode[inside] == kind) and np.all(segment[inside] == number)
    assert np.array_equal(out["slewing"], mode == SLEW)


def test_q_w_and_dw_are_continuous_at_every_switch(four_segments):
    """Across 2ε at each switch every output moves by what its derivative allows: |Δq| ≤
    2ε |ω|/2·1.01, |Δω| ≤ 2ε α, |Δω̇| ≤ 2ε 2j (a step of ω̇ there would be ≈ α)."""
    out, switches = four_segments
    t = out["time"]
    for switch in switches:
        before, after = at(t, switch - EPSILON), at(t, switch + EPSILON)
        dq = out["q_ref"][after] - out["q_ref"][before]
        dw = out["w_ref"][after] - out["w_ref"][before]
        ddw = out["dw_ref"][after] - out["dw_ref"][before]
        assert np.linalg.norm(dq) <= 2 * EPSILON * RATE / 2 * 1.01, switch
        assert np.linalg.norm(dw) <= 2 * EPSILON * ACCEL * 1.01, switch
        assert np.linalg.norm(ddw) <= 2 * EPSILON * 2 * JERK, switch


def test_without_a_jerk_limit_the_acceleration_steps_at_the_switches():
    """The control of the test above: the measurement sees a step of ω̇ where there is one."""
    _, ends = pass_run(stop=50.0, jerk_limit=math.inf)
    out, _ = pass_run(stop=50.0, jerk_limit=math.inf, extra=[ends[0] - EPSILON, ends[0] + EPSILON])
    before = at(out["time"], ends[0] - EPSILON)
    assert np.linalg.norm(out["dw_ref"][before + 1] - out["dw_ref"][before]) > 0.5 * ACCEL


def test_the_pass_stays_within_the_limits(four_segments):
    """Checked at 32 instants of each slew on a two-body prediction: between them and on
    the J2 orbit the reference may exceed a limit by a sliver."""
    out, _ = four_segments
    assert np.linalg.norm(out["w_ref"], axis=1).max() <= RATE * 1.001
    assert np.linalg.norm(out["dw_ref"], axis=1).max() <= ACCEL * 1.001


def test_each_stare_holds_the_boresight_on_its_target_and_the_footprint_on_the_ground(
    four_segments,
):
    out, switches = four_segments
    orbit = OrbitEnvironment(**ORBIT).start(0.0)
    t = out["time"]
    for (lat, lon), (low, high) in zip((TARGET_A, TARGET_B), (switches[1:3], switches[3:5])):
        inside = np.flatnonzero((t >= low) & (t < high))
        azimuths = []
        for i in inside:
            orbit.advance(0.0, t[i])
            angle = orbit.get("earth_angle")
            c, s = math.cos(angle), math.sin(angle)
            r_T = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ geodetic_to_ecef(lat, lon, 0.0)
            los = (r_T - orbit.get("r_I")) / np.linalg.norm(r_T - orbit.get("r_I"))
            assert dcm_from_quat(out["q_ref"][i]).T @ [0, 0, 1] == pytest.approx(los, abs=1e-12)
            azimuths.append(footprint_azimuth(out["q_ref"][i], r_T))
        assert np.ptp(azimuths) < 1e-9  # the footprint does not turn on the ground


@pytest.mark.parametrize("accel, rate", [(0.1, 1.0), (0.02, 2.0)], ids=["margin", "stretch"])
def test_a_short_slew_between_two_stares_stays_within_tight_limits(accel, rate):
    """Two targets 2 km apart: the frames' own rates (up to 0.6 °/s) and the change between
    them, not the angle, decide the slew (limits reduced by the frames' motion, or the
    profile stretched in time); the reference stays within the limits throughout."""
    table = timeline(stare(0.0, *TARGET_A), stare(60.0, TARGET_A[0] + 0.02 * DEG, TARGET_A[1]))
    guidance = SlewGuidance(**table, accel_limit=accel * DEG, rate_limit=rate * DEG)
    out = run(guidance, np.arange(0.0, 180.0, 0.5), OrbitEnvironment(**ORBIT).start(0.0))
    assert np.any(out["slewing"]) and not out["slewing"][-1]
    assert np.linalg.norm(out["w_ref"], axis=1).max() <= rate * DEG * 1.001
    assert np.linalg.norm(out["dw_ref"], axis=1).max() <= accel * DEG * 1.001


def test_frames_faster_than_the_limits_are_refused():
    table = timeline(stare(0.0, *TARGET_A), stare(60.0, TARGET_A[0] + 0.02 * DEG, TARGET_A[1]))
    guidance = SlewGuidance(**table, rate_limit=0.6 * DEG)
    with pytest.raises(ModelError, match=r"segments 1 and 2 turn at up to 0.01\d* rad/s"):
        run(guidance, np.arange(0.0, 70.0, 1.0), OrbitEnvironment(**ORBIT).start(0.0))


def test_a_slew_that_would_end_after_the_next_segment_starts_is_refused():
    parameters = timeline(inertial(0.0, (1, 0, 0, 0)), inertial(1.0, (0, 1, 0, 0)))
    parameters["segment_count"] = 3
    parameters["segment_kind"][2], parameters["segment_start"][2] = 1, 20.0
    guidance = SlewGuidance(**parameters).start(0.0)
    with pytest.raises(
        ModelError,
        match=r"slew into segment 2 .* 180 deg.* ends at 96 s, after segment 3 starts at 20 s",
    ):
        guidance.advance(0.0, 1.0)


@pytest.mark.parametrize(
    "change, match",
    [
        ({"segment_count": N_SEGMENTS + 1}, "segment_count must be 0 to 10"),
        ({"segment_kind": [1, 4] + [0] * 8}, r"segment_kind\[2\] must be 1 = INERTIAL"),
        ({"segment_start": [0.0, 5.0, 5.0] + [0.0] * 7}, "segment_start must increase"),
        ({"segment_start": [1.0, 5.0, 6.0] + [0.0] * 7}, "after the start 0.0 s"),
        ({"segment_q": [[2, 0, 0, 0]] * N_SEGMENTS}, r"segment_q\[1,:\] must be a unit"),
        ({"rate_limit": 0.0}, "rate_limit must be finite and > 0"),
        ({"jerk_limit": -1.0}, "jerk_limit must be > 0"),
    ],
)
def test_bad_tables_are_named(change, match):
    parameters = timeline(inertial(0.0, (1, 0, 0, 0)), nadir(5.0), inertial(6.0, (1, 0, 0, 0)))
    parameters.update(change)
    with pytest.raises(ModelError, match=match):
        SlewGuidance(**parameters).start(0.0)


def test_a_restored_state_continues_the_slew_bit_for_bit():
    guidance = SlewGuidance(slew_start=1.0).start(0.0)
    for k in range(30):
        guidance.advance(0.1 * k, 0.1)
    state = guidance.get_state()
    guidance.advance(3.0, 0.1)
    expected = guidance.get("q_ref"), guidance.get("dw_ref")
    other = SlewGuidance(slew_start=1.0).start(0.0)
    other.set_state(state)
    other.advance(3.0, 0.1)
    assert np.array_equal(other.get("q_ref"), expected[0])
    assert np.array_equal(other.get("dw_ref"), expected[1])


def test_a_timeline_is_the_table_a_host_sets():
    table = timeline(nadir(0.0, roll=deg(25)), stare(60.0, deg(30), "120 deg", 10.0))
    assert table["segment_count"] == 2
    assert table["segment_kind"][:2] == [NADIR, STARE] and len(table["segment_kind"]) == N_SEGMENTS
    half = 12.5 * DEG
    assert table["segment_q"][0] == pytest.approx([math.cos(half), math.sin(half), 0, 0])
    target = (table["target_lat"][1], table["target_lon"][1], table["target_alt"][1])
    assert target == pytest.approx((30 * DEG, 120 * DEG, 10.0))
    with pytest.raises(ValueError, match="1 to 10 segments"):
        timeline(*[nadir(float(k)) for k in range(N_SEGMENTS + 1)])
