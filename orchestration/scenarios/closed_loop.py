"""The attitude loop as flown, for the shipped scenarios' ``sensed`` variants
(docs/sensing.md): a star tracker and a gyro measure the hub, an MEKF estimates, the
command side (controller, steering, wheel drive) reads the estimate instead of the truth,
and the disturbance torques act on the hub.

Each FMU at its defaults, the datasheet-class values of docs/sensing.md (SSTL Rigel-L
star tracker, STIM300 gyro, the MEKF tuned from them, the illustrative facet model of the
disturbances); only the star tracker's mounting is the scenario's, chosen so that it
never looks into the Sun or the Earth during the run (``star_tracker_valid`` says so).

The truth side stays on the truth: the sensors and the disturbance torques read
``SatelliteDynamics``, the estimator reads the sensors.  The summaries then tell the two
errors of [Ecss 2008] apart: the *performance* error (true attitude against the
reference, the scenario's own metrics) and the *knowledge* error (estimate against the
truth, :data:`KNOWLEDGE_METRICS`).
"""

from __future__ import annotations

import math

import numpy as np

from agilesat.orchestration.mission import NotEvaluable, System
from agilesat.orchestration.mission import metrics as m
from agilesat.orchestration.output.results import per_results
from agilesat.orchestration.pointing import PointingRequirement, knowledge_error
from agilesat.orchestration.scenarios.constants import KNOWLEDGE_START, POINTING_LEVEL

ARCSEC = math.pi / 648_000
#: figure units: (rad per unit, as printed)
UNITS = {"arcsec": (ARCSEC, "arcsec"), "urad": (1e-6, "µrad")}
#: what makes the sensors exact: no noise, bias, scale factor, misalignment, quantisation
#: or latency; the star tracker samples at every step of 0.05 s; the filter trusts it
#: (a tiny NEA: the estimate is the measurement) and keeps a zero bias estimate; no
#: disturbance torque.  The gyro still measures the average rate over its sample interval
#: (a rate-integrating unit), half its period late: with the step it is a first-order
#: coupling error (tests/papers/test_closed_loop.py).
PERFECT = {
    "StarTracker.nea_cross": 0.0,
    "StarTracker.nea_boresight": 0.0,
    "StarTracker.bias_lf": [0.0, 0.0, 0.0],
    "StarTracker.latency": 0.0,
    "StarTracker.rate": 20.0,
    "Gyro.arw": 0.0,
    "Gyro.rrw": 0.0,
    "Gyro.bias_instability": 0.0,
    "Gyro.bias0": [0.0, 0.0, 0.0],
    "Gyro.scale_factor": [0.0, 0.0, 0.0],
    "Gyro.misalignment": np.zeros((3, 3)).tolist(),
    "Gyro.quantization": 0.0,
    "AttitudeEstimator.nea_cross": 1e-12,
    "AttitudeEstimator.nea_boresight": 1e-12,
    "AttitudeEstimator.rrw": 0.0,
    "AttitudeEstimator.sigma_bias0": 1e-15,
    "DisturbanceTorques.aero": False,
    "DisturbanceTorques.srp": False,
    "DisturbanceTorques.magnetic": False,
}


def mounting(boresight) -> list[float]:
    """q_SB of a star tracker whose boresight +z_S points along ``boresight`` (body axes):
    the shortest rotation from z_B to it (C_SBᵀ ẑ = boresight)."""
    b = np.asarray(boresight, dtype=float) / np.linalg.norm(boresight)
    axis = np.cross((0.0, 0.0, 1.0), b)
    s, c = np.linalg.norm(axis), b[2]
    if s == 0.0:
        return [1.0, 0.0, 0.0, 0.0] if c > 0 else [0.0, 1.0, 0.0, 0.0]
    half = math.atan2(s, c) / 2
    return [math.cos(half), *(math.sin(half) * axis / s)]


def close_the_loop(
    system: System, *, controller: str, mount, frame: str = "BI", rate_inputs=()
) -> None:
    """Add StarTracker, Gyro, AttitudeEstimator and DisturbanceTorques to ``system`` and
    rewire the ``controller``'s attitude inputs to the estimate: q_BI, w_BI_B (``frame``
    "BI"), or q_BO, w_BO_B ("BO": the estimator is given the orbit frame of
    OrbitEnvironment and gives the estimate relative to it); ``rate_inputs`` (other inputs
    of the command side that take the body rate) too.  ``mount``: the star tracker's
    q_SB (the filter is told the same)."""
    mount = [float(x) for x in mount]
    system.add("StarTracker", q_SB=mount)
    system.add("Gyro")
    system.add("AttitudeEstimator", q_SB=mount)
    system.add("DisturbanceTorques")
    for signal in ("q_BI", "w_BI_B"):
        system.connect(f"SatelliteDynamics.{signal}", f"StarTracker.{signal}")
        system.connect(f"SatelliteDynamics.{signal}", f"DisturbanceTorques.{signal}")
    for signal in ("sun_I", "r_I"):
        system.connect(f"OrbitEnvironment.{signal}", f"StarTracker.{signal}")
    for signal in ("r_I", "v_I", "sun_I", "earth_angle"):
        system.connect(f"OrbitEnvironment.{signal}", f"DisturbanceTorques.{signal}")
    system.connect("SatelliteDynamics.w_BI_B", "Gyro.w_BI_B")
    system.connect("Gyro.w_meas_B", "AttitudeEstimator.w_meas_B")
    system.connect("StarTracker.q_BI_meas", "AttitudeEstimator.q_BI_meas")
    system.connect("StarTracker.valid", "AttitudeEstimator.meas_valid")
    system.connect("StarTracker.t_meas", "AttitudeEstimator.t_meas")
    system.connect("DisturbanceTorques.tau_ext_B", "SatelliteDynamics.tau_ext")
    if frame == "BO":
        system.connect("OrbitEnvironment.q_OI", "AttitudeEstimator.q_OI")
        system.connect("OrbitEnvironment.w_OI_O", "AttitudeEstimator.w_OI_O")
    elif frame != "BI":
        raise ValueError(f"frame must be 'BI' or 'BO', got {frame!r}")
    system.connect(f"AttitudeEstimator.q_{frame}_est", f"{controller}.q_{frame}", replace=True)
    system.connect(f"AttitudeEstimator.w_{frame}_B_est", f"{controller}.w_{frame}_B", replace=True)
    for target in rate_inputs:
        system.connect("AttitudeEstimator.w_BI_B_est", target, replace=True)


#: how the knowledge metrics and figures say their window
AFTER_START_UP = f"from t = {KNOWLEDGE_START:g} s, after the estimator's start-up"


@per_results
def valid_knowledge_error(results):
    """The knowledge error (estimate against truth) over the valid estimates from
    :data:`KNOWLEDGE_START` on, computed once per results (the knowledge indices read it);
    :class:`NotEvaluable` with fewer than 2 of them."""
    valid = (results["AttitudeEstimator.valid"] > 0) & (results.time >= KNOWLEDGE_START)
    if valid.sum() < 2:
        raise NotEvaluable(
            f"fewer than 2 valid estimates from t = {KNOWLEDGE_START:g} s on (the run "
            f"covers {results.time[0]:g} … {results.time[-1]:g} s)"
        )
    return knowledge_error(
        results.vector("AttitudeEstimator.q_BI_est")[valid],
        results.vector("SatelliteDynamics.q_BI")[valid],
        results.time[valid],
    )


def knowledge_index(index: str, window: float | None = None) -> m.Metric:
    """The ECSS knowledge index (AKE, RKE, ...) of the 3-axis knowledge error at 99.73 %
    of the run's time (temporal interpretation; docs/pointing.md), over the valid
    estimates from :data:`KNOWLEDGE_START` on (after the estimator's start-up)."""
    requirement = PointingRequirement(index, None, POINTING_LEVEL, "temporal", window=window)

    def compute(results):
        result = requirement.evaluate(valid_knowledge_error(results))
        if result.value is None:
            raise NotEvaluable(result.reason)
        return result.value

    label = requirement.label()
    return m.Metric(
        f"knowledge_{index.lower()}" + ("" if window is None else f"_{window:g}s"),
        compute,
        "rad",
        "arcsec",
        f"{label} at {100 * POINTING_LEVEL:g} % of the time (knowledge, 3-axis), " + AFTER_START_UP,
    )


#: the knowledge error, the star tracker's availability and the disturbances' size
KNOWLEDGE_METRICS = [
    knowledge_index("AKE"),
    knowledge_index("RKE", window=1.0),
    m.pointing_error(
        "AttitudeEstimator.q_BI_est",
        "SatelliteDynamics.q_BI",
        start=KNOWLEDGE_START,
        name="knowledge_error_max",
        display_unit="arcsec",
        description="max angle of the estimated attitude from the true one (knowledge, "
        f"3-axis), {AFTER_START_UP}",
    ),
    m.pointing_error(
        "AttitudeEstimator.q_BI_est",
        "SatelliteDynamics.q_BI",
        statistic="rms",
        start=KNOWLEDGE_START,
        name="knowledge_error_rms",
        display_unit="arcsec",
        description="RMS angle of the estimated attitude from the true one (knowledge, "
        f"3-axis), {AFTER_START_UP}",
    ),
    m.mean(
        "StarTracker.valid",
        name="star_tracker_valid",
        unit="1",
        description="fraction of the run with a valid star-tracker sample (outside its "
        "Sun, Earth and rate exclusions)",
    ),
    m.max_abs(
        "DisturbanceTorques.tau_ext_B",
        norm=True,
        name="disturbance_torque_max",
        description="max |drag + solar pressure + residual-dipole torque|",
    ),
]


def knowledge_angles(results) -> np.ndarray:
    """The knowledge error (rad): rotation vector of the estimate from the truth, (N, 3)."""
    error = knowledge_error(
        results.vector("AttitudeEstimator.q_BI_est"),
        results.vector("SatelliteDynamics.q_BI"),
        results.time,
    )
    return error.values[0]


def knowledge_rows(results, unit: str = "arcsec") -> list:
    """Figure rows (:func:`..mission.panels`) of the knowledge error about each body axis,
    with the filter's own ±3σ, over the valid estimates from :data:`KNOWLEDGE_START` on
    (after the estimator's start-up, as the knowledge metrics), in ``unit`` ("arcsec" or
    "urad")."""
    scale, shown = UNITS[unit]
    t = results.time
    valid = (results["AttitudeEstimator.valid"] > 0) & (t >= KNOWLEDGE_START)
    knowledge = knowledge_angles(results)[valid] / scale
    sigma = 3 * results.vector("AttitudeEstimator.sigma_att")[valid] / scale
    return [
        (
            t[valid],
            {
                f"knowledge error about {axis}_B": knowledge[:, i],
                "filter 3σ": sigma[:, i],
                "filter −3σ": -sigma[:, i],
            },
            f"{axis}_B [{shown}], t ≥ {KNOWLEDGE_START:g} s",
        )
        for i, axis in enumerate("xyz")
    ]


def magnitude_row(t, label: str, error, ylabel: str, unit: str = "arcsec", limit=None):
    """A figure row of |error| (rad, or rad/s) on a logarithmic axis in ``unit`` (per second
    for a rate), with the requirement ``limit`` = (bound, label) drawn; the axis starts at
    a ten-thousandth of the bound (a run starting on its reference starts at zero error)."""
    scale, shown = UNITS[unit]
    error = np.abs(np.asarray(error)) / scale
    marks: dict = {"log": True}
    if limit is not None:
        marks.update(limit=((limit[0] / scale,), limit[1]), bottom=1e-4 * limit[0] / scale)
    return (t, {label: np.where(error > 0, error, np.nan)}, ylabel.format(unit=shown), marks)
