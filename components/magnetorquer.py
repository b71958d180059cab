"""Magnetorquers: three rods along the body axes, the torque of a dipole in the Earth's field.

Each rod i saturates at its largest dipole (per-axis clipping, which turns the dipole's
direction when one rod saturates, as the rods do)::

    m_B,i = max(−m_max,i, min(m_max,i, m_cmd_B,i)),      tau_B = m_B × b_B

b_B is the geomagnetic field in B from the field model DisturbanceTorques computes
(components/disturbance_torques.py): connect its output, so the torquers and the residual
dipole see one field.  Stateless: the rods' coil dynamics (milliseconds) are neglected at
attitude-control time steps.
"""

from __future__ import annotations

import math

import numpy as np

from .model import Model, ModelError
from .variables import input_, output, parameter
from .vectors import cross


class Magnetorquer(Model):
    """Three magnetic torque rods: dipole command to torque m × b, per-axis saturation."""

    VARIABLES = (
        parameter(
            "max_dipole",
            (30.0, 30.0, 30.0),
            "A.m2",
            "largest dipole of the rod along each body axis",
            shape=(3,),
        ),
        input_("m_cmd_B", "A.m2", "commanded dipole, in B", shape=(3,)),
        input_("b_B", "T", "geomagnetic field, in B", shape=(3,), display_unit="nT"),
        output(
            "m_B", "A.m2", "dipole of the rods (saturated), in B", shape=(3,), depends=("m_cmd_B",)
        ),
        output(
            "tau_B",
            "N.m",
            "magnetic torque m_B x b_B on the body, in B",
            shape=(3,),
            depends=("m_cmd_B", "b_B"),
        ),
        output(
            "saturated",
            "1",
            "a rod is at its largest dipole",
            type="Boolean",
            depends=("m_cmd_B",),
        ),
    )

    def initialize(self, t0):
        limit = self.p.max_dipole
        if not (np.all(np.isfinite(limit)) and np.all(limit >= 0.0)):
            raise ModelError(f"max_dipole must be finite and >= 0, got {limit.tolist()}")
        self.t = t0

    def step(self, t, dt):
        self.t = t + dt  # stateless between communication points

    def output(self):
        u, y = self.u, self.y
        limit = self.p.max_dipole.tolist()
        command = u.m_cmd_B.tolist()
        if not all(map(math.isfinite, command + u.b_B.tolist())):
            raise ModelError(f"t={self.t:.6g} s: m_cmd_B and b_B must be finite")
        m = [max(-a, min(a, x)) for a, x in zip(limit, command)]
        y.m_B[:] = m
        y.tau_B[:] = cross(m, u.b_B.tolist())
        y.saturated = any(abs(x) > a for a, x in zip(limit, command))
