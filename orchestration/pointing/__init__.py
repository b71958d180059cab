"""ECSS-E-ST-60-10C pointing error indices of simulated runs and campaigns ([Ecss 2008]).

Pure NumPy (SciPy for the binomial distribution): nothing here imports FMI or the rest of
the orchestration, so it works on any arrays.  See docs/pointing.md.

    from agilesat.orchestration.pointing import PointingRequirement, performance_error
    error = performance_error(q_BI, q_RI, t)        # (runs, samples, 4) each, t in s
    result = PointingRequirement("RPE", bound=math.radians(0.001), level=0.9973,
                                 interpretation="ensemble", window=1.0,
                                 boresight=(0, 0, 1), confidence=0.95).evaluate(error)
    print(result.line("arcsec"))
"""

import importlib

from .names import ANGLE_UNITS, INDICES, INTERPRETATIONS

_WHERE = {
    **dict.fromkeys(
        (
            "ErrorHistory",
            "knowledge_error",
            "performance_error",
            "quaternion_product",
            "rotation_quaternion",
            "rotation_vector",
        ),
        "errors",
    ),
    **dict.fromkeys(
        (
            "IndexSeries",
            "NotEvaluable",
            "index_series",
            "magnitude",
            "position_weights",
            "window_positions",
        ),
        "indices",
    ),
    **dict.fromkeys(("PointingRequirement", "PointingResult", "format_angle"), "requirement"),
    **dict.fromkeys(
        (
            "Statistic",
            "allowed_exceedances",
            "confidence_achieved",
            "runs_needed",
            "statistic",
        ),
        "statistics",
    ),
    **dict.fromkeys(("Decision", "decide", "decide_counts", "next_look"), "verdicts"),
}


def __getattr__(name):
    """The names are imported on first use (PEP 562): the options' names (:mod:`.names`)
    come without NumPy and SciPy."""
    if name in _WHERE:
        value = getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "ANGLE_UNITS",
    "INDICES",
    "INTERPRETATIONS",
    "Decision",
    "ErrorHistory",
    "IndexSeries",
    "NotEvaluable",
    "PointingRequirement",
    "PointingResult",
    "Statistic",
    "allowed_exceedances",
    "confidence_achieved",
    "decide",
    "decide_counts",
    "format_angle",
    "index_series",
    "knowledge_error",
    "magnitude",
    "next_look",
    "performance_error",
    "position_weights",
    "quaternion_product",
    "rotation_quaternion",
    "rotation_vector",
    "runs_needed",
    "statistic",
    "window_positions",
]
