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

from .errors import (
    ErrorHistory,
    knowledge_error,
    performance_error,
    quaternion_product,
    rotation_quaternion,
    rotation_vector,
)
from .indices import INDICES, IndexSeries, NotEvaluable, index_series, magnitude
from .requirement import ANGLE_UNITS, PointingRequirement, PointingResult, format_angle
from .statistics import (
    INTERPRETATIONS,
    Statistic,
    allowed_exceedances,
    confidence_achieved,
    runs_needed,
    statistic,
)

__all__ = [
    "ANGLE_UNITS",
    "INDICES",
    "INTERPRETATIONS",
    "ErrorHistory",
    "IndexSeries",
    "NotEvaluable",
    "PointingRequirement",
    "PointingResult",
    "Statistic",
    "allowed_exceedances",
    "confidence_achieved",
    "format_angle",
    "index_series",
    "knowledge_error",
    "magnitude",
    "performance_error",
    "quaternion_product",
    "rotation_quaternion",
    "rotation_vector",
    "runs_needed",
    "statistic",
]
