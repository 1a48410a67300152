"""The experiment engine on a tiny fake experiment (cheap NumPy runs)."""

from __future__ import annotations

import json
import uuid
from pathlib import Path

import numpy as np
import pytest
from toy import toy

from skinny_mj.engine.experiment import (
    Row,
    RunFailed,
    aggregate,
    markdown_table,
    run_seed,
    run_sweep,
)
from skinny_mj.engine.plan import Experiment
from skinny_mj.engine.stats import load_runs, summarize
from skinny_mj.errors import SkinnyInputError

#: ``run_seed(0, "1", 0)``, written down once: a change of the seeding shows here.
SEED_OF_ROW_1_RUN_0 = 1592038890


def make_run_one(marker_dir: Path | None = None):
    """A closure (pickled by value, so loky/dask workers need not import the tests)."""

    def run_one(row: Row, seed: int) -> dict:
        if marker_dir is not None:
            (marker_dir / f"{row.id}-{seed}-{uuid.uuid4().hex}").touch()
        if row.params.get("fail"):
            raise RunFailed("diverged on purpose")
        rng = np.random.default_rng(seed)
        x = rng.normal(row.params["mu"], 1.0, size=200)
        out = {"error": float(abs(x.mean())), "spread": float(x.std()),
               "curve": np.cumsum(x[:5]), "label": "ok"}
        if row.params.get("nan"):
            out["spread"] = float("nan")
        return out

    return run_one


def make_experiment(marker_dir: Path | None = None, *, fail: bool = False,
                    base_seed: int = 7, mu2: float = 1.0, **study) -> Experiment:
    rows = [Row("exp1", params={"mu": 0.5}, paper={"error": 0.4, "error_var": 0.0024}),
            Row("exp2", params={"mu": mu2}, paper={"error": 0.1})]
    if fail:
        rows.append(Row("bad", params={"mu": 0.0, "fail": True}))
    return toy("fake", rows, make_run_one(marker_dir), params={"n": 200}, runs=3,
               base_seed=base_seed, columns=("error", "spread"), **study)


def _without_wall(results: dict) -> dict:
    return {**results, "rows": [{k: v for k, v in r.items() if k != "wall_s"}
                                for r in results["rows"]]}


def test_run_seed_is_deterministic_and_distinct():
    seeds = {run_seed(0, row, k) for row in ("1", "2", "a", "b", "fig4") for k in range(20)}
    assert len(seeds) == 100
    assert run_seed(3, "a", 2) == run_seed(3, "a", 2) != run_seed(4, "a", 2)
    # fixed bits: the same on every machine and Python (no salted hash())
    assert run_seed(0, "1", 0) == SEED_OF_ROW_1_RUN_0
    with pytest.raises(TypeError, match="row id"):
        run_seed(0, 1, 0)


def test_a_rows_seeds_follow_its_id_not_its_place(tmp_path):
    def seed_of(row, seed):
        return {"seed": float(seed)}

    ab = toy("ab", (Row("a"), Row("b")), seed_of, runs=2)
    ba = toy("ab", (Row("x"), Row("b"), Row("a")), seed_of, runs=2)
    run_sweep(ab, tmp_path / "ab", workers=1, progress=False)
    run_sweep(ba, tmp_path / "ba", workers=1, progress=False)
    names = [sorted(p.name for p in (tmp_path / d / "runs").glob("[ab]-*.json"))
             for d in ("ab", "ba")]
    assert names[0] == names[1] and len(names[0]) == 4


def test_sweep_writes_layout_and_results_equal_aggregate_of_run_files(tmp_path):
    results = run_sweep(make_experiment(), tmp_path, workers=1, progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == \
        ["config.json", "results.json", "runs", "table.md"]
    assert len(list((tmp_path / "runs").glob("*.json"))) == 6
    on_disk = json.loads((tmp_path / "results.json").read_text())
    assert on_disk == results == aggregate(tmp_path, write=False)
    # recompute one statistic by hand from the run files
    errors = [r["metrics"]["error"] for r in load_runs(tmp_path) if r["row"] == "exp2"]
    row = next(r for r in results["rows"] if r["row"] == "exp2")
    assert row["metrics"]["error"]["mean"] == pytest.approx(np.mean(errors))
    assert row["metrics"]["error"]["variance"] == pytest.approx(np.var(errors, ddof=1))
    assert row["metrics"]["error"]["n"] == 3 and row["n_ok"] == 3 and row["n_failed"] == 0
    assert row["paper"] == {"error": 0.1}
    assert "curve" not in row["metrics"]  # lists are kept in the run file, not aggregated
    config = json.loads((tmp_path / "config.json").read_text())
    assert config["experiment"] == "fake" and config["runs"] == 3
    table = (tmp_path / "table.md").read_text()
    assert "| exp1 | 0 / 3 |" in table and "| 0.4000 (0.0024) |" in table
    assert "Means (variance) over the runs that did not fail" in table


def test_a_diverged_run_is_recorded_as_failed_data(tmp_path):
    results = run_sweep(make_experiment(fail=True), tmp_path, workers=1, progress=False)
    bad = next(r for r in results["rows"] if r["row"] == "bad")
    assert bad["n_failed"] == 3 and bad["n_ok"] == 0 and bad["metrics"] == {}
    assert bad["n"] == 3 and bad["n_error"] == 0 and results["n_error"] == 0
    assert bad["failures"][0]["fail_reason"] == "diverged on purpose"
    records = [r for r in load_runs(tmp_path) if r["row"] == "bad"]
    assert all(r["status"] == "failed" and r["fail_reason"] == "diverged on purpose"
               and r["error"] is None and "traceback" not in r for r in records)
    assert "| bad | 3 / 3 |" in (tmp_path / "table.md").read_text()


def test_nonfinite_metric_is_stored_as_null(tmp_path):
    exp = toy("fake", (Row("n", params={"mu": 0.0, "nan": True}),), make_run_one(), runs=2)
    results = run_sweep(exp, tmp_path, workers=1, progress=False)
    rec = load_runs(tmp_path)[0]
    assert rec["status"] == "ok" and rec["metrics"]["spread"] is None
    assert rec["nonfinite_metrics"] == ["spread"]
    assert results["rows"][0]["metrics"]["spread"]["n"] == 0


def test_resume_skips_finished_runs(tmp_path):
    out, markers = tmp_path / "out", tmp_path / "markers"
    markers.mkdir()
    first = run_sweep(make_experiment(markers), out, workers=1, progress=False)
    assert len(list(markers.iterdir())) == 6
    lost = sorted((out / "runs").glob("exp2-*.json"))[0]
    lost.unlink()
    second = run_sweep(make_experiment(markers), out, workers=1, resume=True, progress=False)
    called = sorted(p.name for p in markers.iterdir())
    assert len(called) == 7  # only the deleted run ran again
    assert sum(name.startswith(lost.stem + "-") for name in called) == 2
    assert _without_wall(second) == _without_wall(first)


def test_resume_refuses_a_different_sweep(tmp_path):
    run_sweep(make_experiment(), tmp_path, workers=1, progress=False)
    with pytest.raises(SkinnyInputError, match="different sweep"):
        run_sweep(make_experiment(mu2=2.0), tmp_path, workers=1, resume=True, progress=False)


def test_same_seed_same_numbers_other_seed_other_numbers(tmp_path):
    a = run_sweep(make_experiment(), tmp_path / "a", workers=1, progress=False)
    b = run_sweep(make_experiment(), tmp_path / "b", workers=1, progress=False)
    c = run_sweep(make_experiment(base_seed=8), tmp_path / "c", workers=1, progress=False)
    assert _without_wall(a) == _without_wall(b)
    assert a["rows"][0]["metrics"] != c["rows"][0]["metrics"]


def test_joblib_workers_give_identical_results_to_sequential(tmp_path):
    seq = run_sweep(make_experiment(fail=True), tmp_path / "seq", workers=1, progress=False)
    par = run_sweep(make_experiment(fail=True), tmp_path / "par", workers=2, progress=False)
    assert _without_wall(par) == _without_wall(seq)
    assert sorted(p.name for p in (tmp_path / "par" / "runs").iterdir()) == \
        sorted(p.name for p in (tmp_path / "seq" / "runs").iterdir())


def test_dask_local_cluster_gives_identical_results(tmp_path):
    pytest.importorskip("dask.distributed")
    seq = run_sweep(make_experiment(), tmp_path / "seq", workers=1, progress=False)
    dsk = run_sweep(make_experiment(), tmp_path / "dask", workers=2, scheduler="local",
                    progress=False)
    assert _without_wall(dsk) == _without_wall(seq)


def test_bad_arguments_are_input_errors(tmp_path):
    with pytest.raises(SkinnyInputError):
        Row("has space")
    with pytest.raises(SkinnyInputError):
        toy("fake", (Row("a"), Row("a")), make_run_one())
    with pytest.raises(SkinnyInputError):
        run_sweep(make_experiment(), tmp_path, runs=0, progress=False)
    with pytest.raises(SkinnyInputError):
        run_sweep(make_experiment(), None, resume=True, progress=False)


def test_summarize_and_markdown_table():
    st = summarize([1.0, 2.0, 3.0, None])
    assert st == {"mean": 2.0, "variance": 1.0, "sd": 1.0, "median": 2.0, "min": 1.0,
                  "max": 3.0, "n": 3}
    results = {"experiment": "x", "rows": [
        {"row": "r1", "n_ok": 3, "n_failed": 0, "paper": {"m": 0.5},
         "metrics": {"m": st}}]}
    table = markdown_table(results, {"m": "position NRMSE"})
    assert "position NRMSE (ours: mean (var))" in table and "position NRMSE (paper)" in table
    assert "| r1 | 0 / 3 | 2.0000 (1.0000) | 0.5000 |" in table


def test_an_unavailable_row_is_left_out_of_a_full_sweep_and_refused_by_name(tmp_path, caplog):
    full = make_experiment()
    exp = make_experiment(unavailable=lambda: {"exp1": "needs a package"})
    run_sweep(exp, tmp_path / "s", workers=1, progress=False)
    assert "row exp1 left out: it needs a package" in caplog.text  # a logging warning
    runs = load_runs(tmp_path / "s")
    assert {r["row"] for r in runs} == {"exp2"}
    # the other rows keep the seeds of the full experiment
    run_sweep(full, tmp_path / "all", workers=1, progress=False)
    seeds = {r["seed"] for r in load_runs(tmp_path / "all") if r["row"] == "exp2"}
    assert {r["seed"] for r in runs} == seeds
    with pytest.raises(SkinnyInputError, match="row 'exp1' needs a package"):
        run_sweep(exp, tmp_path / "named", rows="exp1", workers=1, progress=False)
