"""Slew guidance: a timeline of time-tagged segments — inertial holds, nadir, stares at
ground targets — and minimum-time eigenaxis slews between them (DESIGN.md §3.2).

Segments.  Row k of the segment table (1 ≤ k ≤ ``segment_count``; FMI has no lists, so
the rows are fixed-size arrays) is a frame R_k(t) the reference follows:

- INERTIAL: q_RI = ``segment_q[k]``, at rest;
- NADIR: q_RI = q_OI ⊗ q_RO with q_RO = ``segment_q[k]`` (identity: the orbit frame O;
  else a fixed offset from it), ω_R = C_RO w_OI_O;
- STARE: the boresight on the ground target (``target_lat[k]``, ``target_lon[k]``,
  ``target_alt[k]``, WGS-84) with [Liang 2019]'s yaw compensation: StaringGuidance's
  geometry (components/staring_guidance.py, its functions): the frame F(û, x_O) of the line
  of sight û with yaw 0, or F(û, g) with g the footprint direction of the yaw-0 frame
  frozen on the ground at the *stare's start*: the end of the slew into it (the first
  segment: the start of the run); exact rates and accelerations along a two-body orbit.

The run starts in segment 1 (whose start must not be after the run's), on it.  At
``segment_start[k]`` (k ≥ 2) the slew into segment k begins; it must end before segment
k + 1 starts (else a ModelError at its start, with the times).  With ``segment_count`` 0
the table is the single inertial slew of DESIGN.md §3.2: hold ``q_initial``, then at
``slew_start`` slew to ``q_target``.  ``agilesat.orchestration.mission.timeline`` writes
the table from readable segments.

Slews (components/slew.py).  A slew from segment A into segment B follows the blend
q_R = q_A ⊗ exp(s L), L = log(q_A* ⊗ q_B), with s = p(t − t_s)/Θ driven by the least-time
rest-to-rest angle profile p under ``rate_limit``, ``accel_limit`` and ``jerk_limit``.  Both
frames keep moving during the slew: the reference starts with A's attitude, rate and
acceleration and ends with B's, so q, ω and ω̇ are continuous at every switch, and a slew
into a moving stare ends matched in attitude and rate.  Between two inertial holds it is
the eigenaxis slew itself and takes exactly the closed-form least time
(:func:`.slew.minimum_time`; with jerk_limit = inf, θ/ω + ω/α, or 2√(θ/α) below
θ = ω²/α; a finite jerk limit adds α/j).

Planning a slew between moving segments, at the first communication point t_p ≥ t_s:

1. Prediction: the satellite's two-body orbit from (r_I, v_I) at t_p (:func:`two_body`),
   the Earth turned by ω_E; J2 and the unmodelled part of the orbit affect only the plan
   (its duration and the stare's frozen footprint direction), never the continuity.
2. The end time, by fixed-point iteration: T = T_min(Θ) with Θ = max(θ(t_p), θ(t_s + T)),
   θ the angle between the frames, g (a stare's footprint direction) captured at t_s + T;
   the limits are reduced by the frames' own motion (ω_f, α_f: the largest |ω|, |ω̇| of A
   and B at t_p and at the end): ω_max − ω_f, α_max − α_f − ω_max ω_f.
3. The check: the planned reference is evaluated at ``SAMPLES`` instants of the slew on the
   predicted geometry; where |ω_R| or |ω̇_R| exceeds a limit (the blend's Coriolis terms:
   the rate change ω_B − ω_A over the slew), the profile is stretched in time (limits
   ω/λ, α/λ², j/λ³) by the least λ found to 1e-3 by bisection.

So between moving segments the slew takes the least time of this family that meets the
limits at the checked instants (not the least time of every possible path).

Outputs: q_ref = q_RI (sign kept continuous), w_ref = ω_RI in R, dw_ref = its derivative,
``mode`` = 0 (SLEW) during a slew, else the segment's kind, ``segment`` (1-based; during a
slew the one being entered), ``slewing``.

Inputs: r_I, v_I for NADIR and STARE, q_OI for NADIR (checked against r_I, v_I to
Q_OI_TOLERANCE), w_OI_O for NADIR (zero: the two-body rate of r_I, v_I), earth_angle for
STARE (C_EI = R3(earth_angle)); ω̇ of the orbit frame is the two-body (0, 2|h| ṙ/r³, 0).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from . import slew
from .model import Model, ModelError
from .orbit_environment import EARTH_RATE, MU_EARTH, WGS84_A, geodetic_to_ecef
from .rotations import IDENTITY_Q, dcm, qmul, quat_of_rows
from .staring_guidance import (
    MIN_SLANT_RANGE,
    OK,
    Q_OI_TOLERANCE,
    START_Q_OI,
    START_R,
    START_V,
    aligned_axes,
    aligned_frame,
    frozen_direction,
    geodetic_latitude,
    ground_fixed,
    line_of_sight,
    mismatch,
    mount,
    orbit_axes,
    tangent_frame,
    x_axis_rates,
)
from .variables import input_, output, parameter
from .vectors import dot, norm, quat_dot, rotate, sub

SLEW, INERTIAL, NADIR, STARE = range(4)
N_SEGMENTS = 10
START_TOLERANCE = 1e-9  # s per s of max(1, |segment_start|): "t >= segment_start"
SAMPLES = 32  # instants of a slew between moving segments checked against the limits
#: (with the ends of its profile's phases)
DEG = math.pi / 180.0
ZERO = (0.0, 0.0, 0.0)
_IDENTITY = tuple(IDENTITY_Q.tolist())
_ROLL_30 = (math.cos(15 * DEG), math.sin(15 * DEG), 0.0, 0.0)
_KINDS = "1 = INERTIAL (segment_q = q_RI), 2 = NADIR (segment_q = q_RO), 3 = STARE"
_INPUTS = ("r_I", "v_I", "q_OI", "w_OI_O", "earth_angle")


# -- orbit: prediction and frame -----------------------------------------------------------
def two_body(r, v, dt: float) -> tuple:
    """(r, v) after ``dt`` on the two-body ellipse through (r, v): Kepler's equation in the
    eccentric-anomaly change ΔE by Newton, then the f and g functions ([Vallado 2013]
    §2.3; n dt = ΔE − (1 − r₀/a) sin ΔE + (r₀·v₀/√(μa)) (1 − cos ΔE))."""
    r0 = norm(r)
    a = 1.0 / (2.0 / r0 - dot(v, v) / MU_EARTH)
    if not a > 0.0:
        raise ModelError(f"r_I, v_I are not an elliptic orbit (a = {a:.6g} m)")
    n = math.sqrt(MU_EARTH / a**3)
    e_c, e_s = 1.0 - r0 / a, dot(r, v) / math.sqrt(MU_EARTH * a)
    E = n * dt
    for _ in range(50):
        step = (E - e_c * math.sin(E) + e_s * (1.0 - math.cos(E)) - n * dt) / (
            1.0 - e_c * math.cos(E) + e_s * math.sin(E)
        )
        E -= step
        if abs(step) <= 1e-15 * max(1.0, abs(E)):
            break
    c, s = math.cos(E), math.sin(E)
    radius = a * (1.0 - e_c * c + e_s * s)
    f, g = 1.0 - a / r0 * (1.0 - c), dt - (E - s) / n
    df, dg = -math.sqrt(MU_EARTH * a) * s / (radius * r0), 1.0 - a / radius * (1.0 - c)
    return (
        tuple(f * x + g * y for x, y in zip(r, v)),
        tuple(df * x + dg * y for x, y in zip(r, v)),
    )


def orbit_frame(r, v) -> tuple:
    """(C_OI rows, w_OI_O, its derivative) of the two-body orbit frame of (r, v)
    (components/orbit_environment.py): w_OI_O = (0, −|h|/r², 0), d/dt = (0, 2|h| ṙ/r³, 0)."""
    defined, rows, radius, r_hat, h = orbit_axes(r, v)
    if not defined:
        raise ModelError("r_I and v_I are parallel or zero: the orbit frame is undefined")
    return rows, (0.0, -h / radius**2, 0.0), (0.0, 2.0 * h * dot(v, r_hat) / radius**3, 0.0)


def _yaw_zero_direction(r, v) -> tuple:
    """(x_O, ẋ_O, ẍ_O) along the two-body orbit (StaringGuidance's reference direction)."""
    (x_O, _, _), _, _ = orbit_frame(r, v)
    _, _, radius, r_hat, h = orbit_axes(r, v)
    return (x_O, *x_axis_rates(x_O, r_hat, radius, h, v))


class Geometry(NamedTuple):
    """What the segments' frames need at one time."""

    r: tuple
    v: tuple
    earth_angle: float
    q_OI: tuple
    w_O: tuple
    dw_O: tuple


@dataclass(frozen=True)
class Row:
    """A segment as the model keeps it: the target in E (m) instead of lat, lon, alt."""

    kind: int
    start: float
    q: tuple = _IDENTITY
    r_T_E: tuple = ZERO


@dataclass(frozen=True)
class Plan:
    """A slew into segment ``into`` (0-based) from ``start``, lasting ``duration``: the
    profile of ``angle``, planned at ``planned_at``; the footprint direction (g in E) of a
    stare with yaw compensation it freezes at its end, else None."""

    into: int
    start: float
    duration: float
    angle: float
    phases: tuple
    planned_at: float
    footprint: tuple | None = None

    @property
    def end(self) -> float:
        return self.start + self.duration


class SlewGuidance(Model):
    """Segments (inertial, nadir, stare) and minimum-time eigenaxis slews between them."""

    DEFAULT_STOP = 30.0  #: the default 30° slew (20 s) and its end

    VARIABLES = (
        parameter("rate_limit", 2.0 * DEG, "rad/s", "largest slew rate", display_unit="deg/s"),
        parameter(
            "accel_limit",
            0.5 * DEG,
            "rad/s2",
            "largest slew acceleration",
            display_unit="deg/s2",
        ),
        parameter(
            "jerk_limit",
            0.5 * DEG,
            "rad/s3",
            "largest jerk of the slew profile (inf: none, bang-coast-bang; finite: the "
            "acceleration is continuous and a slew reaching accel_limit takes "
            "accel_limit/jerk_limit longer)",
            display_unit="deg/s3",
        ),
        parameter(
            "slew_start",
            0.0,
            "s",
            "segment_count 0: start of the single inertial slew from q_initial to q_target",
        ),
        parameter(
            "q_initial",
            _IDENTITY,
            "1",
            "segment_count 0: the attitude q_RI held before the slew",
            shape=(4,),
        ),
        parameter(
            "q_target",
            _ROLL_30,
            "1",
            "segment_count 0: the target attitude q_RI of the single slew",
            shape=(4,),
        ),
        parameter(
            "segment_count",
            0,
            "1",
            f"rows of the segment table in use, up to {N_SEGMENTS} (0: the single slew of "
            "q_initial, q_target and slew_start)",
            type="Integer",
        ),
        parameter(
            "segment_kind",
            0,
            "1",
            f"kind of each segment: {_KINDS}",
            shape=(N_SEGMENTS,),
            type="Integer",
        ),
        parameter(
            "segment_start",
            0.0,
            "s",
            "start of each segment: the slew into it begins then (the first segment holds "
            "from the start of the run)",
            shape=(N_SEGMENTS,),
        ),
        parameter(
            "segment_q",
            [_IDENTITY] * N_SEGMENTS,
            "1",
            "INERTIAL: the attitude q_RI; NADIR: the attitude q_RO relative to the orbit "
            "frame (identity: O itself)",
            shape=(N_SEGMENTS, 4),
        ),
        parameter(
            "target_lat",
            0.0,
            "rad",
            "STARE: geodetic latitude of the target (WGS-84)",
            shape=(N_SEGMENTS,),
            display_unit="deg",
        ),
        parameter(
            "target_lon",
            0.0,
            "rad",
            "STARE: longitude of the target",
            shape=(N_SEGMENTS,),
            display_unit="deg",
        ),
        parameter(
            "target_alt",
            0.0,
            "m",
            "STARE: height of the target above the WGS-84 ellipsoid",
            shape=(N_SEGMENTS,),
        ),
        parameter(
            "yaw_compensation",
            True,
            "1",
            "STARE: true: the footprint direction of the yaw-0 attitude at the stare's "
            "start is held on the ground ([Liang 2019] eq 12); false: yaw 0 (eqs 10-11)",
            type="Boolean",
        ),
        parameter(
            "boresight_B",
            (0.0, 0.0, 1.0),
            "1",
            "STARE: the boresight in B, normalised by the model",
            shape=(3,),
        ),
        input_(
            "r_I",
            "m",
            "satellite position in I",
            START_R,
            shape=(3,),
            optional="needed by NADIR and STARE segments only",
        ),
        input_(
            "v_I",
            "m/s",
            "satellite velocity in I",
            START_V,
            shape=(3,),
            optional="needed by NADIR and STARE segments only",
        ),
        input_(
            "q_OI",
            "1",
            "attitude of the orbit frame O relative to I (must match r_I, v_I)",
            START_Q_OI,
            shape=(4,),
            optional="needed by NADIR segments only",
        ),
        input_(
            "w_OI_O",
            "rad/s",
            "angular velocity of O relative to I, in O",
            shape=(3,),
            optional="zero: the two-body rate of r_I, v_I",
            display_unit="deg/s",
        ),
        input_(
            "earth_angle",
            "rad",
            "Earth rotation angle (C_EI = R3(earth_angle))",
            optional="zero: needed by STARE segments only (connect it for them)",
        ),
        output(
            "q_ref",
            "1",
            "attitude of the reference frame R relative to I (q_RI)",
            shape=(4,),
            depends=_INPUTS,
        ),
        output(
            "w_ref",
            "rad/s",
            "angular velocity of R relative to I, in R axes",
            shape=(3,),
            depends=_INPUTS,
            display_unit="deg/s",
        ),
        output(
            "dw_ref",
            "rad/s2",
            "time derivative of w_ref, in R axes",
            shape=(3,),
            depends=_INPUTS,
            display_unit="deg/s2",
        ),
        output(
            "mode",
            "1",
            "0 = SLEW, else the segment's kind: 1 = INERTIAL, 2 = NADIR, 3 = STARE",
            type="Integer",
        ),
        output(
            "segment",
            "1",
            "the segment held or, during a slew, entered (1-based)",
            type="Integer",
        ),
        output("slewing", "1", "a slew is under way", type="Boolean"),
    )

    def initialize(self, t0):
        p = self.p
        for name in ("rate_limit", "accel_limit"):
            if not (math.isfinite(getattr(p, name)) and getattr(p, name) > 0.0):
                raise ModelError(f"{name} must be finite and > 0, got {getattr(p, name)}")
        if not p.jerk_limit > 0.0:
            raise ModelError(f"jerk_limit must be > 0 (inf: none), got {p.jerk_limit}")
        self.rows = self._rows(t0)
        C_RP = mount(p.boresight_B)
        self.mount = None if np.array_equal(C_RP, np.eye(3)) else tuple(map(tuple, C_RP))
        self.segment = 0  # held, or entered by self.plan
        self.plan: Plan | None = None
        self.footprint: dict = {}  # segment -> (g in E, the time it was frozen)
        self.anchor_q = self.last_q = None  # q_ref at the last communication point, now
        self.anchor_D = self.last_D = None  # the same for q_A* ⊗ q_B during a slew
        self.below_horizon: frozenset = frozenset()  # stares already warned about
        self._now: Geometry | None = None  # the geometry at t while output() runs
        self.t = t0

    def _rows(self, t0: float) -> list[Row]:
        p = self.p
        count = p.segment_count
        if count == 0:
            if not p.slew_start >= t0 - START_TOLERANCE * max(1.0, abs(t0)):
                raise ModelError(f"slew_start {p.slew_start} s is before the start {t0} s")
            return [
                Row(INERTIAL, t0, _unit(p.q_initial, "q_initial")),
                Row(INERTIAL, p.slew_start, _unit(p.q_target, "q_target")),
            ]
        if not 1 <= count <= N_SEGMENTS:
            raise ModelError(f"segment_count must be 0 to {N_SEGMENTS}, got {count}")
        rows: list[Row] = []
        for k in range(count):
            kind, start = int(p.segment_kind[k]), float(p.segment_start[k])
            where = f"segment {k + 1}"
            if kind not in (INERTIAL, NADIR, STARE):
                raise ModelError(f"segment_kind[{k + 1}] must be {_KINDS}, got {kind}")
            if not math.isfinite(start):
                raise ModelError(f"segment_start[{k + 1}] must be finite, got {start}")
            if k == 0 and start > t0 + START_TOLERANCE * max(1.0, abs(t0)):
                raise ModelError(
                    f"{where} starts at {start} s, after the start {t0} s: a run starts in "
                    "segment 1"
                )
            if k == 1 and start < t0 - START_TOLERANCE * max(1.0, abs(t0)):
                raise ModelError(f"{where} starts at {start} s, before the start {t0} s")
            if k >= 1 and not (start > rows[-1].start or (k == 1 and start == rows[0].start)):
                raise ModelError(
                    f"segment_start must increase: {where} at {start} s, segment {k} at "
                    f"{rows[-1].start} s"
                )
            if kind == STARE:
                lat, lon, alt = (
                    float(p.target_lat[k]),
                    float(p.target_lon[k]),
                    float(p.target_alt[k]),
                )
                if not (
                    abs(lat) <= math.pi / 2 and math.isfinite(lon) and abs(alt) < 0.1 * WGS84_A
                ):
                    raise ModelError(
                        f"{where}: the target (lat {lat}, lon {lon} rad, alt {alt} m) must have "
                        f"|lat| <= pi/2 and |alt| < {0.1 * WGS84_A:g} m"
                    )
                rows.append(Row(kind, start, r_T_E=geodetic_to_ecef(lat, lon, alt)))
            else:
                rows.append(Row(kind, start, _unit(p.segment_q[k], f"segment_q[{k + 1},:]")))
        return rows

    def step(self, t, dt):
        self.anchor_q, self.anchor_D = self.last_q, self.last_D
        self.t = t + dt

    def output(self):
        t, rows = self.t, self.rows
        later = self.segment + 1 < len(rows)
        if self.plan is not None and self.plan.planned_at == t:  # evaluated again at t
            self.plan = self._plan(t)
        elif self.plan is None and later and t >= _due(rows[self.segment + 1].start):
            self.segment += 1
            self.plan = self._plan(t)
        k = self.segment
        if k == 0 and rows[0].kind == STARE and self.p.yaw_compensation:
            frozen = self.footprint.get(0)
            if frozen is None or frozen[1] == t:  # the first output, or again at it
                self.footprint[0] = (self._freeze(rows[0], self.now()), t)
        plan = self.plan
        if plan is not None and t - plan.start < plan.duration:
            q, w, dw = self._slewing(plan, t)
        else:
            self.plan = None
            q, w, dw = self.frame(k, self.now())
            self.last_D = None
        if rows[k].kind == STARE:
            self._check_horizon(k)
        if self.anchor_q is not None and quat_dot(q, self.anchor_q) < 0.0:
            q = (-q[0], -q[1], -q[2], -q[3])
        self.last_q = q
        y = self.y
        y.q_ref[:], y.w_ref[:], y.dw_ref[:] = q, w, dw
        y.mode = SLEW if self.plan is not None else rows[k].kind
        y.segment = k + 1
        y.slewing = self.plan is not None
        self._now = None  # made again at the next output: no part of the state

    # -- frames --------------------------------------------------------------------------
    def now(self) -> Geometry:
        """The geometry of the inputs at t (q_OI checked against r_I, v_I)."""
        if self._now is None:
            u = self.u
            r, v, q_OI = tuple(u.r_I.tolist()), tuple(u.v_I.tolist()), tuple(u.q_OI.tolist())
            w_O = tuple(u.w_OI_O.tolist())
            bad = [n for n in _INPUTS if not np.all(np.isfinite(getattr(u, n)))]
            if bad:
                raise ModelError(f"t={self.t:.6g} s: inputs {bad} are not finite")
            rows, w_two_body, dw_O = orbit_frame(r, v)
            error = mismatch(dcm(q_OI), rows)
            if any(row.kind == NADIR for row in self.rows) and error > Q_OI_TOLERANCE:
                raise ModelError(
                    f"t={self.t:.6g} s: q_OI does not match the orbit frame of r_I, v_I by "
                    f"{error:.3g} > {Q_OI_TOLERANCE:g}: connect q_OI, r_I and v_I from one orbit"
                )
            self._now = Geometry(
                r, v, float(u.earth_angle), q_OI, w_O if any(w_O) else w_two_body, dw_O
            )
        return self._now

    def frame(self, k: int, geometry: Geometry | None, footprint=None) -> tuple:
        """(q_RI, ω in R, ω̇ in R) of segment k (0-based) at ``geometry``; a stare with yaw
        compensation with its frozen footprint direction (g in E), or ``footprint``."""
        row = self.rows[k]
        if row.kind == INERTIAL:
            return row.q, ZERO, ZERO
        assert geometry is not None  # NADIR and STARE need one
        if row.kind == NADIR:
            C_RO = dcm(row.q)
            return (
                qmul(geometry.q_OI, row.q),
                rotate(C_RO, geometry.w_O),
                rotate(C_RO, geometry.dw_O),
            )
        if footprint is None and self.p.yaw_compensation:
            footprint = self.footprint[k][0]  # frozen at the stare's start
        return self._stare(row, geometry, footprint, k)

    def _target(self, row: Row, geometry: Geometry) -> tuple:
        """(r_T, v_T, û, u̇, ü) in I (StaringGuidance's line of sight)."""
        r_T, v_T, _ = ground_fixed(row.r_T_E, geometry.earth_angle)
        distance = norm(sub(r_T, geometry.r))
        if not distance > MIN_SLANT_RANGE:
            raise ModelError(f"t={self.t:.6g} s: the satellite is at the target of a stare")
        return (r_T, v_T) + line_of_sight(geometry.r, geometry.v, r_T, v_T, distance)

    def _stare(self, row: Row, geometry: Geometry, footprint, k: int) -> tuple:
        _, _, u, du, ddu = self._target(row, geometry)
        if footprint is None:
            a, da, dda = _yaw_zero_direction(geometry.r, geometry.v)
        else:
            a, da, dda = ground_fixed(footprint, geometry.earth_angle)
        ok, C_RI, w, dw = aligned_frame(u, du, ddu, a, da, dda)
        if not ok:
            raise ModelError(
                f"t={self.t:.6g} s: segment {k + 1}: the line of sight is parallel to the "
                "reference direction of the stare (pitch +-90 deg, or a grazing view)"
            )
        if self.mount is not None:
            M = self.mount
            C_RI = tuple(
                tuple(sum(M[i][m] * C_RI[m][j] for m in range(3)) for j in range(3))
                for i in range(3)
            )
            w, dw = rotate(M, w), rotate(M, dw)
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C_RI
        return quat_of_rows(c00, c01, c02, c10, c11, c12, c20, c21, c22), w, dw

    def _freeze(self, row: Row, geometry: Geometry) -> tuple:
        """g in E: the ground line of the yaw-0 frame at ``geometry`` (StaringGuidance)."""
        r_T, _, u, _, _ = self._target(row, geometry)
        ok, x0, _, _, _ = aligned_axes(u, _yaw_zero_direction(geometry.r, geometry.v)[0])
        status, g, _, _ = frozen_direction(u, x0, r_T) if ok else (not OK, x0, 0.0, 0.0)
        if status != OK:
            raise ModelError(
                f"t={self.t:.6g} s: the footprint direction of a stare is undefined (target at "
                "a pole, pitch +-90 deg, or a grazing view)"
            )
        return ground_fixed(g, -geometry.earth_angle)[0]  # in E

    def _check_horizon(self, k: int) -> None:
        """Warn once when a stare's target is below the satellite's horizon."""
        row, geometry = self.rows[k], self.now()
        r_T = ground_fixed(row.r_T_E, geometry.earth_angle)[0]
        found, latitude = geodetic_latitude(r_T)
        up = tangent_frame(r_T, latitude)[0] if found else tuple(x / norm(r_T) for x in r_T)
        if dot(up, sub(geometry.r, r_T)) < 0.0 and k not in self.below_horizon:
            self.below_horizon |= {k}
            self.warnings.append(
                f"t={self.t:.6g} s: the target of segment {k + 1} is below the horizon: the "
                "stare looks through the Earth"
            )

    # -- slews ---------------------------------------------------------------------------
    def _slewing(self, plan: Plan, t: float) -> tuple:
        geometry = self.now() if self._needs_geometry(plan.into) else None
        a = self.frame(plan.into - 1, geometry)
        b = self.frame(plan.into, geometry)
        q_D = qmul((a[0][0], -a[0][1], -a[0][2], -a[0][3]), b[0])
        reference = self.anchor_D if self.anchor_D is not None else (1.0, 0.0, 0.0, 0.0)
        if quat_dot(q_D, reference) < 0.0:
            q_D = (-q_D[0], -q_D[1], -q_D[2], -q_D[3])
        self.last_D = q_D
        return _blend(a, b, q_D, plan, t - plan.start)

    def _needs_geometry(self, k: int) -> bool:
        return self.rows[k - 1].kind != INERTIAL or self.rows[k].kind != INERTIAL

    def _plan(self, t: float) -> Plan:
        """The slew into self.segment (module docstring), planned at t."""
        k, p = self.segment, self.p
        start, limits = self.rows[k].start, (p.rate_limit, p.accel_limit, p.jerk_limit)
        self.anchor_D = self.last_D = None
        if not self._needs_geometry(k):
            angle = _angle(qmul(_conjugate(self.rows[k - 1].q), self.rows[k].q))
            phases = slew.profile(angle, *limits)
            return self._checked(Plan(k, start, slew.duration(phases), angle, phases, t))
        now = self.now()

        def passes(margin: float, stretch: float = 1.0) -> Plan | None:
            plan = self._attempt(k, t, now, margin, stretch)
            return plan if plan is not None and self._meets_limits(plan, now) else None

        plan = passes(0.0)  # the full limits
        if plan is None and (margined := passes(1.0)) is not None:
            plan = _least(passes, 0.0, 1.0, margined)
        elif plan is None:  # the full limits, stretched
            stretch = 1.0
            while plan is None:
                stretch *= 2.0
                if stretch > 64.0:
                    raise ModelError(
                        f"t={t:.6g} s: no slew from segment {k} into segment {k + 1} meets "
                        "rate_limit and accel_limit: the frames turn too fast"
                    )
                plan = passes(0.0, stretch)
            plan = _least(lambda x: passes(0.0, x), stretch / 2.0, stretch, plan)
        return self._checked(plan)

    def _attempt(
        self, k: int, t: float, now: Geometry, margin: float, stretch: float
    ) -> Plan | None:
        """The slew into segment k under the limits reduced by ``margin`` times the frames'
        own motion and stretched by λ = ``stretch``: (ω − m ω_f)/λ, (α − m (α_f + ω ω_f))/λ²,
        j/λ³; the end time by fixed-point iteration (module docstring).  None where the
        reduced limits are not positive."""
        p, start = self.p, self.rows[k].start
        freeze = self.rows[k].kind == STARE and p.yaw_compensation
        duration, footprint = 0.0, None
        for _ in range(50):
            later = _predicted(now, start + duration - t)
            if freeze:
                footprint = self._freeze(self.rows[k], later)
            a0, b0 = self.frame(k - 1, now), self.frame(k, now, footprint)
            a1, b1 = self.frame(k - 1, later), self.frame(k, later, footprint)
            angle = max(
                _angle(qmul(_conjugate(a0[0]), b0[0])), _angle(qmul(_conjugate(a1[0]), b1[0]))
            )
            w_f = max(norm(f[1]) for f in (a0, b0, a1, b1))
            a_f = max(norm(f[2]) for f in (a0, b0, a1, b1))
            if not (w_f < p.rate_limit and a_f < p.accel_limit):
                raise ModelError(
                    f"t={t:.6g} s: segments {k} and {k + 1} turn at up to {w_f:.4g} rad/s, "
                    f"{a_f:.4g} rad/s2: no slew between them meets rate_limit "
                    f"{p.rate_limit:.4g} rad/s and accel_limit {p.accel_limit:.4g} rad/s2"
                )
            rate = p.rate_limit - margin * w_f
            accel = p.accel_limit - margin * (a_f + p.rate_limit * w_f)
            if not (rate > 0.0 and accel > 0.0):
                return None
            phases = slew.profile(
                angle, rate / stretch, accel / stretch**2, p.jerk_limit / stretch**3
            )
            previous, duration = duration, slew.duration(phases)
            if abs(duration - previous) <= 1e-9 * max(1.0, duration):
                break
        return Plan(k, start, duration, angle, phases, t, footprint)

    def _meets_limits(self, plan: Plan, now: Geometry) -> bool:
        """The planned reference within the limits at SAMPLES instants and the ends of the
        profile's phases (on the predicted geometry)."""
        p, k = self.p, plan.into
        anchor = (1.0, 0.0, 0.0, 0.0)
        boundaries = itertools.accumulate(phase[0] for phase in plan.phases)
        uniform = (plan.duration * i / (SAMPLES + 1) for i in range(1, SAMPLES + 1))
        for tau in sorted(set(boundaries) | set(uniform) if plan.duration > 0.0 else ()):
            later = _predicted(now, plan.start + tau - plan.planned_at)
            a, b = self.frame(k - 1, later), self.frame(k, later, plan.footprint)
            q_D = qmul(_conjugate(a[0]), b[0])
            if quat_dot(q_D, anchor) < 0.0:
                q_D = tuple(-x for x in q_D)
            anchor = q_D
            _, w, dw = _blend(a, b, q_D, plan, tau)
            if norm(w) > p.rate_limit * (1 + 1e-9) or norm(dw) > p.accel_limit * (1 + 1e-9):
                return False
        return True

    def _checked(self, plan: Plan) -> Plan:
        """The plan, if its slew ends before the next segment starts (a stare's footprint
        direction then frozen)."""
        k = plan.into
        if k + 1 < len(self.rows) and plan.end > self.rows[k + 1].start:
            raise ModelError(
                f"the slew into segment {k + 1} (from {plan.start:.6g} s, {plan.angle / DEG:.4g} "
                f"deg) ends at {plan.end:.6g} s, after segment {k + 2} starts at "
                f"{self.rows[k + 1].start:.6g} s: start segment {k + 2} later or raise the "
                "limits"
            )
        if plan.footprint is not None:
            self.footprint[k] = (plan.footprint, plan.end)
        return plan


def _blend(a, b, q_D, plan: Plan, tau: float) -> tuple:
    """The reference of ``plan`` at τ from its start (q_D = ±q_A* ⊗ q_B)."""
    L, dL, ddL = slew.relative(a, b, q_D)
    angle, rate, accel = slew.at(plan.phases, tau)
    return slew.blend(a, L, dL, ddL, angle / plan.angle, rate / plan.angle, accel / plan.angle)


def _predicted(now: Geometry, dt: float) -> Geometry:
    """The two-body geometry ``dt`` after ``now`` (the Earth turned by ω_E dt)."""
    r, v = two_body(now.r, now.v, dt)
    rows, w_O, dw_O = orbit_frame(r, v)
    (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = rows
    q_OI = quat_of_rows(c00, c01, c02, c10, c11, c12, c20, c21, c22)
    return Geometry(r, v, now.earth_angle + EARTH_RATE * dt, q_OI, w_O, dw_O)


def _least(passes, low: float, high: float, plan: Plan) -> Plan:
    """The plan of the least x in (low, high] (to 1e-3) for which ``passes(x)`` gives one,
    by bisection (None at low; ``plan`` at high)."""
    while high - low > 1e-3 * max(1.0, low):
        middle = 0.5 * (low + high)
        candidate = passes(middle)
        if candidate is None:
            low = middle
        else:
            high, plan = middle, candidate
    return plan


def _due(start: float) -> float:
    return start - START_TOLERANCE * max(1.0, abs(start))


def _unit(q, name: str) -> tuple:
    q = tuple(float(x) for x in q)
    size = math.sqrt(sum(x * x for x in q))
    if not abs(size - 1.0) < 1e-6:
        raise ModelError(f"{name} must be a unit quaternion, got {list(q)}")
    return tuple(x / size for x in q)


def _conjugate(q) -> tuple:
    return (q[0], -q[1], -q[2], -q[3])


def _angle(q) -> float:
    """The rotation angle of q, the short way (0 to π)."""
    return 2.0 * math.atan2(math.sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]), abs(q[0]))
