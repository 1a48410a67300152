"""The imitation task: dm_env contract, determinism, episode logic, servo accuracy, limits."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from absl.testing import absltest
from dm_env import test_utils

import skinny_mj
from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.plant.adapters import BatchPlant
from skinny_mj.plant.ideal import MIN_MAX_SPEED_RAD_S, IdealController, max_speeds, true_commands
from skinny_mj.plant.task import load
from skinny_mj.trajectories import load_movement


@dataclass(frozen=True)
class StandIn:
    """Duck-typed trajectory until skinny_mj.trajectories lands."""

    angles: np.ndarray
    dof: int
    dt: float = 0.02


def stand_in(dof: int, n: int = 40, still_dof: int | None = None) -> StandIn:
    """Smooth movement starting arms down (on the lower limits of abduction/elbow)."""
    t = np.linspace(0.0, 1.0, n)[:, None]
    lo, hi = body.body_of(dof).joint_ranges().T
    angles = lo + (hi - lo) * 0.45 * (1 - np.cos(np.pi * t * (1 + np.arange(dof) % 3)))
    angles = np.clip(angles, lo, hi)
    if still_dof is not None:
        angles[:, still_dof] = angles[0, still_dof]
    return StandIn(angles, dof)


class Env2DTest(test_utils.EnvironmentTestMixin, absltest.TestCase):
    def make_object_under_test(self):
        return load(4, "cartesian", stand_in(4), seed=1)


class Env3DTest(test_utils.EnvironmentTestMixin, absltest.TestCase):
    def make_object_under_test(self):
        return load(8, "cartesian", stand_in(8), seed=1)


class Env3DTorqueJointTest(test_utils.EnvironmentTestMixin, absltest.TestCase):
    def make_object_under_test(self):
        return load("3d-torque", "joint", stand_in(8), seed=1)


def _rollout(env, commands):
    ts = env.reset()
    out = [ts.observation]
    for c in commands:
        ts = env.step(c)
        out.append(ts.observation)
    return out


@pytest.mark.parametrize("dof", [4, 8])
def test_same_seed_same_numbers_other_seed_other_noise(dof):
    traj = stand_in(dof)
    commands = np.random.default_rng(3).uniform(-1, 1, (20, dof))
    a = _rollout(load(dof, trajectory=traj, seed=7), commands)
    b = _rollout(load(dof, trajectory=traj, seed=7), commands)
    c = _rollout(load(dof, trajectory=traj, seed=8), commands)
    for oa, ob, oc in zip(a, b, c, strict=True):
        for key in oa:
            np.testing.assert_array_equal(oa[key], ob[key])
        np.testing.assert_array_equal(oa["joint_angles"], oc["joint_angles"])
        assert np.abs(oa["sensed"] - oc["sensed"]).max() > 1e-4


@pytest.mark.parametrize("signals", ["joint", "cartesian"])
def test_episode_observations_and_reward(signals):
    traj = stand_in(4, n=25)
    env = load(4, signals, traj, sensor_noise=0.05, seed=0)
    desired = body.body_of(4).position_signals(traj.angles, signals)
    ts = env.reset()
    lo, hi = body.body_of(4).joint_ranges().T
    np.testing.assert_allclose(ts.observation["joint_angles"],
                               np.clip(traj.angles[0], lo + 1e-3, hi - 1e-3), atol=1e-12)
    assert list(ts.observation) == ["sensed", "desired", "desired_next", "joint_angles", "step"]
    noise = []
    steps = 0
    while not ts.last():
        t = int(ts.observation["step"])
        assert t == steps
        np.testing.assert_array_equal(ts.observation["desired"], desired[t])
        np.testing.assert_array_equal(ts.observation["desired_next"], desired[t + 1])
        true = body.body_of(4).position_signals(ts.observation["joint_angles"], signals)
        noise.append(ts.observation["sensed"] - true)
        ts = env.step(np.zeros(4))
        steps += 1
        true = body.body_of(4).position_signals(ts.observation["joint_angles"], signals)
        assert ts.reward == pytest.approx(-np.mean(np.abs(desired[steps] - true)), abs=1e-12)
    assert steps == len(traj.angles) - 1
    noise = np.concatenate(noise)
    assert 0.03 < noise.std() < 0.07 and abs(noise.mean()) < 0.02
    assert env.task.signals == signals


def test_max_speed_default_floor_and_override():
    traj = stand_in(4, still_dof=3)
    env = load(4, trajectory=traj)
    fastest = np.abs(np.diff(traj.angles, axis=0)).max(axis=0) / 0.02
    np.testing.assert_allclose(env.task.max_speed_rad_s[:3], 2.0 * fastest[:3])
    assert env.task.max_speed_rad_s[3] == MIN_MAX_SPEED_RAD_S
    env = load(4, trajectory=traj, speed_factor=1.5)
    np.testing.assert_allclose(env.task.max_speed_rad_s[:3], 1.5 * fastest[:3])
    env = load(4, trajectory=traj, max_speed_rad_s=[1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(env.task.max_speed_rad_s, [1.0, 2.0, 3.0, 4.0])
    np.testing.assert_allclose(max_speeds(traj.angles, 0.02, 2.0), load(4, trajectory=traj)
                               .task.max_speed_rad_s)


@pytest.mark.parametrize("dof", [4, 8])
def test_ideal_controller_tracks_and_true_commands_integrate(dof):
    traj = stand_in(dof)
    env = load(dof, "cartesian", traj, sensor_noise=0.0)
    speed = env.task.max_speed_rad_s
    ctrl = IdealController(traj.angles, speed, 0.02)
    ts = env.reset()
    errors = []
    while not ts.last():
        ts = env.step(ctrl.command(int(ts.observation["step"]), ts.observation["joint_angles"]))
        errors.append(-ts.reward)
    assert max(errors) < 5e-3  # servo lag ~1 % of a step plus the 1e-3 rad limit margin
    u = true_commands(traj.angles, speed, 0.02)
    assert u.shape == (len(traj.angles) - 1, dof) and np.abs(u).max() <= 0.5 + 1e-12
    np.testing.assert_allclose(traj.angles[0] + np.cumsum(u * speed * 0.02, axis=0),
                               traj.angles[1:], atol=1e-12)


@pytest.mark.parametrize("dof", [4, 8])
def test_servo_moves_command_times_full_scale_step(dof):
    """One control step with command c moves each joint by c * max_speed * dt, to 1 % of
    the full-scale step, from rest, at constant speed and on a reversal -1 -> +1."""
    speed = np.linspace(2.0, 10.0, dof)
    step_rad = speed * 0.02
    plant = BatchPlant(dof, "joint", stand_in(dof), sensor_noise=0.0, max_speed_rad_s=speed)
    lo, hi = body.body_of(dof).joint_ranges().T
    mid = (lo + hi) / 2
    worst = 0.0
    for c_prev, c in [(0.0, 1.0), (0.0, -0.3), (0.5, 0.5), (-1.0, 1.0), (1.0, -1.0), (0.2, -0.7)]:
        plant.reset()
        plant.set_joint_angles((mid - 2.5 * c_prev * step_rad)[None])
        for _ in range(2):
            plant.step(np.full((1, dof), c_prev))
        q = plant.joint_angles()[0]
        plant.step(np.full((1, dof), c))
        moved = plant.joint_angles()[0] - q
        worst = max(worst, np.max(np.abs(moved - c * step_rad) / step_rad))
    assert worst < 0.01


@pytest.mark.parametrize("dof", [4, 8])
def test_random_commands_never_pass_the_range(dof):
    plant = BatchPlant(dof, "cartesian", stand_in(dof), sensor_noise=0.0, max_speed_rad_s=12.0)
    lo, hi = body.body_of(dof).joint_ranges().T
    rng = np.random.default_rng(dof)
    plant.reset()
    worst = -np.inf
    for k in range(10_000):
        if k % 5 == 0:  # held, often saturated commands drive the joints into the limits
            command = np.clip(rng.normal(0.0, 2.0, (1, dof)), -1, 1)
        plant.step(command)
        q = plant.joint_angles()[0]
        worst = max(worst, np.max(lo - q), np.max(q - hi))
    assert worst < 1e-3
    assert all(w.number == 0 for w in plant.data.warning)


def test_the_default_trajectory_is_ymca_and_the_packages_not_the_plants():
    trajectories = pytest.importorskip("skinny_mj.trajectories")
    env = skinny_mj.load(4)
    np.testing.assert_array_equal(env.task.setup.angles, trajectories.get("ymca", 4).angles)
    with pytest.raises(SkinnyInputError, match="needs a trajectory"):
        load(4)


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"body": 5}, "unknown body 5"),
        ({"body": "2d-long"}, "unknown body '2d-long'; the bodies: 2d, 3d, 2d-torque"),
        ({"signals": "polar"}, "signals"),
        ({"sensor_noise": -0.1}, "sensor_noise"),
        ({"max_speed_rad_s": 0.0}, "max_speed"),
        ({"speed_factor": 0.0}, "speed_factor"),
        ({"trajectory": StandIn(np.zeros((10, 8)), 8)}, "trajectory has 8 DOFs, the 2d body 4"),
        ({"trajectory": StandIn(np.full((10, 4), np.nan), 4)}, "NaN"),
        ({"trajectory": StandIn(np.zeros((1, 4)), 4)}, "T >= 2"),
        ({"trajectory": StandIn(np.zeros((10, 4)), 4, dt=0.01)}, "dt"),
        ({"trajectory": "ym"}, "the plant takes a Trajectory"),  # names: skinny_mj.load
        ({"seed": -1}, "seed must be a whole number >= 0"),
        ({"seed": 1.5}, "seed must be a whole number >= 0"),
        ({"sensor_noise": "x"}, "sensor_noise must be a number"),
        ({"speed_factor": None}, "speed_factor must be a number"),
        ({"max_speed_rad_s": [1.0, 2.0]}, "max_speed_rad_s must be a number or 4 numbers"),
    ],
)
def test_bad_arguments_raise_input_error(kwargs, match):
    args = {"body": "2d", "trajectory": stand_in(4)} | kwargs
    with pytest.raises(SkinnyInputError, match=match):
        load(**args)


@pytest.mark.parametrize("actuation", ["velocity", "torque"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_non_finite_action_is_refused_before_mujoco(actuation, bad):
    env = load(body.body_of(4).twin(actuation), trajectory=stand_in(4), seed=0)
    env.reset()
    before = env.physics.data.qpos.copy()
    with pytest.raises(ValueError, match=r"action \(2,\) is .*must be finite"):
        env.step([0.1, 0.0, bad, 0.0])
    np.testing.assert_array_equal(env.physics.data.qpos, before)  # nothing stepped
    env.step([2.0, -2.0, 0.0, 0.0])  # a finite value outside [-1, 1] is clipped, no error


@pytest.mark.parametrize("name", ["ym", "ymca@0.5", "babble:seed=3,duration=4",
                                  "set:ym+babble:duration=2", "md_03.amc@start=1,duration=1"])
def test_skinny_mj_load_takes_every_name_the_command_line_takes(name):
    env = skinny_mj.load(4, trajectory=name)
    np.testing.assert_array_equal(env.task.setup.angles, load_movement(name, 4)[0].angles)


@pytest.mark.parametrize("trajectory,match", [
    ("nope", "unknown movement 'nope'"), ("ymca@", "no speed after '@'"),
    ("", "empty movement name"), (3, "trajectory must be a movement name or file"),
    (np.zeros((10, 3)), "3 columns"),
])
def test_skinny_mj_load_refuses_a_bad_movement_in_one_error(trajectory, match):
    with pytest.raises(SkinnyInputError, match=match):
        skinny_mj.load(4, trajectory=trajectory)
