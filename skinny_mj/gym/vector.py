"""N Skinnies as one ``gymnasium.vector.VectorEnv`` over the lockstep
:class:`skinny_mj.plant.adapters.BatchPlant`: N robots in one MuJoCo model, one ``mj_step`` for
all, and the work around the physics vectorized over N.

Sub-environment i is :class:`skinny_mj.gym.env.SkinnyEnv` with noise seed ``seeds[i]``:
the same spaces, the same episode (T - 1 steps, then ``truncated``), the same reward,
and with the velocity servo the same bits (BatchPlant run r equals the dm_control task
with seed r; ``tests/test_gym.py`` checks the whole vector env against Gymnasium's
``SyncVectorEnv`` of single envs). With the torque twin, MuJoCo solves the N robots'
joint-limit constraints as N islands but one robot's as one piece: equal up to rounding
(~1e-16 per step, growing as chaotic dynamics do), not bitwise.

Actions as a single env's: finite values outside [-1, 1] are clipped, a NaN or infinite
one raises ``ValueError`` before the step.

Autoreset: ``AutoresetMode.NEXT_STEP``, Gymnasium 1.x's default. Every sub-environment
follows the same movement and none can fail, so all of them end on the same step; the
next ``step`` ignores its actions, resets all of them (each noise stream continues, as
``SkinnyEnv.reset()`` does) and returns the first observations with reward 0,
``terminated`` and ``truncated`` False. A partial reset (``options["reset_mask"]``
with some False) is refused: the lockstep plant resets all robots at once.

A diverging robot (the torque twin under some full random torques) raises dm_control's
``PhysicsError`` as a single env does: MuJoCo then resets the whole model (every robot)
and only logs it, so going on would silently restart the other N - 1 episodes.

Seeding: ``reset(seed=s)`` gives sub-environment i the seed ``s + i`` (a list gives one
seed each), as ``SyncVectorEnv`` does; the constructor's ``seed`` works the same way
until then. A new seed rebuilds the BatchPlant (its Generators prefetch noise in blocks,
so they cannot be swapped in place): ~0.15 s at N = 64, only on a seeded reset.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np
from dm_control.rl.control import PhysicsError
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from skinny_mj.errors import SkinnyInputError
from skinny_mj.gym.env import (
    action_space,
    check_id,
    check_seed,
    observation_space,
    resolve_trajectory,
)
from skinny_mj.plant.adapters import BatchPlant
from skinny_mj.plant.task import arguments, finite_actions


class SkinnyVectorEnv(VectorEnv):
    """``num_envs`` Skinnies stepping in lockstep (see the module docstring).

    Parameters
    ----------
    num_envs : N.
    *task, **task_kw : the arguments of :func:`skinny_mj.plant.task.load`, as
        :class:`skinny_mj.gym.env.SkinnyEnv` takes them; sub-environment i draws its noise
        from ``default_rng(seed + i)`` until ``reset(seed=...)``.
    env_id : the Gymnasium id (``make_vec`` passes it): a ``body`` contradicting it is
        refused.
    max_episode_steps : episodes end (``truncated``) after this many steps, or at the
        movement's end if sooner (``make_vec`` passes the id's, YMCA's length); None:
        the movement's end.
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(
        self,
        num_envs: int,
        *task: Any,
        env_id: str | None = None,
        max_episode_steps: int | None = None,
        **task_kw: Any,
    ):
        if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) \
                or num_envs < 1:
            raise SkinnyInputError(f"num_envs must be a whole number >= 1, got {num_envs!r}")
        self.num_envs = int(num_envs)
        self.render_mode = None
        self._plant_kwargs = arguments(*task, **task_kw)
        seed = self._plant_kwargs.pop("seed")
        self._plant_kwargs["trajectory"] = resolve_trajectory(self._plant_kwargs["trajectory"],
                                                              self._plant_kwargs["body"])
        seeds = [int(seed) + i for i in range(self.num_envs)]
        self.plant = BatchPlant(n_runs=self.num_envs, seeds=seeds, **self._plant_kwargs)
        self._fresh_seeds: list[int] | None = seeds  # the plant's Generators are unused
        self.setup = self.plant.setup
        check_id(env_id, self.setup.body, len(self.setup.desired) - 1, max_episode_steps)
        if max_episode_steps == -1:  # Gymnasium's "no time limit"
            max_episode_steps = None
        if max_episode_steps is not None and max_episode_steps < 1:
            raise SkinnyInputError(f"max_episode_steps must be >= 1, got {max_episode_steps}")
        self._limit = len(self.setup.desired) - 1 if max_episode_steps is None \
            else min(int(max_episode_steps), len(self.setup.desired) - 1)
        self.single_observation_space = observation_space(self.setup)
        self.single_action_space = action_space(self.setup.dof)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._np_random, self._np_random_seed = seeding.np_random(seed)
        self._desired = self.setup.desired
        self._n_sig = self._desired.shape[1]
        self._t = 0
        self._running = False
        self._autoreset = False

    @property
    def n_steps(self) -> int:
        """Steps per episode: the movement's length T - 1, or ``max_episode_steps`` if
        fewer."""
        return self._limit

    def reset(
        self,
        *,
        seed: int | Sequence[int] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        mask = (options or {}).get("reset_mask")
        if mask is not None and not np.all(mask):
            raise SkinnyInputError("SkinnyVectorEnv resets all sub-environments together "
                             f"(lockstep plant); got reset_mask={mask}")
        if seed is not None:
            for one in (list(seed) if isinstance(seed, Sequence | np.ndarray) else [seed]):
                check_seed(one)  # -1 or 1.5: one line, not Gymnasium's or NumPy's error
            if isinstance(seed, int | np.integer):
                super().reset(seed=int(seed))
                seeds = [int(seed) + i for i in range(self.num_envs)]
            else:
                seeds = list(seed)
                if len(seeds) != self.num_envs or any(s is None for s in seeds):
                    raise SkinnyInputError(f"need {self.num_envs} int seeds, got {seed}")
                seeds = [int(s) for s in seeds]
            if seeds != self._fresh_seeds:
                self.plant = BatchPlant(n_runs=self.num_envs, seeds=seeds, **self._plant_kwargs)
        self._fresh_seeds = None
        return self._reset_all(), {}

    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if not self._running:
            raise RuntimeError("SkinnyVectorEnv: call reset() first")
        n = self.num_envs
        if self._autoreset:  # NEXT_STEP: the actions of this call are ignored
            return (self._reset_all(), np.zeros(n), np.zeros(n, bool), np.zeros(n, bool),
                    {})
        warnings_before = self.plant.data.warning.number.copy()
        sensed = self.plant.step(finite_actions(actions, (n, self.single_action_space.shape[0])))
        self._raise_on_new_warnings(warnings_before)
        self._t += 1
        # the task's reward, -mean |desired(t) - true(t)|, row by row: np.mean is this
        # sum over the contiguous last axis divided by the count, so the same bits
        error = self._desired[self._t] - self.plant.true_signals()
        reward = np.add.reduce(np.abs(error, out=error), axis=1)
        reward /= -self._n_sig
        self._autoreset = self._t >= self.n_steps
        return (self._observation(sensed), reward, np.zeros(n, bool),
                np.full(n, self._autoreset), {})

    def _raise_on_new_warnings(self, before: np.ndarray) -> None:
        # as dm_control's Physics.check_invalid_state, which the single env goes through
        new = self.plant.data.warning.number > before
        if new.any():
            self._running = False
            names = ", ".join(np.compress(new, list(mujoco.mjtWarning.__members__)))
            raise PhysicsError(f"Physics state is invalid. Warning(s) raised: {names} "
                               "(MuJoCo reset every robot of the batch; call reset())")

    def _reset_all(self) -> np.ndarray:
        sensed = self.plant.reset()
        self._t, self._running, self._autoreset = 0, True, False
        return self._observation(sensed)

    def _observation(self, sensed: np.ndarray) -> np.ndarray:
        n, last = self._n_sig, len(self._desired) - 1
        out = np.empty((self.num_envs, 3 * n))
        out[:, :n] = sensed
        out[:, n:2 * n] = self._desired[min(self._t, last)]
        out[:, 2 * n:] = self._desired[min(self._t + 1, last)]
        return out
