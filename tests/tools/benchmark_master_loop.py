"""Benchmark of the master's loop: prints a report (not a test; timings on shared machines vary).

    python tests/tools/benchmark_master_loop.py [--repeat N] [--stop S]

scan_pitch at macro steps 0.01, 0.05 and 0.1 s, N interleaved rounds, median per entry:
the Python loop, the compiled loop called through ctypes.PyDLL (holding the GIL, the
default) and through ctypes.CDLL (releasing it), each with the real models and with every
model's work stubbed out (the FMI layer and the master alone, as in
tests/tools/benchmark_scan_pitch.py).  The master's share is what the compiled loop saves per
step, over the Python loop's total (the compiled loop's own work is a gather/scatter).
"""

from __future__ import annotations

import argparse
import ctypes
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from benchmark_scan_pitch import stub_models

from agilesat.fmus.build import build_all
from agilesat.orchestration import simulate
from agilesat.orchestration.cosim import loop
from agilesat.orchestration.scenarios import get

STEPS = (0.01, 0.05, 0.1)
VARIANTS = ("python", "PyDLL", "CDLL")


def run(ssd, step: float, stop: float, variant: str) -> float:
    if variant != "python":  # no output directory: csv_text (needs the GIL) is not called
        loop._DLL = getattr(ctypes, variant)
        loop._loaded.clear()
    began = time.perf_counter()
    results = simulate(
        ssd, step=step, stop=stop, loop="python" if variant == "python" else "compiled"
    )
    elapsed = time.perf_counter() - began
    assert results.meta["loop"] == ("python" if variant == "python" else "compiled")
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--stop", type=float, default=150.0)
    args = parser.parse_args()
    build_all()
    ssd = get("scan_pitch").ssd
    simulate(ssd, step=0.1, stop=1.0, loop="compiled")  # load every FMU module, compile
    print(
        f"master loop benchmark: scan_pitch, {args.stop:g} s simulated, median of "
        f"{args.repeat} interleaved rounds, us per macro step\n"
    )
    print(
        f"{'step':>6} {'models':>7} "
        + " ".join(f"{v:>8}" for v in VARIANTS)
        + f" {'master share':>13}"
    )
    for step in STEPS:
        n = round(args.stop / step)
        for stubbed in (False, True):
            restore = stub_models() if stubbed else (lambda: None)
            try:
                times = {v: [] for v in VARIANTS}
                for _ in range(args.repeat):
                    for v in VARIANTS:
                        times[v].append(run(ssd, step, args.stop, v))
            finally:
                restore()
            us = {v: statistics.median(t) / n * 1e6 for v, t in times.items()}
            share = (us["python"] - us["PyDLL"]) / us["python"]
            print(
                f"{step:>6} {'stub' if stubbed else 'real':>7} "
                + " ".join(f"{us[v]:>8.1f}" for v in VARIANTS)
                + f" {share:>12.0%}"
            )
    loop._DLL = ctypes.PyDLL
    loop._loaded.clear()
    print(f"\nnumpy {np.__version__}; shared machine: compare ratios within one run")


if __name__ == "__main__":
    main()
