"""Print the fault-injection matrix (fault → expected → observed) of every fault-case
module (``fault_cases_*.py``: the master and its files, runs and their interruptions,
inputs, missions of a user's own, what a run leaves and what reads it back, campaigns, FMU
states and what is loaded, the FMU binary), the counts of cases that held, failed and were
skipped, then the resource figures, as Markdown for the docs
(docs/reliability.md).

    .venv/bin/python tests/tools/fault_matrix.py [--n N] [--no-figures] [--brief] [--only MODULE]

``--n`` sizes the resource loops (default 1000; the test suite uses smaller ones);
``--no-figures`` leaves them out; ``--brief`` leaves out the observed column (its temporary
paths and hashes: the docs' pages keep no diary, the performance log the full table);
``--only fault_cases_runs`` runs one module.  Every row
is measured in fresh processes as the script runs; the exit status is 1 if a case failed.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE.parent)]  # the fault cases; helpers

import fault_cases_campaign  # noqa: E402
import fault_cases_fmu  # noqa: E402
import fault_cases_inputs  # noqa: E402
import fault_cases_master  # noqa: E402
import fault_cases_mission  # noqa: E402
import fault_cases_records  # noqa: E402
import fault_cases_runs  # noqa: E402
import fault_cases_state  # noqa: E402

MODULES = (
    fault_cases_master,
    fault_cases_runs,
    fault_cases_inputs,
    fault_cases_mission,
    fault_cases_records,
    fault_cases_campaign,
    fault_cases_state,
    fault_cases_fmu,
)


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1000, help="size of the resource loops")
    parser.add_argument("--no-figures", action="store_true", help="no resource figures")
    parser.add_argument("--brief", action="store_true", help="no observed column")
    parser.add_argument("--only", choices=[m.__name__ for m in MODULES], help="one module")
    args = parser.parse_args(argv)
    modules = [m for m in MODULES if args.only in (None, m.__name__)]
    counts = {"ok": 0, "FAILED": 0, "skipped": 0}
    columns = ("fault", "expected") if args.brief else ("fault", "expected", "observed")
    print("| " + " | ".join(columns) + " | |\n|" + "---|" * (len(columns) + 1))
    for module in modules:
        for case in module.CASES:
            result = case()
            verdict = "skipped" if "skipped" in result else "ok" if result["ok"] else "FAILED"
            counts[verdict] += 1
            print("| " + " | ".join(_cell(result[k]) for k in columns) + f" | {verdict} |")
            sys.stdout.flush()
    print(
        f"\n{sum(counts.values())} cases: {counts['ok']} held, {counts['FAILED']} failed, "
        f"{counts['skipped']} skipped"
    )
    if not args.no_figures:
        print("\n| resource figure | value |\n|---|---|")
        for module in modules:
            for figure, value in getattr(module, "resource_figures", lambda n: [])(args.n):
                print(f"| {_cell(figure)} | {_cell(value)} |")
                sys.stdout.flush()
    return 1 if counts["FAILED"] else 0


if __name__ == "__main__":
    sys.exit(main())
