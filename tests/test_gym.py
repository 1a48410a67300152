"""The Gymnasium adapter: registration, ``check_env`` on every id, seeding, and the
lockstep vector env against Gymnasium's own ``SyncVectorEnv`` of single envs."""

from __future__ import annotations

import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402

import skinny_mj.gym  # noqa: E402  (registers the ids)
from skinny_mj.errors import SkinnyInputError  # noqa: E402
from skinny_mj.gym import IDS  # noqa: E402
from skinny_mj.gym.env import SkinnyEnv  # noqa: E402
from skinny_mj.gym.vector import SkinnyVectorEnv  # noqa: E402
from skinny_mj.plant.body import body_of  # noqa: E402
from skinny_mj.trajectories import get  # noqa: E402

VELOCITY_IDS = [i for i, kw in IDS.items() if body_of(kw["body"]).actuation == "velocity"]
TORQUE_IDS = [i for i, kw in IDS.items() if body_of(kw["body"]).actuation == "torque"]
# The only warnings check_env may give: the sensed signals carry Gaussian noise, so
# their Box is unbounded (as Gymnasium's own MuJoCo envs' observations are).
UNBOUNDED = ("observation space minimum value is -infinity",
             "observation space maximum value is infinity")


def test_importing_skinny_mj_does_not_import_gymnasium():
    code = (
        "import sys, skinny_mj, skinny_mj.plant.task, skinny_mj.plant.adapters, "
        "skinny_mj.training.loop; "
        "skinny_mj.load(4); assert 'gymnasium' not in sys.modules, 'gymnasium imported'"
    )
    env = dict(os.environ, MUJOCO_GL="disabled")
    subprocess.run([sys.executable, "-c", code], check=True, env=env)


def test_ids_are_registered_with_both_entry_points():
    for env_id, kwargs in IDS.items():
        spec = gymnasium.spec(env_id)
        assert spec.kwargs == {"env_id": env_id, **kwargs}
        assert spec.max_episode_steps == len(get("ymca", kwargs["body"])) - 1  # YMCA's
        assert spec.entry_point == "skinny_mj.gym.env:SkinnyEnv"
        assert spec.vector_entry_point == "skinny_mj.gym.vector:SkinnyVectorEnv"
    skinny_mj.gym.register()  # a second registration is a no-op, not a warning


@pytest.mark.parametrize("env_id", list(IDS))
def test_check_env_passes(env_id):
    env = gymnasium.make(env_id)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped, skip_render_check=True)  # the suite has no OpenGL
    messages = [str(w.message) for w in caught]
    assert all(any(u in m for u in UNBOUNDED) for m in messages), messages
    dof = body_of(IDS[env_id]["body"]).dof
    assert env.action_space.shape == (dof,)
    assert env.observation_space.shape == (3 * env.unwrapped.setup.desired.shape[1],)


def test_check_env_with_rendering_in_a_fresh_process():
    """Rendering needs OpenGL chosen before mujoco is imported: EGL, in a subprocess."""
    code = f"""
import sys, warnings
try:
    import skinny_mj
    env = skinny_mj.load(4)
    env.reset()
    env.physics.render(8, 8)
except Exception as exc:
    print("no EGL:", exc)
    sys.exit(77)
import gymnasium, skinny_mj.gym
from gymnasium.utils.env_checker import check_env
for env_id in {list(IDS)!r}:
    check_env(gymnasium.make(env_id, render_mode="rgb_array").unwrapped)
    frame = gymnasium.make(env_id, render_mode="rgb_array", width=64, height=48)
    frame.reset(seed=0)
    assert frame.render().shape == (48, 64, 3)
"""
    env = dict(os.environ, MUJOCO_GL="egl")
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True)
    if done.returncode == 77:
        pytest.skip(done.stdout.strip())
    assert done.returncode == 0, done.stderr[-2000:]


def _episode(env, seed, actions):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for a in actions:
        obs, reward, terminated, truncated, _ = env.step(a)
        out.append(np.append(obs, reward))
    return out


@pytest.mark.parametrize("env_id", ["SkinnyMJ/Skinny2D-v0", "SkinnyMJ/Skinny3D-Torque-v0"])
def test_reset_seed_is_reproducible_and_means_the_task_seed(env_id):
    env = gymnasium.make(env_id)
    dof = body_of(IDS[env_id]["body"]).dof
    actions = np.random.default_rng(0).uniform(-0.3, 0.3, (25, dof))
    a, b, c = (_episode(env, s, actions) for s in (7, 7, 8))
    for x, y, z in zip(a, b, c, strict=True):
        np.testing.assert_array_equal(x, y)
        n = env.unwrapped.setup.desired.shape[1]
        assert np.abs(x[:n] - z[:n]).max() > 0  # other seed, other sensor noise
        np.testing.assert_array_equal(x[n:3 * n], z[n:3 * n])  # same movement
    # reset(seed=s) is skinny_mj.load(..., seed=s); reset() continues the stream
    dm = skinny_mj.load(IDS[env_id]["body"], seed=7)
    for episode in range(2):
        obs, _ = env.reset(seed=7 if episode == 0 else None)
        ts = dm.reset()
        np.testing.assert_array_equal(obs[:n], ts.observation["sensed"])
        for action in actions[:5]:
            obs, reward, *_ = env.step(action)
            ts = dm.step(action)
            np.testing.assert_array_equal(obs[:n], ts.observation["sensed"])
            assert reward == ts.reward


def test_episode_ends_truncated_and_refuses_to_go_on():
    env = SkinnyEnv(4)
    env.reset(seed=0)
    flags = [env.step(np.zeros(4))[2:4] for _ in range(env.n_steps)]
    assert flags[-1] == (False, True)
    assert all(f == (False, False) for f in flags[:-1])
    with pytest.raises(RuntimeError):
        env.step(np.zeros(4))
    assert env.reset()[0].shape == env.observation_space.shape


def _lockstep_vs_sync(env_id, n, steps, seed=5):
    vector = gymnasium.make_vec(env_id, num_envs=n)  # the registered vector entry point
    sync = gymnasium.make_vec(env_id, num_envs=n, vectorization_mode="sync")
    assert isinstance(vector.unwrapped, SkinnyVectorEnv)
    assert isinstance(sync, gymnasium.vector.SyncVectorEnv)
    assert sync.metadata["autoreset_mode"] == vector.metadata["autoreset_mode"] \
        == gymnasium.vector.AutoresetMode.NEXT_STEP
    assert vector.single_observation_space == sync.single_observation_space
    assert vector.single_action_space == sync.single_action_space
    rng = np.random.default_rng(0)
    got, want = [vector.reset(seed=seed)[0]], [sync.reset(seed=seed)[0]]
    for _ in range(steps):
        # random actions, a few beyond the box (both clip them the same way)
        a = rng.uniform(-1.2, 1.2, (n, vector.single_action_space.shape[0]))
        got.append(vector.step(a)[:4])
        want.append(sync.step(a)[:4])
    return vector.unwrapped, got, want


@pytest.mark.parametrize("env_id", VELOCITY_IDS)
def test_vector_env_equals_single_envs_bit_for_bit(env_id):
    """N = 4 robots in one MuJoCo model == N SkinnyEnv with seeds 5..8, through two
    whole episodes, the autoreset step between them and the start of a third."""
    n = 4
    probe = gymnasium.make_vec(env_id, num_envs=n).unwrapped
    steps = 2 * (probe.n_steps + 1) + 3
    vector, got, want = _lockstep_vs_sync(env_id, n, steps)
    np.testing.assert_array_equal(got[0], want[0])
    for k, (g, w) in enumerate(zip(got[1:], want[1:], strict=True), start=1):
        for name, x, y in zip(("obs", "reward", "terminated", "truncated"), g, w, strict=True):
            np.testing.assert_array_equal(x, y, err_msg=f"{name} at step {k}")
            assert x.dtype == y.dtype, name
        assert g[0] in vector.observation_space
    # NEXT_STEP autoreset, as Gymnasium 1.x defines it: truncated on the last step of
    # the movement; the next step ignores the actions and returns the first observation
    end = vector.n_steps
    desired = vector.setup.desired
    n_sig = desired.shape[1]
    for last in (end, 2 * end + 1):
        assert got[last][3].all() and not got[last][2].any()
        assert not any(got[k][3].any() for k in range(last - end + 1, last))
        obs, reward, terminated, truncated = got[last + 1]
        assert (reward == 0).all() and not terminated.any() and not truncated.any()
        np.testing.assert_array_equal(obs[:, n_sig:2 * n_sig], np.broadcast_to(desired[0],
                                                                               (n, n_sig)))


@pytest.mark.parametrize("env_id", TORQUE_IDS)
def test_torque_vector_env_equals_single_envs(env_id):
    """One robot in the batch model: bit for bit. Several: MuJoCo solves their
    joint-limit constraints island by island (one robot's in one piece), so the states
    agree to rounding, which the chaotic swings then grow (measured 1.9e-6 after two
    YMCA episodes of random torques); the noise, the movement and the flags stay exact."""
    steps = gymnasium.make_vec(env_id, num_envs=1).unwrapped.n_steps + 3
    _, got, want = _lockstep_vs_sync(env_id, 1, steps)
    for g, w in zip(got[1:], want[1:], strict=True):
        for x, y in zip(g, w, strict=True):
            np.testing.assert_array_equal(x, y)
    vector, got, want = _lockstep_vs_sync(env_id, 3, steps)
    n_sig = vector.setup.desired.shape[1]
    for g, w in zip(got[1:], want[1:], strict=True):
        np.testing.assert_array_equal(g[0][:, n_sig:], w[0][:, n_sig:])  # the movement
        np.testing.assert_allclose(g[0], w[0], rtol=0, atol=1e-4)
        np.testing.assert_allclose(g[1], w[1], rtol=0, atol=1e-4)
        np.testing.assert_array_equal(g[2], w[2])
        np.testing.assert_array_equal(g[3], w[3])


def test_vector_env_seeding_and_refusals():
    envs = SkinnyVectorEnv(3, body="2d", trajectory="y")
    actions = np.random.default_rng(1).uniform(-1, 1, (10, 3, 4))

    def run(seed):
        out = [envs.reset(seed=seed)[0]]
        out += [envs.step(a)[0] for a in actions]
        return np.stack(out)

    first = run(3)
    np.testing.assert_array_equal(run(3), first)  # reseeding rebuilds the same streams
    np.testing.assert_array_equal(run([3, 4, 5]), first)  # int s == [s, s + 1, ...]
    other = run([3, 4, 6])
    np.testing.assert_array_equal(other[:, :2], first[:, :2])
    assert np.abs(other[:, 2] - first[:, 2]).max() > 0
    # no seed: the constructor's seed, then the streams go on
    fresh = SkinnyVectorEnv(3, body="2d", trajectory="y", seed=3)
    np.testing.assert_array_equal(fresh.reset()[0], first[0])
    assert not np.array_equal(fresh.reset()[0], first[0])
    with pytest.raises(ValueError):
        envs.reset(options={"reset_mask": np.array([True, False, True])})
    envs.reset(options={"reset_mask": np.ones(3, bool)})
    with pytest.raises(ValueError):
        envs.reset(seed=[1, None, 2])
    with pytest.raises(RuntimeError):
        SkinnyVectorEnv(2).step(np.zeros((2, 4)))


def test_a_diverging_robot_raises_in_the_vector_env_as_in_a_single_env():
    """MuJoCo resets the whole model when one robot diverges and only logs it; the
    vector env raises dm_control's PhysicsError instead, as the single env does."""
    from dm_control.rl.control import PhysicsError

    single = SkinnyEnv(4)
    single.reset(seed=0)
    single.dm_control_env.physics.data.qvel[0] = 1e11  # beyond mjMAXVAL: diverged
    with pytest.raises(PhysicsError):
        single.step(np.zeros(4))
    with pytest.raises(RuntimeError):
        single.step(np.zeros(4))
    envs = SkinnyVectorEnv(3, body="2d")
    envs.reset(seed=0)
    envs.step(np.zeros((3, 4)))
    envs.plant.data.qvel[envs.plant.model.nv // 3] = 1e11  # robot 1 of 3
    with pytest.raises(PhysicsError):
        envs.step(np.zeros((3, 4)))
    with pytest.raises(RuntimeError):
        envs.step(np.zeros((3, 4)))
    envs.reset(seed=0)  # clears MuJoCo's warnings: stepping works again
    assert np.isfinite(envs.step(np.zeros((3, 4)))[0]).all()


@pytest.mark.parametrize("env_id,kwargs,says", [
    ("SkinnyMJ/Skinny2D-v0", {"body": "3d"},
     "has body='2d', got body='3d': use SkinnyMJ/Skinny3D-v0"),
    ("SkinnyMJ/Skinny3D-v0", {"body": 4}, "has body='3d', got body='2d': use SkinnyMJ/Skinny2D-v0"),
    ("SkinnyMJ/Skinny2D-v0", {"body": "2d-torque"}, "use SkinnyMJ/Skinny2D-Torque-v0"),
    ("SkinnyMJ/Skinny2D-v0", {"dof": 8}, "unexpected keyword argument 'dof'; the task takes body"),
    ("SkinnyMJ/Skinny2D-v0", {"trajectory": "nope"}, "unknown movement 'nope'"),
    ("SkinnyMJ/Skinny2D-v0", {"trajectory": 3}, "trajectory must be a movement name"),
])
def test_make_refuses_what_contradicts_the_id_or_names_nothing(env_id, kwargs, says):
    with pytest.raises(SkinnyInputError, match=says.replace("(", r"\(")):
        gymnasium.make(env_id, **kwargs)
    with pytest.raises(SkinnyInputError, match=says.replace("(", r"\(")):
        gymnasium.make_vec(env_id, num_envs=2, **kwargs)


def test_make_takes_every_movement_name_and_limits_episodes_to_the_ids():
    env = gymnasium.make("SkinnyMJ/Skinny2D-v0", trajectory="ym@1.5")
    assert env.unwrapped.n_steps < skinny_mj.gym.MAX_EPISODE_STEPS  # plays to its end
    with pytest.warns(UserWarning, match="max_episode_steps=312 of the movement's 467"):
        gymnasium.make("SkinnyMJ/Skinny2D-v0", trajectory="md_02.amc")
    whole = gymnasium.make("SkinnyMJ/Skinny2D-v0", trajectory="md_02.amc",
                           max_episode_steps=467)
    assert whole.spec.max_episode_steps == 467
    vector = gymnasium.make_vec("SkinnyMJ/Skinny2D-v0", num_envs=2, max_episode_steps=10)
    vector.reset(seed=0)
    flags = [vector.step(np.zeros((2, 4)))[3] for _ in range(10)]
    assert not flags[8].any() and flags[9].all()  # truncated at the limit, as TimeLimit
