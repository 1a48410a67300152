"""The general presets per body and signal, the babbling that reaches the joint limits,
and the trained general models shipped as package data."""

from __future__ import annotations

import numpy as np
import pytest

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.training.presets import GENERAL, SHIPPED, SHIPPED_TORQUE, model_path, preset_fields
from skinny_mj.trajectories import load_movement
from skinny_mj.trajectories.babble import HOLD_S, LIMIT_MARGIN_RAD, babble

# -- babbling at the limits and at rest --------------------------------------------------


def _near_limit(angles: np.ndarray, dof: int, tol_rad: float) -> np.ndarray:
    lo, hi = body.body_of(dof).joint_ranges().T
    return (angles - lo < tol_rad) | (hi - angles < tol_rad)


@pytest.mark.parametrize("dof", [4, 8])
def test_babble_limits_and_holds_reach_the_limits_and_rest(dof):
    plain = babble(dof, seed=2, duration_s=30.0)
    assert np.array_equal(plain.angles, babble(dof, seed=2, duration_s=30.0, limits=0.0,
                                               holds=0.0).angles)
    a = babble(dof, seed=2, duration_s=30.0, limits=0.5, holds=0.2)
    lo, hi = body.body_of(dof).joint_ranges().T
    assert np.all(a.angles >= lo + LIMIT_MARGIN_RAD - 1e-12)
    assert np.all(a.angles <= hi - LIMIT_MARGIN_RAD + 1e-12)
    tol = np.radians(3.0)
    assert _near_limit(a.angles, dof, tol).mean() > 5 * _near_limit(plain.angles, dof, tol).mean()
    # rests: runs of unchanged samples at least the shortest hold long, in every DOF
    still = np.diff(a.angles, axis=0) == 0
    shortest = int(round(HOLD_S[0] / a.dt))
    for j in range(dof):
        runs = np.diff(np.flatnonzero(np.diff(np.r_[0, still[:, j].astype(int), 0])))[::2]
        assert runs.size and runs.max() >= shortest
    named, _ = load_movement("babble:seed=2,duration=30,limits=0.5,holds=0.2", dof)
    assert np.array_equal(named.angles, a.angles)
    assert named.name == "babble:seed=2,duration=30,limits=0.5,holds=0.2"


def test_babble_refuses_bad_limits_and_holds():
    for bad in ("babble:limits=1.5", "babble:holds=-0.1", "babble:limits=0.6,holds=0.6",
                "babble:limits=x"):
        with pytest.raises(SkinnyInputError):
            load_movement(bad, 4)


# -- presets -------------------------------------------------------------------------------


def _train_config(argv):
    from skinny_mj.cli.config_files import train_config
    from skinny_mj.cli.parser import build_parser

    return train_config(build_parser().parse_args(argv))[0]


@pytest.mark.parametrize(("dof", "signals"), list(GENERAL))
def test_general_preset_per_body_and_signal(dof, signals):
    from skinny_mj.training.config import TrainConfig

    fields = preset_fields("general", dof=dof, signals=signals)
    # the signals asked for, or a refinement of them (cartesian -> cartesian-elbow)
    assert body.body_of(fields["plant.body"]).dof == dof
    assert fields["plant.signals"] in (signals, f"{signals}-elbow")
    cfg = _train_config(["train", "--preset", "general", "--dof", str(dof),
                         "--signals", signals])
    assert cfg == TrainConfig().override(fields)
    traj, report = load_movement(fields["movement.trajectory"], dof)
    assert report.clipped_samples == 0 and len(traj) > 100


def test_general_preset_defaults_to_2d_joint_and_the_torque_one_is_apart():
    assert preset_fields("general") == preset_fields("general", dof=4, signals="joint")
    assert _train_config(["train", "--preset", "general", "--signals", "cartesian"]) == \
        _train_config(["train", "--preset", "general", "--dof", "4", "--signals",
                       "cartesian"])
    torque = preset_fields("general", "torque", dof=4, signals="cartesian")
    assert torque == preset_fields("general", "torque") and torque["actuation"] == "torque"
    torque3 = preset_fields("general", "torque", dof=8, signals="cartesian")  # one per body
    assert (torque3["plant.body"], torque3["plant.signals"]) == ("3d-torque", "joint")
    with pytest.raises(SkinnyInputError):
        _train_config(["train", "--preset", "general", "plant.dof=x"])


# -- the shipped models ----------------------------------------------------------------------


def _shipped(name):
    from skinny_mj.controllers.esn import ESN, read_metadata

    path = model_path(name)
    return path, ESN.load(path), read_metadata(path)


def test_shipped_names_cover_every_body_and_signal():
    assert sorted(SHIPPED.values()) == sorted(GENERAL)
    assert model_path("results/x/model.npz").as_posix() == "results/x/model.npz"


@pytest.mark.parametrize("name", list(SHIPPED))
def test_shipped_model_loads_records_its_preset_and_imitates_a_clip(name):
    from skinny_mj.training.config import TrainConfig
    from skinny_mj.training.loop import evaluate, run_of, run_streams

    path, esn, meta = _shipped(name)
    dof, signals = SHIPPED[name]
    assert path.is_file() and path.stat().st_size < 2_000_000
    with np.load(path, allow_pickle=False) as data:  # plain arrays, no pickled objects
        assert all(data[k].dtype != object for k in data.files)
    fields = preset_fields("general", dof=dof, signals=signals)
    assert (meta["dof"], meta["signals"], meta["training"]["preset"]) == (
        dof, fields["plant.signals"], "general")
    cfg = TrainConfig.from_dict(meta["config"])
    assert cfg == TrainConfig().override(fields)
    clip, _ = load_movement("md_03.amc@start=0,duration=1", dof)
    run = run_of(cfg, esn, np.asarray(meta["max_speed_rad_s"]), clip,
                 [run_streams(0).plant_seed])
    (outcome,) = evaluate(run)
    assert not outcome.failed and 0 < outcome.position_nrmse < 0.5
    silent = _shipped(name)[1]  # the same network with its readout zeroed: it stands still
    silent.W_out[...] = 0.0
    (still,) = evaluate(run_of(cfg, silent, np.asarray(meta["max_speed_rad_s"]), clip,
                               [run_streams(0).plant_seed]))
    assert outcome.position_nrmse < still.position_nrmse


@pytest.mark.parametrize("name", list(SHIPPED_TORQUE))
def test_shipped_torque_model_records_its_preset_and_imitates_a_clip(name):
    """A shipped torque model is the torque preset's (its config, under the robot's
    sensing), and on a clip it never saw it tracks better than the same arm with the
    network silent (the commands zero: gravity takes the arm down)."""
    from skinny_mj.training.config import Encoders, TrainConfig
    from skinny_mj.training.loop import evaluate, run_of, run_streams

    path, esn, meta = _shipped(name)
    dof = SHIPPED_TORQUE[name]
    assert path.is_file() and path.stat().st_size < 2_000_000
    with np.load(path, allow_pickle=False) as data:
        assert all(data[k].dtype != object for k in data.files)
    assert (meta["dof"], meta["training"]["preset"]) == (dof, "general")
    cfg = TrainConfig.from_dict(meta["config"])
    assert cfg == TrainConfig().override(preset_fields("general", "torque", dof=dof))
    assert cfg.actuation.kind == "torque" and isinstance(cfg.actuation.sensing, Encoders)
    clip, _ = load_movement("md_03.amc@start=0,duration=1", dof, speed=0.5)
    seeds = [run_streams(0).plant_seed]
    speeds = np.asarray(meta["max_speed_rad_s"])
    (outcome,) = evaluate(run_of(cfg, esn, speeds, clip, seeds))
    silent = _shipped(name)[1]
    silent.W_out[...] = 0.0
    (still,) = evaluate(run_of(cfg, silent, speeds, clip, seeds))
    assert not outcome.failed and outcome.position_nrmse < 0.5 * still.position_nrmse


@pytest.mark.slow  # the CLI end to end (imports rerun for the recording)
def test_skinny_test_runs_a_shipped_model_by_name(tmp_path):
    import json

    from skinny_mj.cli.parser import main

    out = tmp_path / "test"
    assert main(["test", "--model", "general-3d-cartesian", "--trajectory",
                 "md_03.amc@start=0,duration=1", "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["dof"] == 8
    assert metrics["signals"] == preset_fields("general", dof=8, signals="cartesian")[
        "plant.signals"]
    assert metrics["test"]["position_nrmse"] > 0


@pytest.mark.slow  # trains each model again (tens of seconds to minutes each)
@pytest.mark.parametrize("name", list(SHIPPED))
def test_retraining_a_shipped_model_from_its_metadata_gives_its_weights(name):
    from skinny_mj.training.config import TrainConfig
    from skinny_mj.training.loop import train

    _, esn, meta = _shipped(name)
    outcome = train(TrainConfig.from_dict(meta["config"]), int(meta["training"]["seed"]))
    for key in ("W", "W_in", "W_out"):
        assert np.array_equal(getattr(outcome.esn, key), getattr(esn, key)), key


def test_each_general_preset_is_a_row_of_the_generalization_study():
    from skinny_mj.experiments.generalization import study as g

    from skinny_mj.training.config import TrainConfig

    full = g.STUDY.build()
    for rep, row in g.GENERAL_OF.items():
        dof, signals = g.REPRESENTATIONS[rep]
        want = TrainConfig().override(preset_fields("general", dof=dof, signals=signals))
        assert full.config(row) == want, rep


def test_the_cli_help_names_every_shipped_model():
    # the parser imports no training code, so its help spells the names; they must match
    from skinny_mj.cli.parser import build_parser
    from skinny_mj.training.presets import SHIPPED_NAMES

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    for command in ("train", "test"):
        text = "".join(sub.choices[command].format_help().split())  # wrapping may split a name
        assert all(name in text for name in SHIPPED_NAMES), command
