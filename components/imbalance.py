"""Rotor microvibration: the static and dynamic imbalance of a spinning rotor (DESIGN.md §3.2),
the one copy CmgCluster and Flywheel use.

A rotor spinning at Ω about the unit axis σ, centred at r from the centre of mass (in B),
with static imbalance U_s (kg·m: a mass off the axis) and dynamic imbalance U_d (kg·m²: a
product of inertia) at angle φ (φ̇ = Ω) has the rotating unit vector::

    e = u cos φ + v sin φ,   v = σ × u                   (u ⊥ σ: the rotor's reference)

and exerts on the body the force and the torque about the centre of mass ([Masterson 2002]'s
fundamental harmonic; Basilisk's JitterSimple writes them so, reactionWheelStateEffector.cpp)::

    F = U_s Ω² e,   τ = U_d Ω² e + r × F

They are minus the rate (as seen in B, at constant Ω and axis) of the imbalance's angular
momentum relative to the body, which is what the hub takes (SatelliteDynamics ``h_extra``,
its rotating rows: the total momentum stays exact)::

    h_u = Ω (U_d w + U_s r × w),   w = σ × e              (ẇ = −Ω e at constant axis)

The rotor's housing may turn relative to the body at ν (a CMG's gimbal: ν = δ̇ g, carrying
σ, u, v along); then ė = Ω w + ν × e and ẇ = −Ω e + ν × w, and the derivatives below are
exact for it and for a changing speed Ω (Ω̇; Ω̈ taken as zero).  Bearing harmonics (2Ω, ball
pass frequencies) are not modelled: we found no source with their amplitudes for these
rotors.
"""

from __future__ import annotations

import math

from .runtime.jit import jitable
from .vectors import add, combine, cross, scale


@jitable
def rotor_imbalance(us, ud, r, spin, u, speed, speed_rate, phase, housing, housing_rate):
    """(h_u, ḣ_u, ḧ_u, F, Ḟ, τ, τ̇) of one rotor (module docstring): static and dynamic
    imbalance ``us``, ``ud``, centre ``r``, axis ``spin``, reference ``u``, speed Ω and its
    rate, angle φ, the housing's angular velocity ν and its rate ν̇ (3-tuples, in B)."""
    c, s = math.cos(phase), math.sin(phase)
    e = combine(c, u, s, cross(spin, u))
    w = cross(spin, e)
    e_dot = add(scale(speed, w), cross(housing, e))
    w_dot = add(scale(-speed, e), cross(housing, w))
    w_ddot = add(
        add(scale(-speed_rate, e), scale(-speed, e_dot)),
        add(cross(housing_rate, w), cross(housing, w_dot)),
    )
    moment = add(scale(ud, w), scale(us, cross(r, w)))
    moment_dot = add(scale(ud, w_dot), scale(us, cross(r, w_dot)))
    moment_ddot = add(scale(ud, w_ddot), scale(us, cross(r, w_ddot)))
    h = scale(speed, moment)
    h_dot = add(scale(speed_rate, moment), scale(speed, moment_dot))
    h_ddot = add(scale(2.0 * speed_rate, moment_dot), scale(speed, moment_ddot))
    squared, squared_rate = speed * speed, 2.0 * speed * speed_rate
    force = scale(us * squared, e)
    force_dot = scale(us, combine(squared_rate, e, squared, e_dot))
    torque = add(scale(ud * squared, e), cross(r, force))
    torque_dot = add(scale(ud, combine(squared_rate, e, squared, e_dot)), cross(r, force_dot))
    return h, h_dot, h_ddot, force, force_dot, torque, torque_dot


def reference_direction(spin) -> tuple:
    """A rotor's reference direction u ⊥ σ for a fixed axis (a wheel's): the body axis
    least aligned with σ (the first of equals), made perpendicular to it; for the axes x,
    y, z of a default assembly: y, x, x."""
    k = min(range(3), key=lambda i: abs(spin[i]))
    axis = [0.0, 0.0, 0.0]
    axis[k] = 1.0
    along = sum(a * b for a, b in zip(axis, spin))
    u = [axis[i] - along * spin[i] for i in range(3)]
    size = math.sqrt(sum(x * x for x in u))
    return tuple(x / size for x in u)
