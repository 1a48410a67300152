"""Skinny's bodies by name, and each one's arms as numbers: DOF names, joint axes and
ranges, segment lengths, and analytic kinematics. A body is its MJCF: the joints, axes,
ranges, segment lengths and actuators are read from it (:func:`skinny_mj.mjcf.read_arms`,
with MuJoCo's ``MjSpec``, on first use), never restated here. The kinematics is pure
NumPy; :func:`skinny_mj.plant.model.check_body` checks that MuJoCo's forward kinematics
agrees with it.

Frame: z up, Skinny faces -y, so his right arm hangs on the -x side and the frontal
plane is x-z. Every arm rotation is intrinsic (MuJoCo composes a body's hinges in
the order they are declared): R = R(a1, q1) R(a2, q2) ... with axes in the local frame.
The arm hangs straight down at q = 0. The left arm is the mirror image of the right
across x = 0: its axes are -M a with M = diag(-1, 1, 1), so equal joint angles give
mirror-image poses.

Skinny's bodies (:data:`BODIES`): ``2d`` (per arm: shoulder abduction theta, 0 = arm
down, pi = straight up, and elbow flexion in the same frontal plane), ``3d`` (shoulder
abduction, flexion about the abducted arm's x axis, rotation about the upper arm's long
axis, elbow flexion; flexion, the middle of the three shoulder hinges, stays well inside
+-90 deg, where the first and third axes would align), and their torque twins
``2d-torque`` and ``3d-torque`` (the same arms with motors, mass and gravity).
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from skinny_mj import plugins
from skinny_mj.errors import SkinnyEnvironmentError, SkinnyInputError
from skinny_mj.plant.kinematics import (  # noqa: F401  (the body's signals, named here too)
    SIDES,
    SIGNAL_SETS,
    SIGNALS,
    Kinematics,
    SignalSet,
    check_signals,
    signal_set,
)

if TYPE_CHECKING:
    from skinny_mj.mjcf import Arms

ACTUATIONS = ("velocity", "torque")
#: The control step, s (50 Hz: the thesis's 200 Hz capture, every 4th sample kept).
CONTROL_DT_S = 0.02
#: Largest sensor noise std (normalized units): 10x the signals' whole range [-1, 1] is
#: noise only; far larger finite values overflow to inf in the noise and the errors.
MAX_SENSOR_NOISE = 10.0
#: Entry-point group through which another package adds a body (a :class:`Body`).
BODY_GROUP = "skinny_mj.bodies"
#: The folder of Skinny's own MJCF instead of the installed one.
MODELS_ENV_VAR = "SKINNY_MJ_MODELS"


def models_dir() -> Path:
    """The folder holding Skinny's XML: ``$SKINNY_MJ_MODELS``, else the installed package
    data ``skinny_mj.models`` (the repo's top-level ``models/``, mapped in pyproject):
    ``<repo>/models/skinny`` in an editable install, inside site-packages otherwise."""
    return Path(os.environ.get(MODELS_ENV_VAR) or _installed_models())


@functools.cache
def _installed_models() -> str:
    try:
        return str(files("skinny_mj.models").joinpath("skinny"))
    except ModuleNotFoundError:  # an install from before the models were package data
        raise SkinnyEnvironmentError(f"skinny_mj.models is not installed: reinstall the "
                                     f"package (pip install -e .) or set {MODELS_ENV_VAR}"
                                     ) from None


@dataclass(frozen=True)
class Body(Kinematics):
    """A body Skinny-MJ trains on: a name and its MJCF, two mirrored arms.

    ``name``: what a user chooses it by (``--body``, ``plant.body``). ``robot``: the MJCF
    of the arms and their actuators (joints and actuators ``{side}_{joint}``, right arm
    first, each hinge moving ``{side}_upper_arm`` or ``{side}_forearm``; sites
    ``{side}_{shoulder,elbow,wrist}``); ``scene``: the robot with floor, light and camera
    ``front``; both in ``folder`` (None: Skinny's own, :func:`models_dir`). ``label``: how
    a message names it (default: the name). A velocity body's torque twin, the one
    ``actuation=torque`` trains instead, is the body named ``<name>-torque``
    (:func:`twin_name`).

    Everything else is read from the robot MJCF on first use (:attr:`arms`): the DOF
    names, ranges, signals and kinematics (:class:`skinny_mj.plant.kinematics.Kinematics`).
    """

    name: str
    robot: str
    scene: str
    folder: Path | None = None
    label: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or any(
                c.isspace() or c in ",=:" for c in self.name):
            raise SkinnyInputError(f"a body's name is a word such as '2d-long' (no spaces, "
                                   f"commas, '=' or ':'), got {self.name!r}")
        if not self.label:
            object.__setattr__(self, "label", self.name)

    # -- its MJCF --------------------------------------------------------------------
    def path(self, scene: bool = True) -> Path:
        """The scene's MJCF (``scene=False``: the robot's); a missing file is the
        installation's fault (or ``$SKINNY_MJ_MODELS``'), a :class:`SkinnyEnvironmentError`."""
        path = (self.folder or models_dir()) / (self.scene if scene else self.robot)
        if not path.is_file():
            raise SkinnyEnvironmentError(
                f"{path}: model file not found (set {MODELS_ENV_VAR} to the models/skinny "
                "folder)")
        return path

    @property
    def arms(self) -> Arms:
        """What the robot MJCF says about the arms (:class:`skinny_mj.mjcf.Arms`), read
        on first use (:meth:`read_arms` reads it again)."""
        read = self.__dict__.get("_read")  # (the models folder it was read from, arms)
        if read is not None and read[0] == self._models_env():
            return read[1]
        return self.read_arms()

    def read_arms(self) -> Arms:
        """Read the robot MJCF's :attr:`arms` (again: a file changed since)."""
        # here, not at the top: mujoco takes 0.6 s to import, and the movements and the
        # command line's help import this module without needing a body's arms
        from skinny_mj.mjcf import read_arms

        found = read_arms(self.path(scene=False))
        object.__setattr__(self, "_read", (self._models_env(), found))
        return found

    def _models_env(self) -> str | None:
        return os.environ.get(MODELS_ENV_VAR) if self.folder is None else None

    def twin(self, actuation: str) -> Body:
        """This body driven by ``actuation``: itself, or its twin (:func:`twin_name`)."""
        check_actuation(actuation)
        return self if self.actuation == actuation else body_of(twin_name(self.name,
                                                                           actuation))


#: A body where one is asked for: a :class:`Body`, its name, or Skinny's 2D and 3D by
#: their number of hinges (:data:`DOF_ALIASES`).
BodyLike = Body | str | int

#: The bodies, by name: Skinny's 2D and 3D and their torque twins, and any a
#: :func:`register_body` (or another package's entry point) added.
BODIES: dict[str, Body] = {b.name: b for b in (
    Body("2d", "skinny_2d.xml", "scene_2d.xml", label="2D"),
    Body("3d", "skinny_3d.xml", "scene_3d.xml", label="3D"),
    Body("2d-torque", "skinny_2d_torque.xml", "scene_2d_torque.xml", label="2D torque"),
    Body("3d-torque", "skinny_3d_torque.xml", "scene_3d_torque.xml", label="3D torque"),
)}
#: The numbers of hinges ``--dof`` and ``plant.dof`` take: Skinny's velocity bodies (with
#: ``actuation=torque``, their torque twins).
DOF_ALIASES = {4: "2d", 8: "3d"}


def register_body(new: Body) -> Body:
    """Add a body, chosen from then on by its name (``--body``, ``plant.body``). The same
    body again is a no-op; another body under a taken name is a :class:`SkinnyInputError`.

    In this process only: for the command line and a sweep's worker processes, register
    it through the entry-point group :data:`BODY_GROUP` instead (``docs/adding-a-body.md``).
    """
    if not isinstance(new, Body):
        raise SkinnyInputError(f"register_body takes a skinny_mj.plant.body.Body, got "
                               f"{type(new).__name__}")
    old = BODIES.get(new.name)
    if old is not None and old != new:
        raise SkinnyInputError(f"the body name {new.name!r} is taken ({old.robot})")
    BODIES[new.name] = new
    return new


def body_of(body: object) -> Body:
    """The :class:`Body` ``body`` names (a :data:`BodyLike`); anything else is a
    :class:`SkinnyInputError` naming the known bodies."""
    if isinstance(body, Body):
        return body
    found = _lookup(body)
    if found is None and isinstance(body, str):  # another package's (read once)
        _register_plugins()
        found = _lookup(body)
    if found is None:
        aliases = ", ".join(f"{n} = {b}" for n, b in DOF_ALIASES.items())
        raise SkinnyInputError(f"unknown body {body!r}; the bodies: {', '.join(BODIES)} "
                               f"(or a number of hinges: {aliases})")
    return found


def _lookup(body: object) -> Body | None:
    if isinstance(body, str):
        return BODIES.get(body)
    if isinstance(body, bool) or not isinstance(body, int | float | np.integer):
        return None
    name = next((n for d, n in DOF_ALIASES.items() if body == d), None)
    return None if name is None else BODIES.get(name)


def _register_plugins() -> None:
    for _, new in plugins.load_group(BODY_GROUP, Body, "skinny_mj.plant.body.Body"):
        register_body(new)


def body_names() -> tuple[str, ...]:
    """The registered bodies' names, another package's included."""
    _register_plugins()
    return tuple(BODIES)


#: A velocity body's torque twin is the body of its name with this after it.
TORQUE_SUFFIX = "-torque"


def twin_name(name: str, actuation: str) -> str:
    """The name of the twin of body ``name`` driven by ``actuation``: a velocity body's
    torque twin is the registered body ``<name>-torque``, a torque twin's velocity body
    the one without the suffix (the registry's names, the MJCF unread); none is a
    :class:`SkinnyInputError` saying how to add it."""
    check_actuation(actuation)
    names = body_names()
    found = f"{name}{TORQUE_SUFFIX}" if actuation == "torque" else name.removesuffix(
        TORQUE_SUFFIX)
    if found == name or found not in names:
        raise SkinnyInputError(
            f"the {name} body has no {actuation} twin registered (bodies: "
            f"{', '.join(names)}); a torque twin is the body {name}{TORQUE_SUFFIX}, its MJCF "
            "written by skinny_mj.plant.torque_files.write_torque_mjcf "
            "(docs/adding-a-body.md)")
    return found


def actuation_of(which: BodyLike) -> str:
    """The body's actuation: of a pair of twins (``X``, ``X-torque``), from their names,
    so that a configuration names a body without reading its MJCF (and importing MuJoCo);
    of any other body, from its MJCF."""
    skinny = body_of(which)
    if f"{skinny.name}{TORQUE_SUFFIX}" in BODIES:
        return "velocity"
    if skinny.name.endswith(TORQUE_SUFFIX) and skinny.name.removesuffix(TORQUE_SUFFIX) \
            in BODIES:
        return "torque"
    return skinny.actuation


def by_dof(dof: object, actuation: str = "velocity") -> str:
    """The name of Skinny's body with ``dof`` hinges (:data:`DOF_ALIASES`: 4 or 8, also as
    text) driven by ``actuation``: ``2d``, ``3d`` or their torque twins."""
    try:
        n = int(str(dof)) if not isinstance(dof, bool) else None
    except ValueError:
        n = None
    if n not in DOF_ALIASES or (not isinstance(dof, str) and dof != n):
        aliases = ", ".join(f"{d} ({b})" for d, b in DOF_ALIASES.items())
        raise SkinnyInputError(f"dof must be {aliases}, got {dof!r}; any other body by its "
                               f"name (bodies: {', '.join(body_names())})")
    name = DOF_ALIASES[n]
    return name if actuation == "velocity" else twin_name(name, actuation)


def body_name(body: object) -> str:
    """The name of the body ``body`` names (see :func:`body_of`)."""
    return body_of(body).name


def check_actuation(actuation: object) -> str:
    """``actuation`` if it is "velocity" or "torque", else a :class:`SkinnyInputError`."""
    if actuation not in ACTUATIONS:
        raise SkinnyInputError(f"actuation must be one of {ACTUATIONS}, got {actuation!r}")
    return str(actuation)


