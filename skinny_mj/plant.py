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
from typing import Any

import dm_env
import mujoco
import numpy as np

from controllers.plant import Plant as _Plant
from skinny_mj import body
from skinny_mj.model import load_model
from skinny_mj.physics import Layout, servo_ctrl
from skinny_mj.task import Setup, prepare, widen_ctrlrange

_NOISE_BLOCK = 128  # sensor-noise vectors drawn per run at once


# The protocol is defined once, next to the pure-NumPy controllers that use it.
Plant = _Plant


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

    The per-step work around the physics is vectorized over R and computes the same
    numbers with the same floating-point operations as :class:`skinny_mj.physics.Layout`
    (bit-identical): the servo ctrl, the position signals from ``site_xpos``, and the
    site Jacobians from ``cdof`` / ``subtree_com`` exactly as MuJoCo's ``mj_jac`` forms
    them. Sensor noise is drawn from each run's Generator in blocks of
    ``_NOISE_BLOCK`` vectors, which yields the same sequence as one draw per step.

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
        self._init_fast_path()

    # -- vectorized views ----------------------------------------------------------
    def _init_fast_path(self) -> None:
        m, lay = self.model, self.layout
        # Views into each MjData stay valid for the data's lifetime (no reallocation).
        self._views = {name: [getattr(d, name) for d in self.data]
                       for name in ("qpos", "ctrl", "site_xpos", "cdof", "subtree_com")}
        # (1, ...) views, so one np.concatenate gathers R runs without np.stack's per-run
        # expand_dims
        self._rows = {name: [v[None] for v in views] for name, views in self._views.items()}
        self._sites = lay.site_ids.reshape(-1)  # (6,) arm-major, shoulder/elbow/wrist
        site_body = m.site_bodyid[self._sites]
        self._site_root = m.body_rootid[site_body]
        # dofs on each site's kinematic chain (mj_jac walks the same chain)
        mask = np.zeros((self._sites.size, m.nv), bool)
        for k, body_id in enumerate(site_body):
            b = int(body_id)
            while b and not m.body_dofnum[b]:
                b = int(m.body_parentid[b])
            if b:
                i = int(m.body_dofadr[b] + m.body_dofnum[b] - 1)
                while i >= 0:
                    mask[k, i] = True
                    i = int(m.dof_parentid[i])
        self._chain = mask[:, None, :]  # (6, 1, nv)
        self._comps = np.array(lay._comps)
        self._lengths = lay._lengths
        self._scale = self.max_speed_rad_s * self.dt
        self._noise_buf = np.zeros((0, self.n_runs, self.n_signals))
        self._noise_pos = 0
        self._cache: dict[str, np.ndarray] = {}

    def _stacked(self, name: str) -> np.ndarray:
        arr = self._cache.get(name)
        if arr is None:
            arr = np.concatenate(self._rows[name])
            self._cache[name] = arr
        return arr

    def _forward_without_actuation(self, data: mujoco.MjData) -> None:
        # as dm_control's Physics.reset / after_reset
        flags = self.model.opt.disableflags
        self.model.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
        try:
            mujoco.mj_forward(self.model, data)
        finally:
            self.model.opt.disableflags = flags

    def _draw_noise(self) -> np.ndarray:
        if self._noise_pos >= self._noise_buf.shape[0]:
            self._noise_buf = np.stack(
                [rng.standard_normal((_NOISE_BLOCK, self.n_signals)) for rng in self.rngs],
                axis=1)  # (B, R, n_signals); same stream as one draw per step
            self._noise_pos = 0
        self._noise_pos += 1
        return self._noise_buf[self._noise_pos - 1]

    def _sensed(self) -> np.ndarray:
        return self.true_signals() + self._draw_noise() * self.setup.sensor_noise

    # -- Plant protocol --------------------------------------------------------------
    def reset(self) -> np.ndarray:
        for data in self.data:
            mujoco.mj_resetData(self.model, data)
            self._forward_without_actuation(data)
            self.layout.set_joint_angles(data, self.setup.start_rad)
            data.ctrl[:] = 0.0
            self._forward_without_actuation(data)
        self._cache = {}
        return self._sensed()

    def step(self, command: np.ndarray) -> np.ndarray:
        command = np.asarray(command, dtype=float).reshape(self.n_runs, self.n_dof)
        if self.setup.actuation == "torque":
            ctrl = np.clip(command, -1.0, 1.0)
        else:
            ctrl = servo_ctrl(command, self.joint_angles(), self.max_speed_rad_s,
                              self.layout.range_rad, self.dt)
        ids, model, extra = self.layout.actuator_ids, self.model, self.n_substeps - 1
        step1, step2 = mujoco.mj_step1, mujoco.mj_step2
        for r, (data, ctrl_view) in enumerate(zip(self.data, self._views["ctrl"],
                                                  strict=True)):
            ctrl_view[ids] = ctrl[r]
            # dm_control's legacy step: finish the step, keep kinematics in sync with qpos
            step2(model, data)
            if extra:
                mujoco.mj_step(model, data, extra)
            step1(model, data)
        self._cache = {}
        return self._sensed()

    def true_signals(self) -> np.ndarray:
        out = self._cache.get("signals")
        if out is None:
            if self.signals == "joint":
                out = body.normalize_angles(self.joint_angles(), self.n_dof)
            else:
                pts = self._stacked("site_xpos")[:, self.layout.site_ids]  # (R, 2, 3, 3)
                seg = (pts[:, :, 1:] - pts[:, :, :-1]) / self._lengths[:, None]
                out = seg[..., self._comps].reshape(self.n_runs, -1)
            self._cache["signals"] = out
        return out.copy()

    def joint_angles(self) -> np.ndarray:
        return self._stacked("qpos")[:, self.layout.qpos_adr]

    def command_jacobian(self) -> np.ndarray:
        n = self.n_runs
        if self.signals == "joint":
            lo, hi = self.layout.range_rad.T
            jac = np.diag(2.0 / (hi - lo)) * self._scale
            return np.broadcast_to(jac, (n, *jac.shape)).copy()
        cdof = self._stacked("cdof")  # (R, nv, 6)
        offset = (self._stacked("site_xpos")[:, self._sites]
                  - self._stacked("subtree_com")[:, self._site_root])  # (R, 6, 3)
        a = np.swapaxes(cdof[..., :3], 1, 2)[:, None]  # (R, 1, 3, nv) angular part
        o = offset[..., None]  # (R, 6, 3, 1)
        cross = np.stack([a[:, :, 1] * o[:, :, 2] - a[:, :, 2] * o[:, :, 1],
                          a[:, :, 2] * o[:, :, 0] - a[:, :, 0] * o[:, :, 2],
                          a[:, :, 0] * o[:, :, 1] - a[:, :, 1] * o[:, :, 0]], axis=2)
        jac = np.where(self._chain, np.swapaxes(cdof[..., 3:], 1, 2)[:, None] + cross, 0.0)
        jac = jac[..., self.layout.dof_adr].reshape(n, 2, 3, 3, self.n_dof)
        seg = (jac[:, :, 1:] - jac[:, :, :-1])[:, :, :, self._comps]
        seg = seg / self._lengths[None, None, :, None, None]
        return seg.reshape(n, self.n_signals, self.n_dof) * self._scale
