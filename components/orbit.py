"""Orbit and ground-target environment: closed-form functions of time (no integration).

Orbit (two-body Kepler, optionally with the secular J2 drift)
--------------------------------------------------------------
The elements (a, e, i, Ω, ω, ν0) hold at t = 0.  With n = √(μ/a³), p = a(1 − e²) and,
when ``j2`` is set, the standard first-order secular J2 rates (Vallado, *Fundamentals of
Astrodynamics and Applications*, 4th ed., §9.6; a is taken as the mean semi-major axis)::

    Ω̇ = −3/2 n J2 (R/p)² cos i
    ω̇ =  3/4 n J2 (R/p)² (4 − 5 sin² i)
    Ṁ  =  n [1 + 3/4 J2 (R/p)² √(1 − e²) (2 − 3 sin² i)]

(all zero, and Ṁ = n, without J2), the orbit at time t is::

    E0 = 2 atan2(√(1−e) sin(ν0/2), √(1+e) cos(ν0/2)),  M0 = E0 − e sin E0
    M  = M0 + Ṁ t,  Ω = Ω0 + Ω̇ t,  ω = ω0 + ω̇ t
    E − e sin E = M                                      (Newton, to machine precision)
    r_P = a (cos E − e, √(1−e²) sin E, 0),  Ė = Ṁ / (1 − e cos E)
    ṙ_P = a Ė (−sin E, √(1−e²) cos E, 0)
    r_I = R r_P,  R = R3(−Ω) R1(−i) R3(−ω) = [P̂ Q̂ Ŵ]     (perifocal axes in I)

R turns with the angular velocity Ω_R = Ω̇ ẑ + ω̇ Ŵ (Ṙ = [Ω_R×] R), so the exact time
derivatives of this r_I(t) are::

    v_I = R ṙ_P + Ω_R × r_I
    a_I = R r̈_P + Ω_R × R ṙ_P + Ω_R × v_I + ω̇ Ω̇ (ẑ × Ŵ) × r_I,   R r̈_P = −Ṁ² a³ r_I / r³

(r_P(t) is a Kepler ellipse with mean motion Ṁ, hence the last identity).  Without J2,
v_I is the Kepler velocity and a_I = −μ r_I / r³.

Orbit frame O (DESIGN.md §2)
----------------------------
``z_O = −r̂``, ``y_O = −ĥ`` with h = r_I × v_I, ``x_O = y_O × z_O = ĥ × r̂``;
C_OI has the O axes (in I) as rows, q_OI = quat(C_OI) (scalar first, q0 ≥ 0, the
convention of :func:`.rotations.quat_from_dcm`).  Its angular velocity relative to I is
that of the frame (r̂, ĥ × r̂, ĥ): ṙ̂ = (|h|/r²) ĥ × r̂ and ḣ̂ = −(r a_h/|h|) ĥ × r̂ give::

    w_OI = (|h|/r²) ĥ + (r a_h / |h|) r̂,  a_h = a_I · ĥ
    w_OI_O = (0, −|h|/r², −r a_h/|h|)

(two-body: a_h = 0; with J2 the orbit normal precesses and a_h ≠ 0).

Earth and ground target
-----------------------
Earth rotation angle θ_E(t) = earth_angle0 + ω_E t, the Earth-fixed frame E being turned by
+θ_E about z from I (C_EI = R3(θ_E)).  Target, WGS-84 geodetic (φ, λ, h)::

    N = a / √(1 − e² sin² φ),  e² = f (2 − f)
    r_T_E = ((N + h) cos φ cos λ, (N + h) cos φ sin λ, (N (1 − e²) + h) sin φ)
    r_T_I = R3(θ_E)ᵀ r_T_E,  v_T_I = ω_E ẑ × r_T_I
"""
from __future__ import annotations

import math

from .model import Model, ModelError
from .rotations import quat_from_dcm
from .variables import output, parameter

# WGS-84 defining parameters: NIMA TR8350.2, 3rd ed. (2000), Table 3.1
WGS84_A = 6378137.0                      # m, semi-major axis
WGS84_F = 1.0 / 298.257223563            # flattening
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)     # first eccentricity squared
WGS84_B = WGS84_A * (1.0 - WGS84_F)      # m, semi-minor axis
EARTH_RATE = 7.2921150e-5                # rad/s, ω_E
MU_EARTH = 3.986004418e14                # m3/s2, GM (atmosphere included)
# Zonal harmonic: EGM96 (Lemoine et al., NASA/TP-1998-206861), unnormalised
# J2 = −√5 C̄20, C̄20 = −4.84165371736e-4; reference radius = WGS-84 a
J2 = 1.08262668e-3
J2_RADIUS = 6378137.0                    # m

SCAN_PITCH_ALTITUDE = 681000.0           # m, DESIGN.md §4.1
SCAN_PITCH_INCLINATION = math.radians(98.1)

TWO_PI = 2.0 * math.pi
_KEPLER_MAX_ITER = 50


def solve_kepler(mean_anomaly: float, e: float) -> float:
    """Eccentric anomaly E in [−π, π] with E − e sin E = M mod 2π (Newton iteration)."""
    M = math.remainder(mean_anomaly, TWO_PI)
    E = M if e < 0.8 else math.copysign(math.pi, M)
    for _ in range(_KEPLER_MAX_ITER):
        step = (E - e * math.sin(E) - M) / (1.0 - e * math.cos(E))
        E -= step
        if abs(step) <= 1e-14:
            return E
    raise ModelError(f"Kepler's equation did not converge (M = {M}, e = {e})")


def wrap_2pi(angle: float) -> float:
    """Angle wrapped to [0, 2π)."""
    wrapped = angle % TWO_PI
    return 0.0 if wrapped >= TWO_PI else wrapped  # -tiny % 2π rounds to 2π


def geodetic_to_ecef(lat: float, lon: float, alt: float) -> tuple[float, float, float]:
    """WGS-84 geodetic latitude, longitude (rad) and height (m) to Earth-fixed x, y, z (m)."""
    s, c = math.sin(lat), math.cos(lat)
    N = WGS84_A / math.sqrt(1.0 - WGS84_E2 * s * s)
    return ((N + alt) * c * math.cos(lon), (N + alt) * c * math.sin(lon),
            (N * (1.0 - WGS84_E2) + alt) * s)


class OrbitEnvironment(Model):
    """Orbit (Kepler, optional secular J2), orbit frame and a rotating-Earth ground target."""

    VARIABLES = (
        parameter("semi_major_axis", WGS84_A + SCAN_PITCH_ALTITUDE, "m",
                  "semi-major axis a (mean value when j2 is set)", display_unit="km"),
        parameter("eccentricity", 0.0, "1", "eccentricity e, 0 <= e < 1"),
        parameter("inclination", SCAN_PITCH_INCLINATION, "rad", "inclination i, 0 <= i <= pi",
                  display_unit="deg"),
        parameter("raan", 0.0, "rad", "right ascension of the ascending node at t = 0",
                  display_unit="deg"),
        parameter("arg_perigee", 0.0, "rad", "argument of perigee at t = 0",
                  display_unit="deg"),
        parameter("true_anomaly0", 0.0, "rad", "true anomaly at t = 0", display_unit="deg"),
        parameter("j2", False, "1", "add the secular J2 drift of raan, arg_perigee and "
                  "mean anomaly", type="Boolean"),
        parameter("earth_angle0", 0.0, "rad", "Earth rotation angle at t = 0 (Earth-fixed x "
                  "from inertial x about z)", display_unit="deg"),
        parameter("target_lat", 0.0, "rad", "ground target geodetic latitude (WGS-84)",
                  display_unit="deg"),
        parameter("target_lon", 0.0, "rad", "ground target longitude (WGS-84)",
                  display_unit="deg"),
        parameter("target_alt", 0.0, "m", "ground target height above the WGS-84 ellipsoid"),
        parameter("mu", MU_EARTH, "m3/s2", "gravitational parameter of the Earth"),
        output("r_I", "m", "satellite position in I", shape=(3,)),
        output("v_I", "m/s", "satellite velocity in I (dr_I/dt)", shape=(3,)),
        output("q_OI", "1", "attitude of the orbit frame O relative to I (scalar first)",
               shape=(4,)),
        output("w_OI_O", "rad/s", "angular velocity of O relative to I, in O", shape=(3,),
               display_unit="deg/s"),
        output("r_T_I", "m", "ground target position in I", shape=(3,)),
        output("v_T_I", "m/s", "ground target velocity in I", shape=(3,)),
        output("earth_angle", "rad", "Earth rotation angle, wrapped to [0, 2 pi)",
               display_unit="deg"),
    )

    def initialize(self, t0):
        p = self.p
        values = {v.name: getattr(p, v.name) for v in self.layout.group("parameter")}
        bad = sorted(name for name, value in values.items() if not math.isfinite(value))
        if bad:
            raise ModelError(f"parameters {bad} must be finite")
        a, e, i, mu = p.semi_major_axis, p.eccentricity, p.inclination, p.mu
        if not a > 0.0:
            raise ModelError(f"semi_major_axis must be > 0 m, got {a}")
        if not 0.0 <= e < 1.0:
            raise ModelError(f"eccentricity must be in [0, 1) (closed orbit), got {e}")
        if not 0.0 <= i <= math.pi:
            raise ModelError(f"inclination must be in [0, pi] rad, got {i}")
        if not mu > 0.0:
            raise ModelError(f"mu must be > 0 m3/s2, got {mu}")
        if not -math.pi / 2 <= p.target_lat <= math.pi / 2:
            raise ModelError(f"target_lat must be in [-pi/2, pi/2] rad, got {p.target_lat}")
        if a * (1.0 - e) < WGS84_B:
            self.warnings.append(f"perigee radius {a * (1.0 - e):.0f} m is below the Earth's "
                                 "surface")

        root = math.sqrt(1.0 - e * e)
        n = math.sqrt(mu / a**3)
        E0 = 2.0 * math.atan2(math.sqrt(1.0 - e) * math.sin(p.true_anomaly0 / 2),
                              math.sqrt(1.0 + e) * math.cos(p.true_anomaly0 / 2))
        raan_rate = argp_rate = 0.0
        mean_motion = n
        if p.j2:
            k = 0.75 * n * J2 * (J2_RADIUS / (a * (1.0 - e * e)))**2
            s2 = math.sin(i)**2
            raan_rate = -2.0 * k * math.cos(i)
            argp_rate = k * (4.0 - 5.0 * s2)
            mean_motion = n + k * root * (2.0 - 3.0 * s2)
        self.a, self.e, self.b = a, e, a * root
        self.M0 = E0 - e * math.sin(E0)
        self.mean_motion, self.raan_rate, self.argp_rate = mean_motion, raan_rate, argp_rate
        self.raan0, self.argp0 = p.raan, p.arg_perigee
        self.cos_i, self.sin_i = math.cos(i), math.sin(i)
        self.mu_kepler = mean_motion**2 * a**3   # = mu without J2
        self.earth_angle0 = p.earth_angle0
        self.r_T_E = geodetic_to_ecef(p.target_lat, p.target_lon, p.target_alt)
        self.t = t0

    def step(self, t, dt):
        self.t = t + dt

    def elements(self, t: float) -> tuple[float, float, float]:
        """(Ω, ω, M) at time t: the secular model's drifting angles."""
        return (self.raan0 + self.raan_rate * t, self.argp0 + self.argp_rate * t,
                self.M0 + self.mean_motion * t)

    def output(self):
        t, a, e, b, y = self.t, self.a, self.e, self.b, self.y
        raan, argp, M = self.elements(t)
        Wr, wr = self.raan_rate, self.argp_rate

        # perifocal position, velocity
        E = solve_kepler(M, e) if e > 0.0 else M
        cE, sE = math.cos(E), math.sin(E)
        one_e = 1.0 - e * cE
        r = a * one_e
        Edot = self.mean_motion / one_e
        xp, yp = a * (cE - e), b * sE
        vxp, vyp = -a * sE * Edot, b * cE * Edot

        # perifocal axes P, Q, W in I: R = R3(−Ω) R1(−i) R3(−ω)
        cO, sO, cw, sw, ci, si = (math.cos(raan), math.sin(raan), math.cos(argp),
                                  math.sin(argp), self.cos_i, self.sin_i)
        Px, Py, Pz = cO * cw - sO * sw * ci, sO * cw + cO * sw * ci, sw * si
        Qx, Qy, Qz = -cO * sw - sO * cw * ci, -sO * sw + cO * cw * ci, cw * si
        Wx, Wy, Wz = sO * si, -cO * si, ci
        rx, ry, rz = xp * Px + yp * Qx, xp * Py + yp * Qy, xp * Pz + yp * Qz
        kx, ky, kz = vxp * Px + vyp * Qx, vxp * Py + vyp * Qy, vxp * Pz + vyp * Qz  # R ṙ_P

        g = -self.mu_kepler / (r * r * r)
        if Wr or wr:  # frame rate Ω_R = Ω̇ ẑ + ω̇ Ŵ
            ox, oy, oz = wr * Wx, wr * Wy, Wr + wr * Wz
            vx, vy, vz = (kx + oy * rz - oz * ry, ky + oz * rx - ox * rz,
                          kz + ox * ry - oy * rx)
            c = wr * Wr   # ω̇ Ω̇ (ẑ × Ŵ) × r, ẑ × Ŵ = (−Wy, Wx, 0)
            ax = g * rx + (oy * kz - oz * ky) + (oy * vz - oz * vy) + c * (Wx * rz)
            ay = g * ry + (oz * kx - ox * kz) + (oz * vx - ox * vz) + c * (Wy * rz)
            az = g * rz + (ox * ky - oy * kx) + (ox * vy - oy * vx) - c * (Wx * rx + Wy * ry)
        else:
            vx, vy, vz = kx, ky, kz
            ax, ay, az = g * rx, g * ry, g * rz

        # orbit frame: z = −r̂, y = −ĥ, x = ĥ × r̂
        hx, hy, hz = ry * vz - rz * vy, rz * vx - rx * vz, rx * vy - ry * vx
        h = math.sqrt(hx * hx + hy * hy + hz * hz)
        ux, uy, uz = rx / r, ry / r, rz / r
        nx, ny, nz = hx / h, hy / h, hz / h
        x_O = (ny * uz - nz * uy, nz * ux - nx * uz, nx * uy - ny * ux)
        a_h = ax * nx + ay * ny + az * nz

        y.r_I[:] = (rx, ry, rz)
        y.v_I[:] = (vx, vy, vz)
        y.q_OI[:] = quat_from_dcm((x_O, (-nx, -ny, -nz), (-ux, -uy, -uz)))
        y.w_OI_O[:] = (0.0, -h / (r * r), -r * a_h / h)

        theta = self.earth_angle0 + EARTH_RATE * t
        cT, sT = math.cos(theta), math.sin(theta)
        xE, yE, zE = self.r_T_E
        xT, yT = cT * xE - sT * yE, sT * xE + cT * yE
        y.r_T_I[:] = (xT, yT, zE)
        y.v_T_I[:] = (-EARTH_RATE * yT, EARTH_RATE * xT, 0.0)
        y.earth_angle = wrap_2pi(theta)
