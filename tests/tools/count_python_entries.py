"""How often a macro step of scan_pitch enters Python in the FMUs: calls from the master
(through ctypes, the shim and pythonfmu) into the slaves (fmus/slave.py), per macro step,
with the shim's fast path on and off (AGILESAT_SHIM_FAST, read at instantiation).  Prints
a report (not a test).  Each count is the difference of two runs (stop T and 2T), so
instantiation and initialisation do not count.

    python tests/tools/count_python_entries.py [--step H] [--stop T]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

RUN = r"""
import collections, json, sys
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get

step, stop = float(sys.argv[1]), float(sys.argv[2])
entries = collections.Counter()

def profile(frame, event, arg):
    if event == "call" and frame.f_code.co_filename.endswith("fmus/slave.py"):
        caller = frame.f_back
        if caller is None or not caller.f_code.co_filename.endswith("fmus/slave.py"):
            name = frame.f_code.co_name
            if name == "wrapper":  # slave._guarded
                name = frame.f_locals["method"].__name__
            entries[name] += 1

ssd = get("scan_pitch").ssd
sys.setprofile(profile)
simulate(ssd, step=step, stop=stop)
sys.setprofile(None)
print(json.dumps(entries))
"""


def count(fast: str, step: float, stop: float) -> dict:
    env = {**__import__("os").environ, "AGILESAT_SHIM_FAST": fast}
    result = subprocess.run(
        [sys.executable, "-c", RUN, str(step), str(stop)],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    )
    return json.loads(result.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--step", type=float, default=0.05)
    parser.add_argument("--stop", type=float, default=10.0)
    args = parser.parse_args()
    steps = round(args.stop / args.step)
    print(f"scan_pitch at {args.step:g} s: Python entries per macro step (all five FMUs)")
    for fast in ("0", "1"):
        short, long = count(fast, args.step, args.stop), count(fast, args.step, 2 * args.stop)
        per_step = {name: (long.get(name, 0) - short.get(name, 0)) / steps for name in long}
        total = sum(per_step.values())
        detail = ", ".join(f"{name} {n:g}" for name, n in sorted(per_step.items()) if n)
        label = "fast path off" if fast == "0" else "fast path on "
        print(f"  {label}: {total:5.2f}  ({detail})")


if __name__ == "__main__":
    main()
