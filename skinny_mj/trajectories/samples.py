"""Real motion capture shipped with the package: two CMU modern-dance trials (subject 05)
and their skeleton, in ``skinny_mj/data/mocap/cmu/`` (credit and terms in its README).

>>> from skinny_mj.trajectories import load_movement, sample_clip
>>> traj, report = load_movement(sample_clip("md_02"), "3d")  # doctest: +SKIP

An ``.amc`` without ``asf=`` finds its skeleton beside it by its CMU subject (``86_02.amc``:
``86.asf``); the shipped clips' subject ``md`` names ``moderndance.asf``
(:data:`SUBJECT_SKELETONS`), so a shipped clip needs no ``asf=``; :data:`SAMPLE_ASF` is that
skeleton, for loaders that want it explicitly.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from skinny_mj.errors import SkinnyInputError

#: The shipped clips (paper C's real movement is md_02).
SAMPLE_CLIPS = ("md_02", "md_03")
_FOLDER = Path(str(files("skinny_mj").joinpath("data", "mocap", "cmu")))
#: The skeleton of subject 05 the shipped clips belong to.
SAMPLE_ASF = _FOLDER / "moderndance.asf"
#: A clip's subject (its name up to the first "_") -> the stem of its skeleton's file,
#: where the two differ: the shipped clips md_02, md_03 are subject 05's, moderndance.asf.
SUBJECT_SKELETONS = {"md": "moderndance"}


def sample_clip(name: str) -> Path:
    """Installed path of a shipped ``.amc`` clip: ``"md_02"`` or ``"md_02.amc"``."""
    stem = name.removesuffix(".amc")
    if stem not in SAMPLE_CLIPS:
        raise SkinnyInputError(f"unknown sample clip {name!r}; shipped: {', '.join(SAMPLE_CLIPS)}")
    return _FOLDER / f"{stem}.amc"
