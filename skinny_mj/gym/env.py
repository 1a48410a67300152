"""One Skinny as a ``gymnasium.Env``: the dm_control task of :func:`skinny_mj.plant.task.load`
with a flat observation and Gymnasium's seeding.

Observation, (3 n_signals,) float64, normalized units::

    [ sensed(t) | desired(t) | desired_next(t) ]

``sensed`` is the task's noisy position signals (unbounded: Gaussian sensor noise),
``desired`` / ``desired_next`` the movement's signals now and one step ahead (bounded by
the movement's range, at least [-1, 1]). Action, (n_dof,) float64 in [-1, 1]: a
normalized joint velocity (a velocity body) or torque (a torque body); finite
values outside are clipped by the task; a NaN or infinite action raises ``ValueError``
(it never reaches MuJoCo). Reward: the task's, ``-mean |desired(t) - true(t)|``
after the step. An episode is the movement, T - 1 steps; it ends with
``truncated=True`` (the task has a time limit and no failure state, so never
``terminated``), as dm_control marks it (``discount`` 1 on the last step). A diverging
simulation raises dm_control's ``PhysicsError`` (then call ``reset``).

Seeding: the task's noise Generator *is* the Env's ``np_random``; ``reset(seed=s)``
starts it as ``numpy.random.default_rng(s)`` (what ``load(..., seed=s)`` does), and
``reset()`` continues the stream, as the task does between episodes.
"""

from __future__ import annotations

import warnings
from typing import Any

import dm_env
import gymnasium
import numpy as np
from dm_control.rl.control import PhysicsError
from gymnasium import spaces
from gymnasium.utils import seeding

from skinny_mj.errors import SkinnyInputError
from skinny_mj.gym import IDS, MAX_EPISODE_STEPS
from skinny_mj.plant.body import BodyLike, body_name
from skinny_mj.plant.render import check_rendering
from skinny_mj.plant.task import Setup, arguments, finite_actions, load
from skinny_mj.trajectories import resolve_trajectory

RENDER_CAMERA = "front"


def check_id(env_id: str | None, body: BodyLike, n_steps: int,
             max_episode_steps: int | None = None) -> None:
    """Refuse a ``body`` that contradicts the registered ``env_id`` (a
    :class:`SkinnyInputError` naming the id that has it); warn when the movement's
    ``n_steps`` exceed the episode's limit (``max_episode_steps``, default the id's)."""
    if env_id is None:
        return
    if env_id not in IDS:
        raise SkinnyInputError(f"unknown env_id {env_id!r}; known: {', '.join(IDS)}")
    fixed, name = IDS[env_id]["body"], body_name(body)
    if name != fixed:
        other = [i for i, kw in IDS.items() if kw["body"] == name]
        raise SkinnyInputError(f"{env_id} has body={fixed!r}, got body={name!r}"
                               + (f": use {other[0]}" if other else ""))
    limit = MAX_EPISODE_STEPS if max_episode_steps is None else max_episode_steps
    if 0 < limit < n_steps:
        warnings.warn(f"{env_id}: episodes end after max_episode_steps={limit} of the "
                      f"movement's {n_steps} steps; pass max_episode_steps={n_steps} to "
                      "play it whole", stacklevel=3)


def observation_space(setup: Setup) -> spaces.Box:
    """The flat observation's ``Box``: sensed unbounded, the desired parts bounded by the
    movement (at least [-1, 1], so rounding in the signals never leaves the box)."""
    n = setup.desired.shape[1]
    lo = min(-1.0, float(setup.desired.min()))
    hi = max(1.0, float(setup.desired.max()))
    low = np.concatenate([np.full(n, -np.inf), np.full(2 * n, lo)])
    high = np.concatenate([np.full(n, np.inf), np.full(2 * n, hi)])
    return spaces.Box(low, high, dtype=np.float64)


def action_space(n_dof: int) -> spaces.Box:
    """(n_dof,) normalized commands in [-1, 1]."""
    return spaces.Box(-1.0, 1.0, (n_dof,), dtype=np.float64)


class SkinnyEnv(gymnasium.Env[np.ndarray, np.ndarray]):
    """Skinny imitating a movement (see the module docstring for spaces and episodes).

    Parameters
    ----------
    *task, **task_kw : the arguments of :func:`skinny_mj.plant.task.load` (``body``,
        ``signals``, ``trajectory``, ``sensor_noise``, ``seed``, ``max_speed_rad_s``,
        ``speed_factor``), ``trajectory`` also a name or file (:func:`resolve_trajectory`;
        default the synthesized YMCA), ``seed`` the noise Generator's until
        ``reset(seed=...)`` replaces it.
    render_mode : None or "rgb_array" (needs an OpenGL backend, e.g. ``MUJOCO_GL=egl``).
    width, height : rendered image size in pixels (at most 640 x 480).
    env_id : the Gymnasium id this env is made for (``gymnasium.make`` passes it): a
        ``body`` contradicting it is refused (:func:`check_id`).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(
        self,
        *task: Any,
        render_mode: str | None = None,
        width: int = 320,
        height: int = 240,
        env_id: str | None = None,
        **task_kw: Any,
    ):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise SkinnyInputError(f"render_mode must be None or 'rgb_array', got "
                                   f"{render_mode!r}")
        for name, value in (("width", width), ("height", height)):
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise SkinnyInputError(f"{name} must be a whole number of pixels >= 1, got "
                                       f"{value!r}")
        if render_mode is not None:
            check_rendering()  # MUJOCO_GL=disabled: one line saying how to turn it on
        self.render_mode = render_mode
        self.width, self.height = int(width), int(height)
        given = arguments(*task, **task_kw)
        given["trajectory"] = resolve_trajectory(given["trajectory"], given["body"])
        self.dm_control_env = load(**given)
        self.setup: Setup = self.dm_control_env.task.setup
        check_id(env_id, self.setup.body, self.n_steps)
        self.observation_space = observation_space(self.setup)
        self.action_space = action_space(self.setup.dof)
        # default_rng(seed) and Gymnasium's np_random(seed) are the same stream
        self._np_random, self._np_random_seed = seeding.np_random(given["seed"])
        self._running = False

    @property
    def n_steps(self) -> int:
        """Steps per episode: the movement's length T - 1."""
        return self.dm_control_env.task.n_steps

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        check_seed(seed)
        super().reset(seed=seed)
        self.dm_control_env.task.rng = self.np_random  # the noise stream is the Env's Generator
        ts = self.dm_control_env.reset()
        self._running = True
        return _flat(ts.observation), {}

    def step(
        self, action: np.ndarray
    ) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if not self._running:
            raise RuntimeError("SkinnyEnv: episode over (or not started); call reset()")
        action = finite_actions(action, (self.setup.dof,))
        try:
            ts = self.dm_control_env.step(action)
        except PhysicsError:  # diverged (the torque twin can): the episode is over
            self._running = False
            raise
        last = ts.step_type == dm_env.StepType.LAST
        terminated = bool(last and ts.discount == 0.0)  # never, for this task
        self._running = not last
        return _flat(ts.observation), float(ts.reward), terminated, last and not terminated, {}

    def render(self) -> np.ndarray | None:
        """(height, width, 3) uint8 picture from the front camera, or None."""
        if self.render_mode != "rgb_array":
            return None
        physics = self.dm_control_env.physics
        return physics.render(self.height, self.width, camera_id=RENDER_CAMERA)


def _flat(observation: dict[str, np.ndarray]) -> np.ndarray:
    return np.concatenate(
        [observation["sensed"], observation["desired"], observation["desired_next"]]
    )


def check_seed(seed: Any) -> None:
    """Refuse a ``reset(seed=...)`` the CLI's ``--seed`` would refuse, as a
    :class:`SkinnyInputError` (Gymnasium's own check raises its ``error.Error``, not a
    ``ValueError``, from deep in its seeding)."""
    if seed is None:
        return
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise SkinnyInputError(f"seed must be None or a whole number >= 0, got {seed!r}")
