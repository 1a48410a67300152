"""Three-d (papers A, B, C on 2D and 3D): the engine's paired seeds (Row.seeds_of), the
rows built from the papers' own, a --quick pair of paper A run end to end (the 2D row is
the paper's own run, seed for seed), and the side-by-side claims."""

from __future__ import annotations

import json

import numpy as np
import pytest
from skinny_mj.experiments import paper_a
from skinny_mj.experiments.three_d import report as three_d_report
from skinny_mj.experiments.three_d import study as three_d
from toy import toy

from skinny_mj.engine import registry
from skinny_mj.engine.experiment import Row, run_sweep
from skinny_mj.engine.stats import load_runs
from skinny_mj.errors import SkinnyInputError


def _draw(row: Row, seed: int) -> dict:
    return {"value": float(np.random.default_rng(seed).normal())}


def test_a_row_with_seeds_of_takes_its_twins_seeds_and_config_records_it(tmp_path):
    rows = (Row("a"), Row("b", seeds_of="a"), Row("c"))
    exp = toy("pair", rows, _draw, runs=3, base_seed=5)
    run_sweep(exp, tmp_path / "all", workers=1, progress=False)
    seeds = {r: sorted(x["seed"] for x in load_runs(tmp_path / "all") if x["row"] == r)
             for r in "abc"}
    assert seeds["a"] == seeds["b"] and not set(seeds["a"]) & set(seeds["c"])
    config = json.loads((tmp_path / "all" / "config.json").read_text())
    assert [r.get("seeds_of") for r in config["rows"]] == [None, "a", None]
    assert "seeds_of" not in config["rows"][0]  # other experiments' config.json unchanged
    run_sweep(exp, tmp_path / "b", rows="b", workers=1, progress=False)  # --rows: same seeds
    assert sorted(x["seed"] for x in load_runs(tmp_path / "b")) == seeds["a"]
    with pytest.raises(SkinnyInputError, match="seeds_of"):  # at build, not mid-sweep
        toy("bad", (Row("a"), Row("b", seeds_of="z")), _draw)


def test_rows_are_the_papers_own_on_both_bodies_the_3d_twin_on_the_2d_seeds():
    exp = three_d.STUDY.build()
    ids = [r.id for r in exp.rows]
    n = sum(len(v) for v in three_d.SUBSET.values())
    assert len(ids) == 2 * n and exp.runs == 10
    for row in exp.rows:
        p, dim, rid = row.params["paper"], row.params["dim"], row.params["row"]
        assert row.id == f"{p}-{dim}-{rid}" and rid in three_d.SUBSET[p]
        assert row.seeds_of == (None if dim == "2d" else f"{p}-2d-{rid}")
        config = exp.config(row.id)
        own, paper_row = three_d.paper_of(config, exp.run_row(row.id))
        assert paper_row.id == rid and own.name == three_d.PAPERS[p]
        assert dict(row.paper) == dict(paper_row.paper)  # the paper's numbers, if any
        if p == "a":  # paper A's own row on the row's body
            trained = own.config(rid)
            assert (trained.plant.dof, trained.plant.signals) == \
                ((4, "joint") if dim == "2d" else (8, "cartesian"))
            assert trained == paper_a.STUDY.build(**({} if dim == "2d" else {
                "body": 8, "signals": "cartesian"})).config(rid)
    assert set(exp.groups["3d"]) == {i for i in ids if "-3d-" in i}
    quick = three_d.STUDY.build(quick=True)
    assert [r.id for r in quick.rows[:6]] == [
        "a-2d-inverse-d0", "a-2d-serial-d4", "b-2d-phase0", "b-2d-phase90", "c-2d-ymca",
        "c-2d-mirror-left"]  # each sweep's own order: its seeds
    body = three_d.STUDY.build(body=8, signals="joint")
    assert body.config("a-3d-serial-d4").plant.signals == "joint"
    assert body.config("a-2d-serial-d4").plant.signals == "joint"
    with pytest.raises(SkinnyInputError, match="takes no --movement"):
        three_d.STUDY.build(movement="ymca")


@pytest.fixture
def tiny_paper_a(monkeypatch):
    """Paper A's --quick sweep cut to 1 epoch of 1 cycle (this module's time budget)."""
    from dataclasses import replace

    from skinny_mj.engine.study import Quick

    quick = paper_a.STUDY.quick
    tiny = replace(paper_a.STUDY, quick=Quick({**quick.overrides, "method.epochs": 1,
                                               "method.cycles": 1}, quick.runs, quick.rows))
    real = registry.get
    monkeypatch.setattr(registry, "get", lambda name: tiny if name == "paper-a" else real(name))
    three_d.paper_experiment.cache_clear()
    yield replace(three_d.STUDY, rows=tuple(  # its paper-A rows run the tiny paper A
        replace(r, of=replace(r.of, study=tiny)) if r.params["paper"] == "a" else r
        for r in three_d.STUDY.rows))
    three_d.paper_experiment.cache_clear()


def test_quick_pair_end_to_end_2d_is_the_papers_own_run(tmp_path, tiny_paper_a):
    exp = tiny_paper_a.build(quick=True)
    results = run_sweep(exp, tmp_path, rows=["a-2d-inverse-d0", "a-3d-inverse-d0"], runs=1,
                        workers=1, progress=False)
    assert results["n_ok"] == 2
    runs = {r["row"]: r for r in load_runs(tmp_path)}
    two, three = runs["a-2d-inverse-d0"], runs["a-3d-inverse-d0"]
    assert two["seed"] == three["seed"]
    pa = registry.get("paper-a").build(quick=True)
    (own,) = pa.run_batch(next(r for r in pa.rows if r.id == "inverse-d0"), [two["seed"]])
    assert own["performance_nrmse"] == two["metrics"]["performance_nrmse"]
    assert two["metrics"]["performance_nrmse"] != three["metrics"]["performance_nrmse"]
    text = three_d_report.write_report(results, tmp_path, True, 8, "cartesian",
                                       figures=False)  # figures: the slow test
    assert (tmp_path / "three_d.md").read_text().strip() == text.strip()
    view = load_runs(tmp_path / "papers" / "a-3d")
    assert [(r["row"], r["experiment"], r["seed"]) for r in view] == [
        ("inverse-d0", "paper-a", three["seed"])]
    line = next(ln for ln in text.splitlines() if "inverse-d0 | performance" in ln)
    assert "0/1, 0/1" in line and "—" not in line.split("|")[4]
    assert text.count("| paper: ") == len(paper_a.claims(tmp_path / "papers" / "a-2d"))


def test_claims_side_by_side_splits_statement_from_numbers_and_counts_changes():
    two = ["- [holds] phase0 generalizes (rel. error < 0.3): worst = 0.1, lag = 3",
           "- [does NOT hold] Y pure -> YM: elbows still (range < 0.2): ratio 0.65 (ref: 1.0)",
           "- [n/a] freq2-3 fails: rel = n/a"]
    three = ["- [does NOT hold] phase0 generalizes (rel. error < 0.3): worst = 0.5, lag = 9",
             "- [does NOT hold] Y pure -> YM: elbows still (range < 0.2): ratio 0.91 (ref: 1.2)",
             "- [n/a] freq2-3 fails: rel = n/a"]
    table, pairs = three_d_report.claims_side_by_side(two, three)
    assert [p[0] for p in pairs] == ["phase0 generalizes (rel. error < 0.3)",
                                     "Y pure -> YM: elbows still (range < 0.2)",
                                     "freq2-3 fails: rel = n/a"]
    assert "| **holds** worst = 0.1, lag = 3 | **does NOT hold** worst = 0.5, lag = 9 |" in table
    line = three_d_report.summary_line(pairs)
    assert line.startswith("2D 1 of 2 checked hold, 3D 0 of 2 checked hold (3 claims)")
    assert "phase0 generalizes (rel. error < 0.3) (holds → does NOT hold)" in line
    assert "Y pure" not in line


def test_angle_nrmse_is_the_joint_angle_error_on_either_body():
    from skinny_mj.plant import body
    from skinny_mj.trajectories import get

    q = get("ymca", 8).angles
    assert three_d_report.angle_nrmse(q, q, 8) == 0.0
    assert three_d_report.angle_nrmse(q[:-1], q, 8) is None
    lo, hi = body.body_of(8).joint_ranges().T
    shifted = q + 0.01 * (hi - lo)  # 1 % of every range = 0.02 in normalized units
    assert three_d_report.angle_nrmse(shifted, q, 8) == pytest.approx(0.01, rel=1e-6)


@pytest.mark.slow
def test_report_makes_the_figure_and_each_papers_own_report_per_body(tmp_path, tiny_paper_a):
    exp = tiny_paper_a.build(quick=True)
    results = run_sweep(exp, tmp_path, rows="a-2d-inverse-d0,a-3d-inverse-d0", runs=1,
                        workers=1, progress=False)
    exp.report(results, tmp_path)
    assert (tmp_path / "three_d.png").stat().st_size > 10_000
    for dim in ("2d", "3d"):
        assert (tmp_path / "papers" / f"a-{dim}" / "fig4_error.png").is_file()
        assert "## Claims" in (tmp_path / "papers" / f"a-{dim}" / "claims.md").read_text()


def test_a_sweep_on_a_row_quick_does_not_keep_is_the_papers_row_under_its_quick_shrink():
    from skinny_mj.engine.grid import grid_study

    sweep = grid_study(["esn.spectral_radius=0.5,0.9"], study=three_d.STUDY,
                       row="a-3d-inverse-d10", quick=True).build()
    config = sweep.config(sweep.rows[1].id)
    own = paper_a.STUDY.config("inverse-d10", body=8, signals="cartesian")
    assert config == own.override({**paper_a.STUDY.quick.overrides,
                                   "esn.spectral_radius": 0.9})
