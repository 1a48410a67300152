"""Paper C (generalization): the paper's settings, the measures behind its claims, and
the whole --quick sweep end to end (train x test matrix, figures, claims)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from skinny_mj.experiments.paper_c import report as paper_c_report
from skinny_mj.experiments.paper_c import study as paper_c

from skinny_mj.engine.experiment import run_sweep
from skinny_mj.engine.plan import plan
from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.ideal import max_speeds
from skinny_mj.trajectories import get


def test_config_is_paper_c_section_3_5():
    cfg = paper_c.STUDY.config("ymca")
    assert (cfg.plant.dof, cfg.plant.signals, cfg.esn.n_reservoir, cfg.esn.spectral_radius,
            cfg.esn.noise_level) == (4, "joint", 1000, 0.1, 0.2)
    assert (cfg.plant.sensor_noise, cfg.method.epochs, cfg.learning_cycles) == (0.01, 150, 5)
    from skinny_mj.training.loop import build_run

    fcfg = build_run(cfg, [0]).cfg.method
    assert fcfg.beta == 1.0  # u_target = u + u_error(t+1): the original target
    gains = fcfg.gains()
    assert gains.shape == (150,) and gains[0] == 1.0
    np.testing.assert_allclose(gains[1:] / gains[:-1], 0.9)  # -10 % per epoch
    assert gains[-1] < 1e-6  # "decreased to ~0"
    tcfg = paper_c.STUDY.config("y-pure")
    assert (tcfg.movement.trajectory, tcfg.method.kind, tcfg.learning_cycles, tcfg.noise_level) == \
        ("y-pure", "original", 5, 0.2)
    assert tcfg.test.washout_cycles == 1  # "the initialization cycle and the evaluation cycle"


def test_every_network_shares_ymcas_command_scale():
    from skinny_mj.training.loop import full_scale_speeds

    ymca = max_speeds(get("ymca").angles, 0.02)
    for row, movement in (("y", "y"), ("y-pure", "y-pure"), ("mirror-left", "mirror-left"),
                          ("ymca-1.5x", "ymca@1.5")):
        own = paper_c.STUDY.config(row)
        np.testing.assert_array_equal(full_scale_speeds(own, get(movement)), ymca)
    # without the shared scale Y's barely moving elbows would get a far smaller one
    assert max_speeds(get("y").angles, 0.02)[1] < 0.2 * ymca[1]


def test_arm_metrics_tell_the_average_from_the_own_target():
    desired = get("ymca").angles
    average = np.tile((desired[:, :2] + desired[:, 2:]) / 2, 2)
    m = paper_c.arm_metrics(average, desired, 4)
    assert m["err_vs_avg"] == pytest.approx(0.0, abs=1e-12)
    assert m["asym_produced"] == pytest.approx(0.0, abs=1e-12)
    assert m["err_vs_own"] > 0.02 and m["asym_desired"] > 0.05
    assert m["corr_vs_avg"] == pytest.approx(1.0)
    own = paper_c.arm_metrics(desired, desired, 4)
    assert own["err_vs_own"] == 0.0 and own["err_vs_avg"] > 0.02


def test_elbow_range_of_the_derived_movements():
    assert paper_c.elbow_range(get("y-pure").angles, 4) == 0.0
    y, ymca = (paper_c.elbow_range(get(n).angles, 4) for n in ("y", "ymca"))
    assert 0 < y < 0.1 * ymca  # Y: "hardly any motion in the elbow"


def test_untrained_network_leaves_the_arm_still_at_test():
    """K = 0 and a zero readout: the commands are zero, so the plant keeps its first pose."""
    from skinny_mj.training.loop import build_run, evaluate

    run = build_run(paper_c.STUDY.config("ymca").override({"esn.n_reservoir": 30}), [0])
    traj = get("ym")
    (test,) = evaluate(run, traj)
    assert not test.failed and np.all(test.rollout.commands == 0)
    assert paper_c.elbow_range(test.rollout.angles[0], 4) < 1e-3
    assert test.true_commands.shape == (len(traj) - 1, 4)
    assert np.abs(test.true_commands).max() <= 1


def test_rows_and_the_movement_option():
    full = paper_c.STUDY.build()
    assert [r.id for r in full.rows] == list(paper_c.MOVEMENTS) and full.runs == 10
    assert paper_c.columns(full.params)[paper_c.REAL_ID].endswith("md_02.amc")
    quick = plan(paper_c.STUDY, quick=True)
    assert [p.id for p in quick.rows] == list(paper_c.QUICK_TRAIN)
    assert quick.config("ymca").esn.n_reservoir == 100
    assert list(paper_c.columns(quick.params)) == [*paper_c.QUICK_TESTS, paper_c.REAL_ID]
    # --movement: a row training on it (kept by --quick, after the others: their seeds
    # stay), and the test column ``real`` in place of md_02; no other row changes
    moved = plan(paper_c.STUDY, quick=True, movement="ymca@0.5", asf="x.asf")
    assert [p.id for p in moved.rows] == [*paper_c.QUICK_TRAIN, paper_c.REAL_ID]
    assert paper_c.columns(moved.params)[paper_c.REAL_ID] == "ymca@0.5"
    real = moved.config(paper_c.REAL_ID).movement
    assert (real.trajectory, real.asf) == ("ymca@0.5", None)  # an .asf is for .amc clips
    assert all(moved.config(i) == quick.config(i) for i in paper_c.QUICK_TRAIN)
    clip = plan(paper_c.STUDY, movement="md_03.amc", asf="x.asf")
    assert clip.config(paper_c.REAL_ID).movement.asf == "x.asf" == clip.params["asf"]
    assert clip.config("ymca").movement.asf is None
    with pytest.raises(SkinnyInputError, match="nope"):
        run_sweep(full, None, rows=["nope"], progress=False)
    eight = plan(paper_c.STUDY, quick=True, body=8, signals="cartesian").config("ymca")
    assert (eight.plant.dof, eight.plant.signals) == (8, "cartesian")


def test_quick_sweep_end_to_end(tmp_path):
    exp = paper_c.STUDY.build(quick=True)
    results = run_sweep(exp, tmp_path, workers=1, progress=False)
    assert all(r["n_failed"] == 0 for r in results["rows"])
    runs = [json.loads(p.read_text()) for p in sorted((tmp_path / "runs").glob("*.json"))]
    assert len(runs) == len(paper_c.QUICK_TRAIN) * exp.runs
    cols = list(paper_c.columns(exp.params))
    for run in runs:
        m = run["metrics"]
        for col in cols:
            assert np.isfinite(m[f"{col}__position_nrmse"]) and 0 <= m[f"{col}__position_nrmse"]
            assert abs(m[f"{col}__lag_steps"]) <= paper_c.MAX_LAG_STEPS  # every pair's timing
        assert np.asarray(m["angles__ymca"]).shape == (len(get("ymca")), 4)
        assert len(m["train_curve_position_nrmse"]) == exp.config(run["row"]).method.epochs
        assert 0 < m["peak_rss_mb"] < 2048
    text = exp.report(results, tmp_path)
    for name in ("matrix_position_nrmse.png", "matrix.md", "train_curves.png", "fig3_ymca.png",
                 "fig4_ypure_ym.png", "fig6_mirror_left_ymca.png"):
        assert (tmp_path / name).is_file(), name
    train, tests, m = paper_c_report.matrix(paper_c_report._runs(tmp_path))
    assert train == list(paper_c.QUICK_TRAIN) and tests == cols and np.isfinite(m).all()
    assert "Y pure -> YM" in text and "mirror-left -> YMCA" in text
    assert "[n/a] trained on YMCA, tested on ymca-0.5x" in text  # not in the quick sweep
    # Even this short training shows paper C's mirror result: a network trained on a
    # symmetric movement answers YMCA with a symmetric output near the arms' average.
    mirror = [r["metrics"] for r in runs if r["row"] == "mirror-left"]
    for mm in mirror:
        assert mm["ymca__err_vs_avg"] < mm["ymca__err_vs_own"]
        assert mm["ymca__asym_produced"] < 0.5 * mm["ymca__asym_desired"]


def test_lockstep_batch_equals_runs_one_at_a_time():
    """The engine's fast path: seeds in lockstep give each seed's metrics alone, bit for
    bit (wall times and memory aside)."""
    quick = plan(paper_c.STUDY, quick=True)
    cfg = quick.config("ymca").override({"method.epochs": 2})
    row = quick.run_row("ymca")
    row = dataclasses.replace(row, params={**row.params, "tests": ("ymca", "y")})
    seeds = [3, 8]
    batch = paper_c.STUDY.run(cfg, row, seeds)
    for seed, got in zip(seeds, batch, strict=True):
        (want,) = paper_c.STUDY.run(cfg, row, [seed])
        assert set(got) == set(want)
        for key, value in want.items():
            if key not in ("wall_s", "train_wall_s", "peak_rss_mb"):
                np.testing.assert_array_equal(np.asarray(got[key]), np.asarray(value),
                                              err_msg=key)


def test_lag_steps_finds_a_shift_of_the_output():
    from skinny_mj.experiments.paper_c.study import lag_steps

    t = np.linspace(0, 4 * np.pi, 300)
    desired = np.stack([np.sin(t), np.cos(t), np.zeros_like(t)], axis=1)
    assert lag_steps(desired, desired) == 0
    late = np.roll(desired, 4, axis=0)  # the output 4 steps behind
    assert lag_steps(late, desired) == 4
    assert lag_steps(np.roll(desired, -3, axis=0), desired) == -3
