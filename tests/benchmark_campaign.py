"""Campaign benchmark: throughput with 1 and 2 workers, per-run overhead of the campaign
machinery against bare loops, memory per worker over many runs, reused-vs-fresh identity.

    python tests/benchmark_campaign.py [--runs 24] [--stop 30] [--memory-runs 2000]

Compare ratios measured in one invocation (absolute times vary with the machine's load).
Targets: speed-up ≥ 1.8× with 2 workers on 2 cores; machinery overhead ≤ 10 %; worker
memory flat over 2,000 runs; a reused worker bit-identical to a fresh process.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from agilesat.orchestration.campaign import engine, report
from agilesat.orchestration.campaign.plan import Plan, Spec
from agilesat.orchestration.campaign.worker import run_one

TARGET = "scan_pitch"
VARY = ["SatelliteDynamics.inertia=inertia(0.03, 1deg)", "CmgCluster.delta0=+normal(0, 0.5deg)"]
KEEP = ["SatelliteDynamics.q_BI[1]", "SatelliteDynamics.w_BI_B[2]", "CmgCluster.delta[3]"]


def timed_campaign(runs: int, stop: float, workers: int) -> tuple[float, float]:
    """(seconds for the runs once the cluster is up, cluster start-up seconds)."""
    plan = Plan(Spec(TARGET, runs, 1, VARY, stop=stop))
    with tempfile.TemporaryDirectory() as tmp:
        began = time.perf_counter()
        with engine.cluster(workers) as client:
            client.wait_for_workers(workers)
            # warm each worker up (imports, first FMU load) outside the timing
            client.run(_warm, stop)
            up = time.perf_counter()
            engine.execute(plan, Path(tmp), client, {}, report.Progress(runs, 0, False), {})
            done = time.perf_counter()
    return done - up, up - began


def _warm(stop):
    run_one(-1, TARGET, {}, None, stop, None, [], 0)


def bare_loops(runs: int, stop: float) -> tuple[float, float]:
    """Seconds for the same runs in one process: simulate() alone, and run() (simulate +
    metrics, what a campaign run does), in a fresh interpreter."""
    code = f"""
import time
from agilesat.orchestration.campaign.plan import Plan, Spec
from agilesat.orchestration import simulate, run
from agilesat.orchestration.scenarios import get
plan = Plan(Spec({TARGET!r}, {runs}, 1, {VARY!r}, stop={stop}))
ssd = get({TARGET!r}).ssd
run({TARGET!r}, stop={stop}, figures=False, build=False)   # warm up
t0 = time.perf_counter()
for i in range({runs}):
    simulate(ssd, stop={stop}, parameters=plan.parameters(i))
t1 = time.perf_counter()
for i in range({runs}):
    run({TARGET!r}, stop={stop}, parameters=plan.parameters(i), figures=False, build=False)
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.split()
    return float(out[0]), float(out[1])


def memory(runs: int, stop: float, every: int) -> list[tuple[int, float]]:
    """(runs made, worker RSS MiB) on one worker process making ``runs`` short runs."""
    import psutil

    plan = Plan(Spec(TARGET, runs, 1, VARY, stop=stop))
    samples = []
    with engine.cluster(1) as client:
        pid = client.run(lambda: __import__("os").getpid())
        worker = next(iter(pid))

        def rss():
            return client.run(lambda: psutil.Process().memory_info().rss / 2**20)[worker]

        samples.append((0, rss()))
        for start in range(0, runs, every):
            futures = [
                client.submit(
                    run_one, i, TARGET, plan.parameters(i), None, stop, None, [], 0, pure=False
                )
                for i in range(start, min(runs, start + every))
            ]
            statuses = {f.result()["status"] for f in futures}
            samples.append((min(runs, start + every), rss()))
            pid = client.run(lambda: __import__("os").getpid())[worker]
            print(
                f"  {samples[-1][0]:5d} runs: worker RSS {samples[-1][1]:7.1f} MiB "
                f"(outcomes {sorted(statuses)}; pid {pid})",
                flush=True,
            )
        reused = client.submit(
            run_one,
            0,
            TARGET,
            plan.parameters(0),
            None,
            stop,
            None,
            KEEP,
            int(round(stop / 0.05)) + 1,
            pure=False,
        ).result()
    fresh = subprocess.run(
        [
            sys.executable,
            "-c",
            f"""
import sys, numpy as np
from agilesat.orchestration.campaign.plan import Plan, Spec
from agilesat.orchestration.campaign.worker import run_one
plan = Plan(Spec({TARGET!r}, 1, 1, {VARY!r}, stop={stop}))
rows = {int(round(stop / 0.05)) + 1}
r = run_one(0, {TARGET!r}, plan.parameters(0), None, {stop}, None, {KEEP!r}, rows)
np.save(sys.argv[1], r["signals"])
""",
            str(Path(tempfile.gettempdir()) / "agilesat_fresh.npy"),
        ],
        check=True,
    )
    del fresh
    alone = np.load(Path(tempfile.gettempdir()) / "agilesat_fresh.npy")
    same = np.array_equal(reused["signals"], alone)
    print(
        f"  reused worker (after {runs} runs) vs fresh process: "
        f"{'bit-identical' if same else 'DIFFERENT'}"
    )
    return samples


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=24)
    parser.add_argument("--stop", type=float, default=30.0)
    parser.add_argument("--memory-runs", type=int, default=2000)
    parser.add_argument("--memory-stop", type=float, default=1.0)
    args = parser.parse_args()
    print(
        f"{TARGET}, {args.runs} runs of {args.stop:g} s at the scenario's step; dispersions {VARY}"
    )
    simulate_s, run_s = bare_loops(args.runs, args.stop)
    one, start1 = timed_campaign(args.runs, args.stop, 1)
    two, start2 = timed_campaign(args.runs, args.stop, 2)
    per = {
        k: v / args.runs
        for k, v in (("simulate", simulate_s), ("run", run_s), ("one", one), ("two", two))
    }
    print(f"  bare simulate() loop    {per['simulate'] * 1e3:8.1f} ms/run")
    print(f"  bare run() loop         {per['run'] * 1e3:8.1f} ms/run  (simulate + metrics)")
    print(
        f"  campaign, 1 worker      {per['one'] * 1e3:8.1f} ms/run  "
        f"{args.runs / one:6.2f} runs/s  (cluster start-up {start1:.1f} s)"
    )
    print(
        f"  campaign, 2 workers     {per['two'] * 1e3:8.1f} ms/run  "
        f"{args.runs / two:6.2f} runs/s  (cluster start-up {start2:.1f} s)"
    )
    print(f"  speed-up 2 vs 1 worker  {one / two:8.2f}×   (target ≥ 1.8×)")
    print(
        f"  overhead vs run()       {100 * (per['one'] / per['run'] - 1):+7.1f} %  "
        "(Dask, pickling, journal; target ≤ 10 %)"
    )
    print(
        f"  overhead vs simulate()  {100 * (per['one'] / per['simulate'] - 1):+7.1f} %  "
        "(the above plus the scenario's metrics)"
    )
    if args.memory_runs:
        print(f"memory: one worker, {args.memory_runs} runs of {args.memory_stop:g} s")
        samples = memory(args.memory_runs, args.memory_stop, max(1, args.memory_runs // 20))
        made, rss = np.array(samples).T
        half = len(made) // 2
        slope = np.polyfit(made[half:], rss[half:], 1)[0] if len(made) > 3 else float("nan")
        print(
            f"  RSS {rss[0]:.1f} → {rss[-1]:.1f} MiB; second half slope "
            f"{slope * 1000:.1f} MiB per 1000 runs (flat: ≈ 0)"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
