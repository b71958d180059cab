"""Print the fault-injection matrix (fault → expected → observed) of the master and file
cases (``fault_cases_master``) and of the FMU binary cases (``fault_cases_fmu``), then the
resource figures of both, as Markdown tables for the README.

    .venv/bin/python tests/tools/fault_matrix.py [--n N]

``--n`` sizes the resource loops (default 1000; the test suite uses smaller ones).  Every
row is measured in fresh processes as the script runs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE.parent)]  # the fault cases; helpers

import fault_cases_fmu  # noqa: E402
import fault_cases_master  # noqa: E402


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1000, help="size of the resource loops")
    args = parser.parse_args(argv)
    failed = 0
    print("| fault | expected | observed | |\n|---|---|---|---|")
    for module in (fault_cases_master, fault_cases_fmu):
        for case in module.CASES:
            result = case()
            verdict = "skipped" if "skipped" in result else "ok" if result["ok"] else "FAILED"
            failed += verdict == "FAILED"
            print(
                "| "
                + " | ".join(_cell(result[k]) for k in ("fault", "expected", "observed"))
                + f" | {verdict} |"
            )
            sys.stdout.flush()
    print("\n| resource figure | value |\n|---|---|")
    for module in (fault_cases_master, fault_cases_fmu):
        for figure, value in module.resource_figures(args.n):
            print(f"| {_cell(figure)} | {_cell(value)} |")
            sys.stdout.flush()
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
