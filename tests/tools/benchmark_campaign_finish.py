"""The summary a campaign writes at its end, timed on a finished campaign's directory:
prints a report (not a test; timings on a shared machine vary).

    python tests/tools/benchmark_campaign_finish.py CAMPAIGN_DIR [--nominal]

``summary.finish`` (runs.csv, the verdicts over the campaign, campaign.json, the figures)
on a copy of CAMPAIGN_DIR in a temporary directory (the original is not written): its
wall and CPU seconds and the process's peak resident memory.  The copy keeps the nominal
run campaign.json holds (made again with the same command and versions: not made), unless
``--nominal``, which drops it so that the finish makes it again in its own process.
"""

from __future__ import annotations

import argparse
import json
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

from agilesat.orchestration.campaign import engine, summary
from agilesat.orchestration.campaign.plan import Plan, Spec


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory", type=Path)
    parser.add_argument("--nominal", action="store_true", help="make the nominal run again")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as temporary:
        out = Path(temporary) / "campaign"
        shutil.copytree(args.directory, out)
        saved = json.loads((out / "campaign.json").read_text())
        if args.nominal:
            saved.pop("nominal", None)
            (out / "campaign.json").write_text(json.dumps(saved))
        plan = Plan(Spec(**saved["spec"]))
        records = {
            i: r for i, r in engine.read_journal(out / "runs.jsonl").items() if i < plan.total
        }
        metrics = json.loads((out / "metrics.json").read_text())
        wall, cpu = time.perf_counter(), time.process_time()
        done = summary.finish(plan, out, records, metrics, [], "complete", saved.get("cluster", {}))
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"{args.directory}: {len(records)} runs, {len(done.summary['figures'])} figures; "
        f"finish {wall:.2f} s wall, {cpu:.2f} s CPU of this process; peak resident memory "
        f"{peak:.0f} MiB",
        file=sys.stdout,
    )


if __name__ == "__main__":
    main()
