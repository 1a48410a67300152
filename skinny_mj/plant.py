"""Plant adapters: what the (pure NumPy) controllers talk to.

:class:`Plant` is R independent copies of Skinny stepping in lockstep. :class:`EnvPlant`
wraps a dm_control environment (R = 1, the user-facing path); :class:`BatchPlant`
steps R ``MjData`` of one ``MjModel`` directly, with the same operations as
dm_control (reset: ``mj_resetData``, pose, ``mj_forward`` without actuation; step:
ctrl, ``mj_step2``, ``mj_step1``) and run r's sensor noise from its own
``np.random.default_rng(seeds[r])`` in the task's draw order (see
:mod:`skinny_mj.task`), so run r equals ``EnvPlant(load(..., seed=seeds[r]))``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol, runtime_checkable

import dm_env
import mujoco
import numpy as np

from skinny_mj.model import load_model
from skinny_mj.physics import Layout, servo_ctrl
from skinny_mj.task import Setup, prepare, widen_ctrlrange


@runtime_checkable
class Plant(Protocol):
    """R independent plants stepping in lockstep (normalized signals, commands in [-1, 1])."""

    n_runs: int
    n_dof: int
    n_signals: int
    dt: float
    max_speed_rad_s: np.ndarray  # (n_dof,) rad/s

    def reset(self) -> np.ndarray:
        """Sensed signals (R, n_signals) at t = 0 in the movement's first pose."""
        ...

    def step(self, command: np.ndarray) -> np.ndarray:
        """Apply commands (R, n_dof) in [-1, 1] for one control step; sensed (R, n_signals)."""
        ...

    def true_signals(self) -> np.ndarray:
        """Noise-free signals (R, n_signals)."""
        ...

    def joint_angles(self) -> np.ndarray:
        """(R, n_dof) joint angles, rad."""
        ...

    def command_jacobian(self) -> np.ndarray:
        """(R, n_signals, n_dof) d signal / d command over one control step at the
        current pose = signal_jacobian(q) * max_speed_rad_s * dt."""
        ...


class EnvPlant:
    """A :func:`skinny_mj.task.load` environment seen as a one-run :class:`Plant`.

    Stepping past the episode's last step raises (call :meth:`reset`).
    """

    def __init__(self, env: Any):
        self.env = env
        self.task = env.task
        self.physics = env.physics
        setup: Setup = self.task.setup
        self.n_runs = 1
        self.n_dof = setup.dof
        self.n_signals = setup.desired.shape[1]
        self.dt = setup.dt
        self.max_speed_rad_s = setup.max_speed_rad_s
        self.signals = setup.signals
        self._last = True

    def reset(self) -> np.ndarray:
        ts = self.env.reset()
        self._last = False
        return ts.observation["sensed"][None].copy()

    def step(self, command: np.ndarray) -> np.ndarray:
        if self._last:
            raise RuntimeError("EnvPlant: episode over (or not started); call reset()")
        command = np.asarray(command, dtype=float).reshape(1, self.n_dof)
        ts = self.env.step(command[0])
        self._last = ts.step_type == dm_env.StepType.LAST
        return ts.observation["sensed"][None].copy()

    def true_signals(self) -> np.ndarray:
        return self.physics.position_signals(self.signals)[None]

    def joint_angles(self) -> np.ndarray:
        return self.physics.joint_angles()[None]

    def command_jacobian(self) -> np.ndarray:
        jac = self.physics.signal_jacobian(self.signals)
        return (jac * (self.max_speed_rad_s * self.dt))[None]


class BatchPlant:
    """R copies of Skinny as R ``MjData`` of one ``MjModel``, stepped without dm_control.

    Parameters
    ----------
    dof, signals, trajectory, actuation, sensor_noise, max_speed_rad_s, speed_factor :
        as in :func:`skinny_mj.task.load`.
    n_runs : R.
    seeds : R seeds of the per-run noise generators; default ``range(n_runs)``.
    """

    def __init__(
        self,
        dof: int = 4,
        signals: str = "cartesian",
        trajectory: Any = None,
        n_runs: int = 1,
        seeds: Sequence[int] | None = None,
        sensor_noise: float = 0.01,
        actuation: str = "velocity",
        max_speed_rad_s: float | np.ndarray | None = None,
        speed_factor: float = 2.0,
    ):
        self.setup = prepare(dof, signals, trajectory, actuation, sensor_noise,
                             max_speed_rad_s, speed_factor)
        seeds = list(range(n_runs)) if seeds is None else list(seeds)
        if n_runs < 1 or len(seeds) != n_runs:
            raise ValueError(f"need n_runs >= 1 and one seed per run, got {n_runs}, {seeds}")
        self.model = load_model(dof, actuation)
        self.layout = Layout(self.model)
        widen_ctrlrange(self.model, self.layout.actuator_ids, self.setup)
        self.data = [mujoco.MjData(self.model) for _ in range(n_runs)]
        self.rngs = [np.random.default_rng(s) for s in seeds]
        self.n_runs = n_runs
        self.n_dof = dof
        self.n_signals = self.setup.desired.shape[1]
        self.dt = self.setup.dt
        self.max_speed_rad_s = self.setup.max_speed_rad_s
        self.signals = signals
        self.n_substeps = int(round(self.dt / self.model.opt.timestep))

    def _forward_without_actuation(self, data: mujoco.MjData) -> None:
        # as dm_control's Physics.reset / after_reset
        flags = self.model.opt.disableflags
        self.model.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
        try:
            mujoco.mj_forward(self.model, data)
        finally:
            self.model.opt.disableflags = flags

    def _sensed(self) -> np.ndarray:
        noise = np.stack([
            rng.standard_normal(self.n_signals) * self.setup.sensor_noise for rng in self.rngs
        ])
        return self.true_signals() + noise

    def reset(self) -> np.ndarray:
        for data in self.data:
            mujoco.mj_resetData(self.model, data)
            self._forward_without_actuation(data)
            self.layout.set_joint_angles(data, self.setup.start_rad)
            data.ctrl[:] = 0.0
            self._forward_without_actuation(data)
        return self._sensed()

    def step(self, command: np.ndarray) -> np.ndarray:
        command = np.asarray(command, dtype=float).reshape(self.n_runs, self.n_dof)
        ids = self.layout.actuator_ids
        for r, data in enumerate(self.data):
            if self.setup.actuation == "torque":
                ctrl = np.clip(command[r], -1.0, 1.0)
            else:
                ctrl = servo_ctrl(command[r], self.layout.joint_angles(data),
                                  self.max_speed_rad_s, self.layout.range_rad, self.dt)
            data.ctrl[ids] = ctrl
            # dm_control's legacy step: finish the step, keep kinematics in sync with qpos
            mujoco.mj_step2(self.model, data)
            if self.n_substeps > 1:
                mujoco.mj_step(self.model, data, self.n_substeps - 1)
            mujoco.mj_step1(self.model, data)
        return self._sensed()

    def true_signals(self) -> np.ndarray:
        return np.stack([self.layout.position_signals(d, self.signals) for d in self.data])

    def joint_angles(self) -> np.ndarray:
        return np.stack([self.layout.joint_angles(d) for d in self.data])

    def command_jacobian(self) -> np.ndarray:
        scale = self.max_speed_rad_s * self.dt
        return np.stack([
            self.layout.signal_jacobian(self.model, d, self.signals) * scale for d in self.data
        ])
