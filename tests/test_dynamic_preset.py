"""``skinny train --preset general --actuation torque``: the torque twin's general preset."""

from __future__ import annotations

import pytest

from skinny_mj.errors import SkinnyInputError


def _config(argv):
    from skinny_mj.cli.config_files import train_config
    from skinny_mj.cli.parser import build_parser

    return train_config(build_parser().parse_args(argv))


def test_torque_general_sets_its_fields_and_the_velocity_preset_is_untouched():
    from skinny_mj.training.config import TrainConfig
    from skinny_mj.training.presets import preset_fields

    cfg, seed = _config(["train", "--preset", "general", "--actuation", "torque",
                         "--epochs", "2", "--seed", "3"])
    want = preset_fields("general", "torque")
    got = cfg.to_dict()
    assert seed == 3 and cfg.method.epochs == 2  # a flag given overrides the preset
    assert {k: got[k] for k in want if k != "method.epochs"} == \
        {k: v for k, v in want.items() if k != "method.epochs"}
    assert (cfg.actuation.kind, cfg.actuation.feedback, cfg.method.fit.kind) == (
        "torque", "inertia-pd", "forgetting")
    velocity, _ = _config(["train", "--preset", "general"])
    assert velocity == TrainConfig().override(preset_fields("general"))  # as before
    assert velocity.torque is None and "vmax" not in velocity.movement.trajectory
    with pytest.raises(SkinnyInputError):
        preset_fields("nope", "torque")


@pytest.mark.parametrize("dof", [4, 8])
def test_torque_general_babbling_is_within_the_torque_limits(dof):
    from skinny_mj.training.presets import preset_fields
    from skinny_mj.training.torque import feasibility
    from skinny_mj.trajectories.library import load_movement

    fields = preset_fields("general", "torque", dof=dof)
    assert fields["plant.body"] == {4: "2d-torque", 8: "3d-torque"}[dof]  # each its own
    traj, _ = load_movement(fields["movement.trajectory"], dof)
    assert bool(feasibility(dof, traj)["feasible"])
    full_speed, _ = load_movement("md_02.amc", dof)  # the shipped clip is not, at full speed
    assert not bool(feasibility(dof, full_speed)["feasible"])


@pytest.mark.slow  # the CLI end to end (imports matplotlib and rerun)
def test_train_torque_general_records_the_preset(tmp_path):
    from skinny_mj.controllers.esn import read_metadata

    from skinny_mj.cli.parser import main

    out = tmp_path / "train"
    assert main(["train", "--preset", "general", "--actuation", "torque", "--epochs", "1",
                 "--cycles", "1", "--reservoir", "20", "--trajectory",
                 "babble:seed=0,duration=1,vmin=0.5,vmax=4", "--out", str(out),
                 "--quiet"]) == 0
    meta = read_metadata(out / "model.npz")
    assert meta["training"]["preset"] == "general"
    assert meta["config"]["actuation"] == "torque"
    assert meta["config"]["actuation.feedback"] == "inertia-pd"
    assert meta["config"]["method.fit"] == "forgetting"
