"""The "cartesian-elbow" signals: the Cartesian segment directions with each arm's elbow
angle appended, their Jacobian, and the plants' agreement with the body's kinematics."""

import numpy as np
import pytest

from skinny_mj.plant import body
from skinny_mj.plant.adapters import BatchPlant
from skinny_mj.training.config import TrainConfig
from skinny_mj.trajectories import get, load_movement


@pytest.mark.parametrize("dof", [4, 8])
def test_elbow_signals_are_the_cartesian_ones_then_the_elbow_angles(dof):
    rng = np.random.default_rng(dof)
    lo, hi = body.body_of(dof).joint_ranges().T
    q = rng.uniform(lo, hi, (5, dof))
    out = body.body_of(dof).position_signals(q, "cartesian-elbow")
    cart = body.body_of(dof).position_signals(q, "cartesian")
    names = body.body_of(dof).signal_names("cartesian-elbow")
    assert names[:cart.shape[1]] == body.body_of(dof).signal_names("cartesian")
    assert names[cart.shape[1]:] == ("right_elbow_flexion", "left_elbow_flexion")
    assert out.shape == (5, len(names)) == (5, cart.shape[1] + 2)
    np.testing.assert_array_equal(out[:, :-2], cart)
    elbows = [body.body_of(dof).dof_names.index(n) for n in names[-2:]]
    np.testing.assert_allclose(out[:, -2:], body.body_of(dof).normalize_angles(q)[:, elbows])
    q[:, elbows] = lo[elbows]  # arm straight: the elbow signal sits at -1
    np.testing.assert_allclose(
        body.body_of(dof).position_signals(q, "cartesian-elbow")[:, -2:], -1.0)


@pytest.mark.parametrize("dof", [4, 8])
def test_elbow_signal_jacobian_matches_finite_differences(dof):
    rng = np.random.default_rng(20 + dof)
    lo, hi = body.body_of(dof).joint_ranges().T
    q = rng.uniform(lo + 0.1, hi - 0.1)
    jac = body.body_of(dof).signal_jacobian(q, "cartesian-elbow")
    eps = 1e-6
    skinny = body.body_of(dof)
    fd = np.stack([(skinny.position_signals(q + eps * e, "cartesian-elbow")
                    - skinny.position_signals(q - eps * e, "cartesian-elbow")) / (2 * eps)
                   for e in np.eye(dof)], axis=-1)
    np.testing.assert_allclose(jac, fd, atol=1e-8)
    if dof == 8:  # the straight arm: the segments lose the upper arm's rotation
        q[[3, 7]] = 0.0
        assert np.linalg.matrix_rank(body.body_of(dof).signal_jacobian(q, "cartesian")[:6, :4],
                                     tol=1e-9) == 3


@pytest.mark.parametrize("dof", [4, 8])
def test_batch_plant_senses_and_differentiates_the_elbow_signals(dof):
    traj = load_movement("babble:seed=0,duration=1", dof)[0]
    plant = BatchPlant(dof, "cartesian-elbow", traj, n_runs=2, sensor_noise=0.0)
    sensed = plant.reset()
    for _ in range(10):
        sensed = plant.step(np.full((2, dof), 0.4))
    q = plant.joint_angles()
    assert sensed.shape == (2, body.body_of(dof).n_signals("cartesian-elbow"))
    np.testing.assert_allclose(sensed, body.body_of(dof).position_signals(q, "cartesian-elbow"),
                               atol=1e-12)
    np.testing.assert_allclose(
        plant.command_jacobian() / (plant.max_speed_rad_s * plant.dt),
        body.body_of(dof).signal_jacobian(q, "cartesian-elbow"), atol=1e-12)


def test_a_new_signal_set_is_one_entry_of_the_table(monkeypatch):
    """An entry of body.SIGNAL_SETS alone (here every hinge's angle after the Cartesian
    signals) gives the names, the signals and the Jacobian of the body, the batch plant
    and the dm_control physics alike."""
    from skinny_mj.plant.physics import SkinnyPhysics

    dof, name = 4, "cartesian-joints"
    monkeypatch.setitem(body.SIGNAL_SETS, name, body.SignalSet("cartesian",
                                                               lambda b: np.arange(b.dof)))
    names = body.body_of(dof).signal_names(name)
    assert names == body.body_of(dof).signal_names("cartesian") + body.body_of(dof).dof_names
    plant = BatchPlant(dof, name, get("ymca", dof), n_runs=2, sensor_noise=0.0)
    plant.reset()
    sensed = plant.step(np.full((2, dof), 0.4))
    q = plant.joint_angles()
    want = body.body_of(dof).position_signals(q, name)
    assert want.shape == (2, len(names))
    np.testing.assert_allclose(sensed, want, atol=1e-12)
    np.testing.assert_array_equal(want[:, -dof:], body.body_of(dof).normalize_angles(q))
    jac = body.body_of(dof).signal_jacobian(q, name)
    np.testing.assert_allclose(plant.command_jacobian() / (plant.max_speed_rad_s * plant.dt),
                               jac, atol=1e-12)
    physics = SkinnyPhysics.load(dof)
    physics.set_joint_angles(q[0])
    np.testing.assert_allclose(physics.position_signals(name), want[0], atol=1e-12)
    np.testing.assert_allclose(physics.signal_jacobian(name), jac[0], atol=1e-12)


def test_training_config_takes_the_elbow_signals():
    cfg = TrainConfig().override({"plant.signals": "cartesian-elbow", "plant.dof": 8})
    assert cfg.plant.signals == "cartesian-elbow"


@pytest.mark.parametrize("dof", [4, 8])
def test_elbow_signal_is_the_angle_between_the_cartesian_segments(dof):
    """The elbow angle adds no information a Cartesian target lacks: it is the angle
    between the upper arm's and the forearm's directions (the elbow hinge is
    perpendicular to the upper arm and bends 0 to at most 180°)."""
    rng = np.random.default_rng(30 + dof)
    lo, hi = body.body_of(dof).joint_ranges().T
    q = rng.uniform(lo, hi, (50, dof))
    seg = body.body_of(dof).segment_vectors(q)  # (50, arm, segment, 3)
    unit = seg / np.linalg.norm(seg, axis=-1, keepdims=True)
    bend = np.arccos(np.clip(np.sum(unit[..., 0, :] * unit[..., 1, :], axis=-1), -1, 1))
    np.testing.assert_allclose(q[:, body.body_of(dof).elbow_dofs()], bend, atol=1e-7)
