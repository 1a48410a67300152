"""Paper B (bimanual coordination): the glue's contracts and the quick sweep end to end."""

from __future__ import annotations

import json

import numpy as np
import pytest
from skinny_mj.controllers import fel
from skinny_mj.controllers.esn import ESN, ESNConfig
from skinny_mj.controllers.plant import Plant
from skinny_mj.experiments import paper_b

from skinny_mj.plant import bimanual as bm
from skinny_mj.plant.body import body_of
from skinny_mj.plant.ideal import max_speeds
from skinny_mj.trajectories import get
from skinny_mj.trajectories import patterns as pt

MV = pt.Movement()


def _plant(pattern: str = "phase0", speed: float = 1.0, noise: float = 0.0, runs: int = 1,
           dof: int = 4, signals: str = "joint"):
    traj = get(f"bimanual-{pattern}@{speed:g}", dof)
    ms = max_speeds(get(f"bimanual-{pattern}", dof).angles, MV.dt)
    return traj.angles, bm.BimanualPlant(dof, signals, traj, "right", ms, n_runs=runs,
                                         seeds=list(range(runs)), sensor_noise=noise)


def _cycles(x: np.ndarray) -> float:
    """Number of full oscillations of x (T,) over its length: the dominant FFT bin."""
    return float(np.argmax(np.abs(np.fft.rfft(x[:-1] - x[:-1].mean()))))


@pytest.mark.parametrize("name", list(pt.PATTERNS))
def test_patterns_define_the_lagging_arm_relative_to_the_leader(name):
    p = pt.PATTERNS[name]
    q = pt.pattern_angles(p, MV)
    lead, lag = q[:, 0], q[:, 2]  # right arm leads by default
    lo, hi = np.radians(0.0), np.radians(180.0)
    assert np.all((q > lo) & (q < hi))
    assert np.ptp(q[:, 1]) == 0 and np.ptp(q[:, 3]) == 0  # elbows still
    assert _cycles(lag) / _cycles(lead) == pytest.approx(p.frequency_ratio)
    assert np.ptp(lag) / np.ptp(lead) == pytest.approx(p.amplitude_ratio, rel=1e-3)
    # The same pattern at another speed is the same function of the leader's phase.
    q2 = pt.pattern_angles(p, MV, 0.5)
    assert len(q2) - 1 == 2 * (len(q) - 1)
    np.testing.assert_allclose(q2[::2], q, atol=1e-12)


def test_relative_phase_is_measured_as_a_lag():
    period = 100.0
    t = np.arange(400)
    lead = np.cos(2 * np.pi * t / period)
    for deg in (0.0, 90.0, 180.0):
        lag = np.cos(2 * np.pi * t / period - np.radians(deg))
        measured = bm.phase_lag_deg(lag, lead, period)
        assert abs(measured) == pytest.approx(deg, abs=3.6)  # +-180 are the same
    q = pt.pattern_angles(pt.PATTERNS["phase90"], MV)
    assert bm.phase_lag_deg(q[:, 2], q[:, 0], MV.period_s / MV.dt) == pytest.approx(90, abs=4)


def test_plant_forces_the_leader_and_controls_only_the_lagging_arm():
    q, plant = _plant("phase90", noise=0.0, runs=2)
    assert isinstance(plant, Plant)
    assert (plant.n_dof, plant.n_signals) == (2, 4)
    s0 = plant.reset()
    np.testing.assert_allclose(s0, body_of("2d").position_signals(q[0], "joint")[None].repeat(2, 0),
                               atol=2e-3)
    jac = plant.command_jacobian()
    assert jac.shape == (2, 4, 2)
    assert np.all(jac[:, :2] == 0) and np.all(np.abs(np.diagonal(jac[:, 2:], axis1=1,
                                                                   axis2=2)) > 0)
    for t in range(10):
        plant.step(np.array([[0.5, 0.0], [0.0, 0.0]]))
        # the leading arm tracks its movement whatever the lagging arm's command
        np.testing.assert_allclose(plant.joint_angles()[:, 0], q[t + 1, 0], atol=2e-3)
    moved = plant.joint_angles()[:, 2] - q[0, 2]
    expected = 0.5 * plant.max_speed_rad_s[0] * plant.dt * 10
    assert moved[0] == pytest.approx(expected, rel=0.05)
    assert abs(moved[1]) < 0.02


def test_3d_plant_controls_the_lagging_arms_four_dofs():
    q, plant = _plant("phase90", dof=8, signals="cartesian")
    assert (plant.n_dof, plant.n_signals) == (4, 12) and isinstance(plant, Plant)
    jac = plant.command_jacobian()
    assert jac.shape == (1, 12, 4) and np.all(jac[:, :6] == 0)
    for _ in range(5):
        plant.step(np.zeros((1, 4)))
    assert plant.joint_angles().shape == (1, 8)


def test_esn_sees_only_the_current_state_of_both_arms():
    q, plant = _plant()
    esn = ESN(ESNConfig(4, 2, 20, 0.5), seed=0)
    desired = body_of("2d").position_signals(q, "joint")
    ro = fel.rollout(esn, plant, desired, 1.0, fel.Loop(inputs="sensed"), noise=False)
    # input block of the extended state [x; u; 1] is the sensed state s(t)
    np.testing.assert_allclose(ro.states[0, :, 20:24], ro.sensed[0, :-1])
    assert ro.commands.shape == (1, len(q) - 1, 2)


def test_feedback_tracks_and_fel_learns_in_phase():
    from skinny_mj.training.loop import build_run, evaluate, train_run

    cfg = paper_b.MODEL.override({"movement.trajectory": "bimanual-phase0", "method.epochs": 4})
    untrained = evaluate(build_run(cfg, [3]))[0].position_nrmse
    run = build_run(cfg, [3])
    result = train_run(run).fel
    assert not result.failed[0]
    assert result.position_nrmse[0, 0] < 0.02  # K = 1: the feedback controller tracks
    assert evaluate(run)[0].position_nrmse < 0.5 * untrained  # K = 0: the ESN moves the arm


def test_lockstep_batch_equals_each_seed_alone():
    config = paper_b.MODEL.override({"movement.trajectory": "bimanual-freq1-2",
                                     "method.epochs": 2})
    row = paper_b.STUDY.row("freq1-2")
    batch = paper_b.STUDY.run(config, row, [4, 5])
    for seed, out in zip([4, 5], batch, strict=True):
        alone = paper_b.STUDY.run(config, row, [seed])[0]
        assert {k: v for k, v in out.items() if k != "wall_s_run"} == \
            {k: v for k, v in alone.items() if k != "wall_s_run"}


@pytest.mark.parametrize("workers", [1])
def test_quick_sweep_end_to_end(tmp_path, workers):
    from skinny_mj.experiments import get

    from skinny_mj.engine.experiment import run_sweep

    study = get("paper-b")
    exp = study.build(quick=True)
    assert [r.id for r in exp.rows] == list(pt.PATTERNS)
    results = run_sweep(exp, tmp_path, workers=workers, progress=False)
    assert all(r["n_ok"] == 1 for r in results["rows"])
    run = json.loads(next((tmp_path / "runs").glob("phase0-*.json")).read_text())
    for speed in ("x1", "x0.5", "x1.5"):
        for metric in ("relative_error", "phase_lag_deg", "position_nrmse", "motor_nrmse"):
            assert np.isfinite(run["metrics"][f"{metric}_{speed}"])
        tr = run["metrics"]["traces"][speed]
        assert len(tr["leader"]) == len(tr["desired"]) == len(tr["actual"])
    assert len(run["metrics"]["traces"]["x0.5"]["leader"]) > \
        len(run["metrics"]["traces"]["x1.5"]["leader"])
    text = exp.report(results, tmp_path)
    assert text.count("- [") >= 9
    assert (tmp_path / "fig3_phase90.png").stat().st_size > 0
    assert (tmp_path / "relative_error.png").is_file()


def test_build_rejects_a_movement():
    from skinny_mj.errors import SkinnyInputError

    with pytest.raises(SkinnyInputError, match="takes no --movement"):
        paper_b.STUDY.build(movement="ymca")
