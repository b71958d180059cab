"""Environmental torques: aerodynamic drag, solar radiation pressure, residual dipole.

The surface is a table of flat facets i (unused rows: zero area): area A_i, outward unit
normal n_i and centre of pressure c_i (from the centre of mass), in B.  Facets do not
shadow each other.  Stateless: the outputs are functions of the inputs at each time.

Aerodynamics ([Vallado 2013] ch. 8, [Wertz 1978] ch. 17; free-molecular flat plates).  The
atmosphere co-rotates with the Earth; the flow seen by facet i, in B::

    v_i = C_BI (v_I − ω_E ẑ × r_I) + w_BI_B × c_i,    v̂_i = v_i / |v_i|
    F_i = −½ ρ c_d A_i |v_i|² (n_i · v̂_i) v̂_i     if n_i · v̂_i > 0, else 0
    τ_aero = Σ c_i × F_i

Density ρ(h) at the height h = |r_I| − R above a sphere of the WGS-84 equatorial radius:
``atmosphere`` TABLE is the piecewise exponential of [Vallado 2013] Table 8-4 (CIRA-72,
0–1000 km), ρ = ρ₀ exp(−(h − h₀)/H) with the row of the highest base height h₀ ≤ h (below
0 km the density at 0 km, above 1000 km the last row); EXPONENTIAL is one such row from the
parameters ``rho0``, ``h0``, ``scale_height``.

Solar radiation pressure ([Wertz 1978] ch. 17, [Vallado 2013] ch. 8).  With ŝ the unit
Sun direction in B (the Earth-centred one: the parallax, < 5e-5 rad in LEO, is neglected),
P the pressure at 1 AU and absorption, specular and diffuse fractions ρ_a + ρ_s + ρ_d = 1::

    cos θ_i = n_i · ŝ
    F_i = −P A_i cos θ_i [(1 − ρ_s) ŝ + 2 (ρ_s cos θ_i + ρ_d / 3) n_i]   if cos θ_i > 0
    τ_srp = Σ c_i × F_i,      zero in the Earth's shadow

Shadow: a cylinder of radius R behind the Earth (no penumbra): ``in_eclipse`` when
r_I · ŝ_I < 0 and |r_I − (r_I · ŝ_I) ŝ_I| < R.  The Sun distance is taken as 1 AU
(its ±1.7 % annual change, ±3.4 % in pressure, is neglected).

Magnetic ([Wertz 1978] ch. 17 and appendix H; the degree-1 terms of IGRF-13
[Alken 2021]).  The tilted centred dipole of the Gauss coefficients g₁⁰, g₁¹, h₁¹ at the
reference radius a, in the Earth-fixed frame E (C_EI = R3(earth_angle), as
OrbitEnvironment's)::

    B_E = (a/r)³ [3 (g · r̂) r̂ − g],   g = (g₁¹, h₁¹, g₁⁰),   r̂ = r_E / |r_E|
    τ_mag = m × C_BI C_IE B_E          (m = dipole_B, the residual dipole, A·m²)

(−∇ of the degree-1 potential a (a/r)² (g · r̂)).

Defaults.  IGRF-13 coefficients of 2020.0 (g₁⁰ = −29404.8, g₁¹ = −1450.9,
h₁¹ = 4652.5 nT, a = 6371.2 km).  P = 1361 W/m² / c = 4.54e-6 N/m² (total solar
irradiance [Kopp 2011]).  c_d = 2.2, the usual free-molecular value ([Vallado 2013]
ch. 8).  Estimates, an illustrative satellite: a 1.2 × 1.2 × 1.6 m box with the
centre of mass 5 cm above its centre along +z_B, one 2 × 2 m solar wing on −y_B whose
cells face −z_B; body faces ρ_s 0.1, ρ_d 0.2; cells ρ_s 0.05, ρ_d 0.05; wing back ρ_s 0,
ρ_d 0.2; residual dipole 0.5 A·m² per axis.
"""

from __future__ import annotations

import math

from .model import Model, ModelError
from .rotations import IDENTITY_Q, dcm, rotate
from .sensing import EARTH_RADIUS, EARTH_RATE, norm
from .variables import choice, input_, output, parameter

N_FACETS = 10
#: [Vallado 2013] Table 8-4: base height (km), density at it (kg/m³), scale height (km)
ATMOSPHERE_TABLE = (
    (0.0, 1.225, 7.249), (25.0, 3.899e-2, 6.349), (30.0, 1.774e-2, 6.682),
    (40.0, 3.972e-3, 7.554), (50.0, 1.057e-3, 8.382), (60.0, 3.206e-4, 7.714),
    (70.0, 8.770e-5, 6.549), (80.0, 1.905e-5, 5.799), (90.0, 3.396e-6, 5.382),
    (100.0, 5.297e-7, 5.877), (110.0, 9.661e-8, 7.263), (120.0, 2.438e-8, 9.473),
    (130.0, 8.484e-9, 12.636), (140.0, 3.845e-9, 16.149), (150.0, 2.070e-9, 22.523),
    (180.0, 5.464e-10, 29.740), (200.0, 2.789e-10, 37.105), (250.0, 7.248e-11, 45.546),
    (300.0, 2.418e-11, 53.628), (350.0, 9.518e-12, 53.298), (400.0, 3.725e-12, 58.515),
    (450.0, 1.585e-12, 60.828), (500.0, 6.967e-13, 63.822), (600.0, 1.454e-13, 71.835),
    (700.0, 3.614e-14, 88.667), (800.0, 1.170e-14, 124.64), (900.0, 5.245e-15, 181.05),
    (1000.0, 3.019e-15, 268.00),
)  # fmt: skip
NANOTESLA = 1e-9
IGRF13_2020 = (-29404.8 * NANOTESLA, -1450.9 * NANOTESLA, 4652.5 * NANOTESLA)  # g10 g11 h11
IGRF_RADIUS = 6371200.0  # m
SPEED_OF_LIGHT = 299792458.0  # m/s
SOLAR_PRESSURE = 1361.0 / SPEED_OF_LIGHT  # N/m² at 1 AU

# the illustrative satellite (estimates, module docstring): faces ±x, ±y, ±z, wing front, back
_COM = (0.0, 0.0, 0.05)  # centre of mass from the box centre
_FACES = (  # area, normal, centroid from the box centre, specular, diffuse
    (1.92, (1, 0, 0), (0.6, 0, 0), 0.1, 0.2), (1.92, (-1, 0, 0), (-0.6, 0, 0), 0.1, 0.2),
    (1.92, (0, 1, 0), (0, 0.6, 0), 0.1, 0.2), (1.92, (0, -1, 0), (0, -0.6, 0), 0.1, 0.2),
    (1.44, (0, 0, 1), (0, 0, 0.8), 0.1, 0.2), (1.44, (0, 0, -1), (0, 0, -0.8), 0.1, 0.2),
    (4.0, (0, 0, -1), (0, -2.2, 0), 0.05, 0.05), (4.0, (0, 0, 1), (0, -2.2, 0), 0.0, 0.2),
)  # fmt: skip
_ROWS = _FACES + ((0.0, (0, 0, 0), (0, 0, 0), 0.0, 0.0),) * (N_FACETS - len(_FACES))
_TORQUES = ("tau_aero_B", "tau_srp_B", "tau_mag_B")
_ALL = ("q_BI", "w_BI_B", "r_I", "v_I", "sun_I", "earth_angle")
#: r_I, v_I unconnected: the default orbit (OrbitEnvironment) at t = 0
_A = EARTH_RADIUS + 681000.0
_V = math.sqrt(3.986004418e14 / _A)
_INCLINATION = math.radians(98.1)


class DisturbanceTorques(Model):
    """Aerodynamic, solar-radiation-pressure and residual-dipole torques on a faceted body."""

    VARIABLES = (
        parameter("aero", True, "1", "include the aerodynamic torque", type="Boolean"),
        parameter("srp", True, "1", "include the solar radiation pressure torque", type="Boolean"),
        parameter("magnetic", True, "1", "include the residual-dipole torque", type="Boolean"),
        parameter(
            "facet_area",
            [row[0] for row in _ROWS],
            "m2",
            "area of each facet (0: unused row)",
            shape=(N_FACETS,),
        ),
        parameter(
            "facet_normal_B",
            [row[1] for row in _ROWS],
            "1",
            "outward unit normal of each facet, in B",
            shape=(N_FACETS, 3),
        ),
        parameter(
            "facet_cp_B",
            [tuple(c - o for c, o in zip(row[2], _COM)) for row in _ROWS],
            "m",
            "centre of pressure of each facet from the centre of mass, in B",
            shape=(N_FACETS, 3),
        ),
        parameter(
            "facet_specular",
            [row[3] for row in _ROWS],
            "1",
            "specular reflection fraction rho_s of each facet",
            shape=(N_FACETS,),
        ),
        parameter(
            "facet_diffuse",
            [row[4] for row in _ROWS],
            "1",
            "diffuse reflection fraction rho_d of each facet (absorbed: 1 - rho_s - rho_d)",
            shape=(N_FACETS,),
        ),
        parameter("cd", 2.2, "1", "drag coefficient of every facet"),
        choice(
            "atmosphere",
            0,
            "density model",
            (("TABLE", "Vallado Table 8-4"), ("EXPONENTIAL", "rho0 exp(-(h - h0)/scale_height)")),
        ),
        parameter("rho0", 3.725e-12, "kg/m3", "EXPONENTIAL: density at h0"),
        parameter("h0", 400e3, "m", "EXPONENTIAL: base height", display_unit="km"),
        parameter("scale_height", 58515.0, "m", "EXPONENTIAL: scale height", display_unit="km"),
        parameter("solar_pressure", SOLAR_PRESSURE, "N/m2", "solar radiation pressure at 1 AU"),
        parameter(
            "dipole_B", (0.5, 0.5, 0.5), "A.m2", "residual magnetic dipole, in B", shape=(3,)
        ),
        parameter(
            "igrf_g10", IGRF13_2020[0], "T", "dipole Gauss coefficient g10", display_unit="nT"
        ),
        parameter(
            "igrf_g11", IGRF13_2020[1], "T", "dipole Gauss coefficient g11", display_unit="nT"
        ),
        parameter(
            "igrf_h11", IGRF13_2020[2], "T", "dipole Gauss coefficient h11", display_unit="nT"
        ),
        input_("q_BI", "1", "attitude of B relative to I", IDENTITY_Q, shape=(4,)),
        input_(
            "w_BI_B",
            "rad/s",
            "angular velocity of B relative to I, in B",
            shape=(3,),
            optional="zero: no rotation-induced flow at the facets",
            display_unit="deg/s",
        ),
        input_("r_I", "m", "satellite position in I", (_A, 0.0, 0.0), shape=(3,)),
        input_(
            "v_I",
            "m/s",
            "satellite velocity in I",
            (0.0, _V * math.cos(_INCLINATION), _V * math.sin(_INCLINATION)),
            shape=(3,),
        ),
        input_("sun_I", "1", "unit Sun direction in I", (1.0, 0.0, 0.0), shape=(3,)),
        input_("earth_angle", "rad", "Earth rotation angle (C_EI = R3(earth_angle))"),
        output("tau_ext_B", "N.m", "sum of the included torques, in B", shape=(3,), depends=_ALL),
        output("tau_aero_B", "N.m", "aerodynamic torque, in B", shape=(3,), depends=_ALL[:4]),
        output(
            "tau_srp_B",
            "N.m",
            "solar radiation pressure torque, in B",
            shape=(3,),
            depends=("q_BI", "r_I", "sun_I"),
        ),
        output(
            "tau_mag_B",
            "N.m",
            "residual-dipole torque, in B",
            shape=(3,),
            depends=("q_BI", "r_I", "earth_angle"),
        ),
        output(
            "in_eclipse",
            "1",
            "in the Earth's cylindrical shadow",
            type="Boolean",
            depends=("r_I", "sun_I"),
        ),
        output("density", "kg/m3", "atmospheric density", depends=("r_I",)),
        output(
            "mag_field_B",
            "T",
            "geomagnetic field (tilted dipole), in B",
            shape=(3,),
            depends=("q_BI", "r_I", "earth_angle"),
            display_unit="nT",
        ),
    )

    def initialize(self, t0):
        p = self.p
        facets = []
        for i in range(N_FACETS):
            area, normal = float(p.facet_area[i]), tuple(p.facet_normal_B[i].tolist())
            specular, diffuse = float(p.facet_specular[i]), float(p.facet_diffuse[i])
            if area < 0.0 or not math.isfinite(area):
                raise ModelError(f"facet_area[{i + 1}] must be >= 0, got {area}")
            if area == 0.0:
                continue
            if abs(norm(normal) - 1.0) > 1e-6:
                raise ModelError(f"facet_normal_B[{i + 1},:] must be a unit vector, got {normal}")
            if not (specular >= 0.0 and diffuse >= 0.0 and specular + diffuse <= 1.0):
                raise ModelError(
                    f"facet {i + 1}: facet_specular and facet_diffuse must be >= 0 with a "
                    f"sum <= 1, got {specular} and {diffuse}"
                )
            facets.append((area, normal, tuple(p.facet_cp_B[i].tolist()), specular, diffuse))
        self.facets = tuple(facets)
        if p.atmosphere == 1 and not (p.rho0 >= 0.0 and p.scale_height > 0.0):
            raise ModelError(
                f"rho0 must be >= 0 and scale_height > 0, got {p.rho0} and {p.scale_height}"
            )
        if p.atmosphere not in (0, 1):
            raise ModelError(self.layout.by_name["atmosphere"].choice_error(p.atmosphere))
        if not (p.cd >= 0.0 and p.solar_pressure >= 0.0):
            raise ModelError(f"cd and solar_pressure must be >= 0, got {p.cd}, {p.solar_pressure}")
        self.t = t0

    def step(self, t, dt):
        self.t = t + dt  # stateless between communication points

    def output(self):
        p, u, y = self.p, self.u, self.y
        r = tuple(u.r_I.tolist())
        radius = norm(r)
        if radius == 0.0:
            raise ModelError("r_I is zero: the satellite position is needed")
        k = 1.0 / float(u.q_BI @ u.q_BI)  # C(q) of a non-unit q scales by |q|²
        C_BI = tuple(tuple(k * x for x in row) for row in dcm(u.q_BI.tolist()))
        zero = (0.0, 0.0, 0.0)
        rho = self.density(radius - EARTH_RADIUS)
        aero = self._aero(C_BI, r, rho) if p.aero else zero
        sun = tuple(u.sun_I.tolist())
        eclipse = in_shadow(r, sun)
        srp = self._srp(rotate(C_BI, sun)) if p.srp and not eclipse else zero
        field = rotate(C_BI, self.field_I(r, u.earth_angle))
        m = tuple(p.dipole_B.tolist())
        mag = cross(m, field) if p.magnetic else zero
        y.tau_aero_B[:] = aero
        y.tau_srp_B[:] = srp
        y.tau_mag_B[:] = mag
        y.tau_ext_B[:] = tuple(a + b + c for a, b, c in zip(aero, srp, mag))
        y.in_eclipse = eclipse
        y.density = rho
        y.mag_field_B[:] = field

    # -- the three models ----------------------------------------------------------------
    def density(self, height: float) -> float:
        """Atmospheric density (kg/m³) at ``height`` (m) above the sphere (below 0 m: the
        density at 0 m)."""
        p = self.p
        height = max(height, 0.0)
        if p.atmosphere == 1:
            return p.rho0 * math.exp(-(height - p.h0) / p.scale_height)
        km = height / 1000.0
        row = ATMOSPHERE_TABLE[0]
        for candidate in ATMOSPHERE_TABLE:
            if candidate[0] <= km:
                row = candidate
        h0, rho0, scale = row
        return rho0 * math.exp(-(km - h0) / scale)

    def field_I(self, r: tuple, earth_angle: float) -> tuple:
        """Tilted-dipole geomagnetic field (T) at r_I, in I (module docstring)."""
        p = self.p
        c, s = math.cos(earth_angle), math.sin(earth_angle)
        r_E = (c * r[0] + s * r[1], -s * r[0] + c * r[1], r[2])  # R3(θ) r_I
        radius = norm(r_E)
        x, y_, z = (v / radius for v in r_E)
        g = (p.igrf_g11, p.igrf_h11, p.igrf_g10)
        k = (IGRF_RADIUS / radius) ** 3
        gr = g[0] * x + g[1] * y_ + g[2] * z
        bx, by, bz = (k * (3.0 * gr * v - gv) for v, gv in zip((x, y_, z), g))
        return (c * bx - s * by, s * bx + c * by, bz)  # R3(θ)ᵀ B_E

    def _aero(self, C_BI, r, rho: float) -> tuple:
        u, cd = self.u, self.p.cd
        vx, vy, vz = u.v_I.tolist()
        flow_I = (vx + EARTH_RATE * r[1], vy - EARTH_RATE * r[0], vz)  # v − ω_E ẑ × r
        flow = rotate(C_BI, flow_I)
        w = tuple(u.w_BI_B.tolist())
        torque = [0.0, 0.0, 0.0]
        for area, normal, cp, _, _ in self.facets:
            v = tuple(a + b for a, b in zip(flow, cross(w, cp)))
            speed = norm(v)
            if speed == 0.0:
                continue
            cos = sum(n * x for n, x in zip(normal, v)) / speed
            if cos > 0.0:
                f = -0.5 * rho * cd * area * speed * cos  # times v = speed v̂
                _accumulate(torque, cp, tuple(f * x for x in v))
        return tuple(torque)

    def _srp(self, sun_B: tuple) -> tuple:
        size = norm(sun_B)
        if size == 0.0:
            raise ModelError("sun_I is zero: the Sun direction is needed for the srp torque")
        s = tuple(x / size for x in sun_B)
        pressure = self.p.solar_pressure
        torque = [0.0, 0.0, 0.0]
        for area, normal, cp, specular, diffuse in self.facets:
            cos = sum(n * x for n, x in zip(normal, s))
            if cos > 0.0:
                a = -pressure * area * cos
                along_s, along_n = a * (1.0 - specular), a * 2.0 * (specular * cos + diffuse / 3.0)
                force = tuple(along_s * si + along_n * ni for si, ni in zip(s, normal))
                _accumulate(torque, cp, force)
        return tuple(torque)


def in_shadow(r: tuple, sun: tuple) -> bool:
    """In the cylindrical shadow of a sphere of radius EARTH_RADIUS (sun: any length > 0)."""
    size = norm(sun)
    if size == 0.0:
        return False
    s = tuple(x / size for x in sun)
    along = sum(a * b for a, b in zip(r, s))
    if along >= 0.0:
        return False
    perpendicular = norm(tuple(a - along * b for a, b in zip(r, s)))
    return perpendicular < EARTH_RADIUS


def cross(a, b) -> tuple:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _accumulate(torque: list, arm: tuple, force: tuple) -> None:
    t = cross(arm, force)
    for k in range(3):
        torque[k] += t[k]
