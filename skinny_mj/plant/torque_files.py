"""The torque twin as MJCF files, for MuJoCo users: ``skinny_{2d,3d}_torque.xml`` (the
robot) and ``scene_{2d,3d}_torque.xml`` (floor, light, camera; ``<include>`` the robot) in
``models/skinny/``, so ``python -m mujoco.viewer --mjcf=models/skinny/scene_2d_torque.xml``
opens the physical arm.

The files are written, never edited: the robot is Skinny's XML with the MjSpec edits of
:func:`skinny_mj.plant.model.load_spec` (``actuation="torque"``), those edits moved into
the default classes (a class per joint kind holds the joint and its motor, as in the
velocity XML), saved by :meth:`mujoco.MjSpec.to_xml` as authored (``savecompiled`` and
``savecanonical`` off: default classes, ``fromto`` capsules, ``<motor>`` shortcuts and
full-precision numbers kept); the scene is the velocity body's scene with its
``<include>`` pointed at the torque robot. The package itself still builds the twin in
code (:func:`load_model`); ``tests/test_torque_files.py`` checks that each shipped file compiles
to that model, field by field. Regenerate after changing the XML or the twin's constants::

    python -m skinny_mj.plant.torque_files models/skinny
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import mujoco
import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.plant.model import load_spec, xml_path

REGENERATE = "python -m skinny_mj.plant.torque_files models/skinny"


def torque_file_names(dof: int) -> tuple[str, str]:
    """The torque twin's robot and scene file names: the velocity body's with
    ``_torque`` before ``.xml`` (``skinny_2d_torque.xml``, ``scene_2d_torque.xml``)."""
    spec = body.body_of(dof)
    return (f"{Path(spec.robot).stem}_torque.xml", f"{Path(spec.scene).stem}_torque.xml")


def _header(dof: int, source: str, what: str) -> str:
    # no "--" in the text: an XML comment may not hold one
    spec = body.body_of(dof)
    if spec.folder is None:  # Skinny's own: shipped, with a model card and a test
        command = REGENERATE
        checked = ("     Model card: README.md. tests/test_torque_files.py checks that this file "
                   "compiles\n"
                   f"     to the model skinny_mj.plant.model.load_model({dof}, \"torque\") "
                   "builds.")
    else:  # a registered body (docs/adding-a-body.md)
        command = f"skinny_mj.plant.torque_files.write_torque_mjcf({dof}, folder)"
        checked = (f"     It compiles to skinny_mj.plant.model.load_model({dof}, \"torque\") "
                   "when written.")
    return (f"<!-- GENERATED from {source} by `{command}`: do not edit.\n"
            f"     Skinny {spec.label} ({dof} DOF), torque twin: {what}\n{checked} -->\n")


#: What the twin sets on the arm joints and motors (skinny_mj.plant.model._make_physical),
#: moved into the default classes so the body's elements state geometry and names only:
#: the same on every joint and motor (in every class), and per joint kind (in its class).
_SHARED = {"joint": ("damping", "solref_limit", "solimp_limit"),
           "actuator": ("ctrllimited", "ctrlrange", "forcelimited", "forcerange")}
_PER_KIND = {"joint": ("armature", "actfrclimited", "actfrcrange"), "actuator": ("gear",)}


def _one_value(elements: list, field: str) -> object:
    values = [getattr(e, field) for e in elements]
    if any(not np.array_equal(v, values[0]) for v in values):
        raise SkinnyInputError(f"{field} differs where one default class should hold it: "
                               f"{values}")
    return values[0].copy() if isinstance(values[0], np.ndarray) else values[0]


def _defaults_hold_the_motors(spec: mujoco.MjSpec, dof: int) -> None:
    """Re-express the twin's per-element edits as Skinny's default classes, as the velocity
    XML does (a class per joint kind holds the joint and its actuator): every class becomes
    a motor class with the settings shared by all arm joints and motors, each joint kind's
    class takes its own (gear, torque range, armature), and the classes of the other
    body's joints go; the arm's capsules lose their masses, which the segments' explicit
    inertials override. The compiled model is unchanged (tests/test_torque_files.py)."""
    names = body.dof_names(dof)
    elements = {"joint": [spec.joint(n) for n in names],
                "actuator": [spec.actuator(n) for n in names]}
    used = {e.classname.name for e in (*elements["joint"], *elements["actuator"],
                                       *spec.geoms, *spec.sites)}
    used |= {b.childclass for b in spec.bodies if b.childclass}
    kinds = {j.classname.name for j in elements["joint"]}
    for b in spec.bodies:  # an explicit <inertial> sets the arm's masses: the capsules' go
        if b.explicitinertial:
            for geom in b.geoms:
                geom.mass = spec.find_default(geom.classname.name).geom.mass
    for name in re.findall(r'<default class="([^"]+)"', spec.to_xml()):
        default = spec.find_default(name)
        if name not in used:
            spec.delete(default)
            continue
        default.actuator.set_to_motor()
        for kind, fields in _SHARED.items():
            for field in fields:
                setattr(getattr(default, kind), field, _one_value(elements[kind], field))
        if name in kinds:
            for kind, fields in _PER_KIND.items():
                of_kind = [e for e in elements[kind] if e.classname.name == name]
                for field in fields:
                    setattr(getattr(default, kind), field, _one_value(of_kind, field))


def torque_robot_xml(dof: int) -> str:
    """The torque robot's MJCF text: ``load_spec(dof, "torque", scene=False)`` saved as
    authored, under a comment saying where it comes from."""
    spec = load_spec(dof, "torque", scene=False)
    _defaults_hold_the_motors(spec, dof)
    spec.compiler.savecompiled = False  # the spec as authored, not the compiled model
    spec.compiler.savecanonical = False  # and in its own terms: fromto, <motor>, radians
    spec.modelname = Path(torque_file_names(dof)[0]).stem
    what = ("the robot's XML with <motor>\n"
            "     actuators of the velocity servos' names (ctrl = torque / limit in [-1, 1],\n"
            "     gear = limit in N m), gravity acting (no gravcomp), de Leva segment\n"
            "     inertials, stiff joint limits, RK4 at 5 ms.")
    return _header(dof, xml_path(dof, scene=False).name, what) + spec.to_xml()


def torque_scene_xml(dof: int) -> str:
    """The torque scene's MJCF text: the velocity scene with its ``<include>`` pointed at
    the torque robot and its model renamed."""
    robot, scene = xml_path(dof, scene=False).name, xml_path(dof)
    torque_robot = torque_file_names(dof)[0]
    text = scene.read_text()
    include = f'<include file="{robot}"/>'
    if text.count(include) != 1 or not text.lstrip().startswith("<!--"):
        raise SkinnyInputError(f"{scene}: expected a leading comment and one {include}")
    text = text.replace(include, f'<include file="{torque_robot}"/>')
    text, renamed = re.subn(r'<mujoco model="[^"]*"',
                            f'<mujoco model="{Path(torque_robot).stem}_scene"', text, count=1)
    if not renamed:
        raise SkinnyInputError(f"{scene}: no <mujoco model=...> to rename")
    body_text = text[text.index("-->") + 3:].lstrip("\n")  # the scene's own comment goes
    what = f"{scene.name} including {torque_robot}\n     (floor, light, camera \"front\")."
    return _header(dof, scene.name, what) + body_text


def write_torque_mjcf(dof: int, folder: Path) -> tuple[Path, Path]:
    """Write the torque robot and scene of body ``dof`` into ``folder``; return their
    paths (robot, scene)."""
    folder = Path(folder)
    robot_name, scene_name = torque_file_names(dof)
    robot, scene = folder / robot_name, folder / scene_name
    robot.write_text(torque_robot_xml(dof))
    scene.write_text(torque_scene_xml(dof))
    return robot, scene


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m skinny_mj.plant.torque_files",
        description="Write the torque twin's MJCF (robot and scene) for each body.")
    parser.add_argument("folder", type=Path, help="where to write (models/skinny)")
    parser.add_argument("--dof", type=int, nargs="+", default=[4, 8],
                        help="the bodies (default: 4 8)")
    args = parser.parse_args(argv)
    for dof in args.dof:
        for path in write_torque_mjcf(dof, args.folder):
            print(path)


if __name__ == "__main__":
    main()
