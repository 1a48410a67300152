"""Shared pieces of the ASF/AMC and BVH readers: line reading with line numbers,
strict number parsing, Euler rotation matrices, and finding the arm bones by name."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from skinny_mj.errors import SkinnyInputError


def read_lines(path: Path) -> list[tuple[int, str]]:
    """Non-empty, non-comment lines as (1-based line number, stripped text); CRLF ok."""
    if path.is_dir():
        raise SkinnyInputError("a folder, not a file", path=path)
    if not path.is_file():
        raise SkinnyInputError("no such file", path=path)
    try:
        text = path.read_text(encoding="utf-8", errors="strict")
    except UnicodeDecodeError:
        text = path.read_text(encoding="latin-1")
    except OSError as exc:
        raise SkinnyInputError(f"cannot read ({exc})", path=path) from None
    out = []
    for no, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if line and not line.startswith("#"):
            out.append((no, line))
    if not out:
        raise SkinnyInputError("file is empty", path=path)
    return out


def to_floats(tokens: list[str], path: Path, line: int, count: int | None = None) -> list[float]:
    """Parse tokens as finite floats; SkinnyInputError (file, line) otherwise."""
    if count is not None and len(tokens) != count:
        raise SkinnyInputError(f"expected {count} numbers, got {len(tokens)}", path=path, line=line)
    out = []
    for tok in tokens:
        try:
            v = float(tok)
        except ValueError:
            raise SkinnyInputError(f"not a number: {tok!r}", path=path, line=line) from None
        if not math.isfinite(v):
            raise SkinnyInputError(f"non-finite number {tok!r}", path=path, line=line)
        out.append(v)
    return out


def _rot(axis: str, angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    one, zero = np.ones_like(angle), np.zeros_like(angle)
    rows = {
        "x": [[one, zero, zero], [zero, c, -s], [zero, s, c]],
        "y": [[c, zero, s], [zero, one, zero], [-s, zero, c]],
        "z": [[c, -s, zero], [s, c, zero], [zero, zero, one]],
    }[axis]
    return np.moveaxis(np.array(rows), (0, 1), (-2, -1))


def euler_matrices(angles: np.ndarray, order: str) -> np.ndarray:
    """Rotations (T, 3, 3) applying ``angles[:, i]`` (rad) about axis ``order[i]`` in turn
    (fixed axes): order "xyz" gives Rz @ Ry @ Rx."""
    angles = np.atleast_2d(angles)
    out = np.broadcast_to(np.eye(3), (angles.shape[0], 3, 3))
    for i, axis in enumerate(order.lower()):
        out = _rot(axis, angles[:, i]) @ out
    return out


@dataclass(frozen=True)
class ArmBones:
    """Bone / joint names per arm, ordered (right, left)."""

    upper: tuple[str, str]
    forearm: tuple[str, str]
    hand: tuple[str, str] | None


# Upper arm, forearm, hand spellings seen in CMU ASF (humerus, radius, wrist/hand),
# MotionBuilder/CMU BVH (Shldr, ForeArm, Hand), Mixamo / Biovision (Arm, ForeArm, Hand),
# and others (UpArm/LowArm, UpperArm/LowerArm).
_PARTS = {
    "upper": ("humerus", "upperarm", "uparm", "shldr", "arm"),
    "forearm": ("radius", "forearm", "lowerarm", "lowarm", "ulna", "elbow"),
    "hand": ("wrist", "hand"),
}


def classify_arm_bone(name: str) -> tuple[str, str] | None:
    """("right"|"left", "upper"|"forearm"|"hand") for an arm bone name, else None."""
    n = name.rsplit(":", 1)[-1]  # Mixamo namespaces: "mixamorig:LeftArm"
    low = re.sub(r"[^a-z]", "", n.lower())
    side = None
    for word, s in (("left", "left"), ("right", "right")):
        if low.startswith(word) or low.endswith(word):
            side, low = s, low.removeprefix(word).removesuffix(word)
            break
    if side is None:
        m = re.fullmatch(
            r"(?:([lr])[_.]?)?([a-z]+?)(?:[_.]([lr]))?", re.sub(r"[^a-z_.]", "", n.lower())
        )
        if not m or not (m.group(1) or m.group(3)) or (m.group(1) and m.group(3)):
            return None
        side = "left" if (m.group(1) or m.group(3)) == "l" else "right"
        low = m.group(2).replace("_", "").replace(".", "")
    for part, spellings in _PARTS.items():
        if low in spellings:
            return side, part
    return None


def find_arm_bones(names: list[str], path: Path, *, need_hand: bool) -> ArmBones:
    """Pick each arm's upper-arm, forearm (and hand) bone among ``names`` (first match in
    the given order); SkinnyInputError listing what is missing."""
    found: dict[tuple[str, str], str] = {}
    for name in names:
        kind = classify_arm_bone(name)
        if kind is not None and kind not in found:
            found[kind] = name
    parts = ("upper", "forearm") + (("hand",) if need_hand else ())
    missing = [f"{s} {p}" for s in ("right", "left") for p in parts if (s, p) not in found]
    if missing:
        raise SkinnyInputError(
            f"no arm bones found for {', '.join(missing)} (looked for names such as "
            "rhumerus/rradius, RightArm/RightForeArm/RightHand)",
            path=path,
        )

    def pair(p: str) -> tuple[str, str]:
        return found[("right", p)], found[("left", p)]

    hand = pair("hand") if all((s, "hand") in found for s in ("right", "left")) else None
    return ArmBones(pair("upper"), pair("forearm"), hand)
