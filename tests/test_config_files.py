"""Runs repeat from the files they wrote: ``skinny train --config metrics.json`` and
``skinny experiment NAME --config config.json``; flags given as well override fields."""

from __future__ import annotations

import json
import types
from functools import partial
from pathlib import Path

import pytest

from skinny_mj import registry
from skinny_mj.cli import main
from skinny_mj.experiment import Experiment, Row

TINY = ["--reservoir", "30", "--epochs", "1", "--quiet"]


def _metrics(folder: Path) -> dict:
    m = json.loads((folder / "metrics.json").read_text())
    m.pop("wall_s")  # the one number that is not the run's
    return m


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("train") / "a"
    assert main(["train", *TINY, "--beta", "0.3", "--seed", "5", "--out", str(out)]) == 0
    return out


def test_train_repeats_from_its_metrics_json(trained, tmp_path):
    assert main(["train", "--config", str(trained / "metrics.json"), "--quiet",
                 "--out", str(tmp_path / "b")]) == 0
    again = _metrics(tmp_path / "b")
    assert again == _metrics(trained)  # config, seed, every metric: bit for bit
    assert again["seed"] == 5 and again["config"]["beta"] == 0.3


def test_train_flags_override_only_what_they_name(trained, tmp_path):
    assert main(["train", "--config", str(trained / "metrics.json"), "--epochs", "2",
                 "--seed", "6", "--quiet", "--out", str(tmp_path / "c")]) == 0
    m, first = _metrics(tmp_path / "c"), _metrics(trained)
    assert m["seed"] == 6 and m["config"]["epochs"] == 2
    # every other field is the file's, not an argparse default (reservoir 30, not 200)
    assert {k: v for k, v in m["config"].items() if k not in ("epochs", "learning_cycles")} \
        == {k: v for k, v in first["config"].items() if k not in ("epochs", "learning_cycles")}


def test_train_takes_a_bare_config(tmp_path):
    (tmp_path / "cfg.json").write_text(json.dumps({"reservoir": 30, "epochs": 1,
                                                   "method": "original"}))
    assert main(["train", "--config", str(tmp_path / "cfg.json"), "--quiet", "--seed", "2",
                 "--out", str(tmp_path / "o")]) == 0
    m = _metrics(tmp_path / "o")
    assert m["config"]["method"] == "original" and m["config"]["reservoir"] == 30
    assert m["seed"] == 2


@pytest.mark.parametrize("content, needle", [
    ("{not json", "not a JSON config"),
    ("[1, 2]", "JSON object"),
    ('{"epochs": "three"}', "bad training config"),
    ('{"no_such_field": 1}', "unknown training config field"),
    ('{"experiment": "paper_e", "options": {}, "selection": {}}', "sweep's config.json"),
    ('{"config": {"reservoir": 30}, "seed": "x"}', "seed"),
])
def test_bad_train_config_is_one_line_exit_2(content, needle, tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text(content)
    assert main(["train", "--config", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0] and str(bad) in err[0]
    assert not (tmp_path / "o").exists()


# -- experiments: a toy module through the registry (the engine and CLI are the real ones)
def _toy_run(quick: bool, dof: int, row: Row, seed: int) -> dict:
    return {"score": (seed % 1000) * row.params["k"] / (10.0 if quick else 1.0) + dof}


def _toy_module() -> types.ModuleType:
    toy = types.ModuleType("toy_experiment")
    toy.NAME = "toy"

    def build(*, quick=False, movement=None, asf=None, dof=None, signals=None):
        dof = 4 if dof is None else dof
        return Experiment(name="toy", rows=tuple(Row(str(k), {"k": k}) for k in (1, 2, 3)),
                          run_one=partial(_toy_run, quick, dof), runs=3,
                          config={"quick": quick, "dof": dof}, groups={"odd": ("1", "3")})

    toy.build = build
    toy.report = lambda results, out_dir: "no claims"
    return toy


@pytest.fixture
def toy(monkeypatch):
    module = _toy_module()
    real = registry.get
    monkeypatch.setattr(registry, "get", lambda name: module if name == "toy" else real(name))


def _results(folder: Path) -> dict:
    r = json.loads((folder / "results.json").read_text())
    for row in r["rows"]:
        row.pop("wall_s")
    return r


def test_experiment_repeats_from_its_config_json(toy, tmp_path, capsys):
    first = tmp_path / "first"
    assert main(["experiment", "toy", "--quick", "--dof", "8", "--rows", "odd", "--runs", "2",
                 "--workers", "1", "--quiet", "--out", str(first)]) == 0
    again = tmp_path / "again"
    assert main(["experiment", "toy", "--config", str(first / "config.json"), "--workers",
                 "1", "--quiet", "--out", str(again)]) == 0
    assert "warning" not in capsys.readouterr().err
    assert _results(again) == _results(first)
    cfg = json.loads((again / "config.json").read_text())
    assert cfg["options"]["quick"] is True and cfg["options"]["dof"] == 8
    assert cfg["selection"] == {"requested": ["odd"], "rows": ["1", "3"]} and cfg["runs"] == 2
    assert sorted(p.name for p in (first / "runs").iterdir()) == \
        sorted(p.name for p in (again / "runs").iterdir())


def test_experiment_flags_override_the_config_json(toy, tmp_path):
    first = tmp_path / "first"
    assert main(["experiment", "toy", "--quick", "--rows", "odd", "--runs", "2",
                 "--workers", "1", "--quiet", "--out", str(first)]) == 0
    other = tmp_path / "other"
    assert main(["experiment", "toy", "--config", str(first / "config.json"), "--rows", "2",
                 "--dof", "8", "--workers", "1", "--quiet", "--out", str(other)]) == 0
    cfg = json.loads((other / "config.json").read_text())
    assert cfg["options"]["quick"] is True and cfg["options"]["dof"] == 8  # file + flag
    assert cfg["selection"]["rows"] == ["2"] and cfg["runs"] == 2


def test_experiment_config_of_another_experiment_is_exit_2(toy, tmp_path, capsys):
    path = tmp_path / "config.json"
    path.write_text(json.dumps({"experiment": "paper_e", "options": {}, "selection": {},
                                "runs": 1}))
    assert main(["experiment", "toy", "--config", str(path), "--out",
                 str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "paper_e" in err[0]


@pytest.mark.slow  # two real sweeps (~30 s on 2 busy cores)
def test_paper_e_repeats_from_its_config_json(tmp_path):
    first, again = tmp_path / "first", tmp_path / "again"
    assert main(["experiment", "paper-e", "--quick", "--rows", "1,2", "--runs", "2",
                 "--workers", "1", "--quiet", "--out", str(first)]) == 0
    assert main(["experiment", "paper-e", "--config", str(first / "config.json"),
                 "--workers", "1", "--quiet", "--out", str(again)]) == 0

    def numbers(folder: Path) -> dict:
        r = _results(folder)
        for row in r["rows"]:
            row["metrics"] = {k: v for k, v in row["metrics"].items() if "wall" not in k}
        return r
    assert numbers(again) == numbers(first)
