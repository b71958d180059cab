"""The momentum envelope and singular surfaces of the default cluster, six gyros and five
(one locked), against closed forms and against the gimbal configurations themselves."""

import math

import numpy as np
import pytest

from agilesat.components.cmg_cluster import (
    DEFAULT_SPINS,
    GIMBAL_AXES,
    PYRAMID_HALF_ANGLE,
    ClusterGeometry,
)
from agilesat.orchestration.scenarios.video_sar import DELTA0
from agilesat.orchestration.studies.cmg_envelope import envelope

H = 16.65
GEOMETRY = ClusterGeometry(H, GIMBAL_AXES, DEFAULT_SPINS)


def test_six_gyros_hold_five_rotors_sin_alpha_along_the_pyramid_axis():
    """Along z every pyramid gyro gives h sin α0 and gyro 6 (gimbal along z) nothing: the
    envelope is symmetric about z, so the ray along ±z meets it where its support is."""
    six = envelope(GEOMETRY, DELTA0, samples=8000)
    along_z = 5 * H * math.sin(PYRAMID_HALF_ANGLE)
    assert six.along_axes["+z"] == pytest.approx(along_z, rel=5e-3)
    assert six.along_axes["+z"] >= along_z * (1 - 1e-12)  # sampled: an upper bound
    assert six.capacity <= min(six.along_axes.values())


@pytest.mark.parametrize("locked", [2, 5])
def test_random_gimbal_sets_stay_inside_the_envelope_of_the_healthy_gyros(locked):
    healthy = [i != locked for i in range(6)]
    five = envelope(GEOMETRY, DELTA0, healthy, samples=4000)
    rng = np.random.default_rng(locked)
    delta = np.tile(DELTA0, (20000, 1))
    delta[:, healthy] = rng.uniform(-math.pi, math.pi, (20000, 5))
    momenta = np.array([GEOMETRY.momentum(d) for d in delta])
    for name, bound in five.along_axes.items():
        axis = "xyz".index(name[1])
        reach = momenta[:, axis] if name[0] == "+" else -momenta[:, axis]
        # no gimbal set gets further along an axis than the hull; a few come close
        inside = reach[np.all(np.delete(np.abs(momenta), axis, axis=1) < 0.05 * H, axis=1)]
        assert inside.max() <= bound * (1 + 1e-9)


def test_the_nearest_internal_singularity_is_a_singular_gimbal_set():
    """Rebuild the gimbal angles of singular momenta H(u, ε) and measure Q = det(A Aᵀ) of
    the healthy gyros: zero, and the momentum is H."""
    healthy = [True, True, False, True, True, True]
    u = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    delta = np.array(DELTA0, dtype=float)
    for i in np.flatnonzero(healthy):
        g, s, t = GEOMETRY.G[i], GEOMETRY.S[i], GEOMETRY.T[i]
        hat = (u - (g @ u) * g) / np.linalg.norm(u - (g @ u) * g)
        sign = -1.0 if i == 1 else 1.0  # an internal surface
        delta[i] = math.atan2(sign * hat @ t, sign * hat @ s)
    A = GEOMETRY.jacobian(delta)[:, healthy]
    assert abs(np.linalg.det(A @ A.T)) < 1e-12
    assert np.allclose(A.T @ u, 0.0, atol=1e-12)  # u is the singular direction
    five = envelope(GEOMETRY, DELTA0, healthy, samples=4000)
    assert 0 < five.singularity_free <= np.linalg.norm(GEOMETRY.momentum(delta))


def test_a_locked_gyro_shrinks_the_envelope_and_brings_singularities_near():
    six = envelope(GEOMETRY, DELTA0)
    for locked in range(6):
        five = envelope(GEOMETRY, DELTA0, [i != locked for i in range(6)])
        assert np.linalg.norm(five.locked_momentum) == pytest.approx(H)
        assert five.capacity < 0.65 * six.capacity
        assert five.singularity_free < 0.4 * six.singularity_free
    with pytest.raises(ValueError, match="2 healthy gyros cannot"):
        envelope(GEOMETRY, DELTA0, [True, True, False, False, False, False])
