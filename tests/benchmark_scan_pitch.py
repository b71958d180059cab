"""Benchmark of scan_pitch: prints a report (not a test; timings on shared machines vary).

    python tests/benchmark_scan_pitch.py [--repeat N]

For macro steps 0.01, 0.05 and 0.1 s, on one core, best of N runs each:
- the co-simulation (our master, the five FMUs) and its real-time factor;
- the monolithic NumPy reference at the same step (tests/reference/scan_pitch.py), and the
  ratio of the two wall times, measured in the same run;
- the co-simulation's time per macro step split into FMI-call overhead (the same run with
  every model's initialize/step/output replaced by a no-op inside the loaded FMUs: the
  master, ctypes, pythonfmu and our slave and shim) and model compute (the rest).
Targets (issue 2): ≥ 300× real time at 0.05 s, and ≤ 3× the monolithic reference.
"""

from __future__ import annotations

import argparse
import platform
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from agilesat.fmus.build import build_all
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
from reference import scan_pitch as reference

STEPS = (0.01, 0.05, 0.1)
STOP = 150.0


def best(function, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def stub_models():
    """Replace every loaded FMU model's work by a no-op; returns a function undoing it."""
    saved = []
    for name, module in list(sys.modules.items()):
        if not name.startswith("agilesat_"):
            continue
        for obj in vars(module).values():
            if isinstance(obj, type) and "VARIABLES" in vars(obj) and obj.__module__ == name:
                for method in ("initialize", "step", "output"):
                    saved.append((obj, method, vars(obj)[method]))
                obj.initialize = lambda self, t0: None
                obj.step = lambda self, t, dt: None
                obj.output = lambda self: None

    def restore():
        for obj, method, function in saved:
            setattr(obj, method, function)

    return restore


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    build_all()
    ssd = get("scan_pitch").ssd
    simulate(ssd, step=0.1, stop=1.0)  # load every FMU module once
    print(f"scan_pitch benchmark: {STOP:g} s simulated, best of {args.repeat} runs per entry")
    print(
        f"  {platform.processor() or platform.machine()}, Python {platform.python_version()}, "
        f"numpy {np.__version__}, one core\n"
    )
    header = (
        f"{'step':>6} {'co-sim':>9} {'RTF':>7} {'us/step':>8} {'reference':>10} "
        f"{'ratio':>6} {'FMI us/step':>12} {'model us/step':>14}"
    )
    print(header)
    rows = {}
    for step in STEPS:
        n = round(STOP / step)
        cosim = best(lambda: simulate(ssd, step=step, stop=STOP), args.repeat)
        monolithic = best(lambda: reference.simulate(step, STOP), args.repeat)
        restore = stub_models()
        try:
            overhead = best(lambda: simulate(ssd, step=step, stop=STOP), args.repeat)
        finally:
            restore()
        rows[step] = (cosim, monolithic)
        print(
            f"{step:>6} {cosim:>8.3f}s {STOP / cosim:>7.0f} {cosim / n * 1e6:>8.0f} "
            f"{monolithic:>9.3f}s {cosim / monolithic:>6.2f} {overhead / n * 1e6:>12.0f} "
            f"{(cosim - overhead) / n * 1e6:>14.0f}"
        )
    cosim, monolithic = rows[0.05]
    rtf = STOP / cosim
    print(
        f"\ntargets at 0.05 s: real-time factor {rtf:.0f} (target >= 300: "
        f"{'met' if rtf >= 300 else 'NOT met'}); co-simulation / reference "
        f"{cosim / monolithic:.2f} "
        f"(target <= 3: {'met' if cosim / monolithic <= 3 else 'NOT met'})"
    )
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory {peak:.0f} MiB")


if __name__ == "__main__":
    main()
