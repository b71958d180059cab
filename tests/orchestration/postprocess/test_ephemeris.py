"""``agilesat export-ephemeris``: a run's AEM and OEM read back by readers other than the
writer (ccsds-ndm-py): our AEM reader written from CCSDS 504.0-B-2's text
(tests/tools/ccsds_text.py) and the ``oem`` package for the OEM.  The attitude comes back
within 1e-9 rad of the run's q_BI, and the quaternion means what the standard says (the
transformation from REF_FRAME_A to REF_FRAME_B): the video_sar boresight, turned into TEME
by the standard's definition, points at the target the OEM's positions see."""

import datetime
import json
import math

import ccsds_text
import numpy as np
import pytest

from agilesat.components.ephemeris import gmst
from agilesat.orchestration.output.results import Results
from helpers import agilesat

pytestmark = [pytest.mark.slow, pytest.mark.integration]

EPOCH = datetime.datetime(2016, 11, 25, 8, 8, 3)  # video_sar's t = 0 (scenarios/video_sar.py)


def angle_between(q, p) -> np.ndarray:
    """Rotation angle [rad] between unit quaternions q and p (N, 4, scalar first), either
    sign: 2 atan2(|d_v|, |d_0|) of d = q* ⊗ p (no arccos: exact near zero)."""
    d0 = (q * p).sum(1)
    dv = q[:, :1] * p[:, 1:] - p[:, :1] * q[:, 1:] - np.cross(q[:, 1:], p[:, 1:])
    return 2 * np.arctan2(np.linalg.norm(dv, axis=1), np.abs(d0))


@pytest.fixture(scope="module")
def video_sar(tmp_path_factory):
    out = tmp_path_factory.mktemp("video_sar")
    run = agilesat("run", "video_sar", "--stop", "20", "--no-figures", "--no-report", "--out", out)
    assert run.returncode == 0, run.stderr
    written = agilesat("export-ephemeris", out)
    assert written.returncode == 0, written.stderr
    return out, Results.load(out)


@pytest.mark.parametrize(
    ("name", "read"),
    [("attitude.aem", ccsds_text.read_kvn), ("attitude.aem.xml", ccsds_text.read_xml)],
)
def test_the_aem_reads_back_as_the_run_s_attitude(video_sar, name, read):
    out, results = video_sar
    message = read((out / name).read_text())
    assert message["header"]["CCSDS_AEM_VERS"] == "2.0"
    (segment,) = message["segments"]
    meta = segment["metadata"]
    assert (meta["REF_FRAME_A"], meta["REF_FRAME_B"], meta["TIME_SYSTEM"]) == (
        "TEME",
        "SC_BODY_1",
        "UTC",
    )
    assert (meta["ATTITUDE_TYPE"], meta["ANGVEL_FRAME"]) == ("QUATERNION/ANGVEL", "SC_BODY_1")
    expected = [EPOCH + datetime.timedelta(seconds=float(t)) for t in results.time]
    assert segment["epochs"] == expected
    data = segment["data"]
    q_read = np.column_stack([data[:, 3], data[:, :3]])  # scalar last in the message
    assert (data[:, 3] >= 0).all()  # QC ≥ 0, as 504.0-B-2 recommends
    assert angle_between(q_read, results.vector("SatelliteDynamics.q_BI")).max() <= 1e-9
    w = np.radians(data[:, 4:])
    assert np.abs(w - results.vector("SatelliteDynamics.w_BI_B")).max() <= 1e-12


def test_the_aem_quaternion_turns_the_boresight_onto_the_target(video_sar):
    """The message's quaternion read as the standard defines it (coordinate transformation
    from A = TEME to B = body): the radar boresight +z_B in TEME is the line of sight from
    the OEM's position to the target, off by the run's own pointing error (its summary's
    max, ~1e-5°).  Read the other way round it would miss by tens of degrees."""
    from oem import OrbitEphemerisMessage

    out, results = video_sar
    attitude = ccsds_text.read_kvn((out / "attitude.aem").read_text())["segments"][0]["data"]
    orbit = OrbitEphemerisMessage.open(out / "orbit.oem")
    (segment,) = orbit.segments
    position = np.array([state.position for state in segment.states])  # km
    target = results.vector("OrbitEnvironment.r_T_I") / 1e3
    worst = 0.0
    for (q1, q2, q3, qc, *_), r, r_T in zip(attitude, position, target):
        # v_A = M(q)ᵀ v_B: of the three body axes, where z_B lies in A
        z_in_a = np.array([ccsds_text.rotate_a_to_b(q1, q2, q3, qc, e)[2] for e in np.eye(3)])
        sight = (r_T - r) / np.linalg.norm(r_T - r)
        worst = max(worst, math.degrees(math.acos(min(1.0, float(z_in_a @ sight)))))
    summary = json.loads((out / "summary.json").read_text())
    assert worst == pytest.approx(
        math.degrees(summary["metrics"]["pointing_error_max"]["value"]), rel=0.02
    )


@pytest.mark.parametrize("name", ["orbit.oem", "orbit.oem.xml"])
def test_the_oem_reads_back_as_the_run_s_orbit(video_sar, name):
    from oem import OrbitEphemerisMessage

    out, results = video_sar
    orbit = OrbitEphemerisMessage.open(out / name)
    (segment,) = orbit.segments
    assert segment.metadata["REF_FRAME"] == "TEME"
    assert segment.metadata["TIME_SYSTEM"] == "UTC"
    assert segment.metadata["CENTER_NAME"] == "EARTH"
    states = list(segment.states)
    position = np.array([s.position for s in states]) * 1e3
    velocity = np.array([s.velocity for s in states]) * 1e3
    r, v = results.vector("OrbitEnvironment.r_I"), results.vector("OrbitEnvironment.v_I")
    assert np.abs(position - r).max() <= 1e-9 * np.abs(r).max()
    assert np.abs(velocity - v).max() <= 1e-9 * np.abs(v).max()
    first = states[0].epoch.datetime
    assert abs((first - EPOCH).total_seconds()) < 1e-6


def test_a_run_without_an_epoch_needs_one_and_keeps_its_ground_geometry(scan_pitch_run, tmp_path):
    """scan_pitch has no epoch: the export says to give one; with ``--epoch`` the OEM's TEME
    positions, turned by GMST(epoch + t), are over the same Earth-fixed points as the run's
    (r_I turned by its Earth angle), and the AEM's attitude is the run's turned alike."""
    out, _, _, results = scan_pitch_run
    refused = agilesat("export-ephemeris", out, "--out", tmp_path)
    assert refused.returncode == 1
    assert "has no epoch" in refused.stderr and "--epoch" in refused.stderr
    made = agilesat("export-ephemeris", out, "--out", tmp_path, "--epoch", "2024-03-20T12:00:00")
    assert made.returncode == 0, made.stderr
    epoch = datetime.datetime(2024, 3, 20, 12)
    from oem import OrbitEphemerisMessage

    (segment,) = OrbitEphemerisMessage.open(tmp_path / "orbit.oem").segments
    assert segment.metadata["REF_FRAME_EPOCH"].datetime == datetime.datetime(2024, 3, 20, 12)
    every = len(results) // 20
    t = results.time[::every]
    theta = results["OrbitEnvironment.earth_angle"][::every]
    r_I = results.vector("OrbitEnvironment.r_I")[::every]
    r_T = np.array([state.position for state in segment.states])[::every] * 1e3
    for x, angle, a, b in zip(t, theta, r_I, r_T):
        run_lon = math.atan2(a[1], a[0]) - angle
        export_lon = math.atan2(b[1], b[0]) - gmst(epoch, float(x))
        assert abs(math.remainder(run_lon - export_lon, 2 * math.pi)) < 1e-8
    attitude = ccsds_text.read_kvn((tmp_path / "attitude.aem").read_text())["segments"][0]
    q = attitude["data"][0, :4]
    q_BI = results.vector("SatelliteDynamics.q_BI")[0]
    z_run = _earth_fixed(q_BI[1], q_BI[2], q_BI[3], q_BI[0], theta[0])
    z_export = _earth_fixed(*q, gmst(epoch))
    assert np.abs(z_run - z_export).max() < 1e-9  # the body's z axis, Earth-fixed


def _earth_fixed(q1, q2, q3, qc, earth_angle) -> np.ndarray:
    """+z_B in an Earth-fixed frame turned by ``earth_angle`` about z from the message's
    (or the run's) inertial frame."""
    z = np.array([ccsds_text.rotate_a_to_b(q1, q2, q3, qc, e)[2] for e in np.eye(3)])
    c, s = math.cos(earth_angle), math.sin(earth_angle)
    return np.array([c * z[0] + s * z[1], -s * z[0] + c * z[1], z[2]])
