"""The torque body in the one training path (config, lockstep, torques, test
plant perturbations) and the ``dynamic`` experiment's rows."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from skinny_mj.engine import results
from skinny_mj.errors import SkinnyInputError
from skinny_mj.training.loop import TrainConfig, build_run, train_batch

#: the torque body's limit-scaled PD alone (nothing learned, K = 1)
TORQUE_PD = TrainConfig().override({"actuation": "torque", "method": "none", "test.gain": 1.0})


@pytest.mark.parametrize("changes", [
    {"actuation.gravity_feedforward": True},  # torque settings on the velocity servo
    {"actuation.test_mass_scale": 1.2},
    {"actuation": "torque", "actuation.feedback": "computed-torque"},  # a controller alone
    {"actuation": "torque", "method": "none"},  # the controller alone needs K > 0
    {"actuation": "torque", "forward": "parallel"},
    {"actuation": "torque", "method": "true-target", "actuation.gravity_feedforward": True},
])
def test_torque_settings_are_validated(changes):
    with pytest.raises(SkinnyInputError):
        TrainConfig().override(changes)


def test_velocity_runs_take_no_torque_inputs():
    run = build_run(TrainConfig().override({"method.epochs": 1}), [0])
    assert run.esn.cfg.n_inputs == 2 * run.desired.shape[1]
    torque = build_run(TrainConfig().override({"actuation": "torque", "method.epochs": 1}), [0])
    assert torque.esn.cfg.n_inputs == 2 * torque.desired.shape[1] + 2 * 4


def test_torque_lockstep_is_each_run_alone():
    cfg = TrainConfig().override({"actuation": "torque", "actuation.gravity_feedforward": True,
                                  "method.epochs": 1, "method.cycles": 1})
    both = train_batch(cfg, [3, 4])
    alone = train_batch(cfg, [4])[0]
    np.testing.assert_array_equal(both[1].test.rollout.commands, alone.test.rollout.commands)
    assert results.test_figures(both[1]) == results.test_figures(alone)


def test_3d_arm_fel_run_is_the_same_in_any_batch():
    """The inertia-scaled teacher (M(q) products) and the remembering readout on the 3D
    torque arm: a seed's run alone, first of two and last of three, bit for bit."""
    cfg = TrainConfig().override({
        "actuation": "torque", "plant.dof": 8, "actuation.feedback": "inertia-pd",
        "method": "new", "method.beta": 1.0, "method.fit": "forgetting", "method.epochs": 1,
        "method.cycles": 1, "esn.n_reservoir": 20})
    alone = train_batch(cfg, [5])[0]
    for seeds in ([5, 6], [3, 4, 5]):
        other = train_batch(cfg, seeds)[seeds.index(5)]
        np.testing.assert_array_equal(other.test.rollout.commands, alone.test.rollout.commands)
        np.testing.assert_array_equal(other.esn.W_out, alone.esn.W_out)
        assert results.test_figures(other) == results.test_figures(alone)


def test_controller_alone_stays_within_limits_without_warnings():
    (out,) = train_batch(TORQUE_PD, [0])
    tq = out.test.torque_figures
    assert tq["within_limits"] and tq["warnings"] == 0 and tq["mean_abs_torque_nm"] > 0
    series = out.test.torque["series"]
    # the motors apply what was commanded (x gear): the limits are the only clamp
    np.testing.assert_allclose(series["applied_nm"], series["commanded_nm"], atol=1e-9)
    assert np.all(np.abs(series["commanded_nm"]) <= series["limit_nm"] + 1e-9)
    # held still at the first pose, the bias torque is gravity's: not zero
    assert np.abs(series["gravity_nm"][0]).max() > 1.0


def test_perturbed_test_plant_changes_every_copy():
    from skinny_mj.plant.adapters import BatchPlant
    from skinny_mj.plant.perturb import perturb
    from skinny_mj.trajectories import get

    plant = BatchPlant("2d-torque", "cartesian", get("ymca", 4), n_runs=2)
    names = [mujoco.mj_id2name(plant.model, mujoco.mjtObj.mjOBJ_BODY, i)
             for i in range(plant.model.nbody)]
    before = plant.model.body_mass.copy()
    perturb(plant, payload_kg=1.0, mass_scale=1.2)
    for r in range(2):
        hand = names.index(f"r{r}/right_hand")
        fore = names.index(f"r{r}/left_forearm")
        assert plant.model.body_mass[hand] == pytest.approx(1.2 * before[hand] + 1.0)
        assert plant.model.body_mass[fore] == pytest.approx(1.2 * before[fore])
    torso = names.index("r0/torso")
    assert plant.model.body_mass[torso] == before[torso]


def test_true_target_learns_torques_with_velocity_inputs():
    (out,) = train_batch(TrainConfig().override({"actuation": "torque", "method": "true-target",
                                                  "method.beta": 1.0}), [0])
    assert not out.failed
    assert out.train.motor_nrmse < 0.5  # teacher-forced fit of the torques


def test_dynamic_experiment_rows():
    from skinny_mj.experiments.dynamic import study as dynamic

    from skinny_mj.engine.plan import plan

    quick = plan(dynamic.STUDY, quick=True)
    ids = {p.id for p in quick.rows}
    assert {"2d-ymca-pd", "3d-md02-tt", "2d-ymca-payload1-fel-new-gff-k1",
            "2d-ymca-kinematic"} <= ids
    groups = quick.groups
    assert set(groups["table"]) == {i for i in ids if "kinematic" not in i
                                    and not any(p in i for p in dynamic.PERTURBATIONS)}
    assert set(groups["2d"]) | set(groups["3d"]) == ids
    cfg = quick.config("2d-ymca-mass-20-pd")
    assert cfg.torque.test_mass_scale == 0.8 and (cfg.method.kind, cfg.test.gain) == ("none", 1.0)
    # --quick shrinks every FEL row to 2 epochs (the long rows to 2 x 2), nothing else
    assert quick.config("2d-ymca-fel-arm").method.epochs == 2
    assert quick.config("3d-ymca-fel-arm-long").method.epochs == 4
    full = plan(dynamic.STUDY)
    arm2, arm3 = full.config("2d-ymca-fel-arm"), full.config("3d-ymca-fel-arm")
    assert (arm2.method.epochs, arm2.method.cycles, arm2.esn.n_reservoir) == (15, 3, 200)
    assert (arm3.method.epochs, arm3.method.cycles, arm3.esn.n_reservoir) == (15, 6, 500)
    long3 = full.config("3d-ymca-fel-arm-long")
    assert (long3.method.epochs, long3.method.cycles) == (30, 3)
    # --movement replaces the md_02 excerpt of the md02 rows only
    other = plan(dynamic.STUDY, movement="md_03.amc")
    assert other.config("2d-md02-pd").movement.trajectory == "md_03.amc"
    assert other.config("2d-ymca-pd").movement.trajectory == "ymca"


def test_a_diverged_simulation_fails_the_run_and_splits_a_batch(monkeypatch):
    """MuJoCo resets a diverged simulation (all copies of a batch at once) and only logs a
    warning: a torque run with warnings is a failed run, never an ok one, and a lockstep
    batch with warnings is run again one seed at a time by the engine."""
    from skinny_mj.plant.adapters import BatchPlant
    from skinny_mj.training.loop import PhysicsBatchError

    monkeypatch.setattr(BatchPlant, "warning_count", lambda self: 3)
    cfg = TORQUE_PD
    (out,) = train_batch(cfg, [0])
    assert out.failed and "physics diverged" in out.fail_reason
    assert results.run_metrics(out)["test"]["position_nrmse"] is None
    with pytest.raises(PhysicsBatchError):
        train_batch(cfg, [0, 1])
