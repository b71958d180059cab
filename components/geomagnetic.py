"""The Earth's magnetic field: the tilted centred dipole of IGRF-13's degree-1 terms
([Wertz 1978] ch. 17 and appendix H; [Alken 2021]), the one field model of the toolkit
(DisturbanceTorques computes it for the residual-dipole torque and outputs it as ``b_B``,
which MomentumManager and Magnetorquer take).

With the Gauss coefficients g₁⁰, g₁¹, h₁¹ at the reference radius a, in the Earth-fixed
frame E (C_EI = R3(earth_angle), as OrbitEnvironment's)::

    B_E = (a/r)³ [3 (g · r̂) r̂ − g],   g = (g₁¹, h₁¹, g₁⁰),   r̂ = r_E / |r_E|

(−∇ of the degree-1 potential a (a/r)² (g · r̂)).  Defaults: the coefficients of 2020.0.
"""

from __future__ import annotations

import math

from .runtime.jit import jitable
from .vectors import norm

NANOTESLA = 1e-9
IGRF13_2020 = (-29404.8 * NANOTESLA, -1450.9 * NANOTESLA, 4652.5 * NANOTESLA)  # g10 g11 h11
IGRF_RADIUS = 6371200.0  # m


@jitable
def dipole_field_I(g10: float, g11: float, h11: float, r, earth_angle: float) -> tuple:
    """The dipole field (T) at r_I, in I (module docstring)."""
    c, s = math.cos(earth_angle), math.sin(earth_angle)
    r_E = (c * r[0] + s * r[1], -s * r[0] + c * r[1], r[2])  # R3(θ) r_I
    radius = norm(r_E)
    x, y_, z = r_E[0] / radius, r_E[1] / radius, r_E[2] / radius
    g = (g11, h11, g10)
    k = math.pow(IGRF_RADIUS / radius, 3.0)
    gr = g[0] * x + g[1] * y_ + g[2] * z
    bx = k * (3.0 * gr * x - g[0])
    by = k * (3.0 * gr * y_ - g[1])
    bz = k * (3.0 * gr * z - g[2])
    return (c * bx - s * by, s * bx + c * by, bz)  # R3(θ)ᵀ B_E
