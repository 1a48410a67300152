"""Skinny's MJCF: loads, steps cleanly, names everything, and equals skinny_mj/plant/body.py."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from skinny_mj.errors import SkinnyEnvironmentError, SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.plant.model import TORQUE_GEAR_NM, load_model, models_dir, xml_path
from skinny_mj.plant.physics import SkinnyPhysics
from skinny_mj.plant.torque_files import torque_file_names

VARIANTS = [(d, a) for d in (4, 8) for a in ("velocity", "torque")]


def _model(dof: int, actuation: str, source: str) -> mujoco.MjModel:
    """The model the package builds, or the shipped torque MJCF file (``source``)."""
    if source == "built":
        return load_model(dof, actuation)
    return mujoco.MjModel.from_xml_path(str(models_dir() / torque_file_names(dof)[1]))


@pytest.mark.parametrize("dof,actuation,source", [*((d, a, "built") for d, a in VARIANTS),
                                                  (4, "torque", "file"), (8, "torque", "file")])
def test_one_second_of_random_control_is_clean(dof, actuation, source):
    model = _model(dof, actuation, source)
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
    names = body.dof_names(dof)
    assert [model.joint(i).name for i in range(model.njnt)] == list(names)
    assert [model.actuator(i).name for i in range(model.nu)] == list(names)
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST


@pytest.mark.parametrize("dof", [4, 8])
def test_joints_match_body_contract(dof):
    model = load_model(dof)
    n_arm = dof // 2
    for k, side in enumerate(body.SIDES):
        for i, spec in enumerate(body.body_of(dof).arm_joints):
            joint = model.joint(f"{side}_{spec.name}")
            assert model.body(joint.bodyid[0]).name == f"{side}_{spec.segment}"
            np.testing.assert_allclose(joint.axis, body.joint_axis(spec, side), atol=1e-15)
            np.testing.assert_allclose(joint.range, spec.range_rad, rtol=0, atol=1e-15)
            assert model.jnt_limited[joint.id]
            assert joint.id == k * n_arm + i
        for part in ("upper_arm", "forearm", "hand"):
            assert model.body_gravcomp[model.body(f"{side}_{part}").id] == 1.0
    np.testing.assert_allclose(model.jnt_range, body.joint_ranges(dof), atol=1e-15)


@pytest.mark.parametrize("dof", [4, 8])
def test_forward_kinematics_and_jacobians_equal_body(dof):
    physics = SkinnyPhysics.load(dof)
    rng = np.random.default_rng(dof)
    ranges = body.joint_ranges(dof)
    for _ in range(20):
        q = rng.uniform(ranges[:, 0], ranges[:, 1])
        physics.set_joint_angles(q)
        np.testing.assert_allclose(physics.joint_angles(), q, atol=0)
        points = np.stack([
            [physics.data.site_xpos[physics.model.site(f"{s}_{p}").id]
             for p in ("shoulder", "elbow", "wrist")]
            for s in body.SIDES
        ])
        np.testing.assert_allclose(points, body.arm_points(q, dof), atol=1e-12)
        np.testing.assert_allclose(physics.segment_vectors(), body.segment_vectors(q, dof),
                                   atol=1e-12)
        for signals in body.SIGNALS:
            np.testing.assert_allclose(physics.position_signals(signals),
                                       body.position_signals(q, dof, signals), atol=1e-12)
            np.testing.assert_allclose(physics.signal_jacobian(signals),
                                       body.signal_jacobian(q, dof, signals), atol=1e-12)


@pytest.mark.parametrize("dof", [4, 8])
def test_segment_jacobian_equals_mujoco_site_jacobians(dof):
    """The analytic signal Jacobian (axis x segment) is MuJoCo's mj_jacSite(b) -
    mj_jacSite(a) over the segment length, per signal component."""
    physics = SkinnyPhysics.load(dof)
    lay = physics.layout
    rng = np.random.default_rng(10 + dof)
    ranges = body.joint_ranges(dof)
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
        wrist_plus, wrist_minus = body.arm_points(q + dq, 8)[0, 2], body.arm_points(q - dq, 8)[0, 2]
        num[:, j] = (wrist_plus - wrist_minus) / (2 * eps)
    np.testing.assert_allclose(jac, num, atol=1e-8)


def test_torque_twin_swaps_the_actuators_and_frees_the_arm():
    vel, tor = load_model(8, "velocity"), load_model(8, "torque")
    assert [tor.actuator(i).name for i in range(tor.nu)] == list(body.dof_names(8))
    assert np.all(tor.actuator_biastype == mujoco.mjtBias.mjBIAS_NONE)
    assert np.all(vel.actuator_biastype == mujoco.mjtBias.mjBIAS_AFFINE)
    gears = [TORQUE_GEAR_NM[n.split("_", 1)[1]] for n in body.dof_names(8)]
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
    assert 'include file="skinny_2d.xml"' in xml_path(4).read_text()
    assert xml_path(8, scene=False).name == "skinny_3d.xml"


def test_bad_arguments_and_model_override(monkeypatch, tmp_path):
    with pytest.raises(SkinnyInputError, match="dof"):
        load_model(6)
    with pytest.raises(SkinnyInputError, match="actuation"):
        load_model(4, "position")
    monkeypatch.setenv("SKINNY_MJ_MODELS", str(tmp_path))
    assert models_dir() == tmp_path
    with pytest.raises(SkinnyEnvironmentError, match="not found"):  # exit 1, not 2
        load_model(4)
