"""Low-precision solar ephemeris: the unit Sun direction, Earth-centred, equatorial.

The Astronomical Almanac's low-precision formulae (section C, "Sun"; also [Vallado 2013]
Algorithm 29 and [Meeus 1998] ch. 25), accurate to 0.01° from 1950 to 2050.  With n the
days from J2000.0 (2000-01-01 12:00 TT)::

    L = 280.460° + 0.9856474° n            mean longitude (aberration included)
    g = 357.528° + 0.9856003° n            mean anomaly
    λ = L + 1.915° sin g + 0.020° sin 2g   ecliptic longitude (latitude 0)
    ε = 23.439° − 0.0000004° n             obliquity of the ecliptic
    ŝ = (cos λ, cos ε sin λ, sin ε sin λ)

in the mean equator and equinox of date, which is the TEME frame OrbitEnvironment takes
as I with an epoch or a TLE to within the formulae's accuracy (nutation is < 0.006°).
The time argument is UTC taken as TT: the 69 s difference moves the Sun by 0.0008°.
"""

from __future__ import annotations

import math

from .runtime.jit import jitable

DAY = 86400.0
_DEG = math.pi / 180.0


@jitable
def sun_direction(days: float, seconds: float) -> tuple:
    """Unit Sun direction at ``days`` (whole days) + ``seconds`` from J2000.0."""
    n = days + seconds / DAY
    L = (280.460 + 0.9856474 * n) * _DEG  # not reduced: sin and cos reduce exactly
    g = (357.528 + 0.9856003 * n) * _DEG
    lam = L + (1.915 * math.sin(g) + 0.020 * math.sin(2.0 * g)) * _DEG
    eps = (23.439 - 0.0000004 * n) * _DEG
    s = math.sin(lam)
    return (math.cos(lam), math.cos(eps) * s, math.sin(eps) * s)
