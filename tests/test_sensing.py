"""Joint sensing: encoders with noise, finite-difference velocities, a delay."""

import numpy as np
import pytest
from skinny_mj.controllers.sensing import JointSensing

from skinny_mj.training import TrainConfig, train
from skinny_mj.training.torque import joint_nrmse


def _sensing(**kw):
    args = dict(encoder_noise_rad=0.0, velocity="finite-difference", velocity_filter_hz=None,
                delay_steps=0, dt=0.02, rngs=[np.random.default_rng(0)])
    return JointSensing(**{**args, **kw})


def test_finite_difference_of_a_ramp_is_its_slope_and_starts_at_rest():
    s = _sensing()
    s.reset(np.zeros((1, 2)), np.zeros((1, 2)))
    assert np.array_equal(s.qd, np.zeros((1, 2)))
    for k in range(1, 4):
        s.update(np.array([[0.1 * k, -0.2 * k]]), np.zeros((1, 2)))
    assert np.allclose(s.qd, [[5.0, -10.0]])
    assert np.allclose(s.q, [[0.3, -0.6]])


def test_a_delay_shows_the_state_one_step_late():
    s = _sensing(delay_steps=1)
    s.reset(np.zeros((1, 1)), np.zeros((1, 1)))
    s.update(np.array([[1.0]]), np.zeros((1, 1)))
    assert s.q[0, 0] == 0.0
    s.update(np.array([[2.0]]), np.zeros((1, 1)))
    assert s.q[0, 0] == 1.0 and s.qd[0, 0] == pytest.approx(50.0)


def test_encoder_noise_has_its_standard_deviation_and_each_run_its_stream():
    rngs = [np.random.default_rng(1), np.random.default_rng(2)]
    s = _sensing(encoder_noise_rad=0.01, rngs=rngs)
    s.reset(np.zeros((2, 3)), np.zeros((2, 3)))
    draws = []
    for _ in range(2000):
        s.update(np.zeros((2, 3)), np.zeros((2, 3)))
        draws.append(s.q.copy())
    draws = np.array(draws)
    assert draws.std() == pytest.approx(0.01, rel=0.05)
    alone = _sensing(encoder_noise_rad=0.01, rngs=[np.random.default_rng(2)])
    alone.reset(np.zeros((1, 3)), np.zeros((1, 3)))
    alone.update(np.zeros((1, 3)), np.zeros((1, 3)))
    assert np.array_equal(alone.q[0], draws[0, 1])


def test_the_filter_smooths_the_velocity_and_oracle_passes_it_through():
    s = _sensing(velocity_filter_hz=2.0)
    s.reset(np.zeros((1, 1)), np.zeros((1, 1)))
    s.update(np.array([[0.02]]), np.zeros((1, 1)))
    assert 0 < s.qd[0, 0] < 1.0
    o = _sensing(velocity="oracle")
    o.reset(np.zeros((1, 1)), np.array([[0.5]]))
    o.update(np.zeros((1, 1)), np.array([[3.0]]))
    assert o.qd[0, 0] == 3.0


def test_oracle_sensing_is_what_the_controllers_saw_before_and_encoders_differ():
    base = TrainConfig().override({"actuation": "torque", "movement.trajectory": "y",
                                   "method": "none", "test.gain": 1.0,
                                   "actuation.feedback": "ct"})
    oracle = train(base.override({"actuation.sensing": "oracle"}), seed=0)
    again = train(base.override({"actuation.sensing": "oracle"}), seed=0)
    enc = train(base, seed=0)
    assert joint_nrmse(oracle) == joint_nrmse(again)
    assert joint_nrmse(enc) != joint_nrmse(oracle)
    assert joint_nrmse(enc) < 0.05  # computed torque still tracks on sensed information


def test_the_second_order_difference_has_no_lag_on_a_parabola():
    s = _sensing(velocity="finite-difference-2")
    s.reset(np.zeros((1, 1)), np.zeros((1, 1)))
    for k in range(1, 5):
        s.update(np.array([[(0.02 * k) ** 2]]), np.zeros((1, 1)))
    assert s.qd[0, 0] == pytest.approx(2 * 0.08)  # d/dt t^2 at t = 0.08 s
