"""``skinny experiment rl-vs-fel``: the two learners are scored alike, FEL's curve is the
one training path's, the RL runs are reproducible, and without the ``rl`` extra the RL
rows are left out (refused by name in one line) while the FEL rows run."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from skinny_mj.experiments.rl_vs_fel import runs  # noqa: E402
from skinny_mj.experiments.rl_vs_fel import study as rl_vs_fel  # noqa: E402

from skinny_mj.engine.experiment import run_sweep  # noqa: E402
from skinny_mj.errors import SkinnyInputError  # noqa: E402
from skinny_mj.training.config import TrainConfig  # noqa: E402
from skinny_mj.training.parts import run_streams  # noqa: E402


def test_without_the_rl_extra_the_rl_rows_are_refused_in_one_line(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "stable_baselines3", None)  # import raises ImportError
    exp = rl_vs_fel.STUDY.build(quick=True)
    assert sorted(exp.unavailable) == sorted(r.row_id for r in exp.rows
                                             if not r.row_id.startswith("fel-"))
    with pytest.raises(SkinnyInputError) as err:
        run_sweep(exp, tmp_path, rows=["ppo-velocity-ymca"], workers=1, progress=False)
    assert str(err.value) == ("experiment 'rl-vs-fel': row 'ppo-velocity-ymca' needs the rl "
                              "extra: pip install -e '.[rl]'")


def test_rows_cover_learner_x_body_x_movement():
    exp = rl_vs_fel.STUDY.build()
    assert {r.row_id for r in exp.rows} == {f"{a}-{b}-{m}" for a in rl_vs_fel.LEARNERS
                                           for b in rl_vs_fel.BODIES
                                           for m in rl_vs_fel.MOVEMENTS}
    g = exp.groups
    assert len(g["sac"]) == 4 and len(g["torque"]) == 6 and len(g["md02"]) == 6
    plan = exp.config
    assert plan.config("fel-torque-md02").movement.trajectory == rl_vs_fel.CLIP
    assert plan.config("fel-torque-md02").actuation.kind == "torque"
    assert plan.config("sac-velocity-ymca").movement.trajectory == "ymca"
    moved = rl_vs_fel.STUDY.build(movement="y").config  # --movement replaces the YMCA only
    assert moved.config("ppo-velocity-ymca").movement.trajectory == "y"
    assert moved.config("ppo-velocity-md02").movement.trajectory == rl_vs_fel.CLIP


@pytest.mark.parametrize("actuation", ["velocity", "torque"])
def test_env_scorer_equals_the_training_paths_test(actuation):
    """An untrained ESN commands 0: its K = 0 test and the env's score of the zero
    policy on the same test seed are the same number, bit for bit."""
    from skinny_mj.training import loop as training

    tc = TrainConfig().override({"actuation": actuation, "method.epochs": 1})
    run = training.build_run(tc, [7])
    env = runs.make_env(tc, 7, velocity_inputs=actuation == "torque")
    zero = np.zeros(tc.plant.dof)
    ours = runs.score_policy(lambda obs: zero, env, run_streams(7).plant_seed)
    assert ours == runs._fel_test(run)
    assert 0.1 < ours < 1.0  # standing still is far from tracking
    n_obs = 3 * 8 + (2 * tc.plant.dof if actuation == "torque" else 0)
    assert env.observation_space.shape == (n_obs,)


def test_fel_curve_ends_at_the_test_of_train():
    from skinny_mj.training.loop import train

    tc = TrainConfig().override({"method.epochs": 2})
    points, facts = runs.fel_curve(tc, 3)
    assert [p["steps"] for p in points] == [0, facts["steps_per_epoch"],
                                           2 * facts["steps_per_epoch"]]
    assert facts["steps_per_epoch"] == (3 + 2) * 312  # 3 learning cycles + washout + test
    assert points[-1]["position_nrmse"] == train(tc, 3).test.position_nrmse
    assert points[-1]["position_nrmse"] < points[0]["position_nrmse"]
    assert 0 < points[1]["wall_s"] < points[2]["wall_s"]
    assert 0 < points[1]["cpu_s"] < points[2]["cpu_s"]


def test_curve_metrics_first_test_at_or_below_each_threshold():
    pts = [runs.point(k * 10, (k * 1.0, k * 0.5), e)
           for k, e in enumerate([0.5, None, 0.04, 0.06, 0.02])]
    m = runs.curve_metrics(pts, (0.05, 0.02, 0.01))
    assert (m["steps_to_0.05"], m["wall_to_0.05"], m["reached_0.05"]) == (20, 2.0, 1)
    assert (m["steps_to_0.02"], m["wall_to_0.02"], m["cpu_to_0.02"]) == (40, 4.0, 2.0)
    assert (m["steps_to_0.01"], m["reached_0.01"]) == (None, 0)
    assert (m["position_nrmse"], m["best_nrmse"], m["env_steps"]) == (0.02, 0.02, 40)


def test_a_diverged_simulation_ends_the_episode_with_the_worst_reward(monkeypatch):
    from dm_control.rl.control import PhysicsError

    env = runs.make_env(TrainConfig().override({"actuation": "torque"}), 0,
                        velocity_inputs=True)
    obs, _ = env.reset(seed=0)
    for _ in range(3):
        obs, *_ = env.step(np.zeros(4))

    def boom(action):
        raise PhysicsError("diverged")

    monkeypatch.setattr(env.env, "step", boom)
    out, reward, terminated, truncated, info = env.step(np.zeros(4))
    assert info == {"diverged": True} and terminated and not truncated
    assert reward == runs.WORST_REWARD * (312 - 3)
    np.testing.assert_array_equal(out, obs)
    assert env.diverged == 1


def test_quick_sweep_writes_curves_table_and_figures(tmp_path):
    pytest.importorskip("stable_baselines3")
    exp = rl_vs_fel.STUDY.build(quick=True)
    res = run_sweep(exp, tmp_path, rows=["ppo-velocity-ymca", "sac-torque-ymca"], workers=1,
                    progress=False)
    assert res["n_ok"] == 2 and res["n_error"] == 0
    for row, budget in (("ppo-velocity-ymca", 256), ("sac-torque-ymca", 100)):
        (path,) = (tmp_path / "runs").glob(f"{row}-*.json")
        m = json.loads(path.read_text())["metrics"]
        steps = [p["steps"] for p in m["curve"]]
        assert steps[0] == 0 and steps == sorted(steps) and steps[-1] >= budget
        assert all(0 < p["position_nrmse"] < 2 for p in m["curve"])
        assert m["position_nrmse"] == m["curve"][-1]["position_nrmse"]
    text = exp.report(res, tmp_path)
    assert (tmp_path / "curves_steps.png").stat().st_size > 0
    assert "| PPO | velocity | ymca | 256 |" in text
    assert (tmp_path / "comparison.md").read_text().strip() in text


def test_rl_runs_are_reproducible():
    pytest.importorskip("stable_baselines3")
    tc = TrainConfig()
    a, _ = runs.rl_curve("ppo", tc, 5, 256, 1, quick=True)
    b, _ = runs.rl_curve("ppo", tc, 5, 256, 1, quick=True)
    assert [p["position_nrmse"] for p in a] == [p["position_nrmse"] for p in b]
    assert a[0]["position_nrmse"] != a[-1]["position_nrmse"]  # the policy did change
