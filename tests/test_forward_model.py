"""Forward model on the toy plant: pre-training predicts, modes behave as documented."""

import numpy as np
import pytest
from skinny_mj.controllers.esn import ESN, ESNConfig
from skinny_mj.controllers.fel import Loop, New, rollout, train
from skinny_mj.controllers.forward_model import ForwardModel, rollout_prediction_error
from skinny_mj.controllers.metrics import nrmse
from skinny_mj.controllers.plant import ToyPlant, toy_movement

LIMITS = np.tile([0.0, np.pi], (4, 1))


def _setup(n_runs=2):
    q, speed, commands = toy_movement(100, 4, seed=1)
    plant = ToyPlant(n_runs, q[0], LIMITS, speed, seed=0)
    return plant, plant.signals_of(q), commands


def _fm(n_runs=2, mode="serial", seed=0):
    cfg = ESNConfig(8, 4, n_reservoir=40, readout_activation="identity", noise_level=0.01,
                    readout="ridge", ridge_lambda=1e-4)
    return ForwardModel(ESN(cfg, n_runs=n_runs, seed=seed), mode)


def test_pretrained_forward_model_beats_the_no_change_guess():
    _, desired, commands = _setup()
    fm = _fm()
    train_err = fm.pretrain(desired, commands)
    test_err = fm.prediction_error(desired, commands)
    no_change = nrmse(desired[:-1], desired[1:])  # "next = current"
    assert np.all(train_err < 0.2 * no_change)
    assert np.all(test_err < 0.5 * no_change)


def test_serial_model_stays_frozen_and_parallel_model_learns_in_fel():
    plant, desired, commands = _setup()
    inv_cfg = ESNConfig(12, 4, n_reservoir=60, noise_level=0.2)
    fel = New(beta=0.3, cycles=2, epochs=2)
    serial = _fm(mode="serial")
    serial.pretrain(desired, commands, delay_steps=2)
    frozen = serial.esn.W_out.copy()
    train(ESN(inv_cfg, n_runs=2, seed=1), plant, desired, fel,
          Loop(forward=serial, delay_steps=2))
    np.testing.assert_array_equal(serial.esn.W_out, frozen)

    parallel = _fm(mode="parallel")
    train(ESN(inv_cfg, n_runs=2, seed=1), plant, desired, fel,
          Loop(forward=parallel, delay_steps=2))
    assert np.all(np.any(parallel.esn.W_out != 0, axis=(1, 2)))


def test_parallel_fit_on_a_rollout_aligns_states_with_the_next_position():
    plant, desired, _ = _setup()
    plant.sensor_noise_std = 0.0
    fm = _fm(mode="parallel")
    inverse = ESN(ESNConfig(12, 4, n_reservoir=30), n_runs=2, seed=2)  # readout 0: feedback only
    ro = rollout(inverse, plant, desired, 1.0, Loop(forward=fm, delay_steps=1), noise=False)
    assert ro.predictions.shape == ro.sensed.shape
    fm.fit_rollout(ro)
    fitted = nrmse(fm.esn.readout(ro.fm_states), ro.sensed[:, 1:])
    no_change = nrmse(ro.sensed[:, :-1], ro.sensed[:, 1:])
    assert np.all(fitted < 0.1 * no_change)
    ro2 = rollout(inverse, plant, desired, 1.0, Loop(forward=fm, delay_steps=1), noise=False)
    assert np.all(rollout_prediction_error(ro2) < 0.3 * no_change)


def test_bad_mode():
    with pytest.raises(ValueError, match="mode"):
        _fm(mode="sideways")
