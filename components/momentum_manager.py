"""Momentum management by magnetic unloading: the cross-product law.

The dipole command that unloads a momentum device (CMGs or wheels) towards a target::

    m_cmd = k (h − h_target) × b / |b|²

([Camillo 1980]) gives, with m × b the torque on the body, the
external torque τ = m × b = −k (Δh − (Δh·b̂) b̂) = −k Δh_⊥: the part of Δh = h − h_target
perpendicular to the field is taken out at the rate k; the part along b cannot be (a
magnetic torque is always ⊥ b).  The attitude controller keeps the body's rate, so the
device absorbs τ: ḣ = τ (inertially fixed attitude, h seen in inertial axes).

Orbit-averaged unloading rate.  Averaged over an orbit much shorter than 1/k,
ḣ = −k (1 − ⟨b̂ b̂ᵀ⟩) Δh.  For a dipole along the Earth's axis and a circular polar orbit,
with u the argument of latitude, r̂ = (cos u, 0, sin u) in (ascending node, orbit normal,
pole) axes, b ∝ 3 (ẑ·r̂) r̂ − ẑ = (3 s c, 0, 3 s² − 1), |b|² ∝ 1 + 3 s² (s = sin u,
c = cos u); with D = 1 + 3 s², 9 s² c² / D = 5 − D − 4/D, ⟨D⟩ = 5/2 and
⟨1/D⟩ = 1/√(1·4) = 1/2 (⟨1/(a + b sin² u)⟩ = 1/√(a (a + b))), so

    ⟨b̂_x²⟩ = 5 − 5/2 − 2 = 1/2,   ⟨b̂_z²⟩ = 1/2,   ⟨b̂_y²⟩ = 0,   ⟨b̂_x b̂_z⟩ = 0

and the in-plane components of Δh decay as e^(−k t/2), the orbit-normal one as e^(−k t):
the polar orbit unloads every axis; the average is exact to O(k T_orbit).  The field in B
comes from DisturbanceTorques' field model (its output, the same field the residual dipole
sees).  Stateless.
"""

from __future__ import annotations

import math

from .model import Model, ModelError
from .variables import input_, output, parameter
from .vectors import cross, dot


class MomentumManager(Model):
    """Cross-product unloading law: a dipole command that takes device momentum out."""

    VARIABLES = (
        parameter("gain", 1e-4, "1/s", "unloading gain k: the rate Δh_⊥ is taken out at"),
        parameter(
            "h_target",
            (0.0, 0.0, 0.0),
            "N.m.s",
            "device momentum to unload towards, in B",
            shape=(3,),
        ),
        input_("h_B", "N.m.s", "momentum of the device to manage, in B", shape=(3,)),
        input_("b_B", "T", "geomagnetic field, in B", shape=(3,), display_unit="nT"),
        output(
            "m_cmd_B",
            "A.m2",
            "dipole command k (h - h_target) x b / |b|^2, in B (zero in a zero field)",
            shape=(3,),
            depends=("h_B", "b_B"),
        ),
    )

    def initialize(self, t0):
        if not (math.isfinite(self.p.gain) and self.p.gain >= 0.0):
            raise ModelError(f"gain must be finite and >= 0, got {self.p.gain}")
        self.t = t0

    def step(self, t, dt):
        self.t = t + dt  # stateless between communication points

    def output(self):
        u = self.u
        b = u.b_B.tolist()
        excess = [h - h0 for h, h0 in zip(u.h_B.tolist(), self.p.h_target.tolist())]
        if not all(map(math.isfinite, b + excess)):
            raise ModelError(f"t={self.t:.6g} s: h_B and b_B must be finite")
        field = dot(b, b)
        k = self.p.gain / field if field > 0.0 else 0.0
        self.y.m_cmd_B[:] = [k * x for x in cross(excess, b)]
