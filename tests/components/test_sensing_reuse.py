"""The sensing models' step reuses the section their output advanced (components/sensing.py,
reusing the advanced section): a model whose output was evaluated before each step, with
the inputs sometimes changed in between, ends every step in the state, bit for bit, of one
that was only stepped.  Pure Python, about a second."""

import math

import numpy as np
import pytest

from agilesat.components.attitude_estimator import AttitudeEstimator
from agilesat.components.gyro import Gyro
from agilesat.components.sensing import quat_exp, reused, stamp, stamp_size
from agilesat.components.star_tracker import StarTracker

H, STEPS = 0.05, 60


def estimator_inputs(rng, t):
    return {
        "w_meas_B": rng.normal(0.0, 0.01, 3),
        "q_BI_meas": np.array(quat_exp(tuple(rng.normal(0.0, 0.5, 3)))),
        "meas_valid": True,
        "t_meas": math.floor((t - 0.2) * 4.0) / 4.0,  # a star tracker's 4 Hz, 0.2 s late
    }


def gyro_inputs(rng, t):
    return {"w_BI_B": rng.normal(0.0, 0.01, 3)}


def tracker_inputs(rng, t):
    return {
        "q_BI": np.array(quat_exp(tuple(rng.normal(0.0, 0.5, 3)))),
        "w_BI_B": rng.normal(0.0, 0.001, 3),
        "sun_I": np.array([1.0, 0.0, 0.0]),
        "r_I": np.array([7.0e6, 0.0, 0.0]),
    }


@pytest.mark.parametrize(
    "model_class, inputs",
    [(AttitudeEstimator, estimator_inputs), (Gyro, gyro_inputs), (StarTracker, tracker_inputs)],
)
def test_a_step_after_the_output_is_the_step_alone(model_class, inputs):
    looked, stepped = model_class().start(0.0), model_class().start(0.0)
    rng = np.random.default_rng(7)
    for k in range(STEPS):
        t = k * H
        given = inputs(rng, t)
        for name, value in given.items():
            looked.set(name, value)
        looked.output()
        if k % 3 == 2:  # an input changed after the output: the step advances again
            name = next(iter(given))
            given[name] = given[name] * 0.5
            looked.set(name, given[name])
        for name, value in given.items():
            stepped.set(name, value)
        looked.step(t, H)
        stepped.step(t, H)
        assert looked.state.tobytes() == stepped.state.tobytes(), k
    looked.output()
    stepped.output()
    assert looked.values.tobytes() == stepped.values.tobytes()


def test_a_stamp_matches_the_inputs_bit_for_bit():
    spans = ((1, 3),)
    values, state = np.array([9.0, 0.0, 2.5]), np.zeros(stamp_size(spans))
    stamp(values, state, 0, spans, 1.5, 4)
    assert reused(values, state, 0, spans, 1.5) == 4
    assert reused(values, state, 0, spans, 1.5 + 1e-15) == -1  # another time
    values[1] = -0.0  # == 0.0, not the same bits
    assert reused(values, state, 0, spans, 1.5) == -1
    values[1], values[0] = 0.0, 8.0  # outside the spans: not read
    assert reused(values, state, 0, spans, 1.5) == 4
