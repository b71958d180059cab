"""Input and output derivatives of the models (FMI 2.0 section 4.2.1; components/model.py).

Inputs interpolated across a step where a model integrates them, against fine
integrations of the same equations with the inputs moving; output derivatives against the
models' own trajectories (differences over small steps, Richardson-extrapolated, with the
inputs moving as a host sets them); the rule for an input whose rate is another input
(``hdot_cmg`` of ``h_cmg``)."""

import math

import numpy as np
import pytest

from agilesat.components.cmg_cluster import CmgCluster, servo1, servo_ramp
from agilesat.components.flywheel import Flywheel
from agilesat.components.gyro import Gyro
from agilesat.components.payload_gimbals import PayloadGimbals, servo_step
from agilesat.components.rotations import qmul
from agilesat.components.satellite_dynamics import SatelliteDynamics
from agilesat.components.sensing import quat_exp


# -- output derivatives against the models' own trajectories ----------------------------
def differences(model, inputs, eps):
    """(analytic output derivatives at the model's time, the Richardson extrapolation of
    (y(t + e) − y(t)) / e for e = eps, eps/2): ``inputs(t)`` are the host's input values
    at t, set after each step as a host does."""
    out = slice(model.layout.range["output"].start, model.layout.range["output"].stop)
    t0 = model.t
    for name, value in inputs(t0).items():
        model.set(name, value)
    model.output()
    y0, analytic = model.values[out].copy(), model.output_derivatives()
    saved, quotients = model.get_state(), []
    for e in (eps, eps / 2):
        model.step(t0, e)
        for name, value in inputs(t0 + e).items():
            model.set(name, value)
        model.output()
        quotients.append((model.values[out] - y0) / e)
        model.set_state(saved)
    return analytic, 2 * quotients[1] - quotients[0]


def output_names(model):
    return [name for v, name in model.layout.scalars if v.causality == "output"]


def hub():
    """A non-isotropic tumbling hub on a moving orbit frame, its inputs moving."""
    model = SatelliteDynamics(
        inertia=[[900.0, 10.0, -20.0], [10.0, 1100.0, 30.0], [-20.0, 30.0, 800.0]],
        attitude0=[0.1, 1.0, 0.2],
        rate0=[0.01, 0.02, -0.01],
    )
    h0, h_rate = np.array([1.0, 2.0, 3.0]), np.array([0.1, -0.2, 0.05])
    w_OI_O, q0 = np.array([0.0, -1e-3, 0.0]), np.array([0.9, 0.1, -0.2, 0.3]) / 0.9899494936611665
    r0, r_rate = np.array([7e6, 1e5, -2e5]), np.array([10.0, 7000.0, 300.0])
    tau0, tau_rate = np.array([1e-3, 2e-3, -1e-3]), np.array([1e-4, 0.0, 0.0])

    def inputs(t):
        return {
            "h_cmg": h0 + h_rate * t,
            "hdot_cmg": h_rate,
            "tau_ext": tau0 + tau_rate * t,
            "w_OI_O": w_OI_O,
            "q_OI": qmul(q0, quat_exp(w_OI_O * t)),
            "r_I": r0 + r_rate * t,
        }

    for name, value in inputs(0.0).items():
        model.set(name, value)
    model.start(0.0)
    model.set_input_rate("tau_ext", tau_rate)
    model.set_input_rate("r_I", r_rate)
    return model, inputs, 1e-4


def cluster():
    """Gimbal rates away from their ramping commands, one over the rate limit."""
    model = CmgCluster().start(0.0)
    model.state[6:12] = [0.1, -0.25, 0.3, 0.06, 0.5, -0.4]
    command, rate = (
        np.array([0.1, -0.2, 0.3, 0.05, 0.59, -0.4]),
        np.array([0.01, 0.2, -0.3, 0, 0.5, -1]),
    )
    model.set_input_rate("delta_dot_cmd", rate)
    return model, lambda t: {"delta_dot_cmd": command + rate * t}, 1e-5


def payloads(bandwidth):
    """Commands along a cubic in time (their rates and accelerations consistent)."""
    model = PayloadGimbals(bandwidth=bandwidth, damping=0.7, accel_inputs=True)
    c = {  # roll and pitch of both payloads: angle, rate, acceleration, jerk at t = 0
        "roll": np.array([[0.2, -0.2], [0.1, -0.1], [0.02, -0.02], [0.003, -0.003]]),
        "pitch": np.array([[0.4, -0.4], [0.01, -0.01], [0.005, -0.005], [0.001, -0.001]]),
    }

    def inputs(t):
        values = {}
        for axis, (a, r, acc, jerk) in c.items():
            values[f"{axis}_cmd"] = a + r * t + acc * t * t / 2 + jerk * t**3 / 6
            values[f"{axis}_rate_cmd"] = r + acc * t + jerk * t * t / 2
            values[f"{axis}_accel_cmd"] = acc + jerk * t
        return values

    for name, value in inputs(0.0).items():
        model.set(name, value)
    model.start(0.0)
    if bandwidth:  # the servo away from its commands
        model.angles, model.rates = [0.21, -0.19, 0.41, -0.38], [0.09, -0.12, 0.02, 0.0]
    for axis, (_, _, acc, jerk) in c.items():
        model.set_input_rate(f"{axis}_rate_cmd", acc)
        model.set_input_rate(f"{axis}_accel_cmd", jerk)
    return model, inputs, 1e-5


def wheels():
    """Three wheels spinning, one at rest breaking away, viscous friction raised."""
    model = Flywheel(speed0=[100.0, -50.0, 0.0, 0.0], viscous_friction=1e-3)
    inputs = {"tau_cmd": [0.01, 0.02, 0.1], "w_BI_B": [0.01, 0.0, 0.02]}
    for name, value in inputs.items():
        model.set(name, value)
    return model.start(0.0), lambda t: inputs, 1e-5


CASES = {
    "SatelliteDynamics": hub,
    "CmgCluster": cluster,
    "PayloadGimbals, servo": lambda: payloads(3.0),
    "PayloadGimbals, ideal tracking": lambda: payloads(0.0),
}


@pytest.mark.parametrize("case", CASES)
def test_output_derivatives_are_those_of_the_models_trajectory(case):
    model, inputs, eps = CASES[case]()
    analytic, numeric = differences(model, inputs, eps)
    scale = np.maximum(np.abs(numeric), 1e-3)
    worst = np.argmax(np.abs(analytic - numeric) / scale)
    assert np.all(np.abs(analytic - numeric) <= 1e-6 * scale), output_names(model)[worst]


def test_wheel_derivatives_follow_the_held_motor_torque():
    """The speeds' and h's derivatives are the trajectory's; ḣ's is that of the motion
    with the motor torque held over the step (its second difference: a step of 2e and one
    of e from the same state), the motor torques' zero (held)."""
    model, inputs, eps = wheels()
    analytic, numeric = differences(model, inputs, eps)
    names = output_names(model)
    smooth = [names.index(n) for n in names if n.startswith(("h[", "speed"))]
    assert np.allclose(analytic[smooth], numeric[smooth], rtol=1e-6, atol=1e-12)
    saved, h = model.get_state(), {0.0: model.y.h.copy()}
    for e in (2.5e-3, 5e-3, 1e-2):
        model.step(0.0, e)
        model.output()
        h[e] = model.y.h.copy()
        model.set_state(saved)
    second = {e: (h[2 * e] - 2 * h[e] + h[0.0]) / e**2 for e in (2.5e-3, 5e-3)}
    hdot_rate = analytic[[names.index(f"hdot[{i}]") for i in (1, 2, 3)]]
    richardson = 2 * second[2.5e-3] - second[5e-3]
    assert np.allclose(hdot_rate, richardson, rtol=1e-6, atol=1e-12)
    assert np.all(hdot_rate != 0)
    assert np.all(analytic[[names.index(f"motor_torque[{i}]") for i in range(1, 5)]] == 0.0)


@pytest.mark.parametrize("make", [cluster, wheels, lambda: payloads(3.0)])
def test_the_derivative_of_h_is_the_output_hdot(make):
    model, _, _ = make()
    model.output()
    names = output_names(model)
    rates = model.output_derivatives()
    assert [rates[names.index(f"h[{i}]")] for i in (1, 2, 3)] == model.y.hdot.tolist()


# -- inputs interpolated across a step, against fine integrations -----------------------
def fine_servo(d, r, c, m, dt, limit=0.6, accel=0.5, n=100_000):
    """The gimbal servo integrated in n steps: each moves the rate toward the target at the
    step's end as far as ``accel`` allows (exact on a ramp once on it)."""
    h = dt / n
    for k in range(n):
        target = min(max(c + m * (k + 1) * h, -limit), limit)
        a = min(max((target - r) / h, -accel), accel)
        d += h * r + 0.5 * a * h * h
        r += a * h
    return d, r


@pytest.mark.slow
@pytest.mark.parametrize(
    "rate, command, slope, dt",
    [
        (0.0, 0.1, 0.2, 1.0),  # catches up with a slow ramp, then rides on it
        (0.2, 0.0, 1.5, 1.0),  # a ramp steeper than the acceleration limit: never caught
        (0.1, 0.3, 0.4, 2.0),  # the command crosses the rate limit: clipped from t = 0.75 s
        (-0.5, 0.7, -0.3, 3.0),  # from above the limit down through both limits' range
        (0.25, -0.9, 0.9, 2.5),  # from below −limit up across it, rate chasing it
    ],
)
def test_a_ramped_rate_command_is_followed_exactly(rate, command, slope, dt):
    angle, rate_end = servo_ramp(0.5, rate, command, slope, dt, 0.6, 0.5)
    d, r = fine_servo(0.5, rate, command, slope, dt)
    # the fine angle is first order in its step where the rate meets a ramp steeper than the
    # acceleration limit (the last case: 5.4e-6 at n = 1e5, 2e-9 at n = 1e8, compiled)
    assert angle == pytest.approx(d, abs=1e-5) and rate_end == pytest.approx(r, abs=1e-9)


def test_a_held_command_is_the_closed_form_of_before():
    assert servo_ramp(0.5, 0.2, -0.4, 1e-300, 0.5, 0.6, 0.5) == pytest.approx(
        servo1(0.5, 0.2, -0.4, 0.5, 0.6, 0.5), abs=1e-12
    )


def rk4_servo(angle, rate, command, a, rate_command, beta, dt, omega, zeta, n=4000):
    """θ̈ = ωn² (θc + a s − θ) + 2ζωn (θ̇c + β s − θ̇) by RK4 in n steps."""

    def f(s, x):
        return np.array(
            [
                x[1],
                omega**2 * (command + a * s - x[0])
                + 2 * zeta * omega * (rate_command + beta * s - x[1]),
            ]
        )

    x, h = np.array([angle, rate]), dt / n
    for k in range(n):
        s = k * h
        k1 = f(s, x)
        k2 = f(s + h / 2, x + h / 2 * k1)
        k3 = f(s + h / 2, x + h / 2 * k2)
        k4 = f(s + h, x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


@pytest.mark.parametrize("zeta", [0.4, 1.0, 2.5])
def test_the_payload_servo_follows_interpolated_commands_exactly(zeta):
    """Angle command at its own slope a (not the rate command's), rate command ramping."""
    args = dict(angle=0.3, rate=-0.05, command=0.25, rate_command=0.02, dt=0.7, omega=4.0)
    got = servo_step(
        args["angle"], args["rate"], args["command"], args["rate_command"], args["dt"],
        args["omega"], zeta, slope=0.035, rate_slope=0.01,
    )  # fmt: skip
    truth = rk4_servo(a=0.035, beta=0.01, zeta=zeta, **args)
    assert np.allclose(got, truth, rtol=0, atol=1e-12)


def test_a_hub_step_with_input_derivatives_is_the_inputs_moving():
    """One step of 2 s with ḧ, τ̇ and ṙ set is, to the RK4 sub-steps' error, 400 steps
    with the inputs set along the same polynomials (h quadratic, τ and r linear); the same
    step with the inputs held is not."""
    h0, slope, curvature = np.array([1.0, 2.0, 3.0]), np.array([0.1, -0.2, 0.05]), 0.02

    def run(steps, interpolate):
        model, inputs, _ = hub()
        dt = 2.0 / steps
        for k in range(steps):
            t = k * dt
            for name, value in inputs(t).items():
                model.set(name, value)
            model.set("h_cmg", h0 + slope * t + 0.5 * curvature * t * t)
            model.set("hdot_cmg", slope + curvature * t)
            for name, rate in (("hdot_cmg", curvature), ("tau_ext", 1e-4), ("r_I", 7000.0)):
                model.set_input_rate(
                    name,
                    inputs(1.0)[name] - inputs(0.0)[name]
                    if name != "hdot_cmg"
                    else [curvature] * 3,
                )
                if not interpolate:
                    model.set_input_rate(name, [0.0, 0.0, 0.0])
            model.step(t, dt)
        model.set("h_cmg", h0 + slope * 2.0 + 0.5 * curvature * 4.0)  # the inputs at the end
        model.output()
        return np.concatenate([model.y.w_BI_B, model.y.q_BI])

    truth = run(400, interpolate=True)
    one, held = run(1, interpolate=True), run(1, interpolate=False)
    assert np.max(np.abs(one - truth)) < 1e-4 * np.max(np.abs(held - truth))


# -- the rule for an input whose rate is another input ---------------------------------
def test_a_derivative_set_for_h_is_the_slope_in_place_of_hdot():
    """hdot_cmg wired (the shipped systems) and the same slope set as the derivative of
    h_cmg with hdot_cmg left at zero give the same run, bit for bit, with a host that sets
    h_cmg at every communication point (a derivative set moves h_cmg to the step's end
    itself: the same value)."""

    def run(rate_as_derivative):
        model, _, _ = hub()
        h = model.get("h_cmg")
        for k in range(20):
            slope = np.array([0.1 * math.sin(0.3 * k), 0.2, -0.05])
            if rate_as_derivative:
                model.set("hdot_cmg", [0.0, 0.0, 0.0])
                model.set_input_rate("h_cmg", slope)
            else:
                model.set("hdot_cmg", slope)
            model.step(0.1 * k, 0.1)
            model.inputs_to_step_end(0.1)
            h = h + slope * 0.1
            model.set("h_cmg", h)
            model.output()
        return model.values[: model.layout.n_numeric].copy(), model.warnings

    (wired, none), (derived, also_none) = run(False), run(True)
    differs = wired != derived
    names = [n for _, n in hub()[0].layout.scalars]
    assert [names[i] for i in np.flatnonzero(differs)] == [f"hdot_cmg[{i}]" for i in (1, 2, 3)]
    assert none == also_none == []


@pytest.mark.parametrize("make, angle, rate", [
    (lambda: hub()[0], "h_cmg", "hdot_cmg"),
    (lambda: payloads(3.0)[0], "roll_cmd", "roll_rate_cmd"),
])  # fmt: skip
def test_a_rate_input_that_disagrees_with_a_set_derivative_is_reported_once(make, angle, rate):
    model = make()
    model.set(rate, np.full(model.layout.by_name[rate].shape, 0.3))
    model.set_input_rate(angle, np.full(model.layout.by_name[angle].shape, 0.3))
    model.advance(model.t, 0.1)
    assert model.warnings == []  # agreeing: nothing to say
    model.set_input_rate(angle, np.full(model.layout.by_name[angle].shape, 0.2))
    model.set(rate, np.full(model.layout.by_name[rate].shape, 0.3))  # again: it moved along
    model.advance(model.t, 0.1)  # its own derivative, where one was set
    assert len(model.warnings) == 1
    assert f"{rate}[1] = 0.3, the derivative of {angle}[1] = 0.2" in model.warnings[0]
    model.advance(model.t, 0.1)
    assert len(model.warnings) == 1


# -- the gyro's true rate between communication points ----------------------------------
def quiet_gyro():
    return Gyro(
        arw=0.0, rrw=0.0, bias_instability=0.0, quantization=0.0, bias0=[0.0] * 3,
        scale_factor=[0.0] * 3, misalignment=np.zeros((3, 3)),
    )  # fmt: skip


@pytest.mark.parametrize("slopes", [True, False])
def test_the_gyro_averages_a_quadratic_rate_exactly_with_its_slope(slopes):
    """w(t) = a + b t + c t² sampled at 20 Hz, communicated every 0.2 s: with the slope at
    each communication point every sample is the exact average over its interval; with
    the line between communication points it is off by c h² terms."""
    a, b, c = (
        np.array([0.01, -0.02, 0.03]),
        np.array([0.05, 0.01, -0.02]),
        np.array([0.2, -0.1, 0.3]),
    )
    gyro, h = quiet_gyro().start(0.0), 0.2
    errors = []
    for k in range(10):
        t = k * h
        gyro.set("w_BI_B", a + b * t + c * t * t)
        if slopes:
            gyro.set_input_rate("w_BI_B", b + 2 * c * t)
        if k:  # the samples of the last step, against the exact averages
            for j in range(1, 5):
                t1, t0 = t - h + j * 0.05, t - h + (j - 1) * 0.05
                mean = a + b * (t0 + t1) / 2 + c * (t0 * t0 + t0 * t1 + t1 * t1) / 3
                if j == 4:
                    gyro.output()
                    errors.append(np.max(np.abs(gyro.y.w_meas_B - mean)))
        gyro.advance(t, h)
    if slopes:
        assert max(errors) < 1e-13  # rounding
    else:
        assert min(errors) > 1e-4


# -- the inputs at a step's end ---------------------------------------------------------
INTERPOLATING = (SatelliteDynamics, CmgCluster, PayloadGimbals, Gyro)


@pytest.mark.parametrize("model_class", INTERPOLATING, ids=lambda m: m.__name__)
def test_outputs_after_a_step_are_those_of_the_inputs_at_its_end(model_class):
    """A host sets the derivative of every Real input and reads the outputs right after the
    step: they are the outputs of the inputs the step integrated, bit for bit those a host
    gets that first sets the inputs again to u + u̇ H (+ ½ ü H² for h_cmg, whose rate input
    hdot_cmg got a derivative too: its curve), and the inputs read back are those values."""
    assert {m for m in INTERPOLATING if m.INTERPOLATES_INPUTS} == set(INTERPOLATING)
    step = 0.05

    def run(again):
        model = model_class().start(0.0)
        layout, rows = model.layout, []
        # (the hub's rows kept still: a row with a frequency rotates and is turned to the
        # step's end, not moved along a line; test_flexible.py)
        inputs = [
            v
            for v in layout.group("input")
            if v.name in layout.derivative and v.name != "h_extra_frequency"
        ]
        rate_of = {v.derivative_of: v.name for v in inputs if v.derivative_of}
        for k in range(10):
            rates = {
                v.name: 1e-3 * np.arange(1 + k, 1 + k + v.size).reshape(v.shape) * (-1) ** i
                for i, v in enumerate(inputs)
            }
            ends = {}
            for v in inputs:
                model.set_input_rate(v.name, rates[v.name])
                u, r = model.get(v.name), rates[v.name]
                bend = rates[rate_of[v.name]] if v.name in rate_of else None
                ends[v.name] = (
                    u + r * step if bend is None else u + (r * step + 0.5 * bend * step * step)
                )
            if again:
                model.step(k * step, step)
                for name, value in ends.items():
                    model.set(name, value)
                model.output()
            else:
                model.advance(k * step, step)
                for name, value in ends.items():
                    assert np.array_equal(model.get(name), value), name
            rows.append(model.values[: layout.n_numeric].copy())
        return np.array(rows)

    after, again = run(False), run(True)
    assert np.array_equal(after, again)
