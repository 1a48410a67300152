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
    lo, hi = body.joint_ranges(dof).T
    q = rng.uniform(lo, hi, (5, dof))
    out = body.position_signals(q, dof, "cartesian-elbow")
    cart = body.position_signals(q, dof, "cartesian")
    names = body.signal_names(dof, "cartesian-elbow")
    assert names[:cart.shape[1]] == body.signal_names(dof, "cartesian")
    assert names[cart.shape[1]:] == ("right_elbow_flexion", "left_elbow_flexion")
    assert out.shape == (5, len(names)) == (5, cart.shape[1] + 2)
    np.testing.assert_array_equal(out[:, :-2], cart)
    elbows = [body.dof_names(dof).index(n) for n in names[-2:]]
    np.testing.assert_allclose(out[:, -2:], body.normalize_angles(q, dof)[:, elbows])
    q[:, elbows] = lo[elbows]  # arm straight: the elbow signal sits at -1
    np.testing.assert_allclose(body.position_signals(q, dof, "cartesian-elbow")[:, -2:], -1.0)


@pytest.mark.parametrize("dof", [4, 8])
def test_elbow_signal_jacobian_matches_finite_differences(dof):
    rng = np.random.default_rng(20 + dof)
    lo, hi = body.joint_ranges(dof).T
    q = rng.uniform(lo + 0.1, hi - 0.1)
    jac = body.signal_jacobian(q, dof, "cartesian-elbow")
    eps = 1e-6
    fd = np.stack([(body.position_signals(q + eps * e, dof, "cartesian-elbow")
                    - body.position_signals(q - eps * e, dof, "cartesian-elbow")) / (2 * eps)
                   for e in np.eye(dof)], axis=-1)
    np.testing.assert_allclose(jac, fd, atol=1e-8)
    if dof == 8:  # the straight arm: the segments lose the upper arm's rotation
        q[[3, 7]] = 0.0
        assert np.linalg.matrix_rank(body.signal_jacobian(q, dof, "cartesian")[:6, :4],
                                     tol=1e-9) == 3


@pytest.mark.parametrize("dof", [4, 8])
def test_batch_plant_senses_and_differentiates_the_elbow_signals(dof):
    traj = load_movement("babble:seed=0,duration=1", dof)[0]
    plant = BatchPlant(dof, "cartesian-elbow", traj, n_runs=2, sensor_noise=0.0)
    sensed = plant.reset()
    for _ in range(10):
        sensed = plant.step(np.full((2, dof), 0.4))
    q = plant.joint_angles()
    assert sensed.shape == (2, body.n_signals(dof, "cartesian-elbow"))
    np.testing.assert_allclose(sensed, body.position_signals(q, dof, "cartesian-elbow"),
                               atol=1e-12)
    np.testing.assert_allclose(
        plant.command_jacobian() / (plant.max_speed_rad_s * plant.dt),
        body.signal_jacobian(q, dof, "cartesian-elbow"), atol=1e-12)


def test_a_new_signal_set_is_one_entry_of_the_table(monkeypatch):
    """An entry of body.SIGNAL_SETS alone (here every hinge's angle after the Cartesian
    signals) gives the names, the signals and the Jacobian of the body, the batch plant
    and the dm_control physics alike."""
    from skinny_mj.plant.physics import SkinnyPhysics

    dof, name = 4, "cartesian-joints"
    monkeypatch.setitem(body.SIGNAL_SETS, name, body.SignalSet("cartesian",
                                                               lambda d: np.arange(d)))
    names = body.signal_names(dof, name)
    assert names == body.signal_names(dof, "cartesian") + body.dof_names(dof)
    plant = BatchPlant(dof, name, get("ymca", dof), n_runs=2, sensor_noise=0.0)
    plant.reset()
    sensed = plant.step(np.full((2, dof), 0.4))
    q = plant.joint_angles()
    want = body.position_signals(q, dof, name)
    assert want.shape == (2, len(names))
    np.testing.assert_allclose(sensed, want, atol=1e-12)
    np.testing.assert_array_equal(want[:, -dof:], body.normalize_angles(q, dof))
    jac = body.signal_jacobian(q, dof, name)
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
    lo, hi = body.joint_ranges(dof).T
    q = rng.uniform(lo, hi, (50, dof))
    seg = body.segment_vectors(q, dof)  # (50, arm, segment, 3)
    unit = seg / np.linalg.norm(seg, axis=-1, keepdims=True)
    bend = np.arccos(np.clip(np.sum(unit[..., 0, :] * unit[..., 1, :], axis=-1), -1, 1))
    np.testing.assert_allclose(q[:, body.elbow_dofs(dof)], bend, atol=1e-7)
