"""Run an SSP package in ECOS (ecospy) and save the chosen outputs after every step.

    python ecos_run.py SYSTEM.ssp STOP STEP PARAMETER_SET OUT.npz COLUMN...

Run as a script in a fresh process (tests/interop/test_ecos.py).  ECOS reads the package itself
(its SSP loader) and applies, at init, only the one parameter set named PARAMETER_SET: our
exports give every component's set the system's name; "-" passes no name (ECOS's default),
and the FMUs' own defaults, which our exports configure, apply.  COLUMN is "<instance>.<name>",
read through ECOS's identifier "<instance>::<name>".  Columns "time", then COLUMN...,
rows after each step (as libcosim_run.py).  Exit status 2 with ECOS's message if a call
fails; the rows recorded so far are saved all the same.
"""

import sys

import numpy as np
from ecospy import EcosSimulation


def main(path, stop, step, parameter_set, out, *columns):
    stop, step = float(stop), float(step)
    rows = []
    sim = EcosSimulation(ssp_path=path, step_size=step)
    try:
        if not sim.init(parameter_set=None if parameter_set == "-" else parameter_set):
            raise RuntimeError(f"ECOS: init with parameter set {parameter_set!r} failed")
        identifiers = [c.replace(".", "::", 1) for c in columns]
        for k in range(1, round(stop / step) + 1):
            t = sim.step(1)
            if abs(t - k * step) > 1e-9 * max(1.0, stop):
                raise RuntimeError(f"ECOS: step {k} ended at t = {t!r}, not {k * step!r}")
            rows.append([t, *map(sim.get_real, identifiers)])
        sim.terminate()
    finally:
        np.savez(out, names=np.array(["time", *columns]), data=np.array(rows, dtype=float))


if __name__ == "__main__":
    try:
        main(*sys.argv[1:])
    except Exception as error:  # noqa: BLE001 - report ECOS's message, keep the rows
        print(error, file=sys.stderr)
        sys.exit(2)
