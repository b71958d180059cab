"""SatelliteDynamics' appendage modes (hybrid coordinates, DESIGN.md §3.2) and its further
device and torque rows, against closed forms, conservation laws and the monolithic reference
written from the equations (tests/tools/reference/flexible.py)."""

import math

import numpy as np
import pytest

from agilesat.components.model import ModelError
from agilesat.components.rotations import dcm_from_quat
from agilesat.components.satellite_dynamics import N_MODES, SatelliteDynamics
from reference import flexible, scan_pitch

DT = 0.05


def hub(inertia, coupling=(), frequency=(), damping=(), eta0=(), eta_dot0=(), **parameters):
    """A hub in inertial space (gravity gradient off) with the first modes given."""

    def padded(values, shape=()):
        table = np.zeros((N_MODES, *shape))
        if len(values):
            table[: len(values)] = values
        return table

    return SatelliteDynamics(
        inertia=inertia,
        gravity_gradient=False,
        modal_coupling=padded(coupling, (3,)),
        modal_frequency=padded(frequency),
        modal_damping=padded(damping),
        eta0=padded(eta0),
        eta_dot0=padded(eta_dot0),
        **parameters,
    )


def run(model, steps, inputs=None):
    """Outputs (rows per time, from t = 0) of ``steps`` macro steps; ``inputs(model, t)`` sets
    the inputs at each communication point t."""
    if inputs:
        inputs(model, 0.0)
    model.start()
    names = ("q_BI", "w_BI_B", "eta", "eta_dot", "H_I")
    rows = {name: [model.get(name)] for name in names}
    for k in range(steps):
        model.step(k * DT, DT)
        if inputs:
            inputs(model, (k + 1) * DT)
        model.output()
        for name in names:
            rows[name].append(model.get(name))
    return {name: np.array(values) for name, values in rows.items()}


def zero_crossing_frequency(t, x) -> float:
    """Angular frequency from the mean interval between zero crossings (linear
    interpolation between samples)."""
    k = np.flatnonzero(np.sign(x[:-1]) * np.sign(x[1:]) < 0)
    crossings = t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k])
    return math.pi / np.mean(np.diff(crossings))


@pytest.mark.parametrize(
    "inertia, axis, ratio",
    [(100.0, 0, 0.05), (956.0, 1, 0.3), (5000.0, 2, 0.7)],
    ids=["weak", "medium", "strong"],
)
def test_one_mode_oscillates_at_its_unconstrained_frequency(inertia, axis, ratio):
    """Released from η0 with the hub at rest, one mode coupled to one axis (L I⁻¹ Lᵀ =
    ``ratio``) oscillates at ω_c / √(1 − L I⁻¹ Lᵀ) ([Hablani 1982]), measured from 10
    periods of η, to 1e-5."""
    omega = 2.45
    L = np.zeros(3)
    L[axis] = math.sqrt(ratio * inertia)
    expected = omega / math.sqrt(1.0 - ratio)
    assert expected == pytest.approx(
        flexible.single_mode_frequency(omega, L, inertia * np.eye(3)), rel=1e-14
    )
    steps = int(10 * 2 * math.pi / expected / DT)
    out = run(hub(inertia * np.eye(3), [L], [omega], eta0=[0.01]), steps)
    measured = zero_crossing_frequency(np.arange(steps + 1) * DT, out["eta"][:, 0])
    print(
        f"J = {inertia:g}, L J⁻¹ Lᵀ = {ratio}: ω_u measured {measured:.7f} rad/s, closed form "
        f"{expected:.7f} rad/s, relative error {measured / expected - 1:.1e}"
    )
    assert measured == pytest.approx(expected, rel=1e-5)
    # the hub swings against the mode: J ω = −Lᵀ η̇ about that axis
    assert np.allclose(
        inertia * out["w_BI_B"][:, axis], -L[axis] * out["eta_dot"][:, 0], atol=1e-15
    )


def tumbling(damping=(0.0,) * 4):
    """A tumbling hub with four modes on all three axes (constants of the reference too)."""
    rng = np.random.default_rng(7)
    inertia = np.array([[900.0, 20.0, -10.0], [20.0, 700.0, 15.0], [-10.0, 15.0, 600.0]])
    coupling = rng.normal(0.0, 6.0, (4, 3))
    frequency = [2.0, 3.1, 5.5, 7.7]
    return dict(
        inertia=inertia,
        coupling=coupling,
        frequency=frequency,
        damping=damping,
        eta0=[0.01, -0.02, 0.005, 0.0],
        eta_dot0=[0.0, 0.01, -0.02, 0.03],
        rate0=[0.02, -0.03, 0.05],
    )


#: a device's momentum relative to the body, h(t) = a + b t + c t² (N·m·s) on three axes:
#: its value, rate and curvature at each communication point make the hub's interpolation
#: h + ḣ s + ½ ḧ s² exact
CURVE = np.array([[1.0, -2.0, 0.0], [0.3, 0.1, 0.5], [-0.01, 0.02, -0.005]])


def device(t):
    """(h, ḣ) of the device at t."""
    a, b, c = CURVE
    return a + b * t + c * t * t, b + 2.0 * c * t


def moving(model, t):
    """The device into h_cmg, with its curvature as the derivative of hdot_cmg."""
    model.set("h_cmg", device(t)[0])
    model.set("hdot_cmg", device(t)[1])
    model.set_input_rate("hdot_cmg", 2.0 * CURVE[2])


def test_total_momentum_is_exact_and_energy_conserved_undamped():
    """H_I is integrated: C_BIᵀ (J ω + h + Σ L_kᵀ η̇_k), recomputed from the outputs, stays
    H_I to round-off with modes and a moving device; undamped and with the device held,
    ½ [ω; η̇]ᵀ M [ω; η̇] + ½ Σ ω_k² η_k² is conserved to the integration error."""
    case = tumbling()
    model = hub(**case)
    out = run(model, 200, moving)
    L = case["coupling"]
    H = [
        dcm_from_quat(q).T @ (case["inertia"] @ w + device(k * DT)[0] + L.T @ e[:4])
        for k, (q, w, e) in enumerate(zip(out["q_BI"], out["w_BI_B"], out["eta_dot"]))
    ]
    drift = np.abs(np.array(H) - out["H_I"][0]).max() / np.linalg.norm(H[0])
    print(f"|C_BIᵀ (J ω + h + Σ L_kᵀ η̇_k) − H_I| / |H_I| over 10 s: {drift:.1e}")
    assert drift < 1e-13
    assert np.array_equal(out["H_I"], np.repeat(out["H_I"][:1], len(H), axis=0))

    out = run(hub(**case), 200)
    reference = flexible.Hub(case["inertia"], L, case["frequency"], case["damping"])
    energy = [
        reference.energy(np.concatenate([q, w, e[:4], d[:4]]))
        for q, w, e, d in zip(out["q_BI"], out["w_BI_B"], out["eta"], out["eta_dot"])
    ]
    energy_drift = np.abs(np.array(energy) / energy[0] - 1.0).max()
    print(f"energy, undamped, over 10 s: relative drift {energy_drift:.1e}")
    assert energy_drift < 1e-7


def test_against_the_monolithic_reference():
    """Four damped modes, a tumbling hub and a moving device for 10 s at 0.05 s against the
    reference's DOP853 solution of the mass-matrix equations (rtol 1e-11): the attitude to
    2e-9 rad (measured 4e-10), the rates to 1e-8 rad/s (2e-9), the modes to 1e-5 of their
    amplitude (3e-6: RK4 at 0.1 rad of the fastest mode a sub-step)."""
    case = tumbling(damping=(0.01, 0.005, 0.02, 0.05))
    out = run(hub(**case), 200, moving)
    reference = flexible.Hub(
        case["inertia"], case["coupling"], case["frequency"], case["damping"], devices=device
    )
    x0 = np.concatenate(
        [out["q_BI"][0], out["w_BI_B"][0], out["eta"][0, :4], out["eta_dot"][0, :4]]
    )
    x = reference.run(x0, np.arange(201) * DT)
    assert np.allclose(out["w_BI_B"][0], case["rate0"], rtol=1e-15, atol=0)
    assert np.allclose(out["eta_dot"][0, :4], case["eta_dot0"], rtol=1e-15, atol=1e-15)
    angle = [
        2 * np.linalg.norm(scan_pitch.qmul(scan_pitch.qconj(a), b)[1:])
        for a, b in zip(out["q_BI"], x[:, :4])
    ]
    print(
        f"against the reference over 10 s: attitude {max(angle):.1e} rad, rate "
        f"{np.abs(out['w_BI_B'] - x[:, 4:7]).max():.1e} rad/s, η "
        f"{np.abs(out['eta'][:, :4] - x[:, 7:11]).max() / np.abs(x[:, 7:11]).max():.1e} and η̇ "
        f"{np.abs(out['eta_dot'][:, :4] - x[:, 11:15]).max() / np.abs(x[:, 11:15]).max():.1e} "
        "of their amplitudes"
    )
    assert max(angle) < 2e-9
    assert np.abs(out["w_BI_B"] - x[:, 4:7]).max() < 1e-8
    assert np.abs(out["eta"][:, :4] - x[:, 7:11]).max() < 1e-5 * np.abs(x[:, 7:11]).max()
    assert np.abs(out["eta_dot"][:, :4] - x[:, 11:15]).max() < 1e-5 * np.abs(x[:, 11:15]).max()


def test_modes_without_coupling_are_the_rigid_hub_bit_for_bit():
    """Frequencies and damping of unused modes (zero rows of modal_coupling) change nothing."""
    rigid = run(hub(np.diag([900.0, 700.0, 600.0]), rate0=[0.02, -0.03, 0.05]), 100)
    idle = run(
        hub(np.diag([900.0, 700.0, 600.0]), [[0, 0, 0]] * 2, [2.0, 3.0], [0.1, 0.2],
            rate0=[0.02, -0.03, 0.05]),
        100,
    )  # fmt: skip
    for name in rigid:
        assert np.array_equal(rigid[name], idle[name]), name
    assert not idle["eta"].any() and not idle["eta_dot"].any()


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"coupling": [[30.0, 0, 0]], "frequency": [2.0]}, "J − Σ L_kᵀ L_k .* positive definite"),
        (
            {"coupling": [[3.0, 0, 0]], "frequency": [0.0]},
            "mode 1 is coupled .* positive frequency",
        ),
        ({"coupling": [[0, 0, 0]], "frequency": [2.0], "eta0": [0.1]}, "mode 1 is unused"),
        ({"coupling": [[3.0, 0, 0]], "frequency": [2.0], "damping": [-0.1]}, "modal_damping"),
    ],
    ids=["too strong", "no frequency", "unused but moving", "negative damping"],
)
def test_impossible_modes_are_refused(changes, message):
    with pytest.raises(ModelError, match=message):
        hub(900.0 * np.eye(3), **changes).start()


def imbalanced_rotor(t):
    """A rotor's imbalance momentum and its rate (the reference's imbalance at 628.3 rad/s)."""
    h, h_dot, _, _ = flexible.imbalance(
        2.4e-6, 4.6e-7, [0.5, 0.3, -0.4], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], ROTOR, ROTOR * t
    )
    return h, h_dot


ROTOR = 628.3


@pytest.mark.slow
def test_a_rotating_row_is_the_bodys_steady_jitter():
    """A row of h_extra rotating at Ω = 628 rad/s (a rotor's imbalance) stepped at 0.05 s
    (31 radians of the rotor a step) against the reference, which resolves it (steps of
    4e-4 s), over 0.5 s: the attitude jitter to 1 %, beside the integration error of the
    mean motion (the same run without the rotor against the reference), the rate jitter
    to 0.5 %; the mean motion is the one without the rotor, H_I bit for bit."""
    inertia = 956.0 * np.eye(3)
    modes = dict(coupling=[[20.0, 0, 0], [0, 0, 15.0]], frequency=[2.45, 6.7], damping=[0.005] * 2)
    start = dict(rate0=[0.001, -0.002, 0.003], eta0=[0.001, -0.002], eta_dot0=[0.0, 0.001])

    def rotor(model, t):
        h, h_dot = imbalanced_rotor(t)
        model.u.h_extra[0], model.u.hdot_extra[0] = h, h_dot
        model.u.h_extra_frequency[0] = ROTOR

    steps = 10
    times = np.arange(steps + 1) * DT
    jittering = run(hub(inertia, **modes, **start), steps, rotor)
    calm = run(hub(inertia, **modes, **start), steps)

    def reference(out, devices=None):
        x0 = np.concatenate([out["q_BI"][0], out["w_BI_B"][0], out["eta"][0, :2],
                             out["eta_dot"][0, :2]])  # fmt: skip
        model = flexible.Hub(inertia, modes["coupling"], modes["frequency"], modes["damping"],
                             devices=devices)  # fmt: skip
        return model.run(x0, times, max_step=4e-4 if devices else np.inf)

    resolved, still = reference(jittering, imbalanced_rotor), reference(calm)

    def angle(a, b):
        return max(2 * np.linalg.norm(scan_pitch.qmul(scan_pitch.qconj(p), q)[1:])
                   for p, q in zip(a, b))  # fmt: skip

    jitter = angle(still[:, :4], resolved[:, :4])
    integration = angle(calm["q_BI"], still[:, :4])
    error = angle(jittering["q_BI"], resolved[:, :4])
    rate_jitter = np.abs(resolved[:, 4:7] - still[:, 4:7]).max()
    rate_error = np.abs(jittering["w_BI_B"] - resolved[:, 4:7]).max()
    print(
        f"rotor at 628 rad/s stepped at 0.05 s: jitter {jitter:.2e} rad, error {error:.1e} rad "
        f"(the mean motion's own {integration:.1e}); rate jitter {rate_jitter:.2e} rad/s, "
        f"error {rate_error:.1e}"
    )
    assert jitter > 1e-9
    assert error < integration + 0.01 * jitter
    assert rate_error < 0.005 * rate_jitter
    assert np.array_equal(jittering["H_I"], calm["H_I"])


@pytest.mark.parametrize("step", [DT, 0.033])
def test_a_rotating_row_with_its_derivative_set_turns_to_the_steps_end(step):
    """A host that sets h_extra's derivative (FMI's input derivatives) and reads right after
    the step: the rotating row is at the step's end as the sinusoid it is (the rotor's own
    value there to round-off), not on the straight line h + ḣ H (31 times its amplitude at
    0.05 s), its derivatives consumed; the outputs bit for bit those of a host that sets the
    turned row again."""

    def stepped(again):
        model = hub(956.0 * np.eye(3), rate0=[0.001, -0.002, 0.003]).start()
        h, h_dot = imbalanced_rotor(0.0)
        model.u.h_extra[0], model.u.hdot_extra[0] = h, h_dot
        model.u.h_extra_frequency[0] = ROTOR
        model.set_input_rate("h_extra", np.vstack([h_dot, np.zeros((5, 3))]))
        model.step(0.0, step)
        turned = model.get("h_extra")[0], model.get("hdot_extra")[0]
        if again:
            model.set("h_extra", np.vstack([turned[0], np.zeros((5, 3))]))
        else:
            model.inputs_to_step_end(step)
        model.output()
        return turned, model.values[: model.layout.n_numeric].copy(), model

    (h, h_dot), after, model = stepped(False)
    _, again, _ = stepped(True)
    expected = imbalanced_rotor(step)
    scale = np.abs(expected[0]).max()
    assert np.abs(h - expected[0]).max() < 1e-12 * scale
    assert np.abs(h_dot - expected[1]).max() < 1e-12 * scale * ROTOR
    assert not model._given("h_extra")[:3].any() and not model.input_rate("h_extra")[:3].any()
    assert np.array_equal(after, again)


def test_the_output_derivatives_with_a_rotating_row_are_the_mean_motions():
    """A host extrapolates the outputs along their derivatives: with a rotating row they are
    the mean motion's (those of the hub without the row, to round-off where the attitude's
    small offset θ̃ enters), not the 100 Hz oscillation's, which is Ω times larger."""

    def derivatives(rotor):
        model = hub(956.0 * np.eye(3), coupling=[[20.0, 0, 0]], frequency=[2.45],
                    rate0=[0.001, -0.002, 0.003])  # fmt: skip
        if rotor:
            h, h_dot = imbalanced_rotor(0.0)
            model.u.h_extra[0], model.u.hdot_extra[0] = h, h_dot
            model.u.h_extra_frequency[0] = ROTOR
        model.start()
        model.step(0.0, DT)
        model.output()
        return model.output_derivatives(), model.get("w_BI_B")

    (jittering, w), (calm, w_calm) = derivatives(True), derivatives(False)
    assert np.abs(w - w_calm).max() > 1e-7  # the jitter is in the outputs
    assert np.allclose(jittering, calm, rtol=1e-6, atol=1e-12)


def test_rows_of_further_devices_and_torques_add_to_the_fixed_inputs():
    """A device in a row of h_extra is the same device in h_wheel, a torque in a row of
    tau_extra the same in tau_ext: the runs agree to round-off."""

    def fixed(model, t):
        model.set("h_wheel", device(t)[0])
        model.set("hdot_wheel", device(t)[1])
        model.set("tau_ext", [0.01, -0.02, 0.03])

    def rows(model, t):
        model.u.h_extra[2], model.u.hdot_extra[2] = device(t)
        model.u.tau_extra[1] = [0.01, -0.02, 0.03]

    case = tumbling()
    a, b = run(hub(**case), 100, fixed), run(hub(**case), 100, rows)
    for name in a:
        assert np.allclose(a[name], b[name], rtol=1e-13, atol=1e-15), name


def test_the_modes_are_saved_and_restored_with_the_fmus_state():
    """fmi2GetFMUstate, serialised to bytes and back, fmi2SetFMUstate: the modes continue
    bit for bit (η, η̇ are state of the hub's FMU)."""
    from helpers import logged, slave

    fmu = slave("SatelliteDynamics")
    at = {name: vr for vr, (_, name) in enumerate(fmu.model.layout.scalars)}
    values = {"modal_frequency[1]": 2.45, "modal_coupling[1,2]": 12.0, "modal_damping[1]": 0.01}
    values.update({"eta0[1]": 0.01, "rate0[3]": 0.02})
    fmu.set_real([at[name] for name in values], list(values.values()))
    fmu.set_boolean([at["gravity_gradient"]], [False])
    fmu.exit_initialization_mode()
    outputs = [
        vr for vr, (v, _) in enumerate(fmu.model.layout.scalars) if v.name in ("eta", "eta_dot")
    ]
    assert fmu.do_step(0.0, DT)
    saved = fmu._fmu_state_to_bytes(fmu._get_fmu_state())
    before = fmu.get_real(outputs)
    assert fmu.do_step(DT, DT)
    after = fmu.get_real(outputs)
    assert after != before  # the modes move: a lost state would show
    fmu._set_fmu_state(fmu._fmu_state_from_bytes(saved))
    assert fmu.do_step(DT, DT)
    assert fmu.get_real(outputs) == after and logged(fmu) == []
