"""Named training configurations for ``skinny train --preset NAME``.

``general`` is the inverse model the generalization matrix
(``skinny experiment generalization``, docs/results/generalization.md) found best on
movements it never saw: 2D Skinny with joint-angle signals, trained on motor babbling
(:mod:`skinny_mj.trajectories.babble`) with paper E's experiment-5 schedule. Test it on
any CMU clip with ``skinny test --model .../model.npz --trajectory CLIP.amc --asf
SKELETON.asf``.
"""

from __future__ import annotations

from typing import Any

from skinny_mj.errors import SkinnyInputError

__all__ = ["PRESETS", "preset_fields", "describe"]

#: Preset name -> (one-line reason, TrainConfig fields the preset sets).
PRESETS: dict[str, tuple[str, dict[str, Any]]] = {
    "general": (
        "2D, joint-angle signals, trained on 15 s of motor babbling (minimum-jerk moves "
        "between random targets over every joint's whole range, peak speeds 1-8 rad/s) "
        "with full scale = 4x its fastest speed per DOF, paper E exp. 5 schedule (N = 200), "
        "one washout cycle before the test: row j2-babble15-scale4, the lowest error on "
        "the unseen real clips in the generalization matrix (md_02 0.009, md_03 0.007)",
        {"dof": 4, "signals": "joint", "trajectory": "babble:seed=0,duration=15",
         "full_scale_factor": 4.0, "test_washout_cycles": 1},
    ),
}


def preset_fields(name: str) -> dict[str, Any]:
    """A copy of the TrainConfig fields preset ``name`` sets."""
    if name not in PRESETS:
        raise SkinnyInputError(f"unknown preset {name!r}; known: {', '.join(PRESETS)}")
    return dict(PRESETS[name][1])


def describe(name: str) -> str:
    return PRESETS[name][0]
