"""The Sun direction (components/sun.py, OrbitEnvironment.sun_I) against published values."""

import math

import numpy as np
import pytest

from agilesat.components import orbit_environment, sensing
from agilesat.components.ephemeris import j2000_parts
from agilesat.components.orbit_environment import OrbitEnvironment
from agilesat.components.sun import sun_direction

# the formulae's accuracy (Astronomical Almanac, low precision)
TOLERANCE = math.radians(0.01)


def direction(ra_deg, dec_deg):
    a, d = math.radians(ra_deg), math.radians(dec_deg)
    return np.array([math.cos(d) * math.cos(a), math.cos(d) * math.sin(a), math.sin(d)])


def angle(a, b):
    return math.atan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b))


@pytest.mark.parametrize(
    "epoch, expected",
    [
        # [Meeus 1998] Example 25.a, 1992 October 13.0 TD: apparent α = 198.38083°,
        # δ = −7.78507°
        ("1992-10-13T00:00:00", direction(198.38083, -7.78507)),
        # USNO: March equinox 2024-03-20 03:06 UTC (λ = 0), June solstice 2024-06-20
        # 20:51 UTC (λ = 90°, on the equator's pole side by the obliquity 23.4393°)
        ("2024-03-20T03:06:00", np.array([1.0, 0.0, 0.0])),
        ("2024-06-20T20:51:00", direction(90.0, 23.4393)),
    ],
)
def test_the_sun_direction_matches_published_ephemeris_values(epoch, expected):
    sun = np.array(sun_direction(*j2000_parts(epoch)))
    print(f"{epoch}: {math.degrees(angle(sun, expected)) * 3600:.1f} arcsec from the published")
    assert np.linalg.norm(sun) == pytest.approx(1.0, abs=1e-15)
    assert angle(sun, expected) < TOLERANCE


def test_the_orbit_environment_gives_the_sun_at_its_epoch_plus_t():
    days, seconds = j2000_parts("2016-06-01T06:00:00")
    orbit = OrbitEnvironment(epoch="2016-06-01T06:00:00").start(0.0)
    orbit.advance(0.0, 3600.0)
    assert orbit.get("sun_I").tolist() == list(sun_direction(days, seconds + 3600.0))
    plain = OrbitEnvironment().start(0.0).advance(0.0, 60.0)  # no epoch: J2000.0 + t
    assert plain.get("sun_I").tolist() == list(sun_direction(0, 60.0))


def test_the_sensing_models_use_the_orbit_environments_earth():
    assert sensing.EARTH_RADIUS == orbit_environment.WGS84_A
    assert sensing.EARTH_RATE == orbit_environment.EARTH_RATE
