"""True-target training (paper D) and the cycles-to-convergence curve (paper E Fig. 3)."""

import numpy as np
import pytest
from skinny_mj.controllers.esn import ESN, ESNConfig
from skinny_mj.controllers.fel import Task, evaluate
from skinny_mj.controllers.plant import ToyPlant, toy_movement
from skinny_mj.controllers.true_target import (
    TrueTarget,
    convergence_curve,
    cycles_to_converge,
    teacher_forced_inputs,
    train_true_target,
)

LIMITS = np.tile([0.0, np.pi], (4, 1))


def _setup(n_runs=2):
    q, speed, commands = toy_movement(100, 4, seed=2)
    plant = ToyPlant(n_runs, q[0], LIMITS, speed, seed=0)
    return plant, plant.signals_of(q), commands


def test_teacher_forced_inputs():
    d = np.arange(6.0).reshape(3, 2)
    np.testing.assert_array_equal(teacher_forced_inputs(d), [[2, 3, 0, 1], [4, 5, 2, 3]])


def test_true_target_training_fits_and_closed_loop_test_works():
    plant, desired, commands = _setup()
    esn = ESN(ESNConfig(8, 4, n_reservoir=100, noise_level=0.02), n_runs=2, seed=3)
    untrained = evaluate(esn, plant, Task(desired, commands))

    def one_step(positions, cmds):  # joint-space toy: d(t) + c * speed * dt in signals
        return positions + cmds * plant.max_speed_rad_s * plant.dt * 2 / np.pi

    result = train_true_target(esn, desired, commands, TrueTarget(beta=1.0), one_step=one_step)
    assert result.outputs.shape == (2, len(desired) - 1, 4)
    assert np.all(result.motor_nrmse < 0.02) and np.all(result.position_nrmse < 0.002)
    tested = evaluate(esn, plant, Task(desired, commands))
    assert np.all(tested.position_nrmse < 0.5 * untrained.position_nrmse)


def test_new_method_with_beta_one_equals_original():
    _, desired, commands = _setup()
    outs = []
    for cfg in (TrueTarget(beta=1.0), TrueTarget(beta=1.0, cycles=1)):
        esn = ESN(ESNConfig(8, 4, n_reservoir=50, noise_level=0.2), seed=4)
        outs.append(train_true_target(esn, desired, commands, cfg).outputs)
    np.testing.assert_array_equal(outs[0], outs[1])


def test_convergence_is_slower_for_smaller_beta():
    _, desired, commands = _setup(n_runs=1)
    curves = {}
    for beta in (1.0, 0.3, 0.1):
        esn = ESN(ESNConfig(8, 4, n_reservoir=100), seed=5)
        curves[beta] = convergence_curve(esn, desired, commands, beta, cycles=60)
    assert curves[1.0][0, 0] == 0.0
    assert curves[0.1][0, 0] > curves[0.3][0, 0] > 0.0
    for curve in curves.values():  # converges (monotone up to fitting error)
        assert curve[0, -1] < 0.01 * max(curve[0, 0], 1e-300) or curve[0, 0] == 0.0
    steps = [cycles_to_converge(curves[b], 1e-3)[0] for b in (1.0, 0.3, 0.1)]
    assert steps[0] < steps[1] < steps[2] < 60


def test_bad_config():
    with pytest.raises(ValueError, match="beta"):
        TrueTarget(beta=1.5)
