"""Resource figures the tests used to assert as thresholds (a page-fault, resident-memory or
time bound fails on a busy machine; the tests keep the behaviour, this prints the figures):

- the page faults of a 20-s scan_pitch run in a worker of our LocalCluster, and in one
  spawned as Dask's nanny does by default (``MALLOC_TRIM_THRESHOLD_=65536``: glibc then
  maps and unmaps every array over 128 KiB afresh; ``engine.LOCAL_CLUSTER_CONFIG`` unsets
  it; ``test_the_local_cluster_leaves_the_cpu_to_the_runs`` checks that it is unset);
- the resident memory and mappings of repeated runs and FMU instances
  (``fault_cases_fmu.resource_figures``; the test keeps the mappings, a count).

    .venv/bin/python tests/tools/benchmark_resources.py [--runs 3] [--n 150]

Record what it prints in docs/performance-log.md with the command and the date.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE.parent)]  # the fault cases; helpers

from helpers import run_python  # noqa: E402

FAULTS = """
import json, os, resource, sys
from agilesat.orchestration import RunOptions
from agilesat.orchestration.campaign import engine
from agilesat.orchestration.campaign.worker import run_one

runs, trim = int(sys.argv[1]), sys.argv[2] == "1"

def faults():
    run_one(0, "scan_pitch", RunOptions(stop=20.0), [], 0)  # warm: FMUs loaded, kernels
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for i in range(runs):
        run_one(i, "scan_pitch", RunOptions(stop=20.0), [], 0)
    return (resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / runs

config = dict(engine.LOCAL_CLUSTER_CONFIG)
if trim:  # as Dask's nanny spawns its worker by default
    config["distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"] = 65536
engine.LOCAL_CLUSTER_CONFIG.clear()
engine.LOCAL_CLUSTER_CONFIG.update(config)
with engine.cluster(1) as client:
    print(json.dumps(client.submit(faults, pure=False).result()))
"""


def page_faults(runs: int, trim: bool) -> float:
    """Minor page faults per 20-s scan_pitch run in a LocalCluster worker."""
    result = run_python(FAULTS, runs, int(trim), timeout=1800)
    if result.returncode:
        raise RuntimeError(result.stderr[-2000:])
    return json.loads(result.stdout.splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="runs measured per worker")
    parser.add_argument("--n", type=int, default=150, help="size of the FMU memory loops")
    args = parser.parse_args(argv)
    import fault_cases_fmu

    print(f"load average {os.getloadavg()[0]:.2f} (1 min)")
    print("| resource figure | value |\n|---|---|")
    for trim, label in ((False, "our LocalCluster"), (True, "MALLOC_TRIM_THRESHOLD_=65536")):
        faults = page_faults(args.runs, trim)
        print(f"| page faults per 20-s scan_pitch run, worker of {label} | {faults:.0f} |")
    for figure, value in fault_cases_fmu.resource_figures(args.n):
        print(f"| {figure} | {value} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
