"""Benchmark of scan_pitch's models alone, compiled kernels against their Python: prints a
report (not a test; timings on shared machines vary: compare the ratios of one run).

    python tests/benchmark_models.py [--repeat N] [--steps N] [--runs N]

Each model in-process with scan_pitch's parameters and its inputs at their start values
(plus OrbitEnvironment with a TLE, the SGP4 path), ``steps`` steps of 0.05 s with step +
output; us per step + output with every kernel of the package compiled and with their
Python (what AGILESAT_JIT=0 and the first AGILESAT_JIT_AFTER calls run), alternated,
least CPU time of ``repeat`` rounds.

Then scan_pitch as a co-simulation (our master, the built FMUs, 150 s at 0.05 s) in fresh
processes, alternately with AGILESAT_JIT_AFTER=0 (every kernel compiled from the first
call) and AGILESAT_JIT=0 (their Python), ``runs`` each: us per macro step (CPU time of the
run after a first run that loads the FMUs), median and least.
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
from helpers import ISS_TLE

MODELS = ("OrbitEnvironment", "CmgCluster", "CmgSteering", "PitchManeuverController")


def parameters(name: str) -> dict:
    prefix = name + "."
    return {
        k[len(prefix) :]: v for k, v in get("scan_pitch").parameters.items() if k.startswith(prefix)
    }


def all_kernels():
    import sys

    return [
        k
        for m in list(sys.modules.values())
        if getattr(m, "__name__", "").startswith("agilesat.components.")
        for k in jit.kernels(m).values()
    ]


def timed(model, steps: int) -> float:
    """CPU seconds of ``steps`` step + output calls."""
    start = time.process_time()
    for k in range(steps):
        model.advance(k * 0.05, 0.05)
    return time.process_time() - start


_SCAN_PITCH = """
import time
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
ssd = get("scan_pitch").ssd
simulate(ssd, step=0.05, stop=1.0)  # load the FMUs (and the compiled kernels)
start = time.process_time()
simulate(ssd, step=0.05, stop=150.0)
print((time.process_time() - start) / 3000 * 1e6)
"""


def scan_pitch_report(runs: int) -> None:
    settings = {"compiled": {"AGILESAT_JIT_AFTER": "0"}, "python": {"AGILESAT_JIT": "0"}}
    times = {label: [] for label in settings}
    for _ in range(runs):
        for label, env in settings.items():
            result = subprocess.run(
                [sys.executable, "-c", _SCAN_PITCH],
                env={**os.environ, **env},
                capture_output=True,
                text=True,
                check=True,
            )
            times[label].append(float(result.stdout.split()[-1]))
    print(f"\nscan_pitch co-simulation at 0.05 s, us per macro step, {runs} runs each, alternated:")
    for label, values in times.items():
        print(
            f"{label:>32} median {statistics.median(values):6.0f}  least {min(values):6.0f}"
            f"  ({', '.join(f'{v:.0f}' for v in values)})"
        )
    ratio = statistics.median(times["python"]) / statistics.median(times["compiled"])
    print(f"{'python / compiled':>32} {ratio:.2f} (medians)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--runs", type=int, default=5, help="scan_pitch runs each (0: none)")
    args = parser.parse_args()
    cases = [(name, parameters(name)) for name in MODELS]
    line1, line2 = ISS_TLE
    cases.append(("OrbitEnvironment", {"tle_line1": line1, "tle_line2": line2}))
    print(f"models alone, us per step + output, least of {args.repeat} rounds of {args.steps}:")
    print(f"{'model':>32} {'compiled':>9} {'python':>7} {'ratio':>6}")
    for name, params in cases:
        cls = model_class(name)
        model = cls(**params).start(0.0)
        kernels = all_kernels()
        times = {"compiled": [], "python": []}
        for k in kernels:
            k.compiled  # noqa: B018  (compile or load outside the timing)
        for _ in range(args.repeat + 1):
            for label, attribute in (("compiled", "compiled"), ("python", "py_func")):
                for k in kernels:
                    k._run = getattr(k, attribute)
                times[label].append(timed(model, args.steps) / args.steps * 1e6)
        compiled, python = (min(times[label][1:]) for label in ("compiled", "python"))
        label = name + (" (TLE)" if "tle_line1" in params else "")
        print(f"{label:>32} {compiled:>9.1f} {python:>7.1f} {python / compiled:>5.1f}x")
    if args.runs:
        scan_pitch_report(args.runs)


if __name__ == "__main__":
    main()
