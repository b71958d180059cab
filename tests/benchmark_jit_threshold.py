"""What the kernels' threshold (components/jit.py, AGILESAT_JIT_AFTER) trades: prints a
report (not a test; timings on shared machines vary: compare the ratios, measured in one
run).

    python tests/benchmark_jit_threshold.py [--repeat N]

- load: the wall time a fresh process spends to import numba and load SatelliteDynamics'
  compiled kernels from the (warm) compile cache: a process that makes one step + output
  with the kernels compiled from the first call (AGILESAT_JIT_AFTER=0) minus one with
  their Python (AGILESAT_JIT=0), interleaved, medians of N;
- gain: µs per step + output of SatelliteDynamics alone, its kernels' Python minus
  compiled (in-process, best of N);
- break-even: load / gain, the steps after which compiling has paid.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

ONE_STEP = """
from agilesat.components.satellite_dynamics import SatelliteDynamics
SatelliteDynamics().start(0.0).advance(0.0, 0.05)
"""


def fresh_process(env: dict) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", ONE_STEP], env={**os.environ, **env}, check=True)
    return time.perf_counter() - start


def per_step(kernels, attribute: str, steps: int = 2000) -> float:
    from agilesat.components.satellite_dynamics import SatelliteDynamics

    for kernel in kernels:
        kernel._run = getattr(kernel, attribute)
    model = SatelliteDynamics().start(0.0)
    start = time.process_time()
    for k in range(steps):
        model.advance(k * 0.05, 0.05)
    return (time.process_time() - start) / steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    repeat = parser.parse_args().repeat
    from agilesat.components import jit, satellite_dynamics

    kernels = list(jit.kernels(satellite_dynamics).values())
    fresh_process({"AGILESAT_JIT_AFTER": "0"})  # fill the cache if it is cold
    with_numba, without = [], []
    for _ in range(repeat):
        with_numba.append(fresh_process({"AGILESAT_JIT_AFTER": "0"}))
        without.append(fresh_process({"AGILESAT_JIT": "0"}))
    load = statistics.median(with_numba) - statistics.median(without)
    per_step(kernels, "compiled", 10)  # load outside the timing
    python = min(per_step(kernels, "py_func") for _ in range(repeat))
    compiled = min(per_step(kernels, "compiled") for _ in range(repeat))
    gain = python - compiled
    print(
        f"fresh process, one step: {statistics.median(without):.2f} s with the Python, "
        f"{statistics.median(with_numba):.2f} s with numba and the cached kernels: "
        f"load {load:.2f} s"
    )
    print(
        f"SatelliteDynamics step + output: {python * 1e6:.1f} us Python, "
        f"{compiled * 1e6:.1f} us compiled: gain {gain * 1e6:.1f} us per step"
    )
    print(f"break-even: {load / gain:,.0f} steps (AGILESAT_JIT_AFTER is {jit.AFTER:,})")


if __name__ == "__main__":
    main()
