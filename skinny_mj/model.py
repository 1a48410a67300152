"""Where Skinny's MJCF files live and how to load them (velocity servo or torque twin).

The XML in ``models/skinny/`` is the single body description. The torque twin is
made from the same XML with :class:`mujoco.MjSpec`: the velocity actuators are
replaced by ``<motor>`` actuators of the same names (see :data:`TORQUE_GEAR_NM`).
"""

from __future__ import annotations

import os
from pathlib import Path

import mujoco

from skinny_mj import body
from skinny_mj.errors import SkinnyInputError

MODELS_ENV_VAR = "SKINNY_MJ_MODELS"
ACTUATIONS = ("velocity", "torque")
# Peak joint torque (N m) of the torque twin: ctrl in [-1, 1] times this gear. Roughly
# a strong adult's isometric shoulder / elbow torque; gravity is compensated anyway.
TORQUE_GEAR_NM = {
    "shoulder_abduction": 60.0,
    "shoulder_flexion": 60.0,
    "shoulder_rotation": 30.0,
    "elbow_flexion": 40.0,
}
# The torque twin integrates at 2 ms (10 substeps per 20 ms control step): full random
# torques on the light shoulder-rotation DOF blow up at the servo's 20 ms step.
TORQUE_TIMESTEP_S = 0.002
_VARIANT = {4: "2d", 8: "3d"}


def models_dir() -> Path:
    """The folder holding Skinny's XML: ``$SKINNY_MJ_MODELS`` or ``<repo>/models/skinny``."""
    override = os.environ.get(MODELS_ENV_VAR)
    if override:
        return Path(override)
    return Path(__file__).resolve().parent.parent / "models" / "skinny"


def _check(dof: int, actuation: str = "velocity") -> None:
    if dof not in _VARIANT:
        raise SkinnyInputError(f"dof must be 4 (2D) or 8 (3D), got {dof!r}")
    if actuation not in ACTUATIONS:
        raise SkinnyInputError(f"actuation must be one of {ACTUATIONS}, got {actuation!r}")


def xml_path(dof: int, scene: bool = True) -> Path:
    """Path of ``scene_{2d,3d}.xml`` (floor, light, camera) or, with ``scene=False``,
    of the robot alone (``skinny_{2d,3d}.xml``)."""
    _check(dof)
    name = f"{'scene' if scene else 'skinny'}_{_VARIANT[dof]}.xml"
    path = models_dir() / name
    if not path.is_file():
        raise SkinnyInputError(
            f"model file not found (set {MODELS_ENV_VAR} to the models/skinny folder)", path=path
        )
    return path


def load_spec(dof: int, actuation: str = "velocity", scene: bool = True) -> mujoco.MjSpec:
    """The scene (``scene=False``: the robot alone) as an editable
    :class:`mujoco.MjSpec`; ``actuation="torque"`` swaps every
    velocity actuator for a motor of the same name and joint, gear = peak torque (N m),
    ctrlrange [-1, 1], timestep :data:`TORQUE_TIMESTEP_S`; the joints keep their
    limits (soft MuJoCo constraints)."""
    _check(dof, actuation)
    spec = mujoco.MjSpec.from_file(str(xml_path(dof, scene)))
    if actuation == "torque":
        spec.option.timestep = TORQUE_TIMESTEP_S
        for name in body.dof_names(dof):
            act = spec.actuator(name)
            act.set_to_motor()
            act.gear[0] = TORQUE_GEAR_NM[name.split("_", 1)[1]]
            act.ctrllimited = 1
            act.ctrlrange = [-1.0, 1.0]
    return spec


def load_model(dof: int, actuation: str = "velocity") -> mujoco.MjModel:
    """Compile Skinny's scene: ``dof`` 4 (2D) or 8 (3D), velocity servo or torque twin."""
    _check(dof, actuation)
    if actuation == "velocity":
        return mujoco.MjModel.from_xml_path(str(xml_path(dof)))
    return load_spec(dof, actuation).compile()


BATCH_PREFIX = "r{}/"  # names of copy r in :func:`load_batch_model`


def load_batch_model(dof: int, copies: int, actuation: str = "velocity") -> mujoco.MjModel:
    """``copies`` independent Skinnies (no scene) in one model, for stepping many runs
    with one ``mj_step``.

    Copy r's elements are named ``r{r}/<name>`` and laid out as contiguous blocks in
    copy order (bodies after the world body, joints, dofs, qpos, sites, actuators), so
    ``data.qpos.reshape(copies, -1)`` etc. are per-copy views. Skinny's geoms never
    collide and the copies share nothing, so each copy computes bit for bit what a
    one-robot model computes (``tests/test_plant.py`` checks it).
    """
    _check(dof, actuation)
    if copies < 1:
        raise SkinnyInputError(f"copies must be >= 1, got {copies}")
    parent = mujoco.MjSpec()
    one = load_spec(dof, actuation, scene=False)
    for name in dir(one.option):  # the robot's physics options, field by field
        if not name.startswith("_"):
            setattr(parent.option, name, getattr(one.option, name))
    parent.compiler.degree = one.compiler.degree
    parent.compiler.autolimits = one.compiler.autolimits
    for r in range(copies):
        parent.attach(load_spec(dof, actuation, scene=False), prefix=BATCH_PREFIX.format(r),
                      frame=parent.worldbody.add_frame())
    return parent.compile()
