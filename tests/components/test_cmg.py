"""CMG cluster and steering law against the paper's formulas and first principles."""

import math

import numpy as np
import pytest

from agilesat.components.cmg_cluster import (
    DEFAULT_SPINS,
    GIMBAL_AXES,
    ClusterGeometry,
    CmgCluster,
    servo_step,
    zero_momentum_angles,
)
from agilesat.components.cmg_steering import PSEUDO_INVERSE, SR_INVERSE, CmgSteering
from agilesat.components.model import ModelError
from agilesat.orchestration.scenarios.scan_pitch import PAPER_DELTA0, PAPER_SPINS

DEG = math.pi / 180
A0, A1, A2 = 63.4 * DEG, 36 * DEG, 18 * DEG  # α0, α1, α2 of [Zhao 2016] §3.2


def paper_matrices(d):
    """A_s0 and A_c0 as printed in [Zhao 2016] §3.2 (3×6), at gimbal angles d.

    Column 6 of A_s0 is printed (cδ06, cδ06, 0); its derivative, A_c0's column 6, is
    (−sδ06, cδ06, 0), so the second entry must be sδ06 (a misprint, used corrected).
    """
    s, c = np.sin(d), np.cos(d)
    sa0, ca0, sa1, ca1, sa2, ca2 = (
        math.sin(A0),
        math.cos(A0),
        math.sin(A1),
        math.cos(A1),
        math.sin(A2),
        math.cos(A2),
    )
    A_s = np.array(
        [
            [
                -s[0],
                -s[1] * sa2 - c[1] * ca0 * ca2,
                s[2] * ca1 - c[2] * ca0 * sa1,
                s[3] * ca1 + c[3] * ca0 * sa1,
                -s[4] * sa2 + c[4] * ca0 * ca2,
                c[5],
            ],
            [
                c[0] * ca0,
                -s[1] * ca2 + c[1] * ca0 * sa2,
                -s[2] * sa1 - c[2] * ca0 * ca1,
                s[3] * sa1 - c[3] * ca0 * ca1,
                s[4] * ca2 + c[4] * ca0 * sa2,
                s[5],
            ],
            [c[0] * sa0, c[1] * sa0, c[2] * sa0, c[3] * sa0, c[4] * sa0, 0.0],
        ]
    )
    A_c = np.array(
        [
            [
                -c[0],
                -c[1] * sa2 + s[1] * ca0 * ca2,
                c[2] * ca1 + s[2] * ca0 * sa1,
                c[3] * ca1 - s[3] * ca0 * sa1,
                -c[4] * sa2 - s[4] * ca0 * ca2,
                -s[5],
            ],
            [
                -s[0] * ca0,
                -c[1] * ca2 - s[1] * ca0 * sa2,
                -c[2] * sa1 + s[2] * ca0 * ca1,
                c[3] * sa1 + s[3] * ca0 * ca1,
                c[4] * ca2 - s[4] * ca0 * sa2,
                c[5],
            ],
            [-s[0] * sa0, -s[1] * sa0, -s[2] * sa0, -s[3] * sa0, -s[4] * sa0, 0.0],
        ]
    )
    return A_s, A_c


@pytest.mark.parametrize("delta", [np.array(PAPER_DELTA0), np.linspace(-2.0, 2.5, 6)])
def test_five_pyramid_reproduces_the_papers_As0_and_Ac0(delta):
    printed = ClusterGeometry(1.0, GIMBAL_AXES, PAPER_SPINS)
    A_s, A_c = paper_matrices(delta)
    assert np.allclose(printed.spins(delta).T, A_s, atol=1e-15)
    assert np.allclose(printed.jacobian(delta), A_c, atol=1e-15)


def test_default_rotor_spin_is_the_printed_one_reversed():
    """The body receives +ḣ_paper (eq. 14) only if the rotor momentum is −h(A_s0 cos δ + ...)."""
    assert np.array_equal(DEFAULT_SPINS, -PAPER_SPINS)
    A_s, _ = paper_matrices(np.array(PAPER_DELTA0))
    cluster = CmgCluster().start()
    assert np.allclose(cluster.get("h"), -16.65 * A_s.sum(axis=1), atol=1e-12)
    assert np.linalg.norm(cluster.get("h")) == pytest.approx(57, abs=0.5)  # DESIGN.md §4.1


def test_gimbal_axes_are_unit_and_perpendicular_to_the_spins():
    G, S = GIMBAL_AXES, PAPER_SPINS
    assert np.allclose(np.linalg.norm(G, axis=1), 1) and np.allclose(np.sum(G * S, axis=1), 0)


def test_momentum_derivative_is_h_rotor_times_jacobian_times_rates():
    cluster = CmgCluster(accel_limit=100.0).start()
    rates = np.array([0.1, -0.2, 0.05, 0.3, -0.15, 0.2])
    cluster.set("delta_dot_cmd", rates)
    cluster.advance(0.0, 0.5)  # rates reached after 3 ms, then held
    h0, hdot = cluster.get("h"), cluster.get("hdot")
    dt = 1e-5
    cluster.advance(0.5, dt)
    assert np.allclose((cluster.get("h") - h0) / dt, hdot, rtol=1e-4, atol=1e-6)


def test_envelope_along_y_is_singular_and_equals_the_capacity_formula():
    """Each spin at its largest y component: Q = 0 and h_y = h Σ √(1 − (g_i·ŷ)²)."""
    geometry = ClusterGeometry(16.65, GIMBAL_AXES, DEFAULT_SPINS)
    y = np.array([0.0, 1.0, 0.0])
    delta = np.arctan2(geometry.T @ y, geometry.S @ y)
    assert geometry.singularity(geometry.jacobian(delta)) == pytest.approx(0, abs=1e-12)
    capacity = 16.65 * np.sqrt(1 - (GIMBAL_AXES @ y) ** 2).sum()
    assert geometry.momentum(delta)[1] == pytest.approx(capacity, rel=1e-12)
    assert capacity == pytest.approx(79, abs=0.5)  # DESIGN.md §4.1


def test_singularity_measure_is_det_of_A_At():
    geometry = ClusterGeometry(16.65, GIMBAL_AXES, DEFAULT_SPINS)
    A = geometry.jacobian(np.array([0.3, -1.0, 2.0, 0.1, 0.7, -0.4]))
    assert geometry.singularity(A) == pytest.approx(np.linalg.det(A @ A.T), rel=1e-12)


@pytest.mark.parametrize(
    "rate, command, dt",
    [
        (0.0, 0.3, 1.0),  # reaches the command after 0.6 s, then holds it
        (0.2, -0.4, 0.5),  # still accelerating at the end of the step
        (0.1, 5.0, 3.0),  # command above the rate limit: clipped to 0.6
        (0.25, 0.25, 0.7),  # already there
    ],
)
@pytest.mark.slow
def test_servo_step_matches_fine_integration(rate, command, dt):
    angle, rate_end = servo_step([0.5], [rate], [command], dt, 0.6, 0.5)
    n = 200000
    h, d, r = dt / n, 0.5, rate
    target = min(max(command, -0.6), 0.6)
    for _ in range(n):
        a = np.clip((target - r) / h, -0.5, 0.5)
        d += h * r + 0.5 * a * h * h
        r += a * h
    assert angle[0] == pytest.approx(d, abs=1e-9) and rate_end[0] == pytest.approx(r, abs=1e-9)


def test_rate_command_above_the_limit_is_reported():
    cluster = CmgCluster().start()
    cluster.set("delta_dot_cmd", [0.0, 0.9, 0.0, 0.0, 0.0, 0.0])
    cluster.advance(3.0, 0.1)
    assert any("exceeds the rate limit" in w and "gimbal 2" in w for w in cluster.warnings)


def test_servo_limits_must_be_positive():
    with pytest.raises(ModelError, match="must be positive"):
        CmgCluster(accel_limit=0.0).start()


# -- steering --------------------------------------------------------------------------
def steering(tau, delta, w, h, **parameters):
    law = CmgSteering(**parameters)
    for name, value in (("tau_cmd", tau), ("delta", delta), ("w_BI_B", w), ("h", h)):
        law.set(name, value)
    return law.start()


def delivered_torque(law, delta, w, h):
    """Torque on the body −ḣ − w × h of the commanded gimbal rates."""
    geometry = ClusterGeometry(law.p.h_rotor, law.p.gimbal_axis, law.p.spin_ref)
    hdot = geometry.h_rotor * geometry.jacobian(delta) @ law.get("delta_dot_cmd")
    return -hdot - np.cross(w, h)


@pytest.mark.parametrize("null_gain", [0.0, 0.5])
def test_pseudo_inverse_delivers_the_commanded_torque_with_gyroscopic_term(null_gain):
    rng = np.random.default_rng(11)
    for _ in range(20):
        delta, w = rng.uniform(-3, 3, 6), rng.normal(scale=0.05, size=3)
        h, tau = rng.normal(scale=30, size=3), rng.normal(scale=4, size=3)
        law = steering(tau, delta, w, h, null_gain=null_gain)
        assert np.allclose(delivered_torque(law, delta, w, h), tau, atol=1e-10)


def test_null_motion_follows_the_gradient_of_Q_without_torque():
    delta = np.array([0.3, -1.0, 2.0, 0.1, 0.7, -0.4])
    geometry = ClusterGeometry(16.65, GIMBAL_AXES, DEFAULT_SPINS)
    free = steering([0, 0, 0], delta, [0, 0, 0], [0, 0, 0], null_gain=1.0).get("delta_dot_cmd")
    assert np.allclose(geometry.jacobian(delta) @ free, 0, atol=1e-13)  # no torque
    Q = lambda d: geometry.singularity(geometry.jacobian(d))
    gradient = np.array([(Q(delta + e) - Q(delta - e)) / 2e-6 for e in np.eye(6) * 1e-6])
    projected = gradient - np.linalg.pinv(geometry.jacobian(delta)) @ (
        geometry.jacobian(delta) @ gradient
    )
    assert np.allclose(free, projected, rtol=1e-6, atol=1e-9)  # the paper's term
    assert gradient @ free > 0  # Q increases


def test_singularity_robust_inverse_bounds_the_rates_near_a_singularity():
    geometry = ClusterGeometry(16.65, GIMBAL_AXES, DEFAULT_SPINS)
    y = np.array([0.0, 1.0, 0.0])
    delta = np.arctan2(geometry.T @ y, geometry.S @ y) + 1e-4  # just off the envelope
    tau = np.array([0.0, -1.0, 0.0])  # push further along +y
    pinv = steering(tau, delta, [0, 0, 0], [0, 0, 0], law=PSEUDO_INVERSE).get("delta_dot_cmd")
    robust = steering(tau, delta, [0, 0, 0], [0, 0, 0], law=SR_INVERSE).get("delta_dot_cmd")
    assert np.abs(pinv).max() > 50 * np.abs(robust).max()
    assert np.abs(robust).max() < 1.0


def test_exact_singularity_gives_finite_rates_and_a_warning():
    geometry = ClusterGeometry(16.65, GIMBAL_AXES, DEFAULT_SPINS)
    y = np.array([0.0, 1.0, 0.0])
    delta = np.arctan2(geometry.T @ y, geometry.S @ y)
    law = steering([0, -1.0, 0.5], delta, [0, 0, 0], [0, 0, 0])
    assert np.all(np.isfinite(law.get("delta_dot_cmd")))
    assert any("singular gimbal configuration" in w for w in law.warnings)


def test_unknown_steering_law_is_rejected():
    with pytest.raises(
        ModelError,
        match=r"law must be one of 0 \(PSEUDO_INVERSE\), "
        r"1 \(SR_INVERSE\), got 2",
    ):
        CmgSteering(law=2).start()


def test_zero_momentum_angles_hold_no_momentum_at_a_local_maximum_of_q():
    geometry = ClusterGeometry(16.65, GIMBAL_AXES, DEFAULT_SPINS)
    delta = zero_momentum_angles(geometry, PAPER_DELTA0)
    assert np.linalg.norm(geometry.momentum(delta)) < 1e-12 * 16.65
    Q = geometry.singularity(geometry.jacobian(delta))
    # along the zero-momentum set (Newton back onto h = 0 after a null-space step) Q falls
    A = geometry.jacobian(delta)
    null = np.linalg.svd(A)[2][3:]  # basis of the null space of A
    for direction in null:
        for sign in (-1.0, 1.0):
            moved = zero_momentum_angles(geometry, delta + sign * 0.05 * direction, iterations=0)
            assert geometry.singularity(geometry.jacobian(moved)) < Q
    assert Q > geometry.singularity(geometry.jacobian(PAPER_DELTA0))


def test_zero_momentum_angles_report_a_failure():
    with pytest.raises(ModelError, match="no zero-momentum gimbal set"):
        zero_momentum_angles(ClusterGeometry(16.65, GIMBAL_AXES, DEFAULT_SPINS), np.zeros(6))
