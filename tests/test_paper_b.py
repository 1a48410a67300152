"""Paper B (bimanual coordination): the glue's contracts and the quick sweep end to end."""

from __future__ import annotations

import json

import numpy as np
import pytest

from controllers.esn import ESN, ESNConfig
from controllers.fel import FELConfig
from controllers.plant import Plant
from skinny_mj import bimanual as bm
from skinny_mj.body import position_signals
from skinny_mj.ideal import max_speeds

MV = bm.Movement()


def _plant(pattern: str = "phase0", speed: float = 1.0, noise: float = 0.0, runs: int = 1):
    q = bm.pattern_angles(bm.PATTERNS[pattern], MV, speed)
    ms = max_speeds(bm.pattern_angles(bm.PATTERNS[pattern], MV), MV.dt)
    return q, bm.BimanualPlant(q, MV, ms, n_runs=runs, seeds=list(range(runs)),
                               sensor_noise=noise)


def _cycles(x: np.ndarray) -> float:
    """Number of full oscillations of x (T,) over its length: the dominant FFT bin."""
    return float(np.argmax(np.abs(np.fft.rfft(x[:-1] - x[:-1].mean()))))


@pytest.mark.parametrize("name", list(bm.PATTERNS))
def test_patterns_define_the_lagging_arm_relative_to_the_leader(name):
    p = bm.PATTERNS[name]
    q = bm.pattern_angles(p, MV)
    lead, lag = q[:, 0], q[:, 2]  # right arm leads by default
    lo, hi = np.radians(0.0), np.radians(180.0)
    assert np.all((q > lo) & (q < hi))
    assert np.ptp(q[:, 1]) == 0 and np.ptp(q[:, 3]) == 0  # elbows still
    assert _cycles(lag) / _cycles(lead) == pytest.approx(p.frequency_ratio)
    assert np.ptp(lag) / np.ptp(lead) == pytest.approx(p.amplitude_ratio, rel=1e-3)
    # The same pattern at another speed is the same function of the leader's phase.
    q2 = bm.pattern_angles(p, MV, 0.5)
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
    q = bm.pattern_angles(bm.PATTERNS["phase90"], MV)
    assert bm.phase_lag_deg(q[:, 2], q[:, 0], MV.period_s / MV.dt) == pytest.approx(90, abs=4)


def test_plant_forces_the_leader_and_controls_only_the_lagging_arm():
    q, plant = _plant("phase90", noise=0.0, runs=2)
    assert isinstance(plant, Plant)
    assert (plant.n_dof, plant.n_signals) == (2, 4)
    s0 = plant.reset()
    np.testing.assert_allclose(s0, position_signals(q[0], 4, "joint")[None].repeat(2, 0),
                               atol=2e-3)
    jac = plant.command_jacobian()
    assert jac.shape == (2, 4, 2)
    assert np.all(jac[:, :2] == 0) and np.all(np.abs(np.diagonal(jac[:, 2:], axis1=1,
                                                                   axis2=2)) > 0)
    for t in range(10):
        plant.step(np.array([[0.5, 0.0], [0.0, 0.0]]))
        # the leading arm tracks its movement whatever the lagging arm's command
        np.testing.assert_allclose(plant.all_joint_angles()[:, 0], q[t + 1, 0], atol=2e-3)
    moved = plant.joint_angles()[:, 0] - q[0, 2]
    expected = 0.5 * plant.max_speed_rad_s[0] * plant.dt * 10
    assert moved[0] == pytest.approx(expected, rel=0.05)
    assert abs(moved[1]) < 0.02


def test_esn_sees_only_the_current_state_of_both_arms():
    q, plant = _plant()
    esn = ESN(ESNConfig(4, 2, 20, 0.5), seed=0)
    desired = position_signals(q, 4, "joint")
    ro = bm.rollout(esn, plant, desired, 1.0, noise=False)
    # input block of the extended state [x; u; 1] is the sensed state s(t)
    np.testing.assert_allclose(ro.states[0, :, 20:24], ro.sensed[0, :-1])
    assert ro.commands.shape == (1, len(q) - 1, 2)


def test_feedback_tracks_and_fel_learns_in_phase():
    q, plant = _plant("phase0", noise=0.01)
    desired = position_signals(q, 4, "joint")
    untrained = ESN(ESNConfig(4, 2, 100, 0.5, noise_level=0.2), seed=3)
    before = bm.evaluate(untrained, plant, desired).position_nrmse[0]
    esn = ESN(ESNConfig(4, 2, 100, 0.5, noise_level=0.2), seed=3)
    tr = bm.train(esn, plant, desired, FELConfig("new", 0.01, 5, 4))
    assert not tr.failed[0]
    assert tr.position_nrmse[0, 0] < 0.02  # K = 1: the feedback controller tracks
    after = bm.evaluate(esn, plant, desired)
    assert after.position_nrmse[0] < 0.5 * before  # K = 0: the ESN moves the arm


@pytest.mark.parametrize("workers", [1])
def test_quick_sweep_end_to_end(tmp_path, workers):
    from experiments import get
    from skinny_mj.experiment import run_sweep

    module = get("paper-b")
    exp = module.build(quick=True)
    assert [r.row_id for r in exp.rows] == list(bm.PATTERNS)
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
    text = module.report(results, tmp_path)
    assert text.count("- [") >= 9
    assert (tmp_path / "fig3_phase90.png").stat().st_size > 0
    assert (tmp_path / "relative_error.png").is_file()


def test_build_rejects_a_movement():
    from experiments.paper_b import build
    from skinny_mj.errors import SkinnyInputError

    with pytest.raises(SkinnyInputError):
        build(movement="ymca")
