"""Plant adapters: BatchPlant run r == EnvPlant(seed r), and the command Jacobian."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import pytest

from skinny_mj.plant import body
from skinny_mj.plant.adapters import BatchPlant, EnvPlant, Plant
from skinny_mj.plant.task import load


@dataclass(frozen=True)
class StandIn:
    angles: np.ndarray
    dof: int
    dt: float = 0.02


def stand_in(dof: int, n: int = 30) -> StandIn:
    t = np.linspace(0.0, 1.0, n)[:, None]
    lo, hi = body.body_of(dof).joint_ranges().T
    return StandIn(lo + (hi - lo) * (0.5 + 0.4 * np.sin(2 * np.pi * t + np.arange(dof))), dof)


@pytest.mark.parametrize("dof,signals,actuation", [
    (4, "cartesian", "velocity"), (4, "joint", "velocity"),
    (8, "cartesian", "velocity"), (8, "joint", "torque"),
])
def test_batch_plant_equals_env_plants(dof, signals, actuation):
    traj = stand_in(dof)
    seeds = [11, 12, 13]
    skinny = body.body_of(dof).twin(actuation)
    batch = BatchPlant(skinny, signals, traj, n_runs=3, seeds=seeds, sensor_noise=0.01)
    envs = [EnvPlant(load(skinny, signals, traj, 0.01, seed=s)) for s in seeds]
    assert isinstance(batch, Plant) and isinstance(envs[0], Plant)
    # Same operations, same bits. The torque twin runs into its soft joint limits, and
    # MuJoCo solves a batch model's constraints island by island but a one-robot
    # model's in one piece: equal up to rounding there (measured 4e-16), not bitwise.
    atol = 0.0 if actuation == "velocity" else 1e-12
    rng = np.random.default_rng(0)
    for _episode in range(2):  # the second reset continues each run's noise stream
        a = batch.reset()
        b = np.concatenate([e.reset() for e in envs])
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
        for _ in range(len(traj.angles) - 1):
            u = rng.uniform(-1.2, 1.2, (3, dof))
            a = batch.step(u)
            b = np.concatenate([e.step(u[r : r + 1]) for r, e in enumerate(envs)])
            np.testing.assert_allclose(a, b, rtol=0, atol=atol)
        for name in ("true_signals", "joint_angles", "command_jacobian"):
            got = getattr(batch, name)()
            want = np.concatenate([getattr(e, name)() for e in envs])
            np.testing.assert_allclose(got, want, rtol=0, atol=atol)
    assert a.shape == (3, batch.n_signals)
    assert batch.command_jacobian().shape == (3, batch.n_signals, dof)


@pytest.mark.parametrize("dof", [4, 8])
def test_command_jacobian_predicts_a_small_step(dof):
    plant = BatchPlant(dof, "cartesian", stand_in(dof), n_runs=1, sensor_noise=0.0,
                       max_speed_rad_s=3.0)  # small steps that stay inside the ranges
    plant.reset()
    for _ in range(5):
        plant.step(np.full((1, dof), 0.3))
    jac = plant.command_jacobian()[0]
    before = plant.true_signals()[0]
    command = np.full(dof, 0.3) + np.random.default_rng(1).uniform(-0.02, 0.02, dof)
    after = plant.step(command[None])[0]
    predicted = jac @ command
    # first-order in the step (0.3 of full scale) plus ~1 % servo lag
    assert np.abs(after - before - predicted).max() < 0.1 * np.abs(predicted).max()
    assert np.abs(after - before - predicted).max() < 0.01


def test_sensed_minus_true_is_the_noise():
    plant = BatchPlant(4, "joint", stand_in(4), n_runs=2, seeds=[0, 0], sensor_noise=0.02)
    sensed = plant.reset()
    np.testing.assert_array_equal(sensed[0], sensed[1])  # same seed, same stream
    noise = sensed - plant.true_signals()
    expected = np.random.default_rng(0).standard_normal(4) * 0.02
    np.testing.assert_allclose(noise[0], expected, atol=1e-12)


def test_env_plant_refuses_to_step_past_the_episode():
    traj = stand_in(4, n=4)
    plant = EnvPlant(load(4, trajectory=traj))
    with pytest.raises(RuntimeError):
        plant.step(np.zeros((1, 4)))
    plant.reset()
    for _ in range(3):
        plant.step(np.zeros((1, 4)))
    with pytest.raises(RuntimeError):
        plant.step(np.zeros((1, 4)))
    assert plant.reset().shape == (1, plant.n_signals)


def test_batch_plant_rejects_wrong_seed_count():
    with pytest.raises(ValueError):
        BatchPlant(4, "joint", stand_in(4), n_runs=2, seeds=[1])


@pytest.mark.parametrize("dof,actuation", [(4, "velocity"), (8, "torque")])
def test_batch_model_copies_are_the_one_robot_model(dof, actuation):
    """Every copy in the batch model has the one-robot model's numbers (bodies, joints,
    dofs, sites, actuators, options): the (R, ...) views and the bitwise equality of
    the fast path rest on it."""
    from skinny_mj.plant.model import load_batch_model, load_model

    skinny = body.body_of(dof).twin(actuation)
    one, batch = load_model(skinny), load_batch_model(skinny, 3)
    compared = 0
    for prefix, world in (("body_", 1), ("jnt_", 0), ("dof_", 0), ("site_", 0),
                          ("actuator_", 0)):
        for name in dir(one):
            want = getattr(one, name)
            if not name.startswith(prefix) or not isinstance(want, np.ndarray) \
                    or want.size == 0:
                continue
            # ids and addresses are offset by the copy (and by the scene's floor geom)
            if name.endswith(("adr", "id")) or name == "body_weldid":
                continue
            got = getattr(batch, name)[world:].reshape(3, *want[world:].shape)
            for r in range(3):
                np.testing.assert_array_equal(got[r], want[world:], err_msg=name)
            compared += 1
    assert compared > 40
    for field in ("timestep", "integrator", "gravity", "disableflags"):
        np.testing.assert_array_equal(getattr(batch.opt, field), getattr(one.opt, field))
    # the constraint Jacobian one robot's "auto" resolves to (dense below nv = 60)
    assert one.opt.jacobian == mujoco.mjtJacobian.mjJAC_AUTO and one.nv < 60
    assert batch.opt.jacobian == mujoco.mjtJacobian.mjJAC_DENSE
    assert batch.ngeom == 3 * (one.ngeom - 1)  # no floor, nothing to collide with
    assert not batch.geom_contype.any() and not batch.geom_conaffinity.any()


def test_torque_copy_is_the_robot_alone_in_a_large_batch():
    """8 3D torque robots (nv = 64, where MuJoCo's automatic choice would turn sparse)
    pressing into their joint limits: copy 0 is bit for bit the one-robot batch."""
    traj = stand_in(8)
    rng = np.random.default_rng(3)
    commands = rng.uniform(-1.0, 1.0, (40, 8, 8))
    plants = [BatchPlant("3d-torque", "cartesian", traj, n_runs=n, seeds=range(n))
              for n in (1, 8)]
    for p in plants:
        p.reset()
    pressed = 0
    for u in commands:
        alone, batch = (p.step(u[:p.n_runs]) for p in plants)
        np.testing.assert_array_equal(batch[0], alone[0])
        np.testing.assert_array_equal(plants[1].joint_angles()[0], plants[0].joint_angles()[0])
        pressed += plants[0].data.nefc > 0
    assert pressed > 10  # the limits were in play
