"""Passes over a ground target: closest approach (zero Doppler), look geometry, pass design.

Plain functions over :class:`.orbit.OrbitEnvironment`: an orbit is given as that model's
parameters (a dict, e.g. ``dict(semi_major_axis=..., epoch=..., target_lat=...)`` or a TLE),
and every quantity below is computed from the model's outputs, so the passes found here are
the ones a simulation of the same configuration flies.

Geometry (all in I, at one time t)
----------------------------------
With ρ = r_I − r_T_I (target to satellite) and the relative velocity v_rel = v_I − v_T_I::

    range rate        ρ̇ = ρ·v_rel / |ρ|        (zero Doppler ⇔ ρ·v_rel = 0)
    squint            asin(ρ̂·v̂_rel)             (0 at zero Doppler)
    look angle        η = ∠(−r̂, −ρ)               (off-nadir angle at the satellite;
                                                   geocentric nadir = z_O of DESIGN.md §2)
    incidence angle   ∠(n̂_T, ρ)                  (at the target, n̂_T the WGS-84 normal)
    elevation         90° − incidence             (target visible ⇔ elevation > 0)
    side              "right" if −ρ·y_O > 0 (y_O = −ĥ: to the right of the velocity
                      when looking down, x_O forward and z_O to nadir), else "left"

The geodetic nadir at the satellite differs from the geocentric one by up to 0.19°
(at 45° latitude), so a "look angle" quoted against the geodetic vertical differs by as
much; the incidence angle is always against the target's geodetic normal.

Closest approach
----------------
``find_passes`` samples ρ·v_rel on a grid over the window, keeps the sign changes from −
to + (local range minima; the + to − ones are range maxima, on the far side of the
Earth) and refines each by a bracketed root search (Illinois false position) to
``time_tol``.  ``find_pass`` returns the closest of the visible ones.

Pass design
-----------
``design_pass`` gives a circular sun-synchronous orbit whose satellite is, at the zero
Doppler time, exactly at zero Doppler with respect to the target and sees it at the
requested look angle on the requested side, on an ascending or descending pass.
Inclination (secular J2 node rate of :mod:`.orbit`, n = √(μ/a³), p = a, e = 0)::

    Ω̇ = −3/2 n J2 (R/a)² cos i = 2π / (365.2421897 d)     (mean tropical year)

Unknowns: the node Ω and argument of latitude u (= true anomaly, ω = 0) at t = 0.  The
two equations, both evaluated on the OrbitEnvironment outputs at the zero-Doppler time::

    F1 = ρ̂·v̂_rel = 0          (zero Doppler)
    F2 = η − η_wanted = 0     (look angle)

are solved by Newton's method with a central-difference Jacobian, from a spherical,
non-rotating first guess: the law of sines in the triangle Earth centre, satellite
(radius a), target (radius ρ_T) gives the Earth central angle γ = asin(a sin η / ρ_T) − η;
at zero Doppler without Earth rotation the target lies in the plane of r and ĥ, so
r̂_T·ĥ = ∓ sin γ (right / left) with ĥ = (sin i sin Ω, −sin i cos Ω, cos i), i.e.
sin(Ω − α_T) = (∓ sin γ − cos i sin β_T) / (sin i cos β_T) (α_T, β_T right ascension and
geocentric latitude of the target); of its two solutions the one whose in-plane angle of
the target u_T has cos u_T > 0 is the ascending pass, the other the descending one, and
u = u_T.  Newton then adds Earth rotation, oblateness of the target position and the J2
velocity terms (3–5 iterations, to 1e-13 rad).
"""

from __future__ import annotations

import datetime
import math
from dataclasses import dataclass

import numpy as np

from ...components.ephemeris import DAY, format_epoch, gmst, parse_epoch, wrap_2pi
from ...components.model import ModelError
from ...components.orbit_environment import (
    MU_EARTH,
    WGS84_A,
    OrbitEnvironment,
    geodetic_to_ecef,
    secular_j2_rates,
)

#: mean tropical year (days), IERS / Astronomical Almanac value for J2000
TROPICAL_YEAR_DAYS = 365.2421897
#: node rate of a sun-synchronous orbit (rad/s): one turn eastward per tropical year
SUN_SYNCHRONOUS_RATE = 2.0 * math.pi / (TROPICAL_YEAR_DAYS * DAY)


@dataclass(frozen=True)
class PassGeometry:
    """Satellite-target geometry at one time (SI units, angles in rad)."""

    time: float  # s, simulation time
    look_angle: float  # off-nadir angle of the target at the satellite (geocentric nadir)
    slant_range: float  # m, |r_I − r_T_I|
    range_rate: float  # m/s, d|ρ|/dt (0 at zero Doppler)
    squint: float  # asin(ρ̂·v̂_rel), 0 at zero Doppler
    incidence_angle: float  # at the target, from its WGS-84 normal
    elevation: float  # of the satellite seen from the target, 90° − incidence
    side: str  # "right" or "left" of the satellite's velocity
    ascending: bool  # satellite moving north (v_z > 0)

    @property
    def visible(self) -> bool:
        return self.elevation > 0.0


class _Orbit:
    """An OrbitEnvironment evaluated at arbitrary times (its outputs depend on t only)."""

    def __init__(self, parameters: dict, target=None):
        parameters = dict(parameters)
        if target is not None:
            parameters.update(zip(("target_lat", "target_lon", "target_alt"), target))
        self.model = OrbitEnvironment(**parameters).start(0.0)
        p = self.model.p
        lat, lon = p.target_lat, p.target_lon
        self.normal_E = (
            math.cos(lat) * math.cos(lon),
            math.cos(lat) * math.sin(lon),
            math.sin(lat),
        )

    def outputs(self, t: float):
        m = self.model
        m.step(0.0, t)
        m.output()
        y = m.y
        return (
            np.array(y.r_I),
            np.array(y.v_I),
            np.array(y.r_T_I),
            np.array(y.v_T_I),
            y.earth_angle,
        )

    def doppler(self, t: float) -> float:
        """ρ·v_rel (m²/s), the zero-Doppler function."""
        r, v, rT, vT, _ = self.outputs(t)
        return float((r - rT) @ (v - vT))

    def geometry(self, t: float) -> PassGeometry:
        r, v, rT, vT, theta = self.outputs(t)
        return look_geometry(r, v, rT, vT, _rotate_to_inertial(self.normal_E, theta), t)


def _rotate_to_inertial(vector_E, theta: float) -> np.ndarray:
    """R3(θ)ᵀ v: Earth-fixed to inertial coordinates."""
    c, s = math.cos(theta), math.sin(theta)
    x, y, z = vector_E
    return np.array([c * x - s * y, s * x + c * y, z])


def look_geometry(r_I, v_I, r_T_I, v_T_I, target_normal_I=None, time: float = 0.0) -> PassGeometry:
    """Look angle, slant range, range rate, squint, incidence, side from the states.

    ``target_normal_I``: the target's ellipsoid normal in I (default: geocentric r̂_T,
    which changes the incidence and elevation by up to 0.19°).
    """
    r, v, rT, vT = (np.asarray(x, dtype=float) for x in (r_I, v_I, r_T_I, v_T_I))
    rho = r - rT
    v_rel = v - vT
    slant = float(np.linalg.norm(rho))
    r_hat = r / np.linalg.norm(r)
    los = -rho / slant  # satellite to target
    look = math.acos(min(1.0, max(-1.0, float(-r_hat @ los))))
    rate = float(rho @ v_rel) / slant
    squint = math.asin(min(1.0, max(-1.0, rate / float(np.linalg.norm(v_rel)))))
    normal = (
        rT / np.linalg.norm(rT)
        if target_normal_I is None
        else np.asarray(target_normal_I, dtype=float) / np.linalg.norm(target_normal_I)
    )
    incidence = math.acos(min(1.0, max(-1.0, float(normal @ rho) / slant)))
    h = np.cross(r, v)
    side = "right" if float(los @ -h) > 0.0 else "left"  # y_O = −ĥ is to the right
    return PassGeometry(
        time=float(time),
        look_angle=look,
        slant_range=slant,
        range_rate=rate,
        squint=squint,
        incidence_angle=incidence,
        elevation=math.pi / 2 - incidence,
        side=side,
        ascending=bool(v[2] > 0),
    )


def _illinois(f, a: float, b: float, fa: float, fb: float, tol: float) -> float:
    """Root of f in [a, b] with f(a) f(b) < 0 (Illinois false position, bisection guard)."""
    side = 0
    for _ in range(200):
        c = (a * fb - b * fa) / (fb - fa)
        if not min(a, b) < c < max(a, b):
            c = 0.5 * (a + b)
        fc = f(c)
        if fc == 0.0 or abs(b - a) < tol:
            return c
        if (fc > 0) == (fb > 0):
            b, fb = c, fc
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            a, fa = c, fc
            if side == 1:
                fb *= 0.5
            side = 1
        if abs(b - a) < tol:
            return c
    raise ModelError(f"zero-Doppler search did not converge in [{a}, {b}]")


def find_passes(
    parameters: dict,
    t_start: float = 0.0,
    t_stop: float = DAY,
    *,
    target=None,
    grid: float = 30.0,
    time_tol: float = 1e-7,
    visible_only: bool = True,
) -> list[PassGeometry]:
    """Every closest approach (range minimum, zero Doppler) to the target in the window.

    ``parameters``: OrbitEnvironment parameters (classical elements or a TLE, epoch,
    target); ``target`` = (lat, lon, alt) in rad, rad, m overrides the target in them.
    ``grid`` (s) must be shorter than the time between a range minimum and the next
    maximum (a quarter orbit is safe).  ``visible_only`` drops minima with the target
    below the satellite's horizon (elevation ≤ 0).  Sorted by time.
    """
    if not t_stop > t_start:
        raise ValueError(f"empty search window [{t_start}, {t_stop}]")
    orbit = _Orbit(parameters, target)
    n = max(2, int(math.ceil((t_stop - t_start) / grid)) + 1)
    times = np.linspace(t_start, t_stop, n)
    values = [orbit.doppler(t) for t in times]
    passes = []
    for k in range(n - 1):
        fa, fb = values[k], values[k + 1]
        if fa < 0.0 <= fb:  # − to +: a range minimum in (t_k, t_k+1]
            t = (
                times[k + 1]
                if fb == 0.0
                else _illinois(orbit.doppler, times[k], times[k + 1], fa, fb, time_tol)
            )
            geometry = orbit.geometry(t)
            if geometry.visible or not visible_only:
                passes.append(geometry)
    return passes


def find_pass(
    parameters: dict,
    t_start: float = 0.0,
    t_stop: float = DAY,
    *,
    target=None,
    grid: float = 30.0,
    time_tol: float = 1e-7,
) -> PassGeometry:
    """The closest approach to the target in the window: of the visible zero-Doppler
    range minima (see :func:`find_passes`), the one with the smallest slant range.
    ModelError if the target is never visible at a range minimum in the window."""
    passes = find_passes(parameters, t_start, t_stop, target=target, grid=grid, time_tol=time_tol)
    if not passes:
        raise ModelError(f"no visible pass over the target in [{t_start}, {t_stop}] s")
    return min(passes, key=lambda g: g.slant_range)


def sun_synchronous_inclination(
    semi_major_axis: float, eccentricity: float = 0.0, mu: float = MU_EARTH
) -> float:
    """Inclination (rad) at which the secular J2 node rate of :mod:`.orbit` is one turn
    per tropical year: cos i = −Ω̇_ss / (3/2 n J2 (R/p)²)."""
    a, e = semi_major_axis, eccentricity
    c = SUN_SYNCHRONOUS_RATE / secular_j2_rates(a, e, 0.0, mu)[0]  # Ω̇ ∝ cos i
    if not -1.0 <= c <= 1.0:
        raise ModelError(f"no sun-synchronous inclination for a = {a} m, e = {e}")
    return math.acos(c)


def design_pass(
    altitude: float,
    target_lat: float,
    target_lon: float,
    target_alt: float,
    epoch,
    look_angle: float,
    side: str = "right",
    node: str = "ascending",
    *,
    t0: float = 0.0,
    j2: bool = True,
) -> dict:
    """A circular sun-synchronous orbit that is at zero Doppler over the target at ``epoch``
    and sees it at ``look_angle`` off nadir on ``side`` ("right"/"left") of the velocity,
    on an ``node`` ("ascending"/"descending") pass.

    ``altitude`` (m) above the WGS-84 equatorial radius (a = 6378137 m + altitude);
    target geodetic (rad, rad, m); ``epoch`` (ISO-8601 UTC or datetime) is the zero-Doppler
    time.  Returns OrbitEnvironment parameters: the classical elements at t = 0 (e = 0,
    ω = 0, ν0 = argument of latitude), ``j2``, the target, and ``epoch`` = zero-Doppler
    time − ``t0``, so that in a simulation from t = 0 the zero Doppler falls at t = t0
    (e.g. t0 = 100 s for 200 s of staring centred on it).  See the module docstring for
    the equations.
    """
    if side not in ("right", "left"):
        raise ValueError(f"side must be 'right' or 'left', got {side!r}")
    if node not in ("ascending", "descending"):
        raise ValueError(f"node must be 'ascending' or 'descending', got {node!r}")
    a = WGS84_A + altitude
    if not altitude > 0.0:
        raise ModelError(f"altitude must be > 0 m, got {altitude}")
    zero_doppler = parse_epoch(epoch)
    r_T_E = geodetic_to_ecef(target_lat, target_lon, target_alt)
    rho_T = math.sqrt(sum(x * x for x in r_T_E))
    horizon = math.asin(min(1.0, rho_T / a))
    if not 0.0 < look_angle < horizon:
        raise ModelError(
            f"look_angle must be in (0, {horizon:.4f}) rad (the horizon from "
            f"{altitude:.0f} m), got {look_angle}"
        )
    parameters = dict(
        semi_major_axis=a,
        eccentricity=0.0,
        inclination=sun_synchronous_inclination(a),
        arg_perigee=0.0,
        j2=bool(j2),
        earth_angle0=0.0,
        epoch=format_epoch(zero_doppler - datetime.timedelta(seconds=t0)),
        target_lat=target_lat,
        target_lon=target_lon,
        target_alt=target_alt,
    )
    r_T = _rotate_to_inertial(r_T_E, gmst(zero_doppler)) / rho_T
    guess = _first_guess(parameters, r_T, rho_T, look_angle, side, node, t0)
    raan, true_anomaly0 = _solve_zero_doppler(parameters, guess, look_angle, side, node, t0)
    parameters.update(raan=raan, true_anomaly0=true_anomaly0)
    return parameters


def _first_guess(parameters, r_T, rho_T, look_angle, side, node, t0) -> np.ndarray:
    """(Ω, u) at t = 0 to start Newton from: the spherical, non-rotating guess at the
    zero-Doppler time (:func:`_spherical_guess`), taken back by ``t0`` at the orbit's
    secular rates (Ω̇, ω̇ + n); an error if no orbit of this inclination sees the target."""
    a, inclination = parameters["semi_major_axis"], parameters["inclination"]
    guess = _spherical_guess(r_T, a, rho_T, look_angle, inclination, side, node)
    if guess is None:
        raise ModelError(
            f"the target at latitude {math.degrees(parameters['target_lat']):.2f}° cannot be "
            f"seen {side} at {math.degrees(look_angle):.2f}° from an orbit of "
            f"inclination {math.degrees(inclination):.2f}°"
        )
    model = OrbitEnvironment(**parameters).start(0.0)  # secular rates to go back by t0
    return guess - t0 * np.array([model.raan_rate, model.argp_rate + model.mean_motion])


def _solve_zero_doppler(parameters, guess, look_angle, side, node, t0) -> tuple[float, float]:
    """(Ω, ν0) in [0, 2π) such that at t = ``t0`` the squint is zero and the look angle is
    ``look_angle`` (Newton on the full model, residuals ≤ 1e-10), seen on ``side`` on an
    ``node`` pass; an error otherwise."""

    def residual(z):
        g = _Orbit(dict(parameters, raan=float(z[0]), true_anomaly0=float(z[1]))).geometry(t0)
        return np.array([g.squint, g.look_angle - look_angle]), g

    z = _newton(residual, guess)
    F, geometry = residual(z)
    if (
        np.max(np.abs(F)) > 1e-10
        or geometry.side != side
        or geometry.ascending != (node == "ascending")
        or not geometry.visible
    ):
        raise ModelError(f"pass design did not converge (residuals {F}, {geometry})")
    return wrap_2pi(float(z[0])), wrap_2pi(float(z[1]))


def _spherical_guess(
    r_T, a: float, rho_T: float, look_angle: float, inclination: float, side: str, node: str
) -> np.ndarray | None:
    """First guess (Ω, u) at the zero-Doppler time: spherical Earth, no rotation, target
    direction ``r_T`` (unit, I axes) at radius ``rho_T``, orbit radius ``a``.  None if no
    orbit of this inclination sees it."""
    alpha, beta = math.atan2(r_T[1], r_T[0]), math.asin(r_T[2])
    gamma = math.asin(a * math.sin(look_angle) / rho_T) - look_angle
    s = (-1.0 if side == "right" else 1.0) * math.sin(gamma)  # r̂_T·ĥ
    ci, si = math.cos(inclination), math.sin(inclination)
    x = (s - ci * math.sin(beta)) / (si * math.cos(beta))
    if abs(x) > 1.0:
        return None
    guess = None
    for node_offset in (math.asin(x), math.pi - math.asin(x)):
        raan = alpha + node_offset
        n_hat = np.array([math.cos(raan), math.sin(raan), 0.0])
        h_hat = np.array([si * math.sin(raan), -si * math.cos(raan), ci])
        u = math.atan2(r_T @ np.cross(h_hat, n_hat), r_T @ n_hat)
        if (math.cos(u) > 0.0) == (node == "ascending"):
            guess = np.array([raan, u])
    return guess


def _newton(residual, z, step: float = 1e-6, tol: float = 1e-13, iterations: int = 30):
    """Newton's method on ``residual(z) -> (F, _)`` with a central-difference Jacobian."""
    for _ in range(iterations):
        F, _ = residual(z)
        J = np.empty((len(z), len(z)))
        for k in range(len(z)):
            dz = np.zeros(len(z))
            dz[k] = step
            J[:, k] = (residual(z + dz)[0] - residual(z - dz)[0]) / (2 * step)
        delta = np.linalg.solve(J, -F)
        z = z + delta
        if np.max(np.abs(delta)) < tol:
            break
    return z
