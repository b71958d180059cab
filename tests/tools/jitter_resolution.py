"""How to simulate the CMG rotors' jitter and the arrays' modes: each treatment against the
fine-step monolithic reference (prints the tables of docs/coupling.md, not a test).

    python tests/tools/jitter_resolution.py [--stop 60] [--steps 0.001 0.00025]

scan_pitch:flexible (tests/tools/reference/flexible.py: the same sampled-data system,
controller and steering at 0.05 s, the hub with its six modes, the exact gimbal servo and the
six rotors' imbalance momentum integrated together by classical RK4 at 0.5 ms, a twentieth
of the rotors' 10 ms period; its step halved moves the attitude by the amount printed).

Modes: the coupling error (largest rotation between the co-simulated and the reference
attitude, and |Δω|) of the shipped Jacobi run at 0.05 s, with and without the wings.

Jitter: the rotors' effect on the attitude is the run with them minus the run without
(their common coupling error cancels); its error is that difference against the
reference's.  The treatments:

- ``steady response``: the hub's rotating row (h_extra with h_extra_frequency, as
  shipped): the body's steady response to the rotors in closed form, at 0.05 s;
- ``held row``: the same row without its frequency, integrated as a device (h + ḣ s over
  the step) at 0.05 s: a 100 Hz momentum sampled at 20 Hz;
- ``held torque``: tau_jitter_B into tau_extra, Basilisk's JitterSimple as an external
  torque, at 0.05 s;
- ``multi-rate H``: the held row with the plant (orbit, hub, cluster) at H, controller and
  steering at 0.05 s (orchestration/cosim/multirate.py).

Each with its CPU time (one process, FMUs loaded, the kernels' Python: a short run's tier).
"""

from __future__ import annotations

import argparse
import datetime
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from coupling_cases import attitude_difference

from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import flexible, get
from reference import flexible as reference

CONTROL = 0.05
DIGITAL = ("PitchManeuverController", "CmgSteering")
ROTOR_SPEED = 200.0 * math.pi


def modes() -> dict:
    p = flexible.PARAMETERS
    n = len(p["SatelliteDynamics.modal_frequency"])
    return {
        "frequency": p["SatelliteDynamics.modal_frequency"],
        "damping": p["SatelliteDynamics.modal_damping"],
        "coupling": p["SatelliteDynamics.modal_coupling"],
        "eta0": [0.0] * n,
        "eta_dot0": [0.0] * n,
    }


def rotors() -> dict:
    p = flexible.PARAMETERS
    return {
        "static": p["CmgCluster.static_imbalance"],
        "dynamic": p["CmgCluster.dynamic_imbalance"],
        "position": np.array(p["CmgCluster.rotor_position_B"], dtype=float),
        "phase0": p["CmgCluster.imbalance_phase0"],
        "speed": ROTOR_SPEED,
    }


def system(treatment: str, step: float, where: Path, start: dict | None = None) -> Path:
    """scan_pitch:flexible with the rotors' jitter fed as ``treatment`` at plant step
    ``step`` (a system file); ``start``: added to the hub's initial rate0, eta0, eta_dot0."""
    scenario = get("scan_pitch")
    spec = scenario.system_for("flexible" if treatment != "rigid" else None).copy()
    for name, offset in (start or {}).items():
        key = f"SatelliteDynamics.{name}"
        value = np.asarray(spec.parameters.get(key, np.zeros(len(offset))), dtype=float)
        spec.set(key, (value + offset).tolist())
    if treatment == "no rotors":
        for name in ("static_imbalance", "dynamic_imbalance"):
            spec.set(f"CmgCluster.{name}", [0.0] * 6)
    elif treatment == "held row":
        spec.disconnect("SatelliteDynamics.h_extra_frequency[1]")
    elif treatment == "held torque":
        for target in ("h_extra[1]", "hdot_extra[1]", "h_extra_frequency[1]"):
            spec.disconnect(f"SatelliteDynamics.{target}")
        spec.connect("CmgCluster.tau_jitter_B", "SatelliteDynamics.tau_extra")
    if step != CONTROL:
        spec.step = step
        for name in DIGITAL:
            spec.set_step(name, CONTROL)
    path = where / f"{treatment.replace(' ', '_')}_{step:g}.ssd"
    spec.write(path)
    return path


def run(path: Path, stop: float):
    """(results at the control samples, CPU s)."""
    start = time.process_time()
    results = simulate(path, stop=stop)
    cpu = time.process_time() - start
    every = round(CONTROL / (results.time[1] - results.time[0]))
    return results, every, cpu


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stop", type=float, default=60.0)
    parser.add_argument("--steps", type=float, nargs="+", default=[0.001, 0.00025])
    parser.add_argument("--rk4", type=int, default=100, help="reference RK4 steps per 0.05 s")
    args = parser.parse_args(argv)
    print(
        f"$ python tests/tools/jitter_resolution.py --stop {args.stop:g}  ({datetime.date.today()})"
    )
    reference_cpu = time.process_time()
    truth = reference.scan_pitch_closed_loop(args.stop, modes(), rotors(), rk4_steps=args.rk4)
    reference_cpu = time.process_time() - reference_cpu
    finer = reference.scan_pitch_closed_loop(args.stop, modes(), rotors(), rk4_steps=2 * args.rk4)
    calm = reference.scan_pitch_closed_loop(args.stop, modes())
    rigid = reference.scan_pitch_closed_loop(args.stop, {**modes(), "coupling": np.zeros((6, 3))})
    jitter_true = attitude_difference(calm["q_BI"], truth["q_BI"])
    halved = attitude_difference(truth["q_BI"], finer["q_BI"]).max()
    print(
        f"reference: RK4 at {CONTROL / args.rk4 * 1e3:g} ms, {reference_cpu:.0f} s CPU; its step "
        f"halved moves the attitude by {halved:.2g} rad; the rotors move it by up to "
        f"{jitter_true.max():.3g} rad"
    )
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(tmp)
        print("\nmodes (Jacobi, 0.05 s): coupling error against the reference")
        print("| system | max attitude error [rad] | max abs Δω [rad/s] | CPU [s] |")
        print("|---|---|---|---|")
        for label, treatment, truth_run in (
            ("rigid", "rigid", rigid),
            ("wings, no rotors", "no rotors", calm),
        ):
            results, every, cpu = run(system(treatment, CONTROL, where), args.stop)
            q = results.vector("SatelliteDynamics.q_BI")[::every]
            w = results.vector("SatelliteDynamics.w_BI_B")[::every]
            error = attitude_difference(q, truth_run["q_BI"]).max()
            dw = np.abs(w - truth_run["w_BI_B"]).max()
            print(f"| {label} | {error:.3g} | {dw:.3g} | {cpu:.1f} |")
        print("\nrotor jitter: error of its effect (with − without rotors) against the reference's")
        print("| treatment | plant step [s] | max error of the jitter [rad] | relative | CPU [s] |")
        print("|---|---|---|---|---|")
        cases = [("steady response", CONTROL), ("held row", CONTROL), ("held torque", CONTROL)]
        cases += [("held row", step) for step in args.steps]
        baselines, start = {}, None
        for treatment, step in cases:
            if step not in baselines:
                baselines[step] = run(system("no rotors", step, where), args.stop)
            calm_run, every, _ = baselines[step]
            # a held treatment starts where the rotors have the body at t = 0, as the
            # reference and the steady response do (its mean motion the rotorless one):
            # else the body's mean rate is off by the jitter's rate at t = 0 for good
            held = start if treatment != "steady response" else None
            results, every, cpu = run(system(treatment, step, where, held), args.stop)
            if treatment == "steady response":
                start = {
                    name: results.vector(f"SatelliteDynamics.{output}")[0]
                    - calm_run.vector(f"SatelliteDynamics.{output}")[0]
                    for name, output in (
                        ("rate0", "w_BO_B"), ("eta0", "eta"), ("eta_dot0", "eta_dot")
                    )
                }  # fmt: skip
            effect = quaternion_difference(calm_run, results, every)
            truth_effect = quaternion_difference_reference(calm, truth)
            error = np.linalg.norm(effect - truth_effect, axis=1).max()
            name = treatment if step == CONTROL else "multi-rate (held row)"
            print(
                f"| {name} | {step:g} | {error:.3g} | {error / jitter_true.max():.3g} | {cpu:.1f} |"
            )
    return 0


def quaternion_difference(a, b, every) -> np.ndarray:
    """The rotation vector (body axes) from run a's attitude to run b's at the samples."""
    return rotation(
        a.vector("SatelliteDynamics.q_BI")[::every], b.vector("SatelliteDynamics.q_BI")[::every]
    )


def quaternion_difference_reference(a, b) -> np.ndarray:
    return rotation(a["q_BI"], b["q_BI"])


def rotation(q_a, q_b) -> np.ndarray:
    """Rotation vector of q_a* ⊗ q_b (small angles)."""
    a0, av = q_a[:, :1], q_a[:, 1:]
    b0, bv = q_b[:, :1], q_b[:, 1:]
    vector = a0 * bv - b0 * av - np.cross(av, bv)
    scalar = np.einsum("ij,ij->i", q_a, q_b)[:, None]
    return 2 * np.sign(scalar) * vector


if __name__ == "__main__":
    sys.exit(main())
