"""The adaptation study's body changes: the longer forearm (an MjSpec variant swapped
into the running model), the torque twin's payload and heavier links, and the
defaults left as they were."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from skinny_mj.experiments import adaptation

from skinny_mj.plant import body
from skinny_mj.plant.adapters import BatchPlant
from skinny_mj.plant.perturb import PerturbedPlant, forearm_rows
from skinny_mj.trajectories import get

Q = np.array([[0.3, 0.8, -0.2, 0.5], [1.0, 0.2, 0.4, 1.1]])  # two poses, rad


def _site_gap(plant, r: int, a: str, b: str) -> float:
    d = plant.data
    return float(np.linalg.norm(d.site(f"r{r}/{b}").xpos - d.site(f"r{r}/{a}").xpos))


def _posed(plant, q=Q):
    plant.reset()
    plant.set_joint_angles(q)
    return plant


def test_longer_forearm_is_longer_and_the_controller_keeps_the_nominal_jacobian():
    nominal = _posed(BatchPlant(4, "cartesian", get("ymca", 4), n_runs=2))
    plant = PerturbedPlant(BatchPlant(4, "cartesian", get("ymca", 4), n_runs=2))
    plant.set(forearm=1.2)
    _posed(plant)
    for r in range(2):  # every copy: the right forearm 1.2 x, the rest as it was
        assert _site_gap(plant, r, "right_elbow", "right_wrist") == pytest.approx(
            1.2 * body.body_of("2d").lengths_m()[1], abs=1e-12)
        assert _site_gap(plant, r, "left_elbow", "left_wrist") == pytest.approx(
            body.body_of("2d").lengths_m()[1], abs=1e-12)
        assert _site_gap(plant, r, "right_shoulder", "right_elbow") == pytest.approx(
            body.body_of("2d").lengths_m()[0], abs=1e-12)
    rows = forearm_rows(4, "cartesian")
    assert [body.body_of(4).signal_names("cartesian")[i] for i in rows] == ["right_wrist_x",
                                                                    "right_wrist_z"]
    diff = plant.true_signals() - nominal.true_signals()
    assert np.allclose(diff[:, rows], 0.2 * nominal.true_signals()[:, rows], atol=1e-12)
    assert np.array_equal(np.delete(diff, rows, axis=1), np.zeros((2, 6)))
    # not told: the nominal arm's Jacobian at the same angles
    assert np.allclose(plant.command_jacobian(), nominal.command_jacobian(), atol=1e-14)
    assert not np.allclose(plant.plant.command_jacobian(), nominal.command_jacobian())
    plant.undo()
    _posed(plant)
    assert np.array_equal(plant.true_signals(), nominal.true_signals())
    assert np.array_equal(plant.model.body_pos, nominal.model.body_pos)
    assert np.array_equal(plant.model.geom_size, nominal.model.geom_size)


def test_torque_payload_adds_mass_at_the_right_hand_and_heavier_links_scale_the_arms():
    nominal = _posed(BatchPlant("2d-torque", "cartesian", get("ymca", 4), n_runs=2))
    plant = PerturbedPlant(BatchPlant("2d-torque", "cartesian", get("ymca", 4), n_runs=2))
    m0 = plant.model.body_mass.copy()
    hands = [plant.model.body(f"r{r}/right_hand").id for r in range(2)]
    plant.set(payload_kg=1.0)
    added = plant.model.body_mass - m0
    assert np.allclose(added[hands], 1.0) and np.count_nonzero(added) == 2
    _posed(plant)
    shoulder = body.body_of(4).dof_names.index("right_shoulder_abduction")
    assert np.all(np.abs(plant.bias_torque_nm()[:, shoulder])
                  > np.abs(nominal.bias_torque_nm()[:, shoulder]) + 1.0)  # > 1 N m more
    plant.set(mass_scale=1.2)  # replaces the payload
    arms = [plant.model.body(f"r{r}/{side}_{seg}").id for r in range(2)
            for side in body.SIDES for seg in ("upper_arm", "forearm", "hand")]
    assert np.allclose(plant.model.body_mass[arms], 1.2 * m0[arms])
    others = np.setdiff1d(np.arange(plant.model.nbody), arms)
    assert np.array_equal(plant.model.body_mass[others], m0[others])
    plant.undo()
    assert np.array_equal(plant.model.body_mass, m0)
    _posed(plant)
    assert np.array_equal(plant.bias_torque_nm(), nominal.bias_torque_nm())


def test_defaults_pass_through_bit_for_bit_and_the_old_rows_keep_their_seeds():
    bare = _posed(BatchPlant(4, "cartesian", get("ymca", 4), n_runs=2, seeds=[5, 6]))
    wrapped = PerturbedPlant(_posed(BatchPlant(4, "cartesian", get("ymca", 4), n_runs=2,
                                               seeds=[5, 6])))
    wrapped.set()  # all defaults: no body change
    cmd = np.full((2, 4), 0.3)
    assert np.array_equal(wrapped.step(cmd), bare.step(cmd))
    assert np.array_equal(wrapped.command_jacobian(), bare.command_jacobian())
    with pytest.raises(ValueError):
        wrapped.set(forearm=1.2, payload_kg=1.0)
    study = adaptation.STUDY
    exp = study.build()
    old = [f"{c}-{lr}" for c in ("gain", "offset") for lr in ("frozen", "fel", "rls")]
    assert [r.id for r in exp.rows[:6]] == old  # row index -> seed: unchanged
    p = exp.params
    assert (p["gain"], p["pre_cycles"], p["change_cycles"], p["post_cycles"],
            p["actuator_gain"], p["offset"], study.runs) == (0.5, 2, 8, 4, 0.7, 0.1, 10)
    assert study.config("gain-fel") == adaptation.TrainConfig().override({"method.epochs": 10})
    assert study.config("payload-fel").actuation.kind == "torque"
    assert 0 < adaptation.forearm_floor(study.base, p["forearm"]) < 0.1
    quick = study.build(quick=True)
    assert (quick.params["change_cycles"], quick.config("mass-rls").method.epochs) == (2, 2)
    # the batch model without an edit is the one it always was
    from skinny_mj.plant.model import load_batch_model
    a, b = load_batch_model(4, 2), load_batch_model(4, 2, edit=None)
    assert np.array_equal(a.body_pos, b.body_pos) and a.nbody == b.nbody
    assert isinstance(a, mujoco.MjModel)
