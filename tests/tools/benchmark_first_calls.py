"""The first calls of simulate() in a fresh process: prints a report (not a test; timings on
a shared machine vary: compare the ratios, measured in one run).

    python tests/tools/benchmark_first_calls.py [--repeat N] [--calls 4]

Per shipped system (the scenarios and their sensed variants), N fresh processes of this
environment (caches warm: ``agilesat build`` made the FMUs and their unpacked copies), each
calling simulate() of the system's file ``--calls`` times: the wall time of each call and
its real-time factor (median over the processes), and whether numba was imported (an FMU's
C entries compiled in the process, fmus/native.py: no).  Targets (issue 38): the second
call within 20 % of the steady state (the least of the later calls), the first at most
0.5 s for the systems without sensing and 1 s for the sensed ones.  The second call's ratio
is given in wall time and in the CPU time of the calling thread, which other processes on a
shared machine do not inflate (a compile or a tier switch inside the call would: it is
work of that thread).
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
times, cpu = [], []
for _ in range(int(sys.argv[2])):
    began, began_cpu = time.perf_counter(), time.thread_time()
    simulate(ssd)
    times.append(time.perf_counter() - began)
    cpu.append(time.thread_time() - began_cpu)
print(json.dumps({"times": times, "cpu": cpu, "stop": stop, "numba": "numba" in sys.modules}))
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
        cpu = [statistics.median(r["cpu"][k] for r in runs) for k in range(args.calls)]
        steady, limit = min(times[2:] or times[1:]), 1.0 if "sensed" in system else 0.5
        steady_cpu = min(cpu[2:] or cpu[1:])
        verdicts.append(
            f"{system}: second call {times[1] / steady:.2f}x the steady state in wall time, "
            f"{cpu[1] / steady_cpu:.2f}x in CPU time (target <= 1.2: "
            f"{'met' if times[1] <= 1.2 * steady else 'NOT met'} in wall time, "
            f"{'met' if cpu[1] <= 1.2 * steady_cpu else 'NOT met'} in CPU time); first "
            f"{times[0]:.2f} s (target <= {limit:g} s: {'met' if times[0] <= limit else 'NOT met'})"
        )
    print("\n".join(verdicts))
    print(f"load average at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
