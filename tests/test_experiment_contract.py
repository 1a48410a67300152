"""The engine's contract on tiny fake experiments: row selection never changes seeds, a
diverged run (RunFailed) is data while any other exception is an error, a raising batch
falls back and says so, run files are validated, and ``skinny experiment`` exits 1 on
errored runs."""

from __future__ import annotations

import argparse
import functools
import json
import sys
import types
from pathlib import Path

import cloudpickle
import numpy as np
import pytest
from toy import toy

from skinny_mj.engine.experiment import (
    Row,
    RunFailed,
    markdown_table,
    run_seed,
    run_sweep,
    select_rows,
)
from skinny_mj.engine.plan import Experiment
from skinny_mj.engine.stats import MEANS_NOTE, load_runs
from skinny_mj.errors import SkinnyInputError

# Loky workers unpickle these fakes by value: they need not import the tests.
cloudpickle.register_pickle_by_value(sys.modules[__name__])

WORKERS = pytest.mark.parametrize("workers", [1, 2])


def run_one(row: Row, seed: int) -> dict:
    """ok, or RunFailed for a ``diverge`` row, or a bug (TypeError) for a ``bug`` row;
    ``bug_flag``: a file whose existence is the bug (delete it to "fix" the code)."""
    bug = row.params.get("bug")
    if bug is True or (isinstance(bug, str) and Path(bug).exists()):
        return {"value": None + 1.0}  # type: ignore[operator]  # a TypeError
    if row.params.get("diverge") and seed % 5 == 0:
        raise RunFailed(f"saturated at seed {seed}")
    rng = np.random.default_rng(seed)
    return {"value": float(rng.normal(row.params.get("mu", 0.0))), "seed_seen": seed}


def counting_run_one(log: Path, row: Row, seed: int) -> dict:
    with log.open("a") as f:
        f.write(f"{row.id}-{seed}\n")
    return run_one(row, seed)


def run_batch(config, row: Row, seeds: list[int]) -> list:
    out: list = []
    for seed in seeds:
        try:
            out.append(run_one(row, seed))
        except Exception as exc:  # RunFailed is data; others become error records
            out.append(exc)
    return out


def raising_batch(config, row: Row, seeds: list[int]) -> list:
    if len(seeds) > 1:
        raise MemoryError("lockstep batch too big")
    return run_batch(config, row, seeds)


def fake(*, rows: tuple[Row, ...] | None = None, one=run_one, runs: int = 3, groups=None,
         **study) -> Experiment:
    rows = rows or tuple(Row(i, params={"mu": mu})
                         for i, mu in zip("abc", (0.0, 1.0, 2.0), strict=True))
    return toy("fake", rows, one, params={"k": 1}, runs=runs, base_seed=3,
               columns=("value",), groups=groups or {}, **study)


def _files(out: Path) -> dict[str, dict]:
    """Run files without their wall-clock fields."""
    drop = ("wall_s", "finished_at")
    return {p.name: {k: v for k, v in json.loads(p.read_text()).items() if k not in drop}
            for p in sorted((out / "runs").glob("*.json"))}


# -- row selection -------------------------------------------------------------------------
@WORKERS
def test_selected_rows_get_the_full_sweeps_seeds_and_files(tmp_path, workers):
    run_sweep(fake(), tmp_path / "all", workers=workers, progress=False)
    run_sweep(fake(), tmp_path / "b", rows=["b"], workers=workers, progress=False)
    full, only_b = _files(tmp_path / "all"), _files(tmp_path / "b")
    assert sorted(only_b) == sorted(n for n in full if n.startswith("b-"))
    assert all(only_b[n] == full[n] for n in only_b)  # bit for bit
    assert sorted(r["seed"] for r in only_b.values()) == sorted(run_seed(3, "b", k)
                                                                 for k in range(3))
    config = json.loads((tmp_path / "b" / "config.json").read_text())
    assert config["selection"] == {"requested": ["b"], "rows": ["b"]}
    assert [r["row"] for r in config["rows"]] == ["a", "b", "c"]  # all rows recorded


def test_unknown_row_is_an_input_error_naming_ids_and_groups(tmp_path):
    exp = fake(groups={"pair": ("a", "b")})
    with pytest.raises(SkinnyInputError, match=r"'zz'.*groups: pair.*row ids: a, b, c"):
        run_sweep(exp, tmp_path / "out", rows=["a", "zz"], workers=1, progress=False)
    assert not (tmp_path / "out").exists()  # refused before writing anything
    with pytest.raises(SkinnyInputError, match="no rows"):
        select_rows(exp, [])


def test_groups_select_their_rows_in_experiment_order():
    exp = fake(groups={"pair": ("b", "a"), "last": ("c",)})
    assert [r.id for r in select_rows(exp, ["pair"])] == ["a", "b"]
    assert [r.id for r in select_rows(exp, "last, a")] == ["a", "c"]
    assert select_rows(exp, None) == exp.rows
    for bad in ({"a": ("b",)}, {"g": ("zz",)}):
        with pytest.raises(SkinnyInputError, match="group"):
            fake(groups=bad)


def test_resume_with_another_selection_adds_rows_and_aggregates_the_disk(tmp_path):
    log = tmp_path / "calls.txt"
    exp = fake(one=functools.partial(counting_run_one, log))
    run_sweep(exp, tmp_path / "out", rows=["a"], workers=1, progress=False)
    first = _files(tmp_path / "out")
    results = run_sweep(exp, tmp_path / "out", rows=["a", "b"], workers=1, resume=True,
                        progress=False)
    assert [r["row"] for r in results["rows"]] == ["a", "b"]
    assert {n: f for n, f in _files(tmp_path / "out").items() if n.startswith("a-")} == first
    assert sum(line.startswith("a-") for line in log.read_text().split()) == 3  # not rerun
    config = json.loads((tmp_path / "out" / "config.json").read_text())
    assert config["selection"]["rows"] == ["a"]
    assert config["resumes"][0]["selection"] == {"requested": ["a", "b"], "rows": ["a", "b"]}


# -- failed is data, error is a bug --------------------------------------------------------
@WORKERS
def test_an_exception_is_an_error_record_and_the_other_runs_finish(tmp_path, workers, caplog):
    rows = (Row("ok", params={"mu": 0.0}), Row("bug", params={"bug": True}),
            Row("div", params={"diverge": True}))
    results = run_sweep(fake(rows=rows), tmp_path, workers=workers, progress=False)
    by_row = {r["row"]: r for r in results["rows"]}
    assert by_row["ok"]["n_ok"] == 3 and by_row["bug"]["n_error"] == 3
    assert by_row["bug"]["n"] == 0 and by_row["bug"]["metrics"] == {}
    assert results["n_error"] == 3 and results["n_runs"] == 9
    for rec in load_runs(tmp_path):
        if rec["row"] == "bug":
            assert rec["status"] == "error" and rec["error"].startswith("TypeError:")
            assert "Traceback" in rec["traceback"] and "in run_one" in rec["traceback"]
            assert rec["metrics"] == {} and rec["fail_reason"] is None
        elif rec["row"] == "div" and rec["status"] == "failed":
            assert rec["fail_reason"].startswith("saturated") and rec["error"] is None
            assert "traceback" not in rec
    div = by_row["div"]
    assert div["n_failed"] + div["n_ok"] == div["n"] == 3 and div["n_error"] == 0
    assert div["n_failed"] >= 1  # seeds are fixed: those divisible by 5 diverge
    assert div["metrics"]["value"]["n"] == div["n_ok"]  # means over ok runs only
    warned = [r.getMessage() for r in caplog.records if r.name == "skinny_mj.engine.experiment"]
    assert sum("errored (a bug, not data): TypeError" in m for m in warned) == 3


def test_run_batch_results_map_to_ok_failed_and_error(tmp_path):
    rows = (Row("bug", params={"bug": True}), Row("div", params={"diverge": True}))
    run_sweep(fake(rows=rows, run_batch=run_batch), tmp_path / "batch", workers=1,
              progress=False)
    run_sweep(fake(rows=rows), tmp_path / "single", workers=1, progress=False, batch_size=0)
    batch, single = _files(tmp_path / "batch"), _files(tmp_path / "single")
    assert sorted(batch) == sorted(single)
    for name, rec in batch.items():
        assert rec["status"] == single[name]["status"]
        assert {k: v for k, v in rec.items() if k != "traceback"} == \
            {k: v for k, v in single[name].items() if k != "traceback"}
        assert "fallback" not in rec


@WORKERS
def test_a_raising_batch_falls_back_to_single_runs_and_says_so(tmp_path, workers, caplog):
    run_sweep(fake(run_batch=raising_batch), tmp_path / "fb", workers=workers, progress=False,
              batch_size=2)
    run_sweep(fake(), tmp_path / "single", workers=1, progress=False)
    fb, single = _files(tmp_path / "fb"), _files(tmp_path / "single")
    assert sorted(fb) == sorted(single)
    for name, rec in fb.items():  # a batch of 2 seeds raises, one of 1 runs
        if rec["run_index"] < 2:
            assert rec["fallback"] == "MemoryError: lockstep batch too big (batch of 2 seeds)"
            assert "raising_batch" in rec["fallback_traceback"]
        else:
            assert "fallback" not in rec
        assert {k: v for k, v in rec.items() if not k.startswith("fallback")} == single[name]
    results = json.loads((tmp_path / "fb" / "results.json").read_text())
    assert all(r["n_fallback"] == 2 and r["n_ok"] == 3 for r in results["rows"])
    assert "ran its seeds one by one" in caplog.text  # a warning of skinny_mj's logger


def test_resume_reruns_errored_runs_only(tmp_path):
    flag, log = tmp_path / "bug-present", tmp_path / "calls.txt"
    flag.touch()
    rows = (Row("ok", params={"mu": 0.0}), Row("bug", params={"bug": str(flag)}),
            Row("div", params={"diverge": True}))
    exp = fake(rows=rows, one=functools.partial(counting_run_one, log))
    first = run_sweep(exp, tmp_path / "out", workers=1, progress=False)
    assert first["n_error"] == 3
    flag.unlink()  # the bug is fixed
    calls_before = log.read_text().split()
    second = run_sweep(exp, tmp_path / "out", workers=1, resume=True, progress=False)
    rerun = log.read_text().split()[len(calls_before):]
    assert sorted(rerun) == sorted(c for c in calls_before if c.startswith("bug-"))
    assert second["n_error"] == 0
    assert next(r for r in second["rows"] if r["row"] == "bug")["n_ok"] == 3
    third = run_sweep(exp, tmp_path / "out", workers=1, resume=True, progress=False)
    assert log.read_text().split()[len(calls_before) + len(rerun):] == []  # nothing left
    assert third["rows"] == second["rows"]


# -- tables and run files ------------------------------------------------------------------
def test_table_shows_failed_over_n_with_errors_and_says_means_exclude_failures(tmp_path):
    rows = (Row("div", params={"diverge": True}, paper={"value": 0.5}),
            Row("bug", params={"bug": True}))
    results = run_sweep(fake(rows=rows, runs=4), tmp_path, workers=1, progress=False)
    table = (tmp_path / "table.md").read_text()
    div = results["rows"][0]
    assert f"| div | {div['n_failed']} / 4 |" in table and "| 0.5000 |" in table
    assert "| bug | 0 / 0 (+4 errors) |" in table
    assert "value (ours: mean (var))" in table and "value (paper)" in table
    assert MEANS_NOTE in table and "excluded" in MEANS_NOTE
    assert "bugs, not data" in table
    one = {"experiment": "x", "rows": [{"row": "r", "n": 20, "n_ok": 19, "n_failed": 1,
                                         "n_error": 1, "paper": {}, "metrics": {}}]}
    assert "| r | 1 / 20 (+1 error) |" in markdown_table(one, ["value"])


@pytest.mark.parametrize("damage, match", [
    (lambda p: p.write_text('{"row": "a", "seed"'), "not a readable JSON run file"),
    (lambda p: p.write_text(json.dumps({"row": "a"})), "lacks experiment, row_index"),
    (lambda p: p.write_text(json.dumps([1, 2])), "JSON list"),
    (lambda p: p.write_text(json.dumps({**json.loads(p.read_text()), "status": "meh"})),
     "status 'meh'"),
    (lambda p: p.rename(p.with_name("a-1.json")), "should be named"),
    (lambda p: p.with_name("notes.txt").write_text("hi"), "not a run file"),
])
def test_a_damaged_run_file_is_a_clear_error_naming_it(tmp_path, damage, match):
    run_sweep(fake(), tmp_path, workers=1, progress=False)
    path = sorted((tmp_path / "runs").glob("a-*.json"))[0]
    damage(path)
    with pytest.raises(SkinnyInputError, match=match) as info:
        load_runs(tmp_path)
    assert str(tmp_path / "runs") in str(info.value)
    with pytest.raises(SkinnyInputError):
        run_sweep(fake(), tmp_path, workers=1, resume=True, progress=False)


def test_leftover_temp_files_of_atomic_writes_are_ignored(tmp_path):
    run_sweep(fake(), tmp_path, workers=1, progress=False)
    (tmp_path / "runs" / ".a-1.json.k2j3.tmp").write_text('{"half": ')
    assert len(load_runs(tmp_path)) == 9


# -- the command line ----------------------------------------------------------------------
def _fake_module(calls: list, rows: tuple[Row, ...]) -> types.ModuleType:
    module = types.ModuleType("fake_paper", "A fake paper.")

    def build(*, quick, movement, asf, body, signals):
        calls.append({"quick": quick, "movement": movement, "asf": asf, "body": body,
                      "signals": signals})
        return fake(rows=rows, groups={"both": ("ok", rows[1].id)},
                    report=lambda results, plan, out: f"- {results['n_error']} errored")

    module.build = build  # type: ignore[attr-defined]
    return module


def _cli(monkeypatch, module: types.ModuleType, *argv: str) -> int:
    from skinny_mj.cli.parser import main
    from skinny_mj.engine import registry

    monkeypatch.setattr(registry, "get", lambda name: module)
    return main(["experiment", "fake", "--workers", "1", *argv])


def test_cli_exits_1_when_a_run_errored_and_still_writes_everything(tmp_path, monkeypatch,
                                                                     capsys):
    calls: list = []
    module = _fake_module(calls, (Row("ok", params={"mu": 0.0}), Row("bug", params={"bug": True})))
    out = tmp_path / "out"
    code = _cli(monkeypatch, module, "--out", str(out), "--movement", "ym", "--dof", "8",
                "--signals", "joint", "--rows", "both")
    assert code == 1
    assert calls == [{"quick": False, "movement": "ym", "asf": None, "body": 8,
                      "signals": "joint"}]
    printed = capsys.readouterr().out
    assert "3 run(s) errored (bugs, not data): see" in printed and "runs/*.json" in printed
    assert printed.index("| bug |") < printed.index("run(s) errored")
    assert {p.name for p in out.iterdir()} >= {"table.md", "claims.md", "results.json"}
    config = json.loads((out / "config.json").read_text())
    assert config["options"]["movement"] == "ym" and config["experiment"] == "fake"
    assert config["selection"] == {"requested": ["both"], "rows": ["ok", "bug"]}


def test_cli_exits_0_with_failed_runs_and_2_on_an_unknown_row(tmp_path, monkeypatch, capsys):
    module = _fake_module([], (Row("ok", params={"mu": 0.0}), Row("div", params={"diverge": True})))
    assert _cli(monkeypatch, module, "--out", str(tmp_path / "a"), "--quick") == 0
    assert "run(s) errored" not in capsys.readouterr().out
    assert _cli(monkeypatch, module, "--out", str(tmp_path / "b"), "--rows", "ok,nope") == 2
    assert "'nope'" in capsys.readouterr().err


def test_cli_parser_knows_body_dof_and_signals():
    from skinny_mj.cli.config_flags import chosen_body
    from skinny_mj.cli.parser import build_parser

    args = build_parser().parse_args(["experiment", "paper-e"])
    assert isinstance(args, argparse.Namespace) and args.signals is None
    assert chosen_body(args, None) is None  # the study's own
    for argv, body in ((["--body", "3d"], "3d"), (["--dof", "8"], 8),
                       (["--dof", "4", "--body", "2d"], "2d")):
        assert chosen_body(build_parser().parse_args(["experiment", "paper-e", *argv]),
                           None) == body
    for bad in (["--dof", "5"], ["--body", "4d"]):
        with pytest.raises(SystemExit):
            build_parser().parse_args(["experiment", "paper-e", *bad])
    with pytest.raises(SkinnyInputError, match="--dof 8 is the 3d body and --body 2d another"):
        chosen_body(build_parser().parse_args(["experiment", "paper-e", "--dof", "8",
                                               "--body", "2d"]), None)
