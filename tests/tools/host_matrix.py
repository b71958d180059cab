"""The host matrix of docs/hosts.md: each shipped scenario, exported, in every host that
runs packages, against our master's run of the same package.

    python tests/tools/host_matrix.py OUT_DIR

Prints, per scenario and host, whether the run reached its end and the largest difference
of the attitude columns the host tests compare (``HOST_CASES``, tests/helpers.py) from our
master's, in degrees.  The hosts: libcosim (tests/tools/libcosim_run.py), ECOS with the set
name and without (tests/tools/ecos_run.py), OMSimulator with and without
``--inputExtrapolation=true`` (where ``AGILESAT_OMSIMULATOR`` names it), the generic
interpolating host with and without derivatives, and reading the outputs right after the
step (Jacobi and Gauss-Seidel, with derivatives: tests/tools/interpolating_host.py).  Then
what each package states of the held-input Jacobi class (orchestration/coupling_error.py)
beside libcosim's and ECOS's attitude difference (the largest rotation between the q_BI).
The tools are this script's; agilesat is the interpreter's: run it with another checkout's
environment to measure that version.
"""

import csv
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

TOOLS = Path(__file__).resolve().parent
sys.path[:0] = [str(TOOLS.parent), str(TOOLS)]
from agilesat.orchestration.cosim.master import simulate  # noqa: E402
from agilesat.orchestration.scenarios import NAMES, get  # noqa: E402
from helpers import HOST_CASES  # noqa: E402


def worst(names, data, ours, scenario, prefix=""):
    columns = HOST_CASES[scenario][1]
    return max(
        float(
            np.max(
                np.abs(data[:, names.index(prefix + c)] - np.interp(data[:, 0], ours.time, ours[c]))
            )
        )
        for c in columns
    )


def saved(path):
    found = np.load(path)
    return list(found["names"]), found["data"]


def ecos(package, scenario, out, name):
    stop, columns = HOST_CASES[scenario]
    npz = out / f"{scenario}_ecos_{name}.npz"
    step = str(get(scenario).step)
    command = [sys.executable, str(TOOLS / "ecos_run.py"), str(package), str(stop), step, name]
    quaternion = [f"SatelliteDynamics.q_BI[{i}]" for i in (1, 2, 3, 4)]
    run = subprocess.run(
        [*command, str(npz), *columns, *quaternion], capture_output=True, text=True, cwd=out
    )
    return "" if run.returncode == 0 else "failed; ", *saved(npz)


def oms(package, scenario, out, *options):
    stop, _ = HOST_CASES[scenario]
    result = out / f"{scenario}_oms{len(options)}.csv"
    result.unlink(missing_ok=True)
    run = subprocess.run(
        [os.environ["AGILESAT_OMSIMULATOR"], f"--stopTime={stop}", f"--resultFile={result}"]
        + [f"--tempDir={out}", *options, str(package)],
        capture_output=True,
        text=True,
        cwd=out,
    )
    errors = sum(line.startswith("error") for line in (run.stdout + run.stderr).splitlines())
    rows = list(csv.reader(result.open()))
    data = np.array(rows[1:], dtype=float)
    data = data[np.append(data[1:, 0] != data[:-1, 0], True)]  # the rows after each step
    steps = round(stop / get(scenario).step)
    note = f"{errors} errors; " if errors else ""
    if len(data) < steps + 1:  # it writes a row at the stop time all the same
        note, data = note + f"stopped after {len(data) - 2} of {steps} steps; ", data[:0]
    return note, rows[0], data


def generic(package, scenario, out, *options):
    stop, _ = HOST_CASES[scenario]
    npz = out / f"{scenario}_generic{''.join(options)}.npz"
    command = [sys.executable, str(TOOLS / "interpolating_host.py"), str(package), str(stop)]
    run = subprocess.run(
        [*command, str(get(scenario).step), str(npz), *options], capture_output=True
    )
    names, data = saved(npz)
    return "" if run.returncode == 0 else f"stopped at t = {data[-1, 0]:g} s; ", names, data


def libcosim(package, scenario, out):
    stop, _ = HOST_CASES[scenario]
    npz = out / f"{scenario}_libcosim.npz"
    command = [sys.executable, str(TOOLS / "libcosim_run.py"), str(package), str(stop)]
    run = subprocess.run([*command, str(npz)], capture_output=True, text=True, cwd=out)
    return "" if run.returncode == 0 else "failed; ", *saved(npz)


def attitude(names, data, ours, prefix=""):
    """The largest rotation (rad) between a host's q_BI and our master's."""
    q = np.column_stack(
        [data[:, names.index(f"{prefix}SatelliteDynamics.q_BI[{i}]")] for i in (1, 2, 3, 4)]
    )
    mine = np.column_stack(
        [
            np.interp(data[:, 0], ours.time, ours[f"SatelliteDynamics.q_BI[{i}]"])
            for i in (1, 2, 3, 4)
        ]
    )
    mine /= np.linalg.norm(mine, axis=1)[:, None]
    return float(np.max(2 * np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", q, mine)), 0, 1))))


def main(out: Path) -> None:
    from agilesat.orchestration.coupling_error import HOST_CLASSES, measure

    out.mkdir(parents=True, exist_ok=True)
    hosts = {
        "libcosim": lambda p, s: libcosim(p, s, out),
        "ECOS, set name given": lambda p, s: ecos(p, s, out, s),
        "ECOS, no set name": lambda p, s: ecos(p, s, out, "-"),
        "generic interpolating host": lambda p, s: generic(p, s, out),
        "generic host, no derivatives": lambda p, s: generic(p, s, out, "--no-derivatives"),
        "generic interpolating host, outputs read right after the step": lambda p, s: generic(
            p, s, out, "--read-after-step"
        ),
        "generic interpolating host, Gauss-Seidel, outputs read right after the step": (
            lambda p, s: generic(p, s, out, "--gauss-seidel", "--read-after-step")
        ),
    }
    if os.environ.get("AGILESAT_OMSIMULATOR"):
        hosts["OMSimulator"] = lambda p, s: oms(p, s, out)
        hosts["OMSimulator --inputExtrapolation=true"] = lambda p, s: oms(
            p, s, out, "--inputExtrapolation=true"
        )
    else:
        print("OMSimulator not given: set AGILESAT_OMSIMULATOR to measure it")
    cells = {host: [] for host in hosts}
    held = next(host for host in HOST_CLASSES if host.startswith("held inputs, Jacobi"))
    stated = {"stated by the package (held inputs, Jacobi)": [], "libcosim": [], "ECOS": []}
    for scenario in NAMES:
        package = out / f"{scenario}.ssp"
        export = [sys.executable, "-m", "agilesat.orchestration", "export", scenario, "--out"]
        subprocess.run([*export, str(package)], check=True, capture_output=True)
        ours = simulate(str(package), stop=HOST_CASES[scenario][0])
        for host, run in hosts.items():
            note, names, data = run(package, scenario)
            prefix = f"{scenario}.{scenario}." if host.startswith("OMSimulator") else ""
            if len(data) > 1:
                note += f"{math.degrees(worst(names, data, ours, scenario, prefix)):.2g}°"
                if host in ("libcosim", "ECOS, set name given"):
                    found = math.degrees(attitude(names, data, ours))
                    stated[host.split(",")[0]].append(f"{found:.4g}°")
            cells[host].append(note.removesuffix("; "))
        claim = measure(package, stop=HOST_CASES[scenario][0])[1][held]["attitude"][0]
        stated["stated by the package (held inputs, Jacobi)"].append(f"{math.degrees(claim):.4g}°")
    for title, table in (("host", cells), ("attitude (rotation of q_BI)", stated)):
        print(f"| {title} | " + " | ".join(NAMES) + " |")
        print("|---" * (len(NAMES) + 1) + "|")
        for host, row in table.items():
            print(f"| {host} | " + " | ".join(row) + " |")
        print()


if __name__ == "__main__":
    main(Path(sys.argv[1]))
