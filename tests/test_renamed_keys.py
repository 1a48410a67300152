"""The FEL method's old keys, ``rule`` and ``rule.*``, set ``method`` and ``method.*``
wherever keys are given (the Python API, ``skinny train`` KEY=VALUE, config files,
``skinny sweep`` axes, a study's rows), each with one warning line per process."""

from __future__ import annotations

import json
import logging

import pytest

from skinny_mj.cli.config_files import train_config
from skinny_mj.cli.parser import build_parser, main
from skinny_mj.engine.grid import grid_study
from skinny_mj.engine.plan import plan
from skinny_mj.engine.study import Quick, Row, Study
from skinny_mj.errors import SkinnyInputError
from skinny_mj.training import overrides
from skinny_mj.training.config import TrainConfig

OLD = {"rule": "original", "rule.epochs": 3, "rule.u_error_gain": 2.0}
NEW = {"method": "original", "method.epochs": 3, "method.u_error_gain": 2.0}


@pytest.fixture
def fresh(monkeypatch, caplog):
    """A process that has warned about no old key yet; its warnings in ``caplog``."""
    monkeypatch.setattr(overrides, "_WARNED", set())
    caplog.set_level(logging.WARNING, logger="skinny_mj")
    return caplog


def _warnings(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]


def test_an_old_key_sets_its_new_key_with_one_warning_per_key(fresh):
    assert TrainConfig().override(OLD) == TrainConfig().override(NEW)
    TrainConfig().override(OLD)  # again: no second warning
    assert TrainConfig().override(rule__epochs=4).method.epochs == 4
    assert sorted(_warnings(fresh)) == ["rule is now method", "rule.epochs is now method.epochs",
                                        "rule.u_error_gain is now method.u_error_gain"]


def test_an_old_key_reads_and_parses_as_its_new_key(fresh):
    cfg = TrainConfig()
    assert overrides.parse_value(cfg, "rule.beta", "0.2") == 0.2
    assert overrides.field_type(cfg, "rule.epochs") is int
    assert overrides.node(cfg, "rule.fit") == cfg.method.fit
    assert overrides.canonical(cfg, "rule.fit.forgetting") == "method.fit.forgetting"
    assert overrides.canonical(cfg, "esn.spectral_radius") == "esn.spectral_radius"
    # the old name of the old name: rule.forgetting -> method.forgetting -> method.fit.forgetting
    rls = TrainConfig().override({"actuation": "torque", "method.fit": "rls"})
    assert rls.override({"rule.forgetting": 0.7}).method.fit.forgetting == 0.7
    assert "rule" not in " ".join(cfg.to_dict())  # files are written with the new keys


def test_an_old_and_a_new_key_that_disagree_are_refused(fresh):
    assert TrainConfig().override({"rule.epochs": 2, "method.epochs": 2}).method.epochs == 2
    with pytest.raises(SkinnyInputError, match="rule.epochs=2 and method.epochs=3 set the "
                                               "same key, method.epochs"):
        TrainConfig().override({"rule.epochs": 2, "method.epochs": 3})


def test_skinny_train_takes_old_keys_and_flags_alike(fresh):
    def config(*argv):
        return train_config(build_parser().parse_args(["train", *argv]))[0]

    assert config("rule=none", "test.gain=1", "--actuation", "torque", "--feedback", "ct") \
        == config("method=none", "test.gain=1", "--actuation", "torque", "--feedback", "ct")
    assert config("rule.epochs=4", "rule=original", "--cycles", "2") \
        == config("method.epochs=4", "method=original", "--cycles", "2")
    assert config("--epochs", "3", "rule.epochs=3").method.epochs == 3  # agree
    with pytest.raises(SkinnyInputError, match="--epochs 3 and method.epochs=2"):
        config("--epochs", "3", "rule.epochs=2")  # contradict: refused
    with pytest.raises(SkinnyInputError, match="rule.epochs=2 and method.epochs=3"):
        config("rule.epochs=2", "method.epochs=3")


def test_skinny_train_repeats_a_file_of_old_keys_bit_for_bit(tmp_path, capsys):
    tiny = ["--reservoir", "30", "--quiet", "--seed", "4"]
    assert main(["train", *tiny, "rule.epochs=1", "rule=original", "--out",
                 str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err
    assert err.count("rule.epochs is now method.epochs\n") == 1
    assert err.count("rule is now method\n") == 1
    first = json.loads((tmp_path / "a" / "metrics.json").read_text())
    assert (first["config"]["method"], first["config"]["method.epochs"]) == ("original", 1)
    assert not any(k.startswith("rule") for k in first["config"])
    old = {**first, "config": {("rule" + k[6:] if k.startswith("method") else k): v
                               for k, v in first["config"].items()}}
    (tmp_path / "old.json").write_text(json.dumps(old))
    assert main(["train", "--config", str(tmp_path / "old.json"), "--quiet", "--out",
                 str(tmp_path / "b")]) == 0
    again = json.loads((tmp_path / "b" / "metrics.json").read_text())
    first.pop("wall_s"), again.pop("wall_s")
    assert again == first  # config (new keys), seed, every metric


def test_a_sweep_axis_of_an_old_key_is_its_new_keys_axis(fresh):
    old = grid_study(["rule.epochs=1,2", "rule=original", "esn.n_reservoir=20"])
    new = grid_study(["method.epochs=1,2", "method=original", "esn.n_reservoir=20"])
    assert [r.id for r in old.rows] == ["method.epochs=1", "method.epochs=2"]
    assert (old.base, old.rows) == (new.base, new.rows)  # the same rows, so the same seeds
    with pytest.raises(SkinnyInputError, match="method.epochs is given twice"):
        grid_study(["rule.epochs=1,2", "method.epochs=3,4"])


def test_a_studys_rows_quick_and_tiny_take_old_keys(fresh):
    def study(epochs: str, method: str) -> Study:
        return Study(name="toy", description="toy", base=TrainConfig(),
                     metrics={"position_nrmse": "test.position_nrmse"},
                     rows=(Row("a", {method: "original", epochs: 3}, quick={epochs: 2}),
                           Row("b", {"esn.n_reservoir": 30})),
                     quick=Quick({"esn.n_reservoir": 20}, runs=1), tiny={epochs: 1})

    old, new = study("rule.epochs", "rule"), study("method.epochs", "method")
    for kw in ({}, {"quick": True}, {"quick": True, "tiny": True}):
        assert plan(old, **kw).configs == plan(new, **kw).configs
    assert [c.method.epochs for c in plan(old, quick=True, tiny=True).configs.values()] == [1, 1]
    assert plan(old).config("a").method.epochs == 3
