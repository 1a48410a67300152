"""The runs of :mod:`skinny_mj.experiments.rl_vs_fel.study`: one learner, one seed, one curve of the
test position NRMSE against the env steps it has used.

A curve is a list of points ``{"steps", "wall_s", "cpu_s", "position_nrmse"}``: env
steps taken so far, training wall time and CPU time of the run's process so far (the
tests themselves excluded; on a shared machine the CPU time is the fairer clock) and
the K = 0 test error then (None when the test diverged). Both kinds of learner are tested alike: a
fresh plant whose sensor noise starts from the run's plant seed
(:func:`skinny_mj.training.parts.run_streams`), one pass of the movement from its first
pose, the controller alone, no learning and no exploration, scored by
:func:`skinny_mj.controllers.metrics.position_nrmse` on the noise-free signals (what
:func:`skinny_mj.training.loop.evaluate` scores).

- ESN + FEL (:func:`fel_curve`): the one training path (:func:`skinny_mj.training.loop.
  train_run`) with a test after every epoch through FEL's ``observe`` hook (the test
  only resets the reservoir state, which the next epoch resets anyway, and draws no
  reservoir noise, so the training is the one :func:`skinny_mj.training.loop.train` runs).
  Env steps per epoch: every cycle the plant ran, (learning cycles + 2) x (T - 1).
- PPO and SAC (:func:`rl_curve`): stable-baselines3 on :class:`skinny_mj.gym.env.
  SkinnyEnv` (imported lazily: the ``rl`` extra), tested every ``budget / evals`` env
  steps with the deterministic policy (the mean action).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
from skinny_mj.controllers.metrics import position_nrmse

from skinny_mj.errors import SkinnyInputError
from skinny_mj.training.config import TrainConfig

RL_EXTRA = "rl-vs-fel needs the rl extra: pip install -e '.[rl]'"
#: The reward's worst value per step: -mean |desired - true| with signals in [-1, 1].
WORST_REWARD = -2.0


def require_rl() -> None:
    """Raise a one-line :class:`SkinnyInputError` when stable-baselines3 is missing."""
    try:
        import stable_baselines3  # noqa: F401
        import torch  # noqa: F401
    except ImportError:
        raise SkinnyInputError(RL_EXTRA) from None


class Clock:
    """Training wall time and this process's CPU time, the tests left out (:meth:`paused`)."""

    def __init__(self) -> None:
        self.start = (time.perf_counter(), time.process_time())
        self.excluded = [0.0, 0.0]

    def elapsed(self) -> tuple[float, float]:
        """(wall s, CPU s) of training so far."""
        return (time.perf_counter() - self.start[0] - self.excluded[0],
                time.process_time() - self.start[1] - self.excluded[1])

    def paused(self, fn: Callable[[], Any]) -> Any:
        t0 = (time.perf_counter(), time.process_time())
        try:
            return fn()
        finally:
            self.excluded[0] += time.perf_counter() - t0[0]
            self.excluded[1] += time.process_time() - t0[1]


def point(steps: int, elapsed: tuple[float, float], nrmse: float | None) -> dict:
    """A test point: env steps, training (wall, CPU) seconds so far, the test error."""
    return {"steps": int(steps), "wall_s": float(elapsed[0]), "cpu_s": float(elapsed[1]),
            "position_nrmse": None if nrmse is None or not np.isfinite(nrmse) else float(nrmse)}


# -- ESN + FEL ----------------------------------------------------------------------------
def _fel_test(run) -> float | None:
    from skinny_mj.training import loop as training

    test = training.evaluate(run)[0]
    if test.failed or (test.torque is not None and test.torque["metrics"]["warnings"]):
        return None
    return test.position_nrmse


def fel_curve(tc: TrainConfig, seed: int) -> tuple[list[dict], dict]:
    """ESN + FEL's curve (a test before training and after every epoch) and facts of the
    run: ``failed`` (diverged in training), ``steps_per_epoch``."""
    from skinny_mj.training import loop as training

    run = training.build_run(tc, [seed])
    steps_per_epoch = (tc.learning_cycles + 2) * (len(run.desired) - 1)
    last_cycle = tc.learning_cycles + 1
    clock = Clock()
    points = [point(0, (0.0, 0.0), clock.paused(lambda: _fel_test(run)))]

    def observe(epoch: int, cycle: int, ro, y_used) -> None:
        if cycle == last_cycle:
            err = clock.paused(lambda: _fel_test(run))
            points.append(point((epoch + 1) * steps_per_epoch, clock.elapsed(), err))

    trained = training.train_run(run, observe=observe)
    failed = bool(trained.fel is not None and trained.fel.failed[0])
    return points, {"failed": failed, "steps_per_epoch": steps_per_epoch}


# -- PPO / SAC ----------------------------------------------------------------------------
def make_env(tc: TrainConfig, seed: int, velocity_inputs: bool):
    """The tracking env of ``tc`` (its movement, full scale, sensor noise, body) as the
    learner sees it (:func:`tracking_wrapper`)."""
    from skinny_mj.gym.env import SkinnyEnv
    from skinny_mj.training.parts import full_scale_speeds, load_trajectory

    trajectory, _ = load_trajectory(tc)
    env = SkinnyEnv(body=tc.plant.body, signals=tc.plant.signals, trajectory=trajectory,
                    sensor_noise=tc.plant.sensor_noise, seed=seed,
                    max_speed_rad_s=full_scale_speeds(tc, trajectory))
    return tracking_wrapper(env, velocity_inputs)


def tracking_wrapper(env, velocity_inputs: bool):
    """``env`` with, for ``velocity_inputs``, the torque ESN's extra inputs appended to
    the observation, [qd_d(t+1) / v_max; qd(t) / v_max] (desired and noise-free actual
    joint velocities, :mod:`skinny_mj.controllers.torque_fel`), and a diverged simulation turned
    into the episode's end with the worst reward for every step left
    (``info["diverged"]``), so that diverging never pays."""
    import gymnasium
    from dm_control.rl.control import PhysicsError
    from gymnasium import spaces

    from skinny_mj.training.torque import desired_velocities_rad_s

    class Tracking(gymnasium.Wrapper):
        def __init__(self, inner):
            super().__init__(inner)
            self.core = inner.unwrapped
            setup = self.core.setup
            self.v_max = np.asarray(setup.max_speed_rad_s, float)
            self.qd_desired = None
            if velocity_inputs:
                self.qd_desired = desired_velocities_rad_s(setup.angles, setup.dt) / self.v_max
                box = inner.observation_space
                extra = np.full(2 * setup.dof, np.inf)
                self.observation_space = spaces.Box(np.concatenate([box.low, -extra]),
                                                    np.concatenate([box.high, extra]),
                                                    dtype=np.float64)
            self.diverged = 0
            self._last = None

        def _obs(self, obs: np.ndarray) -> np.ndarray:
            if self.qd_desired is not None:
                t = self.core.dm_control_env.task.step_index
                qd = self.core.dm_control_env.physics.joint_velocities() / self.v_max
                obs = np.concatenate([obs, self.qd_desired[min(t + 1, len(self.qd_desired) - 1)],
                                      qd])
            self._last = obs
            return obs

        def reset(self, **kwargs):
            obs, info = self.env.reset(**kwargs)
            return self._obs(obs), info

        def step(self, action):
            left = self.core.n_steps - self.core.dm_control_env.task.step_index
            try:
                obs, reward, terminated, truncated, info = self.env.step(action)
            except PhysicsError:
                self.diverged += 1
                return self._last, WORST_REWARD * left, True, False, {"diverged": True}
            return self._obs(obs), reward, terminated, truncated, info

    return Tracking(env)


def score_policy(predict: Callable[[np.ndarray], np.ndarray], env, seed: int) -> float | None:
    """One pass of the movement with ``predict(obs) -> action`` on ``env`` reset with
    ``seed``: the position NRMSE of the noise-free signals, None if it diverged."""
    obs, _ = env.reset(seed=int(seed))
    physics, setup = env.core.dm_control_env.physics, env.core.setup
    true = [physics.position_signals(setup.signals).copy()]
    done = False
    while not done:
        obs, _, terminated, truncated, info = env.step(predict(obs))
        if info.get("diverged"):
            return None
        true.append(physics.position_signals(setup.signals).copy())
        done = terminated or truncated
    return float(position_nrmse(np.asarray(true)[None], setup.desired)[0])


def _algorithm(name: str, env, seed: int, quick: bool):
    """SB3's PPO or SAC with its default hyper-parameters (``quick``: smaller batches
    and an earlier start, so a few hundred steps already update the policy)."""
    from stable_baselines3 import PPO, SAC

    if name == "ppo":
        kw = {"n_steps": 128, "batch_size": 64} if quick else {}
        return PPO("MlpPolicy", env, seed=seed, device="cpu", verbose=0, **kw)
    if name == "sac":
        kw = {"learning_starts": 50, "batch_size": 64} if quick else {}
        return SAC("MlpPolicy", env, seed=seed, device="cpu", verbose=0, **kw)
    raise ValueError(f"unknown learner {name!r}")


def rl_curve(name: str, tc: TrainConfig, seed: int, budget: int, evals: int,
             quick: bool = False) -> tuple[list[dict], dict]:
    """PPO or SAC trained for ``budget`` env steps on the movement of ``tc``, tested
    before training and every ``budget // evals`` steps. The training env is reset with
    the run's seed (SB3 seeds it, torch and NumPy from ``seed``); the test env's sensor
    noise starts from the run's plant seed, as ESN + FEL's test plant's."""
    import torch
    from stable_baselines3.common.callbacks import BaseCallback

    from skinny_mj.training.parts import run_streams

    torch.set_num_threads(1)
    velocity_inputs = tc.torque is not None
    train_env = make_env(tc, seed, velocity_inputs)
    test_env = make_env(tc, seed, velocity_inputs)
    test_seed = run_streams(seed).plant_seed
    every = max(1, budget // evals)

    class Curve(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.points: list[dict] = []
            self.next = 0
            self.clock: Clock | None = None

        def test(self) -> None:
            predict = lambda obs: self.model.predict(obs, deterministic=True)[0]  # noqa: E731
            err = self.clock.paused(lambda: score_policy(predict, test_env, test_seed))
            self.points.append(point(self.num_timesteps, self.clock.elapsed(), err))
            self.next += every

        def _on_training_start(self) -> None:
            self.clock = Clock()
            self.test()

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next:
                self.test()
            return True

    model = _algorithm(name, train_env, seed, quick)
    curve = Curve()
    model.learn(budget, callback=curve)
    if curve.points[-1]["steps"] == model.num_timesteps:  # tested before the last update
        curve.points.pop()
    curve.test()
    return curve.points, {"failed": False, "diverged_episodes": train_env.diverged}


# -- metrics of a curve ---------------------------------------------------------------------
def curve_metrics(points: list[dict], thresholds: tuple[float, ...]) -> dict:
    """Final and best test error, and per threshold the env steps, training wall time
    and CPU time of the first test at or below it (None if none; ``reached_<th>`` 1 or 0)."""
    errs = [p["position_nrmse"] for p in points]
    finite = [e for e in errs if e is not None]
    out: dict[str, Any] = {"position_nrmse": errs[-1],
                           "best_nrmse": min(finite) if finite else None,
                           "env_steps": points[-1]["steps"],
                           "train_wall_s": points[-1]["wall_s"],
                           "train_cpu_s": points[-1]["cpu_s"]}
    for th in thresholds:
        first = next((p for p in points if p["position_nrmse"] is not None
                      and p["position_nrmse"] <= th), None)
        out[f"reached_{th:g}"] = int(first is not None)
        out[f"steps_to_{th:g}"] = None if first is None else first["steps"]
        out[f"wall_to_{th:g}"] = None if first is None else first["wall_s"]
        out[f"cpu_to_{th:g}"] = None if first is None else first["cpu_s"]
    return out
