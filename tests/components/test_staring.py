"""StaringGuidance against truth built here with NumPy: a real pass from OrbitEnvironment
(567 km sun-synchronous, target 33.16° N 129.72° E seen 30° off nadir at t = 0), the
paper's eqs 10–11, the footprint's ground line measured in the target's Earth-fixed
east/north frame, and Richardson-extrapolated central differences of q_ref and w_ref."""

import math

import numpy as np
import pytest

from agilesat.components import staring_guidance
from agilesat.components.model import ModelError
from agilesat.components.orbit_environment import (
    J2,
    J2_RADIUS,
    MU_EARTH,
    WGS84_A,
    OrbitEnvironment,
    geodetic_to_ecef,
)
from agilesat.components.rotations import (
    dcm_from_euler123,
    dcm_from_quat,
    euler123_rates,
    quat_from_dcm,
)
from agilesat.components.staring_guidance import StaringGuidance, footprint_azimuth
from agilesat.fmus.model_description import UNITS

DEG = math.pi / 180
INPUTS = ("r_I", "v_I", "r_T_I", "v_T_I", "q_OI")
A = WGS84_A + 567e3
LAT, LON = 33.16 * DEG, 129.72 * DEG
LOOK = 30 * DEG
STARE = 100.0  # s each side of closest approach
TILTED = (0.0, -math.sin(20 * DEG), math.cos(20 * DEG))


# -- geometry, independent of the model under test -----------------------------------------
def sso_inclination(a=A):
    """Ω̇ = −3/2 n J2 (R/a)² cos i = 2π per tropical year."""
    n = math.sqrt(MU_EARTH / a**3)
    return math.acos(-2 * math.pi / (365.2421897 * 86400) / (1.5 * n * J2 * (J2_RADIUS / a) ** 2))


def pass_parameters(look=LOOK, side=1.0, northbound=False, **extra):
    """OrbitEnvironment parameters (earth_angle0 = 0, circular) such that at t = 0 the
    target lies in the plane of r and the orbit normal (inertial broadside), ``look`` off
    the geocentric nadir, right (side 1) or left (side −1) of the track."""
    inc = sso_inclination()
    r_T = np.array(geodetic_to_ecef(LAT, LON, 0.0))
    t_hat = r_T / np.linalg.norm(r_T)
    gamma = math.asin(A * math.sin(look) / np.linalg.norm(r_T)) - look  # Earth central angle
    sin_g = -side * math.sin(gamma)  # right of the track = −ĥ side: ĥ·t̂ = −sin γ
    z = np.array([0.0, 0.0, 1.0])
    sc, ci = t_hat[2], math.cos(inc)
    beta = (sin_g - sc * ci) / (1 - sc * sc)
    alpha = ci - beta * sc
    e = np.cross(z, t_hat) / np.linalg.norm(np.cross(z, t_hat))
    for sense in (1.0, -1.0):
        kappa = sense * math.sqrt(1 - alpha**2 - beta**2 - 2 * alpha * beta * sc)
        h = alpha * z + beta * t_hat + kappa * e  # ĥ·ẑ = cos i, ĥ·t̂ = sin_g
        s = (t_hat - sin_g * h) / math.cos(gamma)
        if (np.cross(h, s)[2] > 0) == northbound:
            break
    node = np.cross(z, h) / np.linalg.norm(np.cross(z, h))
    return dict(
        semi_major_axis=A,
        inclination=inc,
        raan=math.atan2(node[1], node[0]),
        true_anomaly0=math.atan2(s @ np.cross(h, node), s @ node),
        target_lat=LAT,
        target_lon=LON,
        **extra,
    )


class Pass:
    """Orbit inputs as functions of time, and the model driven by them."""

    def __init__(self, **parameters):
        self.parameters = pass_parameters(**parameters)
        self.orbit = OrbitEnvironment(**self.parameters).start(0.0)

    def inputs(self, t):
        self.orbit.advance(0.0, t)  # a pure function of time
        return {name: self.orbit.get(name) for name in INPUTS + ("earth_angle", "w_OI_O")}

    def closest_approach(self):
        """Zero of ρ·ρ̇ by the secant method."""

        def f(t):
            x = self.inputs(t)
            return (x["r_T_I"] - x["r_I"]) @ (x["v_T_I"] - x["v_I"])

        t0, t1 = 0.0, 1.0
        for _ in range(30):
            f0, f1 = f(t0), f(t1)
            if f1 == f0:
                break
            t0, t1 = t1, t1 - f1 * (t1 - t0) / (f1 - f0)
        return t1

    def feed(self, model, t):
        x = self.inputs(t)
        for name in INPUTS:
            model.set(name, x[name])
        return x

    def start(self, t0, **guidance):
        model = StaringGuidance(**guidance)
        self.feed(model, t0)
        return model.start(t0)

    def at(self, state, t_from, t):
        """Outputs at t of the model in ``state`` (at t_from), reached in one step."""
        model = StaringGuidance()
        model.set_state(state)
        self.feed(model, t)
        model.advance(t_from, t - t_from)
        return {
            name: model.get(name)
            for name in ("q_ref", "w_ref", "dw_ref", "euler_ref_BO", "footprint_rotation")
        }

    def run(self, t0, t1, step, **guidance):
        """Sequential co-simulation from t0 to t1: list of (t, inputs, outputs)."""
        model = self.start(t0, **guidance)
        rows = []
        for k in range(int(round((t1 - t0) / step)) + 1):
            t = t0 + k * step
            if k:
                x = self.feed(model, t)
                model.advance(t - step, step)
            else:
                x = self.inputs(t)
            rows.append(
                (
                    t,
                    x,
                    {
                        name: model.get(name)
                        for name in (
                            "q_ref",
                            "w_ref",
                            "dw_ref",
                            "euler_ref_BO",
                            "look_angle",
                            "slant_range",
                            "footprint_rotation",
                        )
                    },
                )
            )
        return rows


def orbit_frame(r, v):
    """C_OI (rows: O axes in I), DESIGN.md §2."""
    z = -r / np.linalg.norm(r)
    y = -np.cross(r, v) / np.linalg.norm(np.cross(r, v))
    return np.array([np.cross(y, z), y, z])


def los(x):
    rho = x["r_T_I"] - x["r_I"]
    return rho / np.linalg.norm(rho)


def rot3(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def ground_azimuth(q_BI, x, boresight=(0.0, 0.0, 1.0)):
    """Azimuth (from north toward east) of the line in which the plane of the body
    boresight and the body axis "x made perpendicular to it" meets the target's tangent
    plane; geodetic east/north/up from LAT, LON in E, taken to I by the Earth angle."""
    b = np.asarray(boresight, float) / np.linalg.norm(boresight)
    axis = np.eye(3)[0] - b[0] * b
    axis = axis / np.linalg.norm(axis) if np.linalg.norm(axis) > 1e-6 else np.eye(3)[1] - b[1] * b
    C = dcm_from_quat(q_BI)
    beam, a = C.T @ b, C.T @ (axis / np.linalg.norm(axis))
    C_EI = rot3(x["earth_angle"])
    up = C_EI.T @ np.array(
        [math.cos(LAT) * math.cos(LON), math.cos(LAT) * math.sin(LON), math.sin(LAT)]
    )
    east = C_EI.T @ np.array([-math.sin(LON), math.cos(LON), 0.0])
    north = np.cross(up, east)
    d = beam * (a @ up) - a * (beam @ up)
    return math.atan2(d @ east, d @ north)


def vee(M):
    return np.array([M[2, 1], M[0, 2], M[1, 0]])


def wrap(angle):
    return (angle + math.pi) % (2 * math.pi) - math.pi


@pytest.fixture(scope="module")
def video_sar():
    """The 200-s stare centred on closest approach, reference at its start."""
    p = Pass()
    t_ca = p.closest_approach()
    return p, t_ca


def stare(video_sar, step=2.0, **guidance):
    p, t_ca = video_sar
    guidance.setdefault("reference_time", t_ca - STARE)
    return p.run(t_ca - STARE, t_ca + STARE, step, **guidance)


# -- geometry of the pass -------------------------------------------------------------------
def test_pass_geometry_is_the_video_sar_one(video_sar):
    p, t_ca = video_sar
    x = p.inputs(0.0)
    r, rho = x["r_I"], x["r_T_I"] - x["r_I"]
    look = math.acos(-rho @ r / np.linalg.norm(rho) / np.linalg.norm(r))
    assert look == pytest.approx(LOOK, abs=1e-12)
    assert abs(t_ca) < 5.0  # the Earth's rotation moves zero Doppler by seconds
    assert np.linalg.norm(r) - WGS84_A == pytest.approx(567e3, rel=1e-9)


@pytest.mark.parametrize("compensation", [True, False])
def test_look_angle_and_slant_range(video_sar, compensation):
    for t, x, y in stare(video_sar, step=20.0, yaw_compensation=compensation):
        rho = x["r_T_I"] - x["r_I"]
        nadir = -x["r_I"] / np.linalg.norm(x["r_I"])
        assert y["slant_range"] == pytest.approx(np.linalg.norm(rho), rel=1e-15)
        assert y["look_angle"] == pytest.approx(
            math.acos(rho @ nadir / np.linalg.norm(rho)), abs=1e-12
        )


# -- pointing and Euler angles ---------------------------------------------------------------
@pytest.mark.parametrize("boresight", [(0.0, 0.0, 1.0), TILTED, (0.0, 0.0, 2.0), (1.0, 0.0, 0.0)])
@pytest.mark.parametrize("compensation", [True, False])
def test_boresight_is_on_the_line_of_sight(video_sar, boresight, compensation):
    b = np.array(boresight) / np.linalg.norm(boresight)
    for t, x, y in stare(
        video_sar, step=10.0, yaw_compensation=compensation, boresight_B=boresight
    ):
        q = y["q_ref"]
        assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-15)
        assert np.allclose(dcm_from_quat(q).T @ b, los(x), rtol=0, atol=1e-13)


@pytest.mark.parametrize("compensation", [True, False])
def test_euler_angles_are_eq_11_and_describe_q_ref(video_sar, compensation):
    previous = None
    for t, x, y in stare(video_sar, step=5.0, yaw_compensation=compensation):
        C_OI = orbit_frame(x["r_I"], x["v_I"])
        ux, uy, uz = C_OI @ los(x)
        phi, theta, psi = y["euler_ref_BO"]
        assert phi == pytest.approx(-math.atan(uy / uz), abs=1e-12)  # eq 11
        assert theta == pytest.approx(math.asin(ux), abs=1e-12)
        if not compensation:
            assert psi == 0.0
        C_RO = dcm_from_quat(y["q_ref"]) @ C_OI.T
        assert np.allclose(dcm_from_euler123(y["euler_ref_BO"]), C_RO, rtol=0, atol=1e-12)
        if previous is not None:
            assert np.all(np.abs(y["euler_ref_BO"] - previous) < 3 * DEG)  # one branch
        previous = y["euler_ref_BO"]


def test_q_ref_keeps_its_sign_between_communication_points():
    """Over ±300 s the principal quaternion (q0 ≥ 0) of this pass flips; q_ref does not."""
    p = Pass()
    t_ca = p.closest_approach()
    q = np.array([y["q_ref"] for *_, y in p.run(t_ca - 300, t_ca + 300, 5.0)])
    assert np.all(np.sum(q[1:] * q[:-1], axis=1) > 0.99)
    assert q[:, 0].min() < 0 < q[:, 0].max()


def test_tilted_boresight_euler_angles_describe_q_ref(video_sar):
    previous = None
    for t, x, y in stare(video_sar, step=5.0, boresight_B=TILTED):
        C_RO = dcm_from_quat(y["q_ref"]) @ orbit_frame(x["r_I"], x["v_I"]).T
        assert np.allclose(dcm_from_euler123(y["euler_ref_BO"]), C_RO, rtol=0, atol=1e-12)
        if previous is not None:
            assert np.all(np.abs(y["euler_ref_BO"] - previous) < 3 * DEG)
        previous = y["euler_ref_BO"]


# -- rates against finite differences --------------------------------------------------------
def richardson(f, t, h):
    """Central difference with one Richardson step: error O(h⁴)."""
    d1 = (f(t + h) - f(t - h)) / (2 * h)
    d2 = (f(t + h / 2) - f(t - h / 2)) / h
    return (4 * d2 - d1) / 3


def captured(video_sar, orbit=None, **guidance):
    p, t_ca = video_sar
    if orbit:
        p = Pass(**orbit)
    t_ref = t_ca - STARE
    model = p.start(t_ref, reference_time=t_ref, **guidance)
    return p, t_ref, model.get_state()


ECCENTRIC = dict(eccentricity=0.02, arg_perigee=1.0)  # ṙ ≠ 0: all terms of ẍ_O
RATE_CASES = [
    dict(yaw_compensation=True),
    dict(yaw_compensation=False),
    dict(yaw_compensation=True, boresight_B=TILTED),
    dict(yaw_compensation=True, orbit=ECCENTRIC),
    dict(yaw_compensation=False, orbit=ECCENTRIC),
]


@pytest.mark.parametrize("guidance", RATE_CASES)
def test_w_ref_is_the_derivative_of_q_ref(video_sar, guidance):
    p, t_ref, state = captured(video_sar, **guidance)
    C = lambda t: dcm_from_quat(p.at(state, t_ref, t)["q_ref"])
    for t in t_ref + np.array([0.5, 40.0, 100.0, 160.0, 199.5]):
        W = -richardson(C, t, 0.4) @ C(t).T  # Ċ_RI = −[w×] C_RI
        w_fd = vee((W - W.T) / 2)
        w = p.at(state, t_ref, t)["w_ref"]
        assert np.linalg.norm(w_fd - w) < 1e-11, (t, w_fd - w)


@pytest.mark.parametrize("guidance", RATE_CASES)
def test_dw_ref_is_the_derivative_of_w_ref(video_sar, guidance):
    p, t_ref, state = captured(video_sar, **guidance)
    w = lambda t: p.at(state, t_ref, t)["w_ref"]
    for t in t_ref + np.array([0.5, 40.0, 100.0, 160.0, 199.5]):
        dw_fd = richardson(w, t, 0.4)
        assert np.linalg.norm(dw_fd - p.at(state, t_ref, t)["dw_ref"]) < 1e-12, t


@pytest.mark.parametrize(
    "compensation, w_bound, dw_bound", [(True, 1e-11, 5e-8), (False, 1e-6, 5e-8)]
)
def test_rates_with_j2_err_only_by_the_neglected_terms(video_sar, compensation, w_bound, dw_bound):
    """With J2 the satellite's acceleration is not −μr/r³ (≈ 1e-2 m/s² more) and the
    orbit normal precesses (w_OI gains r a_h/|h| r̂): w_ref stays exact with compensation,
    the yaw-0 frame's w_ref errs by ~1e-6 rad/s, dw_ref by ~1e-8 rad/s²."""
    p, t_ref, state = captured(video_sar, orbit=dict(j2=True), yaw_compensation=compensation)
    C = lambda t: dcm_from_quat(p.at(state, t_ref, t)["q_ref"])
    w = lambda t: p.at(state, t_ref, t)["w_ref"]
    for t in t_ref + np.array([0.5, 100.0, 199.5]):
        W = -richardson(C, t, 0.4) @ C(t).T
        assert np.linalg.norm(vee((W - W.T) / 2) - w(t)) < w_bound
        assert np.linalg.norm(richardson(w, t, 0.4) - p.at(state, t_ref, t)["dw_ref"]) < dw_bound


@pytest.mark.parametrize("compensation", [True, False])
def test_w_ref_is_eq_13_of_the_euler_rates_plus_the_orbit_rate(video_sar, compensation):
    """w_ref = w_RO + C_RO w_OI_O, w_RO from eq (13) with finite-differenced Euler rates."""
    p, t_ref, state = captured(video_sar, yaw_compensation=compensation)
    euler = lambda t: p.at(state, t_ref, t)["euler_ref_BO"]
    for t in t_ref + np.array([0.5, 60.0, 140.0, 199.5]):
        (_, theta, psi), (dphi, dtheta, dpsi) = euler(t), richardson(euler, t, 0.4)
        w_RO = np.array(
            [
                dphi * math.cos(psi) * math.cos(theta) + dtheta * math.sin(psi),
                -dphi * math.sin(psi) * math.cos(theta) + dtheta * math.cos(psi),
                dpsi + dphi * math.sin(theta),
            ]
        )
        x = p.inputs(t)
        C_RO = dcm_from_quat(p.at(state, t_ref, t)["q_ref"]) @ orbit_frame(x["r_I"], x["v_I"]).T
        w = p.at(state, t_ref, t)["w_ref"]
        assert np.linalg.norm(w_RO + C_RO @ x["w_OI_O"] - w) < 1e-11


# -- footprint ------------------------------------------------------------------------------
@pytest.mark.parametrize("boresight", [(0.0, 0.0, 1.0), TILTED, (1.0, 0.0, 0.0)])
def test_compensated_footprint_does_not_rotate_on_the_ground(video_sar, boresight):
    rows = stare(video_sar, yaw_compensation=True, boresight_B=boresight)
    azimuths = np.array([ground_azimuth(y["q_ref"], x, boresight) for _, x, y in rows])
    assert np.max(np.abs(azimuths - azimuths[0])) < 1e-12
    assert max(abs(y["footprint_rotation"]) for *_, y in rows) < 1e-12
    for _, x, y in rows[::10]:
        assert footprint_azimuth(y["q_ref"], x["r_T_I"], boresight) == pytest.approx(
            ground_azimuth(y["q_ref"], x, boresight), abs=1e-12
        )


def test_compensated_footprint_of_a_raised_target():
    """target_alt = 3 km: the tangent plane is the geodetic one of the foot point."""
    p = Pass(target_alt=3000.0)
    t_ca = p.closest_approach()
    rows = p.run(t_ca - STARE, t_ca + STARE, 5.0, reference_time=t_ca - STARE)
    azimuths = np.array([ground_azimuth(y["q_ref"], x) for _, x, y in rows])
    assert np.max(np.abs(azimuths - azimuths[0])) < 1e-12


@pytest.mark.parametrize("side, northbound", [(1.0, False), (-1.0, False), (1.0, True)])
def test_uncompensated_footprint_drifts(side, northbound):
    p = Pass(side=side, northbound=northbound)
    t_ca = p.closest_approach()
    rows = p.run(
        t_ca - STARE, t_ca + STARE, 2.0, yaw_compensation=False, reference_time=t_ca - STARE
    )
    azimuth0 = ground_azimuth(rows[0][2]["q_ref"], rows[0][1])
    drift = np.array([wrap(ground_azimuth(y["q_ref"], x) - azimuth0) for _, x, y in rows])
    rotation = np.array([y["footprint_rotation"] for *_, y in rows])
    assert np.allclose(rotation, drift, rtol=0, atol=1e-12)
    assert np.max(np.abs(drift)) > 5 * DEG  # 6.5° on the descending pass
    assert np.all(np.diff(np.abs(drift)) > 0)  # monotonic over the stare


def test_footprint_azimuth_of_a_perturbed_attitude(video_sar):
    """The public function measures any attitude, e.g. one off the reference."""
    rng = np.random.default_rng(2)
    for _, x, y in stare(video_sar, step=50.0):
        for _ in range(5):
            angle = rng.normal(size=3) * 1e-2
            half = np.linalg.norm(angle) / 2
            dq = np.concatenate(([math.cos(half)], math.sin(half) * angle / (2 * half)))
            q0, q = dq[0], y["q_ref"]  # q_BI = q_RI ⊗ dq
            qb = np.array(
                [
                    q[0] * q0 - q[1:] @ dq[1:],
                    *(q[0] * dq[1:] + q0 * q[1:] + np.cross(q[1:], dq[1:])),
                ]
            )
            assert footprint_azimuth(qb, x["r_T_I"]) == pytest.approx(
                ground_azimuth(qb, x), abs=1e-12
            )


# -- yaw and capture over time --------------------------------------------------------------
def test_yaw_is_zero_before_the_reference_time_and_continuous_across_it(video_sar):
    p, t_ca = video_sar
    t_ref = t_ca - 50.0
    rows = p.run(t_ca - 100.0, t_ca + 100.0, 1.0, reference_time=t_ref)
    yaw = np.array([y["euler_ref_BO"][2] for *_, y in rows])
    times = np.array([t for t, *_ in rows])
    before = times < t_ref - 1e-6
    assert np.all(yaw[before] == 0.0)
    assert np.all(np.array([y["footprint_rotation"] for *_, y in rows])[before] == 0.0)
    assert abs(yaw[np.argmin(np.abs(times - t_ref))]) < 1e-12
    assert np.max(np.abs(np.diff(yaw))) < 0.2 * DEG  # ≤ 1 s × peak yaw rate
    assert np.max(np.abs(yaw)) > 1 * DEG  # and it does compensate


def test_capture_at_the_start_when_it_is_after_reference_time(video_sar):
    p, t_ca = video_sar
    rows = p.run(t_ca, t_ca + 20.0, 10.0, reference_time=t_ca - 1000.0)
    assert abs(rows[0][2]["euler_ref_BO"][2]) < 1e-12
    assert rows[0][2]["footprint_rotation"] == 0.0
    assert abs(rows[-1][2]["euler_ref_BO"][2]) > 0.1 * DEG  # compensating from t_ca
    assert abs(rows[-1][2]["footprint_rotation"]) < 1e-12


def test_state_restores_the_captured_footprint(video_sar):
    p, t_ca = video_sar
    t_ref = t_ca - STARE
    model = p.start(t_ref, reference_time=t_ref)
    state = model.get_state()
    expected = p.at(state, t_ref, t_ca)
    other = p.start(t_ref - 30.0, reference_time=t_ref)  # not captured yet
    other.set_state(state)
    p.feed(other, t_ca)
    other.advance(t_ref, t_ca - t_ref)
    for name, value in expected.items():
        assert np.array_equal(other.get(name), value), name
    # the snapshot is a copy: later captures do not leak into it
    fresh = p.start(t_ca, reference_time=t_ca)
    fresh.set_state(state)
    p.feed(fresh, t_ca)
    fresh.advance(t_ref, t_ca - t_ref)
    assert np.array_equal(fresh.get("q_ref"), expected["q_ref"])


def test_reevaluating_at_the_capture_time_is_idempotent(video_sar):
    p, t_ca = video_sar
    model = p.start(t_ca, reference_time=t_ca)
    first = {n: model.get(n) for n in ("q_ref", "w_ref", "euler_ref_BO")}
    model.output()
    for name, value in first.items():
        assert np.array_equal(model.get(name), value)


def test_yaw_rate_and_peaks_of_the_video_sar_stare(video_sar):
    """Headline numbers (printed with pytest -rP): the stare of DESIGN.md §4.3."""
    p, t_ca = video_sar
    on = stare(video_sar, step=1.0, yaw_compensation=True)
    off = stare(video_sar, step=1.0, yaw_compensation=False)
    w_peak = max(np.linalg.norm(y["w_ref"]) for *_, y in on)
    yaw = np.array([y["euler_ref_BO"][2] for *_, y in on])
    yaw_rate = []  # eq (13) inverted, w_RO = w_ref − C_RO w_OI_O
    for _, x, y in on:
        C_RO = dcm_from_quat(y["q_ref"]) @ orbit_frame(x["r_I"], x["v_I"]).T
        yaw_rate.append(euler123_rates(y["euler_ref_BO"], y["w_ref"] - C_RO @ x["w_OI_O"])[2])
    yaw_rate = np.array(yaw_rate)
    assert np.allclose(yaw_rate[1:-1], np.gradient(yaw, 1.0)[1:-1], rtol=0, atol=1e-6)
    dw_peak = max(np.linalg.norm(y["dw_ref"]) for *_, y in on)
    drift = max(abs(y["footprint_rotation"]) for *_, y in off)
    look = [y["look_angle"] for *_, y in on]
    print(
        f"\nclosest approach t = {t_ca:.3f} s, look {min(look) / DEG:.3f}..{max(look) / DEG:.3f}"
        f" deg, slant range {min(y['slant_range'] for *_, y in on) / 1e3:.1f}.."
        f"{max(y['slant_range'] for *_, y in on) / 1e3:.1f} km"
        f"\npeak |w_ref| {w_peak / DEG:.4f} deg/s (yaw 0: "
        f"{max(np.linalg.norm(y['w_ref']) for *_, y in off) / DEG:.4f}), peak |dw_ref| "
        f"{dw_peak / DEG:.5f} deg/s2"
        f"\nwith compensation: peak |yaw| {np.max(np.abs(yaw)) / DEG:.3f} deg, peak |yaw rate| "
        f"{np.max(np.abs(yaw_rate)) / DEG:.4f} deg/s, yaw rate at capture "
        f"{yaw_rate[0] / DEG:.4f} deg/s, max |footprint_rotation| "
        f"{max(abs(y['footprint_rotation']) for *_, y in on):.2g} rad"
        f"\nwithout: footprint drift over the stare {drift / DEG:.3f} deg"
    )
    assert 0.5 * DEG < w_peak < 1.0 * DEG
    assert 5 * DEG < np.max(np.abs(yaw)) < 15 * DEG
    assert 5 * DEG < drift < 10 * DEG


# -- interface and errors -------------------------------------------------------------------
def test_variable_table():
    names = {v.name: v for v in StaringGuidance.VARIABLES}
    for name in (
        "yaw_compensation",
        "boresight_B",
        "reference_time",
        *INPUTS,
        "q_ref",
        "w_ref",
        "euler_ref_BO",
        "look_angle",
        "slant_range",
        "footprint_rotation",
        "dw_ref",
    ):
        assert name in names
        assert names[name].unit in UNITS
    assert names["yaw_compensation"].type == "Boolean"
    assert np.array_equal(StaringGuidance().get("boresight_B"), [0.0, 0.0, 1.0])
    assert StaringGuidance().get("yaw_compensation") == 1.0


def consistent_inputs(r, v, r_T):
    """Inputs with q_OI matching r, v (built here) and an Earth-fixed target velocity."""
    r, v, r_T = (np.asarray(a, float) for a in (r, v, r_T))
    return dict(
        r_I=r,
        v_I=v,
        r_T_I=r_T,
        v_T_I=7.292115e-5 * np.cross([0, 0, 1.0], r_T),
        q_OI=quat_from_dcm(orbit_frame(r, v)),
    )


def started(inputs, **parameters):
    model = StaringGuidance(**parameters)
    for name, value in inputs.items():
        model.set(name, value)
    return model.start(0.0)


R0, V0, T0 = (A, 0.0, 0.0), (0.0, 7.6e3, 0.0), (WGS84_A, -3.0e5, 0.0)


@pytest.mark.parametrize(
    "change, match",
    [
        (dict(r_T_I=R0), "zero-length line of sight"),
        (dict(v_I=(2.0, 0.0, 0.0)), "r_I and v_I are parallel"),
        (dict(q_OI=(1.0, 0.0, 0.0, 0.0)), "q_OI does not match"),
        (dict(v_T_I=(math.nan, 0.0, 0.0)), r"inputs \['v_T_I'\] are not finite"),
    ],
)
def test_bad_inputs_are_named(change, match):
    inputs = consistent_inputs(R0, V0, T0)
    inputs.update(change)
    with pytest.raises(ModelError, match=match):
        started(inputs)


def test_line_of_sight_along_the_orbit_x_axis():
    inputs = consistent_inputs(R0, V0, (A, 5e5, 0.0))  # straight ahead
    with pytest.raises(ModelError, match="orbit frame's x axis"):
        started(inputs)


def test_line_of_sight_along_the_captured_footprint_direction():
    model = started(consistent_inputs(R0, V0, T0))  # captured at t = 0, yaw 0
    r_T = np.array(T0)
    u = (r_T - np.array(R0)) / np.linalg.norm(r_T - np.array(R0))
    x = dcm_from_quat(model.get("q_ref"))[0]  # body x in I
    up = r_T / np.linalg.norm(r_T)  # on the equator: geodetic = radial
    g = u * (x @ up) - x * (u @ up)  # the frozen footprint direction
    g /= np.linalg.norm(g)
    for name, value in consistent_inputs(r_T - 7e5 * g, (0.0, 7.6e3, 0.0), r_T).items():
        model.set(name, value)
    with pytest.raises(ModelError, match="captured footprint direction"):
        model.advance(0.0, 1e-9)  # g turns by 7e-14 rad: still parallel


@pytest.mark.parametrize(
    "parameters, match",
    [
        (dict(boresight_B=(0.0, 0.0, 0.0)), "boresight_B"),
        (dict(boresight_B=(0.0, math.inf, 1.0)), "boresight_B"),
        (dict(reference_time=math.nan), "reference_time"),
    ],
)
def test_bad_parameters_are_named(parameters, match):
    with pytest.raises(ModelError, match=match):
        started(consistent_inputs(R0, V0, T0), **parameters)


def test_a_history_is_measured_row_by_row_bit_for_bit():
    """footprint_azimuths normalises each row of a history at once, as
    footprint_azimuth normalises one quaternion (q / √(q·q), the dot product as NumPy
    takes it): the same azimuths, bit for bit, for any scale of the rows."""
    rng = np.random.default_rng(8)
    q = rng.normal(size=(500, 4)) * rng.uniform(0.5, 2.0, size=(500, 1))
    r_T = np.array(geodetic_to_ecef(math.radians(48.0), math.radians(11.0), 500.0))
    r_T = r_T + rng.normal(size=(500, 3)) * 1e3
    beam, axis = (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)
    one = staring_guidance._footprint_azimuths.py_func
    expected = np.empty(1)
    for k, azimuth in enumerate(staring_guidance.footprint_azimuths(q, r_T)):
        unit = q[k : k + 1] / math.sqrt(float(q[k] @ q[k]))
        assert one(unit, r_T[k : k + 1], beam, axis, expected) == -1
        assert azimuth == expected[0], k


def test_footprint_azimuth_is_undefined_at_a_pole():
    with pytest.raises(ModelError, match="pole"):
        footprint_azimuth((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 6356752.3))


def test_the_start_values_are_a_consistent_geometry():
    """FMI 2.0: outputs can be asked for in Initialization Mode before any input is set;
    the start values (a nadir view from 567 km) must be a valid geometry."""
    model = StaringGuidance().start(0.0)
    assert model.get("look_angle") == 0.0
    assert np.allclose(model.get("euler_ref_BO"), 0.0, atol=1e-15)
    assert model.get("slant_range") == pytest.approx(567e3)
