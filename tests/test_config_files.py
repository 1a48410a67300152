"""Runs repeat from the files they wrote: ``skinny train --config metrics.json`` and
``skinny experiment NAME --config config.json``; flags given as well override fields."""

from __future__ import annotations

import json
import types
from functools import partial
from pathlib import Path

import pytest
import toy as toys

from skinny_mj.cli.parser import main
from skinny_mj.engine import registry
from skinny_mj.engine.experiment import Row
from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.body import body_of

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
    assert again["seed"] == 5 and again["config"]["method.beta"] == 0.3


def test_train_flags_override_only_what_they_name(trained, tmp_path):
    assert main(["train", "--config", str(trained / "metrics.json"), "--epochs", "2",
                 "--seed", "6", "--quiet", "--out", str(tmp_path / "c")]) == 0
    m, first = _metrics(tmp_path / "c"), _metrics(trained)
    assert m["seed"] == 6 and m["config"]["method.epochs"] == 2
    # every other setting is the file's, not a default (reservoir 30, not 200)
    changed = ("method.epochs", "learning_cycles")
    assert {k: v for k, v in m["config"].items() if k not in changed} \
        == {k: v for k, v in first["config"].items() if k not in changed}


@pytest.mark.parametrize("bare", [
    {"esn.n_reservoir": 30, "method.epochs": 1, "method": "original"},
    {"reservoir": 30, "epochs": 1, "method": "original"},  # an earlier version's flat fields
])
def test_train_takes_a_bare_config(tmp_path, bare):
    (tmp_path / "cfg.json").write_text(json.dumps(bare))
    assert main(["train", "--config", str(tmp_path / "cfg.json"), "--quiet", "--seed", "2",
                 "--out", str(tmp_path / "o")]) == 0
    m = _metrics(tmp_path / "o")
    assert m["config"]["method"] == "original" and m["config"]["esn.n_reservoir"] == 30
    assert m["seed"] == 2


def test_train_takes_key_value_overrides_after_the_file(trained, tmp_path):
    assert main(["train", "--config", str(trained / "metrics.json"), "--cycles", "2",
                 "method.epochs=2", "esn.spectral_radius=0.4", "method=original", "--quiet",
                 "--out", str(tmp_path / "kv")]) == 0
    cfg = _metrics(tmp_path / "kv")["config"]
    assert (cfg["method"], cfg["method.epochs"], cfg["esn.spectral_radius"]) == ("original", 2, 0.4)
    assert cfg["esn.n_reservoir"] == 30  # the file's


@pytest.mark.parametrize("argv, words", [
    (["esn.spectral_radus=0.9"], "did you mean 'esn.spectral_radius'"),
    (["method.fit=forgetting"], "method.fit=forgetting"),
    (["method=original", "method.beta=0.5"], "not a setting of method=original"),
    (["method.epochs=two"], "method.epochs must be a whole number"),
    (["spectral_radius"], "KEY=VALUE"),
    (["--epochs", "0"], "epochs must be >= 1"),
    (["--epochs", "3", "method.epochs=2"], "--epochs 3 and method.epochs=2 set the same key"),
])
def test_train_refuses_a_bad_key_or_value_in_one_line(tmp_path, capsys, argv, words):
    assert main(["train", *argv, "--quiet", "--out", str(tmp_path / "no")]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1
    assert not (tmp_path / "no").exists()


def test_key_values_and_flags_apply_together_before_the_config_checks():
    from skinny_mj.cli.config_files import train_config
    from skinny_mj.cli.parser import build_parser
    from skinny_mj.training.config import NoLearning

    def config(*argv):
        return train_config(build_parser().parse_args(["train", *argv]))[0]

    # method=none needs test.gain > 0: either alone is refused, together they are one config
    cfg = config("method=none", "test.gain=1", "--actuation", "torque", "--feedback", "ct")
    assert isinstance(cfg.method, NoLearning) and cfg.test.gain == 1.0
    assert cfg.torque.feedback == "ct"
    assert config("--reservoir", "50", "esn.n_reservoir=50").esn.n_reservoir == 50  # agree
    with pytest.raises(SkinnyInputError, match="--reservoir 40 and esn.n_reservoir=50"):
        config("--reservoir", "40", "esn.n_reservoir=50")  # contradict: refused
    assert config("--method", "original", "--epochs", "4").method.epochs == 4


_LEGACY = Path(__file__).parent / "data" / "legacy_n5"  # `skinny train --reservoir 5
# --epochs 1` of the code before the composed config (its flat metrics.json and model.npz)


def test_train_repeats_an_earlier_versions_metrics_json(tmp_path):
    assert main(["train", "--config", str(_LEGACY / "metrics.json"), "--quiet",
                 "--out", str(tmp_path / "r")]) == 0
    old, new = json.loads((_LEGACY / "metrics.json").read_text()), _metrics(tmp_path / "r")
    assert new["config"]["esn.n_reservoir"] == 5 and new["config"]["method.epochs"] == 1
    for part in ("train", "test"):  # the same run (float-exact on one machine)
        for key, value in old[part].items():
            assert new[part][key] == pytest.approx(value, rel=1e-9)


def test_test_runs_an_earlier_versions_model(tmp_path):
    from skinny_mj.controllers.esn import read_metadata

    assert "reservoir" in read_metadata(_LEGACY / "model.npz")["config"]  # flat, old
    assert main(["test", "--model", str(_LEGACY / "model.npz"), "--out",
                 str(tmp_path / "t")]) == 0
    got = json.loads((tmp_path / "t" / "metrics.json").read_text())["test"]
    trained = json.loads((_LEGACY / "metrics.json").read_text())["test"]  # the same test
    assert got["position_nrmse"] == pytest.approx(trained["position_nrmse"], rel=1e-9)


def test_an_earlier_versions_setting_it_ignored_is_dropped():
    """Old files set fields their method never read (a true-target run's epochs, a
    forward model's size without one): the old code ran them, so they still run."""
    from skinny_mj.training.config import TrainConfig

    cfg = TrainConfig.from_dict({"method": "true-target", "epochs": 2, "tt_cycles": 7,
                                 "forward_reservoir": 50, "u_error_gain": 2.0})
    assert cfg.method.kind == "true-target" and cfg.method.cycles == 7
    assert cfg.forward.kind == "none" and not hasattr(cfg.method, "epochs")
    fel = TrainConfig.from_dict({"method": "original", "cycles": 5, "tt_input_noise": 0.1})
    assert fel.learning_cycles == 5 and not hasattr(fel.method, "input_noise")


@pytest.mark.parametrize("content, needle", [
    ("{not json", "not a JSON config"),
    ("[1, 2]", "JSON object"),
    ('{"epochs": "three"}', "method.epochs must be a whole number"),
    ('{"method.epochs": "three"}', "method.epochs must be a whole number"),
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
    module = types.ModuleType("toy_experiment")
    module.NAME = "toy"

    def build(*, quick=False, movement=None, asf=None, body=None, signals=None):
        dof = 4 if body is None else body_of(body).dof
        return toys.toy("toy", tuple(Row(str(k), params={"k": k}) for k in (1, 2, 3)),
                        partial(_toy_run, quick, dof), runs=3,
                        params={"quick": quick, "dof": dof}, groups={"odd": ("1", "3")},
                        report=lambda results, plan, out_dir: "no claims")

    module.build = build
    return module


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
    assert cfg["options"]["quick"] is True and cfg["options"]["body"] == 8
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
    assert cfg["options"]["quick"] is True and cfg["options"]["body"] == 8  # file + flag
    third = tmp_path / "third"  # a config.json of an earlier version: options.dof
    old = json.loads((first / "config.json").read_text())
    old["options"]["dof"] = old["options"].pop("body")
    (tmp_path / "old.json").write_text(json.dumps(old))
    assert main(["experiment", "toy", "--config", str(tmp_path / "old.json"), "--body", "3d",
                 "--workers", "1", "--quiet", "--out", str(third)]) == 0
    assert json.loads((third / "config.json").read_text())["options"]["body"] == "3d"
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
