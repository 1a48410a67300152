"""Reading a body's MJCF with errors a user can act on: a malformed or edited file is a
:class:`~skinny_mj.errors.SkinnyInputError` naming the file and line, in one line; and
what a body's MJCF says about its two arms (:func:`read_arms`), the one description of
them that :class:`skinny_mj.plant.body.Body` and everything after it read.

MuJoCo reports an error inside an ``<include>``d file at the including element
("Element 'include', line 3", or line 0), without the file's name. On a failure, the
files are read again one by one, the includes first: the first one that fails on its
own (as XML, or as MJCF) is the one named.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from skinny_mj.errors import SkinnyInputError

_LINE = re.compile(r"line(?: number)?[ =](\d+)", re.IGNORECASE)


def read_model(path: Path) -> mujoco.MjModel:
    """``mujoco.MjModel.from_xml_path(path)``; a bad file is a :class:`SkinnyInputError`."""
    return _guarded(path, lambda: mujoco.MjModel.from_xml_path(str(path)))


def read_spec(path: Path) -> mujoco.MjSpec:
    """``mujoco.MjSpec.from_file(path)``; a bad file is a :class:`SkinnyInputError`."""
    return _guarded(path, lambda: mujoco.MjSpec.from_file(str(path)))


def compile_spec(spec: mujoco.MjSpec, path: Path) -> mujoco.MjModel:
    """``spec.compile()`` for a spec read from ``path``; an error is a
    :class:`SkinnyInputError` naming the file it comes from."""
    return _guarded(path, spec.compile)


def _guarded(path: Path, read: Callable):
    try:
        return read()
    except ValueError as err:
        raise mjcf_error(Path(path), err) from None


def mjcf_error(path: Path, err: BaseException) -> SkinnyInputError:
    """The one-line error for MuJoCo's ``err`` on reading ``path``: the innermost file
    that fails on its own, with its line where one is known."""
    files, parents = _files(path)
    for f in files:  # well-formed XML first: ElementTree knows the line of any file
        try:
            ET.parse(f)
        except ET.ParseError as bad:
            line, column = bad.position if bad.position else (None, None)
            what = re.sub(r":? line \d+, column \d+$", "", _squash(bad))
            if not f.read_bytes().strip():
                return SkinnyInputError("empty file, not an MJCF", path=f)
            return SkinnyInputError(f"not well-formed XML: {what} (column {column})",
                                    path=f, line=line)
        except OSError as bad:
            by = f" (included by {parents[f].name})" if f in parents else ""
            return SkinnyInputError(f"cannot read the file: {bad.strerror}{by}", path=f)
    for f in reversed(files[1:]):  # an included file that fails alone
        try:
            mujoco.MjSpec.from_file(str(f)).compile()
        except ValueError as alone:
            line = _line(alone)
            if line:
                return SkinnyInputError(f"MJCF error: {_text(alone)}", path=f, line=line)
    return SkinnyInputError(f"MJCF error: {_text(err)}", path=path, line=_line(err))


def _files(path: Path) -> tuple[list[Path], dict[Path, Path]]:
    """``path`` and the files it includes (MuJoCo resolves an include against the
    main file's folder), outermost first, and each included file's includer; what
    cannot be parsed is left unexpanded."""
    out, todo, parents = [], [Path(path)], {}
    while todo:
        f = todo.pop(0)
        if f in out:
            continue
        out.append(f)
        try:
            root = ET.parse(f).getroot()
        except (ET.ParseError, OSError):
            continue
        for inc in root.iter("include"):
            if inc.get("file"):
                child = Path(path).parent / inc.get("file")
                parents.setdefault(child, f)
                todo.append(child)
    return out, parents


def _line(err: BaseException) -> int | None:
    found = [int(n) for n in _LINE.findall(str(err))]
    return next((n for n in found if n > 0), None)


def _text(err: BaseException) -> str:
    """MuJoCo's message without its prefixes and the element's position."""
    lines = [ln.strip() for ln in str(err).splitlines() if ln.strip()]
    kept = [ln for ln in lines if not ln.startswith("Element ")]
    element = next((ln for ln in lines if ln.startswith("Element ")), "")
    text = " ".join(kept) or str(err)
    text = re.sub(r"^(XML Error: |Error: )", "", text)
    name = re.search(r"Element (name '[^']*'|'[^']*')", element)
    return _squash(text) + (f" (element {name.group(1)})" if name else "")


def _squash(err: object) -> str:
    return " ".join(str(err).split())


# -- a body's arms, as its MJCF states them ---------------------------------------------
SIDES = ("right", "left")
SEGMENTS = ("upper_arm", "forearm")
POINTS = ("shoulder", "elbow", "wrist")
#: What the actuators of a body are, by MuJoCo's shortcut: ``<velocity>`` servos (an
#: affine bias -kv qvel) make a velocity body, ``<motor>``\\s (no bias) a torque body.
ACTUATION_OF = {"velocity": "velocity", "motor": "torque"}


@dataclass(frozen=True)
class Arms:
    """What a body's MJCF says about its two arms, in the terms of Skinny's analytic
    kinematics (:class:`skinny_mj.plant.body.Body`).

    joints: the right arm's hinges from the shoulder out, without the ``right_`` prefix
    (the left arm's carry the same names after ``left_``). segments: the segment each
    moves ("upper_arm", "forearm"). axes_right: each hinge's local axis on the right arm
    (the left arm is its mirror image; :func:`skinny_mj.plant.model.check_body` checks
    it). ranges_rad: every hinge's range, right arm first, then left. lengths_m: shoulder
    to elbow and elbow to wrist, m (each segment hangs straight down at rest).
    shoulders_m: the right and left shoulder sites at rest, world frame, m. actuation:
    "velocity" or "torque". gears: each actuator's gear, in the hinges' order (a motor's
    peak torque in N m: its ctrl is in [-1, 1]).
    """

    joints: tuple[str, ...]
    segments: tuple[str, ...]
    axes_right: tuple[tuple[float, float, float], ...]
    ranges_rad: tuple[tuple[float, float], ...]
    lengths_m: tuple[float, float]
    shoulders_m: tuple[tuple[float, float, float], tuple[float, float, float]]
    actuation: str
    gears: tuple[float, ...]


def read_arms(path: Path) -> Arms:
    """The :class:`Arms` of the robot MJCF at ``path``, read with :class:`mujoco.MjSpec`
    and compiled; what cannot be read as two mirrored arms of named hinges, each with its
    actuator, and the sites ``{side}_{shoulder,elbow,wrist}`` is a
    :class:`SkinnyInputError` naming the file and what is wrong."""
    path = Path(path)
    model = compile_spec(read_spec(path), path)

    def refuse(message: str) -> SkinnyInputError:
        return SkinnyInputError(f"not a body of two arms: {message}", path=path)

    names = [model.joint(i).name for i in range(model.njnt)]
    if bad := [n for n, t in zip(names, model.jnt_type, strict=True)
               if t != mujoco.mjtJoint.mjJNT_HINGE or not n.startswith(("right_", "left_"))]:
        raise refuse(f"joint {bad[0]!r} is not an arm's hinge (right_... or left_...)")
    joints = tuple(n.removeprefix("right_") for n in names if n.startswith("right_"))
    dof_names = [f"{side}_{j}" for side in SIDES for j in joints]
    if names != dof_names:
        raise refuse(f"the hinges {names} are not the right arm's, then the same for the "
                     f"left arm ({dof_names})")
    if not joints:
        raise refuse("no hinges")
    segments = tuple(model.body(model.jnt_bodyid[names.index(f"right_{j}")]).name
                     .removeprefix("right_") for j in joints)
    for side in SIDES:
        where = [model.body(model.jnt_bodyid[names.index(f"{side}_{j}")]).name
                 for j in joints]
        if where != [f"{side}_{s}" for s in segments] or set(segments) - set(SEGMENTS) \
                or list(segments) != sorted(segments, key=SEGMENTS.index) \
                or "forearm" not in segments:
            raise refuse(f"the {side} arm's hinges move {where}: each moves "
                         f"{side}_upper_arm or {side}_forearm, the upper arm's first, "
                         "at least one the forearm")
    if not np.all(model.jnt_limited):
        raise refuse(f"hinge {names[int(np.argmin(model.jnt_limited))]!r} has no range")
    actuators = [model.actuator(i).name for i in range(model.nu)]
    targets = [names[j] if t == mujoco.mjtTrn.mjTRN_JOINT else None
               for t, j in zip(model.actuator_trntype, model.actuator_trnid[:, 0], strict=True)]
    if actuators != dof_names or targets != dof_names:
        raise refuse(f"the actuators {actuators} are not one per hinge, named and ordered "
                     f"as the hinges ({dof_names})")
    kinds = {_actuator_kind(model, i) for i in range(model.nu)}
    if len(kinds) != 1 or next(iter(kinds)) not in ACTUATION_OF:
        raise refuse(f"the actuators are {sorted(kinds)}: a body's are all <velocity> "
                     "servos or all <motor>s")
    sites = {f"{s}_{p}": mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"{s}_{p}")
             for s in SIDES for p in POINTS}
    if missing := [n for n, i in sites.items() if i < 0]:
        raise refuse(f"no site {missing[0]!r}")
    lengths = tuple(_hanging_length(model, sites[f"right_{a}"], sites[f"right_{b}"], refuse)
                    for a, b in zip(POINTS[:-1], POINTS[1:], strict=True))
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)  # at rest (qpos0)
    shoulders = tuple(tuple(float(x) for x in data.site_xpos[sites[f"{s}_shoulder"]])
                      for s in SIDES)
    axes = tuple(tuple(float(x) for x in model.jnt_axis[names.index(f"right_{j}")])
                 for j in joints)
    return Arms(joints, segments, axes,  # type: ignore[arg-type]
                tuple((float(lo), float(hi)) for lo, hi in model.jnt_range),
                lengths, shoulders,  # type: ignore[arg-type]
                ACTUATION_OF[next(iter(kinds))],
                tuple(float(g) for g in model.actuator_gear[:, 0]))


def _actuator_kind(model: mujoco.MjModel, i: int) -> str:
    """"velocity" (MuJoCo's ``<velocity>``: gain kv, bias -kv qvel), "motor" (gain 1
    scaled by the gear, no bias) or "other"."""
    gain, bias = model.actuator_gainprm[i], model.actuator_biasprm[i]
    plain = model.actuator_dyntype[i] == mujoco.mjtDyn.mjDYN_NONE and \
        model.actuator_gaintype[i] == mujoco.mjtGain.mjGAIN_FIXED
    if plain and model.actuator_biastype[i] == mujoco.mjtBias.mjBIAS_NONE:
        return "motor"
    if plain and model.actuator_biastype[i] == mujoco.mjtBias.mjBIAS_AFFINE and \
            bias[0] == 0 and bias[1] == 0 and bias[2] == -gain[0] != 0:
        return "velocity"
    return "other"


def _hanging_length(model: mujoco.MjModel, site_a: int, site_b: int,
                    refuse: Callable[[str], Exception]) -> float:
    """The distance, m, from site ``a`` to site ``b`` further down the same arm at rest,
    from the MJCF's own numbers (each body's position in its parent, unrotated, and the
    sites' in their bodies): the segment must hang straight down (-z)."""
    body_a, body = int(model.site_bodyid[site_a]), int(model.site_bodyid[site_b])
    offset = model.site_pos[site_b].copy()
    while body != body_a:
        if body == 0:
            raise refuse(f"site {model.site(site_b).name!r} is not below "
                         f"{model.site(site_a).name!r} on the arm")
        if not np.array_equal(model.body_quat[body], [1.0, 0.0, 0.0, 0.0]):
            raise refuse(f"body {model.body(body).name!r} is rotated in its parent: the "
                         "arm's frames are aligned at rest")
        offset = model.body_pos[body] + offset
        body = int(model.body_parentid[body])
    offset = offset - model.site_pos[site_a]
    if offset[0] != 0 or offset[1] != 0 or not offset[2] < 0:
        raise refuse(f"{model.site(site_b).name!r} is not straight below "
                     f"{model.site(site_a).name!r} at rest: the arm hangs down (-z) at "
                     "all joint angles 0")
    return float(-offset[2])
