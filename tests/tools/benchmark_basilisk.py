"""Basilisk (``bsk`` on PyPI, all-C++ dynamics) as a speed anchor for
tests/tools/benchmark_scan_pitch.py: a rigid hub of scan_pitch's and video_sar's inertia
(956 kg.m^2 on each axis; a mass of 750 kg, which Basilisk's hub needs and our attitude-only
SatelliteDynamics has not) with our CmgCluster's six gyros as Basilisk VSCMGs (balanced
model): the five-pyramid gimbals (half-angle 63.4 deg, azimuths 90, 162, 234, 306, 18 deg)
and the sixth along z, the cluster's default rotor spins, 16.65 N.m.s rotors at 6000 rpm,
scan_pitch's initial gimbal angles (Table 1), so the same h = h_rotor sum(s_i cos d_i +
t_i sin d_i) at the start; or three reaction wheels (Honeywell HR16).  RK4 at a given step
and duration, no flight software (constant zero commands): the time of Basilisk's own
dynamics loop alone.  A VSCMG has more states than our gyro (rotor angle and speed besides
the gimbal's angle and rate): the same physics and more.  Optional: ``pip install -e
'.[basilisk]'`` (bsk pins older sgp4, tqdm, pandas, matplotlib; a separate environment
keeps ours intact).  Checked with bsk 2.12.1.

    python tests/tools/benchmark_basilisk.py      # 150 s at 0.05 s, both hubs
    python tests/tools/benchmark_basilisk.py --monte-carlo 40 --stop 200
        # a Monte Carlo of the VSCMG hub (inertia dispersed 3 %): runs per core-second,
        # each run set up and run as Basilisk's MonteCarlo executes one (tests/tools/
        # benchmark_campaign_scale.py prints it beside a video_sar campaign)
"""

from __future__ import annotations

import time

import numpy as np
from Basilisk.architecture import messaging
from Basilisk.simulation import (
    reactionWheelStateEffector,
    spacecraft,
    svIntegrators,
    vscmgStateEffector,
)
from Basilisk.utilities import SimulationBaseClass, macros, simIncludeRW

KINDS = ("vscmg", "rw")
H_ROTOR = 16.65  # N.m.s, scan_pitch's and video_sar's
ROTOR_SPEED = 200.0 * np.pi  # rad/s, components/cmg_cluster.py's ROTOR_SPEED
ALPHA0 = np.radians(63.4)
AZIMUTHS = np.radians([90.0, 162.0, 234.0, 306.0, 18.0])
DELTA0 = (np.pi / 4, 0.0, -np.pi / 4, np.pi / 2, np.pi / 4, 0.0)


def gyros() -> tuple[np.ndarray, np.ndarray]:
    """Gimbal axes g_i and reference spins s_i (rows): gimbals 1-5 from the pyramid's base
    to its apex on +z, g = (-sin a0 cos az, -sin a0 sin az, cos a0); gimbal 6 along z;
    the spins the reverse of (cos a0 cos az, cos a0 sin az, sin a0) and of x."""
    c, s = np.cos(ALPHA0), np.sin(ALPHA0)
    g = [[-s * np.cos(a), -s * np.sin(a), c] for a in AZIMUTHS] + [[0.0, 0.0, 1.0]]
    spin = [[c * np.cos(a), c * np.sin(a), s] for a in AZIMUTHS] + [[1.0, 0.0, 0.0]]
    return np.array(g), -np.array(spin)


def hub_time(kind: str, step: float, stop: float, inertia=None, clock=time.perf_counter) -> float:
    """Time of Basilisk's ExecuteSimulation for the hub ``kind`` (vscmg or rw), by
    ``clock`` (wall by default)."""
    sim = SimulationBaseClass.SimBaseClass()
    proc = sim.CreateNewProcess("p")
    proc.addTask(sim.CreateNewTask("t", macros.sec2nano(step)))
    sc = spacecraft.Spacecraft()
    sc.hub.mHub = 750.0
    sc.hub.IHubPntBc_B = (
        [[956.0, 0, 0], [0, 956.0, 0], [0, 0, 956.0]] if inertia is None else inertia.tolist()
    )
    sc.hub.omega_BN_BInit = [[0.001], [0.002], [0.003]]
    sc.setIntegrator(svIntegrators.svIntegratorRK4(sc))
    keep = []
    if kind == "vscmg":
        eff = vscmgStateEffector.VSCMGStateEffector()
        for g, s, delta0 in zip(*gyros(), DELTA0):
            c = messaging.VSCMGConfigMsgPayload()
            c.VSCMGModel = 0
            t = np.cross(g, s)
            c.ggHat_B = [[g[0]], [g[1]], [g[2]]]
            c.gsHat0_B = [[s[0]], [s[1]], [s[2]]]
            c.gtHat0_B = [[t[0]], [t[1]], [t[2]]]
            c.IW1 = H_ROTOR / ROTOR_SPEED  # about the spin axis: IW1 Omega = h_rotor
            c.IW2, c.IW3, c.IG1, c.IG2, c.IG3 = 0.5 * c.IW1, 0.5 * c.IW1, 0.1, 0.1, 0.1
            c.Omega, c.gamma, c.gammaDot = ROTOR_SPEED, delta0, 0.0
            c.u_s_max = c.u_g_max = -1
            c.massW = c.massG = 1.0
            c.rGB_B = [[0.0], [0.0], [0.0]]
            c.Omega_max = 6000.0  # rad/s
            c.gammaDot_max = -1
            eff.AddVSCMG(c)
            keep.append(c)
        sc.addStateEffector(eff)
        cmd = messaging.VSCMGArrayTorqueMsgPayload()
        msg = messaging.VSCMGArrayTorqueMsg().write(cmd)
        eff.cmdsInMsg.subscribeTo(msg)
        keep += [eff, cmd, msg]
        sim.AddModelToTask("t", eff)
    else:
        f = simIncludeRW.rwFactory()
        for axis in ([1, 0, 0], [0, 1, 0], [0, 0, 1]):
            f.create("Honeywell_HR16", axis, maxMomentum=50.0, Omega=100.0)
        eff = reactionWheelStateEffector.ReactionWheelStateEffector()
        f.addToSpacecraft("rw", eff, sc)
        cmd = messaging.ArrayMotorTorqueMsgPayload()
        msg = messaging.ArrayMotorTorqueMsg().write(cmd)
        eff.rwMotorCmdInMsg.subscribeTo(msg)
        keep += [eff, f, cmd, msg]
        sim.AddModelToTask("t", eff)
    sim.AddModelToTask("t", sc)
    sim.InitializeSimulation()
    sim.ConfigureStopTime(macros.sec2nano(stop))
    start = clock()
    sim.ExecuteSimulation()
    elapsed = clock() - start
    return elapsed


def monte_carlo(runs: int, step: float, stop: float, seed: int = 1) -> tuple[float, float]:
    """(CPU seconds per run, of it in ExecuteSimulation) of ``runs`` VSCMG-hub runs, each
    built, initialised and run in this process with the hub inertia dispersed by 3 %."""
    rng = np.random.default_rng(seed)
    began, inside = time.process_time(), 0.0
    for _ in range(runs):
        inertia = np.diag(956.0 * (1.0 + 0.03 * rng.normal(size=3)))
        inside += hub_time("vscmg", step, stop, inertia, time.process_time)
    return (time.process_time() - began) / runs, inside / runs


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--monte-carlo", type=int, default=0)
    parser.add_argument("--stop", type=float, default=150.0)
    args = parser.parse_args()
    if args.monte_carlo:
        per_run, inside = monte_carlo(args.monte_carlo, 0.05, args.stop)
        print(f"{per_run} {inside}")
    else:
        for kind in KINDS:
            print(kind, f"{hub_time(kind, 0.05, args.stop):.3f} s")
