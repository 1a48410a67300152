"""Skinny's MJCF: loads, steps cleanly, names everything, and MuJoCo's kinematics equals the
analytic kinematics skinny_mj/plant/body.py reads from it."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from skinny_mj.errors import SkinnyEnvironmentError, SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.plant.body import models_dir
from skinny_mj.plant.model import TORQUE_GEAR_NM, load_model, torque_spec
from skinny_mj.plant.physics import SkinnyPhysics

BODIES = ("2d", "3d", "2d-torque", "3d-torque")


def _model(name: str, source: str) -> mujoco.MjModel:
    """The body's MJCF as the package loads it, or a torque body as the generator builds it
    in code (``source``)."""
    if source == "file":
        return load_model(name)
    return torque_spec(body.body_of(name).twin("velocity")).compile()


@pytest.mark.parametrize("name,source", [*((n, "file") for n in BODIES),
                                         ("2d-torque", "built"), ("3d-torque", "built")])
def test_one_second_of_random_control_is_clean(name, source):
    model = _model(name, source)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    lo, hi = model.actuator_ctrlrange.T
    for _ in range(int(round(1.0 / model.opt.timestep))):
        data.ctrl[:] = rng.uniform(lo, hi)
        mujoco.mj_step(model, data)
    assert all(w.number == 0 for w in data.warning)
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
    assert np.all(np.isfinite(data.qacc))


@pytest.mark.parametrize("dof", [4, 8])
def test_every_named_element_exists(dof):
    model = load_model(dof)
    for side in body.SIDES:
        for part in ("upper_arm", "forearm", "hand"):
            assert model.body(f"{side}_{part}").id > 0
        for point in ("shoulder", "elbow", "wrist"):
            assert model.site(f"{side}_{point}").id >= 0
    for name in ("pelvis", "torso", "head"):
        assert model.body(name).id > 0
    assert model.camera("front").id >= 0
    names = body.body_of(dof).dof_names
    assert [model.joint(i).name for i in range(model.njnt)] == list(names)
    assert [model.actuator(i).name for i in range(model.nu)] == list(names)
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST


#: The model card's joints (models/skinny/README.md): right arm's hinge, segment, axis, range.
CARD = {
    4: (("shoulder_abduction", "upper_arm", (0, 1, 0), (0, np.pi)),
        ("elbow_flexion", "forearm", (0, 1, 0), (0, np.pi))),
    8: (("shoulder_abduction", "upper_arm", (0, 1, 0), (0, np.pi)),
        ("shoulder_flexion", "upper_arm", (-1, 0, 0), (-np.pi / 4, 5 * np.pi / 12)),
        ("shoulder_rotation", "upper_arm", (0, 0, 1), (-np.pi / 2, np.pi / 2)),
        ("elbow_flexion", "forearm", (0, 1, 0), (0, 5 * np.pi / 6))),
}


@pytest.mark.parametrize("dof", [4, 8])
def test_joints_are_the_model_cards_and_the_body_reads_them(dof):
    model, skinny = load_model(dof), body.body_of(dof)
    n_arm = dof // 2
    assert skinny.arms.joints == tuple(j[0] for j in CARD[dof])
    assert skinny.arms.segments == tuple(j[1] for j in CARD[dof])
    for k, side in enumerate(body.SIDES):
        for i, (name, segment, axis, rng) in enumerate(CARD[dof]):
            joint = model.joint(f"{side}_{name}")
            assert model.body(joint.bodyid[0]).name == f"{side}_{segment}"
            mirrored = axis if side == "right" else -np.diag([-1, 1, 1]) @ axis
            np.testing.assert_allclose(joint.axis, mirrored, atol=1e-15)
            np.testing.assert_array_equal(joint.axis, skinny.joint_axis(i, side) + 0.0)
            np.testing.assert_allclose(joint.range, rng, rtol=0, atol=1e-15)
            assert model.jnt_limited[joint.id]
            assert joint.id == k * n_arm + i
        for part in ("upper_arm", "forearm", "hand"):
            assert model.body_gravcomp[model.body(f"{side}_{part}").id] == 1.0
    np.testing.assert_array_equal(model.jnt_range, skinny.joint_ranges())
    np.testing.assert_array_equal(skinny.lengths_m(), [0.30, 0.27])
    np.testing.assert_array_equal(skinny.shoulder_positions(),
                                  [[-0.19, 0.0, 1.42], [0.19, 0.0, 1.42]])


@pytest.mark.parametrize("dof", [4, 8])
def test_forward_kinematics_and_jacobians_equal_body(dof):
    physics = SkinnyPhysics.load(dof)
    rng = np.random.default_rng(dof)
    ranges = body.body_of(dof).joint_ranges()
    for _ in range(20):
        q = rng.uniform(ranges[:, 0], ranges[:, 1])
        physics.set_joint_angles(q)
        np.testing.assert_allclose(physics.joint_angles(), q, atol=0)
        points = np.stack([
            [physics.data.site_xpos[physics.model.site(f"{s}_{p}").id]
             for p in ("shoulder", "elbow", "wrist")]
            for s in body.SIDES
        ])
        np.testing.assert_allclose(points, body.body_of(dof).arm_points(q), atol=1e-12)
        np.testing.assert_allclose(physics.segment_vectors(), body.body_of(dof).segment_vectors(q),
                                   atol=1e-12)
        for signals in body.SIGNALS:
            np.testing.assert_allclose(physics.position_signals(signals),
                                       body.body_of(dof).position_signals(q, signals), atol=1e-12)
            np.testing.assert_allclose(physics.signal_jacobian(signals),
                                       body.body_of(dof).signal_jacobian(q, signals), atol=1e-12)


@pytest.mark.parametrize("dof", [4, 8])
def test_segment_jacobian_equals_mujoco_site_jacobians(dof):
    """The analytic signal Jacobian (axis x segment) is MuJoCo's mj_jacSite(b) -
    mj_jacSite(a) over the segment length, per signal component."""
    physics = SkinnyPhysics.load(dof)
    lay = physics.layout
    rng = np.random.default_rng(10 + dof)
    ranges = body.body_of(dof).joint_ranges()
    for _ in range(20):
        physics.set_joint_angles(rng.uniform(ranges[:, 0], ranges[:, 1]))
        rows = []
        for arm in range(2):
            jac = [lay.site_jacobian(physics.model.ptr, physics.data.ptr, s)[:, lay.dof_adr]
                   for s in lay.site_ids[arm]]
            for seg, length in enumerate(lay.arm_lengths):
                rows.append((jac[seg + 1] - jac[seg])[lay.components] / length)
        np.testing.assert_allclose(physics.signal_jacobian("cartesian"),
                                   np.concatenate(rows), rtol=0, atol=1e-12)


def test_site_jacobian_is_finite_difference_of_site_position():
    physics = SkinnyPhysics.load(8)
    q = np.array([1.0, 0.3, -0.4, 1.1, 0.5, -0.2, 0.6, 0.7])
    physics.set_joint_angles(q)
    jac = physics.site_jacobian("right_wrist")[:, physics.layout.dof_adr]
    eps = 1e-6
    num = np.empty((3, 8))
    for j in range(8):
        dq = np.zeros(8)
        dq[j] = eps
        wrist_plus = body.body_of(8).arm_points(q + dq)[0, 2]
        wrist_minus = body.body_of(8).arm_points(q - dq)[0, 2]
        num[:, j] = (wrist_plus - wrist_minus) / (2 * eps)
    np.testing.assert_allclose(jac, num, atol=1e-8)


def test_torque_twin_swaps_the_actuators_and_frees_the_arm():
    vel, tor = load_model("3d"), load_model("3d-torque")
    assert [tor.actuator(i).name for i in range(tor.nu)] == list(body.body_of(8).dof_names)
    assert np.all(tor.actuator_biastype == mujoco.mjtBias.mjBIAS_NONE)
    assert np.all(vel.actuator_biastype == mujoco.mjtBias.mjBIAS_AFFINE)
    gears = [TORQUE_GEAR_NM[n.split("_", 1)[1]] for n in body.body_of(8).dof_names]
    np.testing.assert_array_equal(tor.actuator_gear[:, 0], gears)
    np.testing.assert_array_equal(tor.actuator_ctrlrange, np.tile([-1.0, 1.0], (8, 1)))
    arm = [i for i in range(tor.nbody) if tor.body(i).name.endswith("arm")
           or tor.body(i).name.endswith("hand")]
    fixed = [i for i in range(tor.nbody) if i not in arm]
    np.testing.assert_array_equal(tor.body_mass[fixed], vel.body_mass[fixed])
    assert np.all(tor.body_gravcomp[arm] == 0) and np.all(vel.body_gravcomp[arm] == 1)
    np.testing.assert_array_equal(tor.jnt_range, vel.jnt_range)


def test_xml_is_hand_readable_radian_and_included():
    folder = models_dir()
    for name in ("skinny_2d.xml", "skinny_3d.xml"):
        text = (folder / name).read_text()
        assert 'angle="radian"' in text and 'include file="skinny_defaults.xml"' in text
    assert 'include file="skinny_2d.xml"' in body.body_of(4).path().read_text()
    assert body.body_of(8).path(scene=False).name == "skinny_3d.xml"


def test_bad_arguments_and_model_override(monkeypatch, tmp_path):
    with pytest.raises(SkinnyInputError, match="unknown body"):
        load_model(6)
    with pytest.raises(SkinnyInputError, match="actuation"):
        body.body_of("2d").twin("position")
    monkeypatch.setenv("SKINNY_MJ_MODELS", str(tmp_path))
    assert models_dir() == tmp_path
    with pytest.raises(SkinnyEnvironmentError, match="not found"):  # exit 1, not 2
        load_model(4)
