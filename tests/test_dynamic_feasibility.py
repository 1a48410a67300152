"""What a movement asks of the torque twin's motors (``Dynamics.feasibility``,
``skinny trajectory show --actuation torque``)."""

from __future__ import annotations

import numpy as np

from skinny_mj.cli.parser import main
from skinny_mj.plant.path_dynamics import torque_dynamics
from skinny_mj.training import torque as torque_training
from skinny_mj.trajectories import get


def test_feasibility_figures_follow_the_step_torques():
    traj = get("ymca", 4)
    f = torque_training.feasibility(4, traj)
    tau = torque_dynamics(4).trajectory_torques_nm(traj.angles, traj.dt)
    limit = torque_training.torque_limits_nm(4)
    np.testing.assert_allclose(f["peak_ratio"], np.abs(tau).max(axis=0) / limit)
    np.testing.assert_allclose(f["mean_abs_nm"], np.abs(tau).mean(axis=0))
    work = np.maximum(tau * np.diff(traj.angles, axis=0), 0).sum(axis=0)
    np.testing.assert_allclose(f["work_j"], work)
    assert np.all(f["p99_ratio"] <= f["peak_ratio"]) and np.all(f["mean_ratio"] <= f["p99_ratio"])
    assert bool(f["feasible"]) and np.all(f["over_limit_share"] == 0)


def test_a_fast_movement_is_infeasible():
    # YMCA at 3x speed needs about 9x the accelerations: beyond the shoulders' motors
    f = torque_training.feasibility(4, get("ymca", 4).resample(3.0))
    assert not bool(f["feasible"])
    assert f["over_limit_share"].max() > 0 and f["peak_ratio"].max() > 1


def test_show_prints_the_torques(capsys):
    assert main(["trajectory", "show", "ymca", "--actuation", "torque"]) == 0
    out = capsys.readouterr().out
    assert "right_shoulder_abduction" in out and "-> feasible" in out


def test_arm_state_matches_the_one_robot_dynamics():
    # the plant side of the textbook laws: each robot's M(q), bias and gravity as the
    # one-robot Dynamics computes them, in a lockstep batch of two
    from skinny_mj.plant.adapters import BatchPlant
    from skinny_mj.plant.dynamics import BatchArmState

    traj = get("ymca", 8)
    plant = BatchPlant("3d-torque", "joint", traj, n_runs=2, sensor_noise=0.0)
    plant.reset()
    plant.step(np.full((2, 8), 0.3))
    state = BatchArmState(plant, gravity=True)(plant.true_signals())
    dyn = torque_dynamics(8)
    for r in range(2):
        q, qd = plant.joint_angles()[r], plant.joint_velocities()[r]
        np.testing.assert_allclose(state.mass[r], dyn.mass_matrix(q), atol=1e-12)
        np.testing.assert_allclose(state.gravity[r], dyn.gravity_torque_nm(q), atol=1e-9)
        np.testing.assert_allclose(state.bias[r], dyn.bias_torque_nm(q, qd), atol=1e-9)
    np.testing.assert_allclose(state.q, plant.joint_angles(), atol=1e-12)


def test_computed_torque_tracks_ymca_within_its_need():
    # the textbook law at 50 Hz tracks the feasible YMCA closely with about the torque
    # the movement needs, and never at the limit
    from skinny_mj.training.loop import TrainConfig, train

    o = train(TrainConfig().override(actuation="torque", method="none", test__gain=1.0,
                                        actuation__feedback="ct"))
    tq = o.test.torque_figures
    need = torque_training.feasibility(4, o.test.trajectory)["mean_abs_nm"].mean()
    assert o.test.position_nrmse < 0.02
    assert tq["mean_abs_torque_nm"] < 1.5 * need and tq["max_commanded_ratio"] < 1.0


def test_a_perturbed_plant_is_controlled_with_the_nominal_model():
    # robustness rows: the controllers' M(q) and bias come from the nominal twin at the
    # plant's state; on an unchanged plant that is the plant's own, on a heavier one not
    from skinny_mj.plant.adapters import BatchPlant
    from skinny_mj.plant.dynamics import BatchArmState

    plant = BatchPlant("2d-torque", "joint", get("ymca", 4), n_runs=2, sensor_noise=0.0)
    plant.reset()
    plant.step(np.full((2, 4), 0.4))
    own, nominal = BatchArmState(plant)(plant.true_signals()), \
        BatchArmState(plant, nominal=True)(plant.true_signals())
    np.testing.assert_allclose(nominal.mass, own.mass, atol=1e-12)
    np.testing.assert_allclose(nominal.bias, own.bias, atol=1e-9)
    torque_training.perturb(plant, mass_scale=1.2)
    plant.step(np.zeros((2, 4)))
    own, nominal = BatchArmState(plant)(plant.true_signals()), \
        BatchArmState(plant, nominal=True)(plant.true_signals())
    np.testing.assert_allclose(own.mass, 1.2 * nominal.mass, rtol=1e-9)
