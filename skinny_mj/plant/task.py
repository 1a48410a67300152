"""The imitation task: Skinny follows a movement, one normalized velocity command per
DOF every 20 ms, and sees its own arm positions through noisy sensors.

Sensor-noise draw order (shared with :class:`skinny_mj.plant.adapters.BatchPlant`): the task's
``np.random.Generator(seed)`` draws one vector ``standard_normal(n_signals)`` per
observed plant state: once at every reset, then once after every step; the vector
is scaled by ``sensor_noise`` (also when it is 0). The generator is not re-seeded
on reset, so episode k of an environment continues episode k-1's stream.
"""

from __future__ import annotations

import collections
from dataclasses import dataclass
from typing import Any

import numpy as np
from dm_control.rl import control
from dm_control.suite import base
from dm_env import specs

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.plant.ideal import max_speeds
from skinny_mj.plant.physics import LIMIT_MARGIN_RAD, SkinnyPhysics, servo_ctrl

CONTROL_DT_S = body.CONTROL_DT_S
SIGNALS = body.SIGNALS
MAX_SENSOR_NOISE = body.MAX_SENSOR_NOISE


def finite_actions(action: Any, shape: tuple[int, ...]) -> np.ndarray:
    """``action`` as a float array of ``shape``; another shape, or a NaN or infinite entry,
    is refused (:class:`SkinnyInputError`, a ``ValueError``, naming where): clipping cannot
    say what such a command meant."""
    try:
        given = np.shape(action)
    except ValueError:  # ragged nested lists
        given = "a ragged list"
    if np.iscomplexobj(action):
        raise SkinnyInputError(f"action must be {shape} real numbers, got complex values")
    try:
        out = np.asarray(action, dtype=float)
    except (TypeError, ValueError) as exc:
        raise SkinnyInputError(f"action must be {shape} numbers, got {given}: {exc}") from None
    if out.shape != tuple(shape):  # (1, 4) for (4,) is a batch, not an action: no reshape
        raise SkinnyInputError(f"action must be {shape} numbers, got shape {given}")
    if not np.all(np.isfinite(out)):
        where = tuple(int(i) for i in np.argwhere(~np.isfinite(out))[0])
        raise SkinnyInputError(f"action {where} is {out[where]}: actions must be finite "
                               "(finite values outside [-1, 1] are clipped)")
    return out


@dataclass(frozen=True)
class Setup:
    """What a movement asks of the plant (validated; shared by the task and BatchPlant).

    angles: (T, n_dof) desired joint angles, rad. desired: (T, n_signals) normalized
    desired signals. start_rad: (n_dof,) first pose, moved ``LIMIT_MARGIN_RAD`` inside
    the joint ranges. max_speed_rad_s: (n_dof,) full-scale speed.
    """

    dof: int
    signals: str
    actuation: str
    sensor_noise: float
    angles: np.ndarray
    desired: np.ndarray
    start_rad: np.ndarray
    max_speed_rad_s: np.ndarray
    dt: float = CONTROL_DT_S


def _number(name: str, value: Any) -> float:
    if isinstance(value, bool):
        raise SkinnyInputError(f"{name} must be a number, got {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise SkinnyInputError(f"{name} must be a number, got {value!r}") from None


def check_seed(seed: Any) -> int:
    """``seed`` as an int if it is a whole number >= 0 (a Generator's seed), else a
    :class:`SkinnyInputError`."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise SkinnyInputError(f"seed must be a whole number >= 0, got {seed!r}")
    return int(seed)


def prepare(
    dof: int,
    signals: str,
    trajectory: Any,
    actuation: str = "velocity",
    sensor_noise: float = 0.01,
    max_speed_rad_s: float | np.ndarray | None = None,
    speed_factor: float = 2.0,
) -> Setup:
    """Validate the arguments of :func:`load` and derive the per-DOF numbers."""
    body.check_dof(dof)
    body.check_signals(signals)
    body.check_actuation(actuation)
    sensor_noise = _number("sensor_noise", sensor_noise)
    speed_factor = _number("speed_factor", speed_factor)
    if not (np.isfinite(sensor_noise) and 0 <= sensor_noise <= MAX_SENSOR_NOISE):
        raise SkinnyInputError(f"sensor_noise must be in [0, {MAX_SENSOR_NOISE:g}] (the std "
                               f"of noise on signals normalized to [-1, 1]), got "
                               f"{sensor_noise!r}")
    if trajectory is None:  # the plant has no movement of its own (it imports none)
        raise SkinnyInputError("the plant needs a trajectory; skinny_mj.load's default is "
                               "the synthesized YMCA, skinny_mj.trajectories.get('ymca', dof)")
    if not hasattr(trajectory, "angles"):  # names and files: skinny_mj.load, the gym envs
        raise SkinnyInputError(f"the plant takes a Trajectory (an object with .angles), got "
                               f"{type(trajectory).__name__}; skinny_mj.load takes movement "
                               "names and files")
    if getattr(trajectory, "dof", dof) != dof:
        raise SkinnyInputError(f"trajectory has dof={trajectory.dof}, the plant dof={dof}")
    angles = np.asarray(trajectory.angles, dtype=float)
    if angles.ndim != 2 or angles.shape[1] != dof or angles.shape[0] < 2:
        raise SkinnyInputError(f"trajectory angles must be (T >= 2, {dof}), got {angles.shape}")
    if not np.all(np.isfinite(angles)):
        raise SkinnyInputError("trajectory angles contain NaN or inf")
    dt = float(getattr(trajectory, "dt", CONTROL_DT_S))
    if abs(dt - CONTROL_DT_S) > 1e-9:
        raise SkinnyInputError(f"trajectory dt must be {CONTROL_DT_S} s (50 Hz), got {dt}")
    if max_speed_rad_s is None:
        if not (np.isfinite(speed_factor) and speed_factor > 0):
            raise SkinnyInputError(f"speed_factor must be a finite number > 0, got "
                                   f"{speed_factor!r}")
        speed = max_speeds(angles, dt, speed_factor)
    else:
        try:
            speed = np.broadcast_to(np.asarray(max_speed_rad_s, dtype=float), (dof,)).copy()
        except (TypeError, ValueError):
            raise SkinnyInputError(f"max_speed_rad_s must be a number or {dof} numbers, "
                                   f"got {max_speed_rad_s!r}") from None
        if not np.all(np.isfinite(speed) & (speed > 0)):
            raise SkinnyInputError(f"max_speed_rad_s must be finite and > 0, got {speed}")
    speed.flags.writeable = False  # the plant's full scale: its own, read-only copy
    rng = body.joint_ranges(dof)
    start = np.clip(angles[0], rng[:, 0] + LIMIT_MARGIN_RAD, rng[:, 1] - LIMIT_MARGIN_RAD)
    return Setup(
        dof=dof,
        signals=signals,
        actuation=actuation,
        sensor_noise=float(sensor_noise),
        angles=angles,
        desired=trajectory.position_signals(signals) if hasattr(trajectory, "position_signals")
        else body.position_signals(angles, dof, signals),  # explicit recorded signals
        start_rad=start,
        max_speed_rad_s=speed,
        dt=dt,
    )


def widen_ctrlrange(model, actuator_ids: np.ndarray, setup: Setup) -> None:
    """Velocity servo only: make sure the actuators' ctrlrange (rad/s) admits 1.5x the
    full-scale speed, so MuJoCo never clamps a command the task let through."""
    if setup.actuation != "velocity":
        return
    need = 1.5 * setup.max_speed_rad_s
    cur = model.actuator_ctrlrange[actuator_ids]
    model.actuator_ctrlrange[actuator_ids, 0] = np.minimum(cur[:, 0], -need)
    model.actuator_ctrlrange[actuator_ids, 1] = np.maximum(cur[:, 1], need)


class Imitation(base.Task):
    """Follow ``setup.angles``; observe noisy normalized positions; reward = -mean |error|.

    Parameters
    ----------
    setup : validated movement and plant settings (:func:`prepare`).
    seed : seed of the task's ``np.random.Generator`` (sensor noise).
    """

    def __init__(self, setup: Setup, seed: int = 0):
        super().__init__(random=0)  # dm_control's RandomState is unused
        self.setup = setup
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self._t = 0
        self._noise = np.zeros(setup.desired.shape[1])

    # --- what a controller may want to know -----------------------------------------
    @property
    def dof(self) -> int:
        return self.setup.dof

    @property
    def signals(self) -> str:
        """"joint" or "cartesian"."""
        return self.setup.signals

    @property
    def max_speed_rad_s(self) -> np.ndarray:
        """(n_dof,) full-scale speed of the command, rad/s."""
        return self.setup.max_speed_rad_s

    @property
    def n_steps(self) -> int:
        """Control steps per episode: trajectory length - 1."""
        return len(self.setup.angles) - 1

    @property
    def step_index(self) -> int:
        return self._t

    # --- dm_control Task --------------------------------------------------------------
    def initialize_episode(self, physics: SkinnyPhysics) -> None:
        physics.layout.set_joint_angles(physics.data.ptr, self.setup.start_rad)
        physics.data.ctrl[:] = 0.0
        self._t = 0
        self._draw_noise()

    def before_step(self, action: np.ndarray, physics: SkinnyPhysics) -> None:
        layout = physics.layout
        action = finite_actions(action, (self.setup.dof,))
        if self.setup.actuation == "torque":
            ctrl = np.clip(action, -1.0, 1.0)
        else:
            ctrl = servo_ctrl(
                action, layout.joint_angles(physics.data.ptr), self.setup.max_speed_rad_s,
                layout.range_rad, self.setup.dt,
            )
        physics.data.ctrl[layout.actuator_ids] = ctrl

    def after_step(self, physics: SkinnyPhysics) -> None:
        self._t += 1
        self._draw_noise()

    def _draw_noise(self) -> None:
        n = self.setup.desired.shape[1]
        self._noise = self.rng.standard_normal(n) * self.setup.sensor_noise

    def get_observation(self, physics: SkinnyPhysics) -> collections.OrderedDict:
        desired = self.setup.desired
        obs = collections.OrderedDict()
        obs["sensed"] = physics.position_signals(self.setup.signals) + self._noise
        obs["desired"] = desired[min(self._t, len(desired) - 1)].copy()
        obs["desired_next"] = desired[min(self._t + 1, len(desired) - 1)].copy()
        obs["joint_angles"] = physics.joint_angles()
        obs["step"] = np.array(self._t, dtype=np.int64)
        return obs

    def observation_spec(self, physics: SkinnyPhysics) -> collections.OrderedDict:
        n_sig, n_dof = self.setup.desired.shape[1], self.setup.dof
        spec = collections.OrderedDict()
        for key, n in (("sensed", n_sig), ("desired", n_sig), ("desired_next", n_sig),
                       ("joint_angles", n_dof)):
            spec[key] = specs.Array((n,), np.float64, name=key)
        spec["step"] = specs.Array((), np.int64, name="step")
        return spec

    def action_spec(self, physics: SkinnyPhysics) -> specs.BoundedArray:
        return specs.BoundedArray(
            (self.setup.dof,), np.float64, -1.0, 1.0, name="command"
        )

    def get_reward(self, physics: SkinnyPhysics) -> float:
        desired = self.setup.desired[min(self._t, len(self.setup.desired) - 1)]
        return -float(np.mean(np.abs(desired - physics.position_signals(self.setup.signals))))


def load(
    dof: int = 4,
    signals: str = "cartesian",
    trajectory: Any = None,
    actuation: str = "velocity",
    sensor_noise: float = 0.01,
    seed: int = 0,
    max_speed_rad_s: float | np.ndarray | None = None,
    speed_factor: float = 2.0,
) -> control.Environment:
    """Skinny imitating a movement, as a dm_control ``control.Environment``.

    Parameters
    ----------
    dof : 4 (2D) or 8 (3D).
    signals : "joint" (normalized angles) or "cartesian" (normalized segment vectors).
    trajectory : object with ``.angles`` (T, dof) rad, ``.dt`` (0.02 s) and ``.dof``
        (required: :func:`skinny_mj.load` defaults to the synthesized YMCA,
        ``skinny_mj.trajectories.get("ymca", dof)``, and takes movement names and files).
    actuation : "velocity" (the kinematic servo; action = normalized joint velocity) or
        "torque" (motor twin; action = normalized torque, ctrl x gear N m).
    sensor_noise : std of the Gaussian noise on the sensed signals (normalized units).
    seed : seed of the task's Generator.
    max_speed_rad_s : full scale of the command, scalar or (dof,) rad/s; default
        ``speed_factor`` x the fastest speed of each DOF in the movement, at least
        :data:`skinny_mj.plant.ideal.MIN_MAX_SPEED_RAD_S`.
    speed_factor : see ``max_speed_rad_s``.

    Returns
    -------
    Environment with episodes of T - 1 control steps of 0.02 s; ``env.task`` exposes
    ``max_speed_rad_s``, ``signals``, ``setup``.
    """
    check_seed(seed)
    setup = prepare(dof, signals, trajectory, actuation, sensor_noise, max_speed_rad_s,
                    speed_factor)
    physics = SkinnyPhysics.load(dof, actuation)
    widen_ctrlrange(physics.model.ptr, physics.layout.actuator_ids, setup)
    n_sub = int(round(setup.dt / physics.timestep()))
    task = Imitation(setup, seed)
    n_steps = len(setup.angles) - 1
    # step_limit = n_steps - 0.5: the episode ends on step n_steps with no float tie.
    return control.Environment(
        physics, task, time_limit=(n_steps - 0.5) * setup.dt, n_sub_steps=n_sub
    )
