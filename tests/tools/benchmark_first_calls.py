"""The first calls of simulate() in a fresh process: prints a report (not a test; timings on
a shared machine vary: compare the ratios, measured in one run).

    python tests/tools/benchmark_first_calls.py [--repeat N] [--calls 4]

Per shipped system (the scenarios and their sensed variants), N fresh processes of this
environment (caches warm: ``agilesat build`` made the FMUs and their unpacked copies), each
calling simulate() of the system's file ``--calls`` times: the wall time of each call and
its real-time factor (median over the processes), and whether numba was imported (an FMU's
C entries compiled in the process, fmus/native.py: no).  Targets (issue 38): the second
call within 20 % of the steady state (the least of the later calls), the first at most
0.5 s for the systems without sensing and 1 s for the sensed ones.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

SYSTEMS = ("scan_pitch", "payload_sweep", "video_sar", "scan_pitch:sensed", "video_sar:sensed")
RUN = """
import json, sys, time
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
base, _, variant = sys.argv[1].partition(":")
scenario = get(base)
ssd, stop = scenario.system_file(variant or None), scenario.system_for(variant or None).stop
times = []
for _ in range(int(sys.argv[2])):
    began = time.perf_counter()
    simulate(ssd)
    times.append(time.perf_counter() - began)
print(json.dumps({"times": times, "stop": stop, "numba": "numba" in sys.modules}))
"""


def fresh(system: str, calls: int) -> dict:
    done = subprocess.run(
        [sys.executable, "-c", RUN, system, str(calls)], capture_output=True, text=True, check=True
    )
    return json.loads(done.stdout.splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--calls", type=int, default=4)
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f}; medians of {args.repeat} fresh processes")
    print(f"{'system':>18} | " + " | ".join(f"{k + 1:>16}" for k in range(args.calls)))
    verdicts = []
    for system in SYSTEMS:
        runs = [fresh(system, args.calls) for _ in range(args.repeat)]
        times = [statistics.median(r["times"][k] for r in runs) for k in range(args.calls)]
        stop = runs[0]["stop"]
        cells = " | ".join(f"{t:6.3f} s {stop / t:7,.0f}x" for t in times)
        numba = "numba imported" if any(r["numba"] for r in runs) else "numba not imported"
        print(f"{system:>18} | {cells}  ({numba})")
        steady, limit = min(times[2:] or times[1:]), 1.0 if "sensed" in system else 0.5
        verdicts.append(
            f"{system}: second call {times[1] / steady:.2f}x the steady state (target <= 1.2: "
            f"{'met' if times[1] <= 1.2 * steady else 'NOT met'}); first {times[0]:.2f} s "
            f"(target <= {limit:g} s: {'met' if times[0] <= limit else 'NOT met'})"
        )
    print("\n".join(verdicts))
    print(f"load average at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
