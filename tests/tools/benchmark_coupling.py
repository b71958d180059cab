"""Coupling accuracy of the co-simulation: prints a report (not a test).

    python tests/tools/benchmark_coupling.py [--scenario scan_pitch|payload_sweep|video_sar|all]
                                       [--coupling gauss-seidel|jacobi|all] [--control 0.05]
                                       [--plant 0.05 0.025 0.01] [--quick] [--repeat N]
                                       [--stop T]

For each scenario, against the monolithic run of the SAME sampled-data system
(tests/tools/reference/, harness tests/tools/coupling_cases.py: digital components sampled at the
control period P with zero-order hold, the plant integrated together):

- for each coupling scheme and plant step H (P a multiple of H; the digital components get P
  as their own step, orchestration/cosim/multirate.py): the coupling error (scan_pitch: max
  |pitch(co-simulation) − pitch(sampled reference)|; payload_sweep, video_sar: the largest
  rotation between the two attitudes q_BI) and max |Δw| over the run, the observed order
  log(e(H1)/e(H2)) / log(H1/H2) between successive plant steps, and the wall time per
  simulated second (in-process, FMUs loaded each run) with its ratio to Gauss-Seidel at the
  same steps, measured in the same run;
- scan_pitch: the distance of the sampled reference to the continuous one (controller at
  1 ms: the effect of the sample period, a design choice, not an error of the method) and
  single rate (P = H) as well, the scenario's own way of running at another step;
- payload_sweep and video_sar (unless --quick): the reference's own checks, its step halved
  and its total-momentum drift; payload_sweep also the effect of sampling the wheel drive at
  H (the Flywheel's communication step) instead of continuously, and that of the
  SweepPlanner's acceleration at the start of an arriving ramp
  (tests/tools/reference/payload_sweep.py).
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from coupling_cases import FINE, attitude_difference, errors, reference, system_file, twist

from agilesat.fmus.build import build_all
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
from reference import payload_sweep, scan_pitch, video_sar

SCENARIOS = ("scan_pitch", "payload_sweep", "video_sar")
SCHEMES = ("gauss-seidel", "jacobi")
ERROR = {"scan_pitch": "coupling error pitch [deg]"}


def run(path: Path, step: float, scheme: str, repeat: int, stop: float):
    """Results and the best wall time per simulated second of ``repeat`` runs."""
    walls = []
    for _ in range(repeat):
        start = time.perf_counter()
        results = simulate(path, step=step, stop=stop, algorithm=scheme)
        walls.append((time.perf_counter() - start) / stop)
    return results, min(walls)


def table(title: str, rows: list[tuple], schemes, error: str) -> None:
    print(f"\n{title}")
    print(
        f"| scheme | plant step H [s] | control period P [s] | {error} "
        "| max dw [rad/s] | observed order | wall per simulated s [ms] | cost vs GS |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for scheme in schemes:
        mine = [r for r in rows if r[0] == scheme]
        for i, (_, H, P, e_angle, e_rate, wall, gs_wall) in enumerate(mine):
            order = "—"
            if i:
                previous = mine[i - 1]
                order = f"{math.log(previous[3] / e_angle) / math.log(previous[1] / H):.2f}"
            print(
                f"| {scheme} | {H:g} | {P:g} | {e_angle:.3g} | {e_rate:.3g} | {order} "
                f"| {1e3 * wall:.1f} | {wall / gs_wall:.2f} |"
            )


def measure(scenario, path, control, steps, schemes, repeat, stop, single=False):
    """Rows of :func:`table` for the plant steps ``steps`` (``single``: P = H), the references
    and the run each was given, by (P, H) (H None when the reference does not depend on it)."""
    rows, truths, recordings = [], {}, {}
    for H in steps:
        P = H if single else control
        walls = {}
        for scheme in ("gauss-seidel", *[s for s in schemes if s != "gauss-seidel"]):
            results, walls[scheme] = run(path, H, scheme, repeat, stop)
            key = (P, H if scenario == "payload_sweep" else None)
            if key not in truths:
                truths[key] = reference(scenario, P, H, stop, results)
                recordings[key] = results
            if scheme in schemes:
                error = errors(scenario, results, truths[key], H)
                rows.append((scheme, H, P, *error, walls[scheme], walls["gauss-seidel"]))
    return rows, truths, recordings


def scan_pitch_report(fmus, args, schemes, tmp):
    stop = get("scan_pitch").stop
    path = system_file("scan_pitch", args.control, fmus, tmp)
    rows, truths, _ = measure(
        "scan_pitch", path, args.control, args.plant, schemes, args.repeat, stop
    )
    continuous = scan_pitch.simulate(FINE["scan_pitch"], stop)

    def effect(P, truth):
        pitch = np.abs(twist(truth["q_BO"]) - twist(continuous["q_BO"])).max()
        print(
            f"sample-period effect, P = {P:g} s: max |pitch(sampled reference) − "
            f"pitch(continuous reference)| = {math.degrees(pitch):.3g} deg"
        )

    effect(args.control, truths[(args.control, None)])
    table(
        f"scan_pitch, multi-rate: controller and steering at P = {args.control:g} s, "
        "plant FMUs at H; error against the sampled reference at P",
        rows,
        schemes,
        ERROR["scan_pitch"],
    )
    if args.quick:
        return
    ssd = get("scan_pitch").ssd
    rows, truths, _ = measure(
        "scan_pitch", ssd, None, args.single, schemes, args.repeat, stop, True
    )
    for (P, _), truth in sorted(truths.items()):
        effect(P, truth)
    table(
        "scan_pitch, single rate (P = H): error against the sampled reference at P = H",
        rows,
        schemes,
        ERROR["scan_pitch"],
    )


def reference_checks(scenario: str, truths: dict, recordings: dict, stop: float) -> None:
    """The reference's step halved, its momentum drift and (payload_sweep) the effect of
    sampling the wheel drive at H, printed."""
    fine = FINE[scenario]
    key = min(truths, key=lambda k: k[1] or 0.0)  # the finest plant step
    (P, H), truth, recorded = key, truths[key], recordings[key]
    if scenario == "payload_sweep":
        half = payload_sweep.simulate(fine / 2, stop, control_period=P, drive_period=H)
        label = f"drive at H = {H:g} s"
    else:
        guidance = video_sar.guidance_from(recorded, P)
        half = video_sar.simulate(fine / 2, stop, guidance, control_period=P)
        label = "guidance of the run"
    halved = attitude_difference(truth["q_BI"], half["q_BI"][::2]).max()
    H_I = truth["H_I"]
    drift = np.linalg.norm(H_I - H_I[0], axis=1).max() / np.linalg.norm(H_I[0])
    print(
        f"{scenario} reference (P = {P:g} s, {label}): step {fine:g} s vs {fine / 2:g} s: "
        f"max attitude difference {math.degrees(halved):.2g} deg; total momentum drift "
        f"{drift:.1g} relative"
    )
    if scenario != "payload_sweep":
        return
    for (P, H), truth in sorted(truths.items()):
        continuous = payload_sweep.simulate(fine, stop, control_period=P)
        drive = attitude_difference(truth["q_BI"], continuous["q_BI"]).max()
        print(
            f"H = {H:g} s (P = {P:g} s): wheel drive at H vs at {fine:g} s: max attitude "
            f"difference {math.degrees(drive):.3g} deg"
        )


def scenario_report(scenario, fmus, args, schemes, tmp):
    stop = args.stop or get(scenario).stop
    path = system_file(scenario, args.control, fmus, tmp)
    rows, truths, recordings = measure(
        scenario, path, args.control, args.plant, schemes, args.repeat, stop
    )
    digital = "controller" if scenario == "payload_sweep" else "controller and steering"
    table(
        f"{scenario}, multi-rate: {digital} at P = {args.control:g} s, plant FMUs at H; "
        "error against the sampled reference at P",
        rows,
        schemes,
        "coupling error attitude [deg]",
    )
    if not args.quick:
        reference_checks(scenario, truths, recordings, stop)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenario", choices=(*SCENARIOS, "all"), default="all")
    parser.add_argument("--coupling", choices=(*SCHEMES, "all"), default="all")
    parser.add_argument("--control", type=float, default=0.05, help="control period P [s]")
    parser.add_argument("--plant", type=float, nargs="+", default=[0.05, 0.025, 0.01])
    parser.add_argument(
        "--single",
        type=float,
        nargs="+",
        default=[0.1, 0.05, 0.025],
        help="single-rate steps (scan_pitch)",
    )
    parser.add_argument("--quick", action="store_true", help="only the multi-rate tables")
    parser.add_argument(
        "--stop", type=float, help="payload_sweep, video_sar: run length [s] (default: theirs)"
    )
    parser.add_argument("--repeat", type=int, default=1, help="best of N wall times")
    args = parser.parse_args()
    schemes = SCHEMES if args.coupling == "all" else (args.coupling,)
    scenarios = SCENARIOS if args.scenario == "all" else (args.scenario,)
    fmus = {p.stem: p for p in build_all()}
    with tempfile.TemporaryDirectory() as tmp:
        for scenario in scenarios:
            if scenario == "scan_pitch":
                scan_pitch_report(fmus, args, schemes, Path(tmp))
            else:
                scenario_report(scenario, fmus, args, schemes, Path(tmp))
            sys.stdout.flush()


if __name__ == "__main__":
    main()
