"""Error histories from attitude quaternions, against the toolkit's rotation conventions."""

import math

import numpy as np
import pytest

from agilesat.components import rotations
from agilesat.orchestration.pointing import (
    ErrorHistory,
    knowledge_error,
    performance_error,
    quaternion_product,
    rotation_quaternion,
    rotation_vector,
)

T = np.arange(5) * 0.1


def random_quaternions(rng, count):
    q = rng.normal(size=(count, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def test_the_error_rotation_is_the_dcm_of_the_toolkit_and_its_rotation_vector():
    """q_XY = q_YI* ⊗ q_XI has C(q_XY) = C(q_XI) C(q_YI)ᵀ (DESIGN.md §2), and φ rebuilds it."""
    rng = np.random.default_rng(1)
    q_x, q_y = random_quaternions(rng, 50), random_quaternions(rng, 50)
    conjugate = q_y * [1, -1, -1, -1]
    q_err = quaternion_product(conjugate, q_x)
    phi = rotation_vector(q_err)
    for a, b, e, p in zip(q_x, q_y, q_err, phi):
        expected = rotations.dcm_from_quat(a) @ rotations.dcm_from_quat(b).T
        assert rotations.dcm_from_quat(e) == pytest.approx(expected, abs=1e-12)
        angle = np.linalg.norm(p)
        assert angle <= math.pi
        rebuilt = rotations.quat_from_axis_angle(p / angle, angle)
        assert rebuilt == pytest.approx(e * np.sign(e[0]), abs=1e-12)
        assert rotation_quaternion(p) == pytest.approx(rebuilt, abs=1e-15)


def test_signs_estimate_minus_truth_and_truth_minus_reference():
    reference = np.tile([1.0, 0.0, 0.0, 0.0], (T.size, 1))
    turned = np.tile(rotations.quat_from_axis_angle([0, 0, 1], 0.01), (T.size, 1))
    assert performance_error(turned, reference, T).values[0, 0] == pytest.approx([0, 0, 0.01])
    assert knowledge_error(turned, reference, T).values[0, 0] == pytest.approx([0, 0, 0.01])
    assert knowledge_error(reference, turned, T).kind == "knowledge"
    assert performance_error(reference, turned, T).values[0, 0] == pytest.approx([0, 0, -0.01])
    tiny = rotations.quat_from_axis_angle([1, 0, 0], 1e-12)
    assert rotation_vector(tiny) == pytest.approx([1e-12, 0, 0], rel=1e-9)
    assert rotation_vector(-tiny) == pytest.approx([1e-12, 0, 0], rel=1e-9)  # ±q alike


@pytest.mark.parametrize("angle", [1e-6, 0.3, 2.5])
def test_line_of_sight_is_the_exact_half_cone_normal_to_the_boresight(angle):
    rng = np.random.default_rng(2)
    axes = rng.normal(size=(20, 3))
    phi = angle * axes / np.linalg.norm(axes, axis=1, keepdims=True)
    b = np.array([0.3, -0.2, 0.9]) / np.linalg.norm([0.3, -0.2, 0.9])
    eps = ErrorHistory(phi, np.arange(20.0)).line_of_sight(b).values[0]
    for p, e in zip(phi, eps):
        q = rotations.quat_from_axis_angle(p, np.linalg.norm(p))
        seen = rotations.dcm_from_quat(q).T @ b  # the body boresight in reference axes
        assert np.linalg.norm(e) == pytest.approx(math.acos(np.clip(seen @ b, -1, 1)), abs=1e-9)
        assert e @ b == pytest.approx(0.0, abs=1e-12)
        assert np.cross(b, seen) @ e >= 0.0
    if angle < 1e-3:  # first order: the rotation vector's part normal to b
        assert eps == pytest.approx(phi - np.outer(phi @ b, b), abs=angle**2)


def test_about_an_axis_is_the_rotation_vector_component():
    phi = np.array([[0.1, -0.2, 0.3], [0.0, 0.5, 0.0]])
    about = ErrorHistory(phi, [0.0, 1.0]).about([0, 2, 0])
    assert about.values[0, :, 0] == pytest.approx([-0.2, 0.5])
    assert about.signal == "about axis (0, 1, 0)"
    assert ErrorHistory(phi, [0.0, 1.0]).signal == "rotation vector, body axes"
    assert ErrorHistory(phi[:, 0], [0.0, 1.0]).signal == "scalar"
    with pytest.raises(ValueError, match="needs a rotation-vector error"):
        about.about([1, 0, 0])
    with pytest.raises(ValueError, match="non-zero 3-vector"):
        ErrorHistory(phi, [0.0, 1.0]).line_of_sight([0, 0, 0])


def test_bad_histories_are_named():
    q = np.tile([1.0, 0.0, 0.0, 0.0], (2, T.size, 1))
    q[1, 3] = [0.5, 0, 0, 0]
    with pytest.raises(ValueError, match=r"q_XI is not a unit quaternion at run 1, sample 3"):
        performance_error(q, np.tile([1.0, 0, 0, 0], (2, T.size, 1)), T)
    with pytest.raises(ValueError, match="uniformly sampled"):
        ErrorHistory(np.zeros(3), [0.0, 0.1, 0.3])
    values = np.zeros((2, 3, 1))
    values[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match=r"error of run 1 is not finite at t = 0.2 s"):
        ErrorHistory(values, [0.0, 0.1, 0.2])
    with pytest.raises(ValueError, match=r"expected \(samples,\)"):
        ErrorHistory(np.zeros((3, 2)), [0.0, 0.1, 0.2])
    with pytest.raises(ValueError, match="error kind"):
        ErrorHistory(np.zeros(3), [0.0, 0.1, 0.2], kind="estimate")


def test_a_campaigns_recorded_error_is_each_runs_own_across_blocks():
    """A campaign's columns (runs, points) give, run for run, the error of that run's own
    columns, over the window asked; runs past the first block (errors.BLOCK) included, and
    a quaternion that is not a unit one named by its run across blocks."""
    from agilesat.orchestration.pointing.errors import BLOCK, quaternion_columns, recorded_error

    rng = np.random.default_rng(4)
    runs, t = BLOCK + 7, np.arange(40) * 0.5
    q_x = random_quaternions(rng, runs * t.size).reshape(runs, t.size, 4)
    q_y = random_quaternions(rng, runs * t.size).reshape(runs, t.size, 4)
    columns = {}
    for name, q in (("A.q", q_x), ("B.q", q_y)):
        for i, column in enumerate(quaternion_columns(name)):
            columns[column] = q[..., i]
    error = recorded_error(columns, t, "A.q", "B.q", start=2.0, stop=15.0)
    window = (t >= 2.0) & (t <= 15.0)
    np.testing.assert_array_equal(error.t, t[window])
    for run in (0, BLOCK - 1, BLOCK, runs - 1):
        one = performance_error(q_x[run, window], q_y[run, window], t[window])
        np.testing.assert_array_equal(error.values[run], one.values[0])
    reference = lambda c: np.stack([c[k] for k in quaternion_columns("B.q")], axis=-1)
    by_function = recorded_error(columns, t, "A.q", reference, start=2.0, stop=15.0)
    np.testing.assert_array_equal(by_function.values, error.values)
    columns["A.q[2]"] = columns["A.q[2]"].copy()
    columns["A.q[2]"][BLOCK + 3, 9] += 0.1
    with pytest.raises(
        ValueError, match=rf"q_XI is not a unit quaternion at run {BLOCK + 3}, sample 5"
    ):
        recorded_error(columns, t, "A.q", "B.q", start=2.0, stop=15.0)


def test_a_signal_of_a_history_is_computed_once_and_the_same_values():
    """A run's requirements on one error and line of sight (an APE and an RPE) share it:
    the second asks the history, the whole of its runs, and gets the first's."""
    rng = np.random.default_rng(3)
    phi = 1e-3 * rng.normal(size=(2, 5, 3))
    error = ErrorHistory(phi, T)
    assert error.runs_between(0, 64) is error
    assert error.runs_between(1, 64).runs == 1
    los = error.line_of_sight((0, 0, 2))
    assert error.runs_between(0, 2).line_of_sight((0, 0, 1)) is los
    again = ErrorHistory(phi.copy(), T).line_of_sight((0, 0, 1))
    assert los is not again and np.array_equal(los.values, again.values)
    about = error.about((1, 0, 0))
    assert error.about((1, 0, 0)) is about and about is not error.about((0, 1, 0))
    assert np.array_equal(about.values[..., 0], phi[..., 0])
