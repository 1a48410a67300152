"""The tracking task as PPO and SAC see it: the one training path's closed loop with a
policy where the ESN stands.

:class:`TrackingEnv` is a ``gymnasium.Env`` over the plant and the actuation's rollout
hook that :func:`skinny_mj.training.loop.build_run` and :func:`~skinny_mj.training.loop.
evaluate` build from a :class:`TrainConfig` (:func:`skinny_mj.training.parts.make_plant`,
:meth:`skinny_mj.training.actuation.TorqueActuation.hook`), stepped as
:func:`skinny_mj.controllers.rollout.rollout` steps it, so the teacher is whatever the
config names (``actuation.feedback``, its poles, its sensing) and nothing is restated:

- observation at step t: the ESN's input, [d(t+1); s(t)] (desired next and sensed
  position signals) followed by the hook's inputs (torque body: [qd_d(t+1); qd(t)] /
  v_max), float64;
- action: (n_dof,) in [-1, 1], standing where the ESN's output y(t) stands: the command
  is ``clip(action + gain u_teacher(t) + feedforward(t), -1, 1)`` with the hook's motor
  error u_teacher (the feedback teacher FEL learns from) and feed-forward. ``gain`` 0:
  plain RL (the action is the normalized torque); 1: residual RL (the action adds to
  the teacher, as the ESN's output adds to K u_error in FEL's training at K = 1);
- reward: ``-mean |d(t+1) - true(t+1)|`` over the noise-free signals (the env's of
  :mod:`skinny_mj.gym`); an episode is one pass of the movement from its first pose
  (T - 1 steps, then ``truncated``); a step that raises a MuJoCo warning (the simulation
  diverged) ends it (``terminated``, ``info["diverged"]``) with the worst reward
  (:data:`WORST_REWARD`) for every step left, so that diverging never pays.

:func:`score` is the test every learner gets (what :func:`~skinny_mj.training.loop.
evaluate` does for the ESN): a fresh plant whose sensor noise starts from the given
seed, ``test.washout_cycles`` unscored passes, one scored pass of the deterministic
policy; position NRMSE of the noise-free signals and the RMS joint error in degrees.
"""

from __future__ import annotations

from collections.abc import Callable

import gymnasium
import numpy as np
from gymnasium import spaces
from skinny_mj.controllers.metrics import position_nrmse

from skinny_mj.training.actuation import actuation_of
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.imitation import robot_metrics
from skinny_mj.training.parts import make_plant

#: The reward's worst value per step: -mean |desired - true| with signals in [-1, 1].
WORST_REWARD = -2.0


class TrackingEnv(gymnasium.Env[np.ndarray, np.ndarray]):
    """One robot following ``trajectory`` in the closed loop of ``cfg`` (module docstring).

    Parameters
    ----------
    cfg : the run's training configuration (plant, actuation and its teacher, inputs).
    trajectory : the movement of one episode.
    max_speed_rad_s : (n_dof,) the full scale the velocity inputs are divided by.
    plant_seed : the sensor noise's seed; the stream continues over episodes.
    gain : the teacher's gain in the command, 0 (plain) or 1 (residual).
    test : a test plant (the actuation's test changes applied, as
        :func:`~skinny_mj.training.loop.evaluate` applies them), else a training plant.
    """

    def __init__(self, cfg: TrainConfig, trajectory, max_speed_rad_s: np.ndarray,
                 plant_seed: int, gain: float, test: bool = False):
        self.cfg, self.trajectory, self.gain = cfg, trajectory, float(gain)
        self.max_speed_rad_s = np.asarray(max_speed_rad_s, float)
        self.plant = make_plant(cfg, trajectory, [plant_seed], self.max_speed_rad_s)
        actuation = actuation_of(cfg)
        if test:  # the nominal plant unless the config perturbs its test plant
            actuation.test_plant(self.plant)
        self.hook = actuation.hook(trajectory, self.max_speed_rad_s, self.plant)
        self.desired = trajectory.position_signals(cfg.plant.signals)
        self.n_steps = len(self.desired) - 1
        n_sig, n_dof = self.desired.shape[1], cfg.plant.dof
        n_hook = 0 if self.hook is None else self.hook.n_inputs
        n_des = n_sig if cfg.inputs == "desired+sensed" else 0
        self._slices = (slice(0, n_des), slice(n_des, n_des + n_sig),
                        slice(n_des + n_sig, n_des + n_sig + n_hook))
        n_obs = n_des + n_sig + n_hook
        self.observation_space = spaces.Box(-np.inf, np.inf, (n_obs,), dtype=np.float64)
        self.action_space = spaces.Box(-1.0, 1.0, (n_dof,), dtype=np.float64)
        self.n_dof = n_dof
        self.diverged = 0  # episodes that ended in a diverged simulation
        self._t, self._running = 0, False
        self._sensed = np.zeros((1, n_sig))
        self.true = np.zeros((self.n_steps + 1, n_sig))  # the last episode's true signals
        self.angles = np.zeros((self.n_steps + 1, n_dof))  # and joint angles, rad

    # -- the loop ---------------------------------------------------------------------
    def _observation(self) -> np.ndarray:
        t, (des, sen, hk) = self._t, self._slices
        out = np.empty(self.observation_space.shape)
        out[des] = self.desired[min(t + 1, self.n_steps)]
        out[sen] = self._sensed[0]
        if self.hook is not None and hk.stop > hk.start:
            out[hk] = self.hook.inputs(min(t, self.n_steps - 1), self.plant)[0]
        return out

    def reset(self, *, seed: int | None = None, options=None):
        super().reset(seed=seed)  # the noise stream is the plant's (its seed is fixed)
        self._sensed = self.plant.reset()
        self._warnings = self.plant.warning_count()
        if self.hook is not None:
            self.hook.begin(self.plant, self.n_steps + 1)
        self._t, self._running = 0, True
        self.true[0] = self.plant.true_signals()[0]
        self.angles[0] = self.plant.joint_angles()[0, :self.n_dof]
        return self._observation(), {}

    def step(self, action):
        if not self._running:
            raise RuntimeError("TrackingEnv: episode over (or not started); call reset()")
        t, plant = self._t, self.plant
        command = np.asarray(action, float).reshape(1, self.n_dof).copy()
        if self.hook is not None:
            u = self.hook.u_error(t, self.desired[t], self._sensed, plant)
            command += self.gain * u
            command += self.hook.feedforward(t, plant)
        np.clip(command, -1.0, 1.0, out=command)
        self._sensed = plant.step(command)
        if self.hook is not None:
            self.hook.after_step(t, plant)
        self._t = t + 1
        self.true[t + 1] = plant.true_signals()[0]
        self.angles[t + 1] = plant.joint_angles()[0, :self.n_dof]
        if plant.warning_count() > self._warnings:  # MuJoCo reset a diverged simulation
            self.diverged += 1
            self._running = False
            left = self.n_steps - t
            return self._observation(), WORST_REWARD * left, True, False, {"diverged": True}
        reward = -float(np.mean(np.abs(self.desired[t + 1] - self.true[t + 1])))
        last = self._t >= self.n_steps
        self._running = not last
        return self._observation(), reward, False, last, {}


Policy = Callable[[np.ndarray], np.ndarray]


def score(policy: Policy, env: TrackingEnv, washout_cycles: int = 0) -> dict | None:
    """One test of ``policy`` (observation -> action) on ``env`` (a fresh one: its noise
    stream starts from its seed): ``washout_cycles`` unscored passes, then a scored one.
    ``{"position_nrmse", "rms_error_deg"}`` of the scored pass, None if it diverged."""
    for _ in range(washout_cycles + 1):
        obs, _ = env.reset()
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs))
            if info.get("diverged"):
                return None
            done = terminated or truncated
    nrmse = float(position_nrmse(env.true[None], env.desired)[0])
    deg = robot_metrics(env.angles, env.trajectory.angles, env.n_dof,
                        env.trajectory.dt)["rms_error_deg"]
    return {"position_nrmse": nrmse, "rms_error_deg": float(deg)}
