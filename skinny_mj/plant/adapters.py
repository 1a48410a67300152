"""Plant adapters: what the (pure NumPy) controllers talk to.

:class:`Plant` is R independent copies of Skinny stepping in lockstep. :class:`EnvPlant`
wraps a dm_control environment (R = 1, the user-facing path); :class:`BatchPlant`
steps R copies of the robot in one ``MjModel`` directly, with the same operations as
dm_control (reset: ``mj_resetData``, pose, ``mj_forward`` without actuation; step:
ctrl, ``mj_step2``, ``mj_step1``) and run r's sensor noise from its own
``np.random.default_rng(seeds[r])`` in the task's draw order (see
:mod:`skinny_mj.plant.task`), so run r equals ``EnvPlant(load(..., seed=seeds[r]))``.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import dm_env
import mujoco
import numpy as np

from skinny_mj.controllers.plant import Plant as _Plant
from skinny_mj.plant.body import BodyLike, signal_set
from skinny_mj.plant.model import BATCH_PREFIX, load_batch_model, load_model
from skinny_mj.plant.physics import (
    Layout,
    segment_jacobian_of,
    segment_signals,
    servo_targets,
    servo_velocity,
)
from skinny_mj.plant.task import Setup, prepare, widen_ctrlrange

_NOISE_BLOCK = 128  # sensor-noise vectors drawn per run at once


# The protocol is defined once, next to the pure-NumPy controllers that use it.
Plant = _Plant


class EnvPlant:
    """A :func:`skinny_mj.plant.task.load` environment seen as a one-run :class:`Plant`.

    Stepping past the episode's last step raises (call :meth:`reset`).
    """

    def __init__(self, env: Any):
        self.env = env
        self.task = env.task
        self.physics = env.physics
        setup: Setup = self.task.setup
        self.body = setup.body
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

    # -- torque loop (skinny_mj.controllers.torque_fel): (1, n_dof) each, as BatchPlant's
    def joint_velocities(self) -> np.ndarray:
        return self.physics.data.qvel[self.physics.layout.dof_adr][None].copy()

    def bias_torque_nm(self) -> np.ndarray:
        return self.physics.data.qfrc_bias[self.physics.layout.dof_adr][None].copy()

    def actuator_force_nm(self) -> np.ndarray:
        return self.physics.data.qfrc_actuator[self.physics.layout.dof_adr][None].copy()

    def warning_count(self) -> int:
        """MuJoCo warnings (``data.warning``, every mjtWarning) of the current episode."""
        return sum(int(w.number) for w in self.physics.data.ptr.warning)


class BatchPlant:
    """R copies of Skinny as one MuJoCo model, stepped without dm_control.

    The R robots are copies in one ``MjModel`` (:func:`skinny_mj.plant.model.load_batch_model`):
    one ``mj_step`` advances all of them in C, and every per-run quantity is a
    (R, ...) view of the one ``MjData``. The copies share nothing, so run r's physics is
    bit for bit that of ``EnvPlant(load(..., seed=seeds[r]))``, with the same operations
    as dm_control (reset: ``mj_resetData``, pose, ``mj_forward`` without actuation;
    step: ctrl, ``mj_step2`` (RK4: ``mj_step``), ``mj_step1``). The work around the
    physics is vectorized over R with the functions :class:`skinny_mj.plant.physics.Layout`
    uses for one run (so bitwise): the servo ctrl, the position signals
    (:func:`skinny_mj.plant.physics.segment_signals`) and the command Jacobian
    (:func:`skinny_mj.plant.physics.segment_jacobian`, equal to ``mj_jacSite`` differences to
    ~1e-16). Sensor noise is drawn from each run's Generator
    (``np.random.default_rng(seeds[r])``, the task's draw order) in blocks of
    ``_NOISE_BLOCK`` vectors, which yields the same sequence as one draw per step.

    Parameters
    ----------
    body, signals, trajectory, sensor_noise, max_speed_rad_s, speed_factor :
        as in :func:`skinny_mj.plant.task.load`.
    n_runs : R.
    seeds : R seeds of the per-run noise generators; default ``range(n_runs)``.
    """

    def __init__(
        self,
        body: BodyLike = "2d",
        signals: str = "cartesian",
        trajectory: Any = None,
        n_runs: int = 1,
        seeds: Sequence[int] | None = None,
        sensor_noise: float = 0.01,
        max_speed_rad_s: float | np.ndarray | None = None,
        speed_factor: float = 2.0,
    ):
        self.setup = prepare(body, signals, trajectory, sensor_noise, max_speed_rad_s,
                             speed_factor)
        self.body = self.setup.body
        seeds = list(range(n_runs)) if seeds is None else list(seeds)
        if n_runs < 1 or len(seeds) != n_runs:
            raise ValueError(f"need n_runs >= 1 and one seed per run, got {n_runs}, {seeds}")
        one = load_model(self.body)  # names and indices of one robot
        self.layout = Layout(one, self.body)
        self.model = load_batch_model(self.body, n_runs)
        for r in range(n_runs):
            widen_ctrlrange(self.model, r * one.nu + self.layout.actuator_ids, self.setup)
        self.data = mujoco.MjData(self.model)
        self.rngs = [np.random.default_rng(s) for s in seeds]
        self.seeds = seeds
        self.n_runs = n_runs
        self.n_dof = self.body.dof
        self._torque = self.setup.actuation == "torque"
        self.n_signals = self.setup.desired.shape[1]
        self.dt = self.setup.dt
        self.max_speed_rad_s = self.setup.max_speed_rad_s
        self.signals = signals
        self._signal_set = signal_set(signals)
        self._joint_signals = self._signal_set.base == "joint"
        self._appended = self._signal_set.appended is not None
        self.n_substeps = int(round(self.dt / self.model.opt.timestep))
        self._rk4 = self.model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
        self._init_views(one)

    # -- per-run views -------------------------------------------------------------
    def _init_views(self, one: mujoco.MjModel) -> None:
        m, d, lay, r = self.model, self.data, self.layout, self.n_runs
        _check_blocks(one, m, r)
        # (R, ...) views of the one MjData (its buffers never move)
        self._qpos = d.qpos.reshape(r, one.nq)
        self._qvel = d.qvel.reshape(r, one.nv)
        self._ctrl = d.ctrl.reshape(r, one.nu)
        self._site_xpos = d.site_xpos.reshape(r, one.nsite, 3)
        self._cdof_flat, self._sites_flat = d.cdof.reshape(r, -1), d.site_xpos.reshape(r, -1)
        sites = lay.site_ids.reshape(-1)  # (6,) arm-major, shoulder/elbow/wrist
        self._comp_sel = _as_slice(np.array(lay.components))  # views, not gathers, if possible
        self._site_sel = _as_slice(sites)
        self._qpos_sel = _as_slice(lay.qpos_adr)
        self._dof_sel = _as_slice(lay.dof_adr)
        self._act_sel = _as_slice(lay.actuator_ids)
        self._noise_buf = np.zeros((0, self.n_runs, self.n_signals))
        self._noise_pos = 0
        self._signals: np.ndarray | None = None
        low_rad, high_rad = servo_targets(lay.range_rad)  # servo_ctrl's bounds, once
        self._servo = functools.partial(servo_velocity, max_speed_rad_s=self.max_speed_rad_s,
                                        low_rad=low_rad, high_rad=high_rad, dt=self.dt)
        self._jacobian = segment_jacobian_of(lay.segment_pairs, lay.segment_lengths,
                                             lay.components, lay.dof_adr, lay.site_ids)

    def _forward_without_actuation(self) -> None:
        # as dm_control's Physics.reset / after_reset
        flags = self.model.opt.disableflags
        self.model.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
        try:
            mujoco.mj_forward(self.model, self.data)
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

    def _sensed(self, out: np.ndarray | None = None) -> np.ndarray:
        out = np.multiply(self._draw_noise(), self.setup.sensor_noise, out=out)
        out += self._true()  # true + noise, as the task adds them
        return out

    # -- torque loop (skinny_mj.controllers.torque_fel) ------------------------------------------
    def joint_velocities(self) -> np.ndarray:
        """(R, n_dof) joint velocities, rad/s (noise-free: a tachometer)."""
        return self._qvel[:, self._dof_sel].copy()

    def bias_torque_nm(self) -> np.ndarray:
        """(R, n_dof) ``qfrc_bias`` of the current state (gravity, Coriolis), N m."""
        return self.data.qfrc_bias.reshape(self.n_runs, -1)[:, self._dof_sel].copy()

    def actuator_force_nm(self) -> np.ndarray:
        """(R, n_dof) joint torque the motors applied in the last step, N m
        (``qfrc_actuator``: gear x ``actuator_force``, after the joints' actfrcrange)."""
        return self.data.qfrc_actuator.reshape(self.n_runs, -1)[:, self._dof_sel].copy()

    def warning_count(self) -> int:
        """MuJoCo warnings (``data.warning``, summed over every mjtWarning) since this
        plant was built, over all R runs (they share one MjData)."""
        return self._warnings + sum(int(w.number) for w in self.data.warning)

    # -- Plant protocol --------------------------------------------------------------
    def reset(self) -> np.ndarray:
        # mj_resetData clears data.warning: keep the count across cycles
        self._warnings = getattr(self, "_warnings", 0) + sum(int(w.number)
                                                             for w in self.data.warning)
        mujoco.mj_resetData(self.model, self.data)
        self._forward_without_actuation()
        self.set_joint_angles(np.broadcast_to(self.setup.start_rad, (self.n_runs, self.n_dof)))
        return self._sensed()

    def set_joint_angles(self, q: np.ndarray) -> None:
        """Pose every run at (R, n_dof) angles (rad), at rest, with zero ctrl, and
        recompute its kinematics (as a reset does)."""
        self._qpos[:, self.layout.qpos_adr] = q
        self._qvel[:, self.layout.dof_adr] = 0.0
        self.data.ctrl[:] = 0.0
        self._forward_without_actuation()
        self._signals = None

    def step(self, command: np.ndarray) -> np.ndarray:
        self._actuate(np.asarray(command, dtype=float).reshape(self.n_runs, self.n_dof))
        self._signals = None
        return self._sensed()

    def step_into(self, command: np.ndarray, sensed: np.ndarray, true: np.ndarray,
                  angles: np.ndarray) -> None:
        """:meth:`step` for a ``command`` (R, n_dof) of floats, writing the new state's
        sensed and true signals (R, n_sig) and joint angles (R, n_dof) into the given
        arrays: the same numbers, no copies."""
        self._actuate(command)
        q = self._qpos[:, self._qpos_sel]
        true[...] = self._signals = self._signals_of(q)
        np.multiply(self._draw_noise(), self.setup.sensor_noise, out=sensed)
        sensed += true  # true + noise, as the task adds them
        angles[...] = q

    def _actuate(self, command: np.ndarray) -> None:
        """Ctrl from ``command`` (R, n_dof) floats, then one control step of physics (the
        kinematics it leaves are the new state's: the caller drops its cached signals)."""
        if self._torque:
            self._ctrl[:, self._act_sel] = np.clip(command, -1.0, 1.0)
        else:
            self._ctrl[:, self._act_sel] = self._servo(command, self._qpos[:, self._qpos_sel])
        # dm_control's legacy step: finish the step, keep kinematics in sync with qpos
        # (mj_step2 integrates with Euler, so RK4, the torque twin's, steps whole)
        if self._rk4:
            mujoco.mj_step(self.model, self.data, self.n_substeps)
        else:
            mujoco.mj_step2(self.model, self.data)
            if self.n_substeps > 1:
                mujoco.mj_step(self.model, self.data, self.n_substeps - 1)
        mujoco.mj_step1(self.model, self.data)

    def true_signals(self) -> np.ndarray:
        return self._true().copy()

    def _true(self) -> np.ndarray:
        if self._signals is None:
            self._signals = self._signals_of(self._qpos[:, self._qpos_sel])
        return self._signals

    def _signals_of(self, q: np.ndarray) -> np.ndarray:
        """(R, n_sig) noise-free signals of the current state, whose angles are q."""
        if self._joint_signals:
            return self._signal_set.extend(self.body.normalize_angles(q), q, self.body)
        points = self._site_xpos[:, self._site_sel].reshape(self.n_runs, 2, 3, 3)
        base = segment_signals(points, self.layout.arm_lengths, self._comp_sel)
        return self._signal_set.extend(base, q, self.body) if self._appended else base

    def joint_angles(self) -> np.ndarray:
        return self._qpos[:, self._qpos_sel].copy()

    def command_jacobian(self) -> np.ndarray:
        if self._joint_signals:
            lo, hi = self.layout.range_rad.T
            jac = np.broadcast_to(np.diag(2.0 / (hi - lo)), (self.n_runs, self.n_dof,
                                                             self.n_dof))
        else:
            jac = self._jacobian(self._cdof_flat, self._sites_flat)
        if self._appended:
            jac = self._signal_set.extend_jacobian(jac, self.body)
        return jac * (self.max_speed_rad_s * self.dt)  # as EnvPlant.command_jacobian


def _as_slice(index: np.ndarray) -> slice | np.ndarray:
    """An index array as the equal slice when it is an evenly spaced ascending run."""
    index = np.asarray(index).reshape(-1)
    if index.size > 1:
        step = int(index[1] - index[0])
        if step > 0 and np.array_equal(index, index[0] + step * np.arange(index.size)):
            return slice(int(index[0]), int(index[-1]) + 1, step)
    return index


def _check_blocks(one: mujoco.MjModel, batch: mujoco.MjModel, copies: int) -> None:
    """The batch model holds ``copies`` robots as contiguous, identically ordered blocks
    (what the (R, ...) views assume); raises if MuJoCo ever lays them out otherwise."""
    sizes = {"nq": one.nq, "nv": one.nv, "nu": one.nu, "nsite": one.nsite,
             "nbody": one.nbody - 1}
    for key, n in sizes.items():
        got = getattr(batch, key) - (1 if key == "nbody" else 0)
        if got != copies * n:
            raise RuntimeError(f"batch model: {key} = {got}, expected {copies} x {n}")
    for kind, count in ((mujoco.mjtObj.mjOBJ_JOINT, one.njnt),
                        (mujoco.mjtObj.mjOBJ_SITE, one.nsite),
                        (mujoco.mjtObj.mjOBJ_ACTUATOR, one.nu)):
        for r in (0, copies - 1):
            for i in range(count):
                name = BATCH_PREFIX.format(r) + mujoco.mj_id2name(one, kind, i)
                if mujoco.mj_name2id(batch, kind, name) != r * count + i:
                    raise RuntimeError(f"batch model: {name} is not where the views expect")
