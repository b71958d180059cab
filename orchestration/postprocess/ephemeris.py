"""A run's attitude and orbit as CCSDS ephemerides (docs/ephemerides.md): the attitude as an
Attitude Ephemeris Message (AEM, CCSDS 504.0-B-2, ADM version 2.0) and the orbit as an
Orbit Ephemeris Message (OEM, CCSDS 502.0-B-3, ODM version 3.0), each in KVN and in XML,
written with ``ccsds-ndm-py`` (its message classes validate what they write).

Frames.  The run's inertial frame I is, with an epoch (``OrbitEnvironment.epoch``,
``epoch_j2000``, or a TLE's), the TEME of that epoch, taken as inertial (the Earth angle
is GMST, ``C_EI = R3(GMST)``: components/orbit_environment.py), named ``TEME`` with the
epoch (OEM ``REF_FRAME_EPOCH``; an AEM has no such keyword: a COMMENT says it).  A run
without an epoch has an I tied to nothing but its Earth angle θ_E: ``--epoch`` then dates
t = 0 and turns I into the TEME of that epoch about z so that the Earth-fixed geometry is
kept, ``C_TI = R3(θ_E(0) − GMST(epoch))`` (the ground track is where the run had it).

Attitude.  ``ATTITUDE_TYPE = QUATERNION/ANGVEL``, ``REF_FRAME_A = TEME``, ``REF_FRAME_B =
SC_BODY_1`` (the body frame B of ``SatelliteDynamics``): the quaternion of the coordinate
transformation from A to B, ``Q1 Q2 Q3`` = e sin(φ/2) and ``QC`` = cos(φ/2), scalar last
(504.0-B-2: B-1's QUATERNION_TYPE and ATTITUDE_DIR are gone; the direction is A to B).
Ours, ``q_BI`` (DESIGN.md §2: scalar first, Hamilton, ``v_B = C(q_BI) v_I``), is that
transformation from I to B: ``(Q1, Q2, Q3, QC) = (q1, q2, q3, q0)`` of ``q_BT = q_IT ⊗
q_BI``, its sign chosen so that QC ≥ 0 (the standard's recommendation; −q is the same
attitude).  ``ANGVEL_X/Y/Z`` = ``w_BI_B`` in deg/s, ``ANGVEL_FRAME = SC_BODY_1``.

Orbit.  ``r_I``, ``v_I`` turned into TEME, km and km/s.

Time.  ``TIME_SYSTEM = UTC``; a sample at run time t is dated epoch + t, t counted in SI
seconds as the run counts them (86 400 s a day: a run across a leap second is dated one
second off after it).
"""

from __future__ import annotations

import datetime
import math
from pathlib import Path

import numpy as np

from ..output.frames import r3, turn_z
from ..pointing import quaternion_product
from .run_directory import RunDirectory

#: the files written, by message and format
FILES = {
    ("aem", "kvn"): "attitude.aem",
    ("aem", "xml"): "attitude.aem.xml",
    ("oem", "kvn"): "orbit.oem",
    ("oem", "xml"): "orbit.oem.xml",
}
FORMATS = ("kvn", "xml")
REF_FRAME = "TEME"
BODY_FRAME = "SC_BODY_1"


class EphemerisError(ValueError):
    """A run that cannot be written as the messages ask (said why)."""


def run_epoch(run: RunDirectory) -> datetime.datetime | None:
    """The UTC date of the run's t = 0 as its OrbitEnvironment had it (``epoch``, else
    ``epoch_j2000``, else the TLE's epoch), or None."""
    from ...components.ephemeris import DAY, J2000, load_tle, parse_epoch, tle_epoch

    text = str(run.parameter("OrbitEnvironment.epoch") or "").strip()
    if text:
        return parse_epoch(text)
    seconds = float(run.parameter("OrbitEnvironment.epoch_j2000") or 0.0)
    if seconds:
        return J2000 + datetime.timedelta(seconds=seconds)
    line1 = str(run.parameter("OrbitEnvironment.tle_line1") or "").strip()
    line2 = str(run.parameter("OrbitEnvironment.tle_line2") or "").strip()
    if line1 and line2:
        days, seconds = tle_epoch(load_tle(line1, line2))
        return J2000 + datetime.timedelta(seconds=days * DAY + seconds)
    return None


def frame_turn(
    run: RunDirectory, epoch: datetime.datetime | None
) -> tuple[datetime.datetime, float]:
    """(the epoch of t = 0, α: C_TI = R3(α)) of a run (module: 0 with the run's own epoch;
    θ_E(0) − GMST(epoch) with one given for a run without)."""
    from ...components.ephemeris import gmst

    own = run_epoch(run)
    if own is not None:
        if epoch is not None and epoch != own:
            raise EphemerisError(
                f"{run.path}: the run has its own epoch, {own.isoformat()} (its I is the TEME "
                "of it); --epoch is for a run without one"
            )
        return own, 0.0
    if epoch is None:
        raise EphemerisError(
            f"{run.path}: the run has no epoch (OrbitEnvironment.epoch): give --epoch "
            "YYYY-MM-DDTHH:MM:SS (UTC) to date its t = 0; its inertial frame is then turned "
            "into the TEME of that epoch, keeping the Earth-fixed geometry"
        )
    theta = _recorded(run, "OrbitEnvironment.earth_angle")
    return epoch, float(theta[0]) - gmst(epoch)


def _recorded(run: RunDirectory, name: str) -> np.ndarray:
    if name not in run.results:
        raise EphemerisError(
            f"{run.path}: the run did not record {name}, which the messages need "
            f"(`agilesat run` records every output unless --record names others)"
        )
    return run.results[name]


def dates(epoch: datetime.datetime, t) -> list[str]:
    """ISO 8601 UTC dates epoch + t (microseconds)."""
    return [
        (epoch + datetime.timedelta(seconds=float(x))).isoformat(timespec="microseconds") for x in t
    ]


def export(
    directory,
    out=None,
    epoch=None,
    formats=FORMATS,
    object_name: str | None = None,
    object_id: str = "UNKNOWN",
    orbit: bool = True,
) -> list[Path]:
    """Write the run's AEM (and its OEM, with ``orbit``) into ``out`` (default the run's
    directory) in each of ``formats``; ``epoch`` (ISO 8601 UTC or a datetime) for a run
    without one.  Returns the files written."""
    from importlib import metadata

    import ccsds_ndm

    from ...components.ephemeris import parse_epoch
    from ..output.recorder import write_text

    run = RunDirectory(directory)
    start, alpha = frame_turn(run, None if epoch is None else parse_epoch(epoch))
    results = run.results
    t = results.time
    when = dates(start, t)
    name = object_name or run.label.replace(":", "-")
    q_BT = quaternion_product(turn_z(-alpha), _vector(run, "SatelliteDynamics.q_BI", 4))
    q_BT *= np.where(q_BT[:, :1] < 0, -1.0, 1.0)
    w = np.degrees(_vector(run, "SatelliteDynamics.w_BI_B"))
    created = datetime.datetime.now(datetime.timezone.utc).replace(tzinfo=None)
    created_text = created.isoformat(timespec="seconds")
    originator = f"agilesat {metadata.version('agilesat')}"
    frame_note = [
        f"REF_FRAME_A {REF_FRAME} is the TEME of {start.isoformat()} UTC (the epoch of t = 0), "
        "taken as inertial: the run's frame I"
        + (
            ""
            if alpha == 0.0
            else f" turned by {math.degrees(alpha):.9f} deg about z "
            "(--epoch: the Earth-fixed geometry kept)"
        ),
        f"REF_FRAME_B {BODY_FRAME} is the body frame B of SatelliteDynamics; quaternion of the "
        "coordinate transformation A to B (q_BI of the run), angular velocity w_BI_B",
        f"made by agilesat export-ephemeris from {run.label} ({run.summary.get('date', '')})",
    ]
    aem = ccsds_ndm.Aem(
        ccsds_ndm.AdmHeader(created_text, originator),
        [
            ccsds_ndm.AemSegment(
                ccsds_ndm.AemMetadata(
                    name,
                    object_id,
                    ref_frame_a=REF_FRAME,
                    ref_frame_b=BODY_FRAME,
                    start_time=when[0],
                    stop_time=when[-1],
                    time_system="UTC",
                    attitude_type="QUATERNION/ANGVEL",
                    center_name="EARTH",
                    angvel_frame=BODY_FRAME,
                    interpolation_method="LAGRANGE",
                    interpolation_degree=7,
                    comment=frame_note,
                ),
                ccsds_ndm.AemData.from_numpy(
                    when,
                    np.column_stack([q_BT[:, 1:], q_BT[:, :1], w]),
                    attitude_type="QUATERNION/ANGVEL",
                ),
            )
        ],
    )
    messages = [("aem", aem)]
    if orbit:
        C_TI = r3(alpha)
        r = _vector(run, "OrbitEnvironment.r_I")
        v = _vector(run, "OrbitEnvironment.v_I")
        state = np.column_stack([r @ C_TI.T, v @ C_TI.T]) / 1e3  # km, km/s
        oem = ccsds_ndm.Oem(
            ccsds_ndm.OdmHeader(created_text, originator),
            [
                ccsds_ndm.OemSegment(
                    ccsds_ndm.OemMetadata(
                        name,
                        object_id,
                        when[0],
                        when[-1],
                        center_name="EARTH",
                        ref_frame=REF_FRAME,
                        time_system="UTC",
                        ref_frame_epoch=when[0],
                        interpolation="LAGRANGE",
                        interpolation_degree=7,
                        comment=[
                            frame_note[0].replace("REF_FRAME_A ", "REF_FRAME "),
                            frame_note[2],
                        ],
                    ),
                    ccsds_ndm.OemData.from_numpy(when, state),
                )
            ],
        )
        messages.append(("oem", oem))
    target = Path(out) if out is not None else run.path
    target.mkdir(parents=True, exist_ok=True)
    written = []
    for kind, message in messages:
        for fmt in formats:
            path = target / FILES[kind, fmt]
            write_text(path, message.to_str(fmt))
            written.append(path)
    return written


def _vector(run: RunDirectory, name: str, n: int = 3) -> np.ndarray:
    """The recorded elements 1 … n of ``name`` as (samples, n)."""
    return np.column_stack([_recorded(run, f"{name}[{k}]") for k in range(1, n + 1)])
