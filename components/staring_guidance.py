"""Staring guidance with yaw compensation: the video-SAR paper ([Liang 2019],
§2.2–2.4, eqs 6–13), made exact.

Line of sight (I axes; r, v satellite, r_T, v_T target, all inputs)::

    ρ = r_T − r,  s = |ρ| (slant_range),  û = ρ / s
    ρ̇ = v_T − v,  ρ̈ = ω_E ẑ × v_T + μ r / |r|³     (Earth-fixed target; two-body satellite)
    ṡ = ρ̇·û,  u̇ = (ρ̇ − ṡ û)/s,  s̈ = ρ̈·û + ρ̇·u̇,  ü = (ρ̈ − s̈ û − 2 ṡ u̇)/s

Pointing frames.  Every reference frame here is F(û, a) for a unit "reference direction"
a not parallel to û::

    z = û,  y = n/|n| with n = û × a,  x = y × z        (x = normalised a − (a·û)û)

so that z is on the target and x lies in the plane of û and a.  Its angular velocity in
its own axes (from ė_i = ω × e_i; exact, no finite difference)::

    ω = (−y·u̇,  x·u̇,  −(ṅ·x)/|n|),   ṅ = u̇ × a + û × ȧ

- Yaw 0 (eqs 10–11): a = x_O, the orbit frame's x axis from q_OI.  F(û, x_O) is the
  1-2-3 attitude (φ, θ, 0) relative to O with, for û_O = C_OI û = (x, y, z),
  ``φ = −atan2(y, z), θ = asin x`` — eq (11) (atan2 = the paper's arctan since z > 0
  for any target below the satellite's local horizontal); indeed eq (10) gives
  C_BOᵀ ẑ = (sθ, −sφ cθ, cφ cθ), and its body y axis R1(φ)ᵀ ŷ ⊥ x_O makes y = û × x_O/|…|.
  ȧ, ä follow from the two-body orbit frame, w_OI = (|h|/r²) ĥ, h = r × v::
  ẋ_O = −(|h|/r²) r̂,  ẍ_O = (2|h| ṙ/r³) r̂ − (|h|²/r⁴) x_O,  ṙ = v·r̂.
  The J2 precession of the orbit normal (w_OI gains r a_h/|h| r̂ ≈ 1e-6 rad/s, see
  :mod:`.orbit`) is neglected here only (w_ref errs by ≈ 3e-7 rad/s at 567 km); the
  frame's orientation uses q_OI as given.  Eq (13) is the same rate in Euler form:
  w_ref = w_RO + C_RO w_OI_O with w_RO = eq (13) of (φ̇, θ̇, ψ̇).
- Yaw compensation (eq 12): the footprint direction is the ground line in which the plane
  of û and the body footprint axis meets the target's tangent plane,
  ``d = û (x·up) − x (û·up)`` (in the tangent plane, along x).  At the first communication
  point t_cap ≥ reference_time (− 1e-9 s relative) at which the outputs are evaluated,
  the yaw-0 frame's d is captured as the unit vector g, fixed in the Earth-fixed frame E
  ("若偏航角为0": yaw 0 at t_ref; re-evaluating at t_cap recaptures, so repeated output
  calls at one time agree; a start after reference_time captures at the start).  Later
  g(t) in I is g(t_cap) turned by ω_E (t − t_cap) about ẑ, ġ = ω_E ẑ × g, and the reference is
  F(û, g): x_R = normalize(g − (g·û)û), eq (12) solved in the projection sense (the body
  x axis is the direction in which the frozen ground vector is seen).  Then the ground line
  of the frame is g(t) itself: the footprint does not rotate relative to the ground.  The
  yaw angle is ψ = atan2(x_R·y_P0, x_R·x_P0) (P0 = the yaw-0 frame), 0 at t_cap, so the
  attitude is continuous there; the yaw *rate* steps from 0 to ψ̇(t_cap) (the paper's law
  has this step; a stare should start at reference_time).  Before t_cap, and always with
  ``yaw_compensation`` false, the reference is the yaw-0 frame.
- Tangent plane ("up") at the target: the WGS-84 ellipsoid normal at the target's
  geodetic latitude, found from r_T_I by the fixed-point iteration
  tan φ = (z + e² N sin φ)/p, exact for any target_alt (the normal of the foot point);
  the ellipsoid is symmetric about ẑ, so no Earth angle is needed.  east = ẑ × up
  normalised, north = up × east; azimuth = atan2(d·east, d·north), from north toward east
  (clockwise seen from above).  Any Earth-fixed normal would do for the compensation
  itself: g is frozen in the same tangent plane that measures it.

Outputs.  ``footprint_rotation`` = azimuth of the reference's ground line minus its value
at t_cap, wrapped to [−π, π) (0 before t_cap): rounding-level with compensation, the drift
without.  :func:`footprint_azimuth` applies the same definition to any attitude (e.g. the
achieved q_BI) with the plane of the *body* boresight and footprint axis (the beam plane;
for the reference, whose boresight is on û, the same plane).  ``look_angle`` =
atan2(|û × r̂|, −û·r̂), the off-nadir angle from the geocentric nadir −r̂ (= z_O).
``euler_ref_BO`` = (φ, θ, ψ) above, each unwrapped to the previous communication point.
``q_ref`` = q_RI, sign kept continuous between communication points.

Boresight other than +z: the body carries the frame P = F(û, ·) above through the fixed
mount C_RP = [a_B, b × a_B, b] (columns; b = boresight_B normalised, a_B = the footprint
axis = body x made perpendicular to b, or body y if b is within 1e-6 rad of ±x).  Then
C_RI = C_RP C_PI, C(q_ref)ᵀ b = û, w_ref = C_RP ω_P, and "yaw 0" is that of P (the Euler
output, from q_ref relative to O, then has a yaw of R ≠ 0).  For b = +z, R = P.

Extension (not in DESIGN.md §3): ``dw_ref`` = d/dt of w_ref (= ω̇ in R axes), analytic::

    ω̇ = (−ẏ·u̇ − y·ü,  ẋ·u̇ + x·ü,  −(n̈·x + ṅ·ẋ)/|n| + (ṅ·x)(ṅ·y)/|n|²),
    ė = ω × e,  n̈ = ü × a + 2 u̇ × ȧ + û × ä,   g̈ = ω_E ẑ × ġ

It is the exact derivative of w_ref along a two-body satellite orbit and an Earth-fixed
target; the unmodelled J2 acceleration (≈ 0.01 m/s² at 567 km) enters through ρ̈/s and
errs by ≈ 2e-8 rad/s², 3e-4 of the peak 7.7e-5 rad/s² of the video-SAR stare
(tests/test_staring.py measures it).

Assumptions: target fixed on the Earth, which turns at ω_E = EARTH_RATE about ẑ_I (the
I and E z axes coincide; :mod:`.orbit`; with an epoch the orbit model turns the Earth at
the GMST rate, 8.6e-12 rad/s faster: 2e-9 rad over a 200-s stare, neglected); μ = MU_EARTH;
q_OI must be the orbit frame built from r_I, v_I (checked to 1e-6 rad); the state (captured
g, anchors of the angle branches) lives in plain attributes, so :meth:`Model.get_state` covers it.
"""

from __future__ import annotations

import math

import numpy as np

from .model import Model, ModelError
from .orbit_environment import EARTH_RATE, MU_EARTH, WGS84_A, WGS84_E2
from .rotations import cross, dcm_from_quat, euler123_from_quat, quat_from_dcm, unwrap_near, wrap_pi
from .variables import input_, output, parameter

CAPTURE_TOLERANCE = 1e-9  # s per s of max(1, |reference_time|): "t >= reference_time"
Q_OI_TOLERANCE = 1e-6  # rad (max element of C_OI error): q_OI vs r_I, v_I
PARALLEL_TOLERANCE = 1e-6  # rad: LOS against a reference direction, boresight against x
MIN_SLANT_RANGE = 1e-3  # m
_INPUTS = ("r_I", "v_I", "r_T_I", "v_T_I", "q_OI")
# Start values of the inputs: a consistent geometry (circular 567-km orbit over the
# equator, the target below it at longitude 0, seen at nadir), so that the FMU can be
# evaluated at its start values in Initialization Mode, before a master sets the inputs.
_START_R = (WGS84_A + 567e3, 0.0, 0.0)
_START_V = (0.0, math.sqrt(MU_EARTH / _START_R[0]), 0.0)
_START_T = (WGS84_A, 0.0, 0.0)
_START_VT = (0.0, EARTH_RATE * WGS84_A, 0.0)
_START_Q_OI = tuple(
    quat_from_dcm(((0.0, 1.0, 0.0), (0.0, 0.0, -1.0), (-1.0, 0.0, 0.0))).tolist()
)  # rows x_O, y_O, z_O
_GEOMETRY = ("r_I", "r_T_I")
_Z = np.array([0.0, 0.0, 1.0])


def _norm(v) -> float:
    return math.sqrt(float(v @ v))


def _orbit_axes(r, v, C_OI, t):
    """(|r|, |h|, r̂, x_O) of the two-body orbit frame of r, v; ModelError if r, v do not
    define one or q_OI (as C_OI) is not it (to Q_OI_TOLERANCE)."""
    r_norm = _norm(r)
    h_vec = cross(r, v)
    h = _norm(h_vec)
    if not h > 1e-12 * r_norm * max(_norm(v), 1.0):
        raise ModelError(
            f"t={t:.6g} s: r_I and v_I are parallel or zero: the orbit frame is undefined"
        )
    r_hat, h_hat = r / r_norm, h_vec / h
    mismatch = float(np.max(np.abs(C_OI - (cross(h_hat, r_hat), -h_hat, -r_hat))))
    if mismatch > Q_OI_TOLERANCE:
        raise ModelError(
            f"t={t:.6g} s: q_OI does not match the orbit frame of r_I, v_I "
            f"(z = -r/|r|, y = -(r x v)/|r x v|) by {mismatch:.3g} > "
            f"{Q_OI_TOLERANCE:g}: connect q_OI from the same orbit as r_I"
        )
    return r_norm, h, r_hat, C_OI[0]


def footprint_axis(boresight_B) -> np.ndarray:
    """Unit body axis ⊥ the boresight whose ground line is the footprint direction: body x
    made perpendicular to the boresight (body y if the boresight is along ±x)."""
    b = np.asarray(boresight_B, dtype=float)
    norm = _norm(b) if np.all(np.isfinite(b)) else 0.0
    if not norm > 0.0:
        raise ModelError(f"boresight_B must be a finite non-zero vector, got {b.tolist()}")
    b = b / norm
    for axis in np.eye(3)[:2]:
        a = axis - (axis @ b) * b
        if _norm(a) > PARALLEL_TOLERANCE:
            return a / _norm(a)
    raise AssertionError("unreachable: b cannot be along both x and y")


def _polar_distance(r_T) -> tuple[float, float, float, float]:
    """(x, y, z, p = distance from the polar axis); ModelError at a pole."""
    x, y, z = (float(c) for c in r_T)
    p = math.hypot(x, y)
    if not p > 1e-9 * max(1.0, abs(z)):
        raise ModelError(
            f"r_T_I = {[x, y, z]} is on the Earth's axis: north (hence the "
            "footprint azimuth) is undefined at a pole"
        )
    return x, y, z, p


def geodetic_latitude(r_T) -> float:
    """WGS-84 geodetic latitude of a point (I or E axes), by the fixed-point iteration
    tan φ = (z + e² N sin φ)/p (~4 iterations near the ground)."""
    _, _, z, p = _polar_distance(r_T)
    lat = math.atan2(z, p * (1.0 - WGS84_E2))
    for _ in range(20):
        s = math.sin(lat)
        lat, previous = (
            math.atan2(z + WGS84_E2 * WGS84_A * s / math.sqrt(1.0 - WGS84_E2 * s * s), p),
            lat,
        )
        if abs(lat - previous) <= 1e-15:
            break
    return lat


def local_tangent_frame(
    r_T, latitude: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(up, east, north) unit vectors at a point, in the axes of r_T (I or E: both share
    the polar axis ẑ).  up = WGS-84 ellipsoid normal at the geodetic latitude (computed
    unless given: an Earth-fixed point keeps it)."""
    x, y, _, p = _polar_distance(r_T)
    lat = geodetic_latitude(r_T) if latitude is None else latitude
    cl, sl, cx, sx = math.cos(lat), math.sin(lat), x / p, y / p
    return (
        np.array([cl * cx, cl * sx, sl]),
        np.array([-sx, cx, 0.0]),
        np.array([-sl * cx, -sl * sx, cl]),
    )


def ground_line(beam, axis, up) -> np.ndarray:
    """Direction of the line in which the plane of ``beam`` and ``axis`` meets the plane
    ⊥ ``up``, oriented along ``axis``: d = beam (axis·up) − axis (beam·up) (not normalised)."""
    return beam * float(axis @ up) - axis * float(beam @ up)


def _azimuth(d, east, north) -> float:
    if not _norm(d) > 1e-12:
        raise ModelError(
            "the footprint plane is parallel to the target's tangent plane "
            "(grazing view): footprint direction undefined"
        )
    return math.atan2(float(d @ east), float(d @ north))


def footprint_azimuth(q_BI, r_T_I, boresight_B=(0.0, 0.0, 1.0)) -> float:
    """Azimuth (rad, from local north toward east, in (−π, π]) of the footprint direction
    of attitude q_BI at the target r_T_I: the ground line of the plane of the body
    boresight and :func:`footprint_axis`, in the target's WGS-84 tangent plane."""
    b = np.asarray(boresight_B, dtype=float)
    a_B = footprint_axis(b)
    q = np.asarray(q_BI, dtype=float)
    C_BI = dcm_from_quat(q / _norm(q))
    up, east, north = local_tangent_frame(r_T_I)
    return _azimuth(ground_line(C_BI.T @ (b / _norm(b)), C_BI.T @ a_B, up), east, north)


def _line_of_sight(r, v, r_T, v_T, t):
    """(s, û, u̇, ü) in I: Earth-fixed target, two-body satellite (module docstring)."""
    rho, drho = r_T - r, v_T - v
    s = _norm(rho)
    if not s > MIN_SLANT_RANGE:
        raise ModelError(
            f"t={t:.6g} s: zero-length line of sight: r_T_I - r_I has length {s:.3g} m"
        )
    ddrho = EARTH_RATE * cross(_Z, v_T) + (MU_EARTH / _norm(r) ** 3) * r
    u = rho / s
    ds = float(drho @ u)
    du = (drho - ds * u) / s
    dds = float(ddrho @ u) + float(drho @ du)
    return s, u, du, (ddrho - dds * u - 2.0 * ds * du) / s


def _aligned_axes(u, a, what: str):
    """Axes x, y of F(û, a) in I, n = û × a and |n| (module docstring)."""
    n = cross(u, a)
    m = _norm(n)
    if not m > PARALLEL_TOLERANCE:
        raise ModelError(
            f"the line of sight (r_T_I - r_I) is parallel to {what}: the "
            "reference frame is undefined"
        )
    y = n / m
    return cross(y, u), y, n, m


def _aligned_frame(u, du, ddu, a, da, dda, what: str):
    """F(û, a): axes (x, y, z) in I as rows, ω and ω̇ in its own axes (module docstring)."""
    x, y, n, m = _aligned_axes(u, a, what)
    dn = cross(du, a) + cross(u, da)
    ddn = cross(ddu, a) + 2.0 * cross(du, da) + cross(u, dda)
    dnx = float(dn @ x)
    w = np.array([-float(y @ du), float(x @ du), -dnx / m])
    w_I = w[0] * x + w[1] * y + w[2] * u
    dx, dy = cross(w_I, x), cross(w_I, y)
    dw = np.array(
        [
            -float(dy @ du) - float(y @ ddu),
            float(dx @ du) + float(x @ ddu),
            -(float(ddn @ x) + float(dn @ dx)) / m + dnx * float(dn @ y) / (m * m),
        ]
    )
    return np.array([x, y, u]), w, dw


class StaringGuidance(Model):
    """Reference attitude staring at a ground target, with yaw compensation ([Liang 2019])."""

    VARIABLES = (
        parameter(
            "yaw_compensation",
            True,
            "1",
            "true: hold the footprint direction fixed "
            "on the ground from reference_time on (eq 12); false: yaw 0 (eqs 10-11)",
            type="Boolean",
        ),
        parameter(
            "boresight_B",
            (0.0, 0.0, 1.0),
            "1",
            "antenna boresight (beam centre) in B, normalised by the model",
            shape=(3,),
        ),
        parameter(
            "reference_time",
            0.0,
            "s",
            "t_ref: the footprint direction of the yaw-0 "
            "attitude is frozen on the ground at the first communication point >= it",
        ),
        input_("r_I", "m", "satellite position in I", _START_R, shape=(3,)),
        input_("v_I", "m/s", "satellite velocity in I", _START_V, shape=(3,)),
        input_("r_T_I", "m", "ground target position in I", _START_T, shape=(3,)),
        input_("v_T_I", "m/s", "ground target velocity in I", _START_VT, shape=(3,)),
        input_(
            "q_OI",
            "1",
            "attitude of the orbit frame O relative to I (must match r_I, v_I)",
            _START_Q_OI,
            shape=(4,),
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
            "time derivative of w_ref (angular acceleration of R "
            "relative to I, in R axes; extension for feedforward)",
            shape=(3,),
            depends=_INPUTS,
            display_unit="deg/s2",
        ),
        output(
            "euler_ref_BO",
            "rad",
            "1-2-3 Euler angles (roll, pitch, yaw) of R relative to O, continuous branch",
            shape=(3,),
            depends=_INPUTS,
            display_unit="deg",
        ),
        output(
            "look_angle",
            "rad",
            "off-nadir angle of the line of sight at the satellite "
            "(from the geocentric nadir -r_I)",
            depends=_GEOMETRY,
            display_unit="deg",
        ),
        output(
            "slant_range",
            "m",
            "distance satellite to target |r_T_I - r_I|",
            depends=_GEOMETRY,
            display_unit="km",
        ),
        output(
            "footprint_rotation",
            "rad",
            "azimuth of R's footprint direction on the "
            "target's tangent plane minus its value at the capture time (0 before)",
            depends=_INPUTS,
            display_unit="deg",
        ),
    )

    def initialize(self, t0):
        p = self.p
        if not math.isfinite(p.reference_time):
            raise ModelError(f"reference_time must be finite, got {p.reference_time}")
        b = np.array(p.boresight_B)
        a_B = footprint_axis(b)
        b = b / _norm(b)
        C_RP = np.column_stack((a_B, cross(b, a_B), b))
        self.C_RP = None if np.array_equal(C_RP, np.eye(3)) else C_RP  # None: R = P
        self.compensate = p.yaw_compensation
        self.tolerance = CAPTURE_TOLERANCE * max(1.0, abs(p.reference_time))
        self.capture_time = None  # t_cap, then the captured g (I, at t_cap)
        self.g_ref_I = None  # and the footprint azimuth at t_cap
        self.azimuth_ref = 0.0
        self.latitude = None  # the target's geodetic latitude, fixed at t_cap
        self.anchor = self.last = None  # (q_ref, euler) at the previous / last point
        inputs = self.layout.range["input"]
        self._inputs = slice(inputs.start, inputs.stop)
        self.t = t0

    def step(self, t, dt):
        self.anchor = self.last  # outputs at t are the branch anchors for t + dt
        self.t = t + dt

    def output(self):
        y, t = self.y, self.t
        r, v, r_T, v_T, C_OI = self._checked_inputs(t)
        r_norm, h, r_hat, x_O = _orbit_axes(r, v, C_OI, t)
        s, u, du, ddu = _line_of_sight(r, v, r_T, v_T, t)
        compensating, (x0, y0), (C_PI, w_P, dw_P) = self._pointing_frame(
            t, r_T, u, du, ddu, (r_norm, h, r_hat, x_O), float(v @ r_hat)
        )
        C_RI, w, dw = C_PI, w_P, dw_P
        if self.C_RP is not None:
            C_RI, w, dw = self.C_RP @ C_PI, self.C_RP @ w_P, self.C_RP @ dw_P
        q, euler = self._attitude(C_RI, C_PI, C_OI, u, x0, y0, compensating)
        rotation = 0.0
        if self.capture_time is not None:
            up, east, north = local_tangent_frame(r_T, self.latitude)
            rotation = wrap_pi(
                _azimuth(ground_line(u, C_PI[0], up), east, north) - self.azimuth_ref
            )
        y.q_ref[:] = q
        y.w_ref[:] = w
        y.dw_ref[:] = dw
        y.euler_ref_BO[:] = euler
        y.look_angle = math.atan2(_norm(cross(u, r_hat)), -float(u @ r_hat))
        y.slant_range = s
        y.footprint_rotation = rotation
        self.last = (q, euler)

    # -- internals -----------------------------------------------------------------
    def _checked_inputs(self, t):
        """(r, v, r_T, v_T, C_OI); ModelError if an input is not finite."""
        u_in = self.u
        if not np.all(np.isfinite(self.values[self._inputs])):
            bad = [name for name in _INPUTS if not np.all(np.isfinite(getattr(u_in, name)))]
            raise ModelError(f"t={t:.6g} s: inputs {bad} are not finite")
        r, v, r_T, v_T = (np.array(getattr(u_in, n)) for n in _INPUTS[:4])
        return r, v, r_T, v_T, dcm_from_quat(u_in.q_OI)

    def _pointing_frame(self, t, r_T, u, du, ddu, orbit, r_dot):
        """(compensating, (x0, y0) axes of the yaw-0 frame P0, (C_PI, ω_P, ω̇_P)): P0 =
        F(û, x_O), or with yaw compensation F(û, g) after the capture (made here at t_cap)."""
        r_norm, h, r_hat, x_O = orbit
        capturing = (
            self.capture_time is None and t >= self.p.reference_time - self.tolerance
        ) or self.capture_time == t  # capture, or recapture at t_cap
        compensating = self.compensate and (capturing or self.capture_time is not None)
        what = "the orbit frame's x axis (pitch +-90 deg)"
        y0 = None
        if compensating:  # only the axes of the yaw-0 frame P0
            x0, y0, _, _ = _aligned_axes(u, x_O, what)
        else:  # P0 = F(û, x_O) is the reference
            dx_O = -(h / r_norm**2) * r_hat
            ddx_O = (2.0 * h * r_dot / r_norm**3) * r_hat - (h / r_norm**2) ** 2 * x_O
            P = _aligned_frame(u, du, ddu, x_O, dx_O, ddx_O, what)
            x0 = P[0][0]
        if capturing:
            self.latitude = geodetic_latitude(r_T)
            up, east, north = local_tangent_frame(r_T, self.latitude)
            d = ground_line(u, x0, up)
            self.azimuth_ref = _azimuth(d, east, north)
            self.capture_time, self.g_ref_I = t, tuple((d / _norm(d)).tolist())
        if compensating:
            angle = EARTH_RATE * (t - self.capture_time)
            c, sn = math.cos(angle), math.sin(angle)
            gx, gy, gz = self.g_ref_I
            g = np.array([c * gx - sn * gy, sn * gx + c * gy, gz])
            dg = EARTH_RATE * cross(_Z, g)
            P = _aligned_frame(
                u,
                du,
                ddu,
                g,
                dg,
                EARTH_RATE * cross(_Z, dg),
                "the captured footprint direction g (grazing view)",
            )
        return compensating, (x0, y0), P

    def _attitude(self, C_RI, C_PI, C_OI, u, x0, y0, compensating):
        """(q_RI with its sign continued, 1-2-3 angles of R relative to O on the branch of
        the previous communication point)."""
        q = quat_from_dcm(C_RI)
        anchor_q, anchor_euler = self.anchor if self.anchor is not None else (None, None)
        if anchor_q is not None and float(q @ anchor_q) < 0.0:
            q = -q
        if self.C_RP is None:  # eq (11) and the yaw of eq (12), continued from the anchor
            x, y_, z = (C_OI @ u).tolist()
            psi = math.atan2(float(C_PI[0] @ y0), float(C_PI[0] @ x0)) if compensating else 0.0
            euler = (-math.atan2(y_, z), math.asin(min(1.0, max(-1.0, x))), psi)
            euler = np.array(euler if anchor_euler is None else unwrap_near(euler, anchor_euler))
        else:
            euler = euler123_from_quat(quat_from_dcm(C_RI @ C_OI.T), anchor_euler)
        return q, euler
