"""Acclaim ASF (skeleton) / AMC (motion) reader and forward kinematics, any CMU subject.

Why not ``dm_control.suite.utils.parse_amc``: it reads AMC values into the fixed joint
order of dm_control's CMU humanoid (``_CMU_MOCAP_JOINT_ORDER``), never reads the ASF
(so bone lengths, axes and hierarchy of other skeletons are lost), and has no error
reporting (a malformed file gives an IndexError). Here the ASF is read in full and
every malformed line raises :class:`SkinnyInputError` with file and line.

Conventions (``/work/shared/mocap/README.md``): a bone's local rotation is
C M C^-1, with C from the bone's ``axis`` line (angles applied in the stated order,
e.g. XYZ -> Rz Ry Rx) and M the AMC rotation (dofs applied in the listed order,
rx ry rz -> Rz Ry Rx); the world rotation chains from the root: L = L_parent C M C^-1;
a bone starts where its parent ends and ends at start + L (direction * length).
Lengths are converted to metres: 1 unit = 0.0254 / ``:units length`` m (CMU: 0.0564 m).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.trajectories.mocap_common import (
    ArmBones,
    euler_matrices,
    find_arm_bones,
    read_lines,
    to_floats,
)
from skinny_mj.trajectories.retarget import ArmClip

CMU_FPS = 120.0
_ROT = {"rx": "x", "ry": "y", "rz": "z"}
_TRANS = {"tx": 0, "ty": 1, "tz": 2}


@dataclass
class Bone:
    """One ASF bone: rest direction (3,) unit, length (m), axis matrix C (3, 3), dofs."""

    name: str
    direction: np.ndarray = field(default_factory=lambda: np.zeros(3))
    length_m: float = 0.0
    axis: np.ndarray = field(default_factory=lambda: np.eye(3))
    dofs: tuple[str, ...] = ()
    line: int = 0
    parent: str | None = None


@dataclass
class Skeleton:
    """An ASF skeleton: bones by name (root included, with its order/axis), hierarchy."""

    path: Path
    bones: dict[str, Bone]
    children: dict[str, list[str]]
    angle_scale: float  # radians per file angle unit
    root_position_m: np.ndarray
    length_scale_m: float  # metres per file length unit


def _axis_matrix(angles: np.ndarray, order: str) -> np.ndarray:
    return euler_matrices(angles[None, :], order.lower())[0]


def _axis_order(text: str, path: Path, line: int) -> str:
    """An axis line's rotation order: three of X, Y, Z (e.g. ``XYZ``)."""
    if len(text) != 3 or any(c not in "xyz" for c in text.lower()):
        raise SkinnyInputError(f"axis order must be three of X, Y, Z, got {text!r}",
                               path=path, line=line)
    return text


def parse_asf(path: str | Path) -> Skeleton:
    """Read an ASF skeleton. Raises SkinnyInputError (file, line) on malformed input."""
    path = Path(path)
    lines = read_lines(path)
    section, length_unit, angle_scale = "", 1.0, np.pi / 180.0
    bones: dict[str, Bone] = {"root": Bone("root", line=0)}
    root_pos = np.zeros(3)
    root_orient, root_order = np.zeros(3), "XYZ"
    children: dict[str, list[str]] = {}
    cur: Bone | None = None
    for no, line in lines:
        tok = line.split()
        if tok[0].startswith(":"):
            section = tok[0][1:].lower()
            continue
        key = tok[0].lower()
        if section == "units":
            if key == "length" and len(tok) > 1:
                length_unit = to_floats(tok[1:2], path, no)[0]
                if length_unit <= 0:
                    raise SkinnyInputError("units length must be > 0", path=path, line=no)
            elif key == "angle" and len(tok) > 1:
                angle_scale = 1.0 if tok[1].lower().startswith("rad") else np.pi / 180.0
        elif section == "root":
            if key == "order":
                bones["root"].dofs = tuple(t.lower() for t in tok[1:])
                bad = [d for d in bones["root"].dofs if d not in _ROT and d not in _TRANS]
                if bad:
                    raise SkinnyInputError(f"unknown root channel(s) {bad}", path=path, line=no)
            elif key == "axis" and len(tok) > 1:
                root_order = _axis_order(tok[1], path, no)
            elif key == "position":
                root_pos = np.array(to_floats(tok[1:4], path, no, count=3))
            elif key == "orientation":
                root_orient = np.array(to_floats(tok[1:4], path, no, count=3))
        elif section == "bonedata":
            if key == "begin":
                cur = Bone("", line=no)
            elif cur is None:
                raise SkinnyInputError(f"{tok[0]!r} outside begin/end", path=path, line=no)
            elif key == "end":
                if not cur.name:
                    raise SkinnyInputError("bone without a name", path=path, line=cur.line)
                bones[cur.name] = cur
                cur = None
            elif key == "name":
                cur.name = tok[1] if len(tok) > 1 else ""
            elif key == "direction":
                d = np.array(to_floats(tok[1:4], path, no, count=3))
                cur.direction = d / max(np.linalg.norm(d), 1e-12)
            elif key == "length":
                cur.length_m = to_floats(tok[1:2], path, no, count=1)[0]
            elif key == "axis":
                vals = to_floats(tok[1:4], path, no, count=3)
                order = _axis_order(tok[4] if len(tok) > 4 else "XYZ", path, no)
                cur.axis = _axis_matrix(np.array(vals) * angle_scale, order)
            elif key == "dof":
                cur.dofs = tuple(t.lower() for t in tok[1:])
                bad = [d for d in cur.dofs if d not in _ROT and d not in _TRANS and d != "l"]
                if bad:
                    raise SkinnyInputError(f"unknown dof(s) {bad}", path=path, line=no)
        elif section == "hierarchy":
            if key in ("begin", "end"):
                continue
            if tok[0] not in bones:
                raise SkinnyInputError(
                    f"hierarchy names unknown bone {tok[0]!r}", path=path, line=no
                )
            for child in tok[1:]:
                if child not in bones:
                    raise SkinnyInputError(
                        f"hierarchy names unknown bone {child!r}", path=path, line=no
                    )
                if bones[child].parent is not None:
                    raise SkinnyInputError(f"bone {child!r} has two parents", path=path, line=no)
                bones[child].parent = tok[0]
                children.setdefault(tok[0], []).append(child)
    if cur is not None:
        raise SkinnyInputError("bone data ends inside begin/end", path=path, line=cur.line)
    if len(bones) < 2 or not children:
        raise SkinnyInputError("no bones or no :hierarchy section", path=path)
    scale_m = 0.0254 / length_unit
    for b in bones.values():
        b.length_m *= scale_m
    bones["root"].axis = _axis_matrix(root_orient * angle_scale, root_order)
    return Skeleton(path, bones, children, angle_scale, root_pos * scale_m, scale_m)


def parse_amc(path: str | Path, skeleton: Skeleton) -> dict[str, np.ndarray]:
    """Read AMC frames: {bone: (T, n_dof) values in file units}. Checks every frame has
    every bone with the right number of numbers; errors name the file and line."""
    path = Path(path)
    lines = read_lines(path)
    frames: list[dict[str, list[float]]] = []
    frame_lines: list[int] = []
    frame_numbers: list[int] = []
    for no, line in lines:
        tok = line.split()
        if tok[0].startswith(":"):
            continue
        if len(tok) == 1 and tok[0].isdecimal():
            if frame_numbers and int(tok[0]) != frame_numbers[-1] + 1:
                raise SkinnyInputError(
                    f"frame {int(tok[0])} follows frame {frame_numbers[-1]}: frames must be "
                    "numbered one after another (one missing, or out of order?)",
                    path=path, line=no)
            frame_numbers.append(int(tok[0]))
            frames.append({})
            frame_lines.append(no)
            continue
        if not frames:
            raise SkinnyInputError(
                f"data before the first frame number: {tok[0]!r}", path=path, line=no
            )
        bone = skeleton.bones.get(tok[0])
        if bone is None:
            raise SkinnyInputError(
                f"unknown bone {tok[0]!r} (not in {skeleton.path.name})", path=path, line=no
            )
        n = len(bone.dofs)
        if len(tok) - 1 != n:
            raise SkinnyInputError(
                f"bone {tok[0]!r} has {len(tok) - 1} values, the skeleton gives it {n}",
                path=path,
                line=no,
            )
        if tok[0] in frames[-1]:
            raise SkinnyInputError(f"bone {tok[0]!r} twice in one frame", path=path, line=no)
        frames[-1][tok[0]] = to_floats(tok[1:], path, no)
    if not frames:
        raise SkinnyInputError("no frames", path=path)
    expected = set().union(*frames)
    if not expected:
        raise SkinnyInputError("frames hold no bone values", path=path, line=frame_lines[0])
    for frame, no in zip(frames, frame_lines, strict=True):
        if set(frame) != expected:
            missing = sorted(expected - set(frame))
            raise SkinnyInputError(
                f"frame is truncated, missing {', '.join(missing)}", path=path, line=no
            )
    return {b: np.array([f[b] for f in frames]) for b in sorted(expected)}


def _local_rotation(
    bone: Bone, values: np.ndarray | None, angle_scale: float, t: int
) -> np.ndarray:
    rot_dofs = [i for i, d in enumerate(bone.dofs) if d in _ROT]
    if values is None or not rot_dofs:
        return np.broadcast_to(np.eye(3), (t, 3, 3))
    order = "".join(_ROT[bone.dofs[i]] for i in rot_dofs)
    m = euler_matrices(values[:, rot_dofs] * angle_scale, order)
    return bone.axis @ m @ bone.axis.T


def forward_kinematics(
    skeleton: Skeleton, motion: dict[str, np.ndarray], wanted: set[str] | None = None
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """World start and end points, {bone: ((T, 3), (T, 3))} in metres (root: both = root
    position). ``wanted`` limits the work to these bones and their ancestors."""
    bones = skeleton.bones
    t = len(next(iter(motion.values())))
    needed = None
    if wanted is not None:
        needed = set()
        for name in wanted:
            while name is not None and name not in needed:
                needed.add(name)
                name = bones[name].parent
    root = bones["root"]
    rv = motion.get("root")
    pos = np.broadcast_to(skeleton.root_position_m, (t, 3)).copy()
    if rv is not None:
        for i, d in enumerate(root.dofs):
            if d in _TRANS:
                pos[:, _TRANS[d]] = rv[:, i] * skeleton.length_scale_m
    rot = {"root": _local_rotation(root, rv, skeleton.angle_scale, t)}
    out = {"root": (pos, pos)}
    stack = list(skeleton.children.get("root", []))
    while stack:
        name = stack.pop()
        if needed is not None and name not in needed:
            continue
        bone = bones[name]
        parent = bone.parent or "root"
        local = _local_rotation(bone, motion.get(name), skeleton.angle_scale, t)
        rot[name] = rot[parent] @ local
        start = out[parent][1]
        end = start + bone.length_m * (rot[name] @ bone.direction)
        out[name] = (start, end)
        stack.extend(skeleton.children.get(name, []))
    return out


def load_asf_amc(asf: str | Path, amc: str | Path, *, fps: float | None = None) -> ArmClip:
    """Read an ASF skeleton and AMC motion and return both arms' joint positions.

    Shoulder = start of the upper-arm bone (e.g. ``rhumerus``), elbow = its end (start of
    ``rradius``), wrist = end of the forearm bone. ``fps`` defaults to CMU's 120 Hz.
    """
    skeleton = parse_asf(asf)
    arms: ArmBones = find_arm_bones(list(skeleton.bones), skeleton.path, need_hand=False)
    motion = parse_amc(amc, skeleton)
    wanted = set(arms.upper) | set(arms.forearm)
    fk = forward_kinematics(skeleton, motion, wanted)
    shoulder = np.stack([fk[b][0] for b in arms.upper], axis=1)
    elbow = np.stack([fk[b][1] for b in arms.upper], axis=1)
    wrist = np.stack([fk[b][1] for b in arms.forearm], axis=1)
    return ArmClip(shoulder, elbow, wrist, fk["root"][0], float(fps or CMU_FPS), str(amc))
