"""The frames of DESIGN.md §2 on arrays of samples, for what reads a run afterwards (the
report's 3-D view, the CCSDS ephemerides): ``C(q)`` of quaternions (scalar first,
Hamilton, ``v_X = C(q_XY) v_Y``) and the turn about z between I and E (``C_EI =
R3(θ_E)``).  Products of quaternions: :func:`..pointing.quaternion_product`."""

from __future__ import annotations

import numpy as np


def dcm(q) -> np.ndarray:
    """C(q) = (q0² − q·q) 1 + 2 q qᵀ − 2 q0 [q×], (N, 3, 3) of quaternions (N, 4)."""
    q = np.asarray(q, dtype=float)
    q0, v = q[:, 0], q[:, 1:]
    skew = np.zeros((len(q), 3, 3))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    skew -= skew.transpose(0, 2, 1)
    return (
        (q0**2 - (v * v).sum(1))[:, None, None] * np.eye(3)
        + 2 * v[:, :, None] * v[:, None, :]
        - 2 * q0[:, None, None] * skew
    )


def r3(angle) -> np.ndarray:
    """R3(θ): coordinates in the frame turned by θ about z ((N, 3, 3) of N angles, or
    (3, 3) of one), ``C_EI`` of the Earth angle θ_E."""
    c, s = np.cos(angle), np.sin(angle)
    zero, one = np.zeros_like(c), np.ones_like(c)
    rows = [
        np.stack([c, s, zero], -1),
        np.stack([-s, c, zero], -1),
        np.stack([zero, zero, one], -1),
    ]
    return np.stack(rows, -2)


def turn_z(angle: float) -> np.ndarray:
    """The quaternion q_XY of C(q_XY) = R3(angle): (cos α/2, 0, 0, sin α/2)."""
    return np.array([np.cos(angle / 2), 0.0, 0.0, np.sin(angle / 2)])
