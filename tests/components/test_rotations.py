"""Attitude conventions (DESIGN.md §2) against independent statements of them."""

import math

import numpy as np
import pytest

from agilesat.components.rotations import (
    dcm_from_euler123,
    dcm_from_quat,
    euler123_from_quat,
    euler123_rates,
    quat_conj,
    quat_from_axis_angle,
    quat_from_dcm,
    quat_from_euler123,
    quat_mul,
    rot1,
    rot2,
    rot3,
)
from agilesat.components.vectors import quat_dot, rotate, rotate_back

RNG = np.random.default_rng(7)


def random_quats(n):
    q = RNG.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1)[:, None]


@pytest.mark.parametrize("axis, rot", [((1, 0, 0), rot1), ((0, 1, 0), rot2), ((0, 0, 1), rot3)])
def test_frame_rotation_about_an_axis_is_the_passive_elementary_matrix(axis, rot):
    for angle in (-2.0, 0.3, 1.7):
        assert np.allclose(dcm_from_quat(quat_from_axis_angle(axis, angle)), rot(angle), atol=1e-15)


def test_the_tuple_products_are_numpys_matrix_products():
    """rotate: M v, rotate_back: Mᵀ v (M as a tuple of rows), quat_dot: p · q, each to
    rounding (the bound: a few ulps of the sum of the products' magnitudes)."""
    rng = np.random.default_rng(11)  # its own draws: the other tests' stay as they were
    for _ in range(50):
        M, v, p, q = (
            rng.normal(size=(3, 3)),
            rng.normal(size=3),
            rng.normal(size=4),
            rng.normal(size=4),
        )
        rows = tuple(tuple(row) for row in M.tolist())
        bound = 4 * np.finfo(float).eps
        assert np.all(abs(np.array(rotate(rows, v)) - M @ v) <= bound * (abs(M) @ abs(v)))
        assert np.all(abs(np.array(rotate_back(rows, v)) - M.T @ v) <= bound * (abs(M.T) @ abs(v)))
        assert abs(quat_dot(p, q) - p @ q) <= bound * (abs(p) @ abs(q))
    C = dcm_from_quat(quat_from_axis_angle(rng.normal(size=3), 2.0))
    rows = tuple(tuple(row) for row in C.tolist())
    v = rng.normal(size=3)
    assert np.allclose(rotate_back(rows, rotate(rows, v)), v, rtol=0, atol=1e-14)  # CᵀC = 1


def test_dcm_maps_reference_coordinates_into_the_rotated_frame():
    # frame B turned +90° about z from I: I's x axis is B's -y axis
    C = dcm_from_quat(quat_from_axis_angle((0, 0, 1), math.pi / 2))
    assert np.allclose(C @ [1, 0, 0], [0, -1, 0], atol=1e-15)


def test_composition_follows_the_hamilton_product_in_reverse_order():
    for q_XY, q_YZ in zip(random_quats(20), random_quats(20)):
        q_XZ = quat_mul(q_YZ, q_XY)
        assert np.allclose(
            dcm_from_quat(q_XZ), dcm_from_quat(q_XY) @ dcm_from_quat(q_YZ), atol=1e-14
        )


@pytest.mark.parametrize("big", [None, 0, 1, 2, 3])  # exercise every branch of Shepperd
def test_quat_from_dcm_inverts_dcm_from_quat(big):
    for q in random_quats(50):
        if big is not None:
            q[big] *= 40
            q /= np.linalg.norm(q)
        back = quat_from_dcm(dcm_from_quat(q))
        assert back[0] >= 0
        assert np.allclose(back, q if q[0] >= 0 else -q, atol=1e-14)


def test_kinematics_match_rotation_about_a_constant_body_axis():
    """q̇ = ½ q ⊗ (0, w) with w fixed in B: q(T) = q(0) ⊗ (cos |w|T/2, ŵ sin |w|T/2)."""
    q0 = random_quats(1)[0]
    w = np.array([0.03, -0.02, 0.05])
    T, n = 20.0, 2000
    q = q0.copy()
    f = lambda q: 0.5 * quat_mul(q, np.r_[0.0, w])
    for _ in range(n):
        h = T / n
        k1 = f(q)
        k2 = f(q + h / 2 * k1)
        k3 = f(q + h / 2 * k2)
        k4 = f(q + h * k3)  # noqa: E702
        q = q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    expected = quat_mul(q0, quat_from_axis_angle(w, np.linalg.norm(w) * T))
    assert np.allclose(q, expected, atol=1e-12)


def test_euler123_matrix_is_the_transpose_of_video_sar_eq9():
    phi, theta, psi = 0.2, -0.7, 1.1
    c, s = math.cos, math.sin
    eq9 = np.array(
        [  # maps body to orbit coordinates (the paper's r_A^o = M r_A^b)
            [c(theta) * c(psi), -c(theta) * s(psi), s(theta)],
            [
                s(phi) * s(theta) * c(psi) + c(phi) * s(psi),
                -s(phi) * s(theta) * s(psi) + c(phi) * c(psi),
                -s(phi) * c(theta),
            ],
            [
                -c(phi) * c(psi) * s(theta) + s(phi) * s(psi),
                c(phi) * s(theta) * s(psi) + s(phi) * c(psi),
                c(phi) * c(theta),
            ],
        ]
    )
    assert np.allclose(dcm_from_euler123((phi, theta, psi)), eq9.T, atol=1e-15)


def test_euler123_roundtrip_on_the_principal_branch():
    for angles in RNG.uniform([-3, -1.5, -3], [3, 1.5, 3], size=(50, 3)):
        assert np.allclose(euler123_from_quat(quat_from_euler123(angles)), angles, atol=1e-12)


@pytest.mark.slow
def test_pitch_runs_continuously_through_the_gimbal_lock():
    """scan_pitch: pitch 120° -> 0° with tiny roll/yaw must not flip roll and yaw by 180°."""
    pitches = np.radians(np.linspace(120, 0, 4801))  # passes 90° within 0.0125°
    previous = np.array([0.0, pitches[0], 0.0])
    out = []
    for theta in pitches:
        q = quat_from_euler123((2e-5, theta, -1e-5))
        previous = euler123_from_quat(q, previous)
        assert np.allclose(dcm_from_euler123(previous), dcm_from_quat(q), atol=1e-12)
        out.append(previous)
    out = np.array(out)
    assert np.max(np.abs(np.diff(out[:, 1]))) < np.radians(0.03)  # pitch: no jump
    far = np.abs(out[:, 1] - math.pi / 2) > np.radians(1.0)
    assert np.max(np.abs(out[far][:, [0, 2]])) < 1e-3  # roll, yaw ≈ 0
    assert np.degrees(out[0, 1]) == pytest.approx(120) and abs(out[-1, 1]) < 1e-12


def test_exact_gimbal_lock_keeps_the_defined_combination():
    q = quat_from_euler123((0.3, math.pi / 2, -0.1))
    angles = euler123_from_quat(q, previous=np.array([0.25, 1.55, -0.05]))
    assert angles[1] == pytest.approx(math.pi / 2)
    assert angles[0] + angles[2] == pytest.approx(0.2, abs=1e-7)
    assert np.allclose(dcm_from_euler123(angles), dcm_from_quat(q), atol=1e-7)


def test_euler_rates_invert_video_sar_eq13():
    phi, theta, psi = 0.1, 0.4, -0.3
    rates = np.array([0.01, -0.02, 0.03])
    w = np.array(
        [
            rates[0] * math.cos(psi) * math.cos(theta) + rates[1] * math.sin(psi),
            -rates[0] * math.sin(psi) * math.cos(theta) + rates[1] * math.cos(psi),
            rates[2] + rates[0] * math.sin(theta),
        ]
    )
    assert np.allclose(euler123_rates((phi, theta, psi), w), rates, atol=1e-15)


def test_euler_rates_are_the_time_derivative_of_the_angles():
    q0, w = quat_from_euler123((0.2, -0.3, 0.5)), np.array([0.02, 0.05, -0.01])
    h = 1e-4
    angles = [
        euler123_from_quat(quat_mul(q0, quat_from_axis_angle(w, np.linalg.norm(w) * t)))
        for t in (-h, 0.0, h)
    ]
    assert np.allclose((angles[2] - angles[0]) / (2 * h), euler123_rates(angles[1], w), atol=1e-9)


def test_conjugate_is_the_inverse_rotation():
    q = random_quats(1)[0]
    assert np.allclose(dcm_from_quat(quat_conj(q)), dcm_from_quat(q).T, atol=1e-15)
