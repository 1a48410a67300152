"""Paper D's fidelity: the true-target grid (input noise × N × movement) on paper D's rows."""

from __future__ import annotations

import pytest
import skinny_mj.experiments as experiments
from skinny_mj.experiments import paper_d
from skinny_mj.experiments.fidelity_d import report as fidelity_d_report
from skinny_mj.experiments.fidelity_d import study as fidelity_d

from skinny_mj.engine.experiment import run_sweep
from skinny_mj.engine.plan import Results
from skinny_mj.training.loop import build_run, train_run


def test_registered_rows_and_groups():
    assert experiments.get("fidelity-d") is fidelity_d.STUDY
    exp = fidelity_d.STUDY.build()
    grid = fidelity_d.grid_of(exp)
    assert grid == fidelity_d.Grid()
    assert len(exp.rows) == len(grid.movements) * len(grid.reservoirs) \
        * len(grid.input_noises) * 5
    ids = {r.id for r in exp.rows}
    assert "recorded-n200-i0.03-e3b" in ids and "smooth-n400-i0-e4" in ids
    assert not any("-n20-" in i for i in ids)  # the quick grid's rows are quick only
    assert {r.split("-e")[-1] for r in exp.groups["stage1"]} == {"1", "2"}
    assert len(exp.groups["stage1"]) == len(exp.rows) * 2 // 5
    assert exp.groups["smooth-n100-i0.05"] == tuple(f"smooth-n100-i0.05-e{e}"
                                                    for e in fidelity_d.EXPS)
    for cell in fidelity_d.STAGE_2_CELLS:  # stage 2 = all five exps at each picked cell
        assert set(exp.groups[cell]) <= set(exp.groups["stage2"])
    quick = fidelity_d.STUDY.build(quick=True)
    assert set(quick.groups["stage2"]) == {r.id for r in quick.rows}
    assert fidelity_d.grid_of(quick) == fidelity_d.QUICK_GRID


def test_rows_are_paper_d_true_target_configs_plus_the_grid():
    plan = fidelity_d.STUDY.build()
    for r in plan.rows:
        p = plan.run_row(r.id).params
        if p["movement"] != "smooth" or p["reservoir"] != 200 or p["input_noise"]:
            continue
        exp = p["exp"]
        want = paper_d.STUDY.build().trainings(exp)["tt"]
        assert plan.trainings(r.id)["tt"] == \
            want.override({"movement.trajectory": "ymca-smooth"})
        assert r.paper["tt_position_test"] == paper_d.PAPER_TABLE_1[exp][2][0]


def test_input_noise_raises_the_training_error():
    plan = fidelity_d.STUDY.build(quick=True)
    errors = {}
    for noise in ("0", "0.05"):  # the same seed: the same reservoir, only the inputs differ
        tt = train_run(build_run(plan.trainings(f"smooth-n20-i{noise}-e1")["tt"],
                                 [3])).true_target
        errors[noise] = (tt.motor_nrmse[0], tt.position_nrmse[0])
    assert errors["0.05"][0] > errors["0"][0] and errors["0.05"][1] > errors["0"][1]


@pytest.fixture(scope="module")
def quick_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("fidelity_d")
    exp = fidelity_d.STUDY.build(quick=True)
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
    text = fidelity_d_report.report(Results(results, out), exp, out)
    assert "Stage 1" in text and "Stage 2" not in text  # stage 2 not run yet
    assert (out / "fig_train_error.png").stat().st_size > 0
    assert (out / "fig_test_error.png").stat().st_size > 0
