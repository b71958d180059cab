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
q_OI must be the orbit frame built from r_I, v_I (checked to 1e-6 rad).

``step`` and ``output`` are each one kernel (components/runtime/jit.py) on the value array and the
state array ``STATE`` (the mount, the captured g, the anchors of the angle branches), on
tuples of floats; the sums of products are taken in the order written (the NumPy version
before them summed the dot products as the CPU's BLAS kernel does, with fused
multiply-adds on some CPUs and not on others).
"""

from __future__ import annotations

import math

import numpy as np

from .model import Model, ModelError
from .orbit_environment import EARTH_RATE, MU_EARTH, WGS84_A, WGS84_E2
from .rotations import _unwrap3, dcm, euler123, quat_from_dcm, quat_of_rows, wrap_pi
from .runtime.flat import hypot, state_table
from .runtime.jit import expect_rows, floats, jitable, kernel, output_kernel, step_kernel
from .variables import input_, output, parameter
from .vectors import (
    add,
    combine,
    cross,
    divide,
    dot,
    matmul,
    norm,
    quat_dot,
    rotate,
    rotate_back,
    scale,
    sub,
)

CAPTURE_TOLERANCE = 1e-9  # s per s of max(1, |reference_time|): "t >= reference_time"
Q_OI_TOLERANCE = 1e-6  # rad (max element of C_OI error): q_OI vs r_I, v_I
PARALLEL_TOLERANCE = 1e-6  # rad: LOS against a reference direction, boresight against x
MIN_SLANT_RANGE = 1e-3  # m
_INPUTS = ("r_I", "v_I", "r_T_I", "v_T_I", "q_OI")
# Start values of the inputs: a consistent geometry (circular 567-km orbit over the
# equator, the target below it at longitude 0, seen at nadir), so that the FMU can be
# evaluated at its start values in Initialization Mode, before a master sets the inputs.
START_R = (WGS84_A + 567e3, 0.0, 0.0)
START_V = (0.0, math.sqrt(MU_EARTH / START_R[0]), 0.0)
START_T = (WGS84_A, 0.0, 0.0)
START_VT = (0.0, EARTH_RATE * WGS84_A, 0.0)
START_Q_OI = tuple(
    quat_from_dcm(((0.0, 1.0, 0.0), (0.0, 0.0, -1.0), (-1.0, 0.0, 0.0))).tolist()
)  # rows x_O, y_O, z_O
_GEOMETRY = ("r_I", "r_T_I")
_Z = (0.0, 0.0, 1.0)

#: the kernels' statuses: done, and each condition the model cannot continue from
#: (StaringGuidance.output raises its ModelError)
(
    OK, NOT_FINITE, NO_ORBIT_FRAME, Q_OI_MISMATCH, NO_LINE_OF_SIGHT, ALONG_X_O, ALONG_G, AT_POLE,
    GRAZING,
) = range(9)  # fmt: skip


# -- geometry (module docstring) -----------------------------------------------------------
def footprint_axis(boresight_B) -> np.ndarray:
    """Unit body axis ⊥ the boresight whose ground line is the footprint direction: body x
    made perpendicular to the boresight (body y if the boresight is along ±x)."""
    b = np.asarray(boresight_B, dtype=float)
    norm = math.sqrt(float(b @ b)) if np.all(np.isfinite(b)) else 0.0
    if not norm > 0.0:
        raise ModelError(f"boresight_B must be a finite non-zero vector, got {b.tolist()}")
    b = b / norm
    for axis in np.eye(3)[:2]:
        a = axis - (axis @ b) * b
        if math.sqrt(float(a @ a)) > PARALLEL_TOLERANCE:
            return a / math.sqrt(float(a @ a))
    raise AssertionError("unreachable: b cannot be along both x and y")


@jitable
def geodetic_latitude(r_T) -> tuple:
    """(off the polar axis, WGS-84 geodetic latitude) of a point (I or E axes), by the
    fixed-point iteration tan φ = (z + e² N sin φ)/p (~4 iterations near the ground)."""
    x, y, z = r_T
    p = hypot(x, y)
    if not p > 1e-9 * max(1.0, abs(z)):
        return False, 0.0
    lat = math.atan2(z, p * (1.0 - WGS84_E2))
    for _ in range(20):
        s = math.sin(lat)
        previous = lat
        lat = math.atan2(z + WGS84_E2 * WGS84_A * s / math.sqrt(1.0 - WGS84_E2 * s * s), p)
        if abs(lat - previous) <= 1e-15:
            break
    return True, lat


@jitable
def tangent_frame(r_T, latitude: float) -> tuple:
    """(up, east, north) unit vectors at a point off the polar axis, in the axes of r_T (I
    or E: both share the polar axis ẑ); up = the WGS-84 ellipsoid normal at ``latitude``."""
    x, y, _ = r_T
    p = hypot(x, y)
    cl, sl, cx, sx = math.cos(latitude), math.sin(latitude), x / p, y / p
    return (cl * cx, cl * sx, sl), (-sx, cx, 0.0), (-sl * cx, -sl * sx, cl)


def _at_pole(r_T) -> str:
    return (
        f"r_T_I = {list(r_T)} is on the Earth's axis: north (hence the "
        "footprint azimuth) is undefined at a pole"
    )


@jitable
def ground_line(beam, axis, up) -> tuple:
    """Direction of the line in which the plane of ``beam`` and ``axis`` meets the plane
    ⊥ ``up``, oriented along ``axis``: d = beam (axis·up) − axis (beam·up) (not normalised)."""
    return combine(dot(axis, up), beam, -dot(beam, up), axis)


@jitable
def _azimuth(d, east, north) -> tuple:
    """(defined, azimuth of d from north toward east): undefined for a vertical d."""
    if not norm(d) > 1e-12:
        return False, 0.0
    return True, math.atan2(dot(d, east), dot(d, north))


def footprint_azimuth(q_BI, r_T_I, boresight_B=(0.0, 0.0, 1.0)) -> float:
    """Azimuth (rad, from local north toward east, in (−π, π]) of the footprint direction
    of attitude q_BI at the target r_T_I: the ground line of the plane of the body
    boresight and :func:`footprint_axis`, in the target's WGS-84 tangent plane."""
    return float(footprint_azimuths([q_BI], [r_T_I], boresight_B)[0])


def footprint_azimuths(q_BI, r_T_I, boresight_B=(0.0, 0.0, 1.0)) -> np.ndarray:
    """:func:`footprint_azimuth` of each row of q_BI (N, 4) and r_T_I (N, 3), in one
    kernel call (a run's history: the kernel runs compiled where that pays,
    components/runtime/jit.py); ModelError at the first row where it is undefined."""
    b = np.asarray(boresight_B, dtype=float)
    a_B = tuple(footprint_axis(b).tolist())
    beam_B = tuple((b / math.sqrt(float(b @ b))).tolist())
    q = np.array(q_BI, dtype=float, ndmin=2)
    # each row's norm from its dot product with itself as ``row @ row`` takes it (the same
    # BLAS dot, with fused multiply-adds on some CPUs): the rows footprint_azimuth always
    # normalised, bit for bit
    q_unit = q / np.sqrt(np.matmul(q[:, np.newaxis, :], q[:, :, np.newaxis]))[:, 0]
    r_T = np.array(r_T_I, dtype=float, ndmin=2)
    azimuth = np.empty(len(q))
    expect_rows(_footprint_azimuths, len(q))
    failed = _footprint_azimuths(q_unit, r_T, beam_B, a_B, azimuth)
    if failed >= 0:
        row = tuple(r_T[failed].tolist())
        raise ModelError(_at_pole(row) if not geodetic_latitude(row)[0] else _GRAZING)
    return azimuth


@kernel
def _footprint_azimuths(q_BI, r_T_I, beam_B, axis_B, azimuth) -> int:
    """The footprint azimuth of each row (unit q_BI, the unit body boresight beam_B and
    its footprint axis axis_B) into ``azimuth``; the first row where it is undefined (at a
    pole, or the ground line vertical), or −1."""
    q, r = floats(q_BI), floats(r_T_I)
    for k in range(len(azimuth)):
        r_T = (r[k][0], r[k][1], r[k][2])
        ok, latitude = geodetic_latitude(r_T)
        if not ok:
            return k
        up, east, north = tangent_frame(r_T, latitude)
        C_BI = dcm(q[k])
        beam, axis = rotate_back(C_BI, beam_B), rotate_back(C_BI, axis_B)
        ok, azimuth[k] = _azimuth(ground_line(beam, axis, up), east, north)
        if not ok:
            return k
    return -1


@jitable
def line_of_sight(r, v, r_T, v_T, s: float) -> tuple:
    """(û, u̇, ü) in I for the slant range s = |r_T − r| > 0: Earth-fixed target,
    two-body satellite (module docstring)."""
    rho, drho = sub(r_T, r), sub(v_T, v)
    r_norm = norm(r)
    ddrho = combine(EARTH_RATE, cross(_Z, v_T), MU_EARTH / (r_norm * r_norm * r_norm), r)
    u = divide(rho, s)
    ds = dot(drho, u)
    du = divide(combine(1.0, drho, -ds, u), s)
    dds = dot(ddrho, u) + dot(drho, du)
    ddu = (
        (ddrho[0] - dds * u[0] - 2.0 * ds * du[0]) / s,
        (ddrho[1] - dds * u[1] - 2.0 * ds * du[1]) / s,
        (ddrho[2] - dds * u[2] - 2.0 * ds * du[2]) / s,
    )
    return u, du, ddu


@jitable
def aligned_axes(u, a) -> tuple:
    """(defined, x, y, n = û × a, |n|) of F(û, a) (module docstring); undefined for a
    reference direction within PARALLEL_TOLERANCE of û."""
    n = cross(u, a)
    m = norm(n)
    if not m > PARALLEL_TOLERANCE:
        return False, n, n, n, m
    y = divide(n, m)
    return True, cross(y, u), y, n, m


@jitable
def aligned_frame(u, du, ddu, a, da, dda) -> tuple:
    """(defined, F(û, a) as rows (x, y, z), ω and ω̇ in its own axes) (module docstring)."""
    ok, x, y, n, m = aligned_axes(u, a)
    if not ok:
        return False, (n, n, n), n, n
    dn = add(cross(du, a), cross(u, da))
    ddn = add(add(cross(ddu, a), scale(2.0, cross(du, da))), cross(u, dda))
    dnx = dot(dn, x)
    w = (-dot(y, du), dot(x, du), -dnx / m)
    w_I = add(combine(w[0], x, w[1], y), scale(w[2], u))
    dx, dy = cross(w_I, x), cross(w_I, y)
    dw = (
        -dot(dy, du) - dot(y, ddu),
        dot(dx, du) + dot(x, ddu),
        -(dot(ddn, x) + dot(dn, dx)) / m + dnx * dot(dn, y) / (m * m),
    )
    return ok, (x, y, u), w, dw


@jitable
def orbit_axes(r, vel) -> tuple:
    """(defined, the two-body orbit frame's axes (x_O, y_O, z_O) in I, |r|, r̂, |h|) of r,
    v (DESIGN.md §2: z = −r̂, y = −ĥ, x = ĥ × r̂); undefined for r ∥ v or zero."""
    r_norm = norm(r)
    h_vec = cross(r, vel)
    h = norm(h_vec)
    if not h > 1e-12 * r_norm * max(norm(vel), 1.0):
        return False, (r, r, r), r_norm, r, h
    r_hat, h_hat = divide(r, r_norm), divide(h_vec, h)
    return True, (cross(h_hat, r_hat), scale(-1.0, h_hat), scale(-1.0, r_hat)), r_norm, r_hat, h


@jitable
def mismatch(C, D) -> float:
    """The largest |C_ij − D_ij| of two 3×3 matrices (rows)."""
    largest = 0.0
    for i in range(3):
        for j in range(3):
            largest = max(largest, abs(C[i][j] - D[i][j]))
    return largest


@jitable
def x_axis_rates(x_O, r_hat, r_norm: float, h: float, vel) -> tuple:
    """(ẋ_O, ẍ_O) of the orbit frame's x axis along the two-body orbit (module docstring):
    ẋ_O = −(|h|/r²) r̂,  ẍ_O = (2|h| ṙ/r³) r̂ − (|h|²/r⁴) x_O."""
    r2 = r_norm * r_norm
    dx_O = scale(-(h / r2), r_hat)
    ddx_O = combine(2.0 * h * dot(vel, r_hat) / (r2 * r_norm), r_hat, -((h / r2) * (h / r2)), x_O)
    return dx_O, ddx_O


@jitable
def ground_fixed(g, angle: float) -> tuple:
    """(g turned by ``angle`` about ẑ, its first and second derivatives as the Earth turns
    it at ω_E): an Earth-fixed direction or point seen in I (g in E and the Earth angle)."""
    c, sn = math.cos(angle), math.sin(angle)
    turned = (c * g[0] - sn * g[1], sn * g[0] + c * g[1], g[2])
    rate = scale(EARTH_RATE, cross(_Z, turned))
    return turned, rate, scale(EARTH_RATE, cross(_Z, rate))


@jitable
def frozen_direction(u, x0, r_T) -> tuple:
    """(status, g, its azimuth, the target's latitude): the unit ground line of the frame
    with footprint axis x0 looking along û at the target r_T (module docstring, yaw
    compensation); status AT_POLE or GRAZING where it is undefined."""
    found, latitude = geodetic_latitude(r_T)
    if not found:
        return AT_POLE, x0, 0.0, 0.0
    up, east, north = tangent_frame(r_T, latitude)
    d = ground_line(u, x0, up)
    defined, azimuth = _azimuth(d, east, north)
    if not defined:
        return GRAZING, x0, 0.0, 0.0
    return OK, divide(d, norm(d)), azimuth, latitude


def mount(boresight_B) -> np.ndarray:
    """C_RP = [a_B, b × a_B, b] (columns): the frame the body carries for a boresight b
    and its footprint axis a_B (module docstring); the identity for b = +z."""
    b = np.asarray(boresight_B, dtype=float)
    a_B = footprint_axis(b)
    b = b / math.sqrt(float(b @ b))
    return np.column_stack((a_B, cross(b, a_B), b))


class StaringGuidance(Model):
    """Reference attitude staring at a ground target, with yaw compensation ([Liang 2019])."""

    DEFAULT_STOP = 200.0  #: the paper's staring window

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
        input_("r_I", "m", "satellite position in I", START_R, shape=(3,)),
        input_("v_I", "m/s", "satellite velocity in I", START_V, shape=(3,)),
        input_("r_T_I", "m", "ground target position in I", START_T, shape=(3,)),
        input_("v_T_I", "m/s", "ground target velocity in I", START_VT, shape=(3,)),
        input_(
            "q_OI",
            "1",
            "attitude of the orbit frame O relative to I (must match r_I, v_I)",
            START_Q_OI,
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
        C_RP = mount(p.boresight_B)
        self.state = S.zeros()
        self.state[S.mounted] = not np.array_equal(C_RP, np.eye(3))  # else R = P
        self.state[S.C_RP : S.C_RP + 9] = C_RP.reshape(-1)
        self.state[S.compensate] = p.yaw_compensation
        self.state[S.reference_time] = p.reference_time
        self.state[S.tolerance] = CAPTURE_TOLERANCE * max(1.0, abs(p.reference_time))
        self.t = t0

    def step(self, t, dt):
        guidance_step(self.values, self.state, self.t, dt)
        self.t = t + dt

    def output(self):
        status = guidance_output(self.values, self.state, self.t)
        if status != OK:
            raise ModelError(self._why(status))

    def _why(self, status: int) -> str:
        """The message of a kernel's status (the condition at time t)."""
        t, u_in, detail = self.t, self.u, float(self.state[S.detail])
        if status == NOT_FINITE:
            bad = [name for name in _INPUTS if not np.all(np.isfinite(getattr(u_in, name)))]
            return f"t={t:.6g} s: inputs {bad} are not finite"
        if status == AT_POLE:
            return _at_pole(u_in.r_T_I.tolist())
        return {
            NO_ORBIT_FRAME: f"t={t:.6g} s: r_I and v_I are parallel or zero: the orbit frame "
            "is undefined",
            Q_OI_MISMATCH: f"t={t:.6g} s: q_OI does not match the orbit frame of r_I, v_I "
            f"(z = -r/|r|, y = -(r x v)/|r x v|) by {detail:.3g} > {Q_OI_TOLERANCE:g}: "
            "connect q_OI from the same orbit as r_I",
            NO_LINE_OF_SIGHT: f"t={t:.6g} s: zero-length line of sight: r_T_I - r_I has "
            f"length {detail:.3g} m",
            ALONG_X_O: _PARALLEL.format("the orbit frame's x axis (pitch +-90 deg)"),
            ALONG_G: _PARALLEL.format("the captured footprint direction g (grazing view)"),
            GRAZING: _GRAZING,
        }[status]


_PARALLEL = "the line of sight (r_T_I - r_I) is parallel to {}: the reference frame is undefined"
_GRAZING = (
    "the footprint plane is parallel to the target's tangent plane "
    "(grazing view): footprint direction undefined"
)

# -- kernels (components/runtime/jit.py) ------------------------------------------------
P, U, Y = StaringGuidance.names()
#: the state array: 1 when the boresight mount C_RP is not the identity, C_RP (row-major),
#: 1 with yaw compensation, reference_time and its capture tolerance; 1 once captured, t_cap,
#: g (I, at t_cap), the azimuth and the target's latitude at t_cap; (1 when set, q_ref,
#: euler_ref_BO) at the previous communication point (the anchor) and at the last output;
#: the number a failing status reports
S = state_table(
    "StaringGuidance state", mounted=1, C_RP=9, compensate=1, reference_time=1, tolerance=1,
    captured=1, capture_time=1, g_ref=3, azimuth_ref=1, latitude=1, anchored=1, anchor_q=4,
    anchor_euler=3, lasted=1, last_q=4, last_euler=3, detail=1,
)  # fmt: skip


@step_kernel(StaringGuidance)
def guidance_step(values, state, t, dt):
    """The outputs at t become the anchors of the angle branches for t + dt."""
    for k in range(8):  # (set, q_ref, euler_ref_BO)
        state[S.anchored + k] = state[S.lasted + k]
    return OK


@output_kernel(StaringGuidance)
def guidance_output(values, state, t):
    """Every output at time t (module docstring); OK, or the status of the condition the
    model cannot continue from (then :meth:`StaringGuidance.output` raises)."""
    v, s = floats(values), floats(state)
    for k in range(U.r_I, U.q_OI + 4):
        if not math.isfinite(v[k]):
            return NOT_FINITE
    r, vel = (v[U.r_I], v[U.r_I + 1], v[U.r_I + 2]), (v[U.v_I], v[U.v_I + 1], v[U.v_I + 2])
    r_T, v_T = (
        (v[U.r_T_I], v[U.r_T_I + 1], v[U.r_T_I + 2]),
        (v[U.v_T_I], v[U.v_T_I + 1], v[U.v_T_I + 2]),
    )
    C_OI = dcm(v[U.q_OI : U.q_OI + 4])

    # the two-body orbit frame of r, v, checked against q_OI
    defined, expected, r_norm, r_hat, h = orbit_axes(r, vel)
    if not defined:
        return NO_ORBIT_FRAME
    error = mismatch(C_OI, expected)
    if error > Q_OI_TOLERANCE:
        state[S.detail] = error
        return Q_OI_MISMATCH
    x_O = C_OI[0]

    s_range = norm(sub(r_T, r))
    if not s_range > MIN_SLANT_RANGE:
        state[S.detail] = s_range
        return NO_LINE_OF_SIGHT
    u, du, ddu = line_of_sight(r, vel, r_T, v_T, s_range)

    # the pointing frame P: P0 = F(û, x_O), or with yaw compensation F(û, g) after the
    # capture (made here at t_cap; re-made when evaluated at t_cap again)
    captured = s[S.captured] != 0.0
    capturing = (not captured and t >= s[S.reference_time] - s[S.tolerance]) or (
        captured and s[S.capture_time] == t
    )
    compensating = s[S.compensate] != 0.0 and (capturing or captured)
    if compensating:  # only the axes of the yaw-0 frame P0
        ok, x0, y0, _, _ = aligned_axes(u, x_O)
        C_PI, w_P, dw_P = (x0, y0, u), x0, y0  # P: after the capture below
    else:  # P0 = F(û, x_O) is the reference
        dx_O, ddx_O = x_axis_rates(x_O, r_hat, r_norm, h, vel)
        ok, C_PI, w_P, dw_P = aligned_frame(u, du, ddu, x_O, dx_O, ddx_O)
        x0, y0 = C_PI[0], C_PI[1]
    if not ok:
        return ALONG_X_O
    if capturing:
        status, g, azimuth, latitude = frozen_direction(u, x0, r_T)
        if status != OK:
            return status
        state[S.captured], state[S.capture_time], state[S.azimuth_ref] = 1.0, t, azimuth
        state[S.latitude] = latitude
        for k in range(3):
            state[S.g_ref + k] = g[k]
    if compensating:
        angle = EARTH_RATE * (t - state[S.capture_time])
        g, dg, ddg = ground_fixed(state[S.g_ref : S.g_ref + 3], angle)
        ok, C_PI, w_P, dw_P = aligned_frame(u, du, ddu, g, dg, ddg)
        if not ok:
            return ALONG_G
    C_RI, w, dw = C_PI, w_P, dw_P
    mounted = s[S.mounted] != 0.0
    if mounted:
        C_RP = s[S.C_RP : S.C_RP + 9]
        M = ((C_RP[0], C_RP[1], C_RP[2]), (C_RP[3], C_RP[4], C_RP[5]), (C_RP[6], C_RP[7], C_RP[8]))
        C_RI, w, dw = matmul(M, C_PI), rotate(M, w_P), rotate(M, dw_P)

    # q_RI with its sign continued; the 1-2-3 angles relative to O on the anchor's branch
    (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C_RI
    q = quat_of_rows(c00, c01, c02, c10, c11, c12, c20, c21, c22)
    anchored = s[S.anchored] != 0.0
    anchor_euler = (s[S.anchor_euler], s[S.anchor_euler + 1], s[S.anchor_euler + 2])
    if anchored and quat_dot(q, s[S.anchor_q : S.anchor_q + 4]) < 0.0:
        q = (-q[0], -q[1], -q[2], -q[3])
    if not mounted:  # eq (11) and the yaw of eq (12), continued from the anchor
        x, y_, z = rotate(C_OI, u)
        psi = math.atan2(dot(C_PI[0], y0), dot(C_PI[0], x0)) if compensating else 0.0
        euler = (-math.atan2(y_, z), math.asin(min(1.0, max(-1.0, x))), psi)
        if anchored:
            euler = _unwrap3(euler, anchor_euler)
    else:
        # C_RO = C_RI C_OIᵀ: row i is C_OI applied to row i of C_RI
        C_RO = (rotate(C_OI, C_RI[0]), rotate(C_OI, C_RI[1]), rotate(C_OI, C_RI[2]))
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C_RO
        q_RO = quat_of_rows(c00, c01, c02, c10, c11, c12, c20, c21, c22)
        euler = euler123(q_RO, dcm(q_RO), anchor_euler, anchored)

    rotation = 0.0
    if state[S.captured] != 0.0:
        up, east, north = tangent_frame(r_T, state[S.latitude])
        defined, azimuth = _azimuth(ground_line(u, C_PI[0], up), east, north)
        if not defined:
            return GRAZING
        rotation = wrap_pi(azimuth - state[S.azimuth_ref])
    for k in range(3):
        values[Y.w_ref + k], values[Y.dw_ref + k], values[Y.euler_ref_BO + k] = (
            w[k],
            dw[k],
            euler[k],
        )
        state[S.last_euler + k] = euler[k]
    for k in range(4):
        values[Y.q_ref + k] = q[k]
        state[S.last_q + k] = q[k]
    state[S.lasted] = 1.0
    values[Y.look_angle] = math.atan2(norm(cross(u, r_hat)), -dot(u, r_hat))
    values[Y.slant_range] = s_range
    values[Y.footprint_rotation] = rotation
    return OK
