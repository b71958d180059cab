"""How big must the reaction wheel be?  (payload_sweep, [Chang 2015])

For a given reversal (turnaround) time, the smallest wheel torque that keeps the pointing
accuracy and stability within their requirement (default: the paper's 0.032° and
0.006 °/s), and the wheel momentum it then uses.  Every point is a real co-simulation of
``payload_sweep`` over one full pitch sweep, run on Dask like a campaign's runs
(:mod:`.campaign`; a LocalCluster, or ``scheduler``): first the whole geometric grid of
torque limits at once, then rounds of k points (k = the number of workers, at least 2)
spaced geometrically between the largest failing and the smallest passing torque, each
round shrinking that bracket (in log torque) by k + 1.  The wheel momentum limit is
lifted (100 N·m·s) so that only the torque limits; the momentum the passing wheel uses is
reported beside it.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path

from ..campaign.engine import cluster
from ..campaign.worker import run_one
from ..cosim.options import RunOptions
from ..output import plots
from ..scenarios import payload_sweep

DEG = math.pi / 180
GRID = (0.05, 0.1, 0.2, 0.4, 0.7, 1.0, 1.5, 2.0, 3.0, 5.0)  # N·m


@dataclass
class Point:
    torque: float  # wheel torque limit, N·m
    accuracy: float  # max |attitude error|, rad
    stability: float  # max |rate error|, rad/s
    momentum: float  # max |wheel momentum| along a body axis, N·m·s
    met: bool


@dataclass
class Sizing:
    turnaround: float
    accuracy: float
    stability: float
    step: float
    points: list[Point]
    torque: float | None  # smallest torque that meets both (None: none on the grid)
    momentum: float | None  # momentum that wheel uses

    def to_json(self, path) -> Path:
        Path(path).write_text(json.dumps(asdict(self), indent=2) + "\n")
        return Path(path)


def evaluate(
    client, torques, turnaround: float, accuracy: float, stability: float, step: float, stop: float
) -> list[Point]:
    """Co-simulations of payload_sweep with these wheel torque limits, in parallel."""
    futures = [
        client.submit(
            run_one,
            i,
            "payload_sweep",
            RunOptions(
                step=step,
                stop=stop,
                parameters={
                    "Flywheel.torque_limit": torque,
                    "Flywheel.momentum_limit": 100.0,
                    "SweepPlanner.turnaround_time": turnaround,
                },
                figures=False,
                build=False,
            ),
            [],
            0,
            pure=False,
        )
        for i, torque in enumerate(torques)
    ]
    points = []
    for torque, future in zip(torques, futures):
        record = future.result()
        if record["status"] == "error":
            raise RuntimeError(
                f"size-flywheel: the run at {torque} N·m stopped: {record['message']}"
            )
        m = record["metrics"]
        a, s = m["pointing_accuracy"]["value"], m["pointing_stability"]["value"]
        points.append(
            Point(torque, a, s, m["wheel_momentum_max"]["value"], a <= accuracy and s <= stability)
        )
    return points


def size_flywheel(
    turnaround: float = 1.0,
    accuracy: float = payload_sweep.ACCURACY,
    stability: float = payload_sweep.STABILITY,
    step: float = 0.05,
    stop: float | None = None,
    grid=GRID,
    refine: int = 3,
    out_dir=None,
    progress=None,
    workers: int | None = None,
    scheduler: str | None = None,
) -> Sizing:
    """The smallest wheel torque meeting both requirements (angles in rad, SI)."""
    sweep = payload_sweep.SWEEP
    # one pitch sweep (4 amplitudes at the pitch rate, plus a reversal) and a margin
    stop = stop or (4 * sweep["pitch_amplitude"] / sweep["pitch_rate"] + turnaround + 10.0)
    payload_sweep.SCENARIO.system_file()  # its FMUs built, for the workers
    points = []
    with cluster(workers, scheduler) as client:
        k = max(2, len(client.scheduler_info()["workers"]))

        def measure(torques):
            new = evaluate(client, list(torques), turnaround, accuracy, stability, step, stop)
            for p in new:
                points.append(p)
                if progress:
                    progress(p)

        measure(grid)
        for _ in range(refine):
            passing = [p.torque for p in points if p.met]
            failing = (
                [p.torque for p in points if not p.met and p.torque < min(passing)]
                if passing
                else []
            )
            if not passing or not failing:
                break
            low, high = max(failing), min(passing)
            measure(low * (high / low) ** (j / (k + 1)) for j in range(1, k + 1))
    points.sort(key=lambda p: p.torque)
    best = min((p for p in points if p.met), key=lambda p: p.torque, default=None)
    result = Sizing(
        turnaround,
        accuracy,
        stability,
        step,
        points,
        best.torque if best else None,
        best.momentum if best else None,
    )
    if out_dir is not None:
        out_dir = Path(out_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
        result.to_json(out_dir / "sizing.json")
        plot(result, out_dir / "sizing.png")
    return result


def plot(result: Sizing, path) -> Path:
    torque = [p.torque for p in result.points]
    return plots.requirement(
        path,
        f"Reaction wheel size, reversal {result.turnaround:g} s (macro step {result.step:g} s)",
        torque,
        [
            (
                "pointing accuracy [deg]",
                [p.accuracy / DEG for p in result.points],
                result.accuracy / DEG,
            ),
            (
                "pointing stability [deg/s]",
                [p.stability / DEG for p in result.points],
                result.stability / DEG,
            ),
        ],
        [p.met for p in result.points],
        "wheel torque limit [N·m]",
    )
