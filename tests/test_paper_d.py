"""Paper D module: rows match the paper's design, and a --quick sweep runs end to end."""

from __future__ import annotations

import json

import numpy as np
import pytest
import skinny_mj.experiments as experiments
from skinny_mj.experiments import paper_d

from skinny_mj.engine.experiment import run_sweep
from skinny_mj.engine.stats import load_runs, summarize


def test_registered_and_described():
    assert experiments.get("paper-d") is paper_d.STUDY
    assert "YMCA" in experiments.describe("paper-d")


def test_rows_follow_the_papers_design():
    study = paper_d.STUDY
    cfg = study.base
    assert (cfg.plant.dof, cfg.plant.signals, cfg.esn.spectral_radius, cfg.plant.sensor_noise,
            study.runs) == (
        8, "cartesian", 0.5, 0.01, 50)
    plan = study.build()
    got = {}
    for row in study.rows:
        c = plan.trainings(row.id)
        tt, fel = c["tt"], c["fel"]
        assert tt.method.kind == "true-target" and fel.method.kind == row.overrides["method"]
        assert tt.noise_level == fel.noise_level and tt.movement.reps == fel.movement.reps
        assert set(row.paper) == {m for k in paper_d.COLUMNS for m in (k, f"{k}_var")}
        got[row.id] = (fel.method.kind, fel.noise_level, fel.movement.reps, fel.learning_cycles,
                       tt.method.beta, fel.method.beta)
    assert got == {
        "1": ("original", 0.0, 1, 1, 1.0, 1.0),
        "2": ("original", 0.2, 1, 1, 1.0, 1.0),
        "3a": ("original", 0.2, 5, 1, 1.0, 1.0),
        "3b": ("original", 0.2, 10, 1, 1.0, 1.0),
        "4": ("new", 0.2, 1, 5, 0.1, 0.1),
    }
    # 50 rounds for the new method in both architectures: 5 cycles x 10 gains, 50 TT rounds.
    assert paper_d.FEL_CYCLES * cfg.method.epochs == paper_d.TT_CYCLES == 50
    assert all(plan.trainings(r.id)["tt"].method.cycles == 50 for r in study.rows)
    assert [r.id for r in study.rows] == ["1", "2", "3a", "3b", "4"]


def test_build_options():
    exp = paper_d.STUDY.build(quick=True, movement="y")
    tt = exp.trainings("2")["tt"]
    fel = exp.trainings("2")["fel"]
    assert exp.runs == 2 and fel.method.epochs == 2 and tt.method.cycles == 3
    assert tt.movement.trajectory == "y" and len(exp.rows) == 5
    assert exp.name == paper_d.STUDY.build().name == "paper-d"  # the movement is in the config
    two_d = paper_d.STUDY.build(body=4, signals="joint").config("1")
    assert (two_d.plant.dof, two_d.plant.signals) == (4, "joint")
    assert set(paper_d.COLUMNS) <= set(exp.table_columns)


@pytest.fixture(scope="module")
def quick_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper_d")
    exp = paper_d.STUDY.build(quick=True)
    results = run_sweep(exp, out, workers=1, progress=False)
    return exp, out, results


def test_quick_sweep_is_complete(quick_sweep):
    exp, out, results = quick_sweep
    assert [r["row"] for r in results["rows"]] == list(paper_d.EXPERIMENTS)
    for row in results["rows"]:
        assert row["n_ok"] == 2 and row["n_failed"] == 0
        for metric in (*paper_d.COLUMNS, "fel_motor_test"):
            st = row["metrics"][metric]
            if st["n"]:  # a diverged architecture gives None, counted in *_failed
                assert 0 <= st["mean"] < 1.5
        assert row["paper"]["tt_position_test"] == paper_d.PAPER_TABLE_1[row["row"]][2][0]
    table = (out / "table.md").read_text()
    assert table.count("\n| 3") == 2 and "TT pos test (paper)" in table
    assert "FEL pos test (ours: mean (var))" in table


def test_results_equal_aggregate_of_run_files(quick_sweep):
    _, out, _ = quick_sweep
    saved = json.loads((out / "results.json").read_text())
    runs = load_runs(out)
    assert len(runs) == 10
    for row in saved["rows"]:
        for metric, st in row["metrics"].items():
            vals = [r["metrics"][metric] for r in runs if r["row"] == row["row"]]
            assert st == pytest.approx(summarize(vals))


def test_both_architectures_are_trained_and_differ(quick_sweep):
    _, out, _ = quick_sweep
    for run in load_runs(out):
        m = run["metrics"]
        assert m["tt_wall_s"] > 0 and m["fel_wall_s"] > 0
        if not (m["tt_failed"] or m["fel_failed"]):
            # Teacher-forced training error is far below the closed-loop test error.
            assert m["tt_position_train"] < m["tt_position_test"]
            assert m["tt_position_test"] != m["fel_position_test"]


def test_report_writes_figures_and_claims(quick_sweep):
    exp, out, results = quick_sweep
    text = exp.report(results, out)
    for name in ("fig3_tt_position_test", "fig3_tt_motor_test", "fig3_fel_position_test",
                 "fig4_right_arm_tt"):
        assert (out / f"{name}.png").stat().st_size > 1000
    assert len([ln for ln in text.splitlines() if ln.startswith("- [")]) == \
        len(paper_d.CLAIMS) + 3
    assert "reproduce their run files (3/3)" in text and "[holds] the Figure 4" in text
    assert len(list(out.glob("exp*_tt_average_run.rrd"))) == 3
    assert "TT: reservoir noise improves testing" in text


def test_run_one_is_reproducible_from_its_seed():
    exp = paper_d.STUDY.build(quick=True)
    cfg = exp.config("2").override({"esn.n_reservoir": 30})
    a, b = (paper_d.STUDY.run(cfg, paper_d.STUDY.row("2"), [7])[0] for _ in range(2))
    c = paper_d.STUDY.run(cfg, paper_d.STUDY.row("2"), [8])[0]
    keys = [*paper_d.COLUMNS]
    assert [a[k] for k in keys] == [b[k] for k in keys]
    assert not np.allclose([a[k] for k in keys], [c[k] for k in keys])


def test_lockstep_batch_equals_one_run_at_a_time():
    exp = paper_d.STUDY.build(quick=True)
    row = next(r for r in exp.rows if r.id == "2")
    single = [exp.run_one(row, seed) for seed in (11, 12)]
    batch = exp.run_batch(row, [11, 12])
    for one, many in zip(single, batch, strict=True):
        assert {k: v for k, v in one.items() if not k.endswith("wall_s")} == \
            {k: v for k, v in many.items() if not k.endswith("wall_s")}
