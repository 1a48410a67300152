"""Movements made feasible for the torque twin: the uniform slow-down's speed
(:func:`skinny_mj.training.feasible.fastest_uniform_speed`, the dynamic study's
``FEASIBLE_SPEED``) and the local re-timing along the path (TOPP-RA, ``NAME@feasible``)."""

from __future__ import annotations

import numpy as np
import pytest

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.path_dynamics import (
    path_torque_terms,
    step_torque_ratio,
    torque_dynamics,
    velocity_limits_rad_s,
)
from skinny_mj.training import feasible
from skinny_mj.trajectories import get, load_movement
from skinny_mj.trajectories.retime import (
    PathTiming,
    back_on_path,
    path_grid,
    path_spline,
    resample,
    sample_times,
)

CLIPS = [(dof, clip) for dof in (4, 8) for clip in ("md_02.amc", "md_03.amc")]


@pytest.fixture(scope="module")
def md03_3d():
    traj = load_movement("md_03.amc", 8)[0]
    return traj, feasible.retime_movement(traj, 8)


# -- the path and its timing (no dynamics) ---------------------------------------------------
def test_the_shipped_timing_gives_the_movement_back():
    traj = get("ymca", 4)
    grid = path_grid(traj, 3)
    timing = PathTiming(grid, np.ones_like(grid))
    assert timing.duration == pytest.approx(traj.dt * (len(traj) - 1))
    np.testing.assert_allclose(resample(traj, timing).angles, traj.angles, atol=1e-12)
    half = PathTiming(grid, np.full_like(grid, 0.5))  # half speed: twice as long
    assert len(resample(traj, half)) == 2 * (len(traj) - 1) + 1
    np.testing.assert_allclose(resample(traj, half).angles, path_spline(traj)(
        0.5 * traj.dt * np.arange(2 * len(traj) - 1)), atol=1e-12)


def test_a_timing_is_exact_between_grid_points():
    # constant path acceleration: s(t) and s'(t) are a parabola and a line in each interval
    timing = PathTiming(np.array([0.0, 1.0, 2.0]), np.array([0.0, 1.0, 0.5]))
    assert timing.times.tolist() == [0.0, 2.0, 2.0 + 2.0 / 1.5]
    assert timing.path_position(1.0) == pytest.approx(0.25)  # s = t^2 / 4
    assert timing.path_speed(1.0) == pytest.approx(0.5)
    assert timing.path_position(timing.duration + 1) == 2.0
    with pytest.raises(SkinnyInputError, match="rest"):
        PathTiming(np.array([0.0, 1.0, 2.0]), np.array([0.0, 0.0, 1.0]))


# -- the plant side ------------------------------------------------------------------------
def test_the_path_torque_terms_add_up_to_mj_inverse():
    dyn = torque_dynamics(8)
    rng = np.random.default_rng(0)
    q, qs, qss = rng.normal(size=(3, 6, 8))
    a, b, c, d = path_torque_terms(dyn, q, qs, qss)
    for sd, sdd in ((1.0, 0.0), (0.3, -2.0), (0.05, 7.0)):
        direct = dyn.inverse_dynamics_nm(q, qs * sd, qs * sdd + qss * sd ** 2)
        np.testing.assert_allclose(a * sdd + b * sd ** 2 + c + d * sd, direct, atol=1e-9)
    np.testing.assert_allclose(c, dyn.gravity_torque_nm(q), atol=1e-9)
    assert np.all(velocity_limits_rad_s(8) == 30.0)


# -- the uniform slow-down -------------------------------------------------------------------
@pytest.mark.parametrize("dof,clip", CLIPS)
def test_the_study_feasible_speeds_are_the_fastest_uniform_speeds(dof, clip):
    # the dynamic study's declared speeds (kept as constants: its rows' results) are the
    # computation: feasible at and below them on the 0.01 grid, not one step above
    from skinny_mj.experiments.dynamic.general import FEASIBLE_SPEED

    traj = load_movement(clip, dof)[0]
    speed = feasible.fastest_uniform_speed(traj, dof)
    assert speed == FEASIBLE_SPEED[dof, clip]
    assert feasible.peak_torque_ratio(traj.resample(speed), dof) <= 1.0
    assert feasible.peak_torque_ratio(traj.resample(speed + 0.01), dof) > 1.0


def test_the_uniform_speed_is_taken_at_and_below():
    # the 3D md_02 fits at 0.48 but not at 0.46-0.47: 0.45 is the speed
    traj = load_movement("md_02.amc", 8)[0]
    assert feasible.peak_torque_ratio(traj.resample(0.48), 8) <= 1.0
    assert feasible.peak_torque_ratio(traj.resample(0.47), 8) > 1.0
    assert feasible.fastest_uniform_speed(traj, 8, stop=0.44) == 0.45


# -- the local re-timing -------------------------------------------------------------------
def test_retiming_keeps_the_path(md03_3d):
    traj, re = md03_3d
    back = back_on_path(re.trajectory, re.timing, traj)
    err = np.abs(back - traj.angles)
    assert err.max() < 0.02 and err.mean() < 1e-3  # rad: the cubic read-back's error
    s = re.timing.path_position(sample_times(re.timing, traj.dt))
    np.testing.assert_allclose(re.trajectory.angles, path_spline(traj)(s), atol=1e-12)
    assert np.all(np.diff(s) >= 0) and s[-1] == pytest.approx(traj.dt * (len(traj) - 1))
    np.testing.assert_allclose(re.trajectory.angles[[0, -1]], traj.angles[[0, -1]], atol=1e-12)


def test_retiming_respects_the_limits(md03_3d):
    traj, re = md03_3d
    assert feasible.peak_torque_ratio(traj, 8) > 2  # the clip as shipped: not at all
    ratio = step_torque_ratio(torque_dynamics(8), re.trajectory.angles, re.trajectory.dt)
    assert ratio.max() <= feasible.TORQUE_MARGIN == re.torque_margin == 0.9
    assert ratio.max() == pytest.approx(re.peak_torque_ratio)
    assert feasible.peak_speed_ratio(re.trajectory, 8) <= 1.0
    assert np.all(re.trajectory.max_speed_rad_s() <= velocity_limits_rad_s(8))
    assert np.all(re.timing.sd <= 1.0)  # never faster than shipped


@pytest.mark.parametrize("dof", [4, 8])
def test_retiming_is_never_slower_than_the_uniform_slow_down(dof, md03_3d):
    traj, re = md03_3d if dof == 8 else (None, None)
    if traj is None:
        traj = load_movement("md_03.amc", dof)[0]
        re = feasible.retime_movement(traj, dof)
    margin = feasible.TORQUE_MARGIN
    uniform = traj.resample(feasible.fastest_uniform_speed(traj, dof, limit_ratio=margin))
    assert len(re.trajectory) <= len(uniform)
    assert re.trajectory.duration_s < 0.5 * uniform.duration_s  # by far, on these clips
    assert 0.5 < re.full_speed_share() < 1.0


def test_retiming_is_deterministic(md03_3d):
    traj, re = md03_3d
    again = feasible.retime_movement(traj, 8)
    assert np.array_equal(again.trajectory.angles, re.trajectory.angles)
    assert np.array_equal(again.timing.sd, re.timing.sd)


def test_a_feasible_movement_keeps_its_speed():
    traj = get("ymca", 4)  # asks at most 0.45 of a limit
    re = feasible.retime_movement(traj, 4)
    assert re.full_speed_share() > 0.99
    assert abs(len(re.trajectory) - len(traj)) <= 2  # the start from rest: a step or two


def test_a_margin_no_pose_can_hold_is_refused():
    with pytest.raises(SkinnyInputError, match="any speed"):
        feasible.retime_movement(load_movement("md_03.amc", 4)[0], 4, torque_margin=0.1)
    with pytest.raises(SkinnyInputError, match="margin"):
        feasible.retime_movement(get("ymca", 4), 4, torque_margin=1.5)


# -- the movement name ---------------------------------------------------------------------
def test_the_feasible_suffix_loads_the_retimed_movement(md03_3d):
    traj, re = md03_3d
    named, report = feasible.load_movement("md_03.amc@feasible", 8)
    assert np.array_equal(named.angles, re.trajectory.angles)
    assert named.name.endswith("@feasible") and report.clipped_samples >= 0
    twice, _ = feasible.load_movement("md_03.amc@feasible", 8, reps=2)
    assert len(twice) == 2 * len(named)
    tighter, _ = feasible.load_movement("md_03.amc@feasible=0.8", 8)
    assert feasible.peak_torque_ratio(tighter, 8) <= 0.8 and len(tighter) >= len(named)
    assert feasible.split_feasible("md_02.amc@start=3,duration=6@feasible") == (
        "md_02.amc@start=3,duration=6", 0.9)
    assert feasible.split_feasible("ymca@0.5") == ("ymca@0.5", None)
    with pytest.raises(SkinnyInputError, match="MARGIN"):
        feasible.load_movement("md_03.amc@feasible=2", 8)
    plain, _ = feasible.load_movement("md_03.amc", 8)  # anything else: trajectories'
    assert np.array_equal(plain.angles, traj.angles)


def test_training_and_the_commands_take_the_suffix(capsys):
    from skinny_mj.cli.parser import main
    from skinny_mj.training.config import TrainConfig
    from skinny_mj.training.parts import load_trajectory

    cfg = TrainConfig().override({"movement.trajectory": "md_03.amc@feasible",
                                  "plant.dof": 8})
    traj, _ = load_trajectory(cfg)
    assert np.array_equal(traj.angles, feasible.load_movement("md_03.amc@feasible", 8)[0].angles)
    assert main(["trajectory", "show", "md_03.amc@feasible", "--dof", "8",
                 "--actuation", "torque"]) == 0
    assert "-> feasible" in capsys.readouterr().out
