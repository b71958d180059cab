"""The coupling-error harness of tests/orchestration/cosim/test_coupling.py and
tests/tools/benchmark_coupling.py.

For each scenario: which components are the digital ones (sampled at the control period P,
zero-order hold), the monolithic reference of that sampled-data system (tests/tools/reference/),
and the coupling error of a co-simulation against it at its plant step H:

- ``scan_pitch``: max |pitch(co-simulation) − pitch(reference)| (pitch as the twist of q_BO
  about y), controller and CMG steering at P; reference at 1 ms.
- ``payload_sweep``: max attitude difference (the rotation angle between the two q_BI),
  controller at P; the Flywheel computes its motor torques at its own communication
  points, so the reference's wheel drive runs at H (``drive_period``); the controller's
  payload feedforward at P is the reference's own closed-form sweep; reference at 2.5 ms.
- ``video_sar``: max attitude difference, controller and CMG steering at P; the reference
  takes the guidance at P from the co-simulation it is compared with (open loop, see
  tests/tools/reference/video_sar.py); reference at 2.5 ms.

and, for every scenario, max |Δ w_BI_B| (scan_pitch: w_BO_B).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from agilesat.orchestration.scenarios import get
from reference import payload_sweep, scan_pitch, video_sar

CONTROL = {
    "scan_pitch": ("PitchManeuverController", "CmgSteering"),
    "payload_sweep": ("AttitudeController",),
    "video_sar": ("AttitudeController", "CmgSteering"),
}
#: the reference's own step (every plant step compared is a multiple of it)
FINE = {"scan_pitch": 1e-3, "payload_sweep": 2.5e-3, "video_sar": 2.5e-3}


def twist(q):
    """Pitch as the twist of q_BO about y (well defined through 90°)."""
    q = np.where(q[:, :1] < 0, -q, q)
    return 2 * np.arctan2(q[:, 2], q[:, 0])


def attitude_difference(q_a, q_b):
    """Rotation angle (rad) between the attitudes q_a and q_b (rows), exact for small angles."""
    a0, av = q_a[:, :1], q_a[:, 1:]
    b0, bv = q_b[:, :1], q_b[:, 1:]
    vector = a0 * bv - b0 * av - np.cross(av, bv)  # vector part of q_a* ⊗ q_b
    scalar = np.abs(np.einsum("ij,ij->i", q_a, q_b))
    return 2 * np.arctan2(np.linalg.norm(vector, axis=1), scalar)


def system_file(scenario: str, control: float, fmus: dict, where: Path) -> Path:
    """The scenario with its digital components at their own step ``control``."""
    spec = get(scenario).system.copy()
    for name in CONTROL[scenario]:
        spec.set_step(name, control)
    path = Path(where) / f"{scenario}_P{control}.ssd"
    path.write_bytes(spec.ssd({n: str(fmus[n]) for n in spec.components}))
    return path


def reference(scenario: str, control: float, plant: float, stop: float, recorded=None) -> dict:
    """The monolithic sampled-data reference at its FINE step for a co-simulation with its
    digital components at ``control`` and its plant at ``plant`` (``recorded``: a run of the
    scenario, for video_sar's guidance, open loop)."""
    fine = FINE[scenario]
    if scenario == "scan_pitch":
        return scan_pitch.simulate(fine, stop, control_period=control)
    if scenario == "payload_sweep":
        return payload_sweep.simulate(fine, stop, control_period=control, drive_period=plant)
    guidance = video_sar.guidance_from(recorded, control)
    return video_sar.simulate(fine, stop, guidance, control_period=control)


def errors(scenario: str, results, truth, plant: float) -> tuple[float, float]:
    """(coupling error [deg], max |Δw| [rad/s]) of ``results`` (plant step ``plant``)."""
    every = round(plant / FINE[scenario])
    if not math.isclose(every * FINE[scenario], plant):
        raise ValueError(f"step {plant} s is not a multiple of the reference's {FINE[scenario]} s")
    assert np.allclose(truth["time"][::every], results.time)
    if scenario == "scan_pitch":
        got = twist(results.vector("SatelliteDynamics.q_BO"))
        angle = np.abs(got - twist(truth["q_BO"])[::every])
        rate = "w_BO_B"
    else:
        angle = attitude_difference(
            results.vector("SatelliteDynamics.q_BI"), truth["q_BI"][::every]
        )
        rate = "w_BI_B"
    dw = np.abs(results.vector(f"SatelliteDynamics.{rate}") - truth[rate][::every])
    return math.degrees(angle.max()), float(dw.max())
