"""Rotor microvibration of CmgCluster and Flywheel (DESIGN.md §3.2) against closed forms: the
amplitudes U_s Ω² and U_d Ω², the spin frequency, the phase progression φ0 + ∫Ω, the torque
about the centre of mass, the imbalances' momentum and its rate."""

import math

import numpy as np
import pytest

from agilesat.components.cmg_cluster import CmgCluster
from agilesat.components.flywheel import Flywheel
from reference import flexible

US, UD = 2.4e-6, 4.6e-7  # kg·m, kg·m² (HR12-25, Honeywell via Basilisk's simIncludeRW)
SPEED = 200.0 * math.pi  # 6000 rpm
ZERO3 = [0.0, 0.0, 0.0]


def one_rotor(model, **imbalance):
    """The first rotor imbalanced (the others balanced)."""
    n = 4 if model is Flywheel else 6
    rows = {k: [0.0] * n for k in ("static_imbalance", "dynamic_imbalance")}
    rows["static_imbalance"][0] = imbalance.get("us", 0.0)
    rows["dynamic_imbalance"][0] = imbalance.get("ud", 0.0)
    rows["rotor_position_B"] = [imbalance.get("r", ZERO3)] + [ZERO3] * (n - 1)
    rows["imbalance_phase0"] = [imbalance.get("phase0", 0.0)] + [0.0] * (n - 1)
    return rows


def cluster(**imbalance):
    return CmgCluster(rotor_speed=SPEED, **one_rotor(CmgCluster, **imbalance)).start()


def samples(model, dt, steps, name):
    """The output ``name`` at t = 0, dt, … (the model's inputs held)."""
    values = [model.get(name)]
    for k in range(steps):
        model.advance(k * dt, dt)
        values.append(model.get(name))
    return np.array(values)


def test_static_imbalance_force_turns_at_the_spin_rate_with_amplitude_us_omega2():
    """One rotor (gimbals at rest): |F| = U_s Ω² at every sample, F ⊥ σ, F(0) along the
    gimbal axis (φ0 = 0: the reference direction), and the angle between successive
    samples is Ω dt (mod 2π); F_x crosses zero at 2 Ω / 2π a second."""
    model = cluster(us=US)
    g, spin = model.p.gimbal_axis[0], model.geometry.spins(model.p.delta0)[0]
    dt = 1e-4
    F = samples(model, dt, 2000, "f_jitter_B")
    size = np.linalg.norm(F, axis=1) / (US * SPEED**2)
    print(f"|F| / U_s Ω²: {size.min():.15f} to {size.max():.15f}")
    assert np.allclose(size, 1.0, rtol=1e-14)
    assert np.abs(F @ spin).max() < 1e-14 * US * SPEED**2
    assert np.allclose(F[0] / (US * SPEED**2), g / np.linalg.norm(g), atol=1e-15)
    step = np.arctan2(np.cross(F[:-1], F[1:]) @ spin, np.einsum("ij,ij->i", F[:-1], F[1:]))
    assert np.allclose(step, SPEED * dt, rtol=1e-9)
    x, t = F[:, 0], np.arange(len(F)) * dt
    k = np.flatnonzero(np.sign(x[:-1]) * np.sign(x[1:]) < 0)
    crossings = t[k] - x[k] * dt / (x[k + 1] - x[k])
    frequency = 0.5 / np.mean(np.diff(crossings))
    print(f"F_x crosses zero at {frequency:.6f} Hz (the spin: {SPEED / (2 * math.pi):.6f} Hz)")
    assert frequency == pytest.approx(SPEED / (2 * math.pi), rel=1e-4)


def test_torque_about_the_centre_of_mass_is_ud_omega2_plus_r_cross_f():
    """τ = U_d Ω² e + r × F with e = F / (U_s Ω²), and ḣ_u = −τ with the gimbals at rest;
    everything zero without imbalance."""
    r = np.array([0.6, -0.2, -0.4])
    model = cluster(us=US, ud=UD, r=r.tolist(), phase0=0.7)
    for _ in range(5):
        F, tau = model.get("f_jitter_B"), model.get("tau_jitter_B")
        e = F / (US * SPEED**2)
        assert np.allclose(tau, UD * SPEED**2 * e + np.cross(r, F), rtol=1e-13, atol=1e-16)
        assert np.allclose(model.get("hdot_jitter_B"), -tau, rtol=1e-13, atol=1e-16)
        model.advance(model.t, 0.013)
    balanced = cluster()
    for name in ("f_jitter_B", "tau_jitter_B", "h_jitter_B", "hdot_jitter_B"):
        assert not balanced.get(name).any()
    assert balanced.get("jitter_frequency") == SPEED


@pytest.mark.parametrize("moving", [False, True], ids=["gimbals at rest", "gimbals turning"])
def test_imbalance_momentum_rate_is_its_derivative(moving):
    """hdot_jitter_B is d/dt h_jitter_B, and the output derivatives of f, τ, h_u, ḣ_u are
    theirs: central differences over ±1e-6 s to 1e-6 (the gimbals' own part, δ̇/Ω ≈ 6e-4
    of it, included)."""
    model = cluster(us=US, ud=UD, r=[0.3, 0.4, -0.5], phase0=1.1)
    if moving:
        model.set("delta_dot_cmd", [0.3, -0.2, 0.1, 0.4, -0.3, 0.2])
        model.advance(0.0, 2.0)  # the gimbals at their commanded rates
    dt = 1e-6
    names = ("f_jitter_B", "tau_jitter_B", "h_jitter_B", "hdot_jitter_B")
    values = []
    for k in range(3):
        values.append([model.get(n) for n in names])
        if k == 1:
            derivatives = model.output_derivatives()[-13:-1].reshape(4, 3)
        model.advance(model.t, dt)
    for k, name in enumerate(names):
        difference = (values[2][k] - values[0][k]) / (2 * dt)
        assert np.abs(difference - derivatives[k]).max() < 1e-6 * np.abs(derivatives[k]).max()
    assert np.array_equal(values[1][3], derivatives[2])  # hdot_jitter_B answers h_jitter_B


def test_the_models_agree_with_the_reference_rotor():
    """Random imbalances, positions and phases of the six rotors at random gimbal angles:
    F, τ, h_u, ḣ_u are the sums of the reference's rotors (tests/tools/reference)."""
    rng = np.random.default_rng(3)
    us, ud = rng.uniform(1e-6, 5e-6, 6), rng.uniform(1e-7, 1e-6, 6)
    r, phase0 = rng.normal(0, 0.5, (6, 3)), rng.uniform(0, 2 * math.pi, 6)
    delta = rng.uniform(-math.pi, math.pi, 6)
    model = CmgCluster(
        rotor_speed=SPEED, delta0=delta, static_imbalance=us, dynamic_imbalance=ud,
        rotor_position_B=r, imbalance_phase0=phase0,
    ).start()  # fmt: skip
    model.advance(0.0, 0.37)  # gimbals at rest: the commands are zero
    spins = model.geometry.spins(model.get("delta"))
    total = np.zeros((4, 3))
    for i in range(6):
        parts = flexible.imbalance(
            us[i], ud[i], r[i], spins[i], model.geometry.G[i], SPEED, phase0[i] + SPEED * 0.37
        )
        total += np.array(parts)[[2, 3, 0, 1]]
    outputs = ("f_jitter_B", "tau_jitter_B", "h_jitter_B", "hdot_jitter_B")
    for k, name in enumerate(outputs):
        assert np.allclose(model.get(name), total[k], rtol=1e-12, atol=1e-18), name


def wheel(speed0=SPEED, torque=0.0, **imbalance):
    """One wheel on x (the others absent), no friction, its motor on a constant torque."""
    model = Flywheel(
        axis=[[1.0, 0, 0], ZERO3, ZERO3, ZERO3],
        speed0=[speed0, 0, 0, 0],
        viscous_friction=0.0,
        coulomb_friction=0.0,
        torque_limit=abs(torque) or 0.2,
        **one_rotor(Flywheel, **imbalance),
    )
    model.set("tau_cmd", [-torque, 0, 0])  # the body torque −m a: the motor gives +m
    return model.start()


def test_a_wheel_imbalance_follows_the_wheel_angle():
    """A wheel accelerating from 300 rad/s at m / J_w: the force's angle from the reference
    direction (y for a wheel on x) is φ0 + Ω0 t + ½ Ω̇ t² (the trapezoidal rule is exact at
    constant acceleration), its size U_s Ω(t)²; rows of absent wheels stay zero."""
    model = wheel(speed0=300.0, torque=0.1, us=US, phase0=0.4)
    accel = 0.1 / model.p.J_wheel
    dt, steps = 0.01, 200
    F = samples(model, dt, steps, "f_jitter_B")
    t = np.arange(steps + 1) * dt
    speed = 300.0 + accel * t
    angle = np.arctan2(F[:, 2], F[:, 1])  # e = y cos φ + (x × y) sin φ = (0, cos φ, sin φ)
    expected = 0.4 + 300.0 * t + 0.5 * accel * t * t
    assert np.allclose(np.angle(np.exp(1j * (angle - expected))), 0.0, atol=1e-9)
    assert np.allclose(np.linalg.norm(F, axis=1), US * speed**2, rtol=1e-12)
    assert not model.get("h_jitter_B")[1:].any()


def test_a_wheel_at_rest_or_balanced_has_no_jitter():
    for model in (wheel(speed0=0.0, us=US, ud=UD), wheel()):
        for name in ("f_jitter_B", "tau_jitter_B", "h_jitter_B", "hdot_jitter_B"):
            assert not model.get(name).any(), name
