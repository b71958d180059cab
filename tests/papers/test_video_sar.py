"""video_sar end to end through the CLI ([Liang 2019]): the pass, the pointing, the footprint.

Truth here is computed in the test from the recorded positions and attitude with plain
NumPy (the DESIGN.md §2 conventions written out again), not with the toolkit's functions.
"""

import datetime
import json
import math
import re

import numpy as np
import pytest

from agilesat.orchestration.output.results import Results
from helpers import ISS_TLE as ISS
from helpers import agilesat

pytestmark = [pytest.mark.slow, pytest.mark.integration]

DEG = math.pi / 180
LAT, LON = 33.16 * DEG, 129.72 * DEG
WGS84_E2 = 6.69437999014e-3


def run(out, *args):
    result = agilesat(*args, "--out", out)
    assert result.returncode == 0, result.stdout + result.stderr
    summary = json.loads((out / "summary.json").read_text())
    return summary, Results.from_csv(out / "results.csv")


@pytest.fixture(scope="module")
def default(fmus, tmp_path_factory):
    return run(
        tmp_path_factory.mktemp("video_sar"), "run", "video_sar", "--no-figures", "--no-report"
    )


@pytest.fixture(scope="module")
def uncompensated(fmus, tmp_path_factory):
    return run(
        tmp_path_factory.mktemp("no_yaw"),
        "run",
        "video_sar:no_yaw_compensation",
        "--no-figures",
        "--no-report",
    )


def value(summary, name):
    return summary["metrics"][name]["value"]


def dcm(q):
    """C(q) of DESIGN.md §2 for each row of q (N, 4): v_B = C v_I."""
    q0, v = q[:, 0], q[:, 1:]
    C = (q0**2 - np.einsum("ij,ij->i", v, v))[:, None, None] * np.eye(3)
    C = C + 2 * v[:, :, None] * v[:, None, :]
    skew = np.zeros_like(C)
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    skew = skew - skew.transpose(0, 2, 1)
    return C - 2 * q0[:, None, None] * skew


def geometry(results):
    r = results.vector("OrbitEnvironment.r_I")
    los = results.vector("OrbitEnvironment.r_T_I") - r
    rel_v = results.vector("OrbitEnvironment.v_T_I") - results.vector("OrbitEnvironment.v_I")
    return r, los, rel_v


def boresight_error(results):
    _, los, _ = geometry(results)
    z = dcm(results.vector("SatelliteDynamics.q_BI"))[:, 2, :]  # body z in I
    return np.arctan2(np.linalg.norm(np.cross(z, los), axis=1), np.einsum("ij,ij->i", z, los))


def footprint_azimuth(results):
    """Azimuth from north of the ground line of the body's x-z plane (the beam plane),
    in the target's tangent plane: normal from the geodetic latitude, turned with the
    Earth like r_T_I."""
    r_T = results.vector("OrbitEnvironment.r_T_I")
    lon = np.arctan2(r_T[:, 1], r_T[:, 0])  # inertial longitude
    up = np.stack(
        [np.cos(LAT) * np.cos(lon), np.cos(LAT) * np.sin(lon), np.full_like(lon, np.sin(LAT))],
        axis=1,
    )
    east = np.stack([-np.sin(lon), np.cos(lon), np.zeros_like(lon)], axis=1)
    north = np.cross(up, east)
    C = dcm(results.vector("SatelliteDynamics.q_BI"))
    x, z = C[:, 0, :], C[:, 2, :]
    d = z * np.einsum("ij,ij->i", x, up)[:, None] - x * np.einsum("ij,ij->i", z, up)[:, None]
    return np.unwrap(np.arctan2(np.einsum("ij,ij->i", d, east), np.einsum("ij,ij->i", d, north)))


def test_the_pass_is_the_papers_zero_doppler_at_30_degrees(default):
    summary, results = default
    t = results.time
    r, los, rel_v = geometry(results)
    doppler = np.einsum("ij,ij->i", los, rel_v)  # ∝ range rate
    k = np.flatnonzero(np.diff(np.sign(doppler)))[0]
    t_zero = t[k] - doppler[k] * (t[k + 1] - t[k]) / (doppler[k + 1] - doppler[k])
    assert t_zero == pytest.approx(100.0, abs=1e-3)  # 08:09:43 UTC
    look = np.arccos(
        -np.einsum("ij,ij->i", r, los) / np.linalg.norm(r, axis=1) / np.linalg.norm(los, axis=1)
    )
    assert np.interp(t_zero, t, look) == pytest.approx(30 * DEG, abs=1e-6)
    assert np.linalg.norm(r, axis=1) == pytest.approx(6378137.0 + 567e3, rel=1e-9)
    # right-looking: the line of sight on the −ĥ side (y_O), as designed
    h = np.cross(r, results.vector("OrbitEnvironment.v_I"))
    assert np.all(np.einsum("ij,ij->i", los, -h) > 0)
    assert value(summary, "zero_doppler_time") == pytest.approx(100.0, abs=0.05)


def test_the_boresight_stays_on_the_target(default):
    summary, results = default
    error = boresight_error(results)
    assert value(summary, "pointing_error_max") == pytest.approx(error.max(), rel=1e-6)
    assert error.max() < 0.005 * DEG  # 0.000015° measured (Jacobi; 0.0006° Gauss-Seidel)
    assert value(summary, "pointing_error_rms") == pytest.approx(
        math.sqrt(np.mean(error**2)), rel=1e-6
    )


def test_with_yaw_compensation_the_footprint_does_not_turn(default):
    summary, results = default
    azimuth = footprint_azimuth(results)
    assert np.abs(azimuth - azimuth[0]).max() < 0.005 * DEG  # 9e-7° measured (Jacobi)
    assert value(summary, "footprint_rotation_max") == pytest.approx(
        np.abs(azimuth - azimuth[0]).max(), abs=1e-7
    )
    assert np.ptp(results["SatelliteDynamics.euler_BO[3]"]) > 5 * DEG  # by turning in yaw


def test_without_yaw_compensation_the_footprint_drifts(uncompensated):
    summary, results = uncompensated
    azimuth = footprint_azimuth(results)
    drift = azimuth - azimuth[0]
    assert 5 * DEG < np.abs(drift).max() < 10 * DEG  # 6.5° measured
    assert np.all(np.diff(drift) < 0) or np.all(np.diff(drift) > 0)  # steadily
    assert np.abs(results["SatelliteDynamics.euler_BO[3]"]).max() < 0.001 * DEG  # starts on it
    assert boresight_error(results).max() < 0.005 * DEG  # still on the target


def test_roll_and_pitch_are_eq11_of_the_line_of_sight(default):
    """φ = −atan(y/z), θ = asin(x) of the unit line of sight in O (eq 11)."""
    _, results = default
    r, los, rel_v = geometry(results)
    v = results.vector("OrbitEnvironment.v_I")
    z_O = -r / np.linalg.norm(r, axis=1)[:, None]
    h = np.cross(r, v)
    y_O = -h / np.linalg.norm(h, axis=1)[:, None]
    x_O = np.cross(y_O, z_O)
    u = los / np.linalg.norm(los, axis=1)[:, None]
    x, y, z = (np.einsum("ij,ij->i", u, axis) for axis in (x_O, y_O, z_O))
    euler = results.vector("SatelliteDynamics.euler_BO")
    assert np.abs(euler[:, 0] + np.arctan(y / z)).max() < 0.01 * DEG
    assert np.abs(euler[:, 1] - np.arcsin(x)).max() < 0.01 * DEG
    assert euler[0, 1] > 40 * DEG and euler[-1, 1] < -40 * DEG  # pitch carries the stare


def test_total_angular_momentum_is_conserved(default):
    H = default[1].vector("SatelliteDynamics.H_I")
    assert np.abs(H - H[0]).max() <= 1e-9 * np.linalg.norm(H[0])


def test_the_acceleration_feedforward_matters(default, fmus, tmp_path):
    summary, _ = run(tmp_path, "run", "video_sar:no_feedforward", "--no-figures", "--no-report")
    assert value(summary, "pointing_error_max") > 10 * value(default[0], "pointing_error_max")


def iss_passes():
    """Zero-Doppler passes of the ISS over the target in the day after its TLE epoch,
    computed here with sgp4 and its own GMST (gstime), target visible: (UTC, look angle)."""
    from sgp4.api import WGS72, Satrec
    from sgp4.propagation import gstime

    sat = Satrec.twoline2rv(*ISS, WGS72)
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    N = a / math.sqrt(1 - e2 * math.sin(LAT) ** 2)
    r_E = N * np.array(
        [math.cos(LAT) * math.cos(LON), math.cos(LAT) * math.sin(LON), (1 - e2) * math.sin(LAT)]
    )

    def state(t):
        fr = sat.jdsatepochF + t / 86400
        _, r, v = sat.sgp4(sat.jdsatepoch, fr)
        theta = gstime(sat.jdsatepoch + fr)
        c, s = math.cos(theta), math.sin(theta)
        r_T = np.array([c * r_E[0] - s * r_E[1], s * r_E[0] + c * r_E[1], r_E[2]])
        return (
            np.array(r) * 1e3,
            np.array(v) * 1e3,
            r_T,
            7.292115e-5 * np.array([-r_T[1], r_T[0], 0]),
        )

    def doppler(t):
        r, v, r_T, v_T = state(t)
        return (r - r_T) @ (v - v_T)

    epoch = datetime.datetime(2000, 1, 1, 12) + datetime.timedelta(
        days=sat.jdsatepoch + sat.jdsatepochF - 2451545.0
    )
    grid = np.arange(0.0, 86400.0, 20.0)
    values = [doppler(t) for t in grid]
    found = []
    for k in np.flatnonzero((np.array(values[:-1]) < 0) & (np.array(values[1:]) >= 0)):
        lo, hi = grid[k], grid[k + 1]
        for _ in range(50):
            lo, hi = ((lo + hi) / 2, hi) if doppler((lo + hi) / 2) < 0 else (lo, (lo + hi) / 2)
        r, _, r_T, _ = state(lo)
        rho = r_T - r
        if rho @ r_T < 0:  # above the target's horizon
            look = math.acos(-r @ rho / np.linalg.norm(r) / np.linalg.norm(rho))
            found.append((epoch + datetime.timedelta(seconds=lo), look))
    return found


def test_stare_from_a_real_satellites_tle(fmus, tmp_path):
    """The ISS over Sasebo: passes found by SGP4 inside OrbitEnvironment, the one nearest a
    30° look chosen, the stare centred on its zero Doppler."""
    passes = [p for p in iss_passes() if p[1] <= 60 * DEG]
    when, look = min(passes, key=lambda p: abs(p[1] - 30 * DEG))
    (tmp_path / "iss.tle").write_text("ISS (ZARYA)\n" + "\n".join(ISS) + "\n")
    result = agilesat(
        "stare", "--tle", tmp_path / "iss.tle", "--look", "30", "--out", tmp_path / "stare"
    )
    assert result.returncode == 0, result.stdout + result.stderr
    start = re.search(r"stare: (\S+) UTC", result.stdout).group(1)
    assert (
        abs(
            (
                datetime.datetime.fromisoformat(start) + datetime.timedelta(seconds=100) - when
            ).total_seconds()
        )
        < 0.01
    )
    listed = re.findall(r"(\d{4}-\d\d-\d\d \d\d:\d\d:\d\d) UTC  look", result.stdout)
    assert len(listed) == len(passes)
    for text, (time, _) in zip(listed, passes):  # each pass's zero Doppler in UTC
        assert abs((datetime.datetime.fromisoformat(text) - time).total_seconds()) <= 1
    summary = json.loads((tmp_path / "stare" / "summary.json").read_text())
    assert value(summary, "zero_doppler_time") == pytest.approx(100.0, abs=0.05)
    assert value(summary, "look_angle_zero_doppler") == pytest.approx(look, abs=0.01 * DEG)
    assert value(summary, "pointing_error_max") < 0.005 * DEG


def test_stare_reports_a_bad_tle(tmp_path):
    (tmp_path / "bad.tle").write_text(ISS[0] + "\n" + ISS[1][:-1] + "0\n")
    result = agilesat("stare", "--tle", tmp_path / "bad.tle", "--out", tmp_path / "x")
    assert result.returncode == 1
    assert "tle_line2 checksum" in result.stderr


def test_mission_analysis_commands_print_the_functions_results(tmp_path):
    from agilesat.orchestration.scenarios import constants as c
    from agilesat.orchestration.studies.mission_analysis import overlap_ratio, walker_sizing

    result = agilesat("mission", "overlap", "--frame-rates", "5", "25", "--out", tmp_path)
    assert result.returncode == 0, result.stderr
    for rate, overlap in zip((5, 25), overlap_ratio([5.0, 25.0], **c.VIDEO_SAR_OVERLAP).overlap):
        assert f"{rate:.2f} Hz   overlap {100 * overlap:6.2f} %" in result.stdout
    assert (tmp_path / "overlap_vs_frame_rate_h567km_look30deg.png").stat().st_size > 0
    result = agilesat("mission", "walker", "--out", tmp_path)
    assert result.returncode == 0, result.stderr
    for kind in ("incidence", "look"):
        w = walker_sizing(c.VIDEO_SAR_ALTITUDE, c.VIDEO_SAR_MAX_INCIDENCE, beta_kind=kind)
        assert f"S = {w.satellites_per_plane}, P = {w.planes}, N = {w.satellites}" in result.stdout
