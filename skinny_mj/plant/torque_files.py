"""The torque twin as MJCF files, for MuJoCo users: ``skinny_{2d,3d}_torque.xml`` (the
robot) and ``scene_{2d,3d}_torque.xml`` (floor, light, camera; ``<include>`` the robot) in
``models/skinny/``, so ``python -m mujoco.viewer --mjcf=models/skinny/scene_2d_torque.xml``
opens the physical arm.

The files are written, never edited: the robot is Skinny's XML with the MjSpec edits of
:func:`skinny_mj.plant.model.torque_spec`, those edits moved into the default classes (a
class per joint kind holds the joint and its motor, as in the velocity XML), saved by
:meth:`mujoco.MjSpec.to_xml` as authored (``savecompiled`` and ``savecanonical`` off:
default classes, ``fromto`` capsules, ``<motor>`` shortcuts and full-precision numbers
kept); the scene is the velocity body's scene with its ``<include>`` pointed at the torque
robot. They are the bodies ``2d-torque`` and ``3d-torque``
(:data:`skinny_mj.plant.body.BODIES`); ``tests/test_torque_files.py`` checks that each
shipped file compiles to the model :func:`torque_spec` builds, field by field.
Regenerate after changing the XML or the twin's constants::

    python -m skinny_mj.plant.torque_files models/skinny
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import mujoco
import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.body import Body, BodyLike, body_of
from skinny_mj.plant.model import torque_spec

REGENERATE = "python -m skinny_mj.plant.torque_files models/skinny"


def torque_file_names(velocity: BodyLike) -> tuple[str, str]:
    """The torque twin's robot and scene file names: the velocity body's with
    ``_torque`` before ``.xml`` (``skinny_2d_torque.xml``, ``scene_2d_torque.xml``)."""
    skinny = body_of(velocity)
    return (f"{Path(skinny.robot).stem}_torque.xml", f"{Path(skinny.scene).stem}_torque.xml")


def _header(velocity: Body, source: str, what: str) -> str:
    # no "--" in the text: an XML comment may not hold one
    call = f"torque_spec(\"{velocity.name}\")"
    if velocity.folder is None:  # Skinny's own: shipped, with a model card and a test
        command = REGENERATE
        checked = ("     Model card: README.md. tests/test_torque_files.py checks that this file "
                   "compiles\n"
                   f"     to the model skinny_mj.plant.model.{call} builds.")
    else:  # a registered body (docs/adding-a-body.md)
        command = f"skinny_mj.plant.torque_files.write_torque_mjcf(\"{velocity.name}\", folder)"
        checked = f"     It compiles to skinny_mj.plant.model.{call} when written."
    return (f"<!-- GENERATED from {source} by `{command}`: do not edit.\n"
            f"     Skinny {velocity.label} ({velocity.dof} DOF), torque twin: {what}\n"
            f"{checked} -->\n")


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


def _defaults_hold_the_motors(spec: mujoco.MjSpec, velocity: Body) -> None:
    """Re-express the twin's per-element edits as Skinny's default classes, as the velocity
    XML does (a class per joint kind holds the joint and its actuator): every class becomes
    a motor class with the settings shared by all arm joints and motors, each joint kind's
    class takes its own (gear, torque range, armature), and the classes of the other
    body's joints go; the arm's capsules lose their masses, which the segments' explicit
    inertials override. The compiled model is unchanged (tests/test_torque_files.py)."""
    names = velocity.dof_names
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


def torque_robot_xml(velocity: BodyLike) -> str:
    """The torque robot's MJCF text: ``torque_spec(velocity, scene=False)`` saved as
    authored, under a comment saying where it comes from."""
    skinny = body_of(velocity)
    spec = torque_spec(skinny, scene=False)
    _defaults_hold_the_motors(spec, skinny)
    spec.compiler.savecompiled = False  # the spec as authored, not the compiled model
    spec.compiler.savecanonical = False  # and in its own terms: fromto, <motor>, radians
    spec.modelname = Path(torque_file_names(skinny)[0]).stem
    what = ("the robot's XML with <motor>\n"
            "     actuators of the velocity servos' names (ctrl = torque / limit in [-1, 1],\n"
            "     gear = limit in N m), gravity acting (no gravcomp), de Leva segment\n"
            "     inertials, stiff joint limits, RK4 at 5 ms.")
    return _header(skinny, skinny.robot, what) + spec.to_xml()


def torque_scene_xml(velocity: BodyLike) -> str:
    """The torque scene's MJCF text: the velocity scene with its ``<include>`` pointed at
    the torque robot and its model renamed."""
    skinny = body_of(velocity)
    robot, scene = skinny.robot, skinny.path()
    torque_robot = torque_file_names(skinny)[0]
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
    return _header(skinny, scene.name, what) + body_text


def write_torque_mjcf(velocity: BodyLike, folder: Path) -> tuple[Path, Path]:
    """Write the torque robot and scene of the velocity body ``velocity`` into ``folder``;
    return their paths (robot, scene)."""
    folder = Path(folder)
    robot_name, scene_name = torque_file_names(velocity)
    robot, scene = folder / robot_name, folder / scene_name
    robot.write_text(torque_robot_xml(velocity))
    scene.write_text(torque_scene_xml(velocity))
    return robot, scene


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m skinny_mj.plant.torque_files",
        description="Write the torque twin's MJCF (robot and scene) for each body.")
    parser.add_argument("folder", type=Path, help="where to write (models/skinny)")
    parser.add_argument("--body", nargs="+", default=["2d", "3d"],
                        help="the velocity bodies (default: 2d 3d)")
    args = parser.parse_args(argv)
    for name in args.body:
        for path in write_torque_mjcf(name, args.folder):
            print(path)


if __name__ == "__main__":
    main()
