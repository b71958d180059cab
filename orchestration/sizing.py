"""How big must the reaction wheel be?  (payload_sweep, [Chang 2015])

For a given reversal (turnaround) time, the smallest wheel torque that keeps the pointing
accuracy and stability within their requirement (default: the paper's 0.032° and
0.006 °/s), and the wheel momentum it then uses.  Every point is a real co-simulation of
``payload_sweep`` over one full pitch sweep: first a geometric grid of torque limits, then
bisection between the last failing and the first passing one.  The wheel momentum limit is
lifted (100 N·m·s) so that only the torque limits; the momentum the passing wheel uses is
reported beside it.
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path

from ..fmus.build import build_all
from . import plots
from .runner import run
from .scenarios import payload_sweep

DEG = math.pi / 180
GRID = (0.05, 0.1, 0.2, 0.4, 0.7, 1.0, 1.5, 2.0, 3.0, 5.0)   # N·m


@dataclass
class Point:
    torque: float            # wheel torque limit, N·m
    accuracy: float          # max |attitude error|, rad
    stability: float         # max |rate error|, rad/s
    momentum: float          # max |wheel momentum| along a body axis, N·m·s
    met: bool


@dataclass
class Sizing:
    turnaround: float
    accuracy: float
    stability: float
    step: float
    points: list[Point]
    torque: float | None     # smallest torque that meets both (None: none on the grid)
    momentum: float | None   # momentum that wheel uses

    def to_json(self, path) -> Path:
        Path(path).write_text(json.dumps(asdict(self), indent=2) + "\n")
        return Path(path)


def evaluate(torque: float, turnaround: float, accuracy: float, stability: float,
             step: float, stop: float) -> Point:
    """One co-simulation of payload_sweep with this wheel torque limit."""
    _, summary = run("payload_sweep", step=step, stop=stop, figures=False, build=False,
                     parameters={"Flywheel.torque_limit": torque,
                                 "Flywheel.momentum_limit": 100.0,
                                 "SweepPlanner.turnaround_time": turnaround})
    m = summary["metrics"]
    a, s = m["pointing_accuracy"]["value"], m["pointing_stability"]["value"]
    return Point(torque, a, s, m["wheel_momentum_max"]["value"], a <= accuracy and s <= stability)


def size_flywheel(turnaround: float = 1.0, accuracy: float = payload_sweep.ACCURACY,
                  stability: float = payload_sweep.STABILITY, step: float = 0.05,
                  stop: float | None = None, grid=GRID, refine: int = 5, out_dir=None,
                  progress=None) -> Sizing:
    """The smallest wheel torque meeting both requirements (angles in rad, SI)."""
    sweep = payload_sweep.PARAMETERS
    # one pitch sweep (4 amplitudes at the pitch rate, plus a reversal) and a margin
    stop = stop or (4 * sweep["SweepPlanner.pitch_amplitude"] / sweep["SweepPlanner.pitch_rate"]
                    + turnaround + 10.0)
    build_all(names=payload_sweep.SCENARIO.components)
    points = []

    def point(torque):
        p = evaluate(torque, turnaround, accuracy, stability, step, stop)
        points.append(p)
        if progress:
            progress(p)
        return p

    failing, passing = None, None
    for torque in grid:
        p = point(torque)
        if p.met:
            passing = p
            break
        failing = p
    if passing is not None and failing is not None:
        for _ in range(refine):
            middle = point(math.sqrt(failing.torque * passing.torque))
            if middle.met:
                passing = middle
            else:
                failing = middle
    points.sort(key=lambda p: p.torque)
    result = Sizing(turnaround, accuracy, stability, step, points,
                    passing.torque if passing else None, passing.momentum if passing else None)
    if out_dir is not None:
        out_dir = Path(out_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
        result.to_json(out_dir / "sizing.json")
        plot(result, out_dir / "sizing.png")
    return result


def plot(result: Sizing, path) -> Path:
    torque = [p.torque for p in result.points]
    return plots.requirement(
        path, f"Reaction wheel size, reversal {result.turnaround:g} s "
        f"(macro step {result.step:g} s)", torque,
        [("pointing accuracy [deg]", [p.accuracy / DEG for p in result.points],
          result.accuracy / DEG),
         ("pointing stability [deg/s]", [p.stability / DEG for p in result.points],
          result.stability / DEG)],
        [p.met for p in result.points], "wheel torque limit [N·m]")
