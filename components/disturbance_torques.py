"""Environmental torques: aerodynamic drag, solar radiation pressure, residual dipole.

The surface is a table of flat facets i (unused rows: zero area): area A_i, outward unit
normal n_i and centre of pressure c_i (from the centre of mass), in B.  Facets do not
shadow each other.  Stateless: the outputs are functions of the inputs at each time, by one
kernel (components/runtime/jit.py) reading the parameters and inputs from the value array.

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

Magnetic: the field B_E of components/geomagnetic.py (the tilted dipole of IGRF-13's
degree-1 terms, the toolkit's one field model), output in B as ``b_B`` for the
magnetorquers and their unloading law::

    τ_mag = m × C_BI C_IE B_E          (m = dipole_B, the residual dipole, A·m²)

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

import numpy as np

from .geomagnetic import IGRF13_2020, dipole_field_I
from .model import Model, ModelError
from .rotations import IDENTITY_Q, dcm
from .runtime.jit import floats, jitable, output_kernel
from .sensing import EARTH_RADIUS, EARTH_RATE
from .variables import choice, input_, output, parameter
from .vectors import cross, dot, norm, rotate

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
            "b_B",
            "T",
            "geomagnetic field (tilted dipole), in B",
            shape=(3,),
            depends=("q_BI", "r_I", "earth_angle"),
            display_unit="nT",
        ),
    )

    def initialize(self, t0):
        p = self.p
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
        if p.atmosphere == 1 and not (p.rho0 >= 0.0 and p.scale_height > 0.0):
            raise ModelError(
                f"rho0 must be >= 0 and scale_height > 0, got {p.rho0} and {p.scale_height}"
            )
        if p.atmosphere not in (0, 1):
            raise ModelError(self.layout.by_name["atmosphere"].choice_error(p.atmosphere))
        if not (p.cd >= 0.0 and p.solar_pressure >= 0.0):
            raise ModelError(f"cd and solar_pressure must be >= 0, got {p.cd}, {p.solar_pressure}")
        self.state = np.zeros(1)  # none: the kernel reads the parameters from the values
        self.t = t0

    #: step() only advances t (the outputs are functions of the inputs)
    STATELESS = True

    def step(self, t, dt):
        self.t = t + dt  # stateless between communication points

    def output(self):
        status = torques_output(self.values, self.state, self.t)
        if status == NO_POSITION:
            raise ModelError("r_I is zero: the satellite position is needed")
        if status == NO_SUN:
            raise ModelError("sun_I is zero: the Sun direction is needed for the srp torque")


# -- kernel (components/runtime/jit.py) -----------------------------------------------
P, U, Y = DisturbanceTorques.names()
#: torques_output's statuses: r_I is zero; sun_I is zero while the srp torque is on
NO_POSITION, NO_SUN = 1, 2
_TABLE = np.array(ATMOSPHERE_TABLE)


@output_kernel(DisturbanceTorques)
def torques_output(values, state, t):
    """The three torques, their sum, the eclipse flag, the density and the field."""
    v = floats(values)
    r = (v[U.r_I], v[U.r_I + 1], v[U.r_I + 2])
    radius = norm(r)
    if radius == 0.0:
        return NO_POSITION
    q = v[U.q_BI : U.q_BI + 4]
    k = 1.0 / (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])  # C(q) scales by |q|²
    (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = dcm(q)
    C_BI = (
        (k * c00, k * c01, k * c02), (k * c10, k * c11, k * c12), (k * c20, k * c21, k * c22)
    )  # fmt: skip
    zero = (0.0, 0.0, 0.0)
    rho = density(v, radius - EARTH_RADIUS)
    aero = _aero(v, C_BI, r, rho) if v[P.aero] != 0.0 else zero
    sun = (v[U.sun_I], v[U.sun_I + 1], v[U.sun_I + 2])
    eclipse = in_shadow(r, sun)
    srp = zero
    if v[P.srp] != 0.0 and not eclipse:
        sun_B = rotate(C_BI, sun)
        if norm(sun_B) == 0.0:
            return NO_SUN
        srp = _srp(v, sun_B)
    g10, g11, h11 = v[P.igrf_g10], v[P.igrf_g11], v[P.igrf_h11]
    field = rotate(C_BI, dipole_field_I(g10, g11, h11, r, v[U.earth_angle]))
    mag = cross(v[P.dipole_B : P.dipole_B + 3], field) if v[P.magnetic] != 0.0 else zero
    for i in range(3):
        values[Y.tau_aero_B + i], values[Y.tau_srp_B + i], values[Y.tau_mag_B + i] = (
            aero[i],
            srp[i],
            mag[i],
        )
        values[Y.tau_ext_B + i] = aero[i] + srp[i] + mag[i]
        values[Y.b_B + i] = field[i]
    values[Y.in_eclipse] = 1.0 if eclipse else 0.0
    values[Y.density] = rho
    return 0


# -- the three models ----------------------------------------------------------------------
@jitable
def density(v, height: float) -> float:
    """Atmospheric density (kg/m³) at ``height`` (m) above the sphere (below 0 m: the
    density at 0 m), with the parameters in the value array ``v``."""
    height = max(height, 0.0)
    if v[P.atmosphere] == 1:
        return v[P.rho0] * math.exp(-(height - v[P.h0]) / v[P.scale_height])
    km = height / 1000.0
    row = 0
    for i in range(len(ATMOSPHERE_TABLE)):
        if _TABLE[i, 0] <= km:
            row = i
    return _TABLE[row, 1] * math.exp(-(km - _TABLE[row, 0]) / _TABLE[row, 2])


@jitable
def _facet(v, i: int) -> tuple:
    """(area, normal, centre of pressure, specular, diffuse) of facet i."""
    n, c = P.facet_normal_B + 3 * i, P.facet_cp_B + 3 * i
    normal, cp = (v[n], v[n + 1], v[n + 2]), (v[c], v[c + 1], v[c + 2])
    return v[P.facet_area + i], normal, cp, v[P.facet_specular + i], v[P.facet_diffuse + i]


@jitable
def _aero(v, C_BI, r, rho: float) -> tuple:
    flow_I = (
        v[U.v_I] + EARTH_RATE * r[1],
        v[U.v_I + 1] - EARTH_RATE * r[0],
        v[U.v_I + 2],
    )  # v − ω_E ẑ × r
    flow = rotate(C_BI, flow_I)
    w = (v[U.w_BI_B], v[U.w_BI_B + 1], v[U.w_BI_B + 2])
    tx = ty = tz = 0.0
    for i in range(N_FACETS):
        area, normal, cp, _, _ = _facet(v, i)
        if area == 0.0:
            continue
        arm = cross(w, cp)
        relative = (flow[0] + arm[0], flow[1] + arm[1], flow[2] + arm[2])
        speed = norm(relative)
        if speed == 0.0:
            continue
        cos = dot(normal, relative) / speed
        if cos > 0.0:
            f = -0.5 * rho * v[P.cd] * area * speed * cos  # times v = speed v̂
            t = cross(cp, (f * relative[0], f * relative[1], f * relative[2]))
            tx, ty, tz = tx + t[0], ty + t[1], tz + t[2]
    return tx, ty, tz


@jitable
def _srp(v, sun_B) -> tuple:
    size = norm(sun_B)
    s = (sun_B[0] / size, sun_B[1] / size, sun_B[2] / size)
    pressure = v[P.solar_pressure]
    tx = ty = tz = 0.0
    for i in range(N_FACETS):
        area, normal, cp, specular, diffuse = _facet(v, i)
        if area == 0.0:
            continue
        cos = dot(normal, s)
        if cos > 0.0:
            a = -pressure * area * cos
            along_s, along_n = a * (1.0 - specular), a * 2.0 * (specular * cos + diffuse / 3.0)
            force = (
                along_s * s[0] + along_n * normal[0],
                along_s * s[1] + along_n * normal[1],
                along_s * s[2] + along_n * normal[2],
            )
            t = cross(cp, force)
            tx, ty, tz = tx + t[0], ty + t[1], tz + t[2]
    return tx, ty, tz


@jitable
def in_shadow(r, sun) -> bool:
    """In the cylindrical shadow of a sphere of radius EARTH_RADIUS (sun: any length > 0)."""
    size = norm(sun)
    if size == 0.0:
        return False
    s = (sun[0] / size, sun[1] / size, sun[2] / size)
    along = dot(r, s)
    if along >= 0.0:
        return False
    return norm((r[0] - along * s[0], r[1] - along * s[1], r[2] - along * s[2])) < EARTH_RADIUS
