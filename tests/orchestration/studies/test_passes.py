"""Pass geometry (closest approach, look angle) and pass design, checked against geometry
recomputed here from OrbitEnvironment's outputs, and the video-SAR paper's example."""

import math

import numpy as np
import pytest

from agilesat.components.ephemeris import DAY, gmst
from agilesat.components.model import ModelError
from agilesat.components.orbit_environment import MU_EARTH, WGS84_A, OrbitEnvironment
from agilesat.components.rotations import dcm_from_quat
from agilesat.orchestration.studies.passes import (
    PassGeometry,
    design_pass,
    find_pass,
    find_passes,
    sun_synchronous_inclination,
)

# The video-SAR paper (Liang et al. 2019, §4): Sasebo, zero Doppler at 2016-11-25 08:09:43
# UTC, 567 km sun-synchronous, 30° look angle, 200 s of staring centred on zero Doppler
SASEBO = (math.radians(33.16), math.radians(129.72), 0.0)
T_ZERO_DOPPLER = "2016-11-25T08:09:43"
ALTITUDE = 567e3
LOOK = math.radians(30.0)

CBERS2 = (
    "1 28057U 03049A   06177.78615833  .00000060  00000-0  35940-4 0  1836",
    "2 28057  98.4283 247.6961 0000884  88.1964 271.9322 14.35478080140550",
)


def outputs(parameters, t):
    m = OrbitEnvironment(**parameters).start(0.0)
    if t:
        m.advance(0.0, t)
    return {n: m.get(n) for n in ("r_I", "v_I", "q_OI", "r_T_I", "v_T_I", "earth_angle")}


def geometry(parameters, t):
    """Recomputed here: squint (sin), look angle, slant range, elevation, side, node."""
    s = outputs(parameters, t)
    rho = s["r_I"] - s["r_T_I"]  # target to satellite
    v_rel = s["v_I"] - s["v_T_I"]
    slant = np.linalg.norm(rho)
    nadir = -s["r_I"] / np.linalg.norm(s["r_I"])
    los = -rho / slant
    look = math.atan2(np.linalg.norm(np.cross(nadir, los)), nadir @ los)
    # the target's ellipsoid normal: geodetic latitude and longitude, turned by the
    # Earth angle
    lat, lon = parameters.get("target_lat", 0.0), parameters.get("target_lon", 0.0)
    east = lon + s["earth_angle"]
    normal = np.array(
        [math.cos(lat) * math.cos(east), math.cos(lat) * math.sin(east), math.sin(lat)]
    )
    elevation = math.asin(rho @ normal / slant)
    los_O = dcm_from_quat(s["q_OI"]) @ los  # y_O to the right, z_O to nadir
    return dict(
        squint=rho @ v_rel / (slant * np.linalg.norm(v_rel)),
        look=look,
        slant=slant,
        elevation=elevation,
        side="right" if los_O[1] > 0 else "left",
        ascending=s["v_I"][2] > 0,
        rho=rho,
        los_O=los_O,
    )


# -- find_pass ----------------------------------------------------------------------------
ORBIT = dict(
    semi_major_axis=WGS84_A + 600e3,
    inclination=math.radians(97.8),
    j2=True,
    raan=math.radians(200.0),
    true_anomaly0=math.radians(10.0),
    epoch="2021-03-20T00:00:00",
    target_lat=math.radians(48.1),
    target_lon=math.radians(11.6),
    target_alt=520.0,
)


@pytest.mark.slow
@pytest.mark.parametrize(
    "parameters",
    [
        ORBIT,
        dict(ORBIT, epoch="", earth_angle0=1.0),
        dict(tle_line1=CBERS2[0], tle_line2=CBERS2[1], target_lat=-0.4, target_lon=2.5),
    ],
    ids=["elements", "no-epoch", "tle"],
)
def test_find_pass_is_zero_doppler_with_the_geometry_there(parameters):
    found = find_pass(parameters, 0.0, DAY)
    g = geometry(parameters, found.time)
    assert abs(g["squint"]) < 1e-9  # (r − r_T)·(v − v_T) = 0
    assert found.look_angle == pytest.approx(g["look"], abs=1e-12)
    assert found.slant_range == pytest.approx(g["slant"], rel=1e-14)
    assert found.elevation == pytest.approx(g["elevation"], abs=1e-12)
    assert found.side == g["side"] and found.ascending == g["ascending"]
    assert found.visible and g["elevation"] > 0
    # a minimum of the range, and the smallest of the day's visible minima
    for dt in (-1.0, 1.0):
        assert geometry(parameters, found.time + dt)["slant"] > found.slant_range
    passes = find_passes(parameters, 0.0, DAY)
    assert found in passes and all(p.slant_range >= found.slant_range for p in passes)
    assert [p.time for p in passes] == sorted(p.time for p in passes)


@pytest.mark.slow
def test_find_passes_sees_every_range_minimum():
    """Sampled brute force: every local minimum of |r − r_T| over 6 h is found."""
    t = np.arange(0.0, 6 * 3600.0, 5.0)
    slant = np.array([geometry(ORBIT, s)["slant"] for s in t])
    minima = t[1:-1][(slant[1:-1] < slant[:-2]) & (slant[1:-1] < slant[2:])]
    found = find_passes(ORBIT, 0.0, 6 * 3600.0, visible_only=False)
    assert len(found) == len(minima)
    assert np.allclose([p.time for p in found], minima, atol=5.0)
    visible = find_passes(ORBIT, 0.0, 6 * 3600.0)
    assert visible == [p for p in found if p.elevation > 0]
    assert len(visible) < len(found)


def test_find_pass_without_a_visible_pass_raises():
    polar_target = dict(ORBIT, inclination=math.radians(20.0), target_lat=math.radians(85.0))
    with pytest.raises(ModelError, match="no visible pass"):
        find_pass(polar_target, 0.0, 3 * 3600.0)


def test_find_pass_target_argument_overrides_the_parameters():
    other = (math.radians(-33.9), math.radians(18.4), 10.0)
    a = find_pass(ORBIT, 0.0, DAY, target=other)
    b = find_pass(
        dict(ORBIT, target_lat=other[0], target_lon=other[1], target_alt=other[2]), 0.0, DAY
    )
    assert a == b


# -- design_pass --------------------------------------------------------------------------
def test_sun_synchronous_inclination_from_the_measured_node_drift():
    """The node, measured where the satellite crosses the equator northward (r_z = 0),
    turns once per tropical year (365.2421897 days) eastward."""
    a = WGS84_A + ALTITUDE
    i = sun_synchronous_inclination(a)
    assert math.degrees(i) == pytest.approx(97.66, abs=0.01)  # 567 km: ≈ 97.7° (tables)
    p = dict(semi_major_axis=a, inclination=i, j2=True, true_anomaly0=-0.3)

    def node_crossing(t_before):
        """First northward equator crossing after t_before: (time, node longitude in I)."""
        lo = t_before
        while not outputs(p, lo)["r_I"][2] < 0 < outputs(p, lo + 30.0)["r_I"][2]:
            lo += 30.0
        hi = lo + 30.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if outputs(p, mid)["r_I"][2] < 0 else (lo, mid)
        r = outputs(p, lo)["r_I"]
        return lo, math.atan2(r[1], r[0])

    t1, node1 = node_crossing(0.0)
    draconic = node_crossing(t1 + 60.0)[0] - t1
    t2, node2 = node_crossing(t1 + 290 * draconic - 300.0)  # ≈ 20 days later
    rate = math.remainder(node2 - node1, 2 * math.pi) / (t2 - t1)
    assert rate == pytest.approx(2 * math.pi / (365.2421897 * DAY), rel=1e-6)


@pytest.mark.parametrize("side", ["right", "left"])
@pytest.mark.parametrize("node", ["ascending", "descending"])
def test_design_pass_paper_example(side, node):
    """At the epoch: zero Doppler, 30° off nadir on the asked side and node, visible."""
    p = design_pass(ALTITUDE, *SASEBO, T_ZERO_DOPPLER, LOOK, side, node)
    assert p["epoch"] == T_ZERO_DOPPLER and p["eccentricity"] == 0.0
    assert p["semi_major_axis"] == WGS84_A + ALTITUDE and p["j2"]
    assert p["inclination"] == sun_synchronous_inclination(WGS84_A + ALTITUDE)
    g = geometry(p, 0.0)
    assert abs(g["squint"]) < 1e-9
    assert g["look"] == pytest.approx(LOOK, abs=1e-6)
    assert g["side"] == side and g["ascending"] == (node == "ascending")
    assert g["elevation"] > math.radians(50.0)
    # law of sines (Earth centre O, satellite S, target T): |ρ| / sin γ = |r_T| / sin η,
    # with the angle at T obtuse (target sees the satellite above its horizon):
    # γ = asin(a sin η / |r_T|) − η
    s = outputs(p, 0.0)
    a, rT = np.linalg.norm(s["r_I"]), np.linalg.norm(s["r_T_I"])
    gamma = math.asin(a * math.sin(LOOK) / rT) - LOOK
    assert g["slant"] == pytest.approx(rT * math.sin(gamma) / math.sin(LOOK), rel=1e-9)
    assert g["slant"] == pytest.approx(672.3e3, abs=100.0)
    # the closest approach of the day is this one
    assert find_pass(p, -DAY / 2, DAY / 2).time == pytest.approx(0.0, abs=1e-6)


def test_design_pass_for_200_s_of_staring_centred_on_zero_doppler():
    p = design_pass(ALTITUDE, *SASEBO, T_ZERO_DOPPLER, LOOK, t0=100.0)
    assert p["epoch"] == "2016-11-25T08:08:03"  # the paper's start of observation
    found = find_pass(p, 0.0, 200.0)
    assert found.time == pytest.approx(100.0, abs=1e-6)
    assert found.look_angle == pytest.approx(LOOK, abs=1e-9)
    assert found.side == "right" and found.ascending
    # the same orbit as designed at the zero-Doppler time, shifted by 100 s
    q = design_pass(ALTITUDE, *SASEBO, T_ZERO_DOPPLER, LOOK)
    a, b = outputs(p, 100.0), outputs(q, 0.0)
    assert np.allclose(a["r_I"], b["r_I"], rtol=0, atol=1e-4)
    assert a["earth_angle"] == pytest.approx(b["earth_angle"], abs=1e-12)
    assert b["earth_angle"] == pytest.approx(gmst(T_ZERO_DOPPLER), abs=1e-15)
    # the target stays in view during the 200 s, on the right; the look angle is
    # smallest at zero Doppler and grows to ≈ 51° at ±100 s (±700 km along track)
    looks = []
    for t in (0.0, 50.0, 150.0, 200.0):
        g = geometry(p, t)
        assert g["elevation"] > math.radians(30.0) and g["side"] == "right"
        looks.append(g["look"])
    assert LOOK < looks[1] < looks[0] and LOOK < looks[2] < looks[3]
    # against a sphere without rotation: the satellite 100 s of orbit (n Δt) along track
    # from broadside of a target at the Earth central angle γ of the 30° look
    a, R = WGS84_A + ALTITUDE, np.linalg.norm(outputs(p, 100.0)["r_T_I"])
    gamma = math.asin(a * math.sin(LOOK) / R) - LOOK
    beta = math.sqrt(MU_EARTH / a**3) * 100.0
    s, target = (
        a * np.array([math.cos(beta), math.sin(beta), 0.0]),
        R * np.array([math.cos(gamma), 0.0, math.sin(gamma)]),
    )
    sphere = math.acos(-s @ (target - s) / a / np.linalg.norm(target - s))  # 50.97°
    assert looks[0] == pytest.approx(sphere, abs=math.radians(0.5))  # 51.29°


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        (dict(side="up"), ValueError, "side must be"),
        (dict(node="north"), ValueError, "node must be"),
        (dict(look_angle=math.radians(70.0)), ModelError, "look_angle must be in"),
        (dict(look_angle=0.0), ModelError, "look_angle must be in"),
        (dict(epoch="2016-11-25"), ModelError, "is not ISO-8601 UTC"),
        (
            dict(target_lat=math.radians(89.0), look_angle=math.radians(5.0)),
            ModelError,
            "cannot be seen",
        ),
    ],
)
def test_design_pass_bad_arguments(kwargs, error, match):
    arguments = dict(
        altitude=ALTITUDE,
        target_lat=SASEBO[0],
        target_lon=SASEBO[1],
        target_alt=0.0,
        epoch=T_ZERO_DOPPLER,
        look_angle=LOOK,
    )
    arguments.update(kwargs)
    with pytest.raises(error, match=match):
        design_pass(**arguments)


def test_pass_geometry_is_a_plain_record():
    g = find_pass(ORBIT, 0.0, DAY)
    assert isinstance(g, PassGeometry) and g.visible
    assert g.incidence_angle == pytest.approx(math.pi / 2 - g.elevation, abs=1e-15)
    assert g.incidence_angle > g.look_angle  # Earth curvature


@pytest.mark.slow
def test_the_frozen_video_sar_design_values_are_the_solved_ones():
    """video_sar ships its pass, cluster start and initial state as literals (the committed
    .ssd must not depend on the solver's last bits); solving again reproduces them."""
    from agilesat.components.cmg_cluster import (
        DEFAULT_SPINS,
        GIMBAL_AXES,
        ClusterGeometry,
        zero_momentum_angles,
    )
    from agilesat.orchestration.scenarios import video_sar as v
    from agilesat.orchestration.scenarios.constants import VIDEO_SAR_ALTITUDE, VIDEO_SAR_LOOK_ANGLE
    from agilesat.orchestration.scenarios.scan_pitch import PAPER_DELTA0

    solved = design_pass(
        VIDEO_SAR_ALTITUDE,
        *v.TARGET,
        v.ZERO_DOPPLER,
        VIDEO_SAR_LOOK_ANGLE,
        "right",
        "ascending",
        t0=v.HALF_STARE,
    )
    assert solved.keys() == v.PASS.keys()
    for key, value in solved.items():
        assert (
            value == v.PASS[key]
            if not isinstance(value, float)
            else abs(value - v.PASS[key]) <= 5e-13
        ), key
    delta = zero_momentum_angles(
        ClusterGeometry(v.H_ROTOR, GIMBAL_AXES, DEFAULT_SPINS), PAPER_DELTA0
    )
    assert np.max(np.abs(delta - v.DELTA0)) <= 5e-10
    for guidance, frozen in (
        (v.GUIDANCE, v.ON_REFERENCE),
        (dict(v.GUIDANCE, yaw_compensation=False), v.ON_REFERENCE_YAW_0),
    ):
        state = v.initial_state(v.ORBIT, guidance)
        assert np.max(np.abs(np.subtract(state, frozen))) <= 5e-13
