"""Do two versions of the code give the same results?  Runs every scenario and variant and
saves, or compares with a saved set (not a test: a tool for refactors and speed work).

    python tests/tools/compare_results.py save DIR [--stop T]     # on the old version
    python tests/tools/compare_results.py compare DIR [--stop T]  # on the new version

Each run is the scenario's system at its own step, to its own stop time (or T); the
comparison prints, per run, "bit-identical" or the largest relative difference
|a - b| / (the largest |value| of that column in either run) over every recorded output
and time (so a sign flip of a value near zero is not a difference of 2), and exits 1 if a run's
rows differ, a baseline column is missing, or any difference exceeds --rtol (default 0: bit
for bit).  Outputs a change added (new columns) are listed and not compared; a renamed
output is compared under its new name with ``--renamed Instance.old=Instance.new``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from agilesat.orchestration.cosim.master import simulate
from agilesat.orchestration.scenarios import NAMES, get


def runs():
    for name in NAMES:
        scenario = get(name)
        for variant in (None, *scenario.variants):
            yield f"{name}:{variant}" if variant else name, scenario, variant


def run(scenario, variant, stop):
    results = simulate(scenario.system_file(variant), stop=stop or scenario.stop)
    return np.asarray(results.names), np.asarray(results.data)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mode", choices=("save", "compare"))
    parser.add_argument("dir", type=Path)
    parser.add_argument("--stop", type=float, default=None)
    parser.add_argument("--rtol", type=float, default=0.0)
    parser.add_argument("--renamed", action="append", default=[], metavar="OLD=NEW")
    args = parser.parse_args(argv)
    renamed = dict(pair.split("=", 1) for pair in args.renamed)
    args.dir.mkdir(parents=True, exist_ok=True)
    worst = 0.0
    failed = False
    for label, scenario, variant in runs():
        path = args.dir / f"{label.replace(':', '__')}.npz"
        if args.mode == "compare" and not path.exists():
            print(f"{label:32s} not in the baseline (a variant newer than it): not compared")
            continue
        names, data = run(scenario, variant, args.stop)
        if args.mode == "save":
            np.savez(path, names=names, data=data)
            print(f"{label:32s} saved {data.shape}")
            continue
        old = np.load(path)
        old_names = [_renamed(name, renamed) for name in old["names"].tolist()]
        column = {name: j for j, name in enumerate(names.tolist())}
        missing = [name for name in old_names if name not in column]
        added = sorted(set(column) - set(old_names))
        if missing or old["data"].shape[0] != data.shape[0]:
            print(f"{label:32s} DIFFERENT rows or missing columns {missing[:5]}")
            failed = True
            continue
        new = data[:, [column[name] for name in old_names]]
        note = f" (added, not compared: {', '.join(added)})" if added else ""
        if np.array_equal(old["data"], new):
            print(f"{label:32s} bit-identical{note}")
            continue
        scale = np.maximum(abs(old["data"]).max(axis=0), abs(new).max(axis=0))
        scale[scale == 0] = 1.0
        rel = abs(old["data"] - new) / scale
        i, j = np.unravel_index(np.argmax(rel), rel.shape)
        worst = max(worst, rel[i, j])
        print(f"{label:32s} max relative difference {rel[i, j]:.3g} ({old_names[j]}, row {i})")
    if args.mode == "compare":
        print(f"worst relative difference {worst:.3g} (tolerance {args.rtol:g})")
    return 1 if failed or worst > args.rtol else 0


def _renamed(name: str, renamed: dict) -> str:
    """``name`` (a column, ``Instance.var[i]``) under the new name of its variable."""
    base, bracket, index = name.partition("[")
    return renamed.get(base, base) + bracket + index


if __name__ == "__main__":
    sys.exit(main())
