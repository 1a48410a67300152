"""Feedback controller: joint/Jacobian paths agree, one-step correction, schedules."""

import numpy as np
import pytest
from skinny_mj.controllers.feedback import (
    FeedbackController,
    fixed_gain,
    jacobian_error,
    joint_space_error,
    linear_gain,
    multiplicative_gain,
)
from skinny_mj.controllers.plant import ToyPlant

LIMITS = np.tile([0.0, np.pi], (4, 1))
SPEED = np.array([1.0, 2.0, 1.5, 0.5])


def _plant(signal_map="joint", **kw):
    q0 = np.array([0.4, 1.0, 2.0, 0.7])
    return ToyPlant(2, q0, LIMITS, SPEED, signal_map=signal_map, sensor_noise_std=0.0, **kw)


def test_joint_and_jacobian_paths_agree_on_a_diagonal_jacobian():
    plant = _plant()
    sensed = plant.reset()
    desired = sensed + np.random.default_rng(0).normal(0, 0.01, sensed.shape)
    per_rad = 2.0 / np.pi * np.ones(4)
    joint = joint_space_error(desired, sensed, per_rad, SPEED, plant.dt)
    jac = jacobian_error(desired, sensed, plant.command_jacobian(), damping=0.0)
    np.testing.assert_allclose(jac, joint, rtol=1e-10)
    ctrl = FeedbackController("joint", signal_per_rad=tuple(per_rad))
    np.testing.assert_allclose(ctrl.u_error(desired, sensed, plant), joint)


def test_command_jacobian_matches_finite_differences_of_a_nonlinear_map():
    plant = _plant("planar_arm")
    plant.reset()
    jac = plant.command_jacobian()
    eps = 1e-6
    for j in range(4):
        c = np.zeros((2, 4))
        c[:, j] = eps
        plant.reset()
        plus = plant.step(c)
        plant.reset()
        minus = plant.step(-c)
        np.testing.assert_allclose((plus - minus) / (2 * eps), jac[:, :, j], atol=1e-7)


def test_one_step_correction_lands_on_a_reachable_target():
    plant = _plant("planar_arm")
    plant.reset()
    q_goal = plant.joint_angles() + np.array([0.01, -0.02, 0.015, 0.005])
    desired = plant.signals_of(q_goal)
    u = FeedbackController().u_error(desired, plant.true_signals(), plant)
    before = np.abs(desired - plant.true_signals()).max()
    after = np.abs(desired - plant.step(u)).max()
    assert after < 0.01 * before


def test_damping_bounds_the_correction_at_a_singularity():
    plant = ToyPlant(1, np.array([1.0, 0.0]), LIMITS[:2], SPEED[:2], signal_map="planar_arm",
                     sensor_noise_std=0.0)  # arm stretched: elbow at 0
    plant.reset()
    jac = plant.command_jacobian()
    jac[:, :, 1] = jac[:, :, 0]  # make it exactly rank deficient
    err = np.array([[0.0, 0.0, 0.01, 0.0]])
    u = jacobian_error(err, np.zeros_like(err), jac, damping=1e-3)
    assert np.all(np.isfinite(u)) and np.abs(u).max() < 1e3


def test_gain_schedules():
    np.testing.assert_allclose(linear_gain(10), np.linspace(1, 0, 10))
    assert linear_gain(10)[-1] == 0.0
    np.testing.assert_allclose(multiplicative_gain(3, 0.9), [1.0, 0.9, 0.81])
    np.testing.assert_allclose(fixed_gain(4, 0.65), [0.65] * 4)
    with pytest.raises(ValueError, match="epochs"):
        linear_gain(0)


@pytest.mark.parametrize("mode", ["joint", "jacobian"])
@pytest.mark.parametrize("gain", [1.0, 0.7])
def test_stepper_gives_u_errors_numbers_bit_for_bit(mode, gain):
    plant = _plant()
    fb = FeedbackController(mode=mode, signal_per_rad=tuple(2.0 / LIMITS[:, 1]), gain=gain)
    rng = np.random.default_rng(3)
    error, out = fb.stepper(plant), np.zeros((2, 4))
    for _ in range(5):
        plant.step(rng.uniform(-1, 1, (2, 4)))
        desired, sensed = rng.uniform(-1, 1, (2, 4)), plant.true_signals()
        error(0, desired, sensed, out)
        np.testing.assert_array_equal(out, fb.u_error(desired, sensed, plant))
