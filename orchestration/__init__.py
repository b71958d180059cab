"""The co-simulation master, system files (SSP), results, scenarios and the CLI.

The flow: :mod:`.system` reads and checks a system, :mod:`.cosim` runs it, :mod:`.output`
records and shows what it did; :mod:`.mission` describes a mission in Python (a
:class:`~.mission.System`, its metrics, requirements, variants: the shipped
:mod:`.scenarios` are written on it), :mod:`.campaign` and :mod:`.studies` are built on
them, and :mod:`.runner` and :mod:`.cli` put them together.

Python API::

    from agilesat.orchestration import run, simulate
    results, summary = run("scan_pitch", out_dir="out/scan_pitch")   # a shipped scenario
    results, summary = run("path/to/mission.py:variant")            # a mission of yours
    results = simulate("my_system.ssd", step=0.05, stop=100.0)       # any SSP system
    options = RunOptions(stop=100.0, record=["SatelliteDynamics.*"])  # what both take
    results, summary = run("scan_pitch", options)
    results["SatelliteDynamics.w_BI_B[2]"], results.vector("CmgCluster.delta")
    assert_within(results, "SatelliteDynamics.w_BI_B[2]", -0.02, 0.02)  # and the other checks
    assert_pointing(results, "RPE", window=1.0, bound=1.7e-5, reference="StaringGuidance.q_ref")

The names are imported on first use (PEP 562), so that a submodule (the CLI's
``agilesat --help``) does not load the master, fmpy and NumPy before it needs them.
"""

import importlib

_WHERE = {
    "run": "runner",
    "simulate": "cosim.master",
    "RunOptions": "cosim.options",
    "SimulationError": "cosim.master",
    "read_system": "system.ssp",
    "SystemFileError": "system.ssp",
    "Results": "output.results",
    "assert_within": "postprocess.checks",
    "assert_settles": "postprocess.checks",
    "assert_momentum_conserved": "postprocess.checks",
    "assert_requirements_met": "postprocess.checks",
    "assert_pointing": "postprocess.checks",
    "System": "mission",
    "Scenario": "mission",
    "Variant": "mission",
    "deg": "mission",
}

__all__ = list(_WHERE)


def __getattr__(name):
    if name in _WHERE:
        value = getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
