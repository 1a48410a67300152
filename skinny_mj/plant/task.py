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
import inspect
from dataclasses import dataclass
from typing import Any

import numpy as np
from dm_control.rl import control
from dm_control.suite import base
from dm_env import specs

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.plant.body import Body, BodyLike, body_of
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

    body: the :class:`~skinny_mj.plant.body.Body` imitating it. angles: (T, n_dof)
    desired joint angles, rad. desired: (T, n_signals) normalized desired signals.
    start_rad: (n_dof,) first pose, moved ``LIMIT_MARGIN_RAD`` inside the joint ranges.
    max_speed_rad_s: (n_dof,) full-scale speed.
    """

    body: Body
    signals: str
    sensor_noise: float
    angles: np.ndarray
    desired: np.ndarray
    start_rad: np.ndarray
    max_speed_rad_s: np.ndarray
    dt: float = CONTROL_DT_S

    @property
    def dof(self) -> int:
        """The body's number of hinges (commands per step)."""
        return self.body.dof

    @property
    def actuation(self) -> str:
        """The body's: "velocity" (a command is a normalized joint velocity) or "torque"
        (a normalized torque)."""
        return self.body.actuation


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
    which: BodyLike,
    signals: str,
    trajectory: Any,
    sensor_noise: float = 0.01,
    max_speed_rad_s: float | np.ndarray | None = None,
    speed_factor: float = 2.0,
) -> Setup:
    """Validate the arguments of :func:`load` and derive the per-DOF numbers."""
    skinny = body_of(which)
    body.check_signals(signals)
    dof = skinny.dof
    sensor_noise = _number("sensor_noise", sensor_noise)
    speed_factor = _number("speed_factor", speed_factor)
    if not (np.isfinite(sensor_noise) and 0 <= sensor_noise <= MAX_SENSOR_NOISE):
        raise SkinnyInputError(f"sensor_noise must be in [0, {MAX_SENSOR_NOISE:g}] (the std "
                               f"of noise on signals normalized to [-1, 1]), got "
                               f"{sensor_noise!r}")
    if trajectory is None:  # the plant has no movement of its own (it imports none)
        raise SkinnyInputError("the plant needs a trajectory; skinny_mj.load's default is "
                               "the synthesized YMCA, skinny_mj.trajectories.get('ymca', body)")
    if not hasattr(trajectory, "angles"):  # names and files: skinny_mj.load, the gym envs
        raise SkinnyInputError(f"the plant takes a Trajectory (an object with .angles), got "
                               f"{type(trajectory).__name__}; skinny_mj.load takes movement "
                               "names and files")
    if getattr(trajectory, "dof", dof) != dof:
        raise SkinnyInputError(f"trajectory has {trajectory.dof} DOFs, the {skinny.name} body "
                               f"{dof}")
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
    rng = skinny.joint_ranges()
    start = np.clip(angles[0], rng[:, 0] + LIMIT_MARGIN_RAD, rng[:, 1] - LIMIT_MARGIN_RAD)
    return Setup(
        body=skinny,
        signals=signals,
        sensor_noise=float(sensor_noise),
        angles=angles,
        desired=trajectory.position_signals(signals, skinny)  # its explicit signals, if any
        if hasattr(trajectory, "position_signals") else skinny.position_signals(angles, signals),
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
        self._torque = setup.actuation == "torque"

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
        if self._torque:
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
    body: BodyLike = "2d",
    signals: str = "cartesian",
    trajectory: Any = None,
    sensor_noise: float = 0.01,
    seed: int = 0,
    max_speed_rad_s: float | np.ndarray | None = None,
    speed_factor: float = 2.0,
) -> control.Environment:
    """Skinny imitating a movement, as a dm_control ``control.Environment``.

    The one definition of the task's arguments: :func:`skinny_mj.load` and the Gymnasium
    envs take these and pass them on (:func:`arguments`).

    Parameters
    ----------
    body : a body's name (:data:`skinny_mj.plant.body.BODIES`: "2d", "3d", or a torque
        twin "2d-torque", "3d-torque", whose action is a normalized torque, ctrl x gear
        N m, where a velocity body's is a normalized joint velocity), or 4 / 8 for "2d" /
        "3d".
    signals : "joint" (normalized angles) or "cartesian" (normalized segment vectors).
    trajectory : object with ``.angles`` (T, n_dof) rad, ``.dt`` (0.02 s) and ``.dof``
        (required: :func:`skinny_mj.load` defaults to the synthesized YMCA,
        ``skinny_mj.trajectories.get("ymca", body)``, and takes movement names and files).
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
    setup = prepare(body, signals, trajectory, sensor_noise, max_speed_rad_s, speed_factor)
    physics = SkinnyPhysics.load(setup.body)
    widen_ctrlrange(physics.model.ptr, physics.layout.actuator_ids, setup)
    n_sub = int(round(setup.dt / physics.timestep()))
    task = Imitation(setup, seed)
    n_steps = len(setup.angles) - 1
    # step_limit = n_steps - 0.5: the episode ends on step n_steps with no float tie.
    return control.Environment(
        physics, task, time_limit=(n_steps - 0.5) * setup.dt, n_sub_steps=n_sub
    )


def arguments(*args: Any, **kwargs: Any) -> dict[str, Any]:
    """The arguments of :func:`load` given as ``args`` and ``kwargs``, by name, every other
    one at its default: what :func:`skinny_mj.load` and the Gymnasium envs take and pass
    on. An argument :func:`load` does not take is a :class:`SkinnyInputError` naming those
    it does."""
    signature = inspect.signature(load)
    try:
        bound = signature.bind(*args, **kwargs)
    except TypeError as err:
        raise SkinnyInputError(f"{err}; the task takes {', '.join(signature.parameters)}"
                               ) from None
    bound.apply_defaults()
    return dict(bound.arguments)
