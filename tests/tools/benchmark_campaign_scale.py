"""A video_sar campaign at verification scale, from cold workers: prints a report (not a
test; timings on a shared machine vary, compare the ratios within one run).

    python tests/tools/benchmark_campaign_scale.py [--runs 1109] [--workers 2] \
        [--basilisk-python PATH]

- bare: simulate() of video_sar (its shipped dispersions' nominal run) in a fresh process,
  compiled (AGILESAT_JIT_AFTER=0), after a warm-up run: CPU and wall per run, best of 5;
  and run(), what a campaign worker makes of each run (metrics, no files);
- a worker's first run, in a fresh process as a worker makes it (AGILESAT_JIT_RUNS = its
  share): importing numba and SciPy's statistics, then the first run_one (FMU loads, the
  compiled kernels' loads) and the second;
- the campaign, as a user starts it: ``agilesat campaign video_sar --runs N`` on local
  workers (its shipped dispersions), timed from the command's start to its end (cluster
  start-up, every FMU load, the report); the runs' own times from its journal: each
  worker's first run and the mean, against the bare run();
- the CPU of all the campaign's processes (client, scheduler, nannies, workers), which
  the machine's other load does not inflate, split into the runs and the rest (Dask,
  start-up, report);
- core-seconds per run (wall × workers / runs) and runs per core-second, beside
  Basilisk's Monte Carlo of its VSCMG hub over the same 200 s at 0.05 s (dynamics only, no
  flight software; tests/tools/benchmark_basilisk.py) where a Python with bsk is given.
Targets (issue 29): N = 1,109 on 2 workers within 5 minutes; a run costs at most 1.2× the
compiled bare simulate() from each worker's first run.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BARE = """
import json, sys, time
from agilesat.orchestration import run, simulate
from agilesat.orchestration.scenarios import get
scenario = get("video_sar")
simulate(scenario.ssd)  # warm-up: imports, FMU loads, numba's
best = {}
for name, once in (
    ("simulate", lambda: simulate(scenario.ssd)),
    ("run", lambda: run("video_sar", figures=False, build=False)),
):
    for _ in range(5):
        wall, cpu = time.perf_counter(), time.process_time()
        once()
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        best[name] = min(best.get(name, (wall, cpu)), (wall, cpu))
print(json.dumps(best))
"""
FIRST = """
import json, os, sys, time
os.environ["AGILESAT_JIT_RUNS"] = sys.argv[1]
from agilesat.orchestration.campaign.worker import run_one
def timed(once):
    wall, cpu = time.perf_counter(), time.process_time()
    once()
    return time.perf_counter() - wall, time.process_time() - cpu
out = {
    "numba": timed(lambda: __import__("numba")),
    "scipy.stats": timed(lambda: __import__("scipy.stats")),
}
for k in range(2):
    out[f"run {k}"] = timed(lambda: run_one(k, "video_sar", {}, None, None, None, [], 0))
print(json.dumps(out))
"""
TOOLS = Path(__file__).resolve().parent


def bare() -> dict:
    out = subprocess.run(
        [sys.executable, "-c", BARE],
        env={**os.environ, "AGILESAT_JIT_AFTER": "0"},
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return json.loads(out.splitlines()[-1])


def first_run(share: int) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", FIRST, str(share)], check=True, capture_output=True, text=True
    ).stdout
    return json.loads(out.splitlines()[-1])


def children_cpu() -> float:
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def campaign(runs: int, workers: int, out: Path) -> tuple[float, float, list[dict]]:
    """(wall, CPU of all its processes: client, scheduler, nannies, workers, records)."""
    cpu = children_cpu()
    began = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "agilesat.orchestration", "campaign", "video_sar"]
        + ["--runs", str(runs), "--workers", str(workers), "--out", str(out), "--no-progress"],
        check=True,
        capture_output=True,
    )
    wall, cpu = time.perf_counter() - began, children_cpu() - cpu
    records = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    return wall, cpu, records


def basilisk(python: str, runs: int) -> tuple[float, float] | None:
    result = subprocess.run(
        [python, str(TOOLS / "benchmark_basilisk.py"), "--monte-carlo", str(runs), "--stop", "200"],
        capture_output=True,
        text=True,
    )
    if result.returncode != 0:
        print(f"Basilisk: {result.stderr.strip().splitlines()[-1:]}")
        return None
    per_run, inside = map(float, result.stdout.split())
    return per_run, inside


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1109)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--basilisk-python", help="a python with bsk installed")
    parser.add_argument("--basilisk-runs", type=int, default=40)
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f} at the start")
    b = bare()
    print(
        f"bare, compiled, best of 5: simulate() {b['simulate'][1]:.3f} s CPU "
        f"({b['simulate'][0]:.3f} s wall), run() {b['run'][1]:.3f} s CPU "
        f"({b['run'][0]:.3f} s wall) per 200-s run"
    )
    share = -(-args.runs // args.workers)
    f = first_run(share)
    bare_cpu = b["simulate"][1]
    print(
        f"a worker's first run, fresh process (wall, CPU): import numba {f['numba'][0]:.3f} s, "
        f"{f['numba'][1]:.3f} s; import scipy.stats {f['scipy.stats'][0]:.3f} s, "
        f"{f['scipy.stats'][1]:.3f} s; first run_one {f['run 0'][0]:.3f} s, "
        f"{f['run 0'][1]:.3f} s (FMU loads, kernel loads); second {f['run 1'][0]:.3f} s, "
        f"{f['run 1'][1]:.3f} s = {f['run 1'][1] / bare_cpu:.2f}x the bare simulate()'s CPU"
    )
    with tempfile.TemporaryDirectory() as tmp:
        wall, cpu, records = campaign(args.runs, args.workers, Path(tmp) / "c")
    statuses = {}
    for r in records:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
    by_pid: dict[int, list[float]] = {}
    for r in sorted(records, key=lambda r: r["index"]):
        by_pid.setdefault(r["pid"], []).append(r["seconds"])
    mean = sum(r["seconds"] for r in records) / len(records)
    firsts = [seconds[0] for seconds in by_pid.values()]
    after_first = [s for seconds in by_pid.values() for s in seconds[1:]]
    steady = sum(after_first) / max(1, len(after_first))
    core = wall * args.workers / args.runs
    print(
        f"campaign: {args.runs} runs on {args.workers} workers in {wall:.1f} s "
        f"({wall / 60:.2f} min; target <= 5 min: {'met' if wall <= 300 else 'NOT met'}); "
        f"outcomes {statuses}"
    )
    print(
        f"  run_one's wall per run: mean {mean:.3f} s = {mean / b['simulate'][0]:.2f}x the bare "
        f"simulate(), {mean / b['run'][0]:.2f}x the bare run(); each worker's first run "
        + ", ".join(f"{s:.3f} s ({s / b['simulate'][0]:.2f}x)" for s in firsts)
        + " (target <= 1.2x from the first run)"
    )
    print(
        f"  the runs after each worker's first: mean {steady:.3f} s "
        f"= {steady / b['simulate'][0]:.2f}x the bare simulate()"
    )
    in_runs = sum(r["seconds"] for r in records) / args.workers
    print(
        f"  the campaign's wall {wall:.1f} s: {in_runs:.1f} s in runs (per worker), the rest "
        f"{wall - in_runs:.1f} s: Python and Dask start-up, "
        f"Dask's round trips, the report ({(wall - in_runs) * args.workers / args.runs:.4f} "
        "core-s per run outside the runs)"
    )
    in_runs_cpu = args.runs * b["run"][1]  # each run as the bare run()'s CPU
    print(
        f"  CPU of all its processes (load-independent): {cpu / args.runs:.3f} core-s per "
        f"run = {cpu / args.runs / bare_cpu:.2f}x the bare simulate()'s CPU; of it the "
        f"runs (as the bare run(), {b['run'][1]:.3f} s) {in_runs_cpu / cpu:.0%}, the rest "
        f"{1 - in_runs_cpu / cpu:.0%}: "
        f"Dask (scheduler, nannies, workers' event loops, round trips), start-up, report"
    )
    print(
        f"  everything (start-up, FMU loads, Dask, report): {core:.3f} core-s per run, "
        f"{1 / core:.1f} runs per core-second; {b['simulate'][1] / core:.2f} of it the bare "
        "simulate()'s CPU"
    )
    if args.basilisk_python:
        result = basilisk(args.basilisk_python, args.basilisk_runs)
        if result:
            per_run, inside = result
            print(
                f"Basilisk Monte Carlo, VSCMG hub, 200 s at 0.05 s, {args.basilisk_runs} runs in "
                f"one process: {per_run:.3f} core-s per run ({inside:.3f} s in its "
                f"dynamics), {1 / per_run:.1f} runs per core-second; this campaign / "
                f"Basilisk: {per_run / core:.2f}x the runs per core-second (wall x "
                f"workers), {per_run / (cpu / args.runs):.2f}x by the CPU of all its processes"
            )
    print(f"load average {os.getloadavg()[0]:.2f} at the end")


if __name__ == "__main__":
    main()
