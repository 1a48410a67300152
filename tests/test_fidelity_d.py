"""Issue 12, paper D: the true-target grid (input noise × N × movement) on paper D's configs."""

from __future__ import annotations

import json

import pytest

import experiments
from experiments import fidelity_d, paper_d
from skinny_mj.experiment import Row, run_sweep
from skinny_mj.training import build_run, train_run


def test_registered_rows_and_groups():
    assert experiments.get("fidelity-d") is fidelity_d
    exp = fidelity_d.build()
    cfg = exp.config
    assert len(exp.rows) == len(cfg.movements) * len(cfg.reservoirs) * len(cfg.input_noises) * 5
    ids = {r.row_id for r in exp.rows}
    assert "recorded-n200-i0.03-e3b" in ids and "smooth-n400-i0-e4" in ids
    assert {r.split("-e")[-1] for r in exp.groups["stage1"]} == {"1", "2"}
    assert len(exp.groups["stage1"]) == len(exp.rows) * 2 // 5
    assert exp.groups["smooth-n100-i0.05"] == tuple(f"smooth-n100-i0.05-e{e}"
                                                    for e in fidelity_d.EXPS)
    for cell in fidelity_d.STAGE_2_CELLS:  # stage 2 = all five exps at each picked cell
        assert set(exp.groups[cell]) <= set(exp.groups["stage2"])


def test_rows_are_paper_d_true_target_configs_plus_the_grid():
    cfg = fidelity_d.Config()
    for row in fidelity_d.all_rows(cfg):
        p = row.params
        if p["movement"] != "smooth" or p["reservoir"] != 200 or p["input_noise"]:
            continue
        method, noise, reps = paper_d.EXPERIMENTS[p["exp"]]
        want = paper_d.train_configs(paper_d.Config(), Row(p["exp"], {
            "method": method, "noise": noise, "reps": reps}))["tt"]
        assert fidelity_d.train_config(cfg, row) == \
            want.override({"movement.trajectory": "ymca-smooth"})
        assert row.paper["tt_position_test"] == paper_d.PAPER_TABLE_1[p["exp"]][2][0]


def test_input_noise_raises_the_training_error():
    cfg = fidelity_d.Config(movements=("smooth",), reservoirs=(20,), input_noises=(0.0, 0.05))
    rows = {r.row_id: r for r in fidelity_d.all_rows(cfg)}
    errors = {}
    for noise in ("0", "0.05"):  # the same seed: the same reservoir, only the inputs differ
        tt = train_run(build_run(fidelity_d.train_config(cfg, rows[f"smooth-n20-i{noise}-e1"]),
                                 [3])).true_target
        errors[noise] = (tt.motor_nrmse[0], tt.position_nrmse[0])
    assert errors["0.05"][0] > errors["0"][0] and errors["0.05"][1] > errors["0"][1]


@pytest.fixture(scope="module")
def quick_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("fidelity_d")
    exp = fidelity_d.build(quick=True)
    results = run_sweep(exp, out, workers=1, progress=False, rows=["stage1"])
    return exp, out, results


def test_quick_stage_1_runs_and_reports(quick_sweep):
    exp, out, results = quick_sweep
    assert results["n_error"] == 0 and results["n_runs"] == len(exp.groups["stage1"]) * 2
    for row in results["rows"]:
        assert row["n"] == 2
        if row["n_ok"]:
            assert {"tt_position_train", "tt_position_test", "tt_motor_test"} <= set(
                row["metrics"])
    text = fidelity_d.report(json.loads((out / "results.json").read_text()), out)
    assert "Stage 1" in text and "Stage 2" not in text  # stage 2 not run yet
    assert (out / "fig_train_error.png").stat().st_size > 0
    assert (out / "fig_test_error.png").stat().st_size > 0
