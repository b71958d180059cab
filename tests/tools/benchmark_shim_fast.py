"""What each of the shim's fast paths gains (prints a report, not a test): CPU µs per macro
step of each scenario at its own step, with everything on and with one gadget off at a
time, run by run in one process, alternating, medians of the rounds (a shared machine's
load then hits all alike):

- "no C step": AGILESAT_SHIM_STEP=0, every fmi2DoStep and output evaluation in Python;
- "no fast get/set": AGILESAT_SHIM_FAST=0, every call through pythonfmu into the slave.

Each in two processes, the kernels compiled from the first call (``AGILESAT_JIT_AFTER=0``,
as in a long run or a campaign worker) and as their Python (``AGILESAT_JIT=0``, a short
run).  The master keeps its components and resets them at the end of a run, and the shim
reads the switches at fmi2Reset: a one-step run after setting them puts them in force.

    python tests/tools/benchmark_shim_fast.py [--rounds N] [--stop T]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

SCENARIOS = ("scan_pitch", "payload_sweep", "video_sar")
CASES = ("all on", "no C step", "no fast get/set")
TIERS = {"compiled kernels": {"AGILESAT_JIT_AFTER": "0"}, "Python kernels": {"AGILESAT_JIT": "0"}}


def case(name: str) -> None:
    """Set the switches of one case."""
    os.environ["AGILESAT_SHIM_STEP"] = "0" if name == "no C step" else "1"
    os.environ["AGILESAT_SHIM_FAST"] = "0" if name == "no fast get/set" else "1"


def measure(rounds: int, stop: float | None) -> dict:
    """{scenario: {case: µs per macro step}} in this process."""
    from agilesat.fmus.build import build_all
    from agilesat.orchestration import simulate
    from agilesat.orchestration.scenarios import get

    build_all()
    times: dict = {name: {c: [] for c in CASES} for name in SCENARIOS}
    for name in SCENARIOS:
        simulate(get(name).ssd, stop=1.0)  # load every FMU module once
    for _ in range(rounds):
        for name in SCENARIOS:
            scenario = get(name)
            run_stop = stop or scenario.stop
            for label in CASES:
                case(label)
                simulate(scenario.ssd, stop=scenario.step)  # reset: the switches read
                start = time.process_time()
                simulate(scenario.ssd, stop=run_stop)
                elapsed = time.process_time() - start
                times[name][label].append(elapsed / round(run_stop / scenario.step) * 1e6)
    return {n: {c: statistics.median(t) for c, t in cases.items()} for n, cases in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--stop", type=float, default=None, help="default: each scenario's")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(measure(args.rounds, args.stop)))
        return
    print(f"CPU µs per macro step, medians of {args.rounds} alternating rounds (ratio: / all on)")
    for tier, env in TIERS.items():
        command = [sys.executable, __file__, "--child", "--rounds", str(args.rounds)]
        command += ["--stop", str(args.stop)] if args.stop else []
        result = subprocess.run(
            command, env={**os.environ, **env}, capture_output=True, text=True, check=True
        )
        got = json.loads(result.stdout.strip().splitlines()[-1])
        print(f"\n{tier}:\n{'':>14}" + "".join(f"{c:>22}" for c in CASES))
        for name, cases in got.items():
            on = cases["all on"]
            cells = [f"{us:9.1f} ({us / on:4.2f}x)" for us in cases.values()]
            print(f"{name:>14}" + "".join(f"{c:>22}" for c in cells))


if __name__ == "__main__":
    main()
