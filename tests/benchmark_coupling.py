"""Coupling accuracy of the co-simulation: prints a report (not a test).

    python tests/benchmark_coupling.py [--coupling gauss-seidel|jacobi|all] [--control 0.05]
                                       [--plant 0.05 0.025 0.01] [--quick] [--repeat N]

scan_pitch (the one scenario with an independent monolithic reference,
tests/reference/scan_pitch.py):

- the yardstick: the monolithic run of the SAME sampled-data system (controller and
  steering sampled at the control period P with zero-order hold, hub and gimbals together
  at 1 ms) and, separately, its distance to the continuous reference (controller at 1 ms):
  the effect of the sample period, a design choice, not an error of the method;
- for each coupling scheme and plant step H (P a multiple of H; controller and steering
  get P as their own step, orchestration/multirate.py): the coupling error
  max |pitch(co-simulation) − pitch(sampled reference)| and max |Δ w_BO_B| over the run,
  the observed order log(e(H1)/e(H2)) / log(H1/H2) between successive plant steps, and
  the wall time per simulated second (in-process, FMUs loaded each run) with its ratio to
  Gauss-Seidel at the same steps, measured in the same run;
- single rate (P = H) as well, the scenario's own way of running at another step.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from agilesat.fmus.build import build_all
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
from reference import scan_pitch as reference

FINE = 1e-3  # the reference's plant step
STOP = 150.0
CONTROL = ("PitchManeuverController", "CmgSteering")
SCHEMES = ("gauss-seidel", "jacobi")


def twist(q):
    """Pitch as the twist of q_BO about y (well defined through 90°)."""
    q = np.where(q[:, :1] < 0, -q, q)
    return 2 * np.arctan2(q[:, 2], q[:, 0])


def system_file(control: float, fmus: dict, where: Path) -> Path:
    """scan_pitch with controller and steering at their own step ``control``."""
    scenario = dataclasses.replace(get("scan_pitch"), steps=dict.fromkeys(CONTROL, control))
    path = where / f"scan_pitch_P{control}.ssd"
    path.write_bytes(scenario.render_ssd({n: str(fmus[n]) for n in scenario.components}))
    return path


def errors(results, truth, step: float) -> tuple[float, float]:
    every = round(step / FINE)
    if not math.isclose(every * FINE, step):
        raise SystemExit(f"step {step} s is not a multiple of the reference's {FINE} s")
    assert np.allclose(truth["time"][::every], results.time)
    pitch = np.abs(twist(results.vector("SatelliteDynamics.q_BO")) - twist(truth["q_BO"])[::every])
    rate = np.abs(results.vector("SatelliteDynamics.w_BO_B") - truth["w_BO_B"][::every])
    return math.degrees(pitch.max()), float(rate.max())


def run(path: Path, step: float, scheme: str, repeat: int):
    """Results and the best wall time per simulated second of ``repeat`` runs."""
    walls = []
    for _ in range(repeat):
        start = time.perf_counter()
        results = simulate(path, step=step, algorithm=scheme)
        walls.append((time.perf_counter() - start) / STOP)
    return results, min(walls)


def table(title: str, rows: list[tuple], schemes) -> None:
    print(f"\n{title}")
    print(
        "| scheme | plant step H [s] | control period P [s] | coupling error pitch [deg] "
        "| max dw_BO_B [rad/s] | observed order | wall per simulated s [ms] | cost vs GS |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for scheme in schemes:
        mine = [r for r in rows if r[0] == scheme]
        for i, (_, H, P, e_pitch, e_rate, wall, gs_wall) in enumerate(mine):
            order = "—"
            if i:
                previous = mine[i - 1]
                order = f"{math.log(previous[3] / e_pitch) / math.log(previous[1] / H):.2f}"
            print(
                f"| {scheme} | {H:g} | {P:g} | {e_pitch:.3g} | {e_rate:.3g} | {order} "
                f"| {1e3 * wall:.1f} | {wall / gs_wall:.2f} |"
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--coupling", choices=(*SCHEMES, "all"), default="all")
    parser.add_argument("--control", type=float, default=0.05, help="control period P [s]")
    parser.add_argument("--plant", type=float, nargs="+", default=[0.05, 0.025, 0.01])
    parser.add_argument(
        "--single", type=float, nargs="+", default=[0.1, 0.05, 0.025], help="single-rate steps"
    )
    parser.add_argument("--quick", action="store_true", help="only the multi-rate table")
    parser.add_argument("--repeat", type=int, default=1, help="best of N wall times")
    args = parser.parse_args()
    schemes = SCHEMES if args.coupling == "all" else (args.coupling,)
    fmus = {p.stem: p for p in build_all()}

    continuous = reference.simulate(FINE, STOP)
    sampled = {}

    def yardstick(P):
        if P not in sampled:
            sampled[P] = reference.simulate(FINE, STOP, control_period=P)
            pitch = twist(sampled[P]["q_BO"]) - twist(continuous["q_BO"])
            print(
                f"sample-period effect, P = {P:g} s: max |pitch(sampled reference) − "
                f"pitch(continuous reference)| = {math.degrees(np.abs(pitch).max()):.3g} deg"
            )
        return sampled[P]

    with tempfile.TemporaryDirectory() as tmp:
        path = system_file(args.control, fmus, Path(tmp))
        rows = []
        for H in args.plant:
            walls = {}
            for scheme in ("gauss-seidel", *[s for s in schemes if s != "gauss-seidel"]):
                results, walls[scheme] = run(path, H, scheme, args.repeat)
                if scheme in schemes:
                    rows.append(
                        (
                            scheme,
                            H,
                            args.control,
                            *errors(results, yardstick(args.control), H),
                            walls[scheme],
                            walls["gauss-seidel"],
                        )
                    )
        table(
            f"scan_pitch, multi-rate: controller and steering at P = {args.control:g} s, "
            "plant FMUs at H; error against the sampled reference at P",
            rows,
            schemes,
        )
        if args.quick:
            return
        rows = []
        for H in args.single:
            walls = {}
            for scheme in ("gauss-seidel", *[s for s in schemes if s != "gauss-seidel"]):
                results, walls[scheme] = run(get("scan_pitch").ssd, H, scheme, args.repeat)
                if scheme in schemes:
                    rows.append(
                        (
                            scheme,
                            H,
                            H,
                            *errors(results, yardstick(H), H),
                            walls[scheme],
                            walls["gauss-seidel"],
                        )
                    )
        table(
            "scan_pitch, single rate (P = H): error against the sampled reference at P = H",
            rows,
            schemes,
        )


if __name__ == "__main__":
    main()
