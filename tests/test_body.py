"""skinny_mj.plant.body's registry of bodies: a body is a name and its MJCF, whose joints,
axes, ranges, segment lengths and actuators are read from the file; two bodies of one
number of hinges live side by side; what cannot be a body is refused naming the file;
another package adds a body through an entry point. (docs/adding-a-body.md trains one.)"""

from __future__ import annotations

import shutil
from dataclasses import replace
from types import SimpleNamespace

import mujoco
import numpy as np
import pytest

from skinny_mj import plugins
from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.plant.adapters import BatchPlant
from skinny_mj.plant.model import check_body, load_model
from skinny_mj.trajectories import get, load_movement

SKINNY = ("2d", "3d", "2d-torque", "3d-torque")


@pytest.fixture
def registry(monkeypatch):
    """The registry as shipped, for this test only (a test may register bodies)."""
    monkeypatch.setattr(body, "BODIES", {n: b for n, b in body.BODIES.items() if n in SKINNY})
    return body.BODIES


def _long_forearm(folder, forearm_m: float = 0.35) -> body.Body:
    """Skinny's 2D robot with longer forearms (its MJCF in ``folder``), not registered."""
    shipped = body.models_dir()
    shutil.copy(shipped / "skinny_defaults.xml", folder)
    robot = (shipped / "skinny_2d.xml").read_text().replace(
        'fromto="0 0 0 0 0 -0.27"', f'fromto="0 0 0 0 0 -{forearm_m}"').replace(
        'pos="0 0 -0.27"', f'pos="0 0 -{forearm_m}"')
    (folder / "long.xml").write_text(robot)
    (folder / "scene_long.xml").write_text(
        (shipped / "scene_2d.xml").read_text().replace("skinny_2d.xml", "long.xml"))
    return body.Body("2d-long", "long.xml", "scene_long.xml", folder=folder)


@pytest.fixture
def six(tmp_path):
    """Skinny without shoulder rotation (6 DOF), its MJCF in tmp_path, not registered."""
    shipped = body.models_dir()
    shutil.copy(shipped / "skinny_defaults.xml", tmp_path)
    robot = "\n".join(line for line in (shipped / "skinny_3d.xml").read_text().splitlines()
                      if "shoulder_rotation" not in line)
    (tmp_path / "six.xml").write_text(robot)
    (tmp_path / "scene_six.xml").write_text(
        (shipped / "scene_3d.xml").read_text().replace("skinny_3d.xml", "six.xml"))
    return body.Body("six", "six.xml", "scene_six.xml", folder=tmp_path)


def test_skinny_bodies_are_named_and_an_unknown_name_lists_them(registry):
    assert tuple(registry) == SKINNY
    assert [body.body_of(n).dof for n in SKINNY] == [4, 8, 4, 8]
    assert [body.body_of(n).actuation for n in SKINNY] == ["velocity", "velocity", "torque",
                                                           "torque"]
    assert body.body_of(4).name == "2d" and body.body_of(8.0).name == "3d"  # the dof aliases
    for bad in (5, True, "2D", "", None, [4]):
        with pytest.raises(SkinnyInputError, match=r"unknown body .*2d, 3d, 2d-torque, "
                                                   r"3d-torque"):
            body.body_of(bad)
    with pytest.raises(SkinnyInputError, match="a word"):
        body.Body("two d", "r.xml", "s.xml")


def test_each_body_is_read_from_its_mjcf_and_nothing_is_restated():
    for name in SKINNY:
        skinny = body.body_of(name)
        model = mujoco.MjModel.from_xml_path(str(skinny.path(scene=False)))
        assert list(skinny.dof_names) == [model.joint(i).name for i in range(model.njnt)]
        np.testing.assert_array_equal(skinny.joint_ranges(), model.jnt_range)
        for i, joint in enumerate(skinny.arms.joints):
            np.testing.assert_array_equal(skinny.joint_axis(i, "right"),
                                          model.joint(f"right_{joint}").axis)
        np.testing.assert_array_equal(skinny.arms.gears, model.actuator_gear[:, 0])
        np.testing.assert_array_equal(skinny.lengths_m(), [0.30, 0.27])
        assert skinny.planar == (name.startswith("2d")) and check_body(name) == []
    torque = body.body_of("3d-torque")
    assert torque.arms.gears == (50.0, 60.0, 30.0, 45.0) * 2  # N m: the motors' peaks
    assert torque.twin("velocity") is body.body_of("3d") and torque.twin("torque") is torque
    assert body.body_of("2d").twin("torque") is body.body_of("2d-torque")
    assert body.by_dof(8, "torque") == "3d-torque" and body.by_dof("4") == "2d"


def test_two_bodies_with_four_hinges_live_side_by_side(registry, tmp_path):
    long = body.register_body(_long_forearm(tmp_path))
    assert body.register_body(long) is long  # the same again: a no-op
    assert body.body_names() == (*SKINNY, "2d-long")
    assert body.body_of("2d-long").dof == body.body_of("2d").dof == 4
    assert long.dof_names == body.body_of("2d").dof_names and check_body(long) == []
    np.testing.assert_array_equal(long.lengths_m(), [0.30, 0.35])
    q = np.array([0.4, 1.0, 0.7, 0.2])
    wrists = [body.body_of(n).arm_points(q)[:, 2] for n in ("2d", "2d-long")]
    assert np.all(np.linalg.norm(wrists[1] - wrists[0], axis=-1) > 0.05)  # 8 cm further
    np.testing.assert_array_equal(long.position_signals(q, "joint"),
                                  body.body_of("2d").position_signals(q, "joint"))
    ymca = get("ymca", "2d-long")  # YMCA is written for the hinges, not the lengths
    assert ymca.body == "2d-long"
    plant = BatchPlant("2d-long", "cartesian", ymca, n_runs=1)
    plant.reset()
    np.testing.assert_allclose(plant.true_signals()[0], long.position_signals(
        plant.setup.start_rad, "cartesian"), atol=1e-12)
    with pytest.raises(SkinnyInputError, match="taken"):
        body.register_body(replace(long, label="another"))
    with pytest.raises(SkinnyInputError, match="taken"):
        body.register_body(replace(body.BODIES["2d"], label="not skinny"))


def test_a_body_with_other_hinges_is_chosen_by_its_name(registry, six):
    body.register_body(six)
    assert body.body_of("six").dof == 6 and check_body("six") == []
    assert six.dof_names[:3] == ("right_shoulder_abduction", "right_shoulder_flexion",
                                 "right_elbow_flexion")
    assert len(six.signal_names("cartesian")) == 12  # x, y, z of 2 segments x 2 arms
    model = load_model("six")
    assert model.njnt == model.nu == 6
    # the forward kinematics of the new body is the 3D body's with rotation 0
    q6 = np.array([0.4, 0.2, 1.0, 0.7, -0.1, 0.5])
    q8 = np.insert(np.insert(q6, 5, 0.0), 2, 0.0)
    np.testing.assert_allclose(six.arm_points(q6), body.body_of("3d").arm_points(q8),
                               atol=1e-15)
    with pytest.raises(SkinnyInputError, match="babbling or a motion-capture clip"):
        load_movement("ymca", "six")
    traj, _ = load_movement("babble:seed=0,duration=2", "six")
    assert traj.angles.shape[1] == 6 and traj.body == "six"


def test_an_mjcf_that_is_not_two_arms_is_refused_naming_the_file(six, tmp_path):
    text = (tmp_path / "six.xml").read_text()
    cases = {
        "no actuator": (text.replace('<velocity name="left_elbow_flexion" joint='
                                     '"left_elbow_flexion" class="elbow_3d"/>', ""),
                        "actuators"),
        "a renamed hinge": (text.replace('<joint name="left_elbow_flexion"',
                                         '<joint name="left_elbow_bend"').replace(
            'joint="left_elbow_flexion"', 'joint="left_elbow_bend"'), "not the right arm's"),
        "a bent forearm": (text.replace('name="right_hand" pos="0 0 -0.27"',
                                        'name="right_hand" pos="0.05 0 -0.27"'),
                           "not straight below"),
        "a left axis not mirrored": (text.replace(
            '<joint name="left_elbow_flexion" class="elbow_3d" axis="0 -1 0"/>',
            '<joint name="left_elbow_flexion" class="elbow_3d" axis="0 1 0"/>'),
            "mirror image"),
    }
    for what, (edited, says) in cases.items():
        (tmp_path / "six.xml").write_text(edited)
        problems = check_body(six)
        assert problems, what
        if says is not None:
            assert any(says in p for p in problems), (what, problems)
    (tmp_path / "six.xml").write_text(cases["no actuator"][0])
    with pytest.raises(SkinnyInputError, match=r"six\.xml: not a body of two arms"):
        load_model(six)


@pytest.fixture
def fresh_entry_points():
    """Entry points read anew in this test, and again after it."""
    plugins.load_group.cache_clear()
    yield
    plugins.load_group.cache_clear()


def test_another_package_adds_a_body_through_the_entry_point_group(registry, six, monkeypatch,
                                                                    fresh_entry_points):
    found = SimpleNamespace(name="six", value="pkg:SIX", load=lambda: six)
    monkeypatch.setattr(plugins, "entry_points",
                        lambda group: [found] if group == body.BODY_GROUP else [])
    assert body.body_of("six") is six and check_body("six") == []
    assert "six" in body.body_names()
    plugins.load_group.cache_clear()
    bad = SimpleNamespace(name="bad", value="pkg:NOT_A_BODY", load=lambda: "six")
    monkeypatch.setattr(plugins, "entry_points", lambda group: [bad])
    with pytest.raises(SkinnyInputError, match="is not a skinny_mj.plant.body.Body"):
        body.body_of("ten")


def test_a_body_without_a_torque_twin_says_how_to_get_one(registry, tmp_path):
    long = body.register_body(_long_forearm(tmp_path))
    with pytest.raises(SkinnyInputError, match="no torque twin registered.*write_torque_mjcf"):
        long.twin("torque")
    from skinny_mj.plant.torque_files import write_torque_mjcf

    robot, scene = write_torque_mjcf("2d-long", tmp_path)
    twin = body.register_body(body.Body("2d-long-torque", robot.name, scene.name,
                                        folder=tmp_path))
    assert twin.actuation == "torque" and check_body(twin) == []
    assert long.twin("torque") is twin and twin.twin("velocity") is long
    assert body.actuation_of("2d-long-torque") == "torque"
    assert twin.lengths_m()[1] == 0.35
    # the longer forearm is heavier and its inertia larger than Skinny's
    model, skinny = load_model(twin), load_model("2d-torque")
    fore = model.body("right_forearm").id
    assert model.body_mass[fore] == skinny.body_mass[fore]
    assert model.body_ipos[fore][2] < skinny.body_ipos[fore][2]
