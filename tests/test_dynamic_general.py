"""The torque ``general`` preset's rows of the dynamic study: trained once, tested on the
unseen clips as shipped and slowed to the speed their inverse dynamics fit the limits."""

from __future__ import annotations

import math

import pytest


def _row(row_id, **tests):
    from skinny_mj.experiments.dynamic import study as dynamic

    from skinny_mj.engine.plan import plan

    p = plan(dynamic.STUDY)
    row = p.row(row_id)
    return p.config(row_id), row


@pytest.mark.parametrize("dof", [4, 8])
def test_feasible_speeds_fit_the_limits_and_full_speed_does_not(dof):
    from skinny_mj.experiments.dynamic import general

    from skinny_mj.training.torque import feasibility

    for col in ("md_02", "md_03"):
        assert not bool(feasibility(dof, general.load_test(col, dof))["feasible"])
        slowed = general.load_test(f"{col}-feasible", dof)
        assert bool(feasibility(dof, slowed)["feasible"])
        full = general.load_test(col, dof)
        assert math.isclose(len(slowed) / len(full), 1 / general.speed_of(f"{col}-feasible", dof),
                            rel_tol=0.02)


@pytest.mark.parametrize("dof", [4, 8])
def test_the_speed_curve_and_the_locally_retimed_clips(dof):
    """The curve's columns run slowest first and include the feasible and full speeds; a
    clip re-timed locally fits the limits and stays shorter than the clip slowed whole."""
    from skinny_mj.experiments.dynamic import general

    from skinny_mj.training.torque import feasibility

    for clip in general.CLIPS:
        cols = general.curve_columns(clip, dof)
        speeds = [general.speed_of(c, dof) for c in cols]
        assert speeds == sorted(speeds) and speeds[-1] == 1.0
        assert f"{clip}-feasible" in cols and len(cols) == len(general.CURVE_SPEEDS) + 2
        retimed = general.load_test(f"{clip}-retimed", dof)
        assert bool(feasibility(dof, retimed)["feasible"])
        assert len(general.load_test(clip, dof)) <= len(retimed) \
            < len(general.load_test(f"{clip}-feasible", dof))
    assert set(general.FLOOR_TESTS) < set(general.TESTS)


def test_computed_torque_floor_is_lower_on_the_feasible_clip():
    import dataclasses

    from skinny_mj.experiments.dynamic import study as dynamic

    cfg, row = _row("2d-general-arm-ct")
    assert cfg.method.kind == "none" and cfg.torque.feedback == "ct"
    row = dataclasses.replace(row, params={"tests": ("md_03", "md_03-feasible")})
    (out,) = dynamic.STUDY.run(cfg, row, [0])
    assert out["n_test_failed"] == 0 and "train_position_nrmse" not in out
    # the same controller: the slowed clip, within the limits, is tracked far better
    assert out["md_03-feasible__position_nrmse"] < 0.2 * out["md_03__position_nrmse"]
    # commands are clipped to the limits, so a ratio of exactly 1 is saturation: at full
    # speed the clip needs more torque than the motors have, and computed torque saturates
    assert out["md_03__max_torque_ratio"] == 1.0
    # per column, the figures in a roboticist's units too (tests/test_robot_metrics.py)
    assert out["md_03-feasible__rms_error_deg"] < out["md_03__rms_error_deg"]
    assert out["md_03__hand_error_cm"] > 0 and out["md_03__abs_work_j"] > 0


def test_a_learned_row_trains_once_and_tests_every_column():
    import dataclasses

    from skinny_mj.experiments.dynamic import study as dynamic

    cfg, row = _row("2d-general-first")
    cfg = cfg.override({"method.epochs": 1, "method.cycles": 1, "esn.n_reservoir": 20,
                        "movement.trajectory": "babble:seed=0,duration=1,vmin=0.5,vmax=4"})
    row = dataclasses.replace(row, params={"tests": ("md_03-feasible", "ymca")})
    outs = dynamic.STUDY.run(cfg, row, [0, 1])
    assert len(outs) == 2
    for out in outs:
        assert math.isfinite(out["train_position_nrmse"])
        for col in ("md_03-feasible", "ymca"):
            assert out[f"{col}__position_nrmse"] > 0
            # never saturated (a clipped command reaches exactly 1): within the limits
            assert out[f"{col}__max_torque_ratio"] < 0.999
    assert outs[0]["ymca__position_nrmse"] != outs[1]["ymca__position_nrmse"]  # two seeds


def test_the_preset_row_is_what_skinny_train_preset_general_trains():
    from skinny_mj.cli.config_files import train_config
    from skinny_mj.cli.parser import build_parser

    cfg, _ = _row("2d-general")
    cli, _ = train_config(build_parser().parse_args(
        ["train", "--preset", "general", "--actuation", "torque", "actuation.sensing=oracle"]))
    assert cfg == cli
    # the 3D body's own preset: its row, with the stiffer teacher of the group omega20
    cfg3, _ = _row("3d-general")
    cli3, _ = train_config(build_parser().parse_args(
        ["train", "--preset", "general", "--actuation", "torque", "--dof", "8",
         "actuation.sensing=oracle"]))
    assert cfg3 == cli3
    assert (cfg3.plant.dof, cfg3.actuation.omega, cfg3.esn.n_reservoir) == (8, 20.0, 200)


def test_the_held_out_preset_candidate_is_what_skinny_train_ships_and_the_choice_is_held_out():
    """The held-out group's ``preset`` candidate is ``skinny train --preset general
    --actuation torque`` as it ships (the robot's sensing); the other candidates change
    only their declared keys; the report chooses on one clip and scores on the other."""
    from skinny_mj.experiments.dynamic import general

    from skinny_mj.cli.config_files import train_config
    from skinny_mj.cli.parser import build_parser

    cfg, row = _row("2d-heldout-preset")
    cli, _ = train_config(build_parser().parse_args(
        ["train", "--preset", "general", "--actuation", "torque"]))
    assert cfg == cli and row.group == "held-out"
    assert row.params["tests"] == general.HELD_OUT_TESTS
    omega, other = _row("2d-heldout-omega10")
    assert omega == cfg.override({"actuation.omega": 10.0})
    assert other.seeds_of == "2d-heldout-preset"
    # md_02: omega10 best; md_03: preset best -> each scored on the other clip
    scores = {("2d-heldout-preset", "md_02-retimed"): [0.03], ("2d-heldout-preset",
              "md_03-retimed"): [0.01], ("2d-heldout-omega10", "md_02-retimed"): [0.02],
              ("2d-heldout-omega10", "md_03-retimed"): [0.04]}

    def get(r, metric):
        if metric == "train_wall_s":
            return [1.0] if r in {"2d-heldout-preset", "2d-heldout-omega10"} else []
        return scores.get((r, metric.split("__")[0]), [])

    lines = general.held_out_lines(get, "2d", 4)
    chose02 = next(ln for ln in lines if "chosen on md_02-retimed" in ln)
    chose03 = next(ln for ln in lines if "chosen on md_03-retimed" in ln)
    assert "(omega10), scored on md_03-retimed" in chose02 and ": 0.0400 ±" in chose02
    assert "(preset), scored on md_02-retimed" in chose03 and ": 0.0300 ±" in chose03
