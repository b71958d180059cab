"""Momentum envelope and singular surfaces of a CMG cluster, with some gyros locked.

Gyro i (gimbal axis g_i) holds momentum h σ_i, σ_i turning in the plane ⊥ g_i; a locked
gyro holds its momentum at the angle it locked at, H_L = h Σ_locked σ_i(δ_i).  The
cluster's torque axes a_i (⊥ g_i and σ_i) lose rank — a singular configuration — exactly
when every healthy a_i is ⊥ one direction u, i.e. every healthy spin is in the plane of
g_i and u: σ_i = ε_i ŝ_i(u), ŝ_i(u) = (u − (g_i·u) g_i)/|u − (g_i·u) g_i|, ε_i = ±1
(Margulies & Aubrun's singular surfaces).  So the singular momenta are

    H(u, ε) = h Σ_healthy ε_i ŝ_i(u) + H_L,    u on the unit sphere

- ε all +1: the saturation (external) surface, the boundary of the momentum envelope.  Its
  support function is h Σ_healthy |u − (g_i·u) g_i| + u·H_L (the Minkowski sum of the
  healthy gyros' circles, shifted by H_L), so the envelope's hull is convex and the
  momentum available along a direction d is its ray distance
  min over u·d > 0 of (support(u)) / (u·d);
- any ε with a −1: internal singular surfaces; the nearest to zero momentum bounds the
  sphere of momenta that no gimbal configuration of the healthy gyros reaches singularly.

Everything here samples u on a Fibonacci sphere (``samples`` points): a capacity is an
upper bound approached as samples grow (the minimum over the samples of a convex body's
ray distance), a nearest singular momentum an upper bound of the true one.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from agilesat.components.cmg_cluster import ClusterGeometry


def sphere(samples: int) -> np.ndarray:
    """``samples`` unit vectors spread evenly (a Fibonacci lattice), rows."""
    k = np.arange(samples) + 0.5
    z = 1.0 - 2.0 * k / samples
    phi = math.pi * (3.0 - math.sqrt(5.0)) * k
    r = np.sqrt(1.0 - z * z)
    return np.column_stack((r * np.cos(phi), r * np.sin(phi), z))


@dataclass(frozen=True)
class Envelope:
    """The envelope of a cluster with its healthy gyros, in N·m·s."""

    healthy: tuple[bool, ...]
    locked_momentum: tuple[float, float, float]  # H_L
    along_axes: dict  # "+x", "-x", ...: the momentum available along each body axis
    capacity: float  # the least momentum available along any direction
    singularity_free: float  # |H| of the nearest internal singular momentum


def envelope(
    geometry: ClusterGeometry, delta, healthy=(True,) * 6, samples: int = 4000
) -> Envelope:
    """The envelope of ``geometry``'s healthy gyros, the others locked at ``delta``
    (module docstring)."""
    healthy = tuple(bool(x) for x in healthy)
    if sum(healthy) < 3:
        raise ValueError(f"{sum(healthy)} healthy gyros cannot make a 3-axis torque")
    h = geometry.h_rotor
    spins = geometry.spins(delta)
    H_L = h * spins[[not x for x in healthy]].sum(axis=0)
    G = geometry.G[list(healthy)]
    u = sphere(samples)
    planar = u[:, None, :] - np.einsum("uk,gk->ug", u, G)[:, :, None] * G[None, :, :]
    lengths = np.linalg.norm(planar, axis=2)  # |u − (g·u) g|, per sample and gyro
    support = h * lengths.sum(axis=1) + u @ H_L

    def available(d) -> float:
        along = u @ d
        ahead = along > 1e-9
        return float(np.min(support[ahead] / along[ahead]))

    axes = {f"{s}{n}": k * e for n, e in zip("xyz", np.eye(3)) for s, k in (("+", 1), ("-", -1))}
    hat = planar / np.where(lengths > 1e-12, lengths, 1.0)[:, :, None]
    nearest = math.inf
    for signs in itertools.product((1.0, -1.0), repeat=len(G)):
        if min(signs) > 0.0:
            continue  # the saturation surface
        H = h * np.einsum("g,ugk->uk", np.array(signs), hat) + H_L
        nearest = min(nearest, float(np.linalg.norm(H, axis=1).min()))
    return Envelope(
        healthy,
        tuple(H_L.tolist()),
        {name: available(d) for name, d in axes.items()},
        min(available(d) for d in sphere(max(samples // 8, 200))),
        nearest,
    )
