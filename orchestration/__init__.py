"""The co-simulation master, system files (SSP), results, scenarios and the CLI.

Python API::

    from agilesat.orchestration import run, simulate
    results, summary = run("scan_pitch", out_dir="out/scan_pitch")   # a shipped scenario
    results = simulate("my_system.ssd", step=0.05, stop=100.0)       # any SSP system
    results["SatelliteDynamics.w_BI_B[2]"], results.vector("CmgCluster.delta")
"""

from .master import SimulationError, simulate
from .results import Results
from .runner import run
from .ssp import SystemFileError, read_system

__all__ = ["run", "simulate", "read_system", "Results", "SimulationError", "SystemFileError"]
