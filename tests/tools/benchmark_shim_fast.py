"""The shim's fast path on scan_pitch (prints a report, not a test): µs per macro step with
AGILESAT_SHIM_FAST=0 (every get/set through pythonfmu into Python) and =1, run by run in
one process, alternating, medians of the rounds (a shared machine's load then hits both
alike).  The master keeps its components and resets them at the end of a run, and the
shim reads the variable at fmi2Reset too: a one-step run after setting it puts it in
force.  "FMI" is the same run with every model's work replaced by a no-op (as in
benchmark_scan_pitch.py): master, ctypes, shim, pythonfmu, slave.

    python tests/tools/benchmark_shim_fast.py [--rounds N] [--stop T]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from benchmark_scan_pitch import STEPS, stub_models

from agilesat.fmus.build import build_all
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get


def timed(ssd, step, stop, fast: str) -> float:
    os.environ["AGILESAT_SHIM_FAST"] = fast
    simulate(ssd, step=step, stop=step)  # its components are reset at its end: with `fast`
    start = time.perf_counter()
    simulate(ssd, step=step, stop=stop)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--stop", type=float, default=60.0)
    args = parser.parse_args()
    build_all()
    ssd = get("scan_pitch").ssd
    simulate(ssd, step=0.1, stop=1.0)  # load every FMU module once
    print(
        f"scan_pitch, {args.stop:g} s simulated, µs per macro step, medians of {args.rounds} "
        "alternating rounds"
    )
    print(
        f"{'step':>6} {'total off':>10} {'total on':>9} {'ratio':>6} "
        f"{'FMI off':>8} {'FMI on':>7} {'ratio':>6}"
    )
    for step in STEPS:
        n = round(args.stop / step)
        total = {"0": [], "1": []}
        fmi = {"0": [], "1": []}
        for _ in range(args.rounds):
            for fast in ("0", "1"):
                total[fast].append(timed(ssd, step, args.stop, fast) / n * 1e6)
            restore = stub_models()
            try:
                for fast in ("0", "1"):
                    fmi[fast].append(timed(ssd, step, args.stop, fast) / n * 1e6)
            finally:
                restore()
        t0, t1 = statistics.median(total["0"]), statistics.median(total["1"])
        f0, f1 = statistics.median(fmi["0"]), statistics.median(fmi["1"])
        print(
            f"{step:>6} {t0:>10.0f} {t1:>9.0f} {t1 / t0:>6.2f} {f0:>8.0f} {f1:>7.0f} "
            f"{f1 / f0:>6.2f}"
        )


if __name__ == "__main__":
    main()
