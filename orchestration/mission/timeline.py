"""SlewGuidance's segment table from readable segments (components/slew_guidance.py).

    from agilesat.orchestration.mission import deg, nadir, stare, timeline

    system.add("SlewGuidance", **timeline(
        nadir(0.0),
        nadir(10.0, roll=deg(25)),                  # the orbit frame rolled by 25°
        stare(120.0, deg(33.16), deg(129.72)),     # a ground target
    ))

Angles are numbers in rad or values with a unit (``deg(25)``, ``"25 deg"``); times in s.
FMI has no lists: the table is ``segment_count`` rows of fixed-size arrays, which
:func:`timeline` fills (the unused rows zero).
"""

from __future__ import annotations

from dataclasses import dataclass

from agilesat.components.rotations import quat_from_euler123, quat_normalize
from agilesat.components.slew_guidance import INERTIAL, N_SEGMENTS, NADIR, STARE

from ..system.units import quantity, to_si

_IDENTITY = (1.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Segment:
    """One row of the table: kind, start (s), attitude q (INERTIAL: q_RI; NADIR: q_RO) or
    target (lat, lon in rad, alt in m; STARE)."""

    kind: int
    start: float
    q: tuple = _IDENTITY
    target: tuple = (0.0, 0.0, 0.0)


def _si(value, unit: str) -> float:
    given = quantity(value)
    return float(to_si(given, unit) if given is not None else value)


def inertial(start: float, q_RI) -> Segment:
    """Hold the attitude q_RI (scalar first) from ``start`` on."""
    return Segment(INERTIAL, float(start), tuple(float(x) for x in q_RI))


def nadir(start: float, roll=0.0, pitch=0.0, yaw=0.0) -> Segment:
    """Follow the orbit frame O from ``start`` on, turned by the 1-2-3 angles (roll,
    pitch, yaw) relative to it (DESIGN.md §2)."""
    euler = [_si(a, "rad") for a in (roll, pitch, yaw)]
    return Segment(NADIR, float(start), tuple(quat_normalize(quat_from_euler123(euler)).tolist()))


def stare(start: float, lat, lon, alt=0.0) -> Segment:
    """Stare at the ground target (geodetic latitude, longitude, height) from ``start`` on."""
    return Segment(STARE, float(start), target=(_si(lat, "rad"), _si(lon, "rad"), _si(alt, "m")))


def timeline(*segments: Segment) -> dict:
    """SlewGuidance's parameter values of a timeline, to pass to ``system.add``."""
    if not 1 <= len(segments) <= N_SEGMENTS:
        raise ValueError(f"a timeline has 1 to {N_SEGMENTS} segments, got {len(segments)}")
    rows = list(segments) + [Segment(0, 0.0)] * (N_SEGMENTS - len(segments))
    return {
        "segment_count": len(segments),
        "segment_kind": [row.kind for row in rows],
        "segment_start": [row.start for row in rows],
        "segment_q": [list(row.q) for row in rows],
        "target_lat": [row.target[0] for row in rows],
        "target_lon": [row.target[1] for row in rows],
        "target_alt": [row.target[2] for row in rows],
    }
