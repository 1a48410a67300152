"""What a movement asks of the torque twin's motors (``Dynamics.feasibility``,
``skinny trajectory show --actuation torque``)."""

from __future__ import annotations

import numpy as np

from skinny_mj import torque_training
from skinny_mj.cli import main
from skinny_mj.trajectories import get


def test_feasibility_figures_follow_the_step_torques():
    traj = get("ymca", 4)
    f = torque_training.feasibility(4, traj)
    tau = torque_training._dynamics(4).trajectory_torques_nm(traj.angles, traj.dt)
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
