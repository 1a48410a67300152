"""skinny_mj.plant.body's registry of bodies: a body is an MJCF and a spec, chosen by its
dof; the spec refuses what cannot be a body; the MJCF is checked against the spec; another
package adds a body through an entry point. (docs/adding-a-body.md trains one.)"""

from __future__ import annotations

import shutil
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from skinny_mj import plugins
from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.plant.model import check_body, load_model, models_dir


@pytest.fixture
def six(tmp_path, monkeypatch):
    """Skinny without shoulder rotation (dof 6), its MJCF in tmp_path, not registered."""
    monkeypatch.setattr(body, "BODIES", {d: b for d, b in body.BODIES.items() if d != 6})
    shipped = models_dir()
    shutil.copy(shipped / "skinny_defaults.xml", tmp_path)
    robot = "\n".join(line for line in (shipped / "skinny_3d.xml").read_text().splitlines()
                      if "shoulder_rotation" not in line)
    (tmp_path / "six.xml").write_text(robot)
    (tmp_path / "scene_six.xml").write_text(
        (shipped / "scene_3d.xml").read_text().replace("skinny_3d.xml", "six.xml"))
    abduction, flexion, _, elbow = body.BODIES[8].arm_joints
    return body.Body(6, (abduction, flexion, elbow), planar=False, label="six",
                     robot="six.xml", scene="scene_six.xml", folder=tmp_path)


def test_skinny_bodies_are_4_and_8_and_an_unknown_dof_names_them():
    assert {d: b.label for d, b in body.BODIES.items() if d in (4, 8)} == {4: "2D", 8: "3D"}
    assert body.check_dof(4) == 4 and body.check_dof(8.0) == 8
    for bad in (5, True, "4", None, [4]):
        with pytest.raises(SkinnyInputError, match=r"dof must be 4 \(2D\) or 8 \(3D\)"):
            body.check_dof(bad)


def test_a_spec_that_cannot_be_a_body_is_refused():
    abduction, flexion, rotation, elbow = body.BODIES[8].arm_joints
    with pytest.raises(SkinnyInputError, match="twice its arm's joints"):
        body.Body(5, (abduction, elbow), planar=True, label="x", robot="r", scene="s")
    with pytest.raises(SkinnyInputError, match="distinct names"):
        body.Body(4, (abduction, abduction), planar=True, label="x", robot="r", scene="s")
    with pytest.raises(SkinnyInputError, match="upper arm first"):
        body.Body(4, (elbow, abduction), planar=True, label="x", robot="r", scene="s")
    with pytest.raises(SkinnyInputError, match="upper arm first"):
        body.Body(4, (abduction, flexion), planar=True, label="x", robot="r", scene="s")


def test_a_registered_body_is_chosen_by_its_dof_everywhere(six):
    with pytest.raises(SkinnyInputError, match="dof must be"):
        body.check_dof(6)
    assert body.register_body(six) is six and body.register_body(six) is six  # again: no-op
    assert body.check_dof(6) == 6 and check_body(6) == []
    assert body.dof_names(6)[:3] == ("right_shoulder_abduction", "right_shoulder_flexion",
                                     "right_elbow_flexion")
    assert len(body.signal_names(6, "cartesian")) == 12  # x, y, z of 2 segments x 2 arms
    model = load_model(6)
    assert model.njnt == model.nu == 6
    # the forward kinematics of the new body is the 3D body's with rotation 0
    q6 = np.array([0.4, 0.2, 1.0, 0.7, -0.1, 0.5])
    q8 = np.insert(np.insert(q6, 5, 0.0), 2, 0.0)
    np.testing.assert_allclose(body.arm_points(q6, 6), body.arm_points(q8, 8), atol=1e-15)
    with pytest.raises(SkinnyInputError, match="taken"):
        body.register_body(replace(six, label="another"))
    with pytest.raises(SkinnyInputError, match="taken"):
        body.register_body(replace(body.BODIES[4], label="not skinny"))


def test_check_body_names_what_the_mjcf_gets_wrong(six, tmp_path):
    abduction, flexion, elbow = six.arm_joints
    wrong_range = replace(six, arm_joints=(abduction, replace(flexion, range_rad=(-1.0, 1.0)),
                                           elbow))
    body.register_body(wrong_range)
    problems = check_body(6)
    assert problems and all("right_shoulder_flexion range" in p or "left_shoulder_flexion range"
                            in p for p in problems)
    body.BODIES.pop(6)
    longer = (tmp_path / "six.xml").read_text().replace(
        'fromto="0 0 0 0 0 -0.30" size="0.045"', 'fromto="0 0 0 0 0 -0.35" size="0.045"').replace(
        'name="right_forearm" pos="0 0 -0.30"', 'name="right_forearm" pos="0 0 -0.35"')
    (tmp_path / "six.xml").write_text(longer)
    body.register_body(six)
    assert any("sites' positions" in p for p in check_body(6))


@pytest.fixture
def fresh_entry_points():
    """Entry points read anew in this test, and again after it."""
    plugins.load_group.cache_clear()
    yield
    plugins.load_group.cache_clear()


def test_another_package_adds_a_body_through_the_entry_point_group(six, monkeypatch,
                                                                    fresh_entry_points):
    found = SimpleNamespace(name="six", value="pkg:SIX", load=lambda: six)
    monkeypatch.setattr(plugins, "entry_points",
                        lambda group: [found] if group == body.BODY_GROUP else [])
    assert body.body_of(6) is six and check_body(6) == []
    plugins.load_group.cache_clear()
    bad = SimpleNamespace(name="bad", value="pkg:NOT_A_BODY", load=lambda: "six")
    monkeypatch.setattr(plugins, "entry_points", lambda group: [bad])
    with pytest.raises(SkinnyInputError, match="is not a skinny_mj.plant.body.Body"):
        body.check_dof(10)


def test_ymca_is_refused_on_a_new_body_with_a_line_saying_what_works(six):
    from skinny_mj.trajectories import load_movement

    body.register_body(six)
    with pytest.raises(SkinnyInputError, match="babbling or a motion-capture clip"):
        load_movement("ymca", 6)
    traj, _ = load_movement("babble:seed=0,duration=2", 6)
    assert traj.angles.shape[1] == 6
