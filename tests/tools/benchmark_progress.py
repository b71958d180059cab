"""What the progress callback costs: scan_pitch (3000 macro steps) run alternately without
a callback, with a bare counting callback and with the CLI's Progress (plain lines to a
non-terminal stream), best of N each; prints the ratios.

    .venv/bin/python tests/tools/benchmark_progress.py [N]
"""

import io
import sys
import time

from agilesat.fmus.build import build_all
from agilesat.orchestration.cosim.master import simulate
from agilesat.orchestration.output.progress import Progress
from agilesat.orchestration.scenarios import get


def main(n: int) -> None:
    scenario = get("scan_pitch")
    build_all(names=scenario.components)
    calls = []
    variants = {
        "none": lambda: None,
        "counting": lambda: lambda done, total: calls.append(done),
        "Progress": lambda: Progress("scan_pitch", stream=io.StringIO(), interval=0.0),
    }
    best = {name: float("inf") for name in variants}
    for _ in range(n):
        for name, make in variants.items():
            start = time.perf_counter()
            simulate(scenario.ssd, progress=make())
            best[name] = min(best[name], time.perf_counter() - start)
    print(f"scan_pitch, 3000 steps, best of {n}; callback calls per run: {len(calls) // n}")
    for name, seconds in best.items():
        print(f"  progress={name:9s} {seconds:7.3f} s   ratio to none {seconds / best['none']:.3f}")
    progress, k = Progress("x", stream=io.StringIO()), 100_000
    start = time.perf_counter()
    for i in range(k):
        progress(i, k)
    per_call = (time.perf_counter() - start) / k
    print(
        f"  one Progress call (no terminal, between lines): {per_call * 1e6:.2f} µs; "
        f"100 per run: {100 * per_call / best['none'] * 100:.4f} % of the run"
    )


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)
