"""PPO and SAC of stable-baselines3 as the study runs them (the ``rl`` extra, imported
only here and only when a run needs it): the declared hyper-parameters, the
observation (and, for PPO, reward) normalization, and checkpoints that let a long
curve be trained in segments.

Hyper-parameters (:data:`HYPERPARAMS`) are rl-baselines3-zoo's, read once from its
``hyperparams/ppo.yml`` and ``sac.yml`` (rl-zoo3 2.9.2) and declared here, so rl-zoo3 is
not needed to run them:

- PPO: the tuned ``Reacher-v2`` entry (the MuJoCo arm that reaches a target with joint
  torques, 2 joints and 10 to 11 observations: the zoo's MuJoCo task closest to this
  one, 4 joint torques tracking a moving target from 16 to 24 observations), with
  ``normalize: true`` (VecNormalize of observations and reward);
- SAC: the zoo's MuJoCo setting (``HalfCheetah-v4``'s, which every MuJoCo env shares:
  stable-baselines3's defaults with ``learning_starts: 10000``); the zoo normalizes
  nothing for SAC, the study normalizes its observations as PPO's (VecNormalize,
  observations only) so both learners see the same inputs.

A checkpoint (under ``results/`` only, never committed) is the model's own zip
(``model.save``: network weights and optimizer states), the VecNormalize statistics and,
for SAC, the replay buffer as ``.npz`` arrays, and a JSON of where the curve stands.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj.io import atomic_write_text

#: learner -> (source, stable-baselines3 keyword arguments, VecNormalize arguments)
HYPERPARAMS: dict[str, tuple[str, dict[str, Any], dict[str, bool]]] = {
    "ppo": ("rl-zoo3 2.9.2 hyperparams/ppo.yml, Reacher-v2 (tuned), normalize: true",
            {"n_steps": 512, "batch_size": 32, "gamma": 0.9, "learning_rate": 0.000104019,
             "ent_coef": 7.52585e-08, "clip_range": 0.3, "n_epochs": 5, "gae_lambda": 1.0,
             "max_grad_norm": 0.9, "vf_coef": 0.950368},
            {"norm_obs": True, "norm_reward": True}),
    "sac": ("rl-zoo3 2.9.2 hyperparams/sac.yml, the MuJoCo envs' setting (HalfCheetah-v4) "
            "(learning_starts: 10000, stable-baselines3's defaults otherwise); observations "
            "normalized by the study",
            {"learning_starts": 10_000},
            {"norm_obs": True, "norm_reward": False}),
}
#: ``--quick`` (a smoke test): small batches and an early start, so that a few hundred
#: env steps already update the policy
QUICK = {"ppo": {"n_steps": 64, "batch_size": 32}, "sac": {"learning_starts": 50,
                                                           "batch_size": 64}}


def settings(learner: str, changes: dict | None = None,
             quick: bool = False) -> tuple[dict[str, Any], dict[str, bool]]:
    """The keyword arguments of ``learner`` ("ppo" or "sac") and its VecNormalize's, with
    a search row's ``changes`` (``policy_kwargs`` keys go into ``policy_kwargs``)."""
    _, kwargs, norm = HYPERPARAMS[learner]
    kwargs = {**kwargs, **(QUICK[learner] if quick else {})}
    policy = {}
    for key, value in (changes or {}).items():
        if key in ("log_std_init", "net_arch"):
            policy[key] = value
        else:
            kwargs[key] = value
    if policy:
        kwargs["policy_kwargs"] = policy
    return kwargs, dict(norm)


def vec_env(env, learner: str, norm: dict[str, bool], gamma: float):
    """``env`` in a one-env DummyVecEnv and VecNormalize (``norm``'s switches)."""
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    return VecNormalize(DummyVecEnv([lambda: env]), gamma=gamma, **norm)


def make_model(learner: str, venv, seed: int, kwargs: dict[str, Any]):
    """A new PPO or SAC (CPU, MlpPolicy) on ``venv`` seeded with ``seed``."""
    from stable_baselines3 import PPO, SAC

    cls = {"ppo": PPO, "sac": SAC}[learner]
    return cls("MlpPolicy", venv, seed=seed, device="cpu", verbose=0, **kwargs)


# -- checkpoints ------------------------------------------------------------------------
_NORM_STATS = ("mean", "var", "count")
_BUFFER = ("observations", "next_observations", "actions", "rewards", "dones", "timeouts")


def save(folder: Path, learner: str, model, venv, state: dict[str, Any]) -> None:
    """Write the checkpoint of a segment's end into ``folder`` (``state``: the curve so
    far, JSON)."""
    folder.mkdir(parents=True, exist_ok=True)
    model.save(folder / "model.zip")
    stats = {f"obs_{k}": np.asarray(getattr(venv.obs_rms, k)) for k in _NORM_STATS}
    stats.update({f"ret_{k}": np.asarray(getattr(venv.ret_rms, k)) for k in _NORM_STATS})
    np.savez(folder / "normalize.npz", **stats)
    if learner == "sac":
        buf = model.replay_buffer  # the filled part only (the budget, not the 10^6 slots)
        n = buf.buffer_size if buf.full else buf.pos
        np.savez(folder / "replay.npz", pos=buf.pos, full=buf.full,
                 **{k: getattr(buf, k)[:n] for k in _BUFFER})
    atomic_write_text(folder / "state.json", json.dumps(state))


def load(folder: Path, learner: str, venv, seed: int) -> tuple[Any, dict[str, Any]]:
    """The model and curve state of the checkpoint in ``folder`` on ``venv`` (its
    VecNormalize statistics restored), reseeded with ``seed``."""
    from stable_baselines3 import PPO, SAC

    state = json.loads((folder / "state.json").read_text())
    with np.load(folder / "normalize.npz") as stats:
        for k in _NORM_STATS:
            setattr(venv.obs_rms, k, stats[f"obs_{k}"].copy())
            setattr(venv.ret_rms, k, stats[f"ret_{k}"].copy())
    cls = {"ppo": PPO, "sac": SAC}[learner]
    model = cls.load(folder / "model.zip", env=venv, device="cpu")
    model.set_random_seed(seed)
    if learner == "sac":
        buf = model.replay_buffer
        with np.load(folder / "replay.npz") as saved:
            for k in _BUFFER:
                getattr(buf, k)[:len(saved[k])] = saved[k]
            buf.pos, buf.full = int(saved["pos"]), bool(saved["full"])
    return model, state
