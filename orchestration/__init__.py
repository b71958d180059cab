"""The co-simulation master, system files (SSP), results, scenarios and the CLI.

Python API::

    from agilesat.orchestration import run, simulate
    results, summary = run("scan_pitch", out_dir="out/scan_pitch")   # a shipped scenario
    results = simulate("my_system.ssd", step=0.05, stop=100.0)       # any SSP system
    results["SatelliteDynamics.w_BI_B[2]"], results.vector("CmgCluster.delta")

The names are imported on first use (PEP 562), so that a submodule (the CLI's
``agilesat --help``) does not load the master, fmpy and NumPy before it needs them.
"""

import importlib

_WHERE = {
    "run": "runner",
    "simulate": "cosim.master",
    "SimulationError": "cosim.master",
    "read_system": "system.ssp",
    "SystemFileError": "system.ssp",
    "Results": "output.results",
}

__all__ = ["run", "simulate", "read_system", "Results", "SimulationError", "SystemFileError"]


def __getattr__(name):
    if name in _WHERE:
        value = getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
