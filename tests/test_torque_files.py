"""The torque bodies' shipped MJCF (models/skinny/*_torque.xml): each file compiles to the
model the generator builds in code from the velocity body (``torque_spec``), field by
field and exactly, is what the generator writes today, and is the body the package loads
as ``2d-torque`` / ``3d-torque`` (Menagerie's model test, 1 s of random torques, runs on
it in tests/test_model.py)."""

from __future__ import annotations

import re

import mujoco
import numpy as np
import pytest

from skinny_mj.plant.body import body_of, models_dir
from skinny_mj.plant.model import load_model, torque_spec
from skinny_mj.plant.torque_files import torque_file_names, torque_robot_xml, torque_scene_xml

DOFS = [4, 8]
TWINS = {4: "2d-torque", 8: "3d-torque"}
#: Model-level structs compared field by field beside MjModel's own arrays and sizes.
STRUCTS = ("opt", "stat", "vis")


def _fields(obj, prefix: str = "") -> dict[str, object]:
    """Every number of ``obj`` by dotted name: arrays, ints and floats, recursing into
    :data:`STRUCTS` (and ``vis``'s sub-structs). The model name (the first entry of
    ``names``) differs by design, so ``names``, ``nnames`` and the ``name_*adr``
    offsets into it are left to :func:`_element_names`."""
    out: dict[str, object] = {}
    for name in dir(obj):
        if name.startswith("_") or name in ("names", "nnames") or name.startswith("name_"):
            continue
        value = getattr(obj, name)
        if isinstance(value, np.ndarray | int | float):
            out[prefix + name] = value
        elif ((not prefix and name in STRUCTS) or prefix == "vis.") and not callable(value):
            out.update(_fields(value, f"{prefix}{name}."))
    return out


def _element_names(model: mujoco.MjModel) -> list[bytes]:
    return model.names.split(b"\x00")[1:]  # every element's name, the model's own left out


def _assert_same_model(got: mujoco.MjModel, want: mujoco.MjModel) -> list[str]:
    a, b = _fields(got), _fields(want)
    assert a.keys() == b.keys()
    differ = [k for k in a if not (np.shape(a[k]) == np.shape(b[k]) and np.array_equal(
        a[k], b[k], equal_nan=True))]
    assert differ == [], f"fields that differ: {differ}"
    assert _element_names(got) == _element_names(want)
    return list(a)


@pytest.mark.parametrize("dof", DOFS)
def test_shipped_torque_files_compile_to_the_package_model(dof):
    robot, scene = (models_dir() / name for name in torque_file_names(dof))
    compared = _assert_same_model(mujoco.MjModel.from_xml_path(str(scene)),
                                  torque_spec(dof).compile())
    _assert_same_model(mujoco.MjModel.from_xml_path(str(robot)),
                       torque_spec(dof, scene=False).compile())
    twin = body_of(TWINS[dof])  # the body the package loads: these files
    assert (twin.path(), twin.path(scene=False)) == (scene, robot)
    assert body_of(dof).twin("torque") is twin
    _assert_same_model(load_model(twin), torque_spec(dof).compile())
    # the fields the model card lists are among those compared, exactly
    for field in ("nq", "nv", "nu", "body_mass", "body_inertia", "body_ipos", "body_gravcomp",
                  "dof_damping", "dof_armature", "jnt_range", "jnt_solref", "jnt_solimp",
                  "jnt_actfrcrange", "actuator_gear", "actuator_ctrlrange",
                  "actuator_forcerange", "actuator_gainprm", "actuator_biastype",
                  "geom_size", "geom_pos", "geom_quat", "opt.gravity", "opt.timestep",
                  "opt.integrator", "opt.disableflags"):
        assert field in compared


@pytest.mark.parametrize("dof", DOFS)
def test_shipped_torque_files_are_what_the_generator_writes(dof):
    """Regenerate with ``python -m skinny_mj.plant.torque_files models/skinny`` if this fails."""
    robot, scene = (models_dir() / name for name in torque_file_names(dof))
    assert robot.read_text() == torque_robot_xml(dof)
    assert scene.read_text() == torque_scene_xml(dof)


@pytest.mark.parametrize("dof", DOFS)
def test_shipped_torque_file_is_tidy(dof):
    robot, scene = (models_dir() / name for name in torque_file_names(dof))
    text = robot.read_text()
    assert text.startswith("<!-- GENERATED") and "python -m skinny_mj.plant.torque_files" in text
    assert 'angle="radian"' in text and "<motor " in text and 'gravcomp="' not in text
    # the classes hold the joints' and motors' parameters; the elements name and place
    elements = re.findall(r"<(?:joint|motor) name=[^>]*>", text)
    assert len(elements) == 2 * dof
    assert not [e for e in elements if re.search(r"gear|range|armature|sol|damping", e)]
    assert f'<include file="{robot.name}"/>' in scene.read_text()
