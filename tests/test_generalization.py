"""Motor babbling, training sets, motion-imitation metrics, the generalization
experiment and the ``general`` preset."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from skinny_mj.controllers.metrics import fraction_within, rmse_per_signal, timing_lag

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.trajectories import get, load_movement
from skinny_mj.trajectories.babble import LIMIT_MARGIN_RAD, babble, bridge

# -- babbling ----------------------------------------------------------------------------


@pytest.mark.parametrize("dof", [4, 8])
def test_babble_is_seeded_inside_the_ranges_and_at_human_speeds(dof):
    a = babble(dof, seed=3, duration_s=12.0, v_min=1.0, v_max=6.0)
    assert len(a) == 600 and a.dof == dof
    assert np.array_equal(a.angles, babble(dof, seed=3, duration_s=12.0, v_min=1.0,
                                           v_max=6.0).angles)
    assert not np.array_equal(a.angles, babble(dof, seed=4, duration_s=12.0).angles)
    lo, hi = body.body_of(dof).joint_ranges().T
    assert np.all(a.angles >= lo + LIMIT_MARGIN_RAD - 1e-12)
    assert np.all(a.angles <= hi - LIMIT_MARGIN_RAD + 1e-12)
    speed = np.abs(a.velocities())
    assert speed.max() <= 6.0 * 1.1  # peak speeds drawn <= v_max (rounding of T)
    # covers the joint space: each DOF sweeps most of its range
    assert np.all(np.ptp(a.angles, axis=0) > 0.6 * (hi - lo))
    # smooth: minimum-jerk pieces start and end at rest, so the acceleration stays under
    # the minimum-jerk peak 5.77 dq / T^2 <= 3.08 v_max / T_min (T_min = 0.3 s): no jumps
    accel = np.abs(np.diff(a.velocities(), axis=0)).max() / a.dt
    assert accel <= 1.05 * 3.08 * 6.0 / 0.3


def test_babble_names_and_errors():
    t = get("babble:seed=3,duration=2", 4)
    assert np.array_equal(t.angles, babble(4, seed=3, duration_s=2.0).angles)
    assert len(get("babble:seed=3,duration=2@2", 4)) == 50
    assert len(load_movement("babble:duration=1", 8)[0]) == 50
    for bad in ("babble:seed=1.5", "babble:speed=3", "babble:", "babble:duration=-1",
                "babble:vmin=3,vmax=1"):
        with pytest.raises(SkinnyInputError):
            load_movement(bad, 4)


def test_training_set_joins_pieces_with_smooth_bridges():
    y, ym = get("y", 4), get("ym", 4)
    joined, report = load_movement("set:y+ym", 4)
    gap = bridge(y.angles[-1], ym.angles[0])
    assert len(joined) == len(y) + len(gap) + len(ym)
    assert np.array_equal(joined.angles[:len(y)], y.angles)
    assert np.array_equal(joined.angles[-len(ym):], ym.angles)
    assert np.abs(joined.velocities()).max() <= max(np.abs(y.velocities()).max(),
                                                    np.abs(ym.velocities()).max()) + 1e-9
    assert report.clipped_samples == 0 and report.steps == len(joined)
    clip, _ = load_movement("set:ymca+md_03.amc@start=0,duration=1", 4)  # a shipped clip
    assert len(clip) > len(get("ymca", 4)) + 49
    for bad in ("set:", "set:y++ym", "set:y+set:ym", "set:y+nope"):
        with pytest.raises(SkinnyInputError):
            load_movement(bad, 4)


def test_full_scale_factor_default_is_todays_scale():
    from skinny_mj.training.config import TrainConfig
    from skinny_mj.training.loop import full_scale_speeds

    cfg = TrainConfig()
    traj = get("ymca", 4)
    base = full_scale_speeds(cfg, traj)
    assert np.array_equal(base, np.maximum(2 * traj.max_speed_rad_s(), 0.5))
    assert np.allclose(full_scale_speeds(cfg.override({"movement.full_scale_factor": 4.0}),
                                         traj), 2 * base)
    with pytest.raises(SkinnyInputError):
        cfg.override({"movement.full_scale_factor": 0.0})


# -- metrics -----------------------------------------------------------------------------


def test_imitation_metrics_on_known_signals():
    from skinny_mj.training.dtw import dtw_nrmse

    t = np.linspace(0, 6, 300)
    x = np.stack([np.sin(t), np.cos(2 * t)], axis=1)
    late = np.roll(x, 5, axis=0)
    assert timing_lag(late, x, 25) == 5 and timing_lag(x, late, 25) == -5
    assert timing_lag(x, x, 10) == 0
    assert np.array_equal(fraction_within(x, x + 0.1, 0.05), [0.0, 0.0])
    assert np.allclose(fraction_within(x, x + 0.01, 0.05), 1.0)
    assert np.allclose(rmse_per_signal(x + 0.2, x), 0.2)
    pytest.importorskip("dtaidistance")
    assert dtw_nrmse(x, x) == pytest.approx(0.0, abs=1e-12)
    pooled = np.sqrt(np.mean((late - x) ** 2)) / 2
    assert 0 < dtw_nrmse(late, x) < 0.5 * pooled  # a pure delay is mostly warped away
    offset = x + 0.1
    assert 0 < dtw_nrmse(offset, x) <= 0.05 + 1e-12  # at most the identity path's 0.1 / 2


# -- experiment and preset ---------------------------------------------------------------


def test_generalization_experiment_runs_a_tiny_matrix(tmp_path):
    pytest.importorskip("dtaidistance")
    from skinny_mj.experiments.generalization import study as g

    exp = g.STUDY.build(quick=True)
    assert {r.id for r in exp.rows} == {f"j2-{s}" for s in g.QUICK_SETS}
    full = g.STUDY.build()
    late_rows = (*g.EXTRA_ROWS, *g.GENERAL_ROWS, *g.CARTESIAN_ROWS)
    assert len(full.rows) == len(g.TRAIN_SETS) + 2 * len(g.CORE_SETS) + len(late_rows)
    assert set(full.groups) == {*g.REPRESENTATIONS, "extra", "general", "cartesian"}
    late = [r.id for r in full.rows[-len(late_rows):]]
    assert late == [*full.groups["extra"], *full.groups["general"],  # earlier rows keep seeds
                    *full.groups["cartesian"]]
    # a Cartesian candidate is its base row with one change, on the base row's seeds
    base, elbow = (full.config(r) for r in ("c3-babble15+ymca", "c3-babble15+ymca+elbow"))
    assert elbow == base.override({"plant.signals": "cartesian-elbow"})
    assert full.config("c2-general+damp0.3").method.u_error_damping == 0.3
    seeds = {r.id: r.seeds_of for r in full.rows}
    assert seeds["c2-general+forward"] == "c2-general" and seeds["c2-general"] is None
    c3 = full.config("c3-md_03")
    assert (c3.plant.dof, c3.plant.signals, c3.movement.trajectory, c3.esn.n_reservoir) == \
        (8, "cartesian", "md_03.amc", 200)
    assert full.config("j2-babble15-N400").esn.n_reservoir == 400
    with pytest.raises(SkinnyInputError):
        g.STUDY.build(movement="ymca")
    config = full.config("j2-md_02-head").override(
        {"esn.n_reservoir": 20, "method.epochs": 1})
    row = dataclasses.replace(g.STUDY.row("j2-md_02-head"),
                              params={"tests": ("y-pure", "md_03-tail")})
    outs = g.STUDY.run(config, row, [1, 2])
    assert len(outs) == 2
    for out in outs:
        assert out["train_steps"] == 250 and 0 < out["train_coverage"] <= 1
        for col in ("y-pure", "md_03-tail"):
            assert 0 <= out[f"{col}__saturated"] <= 1
            assert 0 <= out[f"{col}__clipped_ideal_nrmse"] <= out[f"{col}__position_nrmse"]
            assert 0 <= out[f"{col}__within5"] <= 1 and len(out[f"{col}__rmse_deg_per_joint"]) == 4
            assert out[f"{col}__dtw_nrmse"] > 0
    single = g.STUDY.run(config, row, [2])
    key = "md_03-tail__position_nrmse"
    assert single[0][key] == outs[1][key]  # lockstep == alone, bit for bit


def test_clipped_ideal_is_exact_within_full_scale_and_pays_beyond():
    from skinny_mj.experiments.generalization.study import clipped_ideal_nrmse, saturation

    traj = get("ymca", 4)
    wide = 2 * traj.max_speed_rad_s()
    assert saturation(traj.angles, traj.dt, wide) == 0.0
    assert clipped_ideal_nrmse(traj.angles, traj.dt, wide, "joint") == pytest.approx(0, abs=1e-12)
    narrow = 0.5 * traj.max_speed_rad_s()
    assert saturation(traj.angles, traj.dt, narrow) > 0
    assert clipped_ideal_nrmse(traj.angles, traj.dt, narrow, "joint") > 0.001


def test_preset_general_sets_its_fields_and_flags_given_override_them():
    from skinny_mj.cli.config_files import train_config
    from skinny_mj.cli.parser import build_parser
    from skinny_mj.training.presets import preset_fields

    argv = ["train", "--preset", "general", "--epochs", "2", "--seed", "5"]
    cfg, seed = train_config(build_parser().parse_args(argv))
    want = preset_fields("general")
    assert seed == 5 and cfg.method.epochs == 2
    got = cfg.to_dict()
    assert {k: got[k] for k in want} == want  # untouched flags keep the preset's
    with pytest.raises(SkinnyInputError):
        preset_fields("nope")


@pytest.mark.slow  # the CLI end to end (imports matplotlib and rerun: ~10 s)
def test_train_preset_general_records_its_training_and_tests_on_a_clip(tmp_path):
    pytest.importorskip("dtaidistance")
    from skinny_mj.controllers.esn import read_metadata

    from skinny_mj.cli.parser import main

    out = tmp_path / "train"
    assert main(["train", "--preset", "general", "--epochs", "1", "--reservoir", "20",
                 "--trajectory", "set:babble:seed=1,duration=1+y-pure@2", "--out", str(out),
                 "--quiet"]) == 0
    meta = read_metadata(out / "model.npz")
    assert meta["signals"] == "joint" and meta["dof"] == 4  # the preset's
    training = meta["training"]
    assert training["preset"] == "general"
    assert training["pieces"] == ["babble:seed=1,duration=1", "y-pure@2"]
    assert training["steps_per_cycle"] == len(
        load_movement("set:babble:seed=1,duration=1+y-pure@2", 4)[0])
    assert meta["config"]["test.washout_cycles"] == 1  # the preset's, overrides kept apart
    test_out = tmp_path / "test"
    assert main(["test", "--model", str(out / "model.npz"), "--trajectory",
                 "md_03.amc@start=0,duration=1.5", "--out", str(test_out)]) == 0
    m = json.loads((test_out / "metrics.json").read_text())["imitation"]
    assert {"dtw_nrmse", "within5", "within5_per_joint", "lag_s", "saturated"} <= set(m)
    from skinny_mj.cli.config_files import train_config
    from skinny_mj.cli.parser import build_parser
    from skinny_mj.training.config import TrainConfig

    both, _ = train_config(build_parser().parse_args([  # the file's keys over the preset's
        "train", "--preset", "general", "--config", str(out / "metrics.json")]))
    assert both == TrainConfig.from_dict(meta["config"]) and both.esn.n_reservoir == 20
