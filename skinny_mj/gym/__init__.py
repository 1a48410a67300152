"""Skinny as Gymnasium environments: ``import skinny_mj.gym`` registers the ids.

>>> import gymnasium, skinny_mj.gym
>>> env = gymnasium.make("SkinnyMJ/Skinny2D-v0")                       # doctest: +SKIP
>>> envs = gymnasium.make_vec("SkinnyMJ/Skinny2D-v0", num_envs=64)     # doctest: +SKIP

====================================  ===========  ===  ===================================
id                                    body         DOF  action
====================================  ===========  ===  ===================================
``SkinnyMJ/Skinny2D-v0``              2d           4    normalized joint velocity
``SkinnyMJ/Skinny3D-v0``              3d           8    normalized joint velocity
``SkinnyMJ/Skinny2D-Torque-v0``       2d-torque    4    normalized torque (x gear N m)
``SkinnyMJ/Skinny3D-Torque-v0``       3d-torque    8    normalized torque (x gear N m)
====================================  ===========  ===  ===================================

Every other argument of :func:`skinny_mj.plant.task.load` is a ``make`` keyword
(``signals``, ``trajectory``, ``sensor_noise``, ``seed``, ``max_speed_rad_s``,
``speed_factor``); a ``body`` that contradicts the id is refused
(:class:`~skinny_mj.errors.SkinnyInputError`, naming the id that has it). Each id's
``max_episode_steps`` is YMCA's length, :data:`MAX_EPISODE_STEPS` control steps (the
default movement's episode); another movement plays to its own end, and one longer than
that needs ``max_episode_steps=env.n_steps`` (the envs warn).
``make_vec`` builds :class:`SkinnyVectorEnv` (the registered vector entry point: N robots
in one MuJoCo model); ``make_vec(..., vectorization_mode="sync")`` gives Gymnasium's
``SyncVectorEnv`` of N :class:`SkinnyEnv` with the same numbers.

Why a direct ``gymnasium.Env`` and not ``shimmy``'s ``DmControlCompatibilityV0``: shimmy
reseeds dm_control's legacy ``RandomState`` on ``reset(seed=)``, which our task never
uses (it owns a ``numpy.random.Generator`` for the sensor noise), so two resets with the
same seed give different observations and ``check_env`` fails ("Deterministic step
observations are not equivalent", measured with shimmy 2.0.1); it would also expose the
observation dict as a ``Dict`` of unbounded boxes (the integer ``step`` as an int64 box,
joint angles in rad beside normalized signals), and it has no vector counterpart to check
the lockstep :class:`skinny_mj.plant.adapters.BatchPlant` against. A small Env over
:func:`skinny_mj.plant.task.load` keeps the dm_control task as the one definition of physics,
noise, reward and episode end, flattens the observation into one ``Box`` and makes
``reset(seed=s)`` mean ``load(..., seed=s)``.
Gymnasium stays optional: ``import skinny_mj`` never imports it (``pip install -e
".[gym]"``).
"""

from __future__ import annotations

import importlib
from typing import Any

import gymnasium

NAMESPACE = "SkinnyMJ"
#: Each id's ``max_episode_steps``: the synthesized YMCA's 313 samples at 50 Hz, 312
#: control steps (the episode of the default movement; a test checks it).
MAX_EPISODE_STEPS = 312
IDS = {
    f"{NAMESPACE}/Skinny2D-v0": {"body": "2d"},
    f"{NAMESPACE}/Skinny3D-v0": {"body": "3d"},
    f"{NAMESPACE}/Skinny2D-Torque-v0": {"body": "2d-torque"},
    f"{NAMESPACE}/Skinny3D-Torque-v0": {"body": "3d-torque"},
}


def register() -> None:
    """Register :data:`IDS` with Gymnasium (done on import; a second call is a no-op)."""
    for env_id, kwargs in IDS.items():
        if env_id in gymnasium.registry:
            continue
        gymnasium.register(
            id=env_id,
            entry_point="skinny_mj.gym.env:SkinnyEnv",
            vector_entry_point="skinny_mj.gym.vector:SkinnyVectorEnv",
            kwargs={"env_id": env_id, **kwargs},  # the env refuses a body the id contradicts
            max_episode_steps=MAX_EPISODE_STEPS,
        )


register()

_LAZY = {"SkinnyEnv": "skinny_mj.gym.env", "SkinnyVectorEnv": "skinny_mj.gym.vector"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:  # the env modules import mujoco and dm_control: only on use
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'skinny_mj.gym' has no attribute {name!r}")


__all__ = ["IDS", "MAX_EPISODE_STEPS", "NAMESPACE", "SkinnyEnv", "SkinnyVectorEnv", "register"]
