"""Mission analysis of the video-SAR paper ([Liang 2019]): frame overlap
ratio versus frame rate (§1, eqs 1–5) and Walker-constellation sizing for continuous
staring (§3, eqs 14–20), with independent numerical checks of both.

Plain functions on NumPy/floats; SI units, angles in radians.  Every function returns a
small frozen dataclass carrying the intermediate quantities, so a reader can follow the
paper's chain of numbers.

Frame overlap (eqs 1–5), reconstructed
--------------------------------------
The paper's geometry (its Fig. 1) is the straight-line ("equivalent squint") model: the
radar moves at speed V along a line, closest slant range Rc at t = 0 (zero Doppler,
broadside).  At time t the squint angle θc obeys ``tan θc = V t / Rc``, so
``cos θc = Rc / √(Rc² + V² t²)``.  A frame whose data are centred at t_i spans the
line-of-sight angles θc_i ± θ_i/2 (θ_i = the frame's synthetic-aperture angle), hence::

    f_d = 2 V sin θ / λ
    B_a = 4 V cos θc_i sin(θ_i/2) / λ ≈ 2 V θ_i cos θc_i / λ            (eq 2)
    ρ_a = V / B_a = λ / (2 θ_i cos θc_i)                                 (text below eq 2)

The OCR prints ρ_a = λ V_r/(2 V_r) · 1/θ_i · 1/cos θc_i: in the straight-line model the
velocity that turns Doppler into along-track position and the one in f_d are the same,
so the ratio is 1 (a spaceborne V_g/V_s factor would be compensated by measuring L along
the orbit, see "which velocity" below).  The along-track length subtended by θ_i at
squint θc_i is dx/dθ · θ_i with x = Rc tan θ, so::

    L_i = θ_i Rc / cos² θc_i = λ Rc / (2 ρ_a cos³ θc_i)
        = λ (Rc² + V² t_i²)^{3/2} / (2 ρ_a Rc²)                          (eq 3)

Frame i covers x_i ± L_i/2 and frame i−1, centred ΔL = V T_f earlier (T_f = 1/frame
rate), covers x_i − ΔL ± L_{i−1}/2, with L_{i−1} = L(t_i − T_f); the overlap length and
ratio are::

    C_L = (L_i + L_{i−1})/2 − V T_f,    α_i = C_L / L_i                  (eqs 4, 5)

which is eq 5 term by term.  At broadside (t_i = 0, the default here: the zero-Doppler
frame, where the frame is shortest and the overlap smallest)::

    α_0 = 1 − T_f / T_a (1 + O(V² T_f² / Rc²)),   T_a = λ Rc / (2 ρ_a V)

T_a is the frame's aperture time: the time the line of sight, seen from the target,
takes to turn by λ/(2ρ_a).  Away from broadside L_i grows as 1/cos³θc_i and the overlap
rises (e.g. 87.2 % and 87.5 % at 5 Hz at the ends, t_i = ±100 s, of the paper's 200-s
stare: L_{i−1} is the shorter frame after broadside, the longer one before).

Which velocity V (the paper's V_r, "卫星平台的运动速度", the platform's speed).  Both L
and ΔL are lengths along the satellite's path, so V is the satellite's speed along its
orbit; physically the overlap depends only on the line-of-sight rate seen from the target,
V/Rc at broadside, so V must be the speed *relative to the Earth-fixed target*:

- ``"inertial"`` (default, the paper's words): V_s = √(μ/r), r = a = R_e + h (circular
  orbit, R_e = WGS-84 equatorial radius; ``altitude`` is a − R_e throughout, as in
  :mod:`.orbit`), Earth rotation ignored;
- ``"earth_fixed"``: |v − ω_E × r| for the circular orbit of inclination i with the
  satellite over the target latitude: V² = V_s² − 2 V_s ω_E r cos i + (ω_E r cos φ)²
  (retrograde sun-synchronous orbits gain ≈ +1 %);
- ``"effective"``: √(V_s V_g), the velocity of the hyperbolic range model
  R² = Rc² + V_e² t² of spaceborne SAR, with V_g = V_s R_t / r;
- ``"ground"``: V_g = V_s R_t / r, the sub-satellite point's speed;
- a number (m/s).
Readings other than "inertial"/"earth_fixed" mix a range-history velocity into a
path-length formula; they are offered only to show what they would give.

Which slant range Rc ("下视角 30°" = 30° off-nadir look angle at the satellite, the
default; ``look_angle_kind="incidence"`` reads it as the incidence angle at the ground):

- ``"sphere"`` (default of :func:`slant_range`): Earth a sphere of radius R_e = WGS-84 a,
  satellite at r = R_e + h: Rc = r cos θ − √(R_e² − r² sin² θ);
- ``"ellipsoid"`` (default of :func:`overlap_ratio`, the paper's target): the look ray,
  θ off the geocentric nadir in the plane of nadir and orbit normal (broadside, right-
  or left-looking), intersected with the WGS-84
  ellipsoid, the satellite on its circular orbit r = R_e + h placed so that the ray
  lands at the target's geodetic latitude (for the paper's 33.16° N the ground is
  6.4 km below R_e and Rc grows by 7.6 km, to 672.3 km);
- ``"flat"``: h / cos θ;
- a number (m).

Walker sizing (eqs 14–20), reconstructed
----------------------------------------
In the plane of the Earth's centre O, the satellite S (OS = r = R_e + h) and a ground
point G (OG = R_e) at Earth central angle α from the sub-satellite point, with look angle
θ at S and incidence angle η at G (angle between GS and the local vertical): the exterior
angle gives η = α + θ and the law of sines r sin θ = R_e sin η.  Eq (14),
``r cos α − r sin α / tan β = R_e``, is r sin(β − α) = R_e sin β, i.e. exactly this
relation with **β = η, the incidence angle at the ground** (check: β → 90°, grazing, gives
the horizon cos α = R_e/r).  Read as the look angle at the satellite, the relation would
be R_e cos α + R_e sin α / tan β = r instead.  So::

    incidence reading:  θ = asin(R_e sin β / r),  α = β − θ
    look reading:       η = asin(r sin β / R_e),  α = η − β

The target is visible from the orbit arc AB = 2α around the overflight (the target in
the orbit plane, Earth rotation ignored), so with ω = √(μ/r³)::

    T_v = 2α/ω                   (eq 15),   T = 2π/ω
    S = ⌈T/T_v⌉ = ⌈π/α⌉          (eq 16; satellites spaced 2π/S ≤ 2α in the plane)
    Δφ = −2π T/T_e               (eq 17; ground-track shift per revolution)
    P = 2π/|Δφ| = T_e/T          (eqs 18, 19 with m = 1), rounded up here
    N = P S                      (eq 20)

T_e: the paper says the Earth's rotation period, i.e. the sidereal day 2π/ω_E (the
default).  For a sun-synchronous orbit the node turns with the mean Sun, and the
ground-track shift per nodal revolution is 2π T/86400 s (``earth_period=SOLAR_DAY``);
at 567 km T_e/T = 14.96 (sidereal) or 15.00 (solar), P = 15 either way.  Eqs 17–19 count
planes by ground-track shifts: P planes whose RAAN are 2π/P apart put a ground track
every |Δφ| in longitude, which closes the coverage only if the strip a plane watches
without a break is as wide as the track spacing.  That strip is narrower than ±α: at
cross-track distance d the visible along-track half-arc is acos(cos α / cos d), which
must stay ≥ π/S.  :func:`walker_coverage` checks the whole argument by simulation.
Roundings: S and P by ``ceil`` (after forgiving a relative 1e-9 so that an
exact integer is not pushed up by floating-point noise).

:func:`visibility_time` is the independent check of eq 15: it finds numerically the time
an overflown target stays within the angle limit on a spherical Earth, with the Earth's
rotation ignored (equals eq 15 to solver precision) or included (the paper ignores it).

Against the paper's numbers (the full table of readings: test_mission_analysis.py)
---------------------------------------------------------------------------------
- Overlap, broadside frame, look angle 30°, V = inertial orbital speed: 56.7 % at 5 Hz
  and 91.34 % at 25 Hz with Rc to the WGS-84 ellipsoid at 33.16° N (56.2 %, 91.24 % on the
  sphere of R_e; the Earth's rotation, which the paper neglects, lowers both by ≈ 0.45
  and 0.09 point).  The paper's 57 % follows; its 91.4 % does not: its two numbers imply
  1 − α = 2.15 T_f /s, the physics gives 2.165 /s (ellipsoid) to 2.21 /s.  Only readings
  without a physical basis give 91.4 % (30° read as incidence with V = √(V_s V_g): 56.8 %,
  91.36 %; or frames centred 10 s off broadside: 57.0 %, 91.40 %).
- Walker: T = 5760 s = 1.60 h and P = 15 follow.  S = 12 (N = 180) follows only if the
  65° is the off-nadir look angle at the satellite (α = 15.71°, incidence at the ground
  80.7°; any look limit in [64.59°, 65.33°] gives S = 12).  With β the incidence angle,
  as eq 14 and the words "最大入射角" say, α = 8.66°, S = 21, N = 315.  Simulated (two
  days, 5-s steps): 12 × 15 covers the target without a break under the look reading at
  every phasing F, while under the incidence reading neither 12 × 15 nor the formulas'
  own 21 × 15 does (≤ 85 % of the time, gaps of 8.5–17.5 min).  With the Earth's rotation
  T_v is 1.0 % shorter; S is unchanged under both readings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...components.orbit_environment import (
    EARTH_RATE,
    MU_EARTH,
    WGS84_A,
    WGS84_E2,
    geodetic_to_ecef,
)
from . import passes

SPEED_OF_LIGHT = 299792458.0  # m/s, exact (SI)
SIDEREAL_DAY = 2.0 * math.pi / EARTH_RATE  # s, Earth rotation period 2π/ω_E
SOLAR_DAY = 86400.0  # s, mean solar day
TROPICAL_YEAR = passes.TROPICAL_YEAR_DAYS * SOLAR_DAY  # s

DEG = math.pi / 180.0

_ROUND_SLACK = 1e-9  # relative, for ceil of near-integers


def _ceil(x: float) -> int:
    return math.ceil(x * (1.0 - _ROUND_SLACK))


def _inclination(altitude: float, inclination: float | None) -> float:
    """The given inclination, or the sun-synchronous one at this altitude (a = R_e + h)."""
    return (
        passes.sun_synchronous_inclination(WGS84_A + altitude)
        if inclination is None
        else inclination
    )


def _check(condition: bool, message: str) -> None:
    if not condition:
        raise ValueError(message)


# --------------------------------------------------------------------------------------
# Orbit helpers
# --------------------------------------------------------------------------------------


def circular_speed(
    altitude: float, *, earth_radius: float = WGS84_A, mu: float = MU_EARTH
) -> float:
    """Inertial speed √(μ/r) of a circular orbit, r = earth_radius + altitude."""
    return math.sqrt(mu / (earth_radius + altitude))


def orbital_period(
    altitude: float, *, earth_radius: float = WGS84_A, mu: float = MU_EARTH
) -> float:
    """Keplerian period 2π √(r³/μ) of a circular orbit, r = earth_radius + altitude."""
    return 2.0 * math.pi * math.sqrt((earth_radius + altitude) ** 3 / mu)


def geocentric_radius(latitude: float) -> float:
    """Distance from the Earth's centre to the WGS-84 ellipsoid at a geodetic latitude."""
    x, _, z = geodetic_to_ecef(latitude, 0.0, 0.0)
    return math.hypot(x, z)


def geocentric_latitude(latitude: float) -> float:
    """Geocentric latitude of the WGS-84 ellipsoid point at a geodetic latitude."""
    return math.atan((1.0 - WGS84_E2) * math.tan(latitude))


# --------------------------------------------------------------------------------------
# Slant range and platform velocity
# --------------------------------------------------------------------------------------


def look_to_incidence(look_angle: float, r: float, R: float) -> tuple[float, float]:
    """(incidence angle η at the ground, Earth central angle α) for an off-nadir look angle
    θ from radius r onto a sphere of radius R: sin η = r sin θ / R, α = η − θ."""
    s = r * math.sin(look_angle) / R
    _check(s <= 1.0, f"look angle {look_angle / DEG:.3f} deg misses the Earth")
    eta = math.asin(s)
    return eta, eta - look_angle


def incidence_to_look(incidence: float, r: float, R: float) -> tuple[float, float]:
    """(look angle θ at the satellite, Earth central angle α) for an incidence angle η at
    a sphere of radius R seen from radius r: sin θ = R sin η / r, α = η − θ."""
    theta = math.asin(R * math.sin(incidence) / r)
    return theta, incidence - theta


def _ellipsoid_slant_range(
    altitude: float, look_angle: float, latitude: float, inclination: float, right_looking: bool
) -> float:
    """Ray from the satellite (circular orbit r = a + h, broadside) at ``look_angle`` off
    −r̂ towards ∓ orbit normal, to the WGS-84 ellipsoid; the satellite's position along
    its orbit is iterated until the ray lands at the geodetic ``latitude``."""
    r = WGS84_A + altitude
    si, ci = math.sin(inclination), math.cos(inclination)
    normal = np.array([0.0, -si, ci])  # ĥ for Ω = 0
    side = -1.0 if right_looking else 1.0  # right of the velocity = −ĥ
    w = np.array([1.0, 1.0, 1.0 / (1.0 - WGS84_E2)])  # (x/a)² + (y/a)² + (z/b)² = 1
    lat_s = geocentric_latitude(latitude)  # satellite latitude, first guess
    for _ in range(50):
        s = math.sin(lat_s) / si
        _check(abs(s) <= 1.0, "the orbit never flies over this latitude")
        u = math.asin(s)  # ascending pass
        rhat = np.array([math.cos(u), ci * math.sin(u), si * math.sin(u)])
        d = -math.cos(look_angle) * rhat + side * math.sin(look_angle) * normal
        p0 = r * rhat
        A = float(np.sum(w * d * d))
        B = 2.0 * float(np.sum(w * p0 * d))
        C = float(np.sum(w * p0 * p0)) - WGS84_A**2
        disc = B * B - 4.0 * A * C
        _check(disc >= 0.0, f"look angle {look_angle / DEG:.3f} deg misses the Earth")
        rng = (-B - math.sqrt(disc)) / (2.0 * A)
        p = p0 + rng * d
        landed = math.atan2(p[2] / (1.0 - WGS84_E2), math.hypot(p[0], p[1]))  # geodetic
        if abs(landed - latitude) < 1e-12:
            break
        lat_s -= landed - latitude
    return rng


def slant_range(
    altitude: float,
    look_angle: float,
    model: str | float = "sphere",
    *,
    look_angle_kind: str = "look",
    earth_radius: float = WGS84_A,
    latitude: float | None = None,
    inclination: float | None = None,
    right_looking: bool = True,
) -> float:
    """Closest (zero-Doppler) slant range Rc, m, for the models listed in the module doc.

    ``look_angle_kind="incidence"`` takes ``look_angle`` as the incidence angle at the
    ground and converts it on the sphere of ``earth_radius`` first.  ``latitude`` and
    ``inclination`` (default: sun-synchronous) are used by ``"ellipsoid"`` only.
    """
    _check(
        look_angle_kind in ("look", "incidence"),
        f"look_angle_kind must be 'look' or 'incidence', got {look_angle_kind!r}",
    )
    if not isinstance(model, str):
        return float(model)
    r = earth_radius + altitude
    theta = look_angle
    if look_angle_kind == "incidence":
        theta, _ = incidence_to_look(look_angle, r, earth_radius)
    if model == "sphere":
        R = earth_radius
        return r * math.cos(theta) - math.sqrt(R * R - (r * math.sin(theta)) ** 2)
    if model == "flat":
        return altitude / math.cos(theta)
    if model == "ellipsoid":
        if latitude is None:
            raise ValueError("the 'ellipsoid' slant range needs the target's latitude")
        inc = _inclination(altitude, inclination)
        return _ellipsoid_slant_range(altitude, theta, latitude, inc, right_looking)
    raise ValueError(
        f"unknown slant-range model {model!r}: 'sphere', 'ellipsoid', 'flat' or a number"
    )


def platform_velocity(
    altitude: float,
    model: str | float = "inertial",
    *,
    earth_radius: float = WGS84_A,
    mu: float = MU_EARTH,
    latitude: float | None = None,
    inclination: float | None = None,
    ground_radius: float | None = None,
) -> float:
    """The velocity V (the paper's V_r), m/s, for the models listed in the module doc.

    ``ground_radius`` (default ``earth_radius``) is the radius R_t of the sphere on which
    V_g is taken; ``latitude``/``inclination`` (default sun-synchronous) serve
    ``"earth_fixed"``.
    """
    if not isinstance(model, str):
        return float(model)
    r = earth_radius + altitude
    vs = math.sqrt(mu / r)
    vg = vs * (earth_radius if ground_radius is None else ground_radius) / r
    if model == "inertial":
        return vs
    if model == "ground":
        return vg
    if model == "effective":
        return math.sqrt(vs * vg)
    if model == "earth_fixed":
        if latitude is None:
            raise ValueError("the 'earth_fixed' velocity needs the target's latitude")
        inc = _inclination(altitude, inclination)
        we = EARTH_RATE
        lat_c = geocentric_latitude(latitude)
        return math.sqrt(
            vs * vs - 2.0 * vs * we * r * math.cos(inc) + (we * r * math.cos(lat_c)) ** 2
        )
    raise ValueError(
        f"unknown velocity model {model!r}: 'inertial', 'earth_fixed', "
        "'effective', 'ground' or a number"
    )


# --------------------------------------------------------------------------------------
# Frame overlap, eqs 1–5
# --------------------------------------------------------------------------------------


def aperture_length(t, wavelength: float, resolution: float, slant_range_c: float, velocity: float):
    """Eq 3: along-track data length L(t) = λ (Rc² + V² t²)^{3/2} / (2 ρ_a Rc²), m."""
    t = np.asarray(t, dtype=float)
    return (
        wavelength
        * (slant_range_c**2 + (velocity * t) ** 2) ** 1.5
        / (2.0 * resolution * slant_range_c**2)
    )


@dataclass(frozen=True)
class OverlapResult:
    """Frame overlap ratio of eqs 1–5 and everything it was computed from (SI, rad).

    Array fields follow the shape of ``frame_rate`` (and ``t_i``) broadcast together.
    """

    frame_rate: np.ndarray  # Hz
    overlap: np.ndarray  # α_i, eq 5 (fraction, 0.57 = 57 %)
    frame_period: np.ndarray  # T_f = 1 / frame rate, s
    t_i: np.ndarray  # data-centre time of frame i from zero Doppler, s
    wavelength: float  # λ = c / f, m
    resolution: float  # ρ_a, m
    altitude: float  # h = a − R_e, m
    look_angle: float  # off-nadir at the satellite (sphere of R_e), rad
    incidence_angle: float  # at the ground (sphere of R_e), rad
    velocity: float  # V used as the paper's V_r, m/s
    velocity_model: str
    slant_range: float  # Rc, m
    slant_range_model: str
    squint: np.ndarray  # θc_i, rad
    aperture_angle: np.ndarray  # θ_i = λ / (2 ρ_a cos θc_i), rad
    aperture_length: np.ndarray  # L_i, m (eq 3)
    previous_aperture_length: np.ndarray  # L_{i−1} = L(t_i − T_f), m
    frame_spacing: np.ndarray  # ΔL = V T_f, m
    overlap_length: np.ndarray  # C_L, m (eq 4)
    aperture_time: np.ndarray  # L_i / V, s
    doppler_bandwidth: np.ndarray  # B_a, eq 2 exact form, Hz
    overlap_broadside_linear: np.ndarray  # 1 − T_f / T_a(t_i = 0), the small-T_f form


def overlap_ratio(
    frame_rate,
    *,
    carrier_frequency: float,
    look_angle: float,
    resolution: float,
    altitude: float,
    t_i=0.0,
    velocity: str | float = "inertial",
    slant_range_model: str | float = "ellipsoid",
    look_angle_kind: str = "look",
    latitude: float | None = None,
    inclination: float | None = None,
    earth_radius: float = WGS84_A,
    mu: float = MU_EARTH,
) -> OverlapResult:
    """Overlap ratio α_i of consecutive video frames versus frame rate (eqs 1–5).

    Reading (see the module doc for the derivation): straight-line geometry with closest
    slant range Rc and platform speed V; frame i's data centred at ``t_i`` seconds from
    zero Doppler (default 0: the broadside frame, smallest overlap), frame i−1 centred at
    t_i − T_f; α_i = ((L_i + L_{i−1})/2 − V T_f) / L_i with L from eq 3.  The radar and
    target are arguments (``latitude``: needed by the ``"ellipsoid"`` slant range); the
    model defaults are V = inertial circular speed (the paper's V_r, Earth rotation
    neglected as in its straight-line model) and Rc to the WGS-84 ellipsoid
    (sun-synchronous inclination).  The paper's case (9.6 GHz, 30° off-nadir look angle,
    ρ_a = 3 m, h = 567 km = a − R_e, target at 33.16° N: ``VIDEO_SAR_OVERLAP`` in
    orchestration/scenarios/constants.py) gives 56.7 % at 5 Hz and 91.34 % at 25 Hz
    (paper: 57 %, 91.4 %).  A negative α means the frames do not touch (gap).
    """
    fr = np.asarray(frame_rate, dtype=float)
    _check(bool(np.all(fr > 0)), "frame_rate must be > 0")
    _check(
        carrier_frequency > 0 and resolution > 0 and altitude > 0,
        "carrier_frequency, resolution and altitude must be > 0",
    )
    lam = SPEED_OF_LIGHT / carrier_frequency
    r = earth_radius + altitude
    if look_angle_kind == "incidence":
        look, _ = incidence_to_look(look_angle, r, earth_radius)
        inc = look_angle
    else:
        look = look_angle
        inc, _ = look_to_incidence(look_angle, r, earth_radius)
    rc = slant_range(
        altitude,
        look_angle,
        slant_range_model,
        look_angle_kind=look_angle_kind,
        earth_radius=earth_radius,
        latitude=latitude,
        inclination=inclination,
    )
    ground_radius = (  # latitude is given: the ellipsoid's slant range above needs it
        geocentric_radius(latitude)
        if slant_range_model == "ellipsoid" and latitude is not None
        else earth_radius
    )
    v = platform_velocity(
        altitude,
        velocity,
        earth_radius=earth_radius,
        mu=mu,
        latitude=latitude,
        inclination=inclination,
        ground_radius=ground_radius,
    )
    tf = 1.0 / fr
    ti = np.asarray(t_i, dtype=float)
    tf, ti = np.broadcast_arrays(tf, ti)
    L_i = aperture_length(ti, lam, resolution, rc, v)
    L_prev = aperture_length(ti - tf, lam, resolution, rc, v)
    spacing = v * tf
    c_l = 0.5 * (L_i + L_prev) - spacing
    squint = np.arctan(v * ti / rc)
    theta_i = lam / (2.0 * resolution * np.cos(squint))
    bandwidth = 4.0 * v * np.cos(squint) * np.sin(theta_i / 2.0) / lam
    t_a0 = lam * rc / (2.0 * resolution * v)
    return OverlapResult(
        frame_rate=fr * np.ones_like(tf),
        overlap=c_l / L_i,
        frame_period=tf,
        t_i=ti,
        wavelength=lam,
        resolution=resolution,
        altitude=altitude,
        look_angle=look,
        incidence_angle=inc,
        velocity=v,
        velocity_model=velocity if isinstance(velocity, str) else "given",
        slant_range=rc,
        slant_range_model=(slant_range_model if isinstance(slant_range_model, str) else "given"),
        squint=squint,
        aperture_angle=theta_i,
        aperture_length=L_i,
        previous_aperture_length=L_prev,
        frame_spacing=spacing,
        overlap_length=c_l,
        aperture_time=L_i / v,
        doppler_bandwidth=bandwidth,
        overlap_broadside_linear=1.0 - tf / t_a0,
    )


# --------------------------------------------------------------------------------------
# Walker sizing, eqs 14–20
def gap_frame_rate(low: float, high: float, **case) -> float | None:
    """The frame rate at which consecutive frames just touch (α = 0 in eq 5, found by
    Brent's method): below it they leave gaps.  ``case``: :func:`overlap_ratio`'s
    keywords; None when α does not change sign between ``low`` and ``high`` Hz."""
    from scipy.optimize import brentq  # type: ignore[import-untyped]

    def alpha(rate: float) -> float:
        return float(overlap_ratio([rate], **case).overlap[0])

    if alpha(low) * alpha(high) > 0:
        return None
    return float(brentq(alpha, low, high, xtol=1e-9))


# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class WalkerSizing:
    """Walker-constellation size of eqs 14–20 with its intermediate quantities (SI, rad)."""

    altitude: float  # h, m
    radius: float  # r = R_e + h, m
    earth_radius: float  # R_e, m
    beta: float  # the β given, rad
    beta_kind: str  # "incidence" (at the ground, eq 14) or "look"
    incidence_angle: float  # η at the edge of visibility, rad
    look_angle: float  # θ at the edge of visibility, rad
    central_angle: float  # α, half the visibility arc, rad (eq 14)
    edge_slant_range: float  # satellite–target distance at the edge, m
    orbit_rate: float  # ω = √(μ/r³), rad/s
    period: float  # T, s
    visibility_time: float  # T_v = 2α/ω, s (eq 15)
    satellites_per_plane_exact: float  # T / T_v
    satellites_per_plane: int  # S = ⌈T/T_v⌉ (eq 16)
    earth_period: float  # T_e, s
    track_shift: float  # Δφ = −2π T/T_e, rad (eq 17)
    planes_exact: float  # 2π/|Δφ| = T_e/T
    planes: int  # P (eq 19), rounded up
    satellites: int  # N = P S (eq 20)


def walker_sizing(
    altitude: float,
    max_incidence: float,
    *,
    beta_kind: str = "incidence",
    earth_period: float = SIDEREAL_DAY,
    earth_radius: float = WGS84_A,
    mu: float = MU_EARTH,
) -> WalkerSizing:
    """Walker constellation for continuous visibility of one target (eqs 14–20).

    ``beta_kind="incidence"`` (default) takes β as the incidence angle at the ground,
    which is what eq 14 encodes and what the paper's words "最大入射角" say;
    ``beta_kind="look"`` takes it as the off-nadir look angle at the satellite.  Spherical
    Earth of radius R_e (WGS-84 a), circular orbit r = R_e + h, Earth rotation ignored in
    T_v (as in the paper), T_e = sidereal day by default.  S and P are rounded up.
    """
    _check(
        beta_kind in ("incidence", "look"),
        f"beta_kind must be 'incidence' or 'look', got {beta_kind!r}",
    )
    _check(altitude > 0 and 0 < max_incidence < math.pi / 2, "need altitude > 0 and 0 < β < 90°")
    r = earth_radius + altitude
    if beta_kind == "incidence":
        eta = max_incidence
        theta, alpha = incidence_to_look(eta, r, earth_radius)
    else:
        theta = max_incidence
        eta, alpha = look_to_incidence(theta, r, earth_radius)
    edge = earth_radius * math.sin(alpha) / math.sin(theta)
    omega = math.sqrt(mu / r**3)
    period = 2.0 * math.pi / omega
    tv = 2.0 * alpha / omega
    s_exact = period / tv
    shift = -2.0 * math.pi * period / earth_period
    p_exact = 2.0 * math.pi / abs(shift)
    S, P = _ceil(s_exact), _ceil(p_exact)
    return WalkerSizing(
        altitude=altitude,
        radius=r,
        earth_radius=earth_radius,
        beta=max_incidence,
        beta_kind=beta_kind,
        incidence_angle=eta,
        look_angle=theta,
        central_angle=alpha,
        edge_slant_range=edge,
        orbit_rate=omega,
        period=period,
        visibility_time=tv,
        satellites_per_plane_exact=s_exact,
        satellites_per_plane=S,
        earth_period=earth_period,
        track_shift=shift,
        planes_exact=p_exact,
        planes=P,
        satellites=P * S,
    )


# --------------------------------------------------------------------------------------
# Independent numerical checks
# --------------------------------------------------------------------------------------


def _angles_at_target(sat, tgt, kind: str):
    """Incidence (angle of the line of sight from the target's vertical) or look angle
    (from the satellite's nadir), rad, of satellites ``sat`` [..., 3] seen from targets
    ``tgt`` [..., 3] on a sphere; NaN where the target is below the horizon."""
    los = sat - tgt
    d = np.linalg.norm(los, axis=-1)
    up = tgt / np.linalg.norm(tgt, axis=-1, keepdims=True)
    cos_inc = np.sum(los * up, axis=-1) / d
    if kind == "incidence":
        ang = np.arccos(np.clip(cos_inc, -1.0, 1.0))
    else:
        nadir = -sat / np.linalg.norm(sat, axis=-1, keepdims=True)
        ang = np.arccos(np.clip(np.sum(-los * nadir, axis=-1) / d, -1.0, 1.0))
    return np.where(cos_inc > 0.0, ang, np.nan)


@dataclass(frozen=True)
class VisibilityResult:
    """Numerically found visibility interval of an overflown target."""

    start: float  # s, relative to the overflight (satellite at zenith)
    end: float  # s
    duration: float  # end − start, s
    earth_rotation: bool
    inclination: float  # rad
    latitude: float  # geocentric latitude of the target (sphere), rad


def visibility_time(
    altitude: float,
    max_angle: float,
    *,
    latitude: float,
    angle_kind: str = "incidence",
    earth_rotation: bool = True,
    inclination: float | None = None,
    ascending: bool = True,
    earth_radius: float = WGS84_A,
    mu: float = MU_EARTH,
    tol: float = 1e-6,
) -> VisibilityResult:
    """Time a target stays within ``max_angle`` (incidence at the target or look angle at
    the satellite) during an overhead pass, found by bisection on the actual geometry.

    Spherical Earth of radius R_e (as eq 14), circular orbit r = R_e + h of the given
    inclination (default sun-synchronous); at t = 0 the satellite is at the target's
    zenith, at (spherical) latitude ``latitude`` on the ascending or descending branch.
    With ``earth_rotation`` the target turns with ω_E about the pole; without it this is
    eq 15's 2α/ω.
    """
    _check(angle_kind in ("incidence", "look"), "angle_kind must be 'incidence' or 'look'")
    inc = _inclination(altitude, inclination)
    _check(abs(latitude) <= min(inc, math.pi - inc), "the orbit never flies over this latitude")
    r = earth_radius + altitude
    n = math.sqrt(mu / r**3)
    u0 = math.asin(math.sin(latitude) / math.sin(inc))
    if not ascending:
        u0 = math.pi - u0
    ci, si = math.cos(inc), math.sin(inc)
    we = EARTH_RATE if earth_rotation else 0.0
    target0 = earth_radius * np.array([math.cos(u0), ci * math.sin(u0), si * math.sin(u0)])

    def angle(t: float) -> float:
        u = u0 + n * t
        sat = r * np.array([math.cos(u), ci * math.sin(u), si * math.sin(u)])
        c, s = math.cos(we * t), math.sin(we * t)
        tgt = np.array(
            [c * target0[0] - s * target0[1], s * target0[0] + c * target0[1], target0[2]]
        )
        a = _angles_at_target(sat, tgt, angle_kind)
        return math.inf if np.isnan(a) else float(a)

    def edge(direction: float) -> float:
        lo, step = 0.0, 1.0
        hi = direction * step
        while angle(hi) <= max_angle:
            lo, step = hi, step * 2.0
            hi = direction * step
            _check(step < 1e5, "the target never leaves the visibility cone")
        while abs(hi - lo) > tol:
            mid = 0.5 * (lo + hi)
            if angle(mid) <= max_angle:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi)

    _check(angle(0.0) <= max_angle, "target not visible at the overflight")
    start, end = edge(-1.0), edge(1.0)
    return VisibilityResult(
        start=start,
        end=end,
        duration=end - start,
        earth_rotation=earth_rotation,
        inclination=inc,
        latitude=latitude,
    )


@dataclass(frozen=True)
class CoverageResult:
    """Simulated visibility of one target from a Walker-delta constellation."""

    satellites_per_plane: int
    planes: int
    phasing: int
    covered_fraction: float  # fraction of sampled instants with ≥ 1 satellite
    longest_gap: float  # s (sampling resolution: ``step``)
    min_visible: int
    mean_visible: float
    duration: float  # s simulated
    step: float  # s


def walker_coverage(
    satellites_per_plane: int,
    planes: int,
    phasing: int = 0,
    *,
    altitude: float,
    max_angle: float,
    latitude: float,
    longitude: float,
    angle_kind: str = "incidence",
    inclination: float | None = None,
    duration: float = SOLAR_DAY,
    step: float = 10.0,
    earth_rotation: bool = True,
    earth_radius: float = WGS84_A,
    mu: float = MU_EARTH,
) -> CoverageResult:
    """Simulate a Walker-delta constellation S·P/P/F (RAAN 2πk/P, in-plane 2πj/S +
    2πFk/(SP)) on circular orbits (two-body, no J2) over a spherical rotating Earth and
    count, every ``step`` seconds, the satellites that see the target within ``max_angle``
    (incidence at the target, or look angle at the satellite; any azimuth: the agile
    satellite points its beam anywhere).  The independent check of eqs 16–20.
    """
    S, P = int(satellites_per_plane), int(planes)
    _check(S >= 1 and P >= 1 and step > 0 and duration > 0, "bad constellation or time grid")
    inc = _inclination(altitude, inclination)
    r = earth_radius + altitude
    n = math.sqrt(mu / r**3)
    we = EARTH_RATE if earth_rotation else 0.0
    k = np.repeat(np.arange(P), S)
    j = np.tile(np.arange(S), P)
    raan = 2.0 * math.pi * k / P
    u0 = 2.0 * math.pi * j / S + 2.0 * math.pi * phasing * k / (S * P)
    t = np.arange(0.0, duration + 0.5 * step, step)
    lat_c = latitude  # a sphere: geodetic = geocentric
    visible = np.empty(t.size, dtype=int)
    cO, sO = np.cos(raan), np.sin(raan)
    ci, si = math.cos(inc), math.sin(inc)
    for start in range(0, t.size, 512):
        tt = t[start : start + 512, None]
        u = u0[None, :] + n * tt
        cu, su = np.cos(u), np.sin(u)
        sat = r * np.stack([cO * cu - sO * ci * su, sO * cu + cO * ci * su, si * su], axis=-1)
        lon = longitude + we * tt[:, 0]
        tgt = earth_radius * np.stack(
            [
                math.cos(lat_c) * np.cos(lon),
                math.cos(lat_c) * np.sin(lon),
                np.full(lon.shape, math.sin(lat_c)),
            ],
            axis=-1,
        )
        ang = _angles_at_target(sat, tgt[:, None, :], angle_kind)
        visible[start : start + 512] = np.sum(np.nan_to_num(ang, nan=np.inf) <= max_angle, axis=1)
    covered = visible > 0
    longest = run = 0
    for c in covered:
        run = 0 if c else run + 1
        longest = max(longest, run)
    return CoverageResult(
        satellites_per_plane=S,
        planes=P,
        phasing=phasing,
        covered_fraction=float(np.mean(covered)),
        longest_gap=longest * step,
        min_visible=int(visible.min()),
        mean_visible=float(visible.mean()),
        duration=float(t[-1]),
        step=step,
    )
