"""The models' kernel cases every fast-path lane runs (tests/fast_paths/test_kernels_models.py:
compiled against Python; test_kernel_convention.py: a kernel against its method): the
configurations whose kernels take other branches (limits, laws, orbits, sensors' timing,
input derivatives a host sets) and the inputs that exercise them, and every other model
with kernels at its defaults on random inputs (a new model is in the lanes by itself; one
whose inputs must be more than random adds its cases here)."""

import numpy as np

from agilesat.components import orbit_environment
from agilesat.components.attitude_controller import AttitudeController
from agilesat.components.attitude_estimator import AttitudeEstimator
from agilesat.components.cmg_cluster import CmgCluster
from agilesat.components.cmg_steering import SR_INVERSE, CmgSteering
from agilesat.components.disturbance_torques import DisturbanceTorques
from agilesat.components.flywheel import Flywheel
from agilesat.components.gyro import Gyro
from agilesat.components.orbit_environment import OrbitEnvironment
from agilesat.components.payload_gimbals import PayloadGimbals
from agilesat.components.pitch_maneuver_controller import PitchManeuverController
from agilesat.components.runtime import jit
from agilesat.components.satellite_dynamics import SatelliteDynamics
from agilesat.components.sensing import quat_exp
from agilesat.components.star_tracker import StarTracker
from agilesat.components.staring_guidance import StaringGuidance
from agilesat.components.sweep_planner import SweepPlanner
from agilesat.fmus import FMUS, model_class
from agilesat.orchestration.scenarios import video_sar
from helpers import ISS_TLE

STEP = 0.05


def snapshot(model):
    state = model.state.copy()
    if isinstance(model, OrbitEnvironment):  # the addresses of its own SGP4 record
        state[orbit_environment.S.sgp4 : orbit_environment.S.sgp4 + 2] = 0.0
    return model.values.tobytes(), state.tobytes(), list(model.warnings)


# -- each model alone on random inputs ---------------------------------------------------
def random_run(model, steps: int, seed: int, scale: float, inputs=None, rates=None):
    """The model started, then random inputs (or ``inputs(k, variable)``) and the input
    derivatives ``rates(k)`` ({input: derivative}, a host interpolating them) before each
    step; the values, state and warnings after the start and each step."""
    rng = np.random.default_rng(seed)
    model.start(0.0)
    record = [snapshot(model)]
    for k in range(steps):
        for v in model.layout.group("input"):
            value = inputs(k, v) if inputs else rng.uniform(-scale, scale, size=v.size)
            model.set(v.name, value)
        for name, rate in (rates(k) if rates else {}).items():
            model.set_input_rate(name, rate)
        model.advance(k * STEP, STEP)
        record.append(snapshot(model))
    return record


def unit_quaternions(seed: int, scale: float):
    """Random inputs in (−scale, scale), the quaternions made unit (a function of k); an
    Integer input (a controller's mode) a whole number 0 to 7, a Boolean one (a gimbal's
    health) mostly true."""

    def inputs(k, v):
        rng = np.random.default_rng([seed, k, sum(map(ord, v.name))])
        if v.type == "Integer":
            return rng.integers(0, 8, size=v.size).astype(float)
        if v.type == "Boolean":
            return (rng.random(size=v.size) < 0.8).astype(float)
        x = rng.uniform(-scale, scale, size=v.size)
        return x / np.linalg.norm(x) if v.name.startswith("q_") else x

    return inputs


def in_orbit(seed: int, scale: float):
    """:func:`unit_quaternions`, with r_I and v_I of a low orbit (any direction)."""
    random = unit_quaternions(seed, scale)

    def inputs(k, v):
        x = random(k, v)
        size = {"r_I": 7.0e6, "v_I": 7.5e3}.get(v.name)
        return size * x / np.linalg.norm(x) if size else x

    return inputs


def tracked(seed: int, scale: float):
    """An estimator's inputs: a gyro reading of a body turning at a constant rate, and a
    star tracker's samples at 4 Hz, 0.2 s late, slightly wrong (one in seven invalid); the
    orbit frame turning at a constant rate."""
    rng = np.random.default_rng(seed)
    rate, errors = rng.uniform(-scale, scale, 3) * 0.1, rng.normal(0.0, 1e-4, (2000, 3))
    orbit_rate = 1.1e-3 * scale

    def inputs(k, v):
        t = k * STEP
        sample = max(0, int((t - 0.2) * 4.0))  # the latest released
        t_meas = sample / 4.0
        return {
            "w_meas_B": rate + errors[k] * 10.0,
            "q_BI_meas": quat_exp(tuple(rate * t_meas + errors[sample])),
            "meas_valid": sample % 7 != 3,
            "t_meas": t_meas,
            "q_OI": quat_exp((0.0, orbit_rate * t, 0.0)),  # an orbit frame turning about y
            "w_OI_O": (0.0, -orbit_rate, 0.0),
        }[v.name]

    return inputs


def video_sar_pass(seed: int, scale: float):
    """The video_sar pass (OrbitEnvironment) at each step's time, the target moved a few km
    in each run (the inputs StaringGuidance checks must be an orbit and its frame)."""
    orbit = OrbitEnvironment(**video_sar.ORBIT)
    orbit.set("target_lat", video_sar.ORBIT["target_lat"] + 1e-3 * scale)
    orbit.start(0.0)
    at = {}

    def inputs(k, v):
        if k not in at:
            orbit.t = k * STEP  # the outputs are functions of time
            orbit.output()
            at[k] = {name: orbit.get(name) for name in ("r_I", "v_I", "r_T_I", "v_T_I", "q_OI")}
        return at[k][v.name]

    return inputs


def ramps(sizes: dict, size: float = 1.0):
    """Derivatives of the inputs ``sizes`` names (their sizes) that a host interpolating
    them sets before each step: random within ±size times the run's scale."""

    def rates(seed: int, scale: float):
        def at(k):
            rng = np.random.default_rng([seed, k, 99])
            return {name: rng.uniform(-size * scale, size * scale, n) for name, n in sizes.items()}

        return at

    return rates


def fixed_devices(seed: int, scale: float):
    """:func:`in_orbit` with the hub's rows of further devices and torques unconnected (the
    hub's own path of the three fixed devices)."""
    random = in_orbit(seed, scale)
    extra = ("h_extra", "hdot_extra", "h_extra_frequency", "tau_extra")
    return lambda k, v: np.zeros(v.size) if v.name in extra else random(k, v)


#: a hub with four appendage modes on all axes
MODES = {
    "modal_frequency": [2.0, 3.1, 5.5, 7.7, 0.0, 0.0],
    "modal_damping": [0.01, 0.0, 0.02, 0.05, 0.0, 0.0],
    "modal_coupling": [[5.0, -2.0, 1.0], [0.0, 4.0, 3.0], [-2.0, 1.0, 6.0], [1.0, 1.0, 1.0]]
    + [[0.0, 0.0, 0.0]] * 2,
    "eta0": [0.01, -0.02, 0.0, 0.005, 0.0, 0.0],
}
#: imbalanced rotors
IMBALANCE = {
    "static_imbalance": [2.4e-6, 1.0e-6, 0.0, 3.0e-6],
    "dynamic_imbalance": [4.6e-7, 0.0, 2.0e-7, 1.0e-7],
    "rotor_position_B": [[0.5, 0.1, -0.4], [0.0, 0.3, 0.2], [-0.2, -0.3, 0.1], [0.1, 0.0, 0.0]],
    "imbalance_phase0": [0.1, 1.2, 2.3, 3.4],
}


#: name: (model class, parameters[, inputs(seed, scale)[, input derivatives(seed, scale)]])
CASES = {
    "hub": (SatelliteDynamics, {}, in_orbit),
    "hub_fixed_devices": (SatelliteDynamics, {}, fixed_devices),
    "hub_modes": (SatelliteDynamics, {"gravity_gradient": True, **MODES}, fixed_devices),
    "hub_modes_rows": (
        SatelliteDynamics,
        MODES,
        in_orbit,
        ramps({"h_extra": 18, "hdot_extra": 18, "tau_extra": 12, "h_cmg": 3}),
    ),
    "cluster_jitter": (
        CmgCluster,
        {k: v + v[:2] for k, v in IMBALANCE.items()},
    ),
    "wheels_jitter": (Flywheel, {**IMBALANCE, "speed0": [600.0, -300.0, 50.0, 0.0]}),
    "hub_gravity_gradient_spinning": (
        SatelliteDynamics,
        {
            "gravity_gradient": True,
            "rate0": [0.3, -1.5, 2.0],
            "inertia": [[900.0, 5.0, -3.0], [5.0, 950.0, 2.0], [-3.0, 2.0, 1000.0]],
        },
        in_orbit,
    ),
    "hub_interpolated": (
        SatelliteDynamics,
        {"gravity_gradient": True},
        in_orbit,
        ramps({"h_cmg": 3, "hdot_cmg": 3, "tau_ext": 3, "r_I": 3}),
    ),
    "cluster_interpolated": (CmgCluster, {}, None, ramps({"delta_dot_cmd": 6}, size=20.0)),
    "payloads_interpolated": (
        PayloadGimbals,
        {"bandwidth": 3.0, "damping": 0.7},
        None,
        ramps({"roll_cmd": 2, "pitch_cmd": 2, "roll_rate_cmd": 2, "pitch_rate_cmd": 2}),
    ),
    "controller": (AttitudeController, {}, unit_quaternions),
    "controller_feedforward": (
        AttitudeController,
        {"acceleration_feedforward": True, "inertia": [[950, 3, -2], [3, 900, 1], [-2, 1, 800]]},
        unit_quaternions,
    ),
    "guidance": (StaringGuidance, {"reference_time": 2.0}, video_sar_pass),
    "guidance_yaw_0_tilted": (
        StaringGuidance,
        {"yaw_compensation": False, "boresight_B": [0.2, -0.1, 1.0]},
        video_sar_pass,
    ),
    "guidance_tilted": (StaringGuidance, {"boresight_B": [0.0, 0.3, 1.0]}, video_sar_pass),
    "sweep": (SweepPlanner, {}),
    "gyro": (Gyro, {}),
    "gyro_saturating_slow_no_quantisation": (
        Gyro,
        {"saturation": 0.3, "rate": 7.0, "quantization": 0.0},
    ),
    "tracker": (StarTracker, {}, unit_quaternions),
    "tracker_late_fast": (StarTracker, {"latency": 0.6, "rate": 10.0}, unit_quaternions),
    "estimator_random": (AttitudeEstimator, {}, unit_quaternions),
    "estimator": (AttitudeEstimator, {"history": 0.5}, tracked),
    "torques": (DisturbanceTorques, {}, in_orbit),
    "torques_exponential_no_srp": (
        DisturbanceTorques,
        {"atmosphere": "EXPONENTIAL", "srp": False, "facet_area": [1.0] * 8 + [0.0] * 2},
        in_orbit,
    ),
    "wheels": (Flywheel, {}),
    "wheels_limited_skewed": (
        Flywheel,
        {
            "torque_limit": 0.05,
            "momentum_limit": 0.005,
            "coulomb_friction": 0.01,
            "axis": [[1, 0, 0], [0, 1, 0], [0, 0, 0], [0.6, 0.6, 0.5]],
        },
    ),
    "wheels_coasting": (Flywheel, {"torque_limit": 0.0, "speed0": [5.0, -3.0, 0.0, 0.0]}),
    "payloads": (PayloadGimbals, {}),
    "payloads_accel_inputs": (PayloadGimbals, {"accel_inputs": True}),
    "payloads_underdamped": (PayloadGimbals, {"bandwidth": 3.0, "damping": 0.5}),
    "payloads_critical": (PayloadGimbals, {"bandwidth": 3.0, "damping": 1.0}),
    "payloads_overdamped": (PayloadGimbals, {"bandwidth": 3.0, "damping": 4.0}),
    "sweep_triangle": (SweepPlanner, {"turnaround_time": 0.0, "symmetric": False}),
    "cluster": (CmgCluster, {}),
    "cluster_slow_gimbals": (CmgCluster, {"rate_limit": 0.05, "accel_limit": 0.02}),
    "steering": (CmgSteering, {}),
    "steering_null_motion": (CmgSteering, {"null_gain": 0.5}),
    "steering_sr_inverse": (CmgSteering, {"law": SR_INVERSE, "sr_lambda0": 0.2}),
    "pitch": (PitchManeuverController, {}),
    "orbit_circular": (OrbitEnvironment, {}),
    "orbit_j2_eccentric_epoch": (
        OrbitEnvironment,
        {
            "semi_major_axis": 1.0e7,  # perigee 7000 km: above the ground
            "eccentricity": 0.3,
            "j2": True,
            "raan": 1.0,
            "arg_perigee": 2.0,
            "true_anomaly0": 0.5,
            "epoch": "2024-03-01T10:00:00",
            "target_lat": 0.5,
            "target_lon": -1.0,
            "target_alt": 100.0,
        },
    ),
    "orbit_very_eccentric": (
        OrbitEnvironment,
        {"semi_major_axis": 7.0e7, "eccentricity": 0.9, "earth_angle0": 1.0},
    ),
    "orbit_tle": (OrbitEnvironment, {"tle_line1": ISS_TLE[0], "tle_line2": ISS_TLE[1]}),
}

#: every other model with kernels (a new one): at its defaults, on random inputs
CASES.update(
    (name, (model_class(name), {}, unit_quaternions))
    for name in FMUS
    if any(jit.declared(model_class(name))) or getattr(model_class(name), "STATELESS", False)
    if all(case[0] is not model_class(name) for case in CASES.values())
)


def run_case(name: str, seed: int, scale: float, steps: int):
    """Case ``name`` run for ``steps`` steps (:func:`random_run`)."""
    cls, parameters, *feeds = CASES[name]
    inputs, rates = (*feeds, None, None)[:2]
    return random_run(
        cls(**parameters),
        steps,
        seed,
        scale,
        inputs(seed, scale) if inputs else None,
        rates(seed, scale) if rates else None,
    )
