"""Your own mission in Python: a system, its metrics, requirements, variants and figures.

    from agilesat.orchestration.mission import Scenario, System, Variant, at_most, deg
    from agilesat.orchestration.mission import metrics, panels

- :class:`System` (:mod:`.system`): components (our FMUs by name, any FMI 2.0 FMU file, a
  model of yours), connections of whole vectors by base name, parameter values with units,
  the algorithm, step, stop, multi-rate and derivatives; checked against the FMUs' model
  descriptions, written as SSD or SSP.
- :class:`Scenario` and :class:`Variant` (:mod:`.scenario`): what ``agilesat run
  mission.py[:variant]`` runs and judges.
- :mod:`.metrics`: settling time, max/RMS over a window, pointing error from quaternions,
  rate error, saturation fraction, momentum margin, singularity measure, ...
- :mod:`.requirements`: bounds on metrics (``at_most``, ``at_least``, ``within``), ECSS
  pointing requirements (:class:`Pointing`), and the protocol any requirement follows.
- :func:`lines`, :func:`panels`: figures for a report (:mod:`..output.plots`).
- :func:`deg`, :func:`arcsec`, :class:`Quantity`: values with units.
- :func:`timeline` of :func:`inertial`, :func:`nadir`, :func:`stare` segments
  (:mod:`.timeline`): SlewGuidance's segment table.
"""

from ..output.plots import lines, panels
from ..system.units import Quantity, arcsec, deg
from . import metrics
from .metrics import Metric, NotEvaluable
from .requirements import (
    Bound,
    Pointing,
    Requirement,
    Verdict,
    at_least,
    at_most,
    within,
)
from .scenario import Scenario, SignalBound, Variant
from .system import System
from .targets import resolve
from .timeline import inertial, nadir, stare, timeline

__all__ = [
    "Bound",
    "Metric",
    "NotEvaluable",
    "Pointing",
    "Quantity",
    "Requirement",
    "Scenario",
    "SignalBound",
    "System",
    "Variant",
    "Verdict",
    "arcsec",
    "at_least",
    "at_most",
    "deg",
    "inertial",
    "lines",
    "metrics",
    "nadir",
    "panels",
    "resolve",
    "stare",
    "timeline",
    "within",
]
