"""Basilisk (``bsk`` on PyPI, all-C++ rigid-body and effector dynamics) runs of a hub with a
hinged panel and of a hub with an imbalanced wheel, as references for SatelliteDynamics'
appendage modes and for the Flywheel's jitter in its rows
(tests/components/test_flexible_basilisk.py).

    python tests/tools/reference/basilisk_flexible.py     # writes basilisk_flexible.json

Needs ``bsk`` (best in an environment of its own: it pins older sgp4, tqdm, pandas,
matplotlib; nothing of agilesat is imported here); the tests read only the JSON it writes:
w_BN_B (our w_BI_B) and the panel's angle every 0.05 s of each case, the cases' values and
Basilisk's version.  Each hub weighs 1e7 kg, so that its translation, which Basilisk
integrates and our hub does not, is negligible (the panel's and the wheel's masses move the
centre of mass by < 1e-5 of their offsets).

**panel**: one rigid panel on a torsional hinge (``hingedRigidBodyStateEffector``: mass m,
inertia I_S about its centre of mass S in its frame, S at d from the hinge H along −ŝ₁,
hinge axis ĥ₂, spring k, damper c; ``PANEL``), released at θ₀ with the hub at rest, RK4 at
1 ms; undamped and damped (``DAMPER``).  As one mode of our hub (:func:`panel_mode`):
η = √I_h θ with I_h = I_S,22 + m d² the panel's inertia about the hinge, ω_c = √(k / I_h),
2 ζ ω_c = c / I_h, and L = (I_h ĥ₂ + m d r_H × ĥ₃) / √I_h (its angular momentum about the
centre of mass per unit η̇: S moves at d θ̇ ŝ₃ = d θ̇ ĥ₃ at θ = 0), ``inertia`` the whole
(hub + panel at θ = 0).

**wheel**: one HR12 wheel of 12 N·m·s (U_s = 1.5e-6 kg·m, U_d = 2.2e-7 kg·m²: Basilisk's
simIncludeRW, from Honeywell's datasheet) on z at 600 rad/s relative to the body, motor off,
no friction, centred off the centre of mass, its imbalance's reference direction that of
components/imbalance.py (x for a wheel on z), with ``JitterSimple`` (F and τ applied to the
hub) and ``JitterFullyCoupled`` (the imbalance in the wheel's mass and inertia), RK4 at
1e-4 s, the body at rest at t = 0.  Basilisk's hub inertia is ours plus the wheel's
spin-axis inertia (J_s ẑẑᵀ: its wheel equation is J_s (Ω̇ + ẑᵀω̇) = u_s with Ω relative to
the body, ours takes h = J_s (Ω + ẑᵀω) of the Flywheel's speed; tests/tools/reference/
basilisk_devices.py has the equivalence).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE / "basilisk_flexible.json"
SAMPLE = 0.05
HUB_MASS = 1e7
HUB_INERTIA = [[800.0, 0.0, 0.0], [0.0, 700.0, 0.0], [0.0, 0.0, 600.0]]
PANEL = {
    "mass": 30.0,
    "d": 1.5,
    "k": 200.0,
    "IPntS_S": [[20.0, 0.0, 0.0], [0.0, 25.0, 0.0], [0.0, 0.0, 8.0]],
    "r_HB_B": [0.8, 0.0, 0.5],
    "dcm_HB": [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],  # rows: ĥ₁, ĥ₂, ĥ₃ in B
    "theta0": 0.01,
    "stop": 20.0,
}
DAMPER = {"undamped": 0.0, "damped": 5.0}  # N·m·s/rad
WHEEL = {
    "axis": [0.0, 0.0, 1.0],
    "u": [1.0, 0.0, 0.0],
    "speed": 600.0,
    "position": [0.3, 0.2, 0.1],
    "static": 1.5e-6,
    "dynamic": 2.2e-7,
    "J_s": 12.0 / (200.0 * math.pi),
    "stop": 2.0,
}
JITTER_MODELS = ("simple", "coupled")


def panel_mode(damper: float) -> dict:
    """The panel as one hybrid-coordinate mode of our hub (module docstring)."""
    m, d, k = PANEL["mass"], PANEL["d"], PANEL["k"]
    I_S, R, r_H = np.array(PANEL["IPntS_S"]), np.array(PANEL["dcm_HB"]), np.array(PANEL["r_HB_B"])
    r_S = r_H - d * R[0]
    I_h = I_S[1, 1] + m * d * d
    inertia = (
        np.array(HUB_INERTIA) + R.T @ I_S @ R + m * (r_S @ r_S * np.eye(3) - np.outer(r_S, r_S))
    )
    omega = math.sqrt(k / I_h)
    return {
        "inertia": inertia,
        "coupling": (I_h * R[1] + m * d * np.cross(r_H, R[2])) / math.sqrt(I_h),
        "frequency": omega,
        "damping": damper / (2.0 * I_h * omega),
        "eta0": math.sqrt(I_h) * PANEL["theta0"],
        "sqrt_I_h": math.sqrt(I_h),
    }


def _simulation(step: float, hub_inertia):
    from Basilisk.simulation import spacecraft, svIntegrators
    from Basilisk.utilities import SimulationBaseClass, macros

    sim = SimulationBaseClass.SimBaseClass()
    sim.CreateNewProcess("p").addTask(sim.CreateNewTask("t", macros.sec2nano(step)))
    sc = spacecraft.Spacecraft()
    sc.hub.mHub, sc.hub.IHubPntBc_B = HUB_MASS, [list(row) for row in hub_inertia]
    sc.setIntegrator(svIntegrators.svIntegratorRK4(sc))
    return sim, sc


def _record(sim, sc, stop: float, *extra):
    from Basilisk.utilities import macros

    states = sc.scStateOutMsg.recorder(macros.sec2nano(SAMPLE))
    sim.AddModelToTask("t", sc)
    sim.AddModelToTask("t", states)
    for recorder in extra:
        sim.AddModelToTask("t", recorder)
    sim.InitializeSimulation()
    sim.ConfigureStopTime(macros.sec2nano(stop))
    sim.ExecuteSimulation()
    return states.omega_BN_B.tolist()


def panel(damper: float) -> dict:
    """w_BN_B and θ every SAMPLE of the panel case."""
    from Basilisk.simulation import hingedRigidBodyStateEffector
    from Basilisk.utilities import macros

    sim, sc = _simulation(1e-3, HUB_INERTIA)
    hinged = hingedRigidBodyStateEffector.HingedRigidBodyStateEffector()
    hinged.mass, hinged.d, hinged.k, hinged.c = PANEL["mass"], PANEL["d"], PANEL["k"], damper
    hinged.IPntS_S, hinged.dcm_HB = PANEL["IPntS_S"], PANEL["dcm_HB"]
    hinged.r_HB_B = [[x] for x in PANEL["r_HB_B"]]
    hinged.thetaInit, hinged.thetaDotInit = PANEL["theta0"], 0.0
    sc.addStateEffector(hinged)
    sim.AddModelToTask("t", hinged)
    angle = hinged.hingedRigidBodyOutMsg.recorder(macros.sec2nano(SAMPLE))
    w = _record(sim, sc, PANEL["stop"], angle)
    return {"w_BI_B": w, "theta": angle.theta.tolist()}


def wheel(model: str) -> list:
    """w_BN_B every SAMPLE of the wheel case with Basilisk's jitter ``model``."""
    from Basilisk.architecture import messaging
    from Basilisk.simulation import reactionWheelStateEffector
    from Basilisk.utilities import simIncludeRW

    axis = np.array(WHEEL["axis"])
    sim, sc = _simulation(1e-4, np.array(HUB_INERTIA) + WHEEL["J_s"] * np.outer(axis, axis))
    factory = simIncludeRW.rwFactory()
    kind = {"simple": messaging.JitterSimple, "coupled": messaging.JitterFullyCoupled}[model]
    rw = factory.create(
        "Honeywell_HR12",
        WHEEL["axis"],
        maxMomentum=12.0,
        Omega=WHEEL["speed"] * 30.0 / math.pi,  # rpm
        RWModel=kind,
        rWB_B=WHEEL["position"],
        useRWfriction=False,
        useMaxTorque=False,
    )
    assert (rw.U_s, rw.U_d, rw.Js) == (WHEEL["static"], WHEEL["dynamic"], WHEEL["J_s"])
    rw.w2Hat0_B = [[x] for x in WHEEL["u"]]
    rw.w3Hat0_B = [[x] for x in np.cross(axis, WHEEL["u"])]
    effector = reactionWheelStateEffector.ReactionWheelStateEffector()
    factory.addToSpacecraft("rw", effector, sc)
    command = messaging.ArrayMotorTorqueMsg().write(messaging.ArrayMotorTorqueMsgPayload())
    effector.rwMotorCmdInMsg.subscribeTo(command)
    sim.AddModelToTask("t", effector)
    return _record(sim, sc, WHEEL["stop"])


if __name__ == "__main__":
    from importlib import metadata

    OUT.write_text(
        json.dumps(
            {
                "basilisk": metadata.version("bsk"),
                "sample": SAMPLE,
                "panel": {variant: panel(c) for variant, c in DAMPER.items()},
                "wheel": {model: {"w_BI_B": wheel(model)} for model in JITTER_MODELS},
            }
        )
        + "\n"
    )
    print(f"wrote {OUT}")
