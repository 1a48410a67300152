"""Named training configurations for ``skinny train --preset NAME``.

``general`` is the inverse model the generalization matrix
(``skinny experiment generalization``, docs/results/generalization.md) found best on
movements it never saw: 2D Skinny with joint-angle signals, trained on motor babbling
(:mod:`skinny_mj.trajectories.babble`) with paper E's experiment-5 schedule. Test it on
any CMU clip with ``skinny test --model .../model.npz --trajectory CLIP.amc --asf
SKELETON.asf``.

With ``--actuation torque`` the same name picks the torque twin's ``general``
(:data:`TORQUE_PRESETS`): babbling slow enough for the motors' torque limits, learned by
FEL with the inertia-scaled PD teacher and the forgetting readout. The shipped clips
need more torque than the motors have at full speed; test it on them slowed down,
``skinny test --model .../model.npz --trajectory md_02.amc --speed 0.18``.
"""

from __future__ import annotations

from typing import Any

from skinny_mj.errors import SkinnyInputError

__all__ = ["PRESETS", "TORQUE_PRESETS", "preset_fields", "describe"]

#: Preset name -> (one-line reason, the dotted TrainConfig keys the preset sets).
PRESETS: dict[str, tuple[str, dict[str, Any]]] = {
    "general": (
        "2D, joint-angle signals, trained on 15 s of motor babbling (minimum-jerk moves "
        "between random targets over every joint's whole range, peak speeds 1-8 rad/s) "
        "with full scale = 4x its fastest speed per DOF, paper E exp. 5 schedule (N = 200), "
        "one washout cycle before the test: row j2-babble15-scale4, the lowest error on "
        "the unseen real clips in the generalization matrix (md_02 0.009, md_03 0.007)",
        {"plant.dof": 4, "plant.signals": "joint",
         "movement.trajectory": "babble:seed=0,duration=15",
         "movement.full_scale_factor": 4.0, "test.washout_cycles": 1},
    ),
}

#: The same names for ``--actuation torque``.
TORQUE_PRESETS: dict[str, tuple[str, dict[str, Any]]] = {
    "general": (
        "torque twin, 2D, joint-angle signals, trained on 15 s of motor babbling with "
        "peak speeds 0.5-4 rad/s (every step within the torque limits, peak "
        "|tau|/limit 0.43), FEL with the inertia-scaled PD teacher, beta = 1, 3 cycles "
        "x 15 epochs, readout on the normal equations with forgetting",
        {"plant.dof": 4, "plant.signals": "joint", "actuation": "torque",
         "movement.trajectory": "babble:seed=0,duration=15,vmin=0.5,vmax=4",
         "actuation.feedback": "inertia-pd", "rule.fit": "forgetting", "rule.beta": 1.0,
         "rule.cycles": 3, "rule.epochs": 15},
    ),
}


def _table(actuation: str) -> dict[str, tuple[str, dict[str, Any]]]:
    return TORQUE_PRESETS if actuation == "torque" else PRESETS


def preset_fields(name: str, actuation: str = "velocity") -> dict[str, Any]:
    """A copy of the dotted TrainConfig keys preset ``name`` sets for ``actuation``
    (``TrainConfig().override(preset_fields(name))`` is the preset's config)."""
    table = _table(actuation)
    if name not in table:
        raise SkinnyInputError(f"unknown preset {name!r}; known: {', '.join(table)}")
    return dict(table[name][1])


def describe(name: str, actuation: str = "velocity") -> str:
    return _table(actuation)[name][0]
