"""Feedback-error learning on the toy plant: learns, beta=1 is the original, lockstep."""

import numpy as np
import pytest
from skinny_mj.controllers.esn import ESN, ESNConfig, run_generators
from skinny_mj.controllers.feedback import FeedbackController
from skinny_mj.controllers.fel import (
    Loop,
    New,
    Original,
    Task,
    Test,
    evaluate,
    health,
    rollout,
    train,
)
from skinny_mj.controllers.metrics import nrmse, position_nrmse
from skinny_mj.controllers.plant import ToyPlant, toy_movement

LIMITS = np.tile([0.0, np.pi], (4, 1))


def _setup(n_runs=2, n_steps=80, noise=0.2, seed=0, plant_rngs=None):
    q, speed, commands = toy_movement(n_steps, 4, seed=0)
    plant = ToyPlant(n_runs, q[0], LIMITS, speed, seed=seed, rngs=plant_rngs)
    desired = plant.signals_of(q)
    cfg = ESNConfig(8, 4, n_reservoir=60, noise_level=noise)
    return plant, desired, commands, cfg


def test_rollout_shapes_and_y_est():
    plant, desired, _, cfg = _setup()
    esn = ESN(cfg, n_runs=2, seed=1)
    ro = rollout(esn, plant, desired, 1.0)
    t = len(desired)
    assert ro.commands.shape == (2, t - 1, 4) and ro.u_error.shape == (2, t, 4)
    assert ro.sensed.shape == ro.true_signals.shape == (2, t, 4)
    np.testing.assert_allclose(ro.y_est, ro.commands + ro.u_error[:, 1:])
    # untrained readout is zero: the commands are pure feedback, and with K = 1 and a
    # noise-free sensor the one-step correction puts the plant on d(t) at t + 1
    assert np.all(ro.y_esn == 0)
    plant.sensor_noise_std = 0.0
    ro = rollout(esn, plant, desired, 1.0, Loop(feedback=FeedbackController(damping=0.0)))
    expected = np.broadcast_to(desired[1:-1], (2, t - 2, 4))
    np.testing.assert_allclose(ro.true_signals[:, 2:], expected, atol=1e-12)
    assert position_nrmse(ro.true_signals, desired).max() > 0.005  # but one step late


def test_fel_reduces_test_error_over_epochs():
    plant, desired, commands, cfg = _setup(n_runs=3)
    fel = New(beta=0.1, cycles=3, epochs=6)
    esn = ESN(cfg, n_runs=3, seed=2)
    untrained = evaluate(esn, plant, Task(desired, commands))
    result = train(esn, plant, Task(desired, commands), fel)
    trained = evaluate(esn, plant, Task(desired, commands))
    assert not result.failed.any()
    assert np.all(trained.position_nrmse < 0.5 * untrained.position_nrmse)
    assert np.all(trained.motor_nrmse < 0.5 * untrained.motor_nrmse)
    assert np.all(np.isfinite(result.position_nrmse))


def test_beta_one_equals_original():
    plant, desired, _, cfg = _setup(seed=4)
    results = []
    for fel in (Original(cycles=1, epochs=3), New(beta=1.0, cycles=1, epochs=3)):
        plant, *_ = _setup(seed=4)
        esn = ESN(cfg, n_runs=2, seed=3)
        results.append((train(esn, plant, desired, fel).position_nrmse, esn.W_out.copy()))
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1], results[1][1])


def test_lockstep_training_equals_single_runs():
    n_runs = 3
    plant, desired, _, cfg = _setup(n_runs=n_runs, plant_rngs=run_generators(9, n_runs))
    fel = New(beta=0.3, cycles=2, epochs=2)
    batch = ESN(cfg, n_runs=n_runs, seed=5)
    curve = train(batch, plant, desired, fel).position_nrmse
    for r, (gen, pgen) in enumerate(zip(run_generators(5, n_runs), run_generators(9, n_runs),
                                        strict=True)):
        single_plant, *_ = _setup(n_runs=1, plant_rngs=[pgen])
        single = ESN(cfg, rngs=[gen])
        single_curve = train(single, single_plant, desired, fel).position_nrmse
        np.testing.assert_allclose(single_curve[0], curve[r], rtol=0, atol=1e-12)
        np.testing.assert_allclose(single.W_out[0], batch.W_out[r], rtol=0, atol=1e-12)


def test_diverged_run_is_marked_failed_and_others_continue():
    plant, desired, _, cfg = _setup(n_runs=2)
    esn = ESN(cfg, n_runs=2, seed=6)
    ticks = []
    esn.W_in[1] *= 1e4  # run 1 saturates its reservoir
    result = train(esn, plant, desired, New(beta=0.1, cycles=2, epochs=2),
                   observe=lambda e, c, ro, y_used: ticks.append((e, c)))
    assert result.failed.tolist() == [False, True]
    assert "saturated" in result.fail_reason[1] and result.fail_epoch[1] == 0
    assert np.all(np.isfinite(result.position_nrmse[0]))
    d = result.to_dict()
    assert d["position_nrmse"][1] == [None, None] and d["failed"] == [False, True]
    assert ticks == [(e, c) for e in range(2) for c in range(4)]


def test_delay_line_feeds_the_model_old_positions_only():
    plant, desired, _, cfg = _setup(n_runs=1, noise=0.0)
    esn = ESN(cfg, seed=7)
    ro = rollout(esn, plant, desired, 1.0, Loop(delay_steps=3))
    sensed_part = ro.states[0, :, cfg.n_reservoir + 4 : cfg.n_reservoir + 8]
    np.testing.assert_allclose(sensed_part[5], ro.sensed[0, 2])
    np.testing.assert_allclose(sensed_part[1], ro.sensed[0, 0])


def test_config_validation():
    with pytest.raises(ValueError, match="inputs"):
        Loop(inputs="desired")
    with pytest.raises(ValueError, match="delay"):
        Loop(delay_steps=-1)
    assert Original().beta == 1.0 and Original(cycles=2).learning_cycles == 2
    assert New(beta=0.1).learning_cycles == 3  # paper E's Table 1
    with pytest.raises(ValueError, match="beta"):
        New(beta=0.0)
    with pytest.raises(ValueError, match="gain schedule"):
        New(gain_schedule="magic")
    with pytest.raises(ValueError, match="washout"):
        Test(washout_cycles=-1)


def test_nrmse_definition():
    target = np.zeros((10, 2))
    actual = np.stack([np.full(10, 0.2), np.full(10, -0.4)], axis=1)
    assert nrmse(actual, target) == pytest.approx((0.1 + 0.2) / 2)
    assert nrmse(np.stack([actual, target]), target).tolist() == pytest.approx([0.15, 0.0])


def test_sensed_only_inputs_leave_the_desired_position_out():
    plant, desired, _, cfg = _setup(n_runs=1, noise=0.0)
    n_sig = desired.shape[1]
    small = ESNConfig(n_inputs=n_sig, n_outputs=cfg.n_outputs, n_reservoir=cfg.n_reservoir)
    ro = rollout(ESN(small, seed=3), plant, desired, 1.0, Loop(inputs="sensed"))
    inputs_part = ro.states[0, :, small.n_reservoir:small.n_reservoir + n_sig]
    np.testing.assert_array_equal(inputs_part, ro.sensed[0, :-1])


def test_health_names_non_finite_commands():
    plant, desired, _, cfg = _setup(n_runs=2, noise=0.0)
    with pytest.raises(ValueError, match="2 plant runs"):
        rollout(ESN(cfg, seed=1), plant, desired, 1.0)
    esn = ESN(cfg, n_runs=2, seed=1)
    ro = rollout(esn, plant, desired, 1.0)
    assert health(esn, ro) == [None, None]
    ro.commands[1, 3, 0] = np.nan
    reasons = health(esn, ro)
    assert reasons[0] is None and "non-finite" in reasons[1]


def test_evaluate_washout_cycles_run_before_the_scored_one():
    plant, desired, _, cfg = _setup(n_runs=1, noise=0.0)
    esn = ESN(cfg, seed=2)
    one = evaluate(esn, plant, desired, test=Test(washout_cycles=1))
    esn.reset()
    rollout(esn, plant, desired, 0.0, noise=False)
    second = rollout(esn, plant, desired, 0.0, noise=False)
    np.testing.assert_array_equal(one.rollout.commands, second.commands)
