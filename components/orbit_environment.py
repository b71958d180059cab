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
Earth rotation angle θ_E(t) = earth_angle0 + ω_E t (without an epoch; with one, GMST, see
below), the Earth-fixed frame E being turned by +θ_E about z from I (C_EI = R3(θ_E)).
Target, WGS-84 geodetic (φ, λ, h)::

    N = a / √(1 − e² sin² φ),  e² = f (2 − f)
    r_T_E = ((N + h) cos φ cos λ, (N + h) cos φ sin λ, (N (1 − e²) + h) sin φ)
    r_T_I = R3(θ_E)ᵀ r_T_E,  v_T_I = θ̇_E ẑ × r_T_I

Epoch and sidereal time
-----------------------
``epoch`` (ISO 8601 UTC) dates t = 0; θ_E(t) is then the Greenwich mean sidereal time
of epoch + t (IAU-82, UT1 = UTC, :mod:`.ephemeris`) and θ̇_E its exact derivative.
``epoch_j2000`` (Real, for hosts without String parameters) gives the same epoch as
seconds since J2000.0 = 2000-01-01T12:00:00 UTC, counted as the String's is (86 400 s per
calendar day, leap seconds not counted), so whole seconds are exact; 0 means none
(J2000.0 itself: give the String).  Giving both is an error.
With an epoch, ``earth_angle0`` must be 0, and classical elements are referred to the
frame that GMST turns into the Earth-fixed one (TEME of the epoch, as for a TLE below).

Sun
---
``sun_I`` is the unit Sun direction (Earth-centred) of the low-precision ephemeris of
components/sun.py at epoch + t, or at J2000.0 + t without an epoch (0.01° accuracy, in the
frame of date, which is I with an epoch or a TLE).

Two-line elements (SGP4)
------------------------
With ``tle_line1`` and ``tle_line2`` set, the orbit is the SGP4 propagation (the ``sgp4``
package, Vallado's code; WGS-72 constants, as TLEs are fitted) of the TLE to epoch + t,
or to t after the TLE's own epoch when ``epoch`` is empty; θ_E is then GMST as above
(from the TLE epoch, which is UTC).  The classical-element parameters, ``j2`` and ``mu``
are not used.  **Approximation: I is TEME** (true equator, mean equinox of date), the
frame SGP4 works in.  Its Earth-fixed frame is R3(GMST) of it, so the satellite-target
geometry is consistent; TEME differs from GCRF by precession-nutation (≈ 0.23° in 2016),
which turns both satellite and target alike and does not matter for their relative
geometry (it would for star trackers or the Sun direction).  TEME rotates by
precession-nutation at < 1e-11 rad/s, which is neglected (TEME taken as inertial).

SGP4's velocity is its own analytic expression, not exactly the derivative of its
position (they differ by up to ≈ 2 cm/s, 3e-6 relative, over an orbit), and it gives no
acceleration.  v_I is SGP4's velocity; q_OI is built from r_I and v_I as above, and
w_OI_O is the exact angular velocity of *that* frame.  With ė_k = w × e_k for the O axes
(e_1, e_2, e_3) = (x_O, y_O, z_O), w·e_1 = ė_2·e_3, w·e_2 = ė_3·e_1, w·e_3 = ė_1·e_2, which gives::

    w_OI_O = (ḣ·r̂/|h|, −ṙ·x_O/r, ḣ·x_O/|h|),   h = r × v

(the Kepler formulas above when ṙ = v and ḣ = r × a).  ṙ and ḣ are fourth-order
central differences of SGP4's r and r × v over ±SGP4_STEP and ±2 SGP4_STEP (truncation
≈ δ⁴ n⁴ / 30 ≈ 6e-13 relative for δ = 2 s; SGP4's round-off gives ≈ 1e-14 rad/s).  Cost:
five SGP4 calls per output, which the compiled kernel makes itself, to the sgp4 package's
own compiled SGP4 (ephemeris.sgp4_entry: the same function, the same bits).

Errors of SGP4 (its error codes: eccentricity out of range, decayed, ...) raise
ModelError naming the code and the time; a TLE is checked for length, line numbers,
checksums, matching catalogue numbers and readable numeric fields before SGP4 sees it.
"""

from __future__ import annotations

import math

import numpy as np

from .ephemeris import (
    DAY,
    TWO_PI,
    j2000_parts,
    load_tle,
    sgp4_at,
    sgp4_entry,
    sidereal_base,
    sidereal_time,
    tle_epoch,
    wrap_2pi,
)
from .model import Model, ModelError
from .rotations import quat_of_rows
from .runtime.flat import remainder, state_table
from .runtime.jit import floats, jitable, output_kernel
from .sun import sun_direction
from .variables import output, parameter

# WGS-84 defining parameters: NIMA TR8350.2, 3rd ed. (2000), Table 3.1
WGS84_A = 6378137.0  # m, semi-major axis
WGS84_F = 1.0 / 298.257223563  # flattening
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)  # first eccentricity squared
WGS84_B = WGS84_A * (1.0 - WGS84_F)  # m, semi-minor axis
EARTH_RATE = 7.2921150e-5  # rad/s, ω_E
MU_EARTH = 3.986004418e14  # m3/s2, GM (atmosphere included)
# Zonal harmonic: EGM96 (Lemoine et al., NASA/TP-1998-206861), unnormalised
# J2 = −√5 C̄20, C̄20 = −4.84165371736e-4; reference radius = WGS-84 a
J2 = 1.08262668e-3
J2_RADIUS = 6378137.0  # m
#: default orbit: the [Zhao 2016] 681 km (DESIGN.md §4.1)
DEFAULT_SEMI_MAJOR_AXIS = WGS84_A + 681000.0

_KEPLER_MAX_ITER = 50

#: step (s) of the central differences that give w_OI_O on the SGP4 path
SGP4_STEP = 2.0
#: TLE older or newer than this (days) against the epoch: warn (SGP4 accuracy degrades)
TLE_AGE_WARNING = 30.0


def solve_kepler(mean_anomaly: float, e: float) -> float:
    """Eccentric anomaly E in [−π, π] with E − e sin E = M mod 2π (Newton iteration)."""
    E, converged = eccentric_anomaly(mean_anomaly, e)
    if not converged:
        M = remainder(mean_anomaly, TWO_PI)
        raise ModelError(f"Kepler's equation did not converge (M = {M}, e = {e})")
    return E


@jitable
def eccentric_anomaly(mean_anomaly: float, e: float) -> tuple[float, bool]:
    """(E, converged) of :func:`solve_kepler`."""
    M = remainder(mean_anomaly, TWO_PI)
    E = M if e < 0.8 else math.copysign(math.pi, M)
    for _ in range(_KEPLER_MAX_ITER):
        step = (E - e * math.sin(E) - M) / (1.0 - e * math.cos(E))
        E -= step
        if abs(step) <= 1e-14:
            return E, True
    return E, False


def _day_parts(seconds: float) -> tuple[int, float]:
    """(whole days, seconds in [0, 86400)) of ``seconds`` since J2000.0."""
    days = math.floor(seconds / DAY)
    return days, seconds - days * DAY


def geodetic_to_ecef(lat: float, lon: float, alt: float) -> tuple[float, float, float]:
    """WGS-84 geodetic latitude, longitude (rad) and height (m) to Earth-fixed x, y, z (m)."""
    s, c = math.sin(lat), math.cos(lat)
    N = WGS84_A / math.sqrt(1.0 - WGS84_E2 * s * s)
    return (
        (N + alt) * c * math.cos(lon),
        (N + alt) * c * math.sin(lon),
        (N * (1.0 - WGS84_E2) + alt) * s,
    )


def secular_j2_rates(
    a: float, e: float, i: float, mu: float = MU_EARTH
) -> tuple[float, float, float]:
    """(Ω̇, ω̇, Ṁ) of the first-order secular J2 model (module docstring)."""
    n = math.sqrt(mu / a**3)
    k = 0.75 * n * J2 * (J2_RADIUS / (a * (1.0 - e * e))) ** 2
    s2 = math.sin(i) ** 2
    return (
        -2.0 * k * math.cos(i),
        k * (4.0 - 5.0 * s2),
        n + k * math.sqrt(1.0 - e * e) * (2.0 - 3.0 * s2),
    )


class OrbitEnvironment(Model):
    """Orbit (Kepler with optional secular J2, or SGP4 from a TLE), orbit frame and a
    rotating-Earth ground target; the Earth angle from GMST when an epoch is given."""

    #: one orbit of the default orbit (681 km: 5,902.5 s), in 10 s steps
    DEFAULT_STEP, DEFAULT_STOP = 10.0, 5910.0

    VARIABLES = (
        # defaults: the [Zhao 2016] orbit, 681 km, 98.1° (DESIGN.md §4.1)
        parameter(
            "semi_major_axis",
            DEFAULT_SEMI_MAJOR_AXIS,
            "m",
            "semi-major axis a (mean value when j2 is set); not used with a TLE",
            display_unit="km",
        ),
        parameter("eccentricity", 0.0, "1", "eccentricity e, 0 <= e < 1; not used with a TLE"),
        parameter(
            "inclination",
            math.radians(98.1),
            "rad",
            "inclination i, 0 <= i <= pi; not used with a TLE",
            display_unit="deg",
        ),
        parameter(
            "raan",
            0.0,
            "rad",
            "right ascension of the ascending node at t = 0; not used with a TLE",
            display_unit="deg",
        ),
        parameter(
            "arg_perigee",
            0.0,
            "rad",
            "argument of perigee at t = 0; not used with a TLE",
            display_unit="deg",
        ),
        parameter(
            "true_anomaly0",
            0.0,
            "rad",
            "true anomaly at t = 0; not used with a TLE",
            display_unit="deg",
        ),
        parameter(
            "j2",
            False,
            "1",
            "add the secular J2 drift of raan, arg_perigee and mean anomaly; not used with a TLE",
            type="Boolean",
        ),
        parameter(
            "earth_angle0",
            0.0,
            "rad",
            "Earth rotation angle at t = 0 (Earth-fixed x "
            "from inertial x about z); must be 0 with an epoch or a TLE, the angle is "
            "then GMST",
            display_unit="deg",
        ),
        parameter(
            "target_lat", 0.0, "rad", "ground target geodetic latitude (WGS-84)", display_unit="deg"
        ),
        parameter("target_lon", 0.0, "rad", "ground target longitude (WGS-84)", display_unit="deg"),
        parameter("target_alt", 0.0, "m", "ground target height above the WGS-84 ellipsoid"),
        parameter(
            "mu", MU_EARTH, "m3/s2", "gravitational parameter of the Earth; not used with a TLE"
        ),
        parameter(
            "epoch",
            "",
            "1",
            "UTC of t = 0, ISO 8601 'YYYY-MM-DDTHH:MM:SS[.ffffff]' "
            "(empty: none). With an epoch the Earth angle is the IAU-82 GMST of "
            "epoch + t (UT1 = UTC) and earth_angle0 must be 0",
            type="String",
        ),
        parameter(
            "epoch_j2000",
            0.0,
            "s",
            "the epoch as seconds since J2000.0 "
            "(2000-01-01T12:00:00 UTC, 86400 s per day, no leap seconds), for hosts "
            "without String parameters; 0: none. Not together with epoch",
        ),
        parameter(
            "tle_line1",
            "",
            "1",
            "line 1 of a two-line element set (empty: use the "
            "classical elements). With a TLE the orbit is SGP4 (WGS-72) in TEME, taken "
            "as I; t = 0 is the epoch, or the TLE epoch without one",
            type="String",
        ),
        parameter("tle_line2", "", "1", "line 2 of the two-line element set", type="String"),
        output("r_I", "m", "satellite position in I", shape=(3,)),
        output(
            "v_I",
            "m/s",
            "satellite velocity in I (dr_I/dt; SGP4's own velocity with a TLE)",
            shape=(3,),
        ),
        output(
            "q_OI", "1", "attitude of the orbit frame O relative to I (scalar first)", shape=(4,)
        ),
        output(
            "w_OI_O",
            "rad/s",
            "angular velocity of O relative to I, in O",
            shape=(3,),
            display_unit="deg/s",
        ),
        output("r_T_I", "m", "ground target position in I", shape=(3,)),
        output("v_T_I", "m/s", "ground target velocity in I", shape=(3,)),
        output(
            "earth_angle", "rad", "Earth rotation angle, wrapped to [0, 2 pi)", display_unit="deg"
        ),
        output(
            "sun_I",
            "1",
            "unit Sun direction in I (low-precision ephemeris at the epoch + t; without "
            "an epoch, J2000.0 + t)",
            shape=(3,),
        ),
    )
    # the SGP4 record cannot be deep-copied and does not evolve, the addresses its kernel
    # calls SGP4 at are this process's: not part of the FMU state
    _NOT_STATE = Model._NOT_STATE | {"_satrec", "_sgp4_entry"}
    #: step() only advances t (the outputs are functions of t)
    STATELESS = True

    def initialize(self, t0):
        p = self.p
        values = {
            v.name: getattr(p, v.name) for v in self.layout.group("parameter") if v.type != "String"
        }
        bad = sorted(name for name, value in values.items() if not math.isfinite(value))
        if bad:
            raise ModelError(f"parameters {bad} must be finite")
        if not -math.pi / 2 <= p.target_lat <= math.pi / 2:
            raise ModelError(f"target_lat must be in [-pi/2, pi/2] rad, got {p.target_lat}")
        epoch, line1, line2 = p.epoch.strip(), p.tle_line1.strip(), p.tle_line2.strip()
        if bool(line1) != bool(line2):
            raise ModelError("tle_line1 and tle_line2 must be given together (or both empty)")

        if epoch and p.epoch_j2000:
            raise ModelError(
                f"the epoch is given twice, as epoch = {epoch!r} and as "
                f"epoch_j2000 = {p.epoch_j2000!r}: give one of them"
            )
        self._epoch = (
            j2000_parts(epoch) if epoch else _day_parts(p.epoch_j2000) if p.epoch_j2000 else None
        )
        self._satrec, self._sgp4_entry = None, (0, 0)
        if line1:
            self._satrec = load_tle(line1, line2)
            self._sgp4_entry = sgp4_entry(self._satrec, load_tle(line1, line2))
            days, seconds = tle_epoch(self._satrec)
            if self._epoch is None:
                self._epoch = (days, seconds)
            offset = (self._epoch[0] - days) * DAY + (self._epoch[1] - seconds)
            self._tsince0 = offset / 60.0  # minutes from the TLE epoch to t = 0
            if abs(offset) > TLE_AGE_WARNING * DAY:
                self.warnings.append(
                    f"the epoch is {offset / DAY:.1f} days from the TLE's: "
                    "SGP4 errors grow by km per day"
                )
        else:
            self._init_kepler()
        self._gmst0 = None if self._epoch is None else sidereal_base(*self._epoch)
        if self._epoch is not None and p.earth_angle0 != 0.0:
            raise ModelError(
                "earth_angle0 must be 0 when an epoch or a TLE is given (the "
                f"Earth angle is then GMST(epoch + t)), got {p.earth_angle0}"
            )
        self.earth_angle0 = p.earth_angle0
        self.r_T_E = geodetic_to_ecef(p.target_lat, p.target_lon, p.target_alt)
        self.state = S.zeros()
        self.state[S.given_at] = math.nan  # no SGP4 samples yet
        if self._satrec is None:
            self.state[S.a : S.mu_kepler + 1] = (
                self.a, self.e, self.b, self.M0, self.mean_motion, self.raan_rate,
                self.argp_rate, self.raan0, self.argp0, self.cos_i, self.sin_i, self.mu_kepler,
            )  # fmt: skip
        self.state[S.earth_angle0] = self.earth_angle0
        self.state[S.r_T_E : S.r_T_E + 3] = self.r_T_E
        self.state[S.given_orbit] = self._satrec is not None
        self.state[S.given_earth] = self._gmst0 is not None
        self.state[S.gmst0 : S.gmst0 + 2] = self._gmst0 or (0.0, 0.0)
        self.state[S.epoch : S.epoch + 2] = self._epoch or (0, 0.0)
        self.t = t0
        if self._satrec is not None:
            self.state[S.tsince0] = self._tsince0
            self._point_at_sgp4()
            self._sgp4(t0)  # SGP4 errors at the start: fail here

    def _point_at_sgp4(self) -> None:
        """The addresses the kernel calls SGP4 at: this instance's record, never a saved
        state's (set_state)."""
        self.state[S.sgp4 : S.sgp4 + 2] = getattr(self, "_sgp4_entry", (0, 0))

    def set_state(self, state) -> None:
        super().set_state(state)
        if isinstance(getattr(self, "state", None), np.ndarray):
            self._point_at_sgp4()

    def _init_kepler(self):
        p = self.p
        a, e, i, mu = p.semi_major_axis, p.eccentricity, p.inclination, p.mu
        if not a > 0.0:
            raise ModelError(f"semi_major_axis must be > 0 m, got {a}")
        if not 0.0 <= e < 1.0:
            raise ModelError(f"eccentricity must be in [0, 1) (closed orbit), got {e}")
        if not 0.0 <= i <= math.pi:
            raise ModelError(f"inclination must be in [0, pi] rad, got {i}")
        if not mu > 0.0:
            raise ModelError(f"mu must be > 0 m3/s2, got {mu}")
        if a * (1.0 - e) < WGS84_B:
            raise ModelError(
                f"the orbit passes inside the Earth: its perigee radius semi_major_axis (1 - "
                f"eccentricity) = {a * (1.0 - e):.0f} m is below the Earth's polar radius "
                f"{WGS84_B:.0f} m"
            )

        E0 = 2.0 * math.atan2(
            math.sqrt(1.0 - e) * math.sin(p.true_anomaly0 / 2),
            math.sqrt(1.0 + e) * math.cos(p.true_anomaly0 / 2),
        )
        raan_rate, argp_rate, mean_motion = (
            secular_j2_rates(a, e, i, mu) if p.j2 else (0.0, 0.0, math.sqrt(mu / a**3))
        )
        self.a, self.e, self.b = a, e, a * math.sqrt(1.0 - e * e)
        self.M0 = E0 - e * math.sin(E0)
        self.mean_motion, self.raan_rate, self.argp_rate = mean_motion, raan_rate, argp_rate
        self.raan0, self.argp0 = p.raan, p.arg_perigee
        self.cos_i, self.sin_i = math.cos(i), math.sin(i)
        self.mu_kepler = mean_motion**2 * a**3  # = mu without J2

    def step(self, t, dt):
        self.t = t + dt

    def _sgp4(self, t: float):
        """SGP4 position (km) and velocity (km/s) in TEME at time t; ModelError on error."""
        error, r, v = self._satrec.sgp4_tsince(self._tsince0 + t / 60.0)
        if error:
            from sgp4.api import SGP4_ERRORS

            raise ModelError(
                f"SGP4 error {error} at t = {t} s: {SGP4_ERRORS.get(error, 'unknown error')}"
            )
        return r, v

    def output(self):
        t = self.t
        status = orbit_output(self.values, self.state, t)
        if status == NOT_GIVEN:  # SGP4 the kernel does not call, or an SGP4 error
            for k, offset in enumerate(SAMPLE_OFFSETS):
                r, v = self._sgp4(t + offset)  # raises its ModelError
                self.state[S.samples + 6 * k : S.samples + 6 * k + 6] = (*r, *v)
            self.state[S.given_at] = t
            status = orbit_output(self.values, self.state, t)
        if status == KEPLER_DIVERGED:
            solve_kepler(elements(self.state.tolist(), t)[2], self.e)  # raises its ModelError


# -- kernel (components/runtime/jit.py) -----------------------------------------------
P, U, Y = OrbitEnvironment.names()
#: the state array: the Kepler/J2 constants (initialize), the Earth's and the target's,
#: whether the orbit is SGP4's (a TLE) and whether θ_E is GMST, SGP4's r, v (km, km/s) at
#: t + SAMPLE_OFFSETS and the t they are of, the addresses of the SGP4 call
#: (ephemeris.sgp4_entry; 0: output() samples it), the TLE's minutes to t = 0, GMST's base
#: (g0, T0: ephemeris.sidereal_base) and the epoch (whole days, seconds since J2000.0; 0
#: without one) for the Sun
S = state_table(
    "OrbitEnvironment state", a=1, e=1, b=1, M0=1, mean_motion=1, raan_rate=1, argp_rate=1,
    raan0=1, argp0=1, cos_i=1, sin_i=1, mu_kepler=1, earth_angle0=1, r_T_E=3, given_orbit=1,
    given_earth=1, samples=30, given_at=1, sgp4=2, tsince0=1, gmst0=2, epoch=2,
)  # fmt: skip
#: the times of SGP4's samples relative to t: t and the central differences' (module doc)
SAMPLE_OFFSETS = (0.0, SGP4_STEP, -SGP4_STEP, 2 * SGP4_STEP, -2 * SGP4_STEP)
#: orbit_output's status: Kepler's equation did not converge (nothing written); SGP4's
#: samples at t are not there (output() takes them: without the direct call, or after an
#: SGP4 error)
KEPLER_DIVERGED, NOT_GIVEN = 1, 2


@output_kernel(OrbitEnvironment)
def orbit_output(values, state, t):
    """The outputs at time t (module docstring): the orbit (Kepler/J2 at t, or the given
    SGP4 r_I, v_I, w_OI_O), the orbit frame O, the Earth angle (earth_angle0 + ω_E t, or
    GMST), the target and the Sun (components/sun.py).  Returns 0,
    KEPLER_DIVERGED or NOT_GIVEN (nothing written)."""
    s = floats(state)
    if s[S.given_orbit]:
        if s[S.given_at] != t:
            if s[S.sgp4] == 0.0:
                return NOT_GIVEN
            for k in range(5):  # in this order: the deep-space integrator keeps its state
                tsince = s[S.tsince0] + (t + SAMPLE_OFFSETS[k]) / 60.0
                if not sgp4_at(s[S.sgp4], s[S.sgp4 + 1], tsince, state, S.samples + 6 * k):
                    return NOT_GIVEN
            state[S.given_at] = t
        r, v, w = sgp4_frame(state[S.samples : S.samples + 30])
    else:
        r, v, w, converged = kepler_state(s, t)
        if not converged:
            return KEPLER_DIVERGED
    (rx, ry, rz), (vx, vy, vz) = r, v

    # orbit frame: z = −r̂, y = −ĥ, x = ĥ × r̂
    hx, hy, hz = ry * vz - rz * vy, rz * vx - rx * vz, rx * vy - ry * vx
    h = math.sqrt(hx * hx + hy * hy + hz * hz)
    r_norm = math.sqrt(rx * rx + ry * ry + rz * rz)
    ux, uy, uz = rx / r_norm, ry / r_norm, rz / r_norm
    nx, ny, nz = hx / h, hy / h, hz / h
    q = quat_of_rows(
        ny * uz - nz * uy, nz * ux - nx * uz, nx * uy - ny * ux, -nx, -ny, -nz, -ux, -uy, -uz
    )
    for k in range(3):
        values[Y.r_I + k], values[Y.v_I + k], values[Y.w_OI_O + k] = r[k], v[k], w[k]
    for k in range(4):
        values[Y.q_OI + k] = q[k]

    if s[S.given_earth]:
        theta, rate = sidereal_time(s[S.gmst0], s[S.gmst0 + 1], t)
    else:
        theta, rate = s[S.earth_angle0] + EARTH_RATE * t, EARTH_RATE
    cT, sT = math.cos(theta), math.sin(theta)
    xE, yE, zE = s[S.r_T_E], s[S.r_T_E + 1], s[S.r_T_E + 2]
    xT, yT = cT * xE - sT * yE, sT * xE + cT * yE
    values[Y.r_T_I], values[Y.r_T_I + 1], values[Y.r_T_I + 2] = xT, yT, zE
    values[Y.v_T_I], values[Y.v_T_I + 1], values[Y.v_T_I + 2] = -rate * yT, rate * xT, 0.0
    values[Y.earth_angle] = wrap_2pi(theta)
    sun = sun_direction(s[S.epoch], s[S.epoch + 1] + t)
    for k in range(3):
        values[Y.sun_I + k] = sun[k]
    return 0


@jitable
def sgp4_frame(samples) -> tuple:
    """r_I, v_I (m, m/s) and w_OI_O of the frame built from them (module docstring) from
    SGP4's r, v (km, km/s) at t + SAMPLE_OFFSETS."""
    rx, ry, rz, vx, vy, vz = samples[0], samples[1], samples[2], samples[3], samples[4], samples[5]
    # 4th-order central differences of r and h = r × v (km, km2/s)
    rd = [0.0, 0.0, 0.0]
    hd = [0.0, 0.0, 0.0]
    for k, weight in ((1, 8.0), (2, -8.0), (3, -1.0), (4, 1.0)):
        x, y, z = samples[6 * k], samples[6 * k + 1], samples[6 * k + 2]
        u, v, w = samples[6 * k + 3], samples[6 * k + 4], samples[6 * k + 5]
        rd[0] += weight * x
        rd[1] += weight * y
        rd[2] += weight * z
        hd[0] += weight * (y * w - z * v)
        hd[1] += weight * (z * u - x * w)
        hd[2] += weight * (x * v - y * u)
    scale = 1.0 / (12.0 * SGP4_STEP)
    hx, hy, hz = ry * vz - rz * vy, rz * vx - rx * vz, rx * vy - ry * vx
    h = math.sqrt(hx * hx + hy * hy + hz * hz)
    r = math.sqrt(rx * rx + ry * ry + rz * rz)
    ux, uy, uz = rx / r, ry / r, rz / r
    nx, ny, nz = hx / h, hy / h, hz / h
    xx, xy, xz = ny * uz - nz * uy, nz * ux - nx * uz, nx * uy - ny * ux  # x_O = ĥ × r̂
    return (
        (1e3 * rx, 1e3 * ry, 1e3 * rz),
        (1e3 * vx, 1e3 * vy, 1e3 * vz),
        (
            scale * (hd[0] * ux + hd[1] * uy + hd[2] * uz) / h,
            -scale * (rd[0] * xx + rd[1] * xy + rd[2] * xz) / r,
            scale * (hd[0] * xx + hd[1] * xy + hd[2] * xz) / h,
        ),
    )


@jitable
def elements(s, t: float) -> tuple[float, float, float]:
    """(Ω, ω, M) at time t: the secular model's drifting angles (classical elements)."""
    return (
        s[S.raan0] + s[S.raan_rate] * t,
        s[S.argp0] + s[S.argp_rate] * t,
        s[S.M0] + s[S.mean_motion] * t,
    )


@jitable
def kepler_state(s, t):
    """r_I, v_I and w_OI_O = (0, w_y, w_z) of the Kepler/J2 model at t (module docstring)
    from the constants in the state ``s``, and whether Kepler's equation converged."""
    a, e, b = s[S.a], s[S.e], s[S.b]
    raan, argp, M = elements(s, t)
    Wr, wr = s[S.raan_rate], s[S.argp_rate]

    # perifocal position, velocity
    E, converged = eccentric_anomaly(M, e) if e > 0.0 else (M, True)
    cE, sE = math.cos(E), math.sin(E)
    one_e = 1.0 - e * cE
    r = a * one_e
    Edot = s[S.mean_motion] / one_e
    xp, yp = a * (cE - e), b * sE
    vxp, vyp = -a * sE * Edot, b * cE * Edot

    # perifocal axes P, Q, W in I: R = R3(−Ω) R1(−i) R3(−ω)
    cO, sO, cw, sw, ci, si = (
        math.cos(raan),
        math.sin(raan),
        math.cos(argp),
        math.sin(argp),
        s[S.cos_i],
        s[S.sin_i],
    )
    Px, Py, Pz = cO * cw - sO * sw * ci, sO * cw + cO * sw * ci, sw * si
    Qx, Qy, Qz = -cO * sw - sO * cw * ci, -sO * sw + cO * cw * ci, cw * si
    Wx, Wy, Wz = sO * si, -cO * si, ci
    rx, ry, rz = xp * Px + yp * Qx, xp * Py + yp * Qy, xp * Pz + yp * Qz
    kx, ky, kz = vxp * Px + vyp * Qx, vxp * Py + vyp * Qy, vxp * Pz + vyp * Qz  # R ṙ_P

    g = -s[S.mu_kepler] / (r * r * r)
    if Wr != 0.0 or wr != 0.0:  # frame rate Ω_R = Ω̇ ẑ + ω̇ Ŵ
        ox, oy, oz = wr * Wx, wr * Wy, Wr + wr * Wz
        vx, vy, vz = (kx + oy * rz - oz * ry, ky + oz * rx - ox * rz, kz + ox * ry - oy * rx)
        c = wr * Wr  # ω̇ Ω̇ (ẑ × Ŵ) × r, ẑ × Ŵ = (−Wy, Wx, 0)
        ax = g * rx + (oy * kz - oz * ky) + (oy * vz - oz * vy) + c * (Wx * rz)
        ay = g * ry + (oz * kx - ox * kz) + (oz * vx - ox * vz) + c * (Wy * rz)
        az = g * rz + (ox * ky - oy * kx) + (ox * vy - oy * vx) - c * (Wx * rx + Wy * ry)
    else:
        vx, vy, vz = kx, ky, kz
        ax, ay, az = g * rx, g * ry, g * rz
    hx, hy, hz = ry * vz - rz * vy, rz * vx - rx * vz, rx * vy - ry * vx
    h = math.sqrt(hx * hx + hy * hy + hz * hz)
    a_h = (ax * hx + ay * hy + az * hz) / h
    return (rx, ry, rz), (vx, vy, vz), (0.0, -h / (r * r), -r * a_h / h), converged
