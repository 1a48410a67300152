"""The learning seam (skinny_mj.controllers.learning): the β target, the default rule equal to the
inline fit it replaced, the contract every batch rule keeps, an online rule in FEL."""

from __future__ import annotations

import numpy as np
import pytest
from skinny_mj.controllers import fel
from skinny_mj.controllers.esn import ESN, ESNConfig
from skinny_mj.controllers.learning import Cycle, CycleFit, beta_target
from skinny_mj.controllers.metrics import position_nrmse
from skinny_mj.controllers.online import OnlineRLS
from skinny_mj.controllers.plant import ToyPlant, toy_movement
from skinny_mj.controllers.ridge_select import RidgeSelector
from skinny_mj.controllers.torque_readout import ForgettingReadout, RLSReadout

LIMITS = np.tile([0.0, np.pi], (4, 1))


def _setup(n_runs=2, n_steps=80, noise=0.2, readout="pinv"):
    q, speed, commands = toy_movement(n_steps, 4, seed=0)
    plant = ToyPlant(n_runs, q[0], LIMITS, speed, seed=3)
    cfg = ESNConfig(8, 4, n_reservoir=40, noise_level=noise, readout=readout)
    return plant, plant.signals_of(q), commands, ESN(cfg, n_runs=n_runs, seed=1)


def test_beta_target_is_the_blend_and_beta_one_the_target_itself():
    rng = np.random.default_rng(0)
    target, y_esn = rng.standard_normal((2, 3, 5, 2))
    got = beta_target(target, y_esn, 0.1)
    assert np.array_equal(got, 0.1 * target + 0.9 * y_esn)
    y_esn[0, 0, 0] = np.nan  # a diverged output does not leak into the original method
    assert beta_target(target, y_esn, 1.0) is target


def _old_train(esn, plant, desired, cfg):
    """fel.train's loop as it was written before the seam: the blend inline, esn.fit."""
    beta, curve = cfg.beta, []
    failed = np.zeros(esn.n_runs, bool)

    def mark(ro):
        reasons = fel.health(esn, ro)
        failed[:] |= np.array([r is not None for r in reasons])
        esn.x[failed], esn.W_out[failed] = 0.0, 0.0

    for gain in cfg.gains():
        esn.reset()
        mark(fel.rollout(esn, plant, desired, gain, noise=True))
        for _ in range(cfg.learning_cycles):
            ro = fel.rollout(esn, plant, desired, gain, noise=True)
            mark(ro)
            esn.fit(ro.states, beta * ro.y_est + (1.0 - beta) * ro.y_esn, runs=~failed)
        ro = fel.rollout(esn, plant, desired, gain, noise=False)
        mark(ro)
        curve.append(position_nrmse(ro.true_signals, desired))
    return np.stack(curve, axis=1)


@pytest.mark.parametrize("method,beta", [("new", 0.3), ("original", 1.0)])
def test_default_rule_is_the_old_inline_fit_bit_for_bit(method, beta):
    cfg = fel.New(beta=beta, cycles=2, epochs=3) if method == "new" \
        else fel.Original(cycles=2, epochs=3)
    plant, desired, _, old = _setup()
    old_curve = _old_train(old, plant, desired, cfg)
    plant, desired, _, new = _setup()
    result = fel.train(new, plant, desired, cfg)
    assert np.array_equal(result.position_nrmse, old_curve)
    assert np.array_equal(new.W_out, old.W_out)


def _rules(esn):
    return {"pinv": CycleFit(), "pinv-reuse": CycleFit(reuse_factors=True),
            "ridge-select": RidgeSelector(esn, 1, grid=(1e-4, 1e-1)),
            "forgetting": ForgettingReadout(esn, 0.5, 1e-2),
            "rls": RLSReadout(esn, steps=200, forgetting=0.5)}


@pytest.mark.parametrize("name", list(_rules(_setup()[3])))
def test_a_batch_rule_refits_the_runs_that_learn_and_only_those(name):
    _, _, _, esn = _setup()
    rule = _rules(esn)[name]
    rng = np.random.default_rng(2)
    states = rng.uniform(-1, 1, (2, 200, esn.cfg.n_extended))
    w = rng.normal(0, 0.1, (esn.cfg.n_extended, 4))
    target = np.tanh(states @ w)  # a tanh readout of the states reaches it
    before = esn.W_out[1].copy()
    rule.washout(esn, Cycle(states, target, np.ones(2, bool)))
    rule.fit(esn, Cycle(states, target, np.array([True, False])))
    assert np.array_equal(esn.W_out[1], before)
    fitted = np.tanh(states[0] @ esn.W_out[0].T)  # the tanh readout's output
    assert np.sqrt(np.mean((fitted - target[0]) ** 2)) < 0.1 * np.std(target[0])


def test_an_online_rule_learns_at_every_step_of_the_learning_cycles():
    cfg = fel.Original(cycles=2, epochs=3)
    plant, desired, commands, esn = _setup(noise=0.0)
    untrained = fel.evaluate(esn, plant, fel.Task(desired, commands)).position_nrmse
    rule = OnlineRLS(esn, forgetting=1.0, ridge_lambda=1e-2)
    result = fel.train(esn, plant, desired, cfg, fel.Loop(rule=rule))
    trained = fel.evaluate(esn, plant, fel.Task(desired, commands)).position_nrmse
    assert not result.failed.any()
    assert rule.updates == cfg.epochs * cfg.learning_cycles * (len(desired) - 1)
    assert np.all(trained < 0.5 * untrained)

