"""Two checkouts of agilesat against each other, interleaved: prints a report (not a test;
timings on shared machines vary, so each round runs both, in turn, in fresh interpreters).

    python tests/tools/benchmark_revisions.py OLD_PYTHON NEW_PYTHON [--rounds N]

OLD_PYTHON and NEW_PYTHON are the interpreters of two environments with agilesat installed
(each its own checkout, its FMUs built).  Each round runs, in a fresh process of each (the
order alternating), every scenario's run at its own step (``simulate`` of the system
file, best of 5), scan_pitch's Python loop (20 s), its per-run costs (a 0.5 s run, best
of 20) and ``run()`` with the metrics (best of 5), in CPU seconds of that process; the
report gives the best of all rounds of each and the ratio new / old.  For a refactor that
must not cost speed (with tests/tools/compare_results.py for its results).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

CHILD = r"""
import json, time
from agilesat.orchestration import run, simulate
from agilesat.orchestration.scenarios import get


def best(call, n):
    times = []
    for _ in range(n):
        began = time.process_time()
        call()
        times.append(time.process_time() - began)
    return min(times)


out = {}
for name in ("scan_pitch", "payload_sweep", "video_sar", "scan_pitch:sensed", "video_sar:sensed"):
    scenario, _, variant = name.partition(":")
    ssd = get(scenario).system_file(variant or None)
    simulate(ssd)  # loads the FMUs and the kernels
    out[name] = best(lambda: simulate(ssd), 5)
ssd = get("scan_pitch").system_file(None)
simulate(ssd, loop="python", stop=20.0)
out["scan_pitch 20 s, Python loop"] = best(lambda: simulate(ssd, loop="python", stop=20.0), 3)
out["scan_pitch 0.5 s (per-run costs)"] = best(lambda: simulate(ssd, stop=0.5), 20)
run("scan_pitch", figures=False, build=False)
out["run(scan_pitch) (+ metrics)"] = best(lambda: run("scan_pitch", figures=False, build=False), 5)
print(json.dumps(out))
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old", help="the old checkout's python")
    parser.add_argument("new", help="the new checkout's python")
    parser.add_argument("--rounds", type=int, default=4)
    args = parser.parse_args()
    pythons = {"old": args.old, "new": args.new}
    best: dict[str, dict[str, float]] = {"old": {}, "new": {}}
    for r in range(args.rounds):
        for which in ("old", "new") if r % 2 == 0 else ("new", "old"):
            out = subprocess.run(
                [pythons[which], "-c", CHILD], capture_output=True, text=True, check=True
            ).stdout
            for name, seconds in json.loads(out.splitlines()[-1]).items():
                best[which][name] = min(seconds, best[which].get(name, seconds))
        print(f"round {r + 1} of {args.rounds} done", file=sys.stderr, flush=True)
    print(
        f"{'':34s} {'old':>9s} {'new':>9s}  new/old   (CPU s, best of {args.rounds} "
        "interleaved rounds)"
    )
    for name, old in best["old"].items():
        new = best["new"][name]
        print(f"{name:34s} {old:9.4f} {new:9.4f}  {new / old:6.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
