"""BVH (Biovision hierarchy) reader and forward kinematics.

HIERARCHY: nested ``ROOT``/``JOINT``/``End Site`` blocks with ``OFFSET x y z`` and
``CHANNELS n name...``; MOTION: ``Frames: N``, ``Frame Time: dt``, then N lines of all
channel values in hierarchy order. Rotations are in degrees and compose in the listed
channel order (``Zrotation Xrotation Yrotation`` -> R = Rz @ Rx @ Ry); a joint's world
transform is parent @ translate(offset [+ position channels]) @ R, and its position is
that transform's origin. Malformed files raise SkinnyInputError with file and line.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.trajectories.mocap_common import (
    euler_matrices,
    find_arm_bones,
    read_lines,
    to_floats,
)
from skinny_mj.trajectories.retarget import ArmClip

_CHANNELS = {
    "xposition": ("p", 0), "yposition": ("p", 1), "zposition": ("p", 2),
    "xrotation": ("r", "x"), "yrotation": ("r", "y"), "zrotation": ("r", "z"),
}  # fmt: skip


@dataclass
class Joint:
    name: str
    parent: int | None
    offset: np.ndarray = field(default_factory=lambda: np.zeros(3))
    channels: tuple[str, ...] = ()
    first_channel: int = 0
    line: int = 0


@dataclass
class BvhMotion:
    """A parsed BVH: joints in hierarchy order (end sites named ``<parent>_end``),
    ``values`` (T, n_channels) as in the file, ``frame_time_s``."""

    path: Path
    joints: list[Joint]
    values: np.ndarray
    frame_time_s: float


def parse_bvh(path: str | Path) -> BvhMotion:
    """Read a BVH file; SkinnyInputError (file, line) on any malformed part."""
    path = Path(path)
    lines = read_lines(path)
    joints: list[Joint] = []
    stack: list[int] = []
    pending: Joint | None = None
    n_channels = 0
    i = 0
    if lines[0][1].split()[0].upper() != "HIERARCHY":
        raise SkinnyInputError("a BVH file starts with HIERARCHY", path=path, line=lines[0][0])
    i = 1
    while i < len(lines):
        no, line = lines[i]
        tok = line.split()
        key = tok[0].upper()
        if key in ("ROOT", "JOINT"):
            if (key == "ROOT") != (not stack) or len(tok) < 2:
                raise SkinnyInputError(f"misplaced {tok[0]}", path=path, line=no)
            pending = Joint(" ".join(tok[1:]), stack[-1] if stack else None, line=no)
        elif key == "END":
            if not stack:
                raise SkinnyInputError("End Site outside a joint", path=path, line=no)
            pending = Joint(joints[stack[-1]].name + "_end", stack[-1], line=no)
        elif key == "{":
            if pending is None:
                raise SkinnyInputError("'{' without a joint", path=path, line=no)
            joints.append(pending)
            stack.append(len(joints) - 1)
            pending = None
        elif key == "}":
            if not stack:
                raise SkinnyInputError("unmatched '}'", path=path, line=no)
            stack.pop()
        elif key == "OFFSET":
            if not stack:
                raise SkinnyInputError("OFFSET outside a joint", path=path, line=no)
            joints[stack[-1]].offset = np.array(to_floats(tok[1:], path, no, count=3))
        elif key == "CHANNELS":
            if not stack or len(tok) < 2:
                raise SkinnyInputError(
                    "CHANNELS outside a joint or without a count", path=path, line=no
                )
            try:
                count = int(tok[1])
            except ValueError:
                raise SkinnyInputError(
                    f"channel count is not an integer: {tok[1]!r}", path=path, line=no
                ) from None
            names = tuple(t.lower() for t in tok[2:])
            if count != len(names):
                raise SkinnyInputError(
                    f"CHANNELS says {count} but names {len(names)} channels", path=path, line=no
                )
            bad = [n for n in names if n not in _CHANNELS]
            if bad:
                raise SkinnyInputError(f"unknown channel(s) {bad}", path=path, line=no)
            joint = joints[stack[-1]]
            joint.channels, joint.first_channel = names, n_channels
            n_channels += count
        elif key == "MOTION":
            break
        else:
            raise SkinnyInputError(f"unexpected {tok[0]!r} in HIERARCHY", path=path, line=no)
        i += 1
    if stack or not joints or i >= len(lines):
        raise SkinnyInputError("HIERARCHY is unbalanced or there is no MOTION section", path=path)
    frames, frame_time = None, None
    i += 1
    while i < len(lines) and (frames is None or frame_time is None):
        no, line = lines[i]
        head, _, rest = line.partition(":")
        if head.strip().lower() == "frames":
            frames = to_floats(rest.split(), path, no, count=1)[0]
            if frames < 1 or frames != int(frames):
                raise SkinnyInputError(f"bad frame count {rest.strip()!r}", path=path, line=no)
        elif head.strip().lower() == "frame time":
            frame_time = to_floats(rest.split(), path, no, count=1)[0]
            if frame_time <= 0:
                raise SkinnyInputError("Frame Time must be > 0", path=path, line=no)
        else:
            raise SkinnyInputError("expected 'Frames:' and 'Frame Time:'", path=path, line=no)
        i += 1
    data = lines[i:]
    if frames is None or frame_time is None:
        missing = "Frames:" if frames is None else "Frame Time:"
        raise SkinnyInputError(f"MOTION has no {missing!r} line", path=path)
    if len(data) != int(frames):
        raise SkinnyInputError(f"MOTION says {int(frames)} frames, the file has {len(data)}",
                               path=path)
    values = np.empty((len(data), n_channels))
    for row, (no, line) in enumerate(data):
        values[row] = to_floats(line.split(), path, no, count=n_channels)
    return BvhMotion(path, joints, values, frame_time)


def joint_positions(motion: BvhMotion) -> dict[str, np.ndarray]:
    """World positions {joint name: (T, 3)} in file units, end sites included."""
    t = motion.values.shape[0]
    rots: list[np.ndarray] = []
    out: dict[str, np.ndarray] = {}
    positions: list[np.ndarray] = []
    for joint in motion.joints:
        local_t = np.broadcast_to(joint.offset, (t, 3)).copy()
        rot_axes, rot_cols = "", []
        for k, ch in enumerate(joint.channels):
            kind, which = _CHANNELS[ch]
            col = joint.first_channel + k
            if kind == "p":
                local_t[:, which] = motion.values[:, col]  # position channels replace the offset
            else:
                rot_axes += which
                rot_cols.append(col)
        # listed order R = R_c0 @ R_c1 @ ...: euler_matrices applies its first axis first
        local_r = np.broadcast_to(np.eye(3), (t, 3, 3))
        if rot_cols:
            local_r = euler_matrices(np.deg2rad(motion.values[:, rot_cols[::-1]]), rot_axes[::-1])
        if joint.parent is None:
            pos, rot = local_t, local_r
        else:
            p_rot, p_pos = rots[joint.parent], positions[joint.parent]
            pos = p_pos + np.einsum("tij,tj->ti", p_rot, local_t)
            rot = p_rot @ local_r
        rots.append(rot)
        positions.append(pos)
        out.setdefault(joint.name, pos)
    return out


def load_bvh(path: str | Path, *, fps: float | None = None) -> ArmClip:
    """Read a BVH and return both arms' joint positions: shoulder = upper-arm joint
    (``RightArm``, ``rShldr``...), elbow = forearm joint, wrist = hand joint (or the
    forearm's end site). ``fps`` defaults to 1 / Frame Time."""
    motion = parse_bvh(path)
    names = [j.name for j in motion.joints if not j.name.endswith("_end")]
    arms = find_arm_bones(names, motion.path, need_hand=False)
    pos = joint_positions(motion)
    if arms.hand is not None:
        wrists = arms.hand
    else:
        wrists = tuple(f"{b}_end" for b in arms.forearm)
        if any(w not in pos for w in wrists):
            raise SkinnyInputError("no hand joint or forearm end site for the wrist", path=path)
    shoulder = np.stack([pos[b] for b in arms.upper], axis=1)
    elbow = np.stack([pos[b] for b in arms.forearm], axis=1)
    wrist = np.stack([pos[b] for b in wrists], axis=1)
    root = pos[motion.joints[0].name]
    return ArmClip(shoulder, elbow, wrist, root, float(fps or 1.0 / motion.frame_time_s), str(path))
