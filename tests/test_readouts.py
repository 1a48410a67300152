"""The readouts and loops beyond the thesis's: the RLS readout (controllers.readout), ridge
selection on a validation cycle (controllers.ridge_select), the rollout's online hook
(controllers.rollout), the perturbed plant, the β method without a plant
(controllers.generation)."""

from __future__ import annotations

import numpy as np
import pytest
from skinny_mj.controllers import fel, generation
from skinny_mj.controllers.esn import ESN, ESNConfig
from skinny_mj.controllers.learning import Cycle
from skinny_mj.controllers.online import OnlineRLS
from skinny_mj.controllers.plant import ToyPlant
from skinny_mj.controllers.readout import RLS, ridge_solve, rls_solve
from skinny_mj.controllers.ridge_select import RidgeSelector, ridge_path, validation_errors

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.perturb import PerturbedPlant
from skinny_mj.training.config import TrainConfig

EPS = np.finfo(float).eps


def _states(rng, t=400, d=30):
    m = np.tanh(rng.standard_normal((t, d)) @ rng.standard_normal((d, d)) * 0.5)
    m[:, -1] = 1.0
    return m, rng.standard_normal((t, 2))


@pytest.mark.parametrize("lam", [1e-4, 1e-2, 1.0])
def test_rls_converges_to_ridge(lam):
    # RLS (forgetting 1, P0 = I / lam) and ridge minimise the same quadratic. Rounding:
    # P starts at 1/lam and shrinks to ~1/||G||, so each update cancels about
    # log10(||G|| / lam) digits, amplified by the conditioning of G + lam I:
    # relative error <= eps ||G|| / lam * cond(G + lam I) (measured ~100x below it).
    m, s = _states(np.random.default_rng(0))
    gram = m.T @ m + lam * np.eye(m.shape[1])
    tol = EPS * np.linalg.norm(m.T @ m, 2) / lam * np.linalg.cond(gram)
    w_rls, w_ridge = rls_solve(m, s, lam), ridge_solve(m, s, lam)
    assert np.abs(w_rls - w_ridge).max() / np.abs(w_ridge).max() < tol
    assert tol < 1e-4  # the bound is meaningful


def test_rls_lockstep_equals_each_run_alone_and_continues_ridge():
    rng = np.random.default_rng(1)
    data = [_states(rng, 200, 12) for _ in range(3)]
    w = np.zeros((3, 2, 12))
    batch = RLS.from_states(w, np.stack([m[:100] for m, _ in data]), 0.5)
    for t in range(100, 200):
        batch.update(np.stack([m[t] for m, _ in data]), np.stack([s[t] for _, s in data]))
    for r, (m, s) in enumerate(data):
        one_w = np.zeros((1, 2, 12))
        one = RLS.from_states(one_w, m[None, :100], 0.5)
        for t in range(100, 200):
            one.update(m[t][None], s[t][None])
        assert np.array_equal(one_w[0], w[r])  # lockstep = alone, bit for bit
        # from W = 0 and P0 = (M1^T M1 + lam I)^-1 the prior pulls W toward 0 with the
        # first block's Gram: the result is ridge on block 2 with that Gram added
        g1 = m[:100].T @ m[:100] + 0.5 * np.eye(12)
        g2 = m[100:].T @ m[100:]
        expect = np.linalg.solve(g1 + g2, m[100:].T @ s[100:])
        assert np.allclose(w[r].T, expect, rtol=1e-8, atol=1e-10)


def test_rls_rejects_bad_input():
    with pytest.raises(ValueError):
        RLS(np.zeros((1, 2, 3)), forgetting=1.5)
    with pytest.raises(ValueError):
        RLS(np.zeros((1, 2, 3)), ridge_lambda=0.0)


def test_ridge_path_and_validation_errors_are_exact():
    rng = np.random.default_rng(2)
    m, s = _states(rng, 300, 20)
    mv, sv = _states(rng, 300, 20)
    grid = np.array([1e-6, 1e-2, 1.0, 100.0])
    w = ridge_path(m, s, grid)
    for k, lam in enumerate(grid):
        assert np.allclose(w[k], ridge_solve(m, s, lam), rtol=1e-7, atol=1e-9)
    direct = [np.sum((mv @ wk - sv) ** 2) for wk in w]
    got = validation_errors(w, mv.T @ mv, mv.T @ sv, float(np.sum(sv**2)))
    assert np.allclose(got, direct, rtol=1e-9)


def test_ridge_selector_picks_a_large_lambda_for_pure_noise_targets():
    # targets independent of the states: the best predictor of another cycle is ~0,
    # i.e. the largest lambda; with targets a fixed readout of the states, a small one
    cfg = ESNConfig(n_inputs=1, n_outputs=1, n_reservoir=10, readout_activation="identity")
    esn = ESN(cfg, n_runs=2, seed=0)
    rng = np.random.default_rng(3)
    fit_states, val_states = (rng.standard_normal((2, 200, cfg.n_extended)) for _ in "ab")
    w_true = rng.standard_normal((cfg.n_extended, 1))

    def targets(states):  # run 0: noise alone; run 1: a readout of the states + noise
        noise = 0.1 * rng.standard_normal((2, 200, 1))
        return np.stack([noise[0], states[1] @ w_true + 0.01 * noise[1]])

    sel = RidgeSelector(esn, n_epochs=1, grid=(1e-6, 1e-2, 1e2, 1e4))
    sel.washout(esn, Cycle(val_states, targets(val_states), np.ones(2, bool)))
    sel.fit(esn, Cycle(fit_states, targets(fit_states), np.ones(2, bool)))
    assert sel.chosen[0, 0] == 1e4 and sel.chosen[1, 0] <= 1e-2


def test_ridge_select_config_is_validated():
    assert TrainConfig().method.fit.kind == "cycle"
    TrainConfig().override({"esn.readout": "ridge", "method.fit": "ridge-select",
                            "method": "original"})
    with pytest.raises(SkinnyInputError):
        TrainConfig().override({"method.fit": "ridge-select"})  # pinv readout
    with pytest.raises(SkinnyInputError):  # the torque body
        TrainConfig().override({"esn.readout": "ridge", "actuation": "torque",
                                "method.fit": "ridge-select"})


def _toy(n_runs=2):
    return ToyPlant(n_runs, np.zeros(2), np.array([[-1.5, 1.5]] * 2), np.ones(2),
                    rngs=[np.random.default_rng(10 + r) for r in range(n_runs)])


def _esn(n_runs=2):
    cfg = ESNConfig(n_inputs=4, n_outputs=2, n_reservoir=20, noise_level=0.0)
    return ESN(cfg, n_runs=n_runs, seed=5)


class _Recorder:
    def __init__(self):
        self.calls = []

    def update(self, state, y_esn, y_est):
        self.calls.append((state.copy(), y_est.copy()))


def test_online_hook_sees_each_steps_target_one_step_late_and_changes_nothing_else():
    desired = 0.3 * np.sin(np.linspace(0, 6, 60))[:, None] * np.ones(2)
    esn = _esn()
    esn.W_out[:] = 0.01
    plain = fel.rollout(esn, _toy(), desired, 0.5, noise=False)
    plain = {k: np.array(getattr(plain, k)) for k in ("commands", "states", "u_error")}
    esn.reset()
    rec = _Recorder()
    hooked = fel.rollout(esn, _toy(), desired, 0.5, fel.Loop(online=rec), noise=False)
    assert np.array_equal(hooked.commands, plain["commands"])  # a no-op learner: same run
    assert len(rec.calls) == len(desired) - 1
    for t, (state, y_est) in enumerate(rec.calls):
        assert np.array_equal(state, hooked.states[:, t])
        assert np.array_equal(y_est, hooked.y_est[:, t])


def test_online_rls_learns_in_the_loop_in_lockstep():
    desired = 0.3 * np.sin(np.linspace(0, 6, 80))[:, None] * np.ones(2)
    errors = []
    both, toy = _esn(2), _toy(2)
    rls = OnlineRLS(both, forgetting=1.0, ridge_lambda=1e-2)
    for _ in range(3):
        ro = fel.rollout(both, toy, desired, 0.3, fel.Loop(online=rls), noise=False)
        errors.append(np.abs(ro.u_error).mean())
    assert errors[-1] < errors[0]  # online learning reduces the feedback's work
    assert rls.updates == 3 * (len(desired) - 1)
    alone = _esn(2).select([1])
    one = OnlineRLS(alone, forgetting=1.0, ridge_lambda=1e-2)
    plant = ToyPlant(1, np.zeros(2), np.array([[-1.5, 1.5]] * 2), np.ones(2),
                     rngs=[np.random.default_rng(11)])
    for _ in range(3):
        fel.rollout(alone, plant, desired, 0.3, fel.Loop(online=one), noise=False)
    assert np.array_equal(alone.W_out[0], both.W_out[1])


class _Sink:
    n_dof, n_runs = 2, 1

    def __init__(self):
        self.sent = []

    def step(self, command):
        self.sent.append(np.array(command))
        return np.zeros((1, 2))


def test_perturbed_plant_scales_offsets_and_undoes():
    sink = _Sink()
    plant = PerturbedPlant(sink)
    cmd = np.array([[0.5, -0.9]])
    plant.step(cmd)
    assert sink.sent[-1] is cmd or np.array_equal(sink.sent[-1], cmd)  # passthrough
    plant.set(gain=0.7, offset=[0.0, 0.2])
    plant.step(cmd)
    assert np.allclose(sink.sent[-1], [[0.35, -0.43]])
    plant.step(np.array([[2.0, 1.0]]))  # clipped before the gain, and after the offset
    assert np.allclose(sink.sent[-1], [[0.7, 0.9]])
    plant.undo()
    plant.step(cmd)
    assert np.array_equal(sink.sent[-1], cmd) and plant.n_dof == 2
    with pytest.raises(ValueError):
        plant.set(offset=[2.0, 0.0])


def test_beta_method_without_noise_only_shrinks_the_ordinary_readout():
    # teacher fed back, no reservoir noise: the states repeat each cycle, so the
    # readout after n cycles is (1 - (1 - beta)^n) x the ordinary one (pinv)
    cfg = ESNConfig(n_inputs=1, n_outputs=2, n_reservoir=30, spectral_radius=0.8,
                    output_feedback=True, readout_activation="identity")
    teacher = generation.figure_eight(400, 50)[None]
    inputs = np.zeros((1, 400, 1))
    ordinary, beta = ESN(cfg, seed=1), ESN(cfg, seed=1)
    generation.fit_ordinary(ordinary, inputs, teacher, 100, noise=False)
    generation.fit_beta(beta, inputs, teacher, 100, 0.2, 5, noise=False)
    assert np.allclose(beta.W_out, (1 - 0.8**5) * ordinary.W_out, rtol=1e-6, atol=1e-9)


def test_horizon_counts_steps_before_the_threshold():
    target = np.ones((2, 10, 1)) * np.linspace(-1, 1, 10)[None, :, None]
    free = target.copy()
    free[0, 4:] += 5.0
    free[1, 7] = np.nan
    assert generation.horizon(free, target, 0.1).tolist() == [4, 7]
    assert generation.horizon(target, target, 0.1).tolist() == [10, 10]


def test_beta_method_to_convergence_stops_per_run_when_the_error_stops_falling():
    cfg = ESNConfig(n_inputs=1, n_outputs=2, n_reservoir=30, spectral_radius=0.8,
                    output_feedback=True, readout_activation="identity", noise_level=1e-3)
    teacher = np.repeat(generation.figure_eight(400, 50)[None], 2, axis=0)
    inputs = np.zeros((2, 400, 1))
    both = ESN(cfg, n_runs=2, rngs=[np.random.default_rng(s) for s in (1, 2)])
    curve = generation.fit_beta(both, inputs, teacher, 100, 0.2, 300, min_improvement=0.01)
    used = np.isfinite(curve).sum(axis=1)
    assert np.all(used < 300)  # stopped before the cap
    for r in range(2):  # each run's curve falls by >= 1 % per pass until it stops
        c = curve[r, :used[r]]
        assert np.all(c[1:] < 0.99 * c[:-1]) and np.all(np.isnan(curve[r, used[r]:]))
    alone = ESN(cfg, n_runs=1, rngs=[np.random.default_rng(2)])
    one = generation.fit_beta(alone, inputs[1:], teacher[1:], 100, 0.2, 300,
                              min_improvement=0.01)
    assert np.array_equal(one[0], curve[1], equal_nan=True)
    assert np.array_equal(alone.W_out[0], both.W_out[1])  # lockstep = alone, bit for bit
    with pytest.raises(ValueError):
        generation.fit_beta(alone, inputs[1:], teacher[1:], 100, 0.2, 5, min_improvement=1.5)
