"""Benchmark of scan_pitch's models alone, compiled kernels against their Python: prints a
report (not a test; timings on shared machines vary: compare the ratios of one run).

    python tests/benchmark_models.py [--repeat N] [--steps N]

Each model in-process with scan_pitch's parameters and its inputs at their start values
(plus OrbitEnvironment with a TLE, the SGP4 path), ``steps`` steps of 0.05 s with step +
output; us per step + output with every kernel of the package compiled and with their
Python (what AGILESAT_JIT=0 and the first AGILESAT_JIT_AFTER calls run), alternated,
least CPU time of ``repeat`` rounds.
"""

from __future__ import annotations

import argparse
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--steps", type=int, default=1000)
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


if __name__ == "__main__":
    main()
