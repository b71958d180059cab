"""Basilisk (``bsk`` on PyPI, all-C++ rigid-body and device dynamics) runs of a hub carrying
momentum devices, as references for our SatelliteDynamics with a Flywheel or a CmgCluster
co-simulated by another host (tests/interop/test_end_of_step.py).

    python tests/tools/reference/basilisk_devices.py     # writes basilisk_devices.json

Needs ``bsk`` (``pip install -e '.[basilisk]'``, best in an environment of its own: it pins
older sgp4, tqdm, pandas, matplotlib); the tests read only the JSON it writes, which holds
w_BN_B (our w_BI_B) at every 0.05 s of each case, the cases' values and Basilisk's version.

**wheels**: three reaction wheels (Basilisk's balanced ``reactionWheelStateEffector``) on
x, y, z of a hub with a general inertia, no friction, driven as our Flywheel's drive does,
sampled and held over each 0.05 s: motor torques m = −τ_cmd − ω × h with h = J_s (Ω + ĝᵀω)
ĝ summed (a Python module of the same task, run before the dynamics, reading the states at
the sample time).  The equivalence: Basilisk's wheel obeys J_s (Ω̇ + ĝᵀω̇) = u_s with Ω
relative to the body, so J_s (Ω + ĝᵀω) is our Flywheel's J_w Ω (J_w Ω̇ = m without
friction); its hub equation, with ``IHubPntBc_B`` the whole body's inertia (the balanced
wheels add none of theirs), is (I − Σ J_s ĝĝᵀ) ω̇ = −ω × (I ω + Σ J_s Ω ĝ) − Σ u_s ĝ: ours
with J = I − Σ J_s ĝĝᵀ and h as above.  Both integrate what the other does (RK4 over motion
that is a polynomial over each step but for the gyroscopic term), so they agree to
rounding (checked against a third integration of the same equations, 5e-17 rad/s).

**cmgs**: our default six-CMG five-pyramid cluster (16.65 N·m·s rotors, reversed spin) as
Basilisk's balanced ``vscmgStateEffector`` with spherical rotors and gimbal frames (their
inertia does not change as they turn: our cluster's rigid-hub assumption), the gimbals at
constant rates from t = 0, held there by Basilisk's ``vscmgGimbalRateServo`` (the rotors'
spin left free).  The servo leaves a tracking error of the gimbal rate that falls as 1/gain
(1.7e-4 rad of gimbal angle over the 10 s at gain 20 /s, 8.5e-7 at 4000 /s: ``SERVO_GAIN``)
and, sampled with the dynamics at a rate R, one first order in 1/R: the reference is the
Richardson extrapolation 2 w(16 kHz) − w(8 kHz), its uncertainty the distance to
2 w(8 kHz) − w(4 kHz) (``servo_uncertainty``).  The gimbal frames' and rotors' momentum
about the gimbal axes, Σ (I_W + I_G) δ̇ ĝ, is constant (the rates are): our system gives it
to the hub as ``h_payload`` (``h_gimbals``); the rotors' spin changes with the body rate by
I_W ŝᵀΔω (4e-6 N·m·s here, 4e-9 rad/s on w).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE / "basilisk_devices.json"
STEP, STOP = 0.05, 10.0
#: the gimbal servo's gain (1/s) and the rates it runs at with the dynamics (Hz)
SERVO_GAIN, SERVO_RATES = 4000.0, (4000.0, 8000.0, 16000.0)

WHEELS = {
    "hub_inertia": [[150.0, 2.0, -1.0], [2.0, 140.0, 3.0], [-1.0, 3.0, 160.0]],  # ours, kg.m2
    "rate0": [0.001, -0.002, 0.003],  # w_BI_B at t = 0, rad/s
    "J_wheel": 12.0 / (200.0 * math.pi),  # kg.m2 (HR12, our Flywheel's default)
    "speed0": [100.0, -50.0, 30.0],  # our Flywheel's speeds at t = 0, rad/s
    "tau_cmd": [0.05, -0.08, 0.1],  # N.m, constant
}
CMGS = {
    "hub_inertia": [[956.0, 0.0, 0.0], [0.0, 956.0, 0.0], [0.0, 0.0, 956.0]],
    "rate0": [0.0, 0.0, 0.0],
    "h_rotor": 16.65,
    "I_rotor": 0.002,  # kg.m2, spherical rotor
    "I_gimbal": 0.0005,  # kg.m2, spherical gimbal frame
    "delta_dot_cmd": [0.02, -0.015, 0.01, 0.025, -0.02, 0.005],  # rad/s, constant
}


def five_pyramid() -> tuple[np.ndarray, np.ndarray]:
    """Gimbal axes and reference spins (rows) of [Zhao 2016]'s cluster as DESIGN.md §4.1
    gives it, with the spin reversed (the scenario's default)."""
    c, s = math.cos(math.radians(63.4)), math.sin(math.radians(63.4))
    azimuths = np.radians([90.0, 162.0, 234.0, 306.0, 18.0])
    G = [[-s * math.cos(a), -s * math.sin(a), c] for a in azimuths] + [[0.0, 0.0, 1.0]]
    S = [[c * math.cos(a), c * math.sin(a), s] for a in azimuths] + [[1.0, 0.0, 0.0]]
    return np.array(G), -np.array(S)


GIMBAL_AXES, SPINS = five_pyramid()
DELTA0 = (math.pi / 4, 0.0, -math.pi / 4, math.pi / 2, math.pi / 4, 0.0)


def _task(sim, step: float):
    from Basilisk.utilities import macros

    process = sim.CreateNewProcess("p")
    process.addTask(sim.CreateNewTask("t", macros.sec2nano(step)))


def _spacecraft(hub_inertia, rate0):
    from Basilisk.simulation import spacecraft, svIntegrators

    sc = spacecraft.Spacecraft()
    sc.hub.mHub = 750.0
    sc.hub.IHubPntBc_B = [list(row) for row in hub_inertia]
    sc.hub.omega_BN_BInit = [[x] for x in rate0]
    sc.setIntegrator(svIntegrators.svIntegratorRK4(sc))
    return sc


def wheels() -> list[list[float]]:
    """w_BN_B every STEP of the wheels case (module docstring)."""
    from Basilisk.architecture import messaging, sysModel
    from Basilisk.simulation import reactionWheelStateEffector
    from Basilisk.utilities import SimulationBaseClass, macros, simIncludeRW

    c = WHEELS
    J_s = c["J_wheel"]
    axes = np.eye(3)
    # Basilisk's hub inertia: ours plus the wheels' spin-axis inertia (module docstring)
    hub = np.array(c["hub_inertia"]) + sum(J_s * np.outer(g, g) for g in axes)
    w0 = np.array(c["rate0"])
    sim = SimulationBaseClass.SimBaseClass()
    _task(sim, STEP)
    sc = _spacecraft(hub, w0)
    factory = simIncludeRW.rwFactory()
    for g, speed in zip(axes, c["speed0"]):
        factory.create(
            "custom",
            g.tolist(),
            Omega=(speed - g @ w0) * 60.0 / (2.0 * math.pi),  # relative, rpm
            Js=J_s,
            useMaxTorque=False,
            RWModel=reactionWheelStateEffector.BalancedWheels,
        )
    effector = reactionWheelStateEffector.ReactionWheelStateEffector()
    factory.addToSpacecraft("rw", effector, sc)

    class Drive(sysModel.SysModel):
        """Our Flywheel's drive without friction, sampled at the task's rate."""

        def __init__(self):
            super().__init__()
            self.out = messaging.ArrayMotorTorqueMsg()

        def Reset(self, t):
            pass  # the first command is written at t = 0, before the effector reads it

        def UpdateState(self, t):
            # the states now, at the sample time (the effector's speed message was written
            # before the last integration: a step older)
            w = np.array(sc.scStateOutMsg.read().omega_BN_B)
            speeds = np.array(speed_state.getState()).reshape(-1)[:3]
            h = sum(J_s * (speeds[i] + axes[i] @ w) * axes[i] for i in range(3))
            payload = messaging.ArrayMotorTorqueMsgPayload()
            payload.motorTorque = list(-np.array(c["tau_cmd"]) - np.cross(w, h))
            self.out.write(payload, t, self.moduleID)

    speed_state = None  # the wheels' speed state, once the simulation registered it
    drive = Drive()
    effector.rwMotorCmdInMsg.subscribeTo(drive.out)
    sim.AddModelToTask("t", drive, 200)
    sim.AddModelToTask("t", effector, 100)
    sim.AddModelToTask("t", sc, 50)
    log = sc.scStateOutMsg.recorder(macros.sec2nano(STEP))
    sim.AddModelToTask("t", log)
    sim.InitializeSimulation()
    speed_state = sc.dynManager.getStateObject(effector.nameOfReactionWheelOmegasState)
    sim.ConfigureStopTime(macros.sec2nano(STOP))
    sim.ExecuteSimulation()
    return np.array(log.omega_BN_B).tolist()


def cmgs(rate_hz: float) -> list[list[float]]:
    """w_BN_B every STEP of the CMG case (module docstring), the dynamics and the gimbal
    servo at ``rate_hz``."""
    from Basilisk.architecture import messaging
    from Basilisk.fswAlgorithms import vscmgGimbalRateServo
    from Basilisk.simulation import simpleNav, vscmgStateEffector
    from Basilisk.utilities import SimulationBaseClass, macros

    c = CMGS
    I_w, I_g = c["I_rotor"], c["I_gimbal"]
    omega = c["h_rotor"] / I_w
    sim = SimulationBaseClass.SimBaseClass()
    _task(sim, 1.0 / rate_hz)
    # our hub inertia is the whole rigid body: Basilisk's hub less rotors and gimbals
    hub = np.array(c["hub_inertia"]) - 6 * (I_w + I_g) * np.eye(3)
    sc = _spacecraft(hub, c["rate0"])
    effector = vscmgStateEffector.VSCMGStateEffector()
    config = messaging.VSCMGArrayConfigMsgPayload()
    keep = []
    for g, s, delta, rate in zip(GIMBAL_AXES, SPINS, DELTA0, c["delta_dot_cmd"]):
        t = np.cross(g, s)
        v = messaging.VSCMGConfigMsgPayload()
        v.VSCMGModel = 0  # balanced
        v.ggHat_B, v.gsHat0_B, v.gtHat0_B = ([[x] for x in axis] for axis in (g, s, t))
        v.IW1 = v.IW2 = v.IW3 = I_w
        v.IG1 = v.IG2 = v.IG3 = I_g
        v.Omega, v.gamma, v.gammaDot = omega, delta, rate
        v.u_s_max = v.u_g_max = -1.0
        v.massW = v.massG = 1.0
        v.rGB_B = [[0.0], [0.0], [0.0]]
        v.Omega_max = v.gammaDot_max = -1.0
        effector.AddVSCMG(v)
        keep.append(v)
    sc.addStateEffector(effector)
    nav = simpleNav.SimpleNav()
    nav.scStateInMsg.subscribeTo(sc.scStateOutMsg)
    servo = vscmgGimbalRateServo.VscmgGimbalRateServo()
    servo.setK_gammaDot(SERVO_GAIN)
    refs = messaging.VSCMGRefStatesMsgPayload()
    refs.gimbalRates = list(c["delta_dot_cmd"])
    refs.wheelAccels = [0.0] * 6
    refs_msg = messaging.VSCMGRefStatesMsg().write(refs)
    config.numVSCMG = 6
    config.GgMatrix_B = [x for g in GIMBAL_AXES for x in g]
    config.Gs0Matrix_B = [x for s in SPINS for x in s]
    config.Gt0Matrix_B = [x for g, s in zip(GIMBAL_AXES, SPINS) for x in np.cross(g, s)]
    config.IwsList = [I_w] * 6
    config.JsList = [I_w + I_g] * 6
    config.JtList = [I_w + I_g] * 6
    config.JgList = [I_w + I_g] * 6
    config.Omega0List = [omega] * 6
    config.gamma0List = list(DELTA0)
    config.gammaDot0List = list(c["delta_dot_cmd"])
    config_msg = messaging.VSCMGArrayConfigMsg().write(config)
    servo.vsmcgParamsInMsg.subscribeTo(config_msg)
    servo.vscmgRefStatesInMsg.subscribeTo(refs_msg)
    servo.attInMsg.subscribeTo(nav.attOutMsg)
    servo.speedsInMsg.subscribeTo(effector.speedOutMsg)
    effector.cmdsInMsg.subscribeTo(servo.cmdsOutMsg)
    for model, priority in ((nav, 300), (servo, 200), (effector, 100), (sc, 50)):
        sim.AddModelToTask("t", model, priority)
    log = sc.scStateOutMsg.recorder(macros.sec2nano(STEP))
    sim.AddModelToTask("t", log)
    sim.InitializeSimulation()
    sim.ConfigureStopTime(macros.sec2nano(STOP))
    sim.ExecuteSimulation()
    del keep, refs_msg, config_msg  # alive until here: Basilisk reads them by pointer
    return np.array(log.omega_BN_B).tolist()


def h_gimbals() -> list[float]:
    """Σ (I_W + I_G) δ̇ ĝ of the CMG case: the gimbals' and rotors' momentum about the
    gimbal axes, in B."""
    c = CMGS
    total = sum(rate * g for g, rate in zip(GIMBAL_AXES, c["delta_dot_cmd"]))
    return ((c["I_rotor"] + c["I_gimbal"]) * total).tolist()


if __name__ == "__main__":
    import sys
    from importlib import metadata

    w_wheels = wheels()
    coarse, middle, fine = (np.array(cmgs(rate)) for rate in SERVO_RATES)
    reference = 2.0 * fine - middle
    uncertainty = float(np.max(np.abs(reference - (2.0 * middle - coarse))))
    print(f"cmgs: the servo's Richardson extrapolation within {uncertainty:.3g} rad/s")
    OUT.write_text(
        json.dumps(
            {
                "basilisk": metadata.version("bsk"),
                "step": STEP,
                "stop": STOP,
                "wheels": {**WHEELS, "w_BI_B": w_wheels},
                "cmgs": {
                    **CMGS,
                    "h_gimbals": h_gimbals(),
                    "w_BI_B": reference.tolist(),
                    "servo_uncertainty": uncertainty,
                },
            },
            separators=(",", ":"),
        )
        + "\n"
    )
    print(OUT, file=sys.stderr)
