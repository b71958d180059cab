"""The lane "compiled kernel against its Python" (components/runtime/jit.py): over every
model's cases (tests/fast_paths/kernel_cases.py) compiled and Python give the same values,
warnings, errors and saved states bit for bit; the paths only the compiled tier can take
(its warnings and errors, a singular steering, SGP4's direct call); and the helpers numba
lacks (components/runtime/flat.py) match CPython's."""

import math
import re
import sys

import numpy as np
import pytest
from kernel_cases import CASES, STEP, random_run, run_case, snapshot

from agilesat.components import (
    cmg_steering,
    orbit_environment,
    pitch_maneuver_controller,
    staring_guidance,
)
from agilesat.components.cmg_cluster import DEFAULT_SPINS, GIMBAL_AXES, ClusterGeometry, CmgCluster
from agilesat.components.cmg_steering import SR_INVERSE, CmgSteering
from agilesat.components.model import ModelError
from agilesat.components.orbit_environment import OrbitEnvironment
from agilesat.components.pitch_maneuver_controller import PitchManeuverController
from agilesat.components.rotations import dcm, quat_of_rows
from agilesat.components.runtime import flat, jit
from agilesat.components.satellite_dynamics import SatelliteDynamics
from agilesat.components.sweep_planner import SweepPlanner
from agilesat.fmus import FMUS, model_class
from agilesat.orchestration.scenarios import scan_pitch, video_sar
from helpers import ISS_TLE

needs_numba = pytest.mark.skipif(
    jit._numba() is None, reason="numba not installed or AGILESAT_JIT=0"
)
#: every model's module
MODULES = [sys.modules[model_class(name).__module__] for name in FMUS]
ALL_KERNELS = [k for module in MODULES for k in jit.kernels(module).values()]


@pytest.fixture(params=[pytest.param("compiled", marks=pytest.mark.slow), "py_func"])
def path(request, monkeypatch):
    """Every kernel of the models running its compiled function or its Python (compiled:
    the slow layer, as numba compiles every model's kernels first on a fresh machine)."""
    for kernel in ALL_KERNELS:
        monkeypatch.setattr(kernel, "_run", getattr(kernel, request.param))
    return request.param


def both(run):
    """run() with every kernel compiled, then with its Python: the two results."""
    results = []
    for attribute in ("compiled", "py_func"):
        saved = [(k, k._run) for k in ALL_KERNELS]
        try:
            for kernel in ALL_KERNELS:
                kernel._run = getattr(kernel, attribute)
            results.append(run())
        finally:
            for kernel, run_ in saved:
                kernel._run = run_
    return results


# -- scan_pitch in-process: the five models, Jacobi coupling --------------------------------
def scan_pitch_run(steps: int):
    """scan_pitch's models with its parameters and connections; every model's values and
    state after each step."""
    models = {
        name: cls()
        for name, cls in (
            ("OrbitEnvironment", OrbitEnvironment),
            ("SatelliteDynamics", SatelliteDynamics),
            ("CmgCluster", CmgCluster),
            ("CmgSteering", CmgSteering),
            ("PitchManeuverController", PitchManeuverController),
        )
    }
    for key, value in scan_pitch.SYSTEM.parameters.items():
        name, variable = key.split(".")
        models[name].set(variable, value)
    connections = [
        (models[a.split(".")[0]], a.split(".")[1], models[b.split(".")[0]], b.split(".")[1])
        for a, b in scan_pitch.SYSTEM.connections
    ]
    for model in models.values():
        model.start(0.0)
    record = []
    for k in range(steps):
        for source, output, target, input_ in connections:
            target.set(input_, source.get(output))
        for model in models.values():
            model.advance(k * STEP, STEP)
        record.append([snapshot(models[name]) for name in models if name != "SatelliteDynamics"])
    return record


@pytest.mark.slow
@needs_numba
def test_a_scan_pitch_run_is_the_same_compiled_and_in_python():
    steps = round(150.0 / STEP)  # the whole maneuver: every phase, the terminal PD
    compiled, readable = both(lambda: scan_pitch_run(steps))
    assert compiled == readable
    phases = {np.frombuffer(row[3][0])[pitch_maneuver_controller.Y.phase] for row in compiled}
    assert phases == {1.0, 2.0, 3.0, 4.0, 5.0}


# -- each model alone on random inputs (tests/fast_paths/kernel_cases.py) -----------------
@pytest.mark.slow
@needs_numba
@pytest.mark.parametrize("case", list(CASES))
def test_every_kernel_compiled_gives_its_python_bit_for_bit(case):
    """The lane "compiled kernel against its Python", over every model's cases: the
    values, states and warnings after each step, of small and of large random inputs."""
    cls = CASES[case][0]
    steps = 2400 if cls in (PitchManeuverController, SweepPlanner) else 300  # every phase
    for seed, scale in ((1, 0.8), (2, 3.0)):
        compiled, readable = both(lambda: run_case(case, seed, scale, steps))
        assert compiled == readable
        outputs = np.array([np.frombuffer(values) for values, _, _ in compiled])
        varying = np.ptp(outputs[:, cls().layout.range["output"]], axis=0) > 0
        # orbit: w_OI_O x, target z, v_z; the sweep over 120 s: no pitch reversal (pitch
        # rate and acceleration), the triangle wave no acceleration at all and coasting
        # wheels no motor torque, saturation, third wheel or z momentum; the estimators
        # valid, the random one's updates and NIS (each measurement is late)
        constant = {"sweep": 4, "sweep_triangle": 6, "wheels_coasting": 9}
        constant.update(estimator=1, estimator_random=7)
        # no modes: η, η̇ (12), two unused; no imbalance: the jitter outputs (12 and the
        # cluster's frequency; 24 + 6 of the wheels); wheels_jitter: the absent 4th wheel's;
        # no gimbal fails: the cluster's healthy (6)
        constant.update({c: 12 for c in CASES if c.startswith("hub") and "modes" not in c})
        constant.update(hub_modes=4, hub_modes_rows=4, cluster_jitter=7, wheels_jitter=10)
        constant.update(cluster=19, cluster_slow_gimbals=19, cluster_interpolated=19)
        constant.update(wheels=32, wheels_limited_skewed=32, wheels_coasting=39)
        assert np.count_nonzero(varying) >= varying.size - constant.get(case, 3)


@needs_numba
def test_the_saturation_warning_comes_from_the_compiled_path_with_its_text(path):
    model = CmgCluster().start(0.0)
    model.set("delta_dot_cmd", [0.1, 0.0, -1.5, 0.2, 0.0, 0.0])
    model.advance(0.0, STEP)
    # the rate moves toward the limit at the acceleration limit
    assert model.get("delta_dot")[2] == -0.5 * STEP
    model.advance(STEP, STEP)  # still saturated: no second warning
    model.set("delta_dot_cmd", [0.0] * 6)
    model.advance(2 * STEP, STEP)
    model.set("delta_dot_cmd", [0.7, 0.0, 0.0, 0.0, 0.0, -0.7])  # equal: the first named
    model.advance(3 * STEP, STEP)
    assert model.warnings == [
        "t=0.000 s: gimbal 3 rate command -1.500 rad/s exceeds the rate limit 0.6 rad/s "
        "(the cluster cannot deliver the commanded torque)",
        "t=0.150 s: gimbal 1 rate command 0.700 rad/s exceeds the rate limit 0.6 rad/s "
        "(the cluster cannot deliver the commanded torque)",
    ]


def singular_angles():
    """Gimbal angles at the cluster's saturation singularity along y (all spins on y)."""
    geometry = ClusterGeometry(16.65, GIMBAL_AXES, DEFAULT_SPINS)
    y = np.array([0.0, 1.0, 0.0])
    return np.arctan2(geometry.T @ y, geometry.S @ y)


@needs_numba
@pytest.mark.slow  # numba compiles the steering kernels first on a fresh machine
@pytest.mark.parametrize("law", [0, SR_INVERSE])
def test_a_singular_configuration_is_the_same_compiled_and_in_python(law):
    delta = singular_angles()

    def run():
        model = CmgSteering(law=law)
        model.set("delta", delta)
        model.set("h", ClusterGeometry(16.65, GIMBAL_AXES, DEFAULT_SPINS).momentum(delta))
        model.set("tau_cmd", [0.3, -0.2, 0.1])
        model.start(0.0)
        return snapshot(model)

    compiled, readable = both(run)
    assert compiled == readable
    values = np.frombuffer(compiled[0])
    assert values[cmg_steering.Y.singularity] < cmg_steering.SINGULAR_Q
    rates = values[cmg_steering.Y.delta_dot_cmd : cmg_steering.Y.delta_dot_cmd + 6]
    assert np.all(np.isfinite(rates)) and np.any(rates != 0)
    assert len(compiled[2]) == 1
    assert re.fullmatch(
        r"t=0\.000 s: singular gimbal configuration \(Q = \d\.\d\de-\d\d\); torque along "
        r"the singular direction is not delivered",
        compiled[2][0],
    )


@needs_numba
def test_the_pseudo_inverse_at_a_singularity_leaves_the_singular_direction_undelivered(path):
    delta = singular_angles()
    geometry = ClusterGeometry(16.65, GIMBAL_AXES, DEFAULT_SPINS)
    model = CmgSteering()
    model.set("delta", delta)
    model.set("h", [0.0, 0.0, 0.0])
    model.set("tau_cmd", [0.3, -0.2, 0.1])
    model.start(0.0)
    hdot = geometry.h_rotor * geometry.jacobian(delta) @ model.get("delta_dot_cmd")
    assert hdot[1] == pytest.approx(0.0, abs=1e-9)  # y: the singular direction
    assert hdot[[0, 2]] == pytest.approx([-0.3, -0.1], rel=1e-9)


@needs_numba
def test_kepler_not_converging_raises_its_model_error_from_the_compiled_path(path):
    model = OrbitEnvironment(semi_major_axis=1.0e7, eccentricity=0.3).start(0.0)
    model.state[orbit_environment.S.M0] = math.nan  # no finite input makes Newton fail
    before = model.values.copy()
    with pytest.raises(
        ModelError, match=re.escape("Kepler's equation did not converge (M = nan, e = 0.3)")
    ):
        model.advance(0.0, STEP)
    assert np.array_equal(model.values, before)  # nothing written


@needs_numba
@pytest.mark.parametrize(
    "case",
    [
        "cluster",
        "steering",
        "pitch",
        "orbit_j2_eccentric_epoch",
        "guidance",
        "controller",
        "wheels_limited_skewed",
        "payloads",
        "payloads_underdamped",
        "gyro",
        "tracker",
        "estimator",
    ],  # fmt: skip
)
def test_a_saved_state_restored_continues_bit_for_bit(case, path):
    cls, parameters, *inputs = CASES[case]
    rng = np.random.default_rng(5)
    values = {k: rng.uniform(-0.8, 0.8, size=32) for k in range(60)}
    feed = inputs[0](5, 0.8) if inputs and inputs[0] else lambda k, v: values[k][: v.size]

    model = cls(**parameters)
    random_run(model, 30, 0, 0.0, inputs=feed)
    saved = model.get_state()

    def continue_(model):
        """(values and state after each step, warnings issued) of steps 30..59."""
        record, issued = [], len(model.warnings)
        for k in range(30, 60):
            for v in model.layout.group("input"):
                model.set(v.name, feed(k, v))
            model.advance(k * STEP, STEP)
            record.append(snapshot(model)[:2])
        return record, model.warnings[issued:]

    first = continue_(model)
    model.set_state(saved)
    again = continue_(model)
    other = cls(**parameters).start(0.0)
    other.set_state(saved)
    assert first == again == continue_(other)


# -- helpers numba lacks, against CPython's ------------------------------------------------
def remainder_cases():
    rng = np.random.default_rng(3)
    cases = [(x, y) for y in (2 * math.pi, 1.0, 0.5) for x in np.arange(-20, 21) * y / 2]
    cases += list(zip(rng.uniform(-1e4, 1e4, 2000), rng.uniform(0.01, 100, 2000)))
    cases += [(1e-300, 2 * math.pi), (-1e-300, 2 * math.pi), (0.0, 1.0), (-0.0, 1.0)]
    cases += [(math.nan, 1.0), (1.0, math.nan), (3.0, math.inf), (-3.0, -math.inf)]
    return [(float(x), float(y)) for x, y in cases]


def same_float(a, b):
    return (math.isnan(a) and math.isnan(b)) or (
        a == b and math.copysign(1, a) == math.copysign(1, b)
    )


@needs_numba
@pytest.mark.parametrize("function", ["compiled", "python"])
def test_remainder_is_math_remainder_bit_for_bit(function):
    remainder = jit._numba().njit(flat.remainder) if function == "compiled" else flat.remainder
    for x, y in remainder_cases():
        assert same_float(remainder(x, y), math.remainder(x, y)), (x, y)


@needs_numba
def test_quat_of_rows_compiled_is_the_python_bit_for_bit():
    compiled = jit._numba().njit(quat_of_rows)
    rng = np.random.default_rng(4)
    qs = list(rng.normal(size=(400, 4)))
    qs += [np.eye(4)[k] for k in range(4)] + [-np.eye(4)[k] for k in range(4)]
    branches = set()
    for q in qs:
        rows = np.array(dcm(q / np.linalg.norm(q))).reshape(-1).tolist()
        assert compiled(*rows) == quat_of_rows(*rows)
        C = np.reshape(rows, (3, 3))
        branches.add(int(np.argmax([np.trace(C), *np.diag(C)])))
    assert branches == {0, 1, 2, 3}


@needs_numba
def test_every_model_kernel_compiles():
    names = {k.__name__ for k in ALL_KERNELS}
    assert names >= {
        "_footprint_azimuths", "_output", "_step", "cluster_output", "cluster_step",
        "controller_output", "estimator_output", "estimator_step", "flywheel_output",
        "flywheel_step", "gimbals_output", "gimbals_step", "guidance_output", "guidance_step",
        "gyro_output", "gyro_step", "orbit_output", "pitch_output", "steering_output",
        "sweep_output", "torques_output", "tracker_output", "tracker_step",
    }  # fmt: skip
    for kernel in ALL_KERNELS:
        assert kernel.compiled is not kernel.py_func
        assert type(kernel.compiled).__module__.startswith("numba")


def hypot_cases():
    rng = np.random.default_rng(6)
    cases = list(zip(rng.normal(size=20000), rng.normal(size=20000)))
    scales = 10.0 ** rng.integers(-20, 20, 5000)
    cases += list(zip(rng.uniform(-1, 1, 5000), rng.uniform(-1, 1, 5000) * scales))
    cases += [(x * 1e-310, y * 1e-310) for x, y in cases[:2000]]  # subnormal
    cases += [(x * 1e300, y * 1e300) for x, y in cases[:200]]  # near overflow
    cases += [(0.0, 0.0), (-0.0, 1.0), (3.0, -4.0), (5e-324, 5e-324), (1.7e308, 1.7e308)]
    cases += [(math.inf, math.nan), (math.nan, 1.0), (-math.inf, 0.0)]
    return [(float(x), float(y)) for x, y in cases]


@needs_numba
@pytest.mark.parametrize("function", ["compiled", "python"])
def test_hypot_is_math_hypot_bit_for_bit(function):
    hypot = jit._numba().njit(flat.hypot) if function == "compiled" else flat.hypot
    differs_in_libm = 0  # numba's own math.hypot is the C library's
    for x, y in hypot_cases():
        assert same_float(hypot(x, y), math.hypot(x, y)), (x, y)
        with np.errstate(over="ignore"):
            libm = float(np.hypot(x, y))
        differs_in_libm += not same_float(libm, math.hypot(x, y))
    assert differs_in_libm > 0  # the reason for the twin


@needs_numba
@pytest.mark.parametrize("function", ["compiled", "python"])
def test_fmod_is_math_fmod_bit_for_bit(function):
    fmod = jit._numba().njit(flat.fmod) if function == "compiled" else flat.fmod
    rng = np.random.default_rng(7)
    xs = rng.normal(size=5000) * 10.0 ** rng.integers(-5, 15, 5000)
    ys = np.abs(rng.normal(size=5000)) * 10.0 ** rng.integers(-3, 6, 5000)
    cases = [*zip(xs, ys), *zip(xs, -ys), (-0.0, 86400.0), (0.0, 1.0), (5.0, math.inf)]
    for x, y in cases:
        assert same_float(fmod(float(x), float(y)), math.fmod(x, y)), (x, y)
    assert math.isnan(fmod(math.inf, 1.0)) and math.isnan(fmod(1.0, 0.0))


@needs_numba
@pytest.mark.parametrize("function", ["compiled", "python"])
def test_the_direct_sgp4_call_is_sgp4_tsince_bit_for_bit(function):
    """ephemeris.sgp4_at calls the function satrec.sgp4_tsince calls (a near-Earth and a
    resonant deep-space TLE), and reports an error where it does (a decayed orbit)."""
    from agilesat.components.ephemeris import load_tle, sgp4_at, sgp4_entry

    call = jit._numba().njit(lambda *a: sgp4_at(*a)) if function == "compiled" else sgp4_at
    geostationary = (
        "1 28626U 05008A   06176.46683397 -.00000205  00000-0  10000-3 0  2190",
        "2 28626   0.0019 286.9433 0000335  13.7918  55.6504  1.00270176  4891",
    )
    for lines in (ISS_TLE, geostationary):
        ours, theirs = load_tle(*lines), load_tle(*lines)
        address, record = sgp4_entry(ours, load_tle(*lines))
        assert address and record
        out = np.zeros(8)
        for tsince in np.linspace(-3000.0, 3000.0, 61):
            assert call(float(address), float(record), float(tsince), out, 2)
            error, r, v = theirs.sgp4_tsince(float(tsince))
            assert (error, out[2:5].tolist(), out[5:].tolist()) == (0, list(r), list(v))
    draggy = ISS_TLE[0][:53] + " 50000-1 0  999" + "4", ISS_TLE[1]  # B* 0.05, its checksum
    decayed = load_tle(*draggy)
    address, record = sgp4_entry(decayed, load_tle(*draggy))
    assert not call(float(address), float(record), 3e4, np.zeros(6), 0)
    assert decayed.error == load_tle(*draggy).sgp4_tsince(3e4)[0] == 1


def test_a_restored_state_calls_sgp4_on_its_own_record():
    """The addresses of the SGP4 call are never taken from a state (a host's bytes): after
    set_state the model's own record is called."""
    one = OrbitEnvironment(tle_line1=ISS_TLE[0], tle_line2=ISS_TLE[1]).start(0.0)
    other = OrbitEnvironment(tle_line1=ISS_TLE[0], tle_line2=ISS_TLE[1]).start(0.0)
    state = one.get_state()
    state[0][:] = 0.0  # the value array
    state[2]["state"][orbit_environment.S.sgp4 : orbit_environment.S.sgp4 + 2] = (8.0, 16.0)
    other.set_state(state)
    assert tuple(other.state[orbit_environment.S.sgp4 : orbit_environment.S.sgp4 + 2]) == tuple(
        map(float, other._sgp4_entry)
    )
    assert "_sgp4_entry" not in state[2]


@needs_numba
def test_footprint_azimuths_compiled_is_the_python_bit_for_bit():
    """The footprint azimuth of a whole attitude history (the video_sar metric's), compiled
    and in Python: the same bits, and the same first row where it is undefined."""
    kernel = staring_guidance._footprint_azimuths
    orbit = OrbitEnvironment(**video_sar.ORBIT)
    orbit.start(0.0)
    r_T = []
    for k in range(300):
        orbit.t = k * 0.5
        orbit.output()
        r_T.append(orbit.get("r_T_I"))
    r_T = np.array(r_T)
    q = np.random.default_rng(5).normal(size=(300, 4))
    q /= np.linalg.norm(q, axis=1)[:, np.newaxis]
    beam, axis = (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)
    compiled, readable = np.empty(300), np.empty(300)
    assert kernel.compiled(q, r_T, beam, axis, compiled) == -1
    assert kernel.py_func(q, r_T, beam, axis, readable) == -1
    assert compiled.tobytes() == readable.tobytes()
    assert np.ptp(compiled) > 1.0
    r_T[120] = (0.0, 0.0, 6356752.3)  # at a pole: undefined
    assert kernel.compiled(q, r_T, beam, axis, compiled) == 120
    assert kernel.py_func(q, r_T, beam, axis, readable) == 120
