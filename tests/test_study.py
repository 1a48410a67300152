"""A study as data (skinny_mj.engine.study, skinny_mj.engine.plan), the ad-hoc grid of
``skinny sweep`` (skinny_mj.engine.grid) and the run-file comparison
(skinny_mj.engine.compare)."""

from __future__ import annotations

import dataclasses
import json

import pytest

from skinny_mj.cli.parser import main
from skinny_mj.engine import compare
from skinny_mj.engine.experiment import run_seed, run_sweep
from skinny_mj.engine.grid import grid_study
from skinny_mj.engine.plan import Results, plan, read_metric
from skinny_mj.engine.study import Quick, Row, Study
from skinny_mj.errors import SkinnyInputError
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.overrides import parse_value


def toy_run(config: TrainConfig, row: Row, seeds: list[int]) -> list:
    """A run without training: the config and params it was given, per seed."""
    return [{"reservoir": config.esn.n_reservoir, "epochs": config.method.epochs,
             "k": row.params["k"],
             "seed": s} for s in seeds]


def toy(**changes) -> Study:
    rows = (Row("a", {"esn.n_reservoir": 30}, group="g", params={"k": 1}),
            Row("b", {"esn.n_reservoir": 40}, {"x": 0.5}, runs=1, group="g", params={"k": 2},
                quick={"k": 3, "esn.n_reservoir": 35}),
            Row("c", {"method.epochs": 3}, seeds_of="a", params={"k": 4}),
            Row("q", {"esn.n_reservoir": 25}, params={"k": 5}, quick_only=True))
    return Study(**{"name": "toy", "rows": rows, "run_batch": toy_run, "runs": 3,
                    "params": {"k": 0, "tol": 0.1}, "groups": {"all": ("g", "c")},
                    "quick": Quick({"method.epochs": 2}, runs=2, rows=("g", "c", "q")),
                    **changes})


def test_rows_configs_params_groups_and_quick_are_derived():
    full = plan(toy())
    assert [p.id for p in full.rows] == ["a", "b", "c"]  # q only in quick sweeps
    assert full.config("a").esn.n_reservoir == 30 and full.config("c").method.epochs == 3
    assert full.run_row("b").params == {"k": 2, "tol": 0.1}
    assert full.groups == {"g": ("a", "b"), "all": ("a", "b", "c")}
    quick = plan(toy(), quick=True)
    assert [p.id for p in quick.rows] == ["a", "b", "c", "q"]
    assert quick.config("b").esn.n_reservoir == 35 and quick.row("b").params["k"] == 3
    assert quick.config("c").method.epochs == 2  # Quick.overrides come after the row's
    exp = toy().build(quick=True)
    assert exp.runs == 2 and [r.runs for r in exp.rows] == [None, 1, None, None]
    assert exp.rows[1].settings == {"esn.n_reservoir": 35, "k": 3}  # what run files record
    with pytest.raises(SkinnyInputError, match="seeds_of no row"):
        toy(quick=Quick(rows=("c",))).build(quick=True)  # c takes a's seeds: a must run


def test_options_are_overrides_of_the_base_and_refused_when_not_taken():
    exp = toy().build(movement="md_02.amc", asf=None, body=8, signals="joint")
    assert {(c.movement.trajectory, c.plant.dof, c.plant.signals) for c in
            (exp.config(r.id) for r in exp.rows)} == {("md_02.amc", 8, "joint")}
    with pytest.raises(SkinnyInputError, match="takes no --body"):
        toy(takes=("movement",)).build(body=8)
    with pytest.raises(SkinnyInputError, match="unknown config key"):
        Study("bad", (Row("a", {"no_such_key": 1}),), metrics={"x": "wall_s"}).build()



def _with_movement(study: Study, movement: str, asf: str | None) -> Study:
    """A study that takes ``--movement`` its own way: one more row, a param."""
    return dataclasses.replace(study, rows=(*study.rows, Row("own", {"method.epochs": 5},
                                                              params={"k": 9})),
                               params={**study.params, "moved": (movement, asf)})


def test_an_own_option_derives_the_study_and_sets_no_config_key():
    study = toy(own_options={"movement": _with_movement})
    assert plan(study).to_dict() == plan(toy()).to_dict()  # not given: the study as it is
    moved = plan(study, movement="y", asf="s.asf", body=8)
    assert [p.id for p in moved.rows] == ["a", "b", "c", "own"]
    assert moved.params["moved"] == ("y", "s.asf") and moved.row("own").params["k"] == 9
    assert {moved.config(i).movement.trajectory for i in ("a", "own")} == \
        {TrainConfig().movement.trajectory}  # --movement set no config key
    assert moved.config("own").plant.dof == 8  # --dof still one
    with pytest.raises(SkinnyInputError, match="own_options .* it does not take"):
        toy(own_options={"dof": _with_movement}, takes=("movement",))

def test_sweep_runs_the_custom_run_with_the_sweeps_seeds(tmp_path):
    exp = toy().build(quick=True)
    results = run_sweep(exp, tmp_path, workers=1, progress=False)
    runs = {(r["row"], r["run_index"]): r for r in Results(results, tmp_path).runs()}
    assert runs[("b", 0)]["metrics"]["reservoir"] == 35
    assert runs[("c", 1)]["seed"] == run_seed(0, "a", 1) == runs[("c", 1)]["metrics"]["seed"]
    assert runs[("q", 0)]["seed"] == run_seed(0, "q", 0)  # by the row's id
    config = json.loads((tmp_path / "config.json").read_text())["config"]
    assert config["after_rows"] == {"method.epochs": 2} and config["base"]["esn.n_reservoir"] == 200
    assert Results(results, tmp_path).values("c", "k") == [4, 4]


def test_a_report_gets_typed_results_and_the_plan(tmp_path):
    seen = {}

    def report(results, plan, out_dir):
        seen.update(values=results.values("a", "k"), base=plan.base, out=out_dir)
        return "claims"

    exp = toy(report=report).build()
    results = run_sweep(exp, tmp_path, rows=["a"], runs=1, workers=1, progress=False)
    assert exp.report(results, tmp_path) == "claims"
    assert seen == {"values": [1], "base": TrainConfig(), "out": tmp_path}


def test_quick_params_columns_and_the_studys_cost_memory_and_unavailable_hooks(tmp_path):
    from skinny_mj import preflight
    from skinny_mj.engine.memory import row_estimate

    study = toy(quick=Quick({"method.epochs": 2}, runs=2, rows=("g", "c"), params={"tol": 0.5},
                            columns=("k",)),
                columns=("reservoir", "k"),
                cost=lambda config, row: float(config.esn.n_reservoir + row.params["k"]),
                memory=lambda config, row, runs: None if row.id == "a" else
                preflight.Estimate({"x": runs * config.esn.n_reservoir}, {"x": "toy"}),
                unavailable=lambda: {"c": "needs a package", "q": "is not in this sweep"})
    full, quick = study.build(), study.build(quick=True)
    assert full.params == {"k": 0, "tol": 0.1} and full.table_columns == ("reservoir", "k")
    assert quick.params == {"k": 0, "tol": 0.5} and quick.table_columns == ("k",)
    assert quick.run_row("a").params == {"k": 1, "tol": 0.5}  # a row's own params win
    assert json.loads(json.dumps(quick.to_dict()))["params"]["tol"] == 0.5
    assert [full.cost(r) for r in full.rows] == [31.0, 42.0, 204.0]
    assert full.unavailable == {"c": "needs a package"}  # of the rows this sweep has
    rows = {r.id: r for r in full.rows}
    assert row_estimate(study, full, rows["b"], 3).parts == {"x": 120}
    # no estimate of its own: the row's training configuration's
    assert row_estimate(study, full, rows["a"], 3).total > 0
    with pytest.raises(SkinnyInputError, match="row 'c' needs a package"):
        run_sweep(full, tmp_path, rows=["c"], workers=1, progress=False)


def test_read_metric_follows_dotted_paths_of_the_run_file_or_calls():
    from skinny_mj.training.loop import train_batch

    (result,) = train_batch(TrainConfig().override(
        {"method.epochs": 1, "method.cycles": 1, "esn.n_reservoir": 20}), [0])
    assert read_metric(result, "test.position_nrmse") == result.test.position_nrmse > 0
    assert read_metric(result, "test.nope") is None
    assert read_metric(result, "train.gains") == result.train.gains and len(result.train.gains) == 1
    assert read_metric(result, lambda r: r.wall_s * 2) == result.wall_s * 2


def test_a_study_checks_its_rows():
    with pytest.raises(SkinnyInputError, match="unique row ids"):
        Study("s", (Row("a"), Row("a")), metrics={"x": "wall_s"})
    with pytest.raises(SkinnyInputError, match="both a config override and"):
        Row("a", {"k": 1}, params={"k": 2})
    with pytest.raises(SkinnyInputError, match="no metrics and no run_batch"):
        Study("s", (Row("a"),))
    with pytest.raises(SkinnyInputError, match="groups name no row or group"):
        Study("s", (Row("a"),), metrics={"x": "wall_s"}, groups={"g": ("zz",)})
    with pytest.raises(SkinnyInputError, match="plain file-name word"):
        Study("s", (Row("a/b"),), metrics={"x": "wall_s"}).build()


# -- skinny sweep --------------------------------------------------------------------------
def test_grid_values_take_the_fields_type():
    cfg = TrainConfig()
    assert parse_value(cfg, "esn.spectral_radius", "0.9") == 0.9
    assert parse_value(cfg, "esn.n_reservoir", "3") == 3
    assert parse_value(cfg, "esn.noise_level", "none") is None
    assert parse_value(cfg, "test.noise", "yes") is True
    assert parse_value(cfg, "movement.trajectory", "ymca") == "ymca"
    for text, key in (("x", "esn.spectral_radius"), ("1.5", "esn.n_reservoir"),
                      ("maybe", "test.noise"), ("none", "esn.n_reservoir")):
        with pytest.raises(SkinnyInputError):
            parse_value(cfg, key, text)


def test_a_grid_parses_a_types_settings_after_the_type_is_chosen():
    study = grid_study(["actuation.feedback=pd,inertia-pd", "actuation=torque"])
    assert study.base.torque is not None
    assert [r.overrides["actuation.feedback"] for r in study.rows] == ["pd", "inertia-pd"]


def test_grid_rows_are_the_product_of_the_swept_keys():
    study = grid_study(["esn.spectral_radius=0.5,0.9", "esn.n_reservoir=100,200",
                        "method.epochs=2"])
    assert [r.id for r in study.rows] == [
        "esn.spectral_radius=0.5+esn.n_reservoir=100",
        "esn.spectral_radius=0.5+esn.n_reservoir=200",
        "esn.spectral_radius=0.9+esn.n_reservoir=100",
        "esn.spectral_radius=0.9+esn.n_reservoir=200"]
    assert study.base.method.epochs == 2 and study.rows[3].overrides == {
        "esn.spectral_radius": 0.9, "esn.n_reservoir": 200}
    quoted = grid_study(["movement.trajectory='md_02.amc@start=3,duration=6.26',ymca"])
    assert [r.overrides["movement.trajectory"] for r in quoted.rows] == [
        "md_02.amc@start=3,duration=6.26", "ymca"]
    assert all(Row(r.id) for r in quoted.rows)  # plain file-name words
    for bad in (["reservoir"], ["esn.n_reservoir=1,1"], ["no_such=1"], ["method.epochs=0,1"], []):
        with pytest.raises(SkinnyInputError):
            grid_study(bad)


def test_skinny_sweep_runs_resumes_and_refuses_in_one_line(tmp_path, capsys):
    out = tmp_path / "sr"
    args = ["sweep", "esn.spectral_radius=0.5,0.9", "method.epochs=1", "esn.n_reservoir=20",
            "--runs", "1",
            "--workers", "1", "--out", str(out), "-q"]
    assert main(args) == 0
    table = (out / "table.md").read_text()
    assert "| esn.spectral_radius=0.9 | 0 / 1 |" in table and "position_nrmse" in table
    files = sorted(p.name for p in (out / "runs").glob("*.json"))
    assert files == [f"esn.spectral_radius={v}-{run_seed(0, f'esn.spectral_radius={v}', 0)}.json"
                     for v in ("0.5", "0.9")]
    before = {p: p.stat().st_mtime_ns for p in (out / "runs").iterdir()}
    assert main([*args, "--resume"]) == 0
    assert {p: p.stat().st_mtime_ns for p in (out / "runs").iterdir()} == before
    capsys.readouterr()
    assert main(["sweep", "esn.spectral_radius=x"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "must be a number" in err


def test_a_quick_grid_is_a_smoke_test_of_its_base_and_the_axes_keep_their_values():
    quick = grid_study(["esn.spectral_radius=0.5,0.9"], quick=True)
    assert (quick.base.method.epochs, quick.runs) == (2, 2)
    assert grid_study(["esn.spectral_radius=0.5,0.9"], quick=True, runs=3).runs == 3
    swept = grid_study(["method.epochs=5,6"], quick=True)  # the axis after --quick's keys
    assert [swept.base.override(dict(r.overrides)).method.epochs for r in swept.rows] == [5, 6]
    tt = grid_study(["method.cycles=2,3"], quick=True,  # a method without epochs: left as it is
                    base=TrainConfig().override({"method": "true-target"}))
    assert tt.base.method.kind == "true-target"
    full = grid_study(["esn.spectral_radius=0.5,0.9"], study=toy(), row="b")
    assert (full.base.esn.n_reservoir, full.rows[0].params["k"], full.runs) == (40, 2, 10)
    small = grid_study(["esn.spectral_radius=0.5,0.9"], study=toy(), row="b", quick=True)
    assert (small.base.esn.n_reservoir, small.base.method.epochs) == (35, 2)  # the study's quick
    assert (small.rows[0].params["k"], small.runs) == (3, 2)
    with pytest.raises(SkinnyInputError, match="two bases"):
        grid_study(["esn.spectral_radius=0.5,0.9"], study=toy(), row="b", base=TrainConfig())


def test_skinny_sweep_starts_from_a_config_file_and_quick_shrinks_it(tmp_path, capsys):
    run_file = tmp_path / "metrics.json"  # what `skinny train` writes: config and seed
    run_file.write_text(json.dumps({"config": {"movement.trajectory": "y", "method.epochs": 7,
                                               "esn.n_reservoir": 20}, "seed": 3}))
    out = tmp_path / "sw"
    assert main(["sweep", "esn.spectral_radius=0.5,0.9", "--config", str(run_file),
                 "--quick", "--workers", "1", "--out", str(out), "-q"]) == 0
    recorded = json.loads((out / "config.json").read_text())
    base = recorded["config"]["base"]
    assert (base["movement.trajectory"], base["esn.n_reservoir"], base["method.epochs"]) == \
        ("y", 20, 2)  # the file's, then --quick's 2 epochs
    assert recorded["options"]["quick"] is True
    assert recorded["options"]["config"] == str(run_file)
    assert len(list((out / "runs").glob("*.json"))) == 4  # 2 rows x --quick's 2 runs
    capsys.readouterr()
    assert main(["sweep", "esn.spectral_radius=0.5,0.9", "--config",
                 str(tmp_path / "missing.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "no such config file" in err


# -- comparing two sweep folders ----------------------------------------------------------
def test_compare_reports_metric_and_seed_differences_but_not_wall_time(tmp_path):
    exp = toy().build(quick=True)
    run_sweep(exp, tmp_path / "a", workers=1, progress=False)
    run_sweep(exp, tmp_path / "b", workers=1, progress=False)
    assert compare.compare(tmp_path / "a", tmp_path / "b") == ([], [])
    path = next((tmp_path / "b" / "runs").glob("b-*.json"))
    record = json.loads(path.read_text())
    record["metrics"]["k"] = 99
    record["params"] = {"renamed": 1}
    path.write_text(json.dumps(record))
    diffs, params = compare.compare(tmp_path / "a", tmp_path / "b")
    assert diffs == [f"{path.name}: metrics differ in ['k']"] and len(params) == 1
    next((tmp_path / "b" / "runs").glob("c-*.json")).unlink()
    assert compare.main([str(tmp_path / "a"), str(tmp_path / "b")]) == 1


def test_compare_leaves_out_measurements_inside_a_metrics_records(tmp_path):
    exp = toy().build(quick=True)
    run_sweep(exp, tmp_path / "a", rows=["a"], runs=1, workers=1, progress=False)
    run_sweep(exp, tmp_path / "b", rows=["a"], runs=1, workers=1, progress=False)
    (path,) = (tmp_path / "b" / "runs").glob("*.json")
    record = json.loads(path.read_text())
    record["metrics"].update(curve=[{"steps": 0, "wall_s": 9.0, "cpu_s": 9.0}],
                             cpu_to_0_05=3.0, wall_to_0_05=3.0)  # a learning curve's clocks
    path.write_text(json.dumps(record))
    (same,) = (tmp_path / "a" / "runs").glob("*.json")
    mine = json.loads(same.read_text())
    mine["metrics"].update(curve=[{"steps": 0, "wall_s": 1.0, "cpu_s": 1.0}])
    same.write_text(json.dumps(mine))
    assert compare.compare(tmp_path / "a", tmp_path / "b") == ([], [])
    record["metrics"]["curve"][0]["steps"] = 1  # a result inside the records: a difference
    path.write_text(json.dumps(record))
    assert compare.compare(tmp_path / "a", tmp_path / "b")[0] == [
        f"{path.name}: metrics differ in ['curve']"]


def _y_movement(config):
    from skinny_mj.trajectories import get

    return get("y", config.plant.dof)


def test_a_study_s_shapes_are_data_train_once_then_test_on_each():
    """``tests=``: the networks are trained once and take every test in order (the
    standard one, another movement, a changed test setting), each as ``evaluate`` gives it;
    ``failure=`` says which results are failed runs; ``trainings=`` trains several
    configurations from the same seeds."""
    from dataclasses import replace

    from skinny_mj.engine.experiment import RunFailed
    from skinny_mj.engine.study import Test
    from skinny_mj.training.loop import build_run, evaluate, train_run

    cfg = TrainConfig().override({"method.epochs": 1, "method.cycles": 1, "esn.n_reservoir": 20})
    study = Study("shapes", (Row("a"),), base=cfg, tests=(
        Test(), Test("y", _y_movement), Test("noisy", overrides={"test.noise": True})),
        metrics=lambda r: {name: t.position_nrmse for name, t in r.tests.items()})
    (got,) = study.run(cfg, study.row("a"), [3])
    run = build_run(cfg, [3])
    train_run(run)
    want = {"": evaluate(run)[0].position_nrmse,
            "y": evaluate(run, _y_movement(cfg))[0].position_nrmse,
            "noisy": evaluate(replace(run, cfg=cfg.override({"test.noise": True})))[0]
            .position_nrmse}
    assert got == want and got["noisy"] != got[""]
    failing = replace(study, failure=lambda r: f"seed {r.seed}")
    (failed,) = failing.run(cfg, study.row("a"), [3])
    assert isinstance(failed, RunFailed) and str(failed) == "seed 3"
    both = replace(study, tests=(Test(),), metrics=lambda rs: {
        k: r.test.position_nrmse for k, r in rs.items()},
        trainings=lambda c, row: {"one": c, "two": c.override({"esn.n_reservoir": 30})})
    (pair,) = both.run(cfg, study.row("a"), [3])
    assert pair["one"] == want[""] and pair["two"] != pair["one"]
