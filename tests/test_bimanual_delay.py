"""Bimanual coordination under delay: the per-arm forward models' inputs and
fits, their config, lockstep determinism, and the report's table on known records."""

from __future__ import annotations

import numpy as np
import pytest
from skinny_mj.controllers import fel
from skinny_mj.controllers.arm_forward import ArmForwardModels
from skinny_mj.controllers.esn import ESN, ESNConfig
from skinny_mj.experiments.bimanual_delay import report as bdr
from skinny_mj.experiments.bimanual_delay import study as bd

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import bimanual as bm
from skinny_mj.plant.body import body_of
from skinny_mj.plant.ideal import max_speeds
from skinny_mj.training.config import TrainConfig
from skinny_mj.trajectories import get

N = 20  # reservoir units of the tiny networks


def _plant():
    traj = get("bimanual-phase0", 4)
    ms = max_speeds(traj.angles, traj.dt)
    return traj, bm.BimanualPlant(4, "joint", traj, "right", ms, sensor_noise=0.0)


def _arm_models(sharing: str) -> ArmForwardModels:
    lag = ESN(ESNConfig(4, 2, N, 0.5), seed=1)
    lead = ESN(ESNConfig(4, 2, N, 0.5), seed=2) if sharing == "predictions" else None
    return ArmForwardModels(lag, lead, bm.arm_signals(4, "joint", "left"),
                            bm.arm_signals(4, "joint", "right"), sharing)


@pytest.mark.parametrize("sharing", ["none", "predictions", "commands"])
def test_the_lagging_arm_gets_delayed_state_its_prediction_and_what_the_leader_shares(sharing):
    traj, plant = _plant()
    fm = _arm_models(sharing)
    fm.esn.lag.W_out[..., -1] = 0.2  # readouts on the bias only: known predictions
    if fm.esn.lead is not None:
        fm.esn.lead.W_out[..., -1] = -0.3
    esn = ESN(ESNConfig(8, 2, N, 0.5), seed=0)
    desired = body_of("2d").position_signals(traj.angles, "joint")
    ro = fel.rollout(esn, plant, desired, 1.0,
                     fel.Loop(inputs="sensed", forward=fm, delay_steps=2), noise=False)
    u = ro.states[0, :, N:N + 8]  # the inverse model's input [s(t - 2); p(t)]
    t = np.arange(len(u))
    np.testing.assert_array_equal(u[:, :4], ro.sensed[0, np.maximum(t - 2, 0)])
    lag, lead = [2, 3], [0, 1]  # right arm leads: signals 0, 1
    np.testing.assert_array_equal(u[:, 4:], ro.predictions[0, :-1])
    p = ro.predictions[0, 1:]
    bias = fm.esn.lag.cfg.bias
    np.testing.assert_allclose(p[:, lag], np.tanh(0.2 * bias))  # its own prediction
    if sharing == "none":
        assert np.all(p[:, lead] == 0)
    elif sharing == "commands":  # the leader's last command moved it by u * v_max * dt
        step = np.diff(ro.angles[0, :, :2], axis=0) / (plant.full_max_speed_rad_s[:2] * plant.dt)
        np.testing.assert_allclose(p[:, lead], step, atol=2e-3)
    else:
        np.testing.assert_allclose(p[:, lead], np.tanh(-0.3 * bias))


def test_each_arms_forward_model_learns_its_own_next_position():
    from skinny_mj.training.loop import build_run, train_run

    cfg = bd.STUDY.build(quick=True).config("phase0-share-predictions-d4").override(
        {"method.epochs": 1, "method.cycles": 1, "movement.speed": 2.0})
    run = build_run(cfg, [7])
    assert isinstance(run.forward, ArmForwardModels) and run.esn.cfg.n_inputs == 8
    ro = train_run(run).fel.last_rollout
    assert run.forward.prediction_nrmse(ro)[0] < 0.02
    lead = run.forward.lead_signals
    np.testing.assert_array_less(np.abs(ro.predictions[0, 1:, lead]
                                        - ro.true_signals[0, 1:, lead]).mean(), 0.02)


def test_config_needs_a_leading_arm_a_parallel_forward_model_and_joint_signals():
    assert TrainConfig().forward.kind == "none"
    assert TrainConfig().override({"forward": "parallel"}).forward.sharing is None
    ok = {"plant.leading_arm": "right", "plant.signals": "joint", "forward": "parallel",
          "inputs": "sensed"}
    TrainConfig().override({**ok, "forward.sharing": "commands"})
    for bad in ({"plant.leading_arm": None}, {"forward": "serial"}, {"forward": "none"},
                {"plant.signals": "cartesian"}, {"forward.sharing": "positions"}):
        with pytest.raises(SkinnyInputError):
            TrainConfig().override({**ok, "forward.sharing": "commands", **bad})


def test_lockstep_batch_equals_each_seed_alone():
    from skinny_mj.training.loop import build_run, evaluate, train_run

    cfg = bd.MODEL.override({  # short cycles (100 steps): a fast test
        "movement.trajectory": "bimanual-phase180", "method.epochs": 1, "method.cycles": 1,
        "plant.delay": 3, "forward": "parallel", "forward.sharing": "predictions",
        "movement.speed": 3.0, "test.washout_cycles": 0})

    def measured(seeds):
        run = build_run(cfg, seeds)
        curve = train_run(run).fel.position_nrmse[:, -1]
        return curve, [t.position_nrmse for t in evaluate(run)]

    both = measured([4, 5])
    for r, seed in enumerate([4, 5]):
        alone = measured([seed])
        assert (alone[0][0], alone[1][0]) == (both[0][r], both[1][r])


def test_rows_cover_patterns_architectures_and_delays():
    exp = bd.STUDY.build()
    assert len(exp.rows) == len(bd.PATTERNS) * len(bd.ARCHITECTURES) * len(bd.DELAYS)
    cfg = exp.config("phase180-share-commands-d6")
    assert (cfg.plant.delay, cfg.forward.kind, cfg.forward.sharing,
            cfg.movement.trajectory) == (6, "parallel", "commands", "bimanual-phase180")
    inverse = exp.config("phase0-inverse-d2")
    assert (inverse.forward.kind, inverse.plant.leading_arm) == ("none", "right")
    assert exp.groups["share-predictions"] == tuple(
        f"{p}-share-predictions-d{d}" for p in bd.PATTERNS for d in bd.DELAYS)
    assert bd.STUDY.build(body=8).config("phase0-forward-d4").plant.dof == 8
    for option in ({"movement": "ymca"}, {"signals": "cartesian"}):
        with pytest.raises(SkinnyInputError):
            bd.STUDY.build(**option)


def test_report_table_and_comparisons_from_known_runs():
    def rec(arch, delay, value, status="ok"):
        m = {k: value for k, _, _ in bdr.SUMMARY}
        m["worst_abs_phase_lag_deg"] = value
        return {"params": {"pattern": "phase0", "architecture": arch, "delay": delay},
                "status": status, "metrics": m if status == "ok" else {}}

    records = [rec("inverse", 4, 2.0), rec("inverse", 4, 4.0), rec("forward", 4, 1.0),
               rec("forward", 4, 0.0, "failed")]
    patterns, delays, by = bdr.index_runs(records)
    table = bdr.summary_table(patterns, delays, by)
    inv = next(line for line in table if "| inverse |" in line)
    assert "| 0 / 2 |" in inv and "3.0000 ± 1.0000" in inv
    assert "| 1 / 2 |" in next(line for line in table if "| forward |" in line)
    lines = bdr.comparisons(patterns, delays, by)
    assert any("forward vs inverse, mean position NRMSE 1x: lower at 1 of 1" in x
               for x in lines)


@pytest.mark.slow
def test_quick_sweep_end_to_end(tmp_path):
    from skinny_mj.engine.experiment import run_sweep

    exp = bd.STUDY.build(quick=True)
    results = run_sweep(exp, tmp_path, workers=1, progress=False)
    assert all(r["n_ok"] == 1 for r in results["rows"])
    text = bd.report(results, exp, tmp_path)
    assert text.count("| phase0 |") == len(exp.rows)
    assert (tmp_path / "delay_sweep.png").stat().st_size > 0
    assert (tmp_path / "traces_d4.png").stat().st_size > 0
