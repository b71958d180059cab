"""What the kernels' threshold (components/jit.py, AGILESAT_JIT_AFTER) trades: prints a
report (not a test; timings on shared machines vary: compare the ratios, measured in one
run).

    python tests/tools/benchmark_jit_threshold.py [--repeat N]

- load: the wall time a fresh process spends to import numba and load the compiled
  kernels of scan_pitch's models from the (warm) compile cache: a process that makes one
  step + output of each model with the kernels compiled from the first call
  (AGILESAT_JIT_AFTER=0) minus one with their Python (AGILESAT_JIT=0), interleaved,
  medians of N;
- gain: µs per step + output of each model alone, its kernels' Python minus compiled
  (in-process, CPU time, best of N), and their sum (a scan_pitch step);
- break-even: load / gain, the steps after which compiling has paid;
- scan_pitch co-simulated (0.05 s, 150 s, our master and the FMUs) in fresh processes,
  AGILESAT_JIT_AFTER=0 and AGILESAT_JIT=0 interleaved: µs per macro step (CPU time, after
  a 1 s run that loads everything), medians of N.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

from agilesat.components import jit
from agilesat.fmus import model_class
from agilesat.orchestration.scenarios import get

NAMES = get("scan_pitch").components
ONE_STEP = f"""
from agilesat.fmus import model_class
for name in {list(NAMES)!r}:
    model_class(name)().start(0.0).advance(0.0, 0.05)
"""


SCAN_PITCH = """
import time
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
ssd = get("scan_pitch").ssd
simulate(ssd, step=0.05, stop=1.0)
start = time.process_time()
simulate(ssd, step=0.05, stop=150.0)
print((time.process_time() - start) / 3000 * 1e6)
"""


def scan_pitch(env: dict) -> float:
    run = subprocess.run(
        [sys.executable, "-c", SCAN_PITCH],
        env={**os.environ, **env},
        check=True,
        capture_output=True,
        text=True,
    )
    return float(run.stdout.split()[-1])


def fresh_process(env: dict) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", ONE_STEP], env={**os.environ, **env}, check=True)
    return time.perf_counter() - start


def per_step(model, attribute: str, steps: int = 1000) -> float:
    for kernel in kernels():
        kernel._run = getattr(kernel, attribute)
    instance = model().start(0.0)
    start = time.process_time()
    for k in range(steps):
        instance.advance(k * 0.05, 0.05)
    return (time.process_time() - start) / steps


def kernels() -> list:
    modules = [m for n, m in list(sys.modules.items()) if n.startswith("agilesat.components.")]
    return [k for m in modules for k in jit.kernels(m).values()]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    repeat = parser.parse_args().repeat
    fresh_process({"AGILESAT_JIT_AFTER": "0"})  # fill the cache if it is cold
    with_numba, without = [], []
    for _ in range(repeat):
        with_numba.append(fresh_process({"AGILESAT_JIT_AFTER": "0"}))
        without.append(fresh_process({"AGILESAT_JIT": "0"}))
    load = statistics.median(with_numba) - statistics.median(without)
    print(
        f"fresh process, one step of each scan_pitch model: {statistics.median(without):.2f} s "
        f"with the Python, {statistics.median(with_numba):.2f} s with numba and the cached "
        f"kernels: load {load:.2f} s"
    )
    print("us per step + output, Python / compiled / gain:")
    total = 0.0
    for name in NAMES:
        model = model_class(name)
        per_step(model, "compiled", 10)  # load outside the timing
        python = min(per_step(model, "py_func") for _ in range(repeat))
        compiled = min(per_step(model, "compiled") for _ in range(repeat))
        total += python - compiled
        print(
            f"  {name:>24}: {python * 1e6:6.1f} / {compiled * 1e6:6.1f} / "
            f"{(python - compiled) * 1e6:6.1f}"
        )
    print(f"  {'all':>24}: gain {total * 1e6:.1f} us per scan_pitch step")
    print(f"break-even: {load / total:,.0f} steps (AGILESAT_JIT_AFTER is {jit.AFTER:,})")
    compiled, python = [], []
    for _ in range(repeat):
        compiled.append(scan_pitch({"AGILESAT_JIT_AFTER": "0"}))
        python.append(scan_pitch({"AGILESAT_JIT": "0"}))
    compiled_us, python_us = statistics.median(compiled), statistics.median(python)
    print(
        f"scan_pitch at 0.05 s, us per macro step: {compiled_us:.0f} compiled "
        f"(AGILESAT_JIT_AFTER=0), {python_us:.0f} Python (AGILESAT_JIT=0): "
        f"{python_us / compiled_us:.2f}x"
    )


if __name__ == "__main__":
    main()
