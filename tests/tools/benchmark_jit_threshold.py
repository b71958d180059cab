"""What the kernels' tier decision (components/runtime/jit.py: expect, PAYS_AFTER) trades: prints a
report (not a test; timings on shared machines vary: compare the ratios, measured in one
run).

    python tests/tools/benchmark_jit_threshold.py [--repeat N]

Per scenario, each in fresh processes of this environment with the compile cache warm
(``agilesat build`` filled it), medians of N, the cases interleaved:
- load: the wall time of a 2-step run in a fresh process (no set-up run before it) with
  the kernels compiled from the first call (AGILESAT_JIT_AFTER=0) minus the same with
  their Python (AGILESAT_JIT=0): importing numba and loading the scenario's cached kernels
  and C entries;
- one whole run at the scenario's length, simulate() only (imports and FMU set-up before
  the timing): compiled (AGILESAT_JIT_AFTER=0), Python (AGILESAT_JIT=0) and the default
  (the tier decided from the run's length); the gain per macro step and the break-even
  steps = load / gain.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys

from agilesat.components.runtime import jit
from agilesat.orchestration.scenarios import NAMES

RUN = """
import sys, time
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
scenario = get(sys.argv[1])
stop = float(sys.argv[2]) if len(sys.argv) > 2 else scenario.stop
if len(sys.argv) <= 2:  # set-up: FMUs loaded, imports (a short run times its load)
    simulate(scenario.ssd, stop=scenario.step)
began = time.perf_counter()
simulate(scenario.ssd, stop=stop)
print(time.perf_counter() - began, "numba" in sys.modules)
"""
CASES = {"compiled": {"AGILESAT_JIT_AFTER": "0"}, "python": {"AGILESAT_JIT": "0"}, "default": {}}


def fresh(env: dict, *args) -> float:
    run = subprocess.run(
        [sys.executable, "-c", RUN, *args],
        env={**{k: v for k, v in os.environ.items() if not k.startswith("AGILESAT_JIT")}, **env},
        check=True,
        capture_output=True,
        text=True,
    )
    return float(run.stdout.split()[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    repeat = parser.parse_args().repeat
    print(f"load average {os.getloadavg()[0]:.2f}; medians of {repeat} fresh processes [s]")
    print(
        f"{'scenario':>14} {'steps':>6} {'load':>6} | {'compiled':>8} {'python':>8} "
        f"{'default':>8} | {'gain/step':>9} {'break-even':>10}"
    )
    for name in NAMES:
        from agilesat.orchestration.scenarios import get

        scenario = get(name)
        steps = round(scenario.stop / scenario.step)
        short = {k: [] for k in ("compiled", "python")}
        whole = {k: [] for k in CASES}
        for _ in range(repeat):
            for case in short:
                short[case].append(fresh(CASES[case], name, str(2 * scenario.step)))
            for case, env in CASES.items():
                whole[case].append(fresh(env, name))
        load = statistics.median(short["compiled"]) - statistics.median(short["python"])
        m = {k: statistics.median(v) for k, v in whole.items()}
        gain = (m["python"] - m["compiled"]) / steps  # the whole runs follow a set-up run
        print(
            f"{name:>14} {steps:>6} {load:6.2f} | {m['compiled']:8.2f} {m['python']:8.2f} "
            f"{m['default']:8.2f} | {gain * 1e6:7.0f} us {load / gain:10,.0f}"
        )
    print(f"PAYS_AFTER = {jit.PAYS_AFTER:,} steps (components/runtime/jit.py)")
    print(f"load average at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
