"""Named training configurations for ``skinny train --preset NAME``.

``general`` is the inverse model for movements it never saw, one per body and signal
(``--body 2d|3d``, ``--signals joint|cartesian``; by default 2D joint angles): each is the
configuration with the lowest error on the real CMU clips it never trained on in the
generalization study (``skinny experiment generalization --rows general,cartesian``,
docs/results/generalization.md). The Cartesian ones see each elbow's angle beside the
segment directions (``cartesian-elbow``, :data:`skinny_mj.plant.body.SIGNAL_SETS`): the
angle between the two segments, so a Cartesian target fixes it too. All train on motor babbling
(:mod:`skinny_mj.trajectories.babble`) with paper E's experiment-5 schedule. The trained
models ship with the package (:data:`SHIPPED`): ``skinny test --model general-3d-cartesian
--trajectory CLIP.amc --asf SKELETON.asf`` runs one without training.

On a torque body (``--body 2d-torque|3d-torque``, or ``--actuation torque``) the same
name picks the torque twin's ``general`` (:data:`TORQUE_GENERAL`, joint-angle signals):
motor babbling in desired joint angles, slow enough for the motors' torque limits, then
YMCA, learned by FEL with the inertia-scaled PD teacher and the forgetting readout; chosen
in the dynamic
study (``skinny experiment dynamic --rows general``, docs/results/dynamic.md). The
shipped clips need more torque than the motors have at full speed: test it on them as
shipped and slowed down to what the motors can do, ``skinny test --model
.../model.npz --trajectory md_02.amc --speed 0.18`` (the speeds per body:
:data:`skinny_mj.experiments.dynamic.general.FEASIBLE_SPEED`).
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path
from typing import Any

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.body import body_of

__all__ = ["GENERAL", "PRESETS", "TORQUE_GENERAL", "TORQUE_PRESETS", "TORQUE_DEFAULTS",
           "SHIPPED", "preset_fields", "torque_defaults", "describe", "model_name",
           "model_path"]

_LIMITS30 = "babble:seed=0,duration=30,limits=0.5,holds=0.2"
#: The joint-angle presets' keys (2D and 3D alike).
_JOINT = {"plant.signals": "joint", "movement.trajectory": _LIMITS30,
          "movement.full_scale_factor": 4.0, "test.washout_cycles": 1}
#: ``general`` per (the body's number of hinges, signals): (one-line reason, the dotted
#: TrainConfig keys).
GENERAL: dict[tuple[int, str], tuple[str, dict[str, Any]]] = {
    (4, "joint"): (
        "2D, joint-angle signals, trained on 30 s of motor babbling (minimum-jerk moves "
        "between random targets over every joint's whole range, peak speeds 1-8 rad/s) "
        "that also moves to the joint limits and rests (limits=0.5, holds=0.2), full "
        "scale = 4x its fastest speed per DOF, paper E exp. 5 schedule (N = 200), one "
        "washout cycle before the test: row j2-limits30-scale4 (unseen md_02 0.0078, md_03 "
        "0.0060, 10 seeds)",
        {"plant.body": "2d", **_JOINT},
    ),
    (8, "joint"): (
        "3D, joint-angle signals, trained on 30 s of babbling that also moves to the "
        "joint limits and rests (limits=0.5, holds=0.2), full scale 4x: row j3-general "
        "(unseen md_02 0.011, md_03 0.012, 10 seeds)",
        {"plant.body": "3d", **_JOINT},
    ),
    (4, "cartesian"): (
        "2D, Cartesian signals with each elbow's angle beside them (cartesian-elbow: the "
        "angle between the segments, which the Cartesian target already fixes), trained on "
        "60 s of babbling that also moves to the joint limits and rests (limits=0.5, "
        "holds=0.2), full scale 4x, the feedback controller's correction x3 in the "
        "learning targets: row c2-general+elbow (unseen md_02 0.027, md_03 0.022, 10 "
        "seeds; without the elbow angles 0.064 and 0.052)",
        {"plant.body": "2d", "plant.signals": "cartesian-elbow",
         "movement.trajectory": "babble:seed=0,duration=60,limits=0.5,holds=0.2",
         "movement.full_scale_factor": 4.0, "method.u_error_gain": 3.0,
         "test.washout_cycles": 1},
    ),
    (8, "cartesian"): (
        "3D, Cartesian signals with each elbow's angle beside them (cartesian-elbow), "
        "trained on 240 s of motor babbling then YMCA (joined by a minimum-jerk bridge), "
        "full scale 2x: row c3-babble15+ymca+elbow-babble240 (unseen md_02 0.029, md_03 "
        "0.026, 10 seeds; with 120 s of babbling 0.034 and 0.032, with 15 s 0.064 and "
        "0.048, without the elbow angles 0.127 and 0.100)",
        {"plant.body": "3d", "plant.signals": "cartesian-elbow",
         "movement.trajectory": "set:babble:seed=0,duration=240+ymca",
         "test.washout_cycles": 1},
    ),
}
#: Preset name -> (one-line reason, the dotted TrainConfig keys) of its default body.
PRESETS: dict[str, tuple[str, dict[str, Any]]] = {"general": GENERAL[4, "joint"]}
#: The trained general models shipped as package data (``skinny_mj/data/models``):
#: name -> (the body's number of hinges, signals); each file is ``skinny train --preset
#: general --body B --signals S --seed 0``'s model.npz, compressed, with its training
#: metadata.
SHIPPED: dict[str, tuple[int, str]] = {
    f"general-{'2d' if dof == 4 else '3d'}-{signals}": (dof, signals) for dof, signals in GENERAL}

#: ``general`` for the torque bodies, per number of hinges: (one-line reason, the dotted
#: TrainConfig keys). Joint-angle signals; the teacher and readout of the dynamic study's
#: ``fel-arm`` rows (inertia-scaled PD, beta = 1, forgetting readout); 240 s of slow
#: babbling, then YMCA, 3 learning cycles per epoch; the robot's sensing with velocities
#: from the model-based observer (the dynamic study's rows sense as an oracle instead).
_TORQUE_FEL = {"actuation": "torque", "plant.signals": "joint",
               "actuation.sensing.velocity": "observer",
               "actuation.feedback": "inertia-pd", "method.fit": "forgetting", "method.beta": 1.0,
               "movement.trajectory": "set:babble:seed=0,duration=240,vmin=0.5,vmax=4+ymca",
               "method.cycles": 3}
TORQUE_GENERAL: dict[int, tuple[str, dict[str, Any]]] = {
    4: ("torque twin, 2D, joint-angle signals, trained on 240 s of motor babbling at peak "
        "speeds 0.5-4 rad/s then YMCA (within the torque limits), FEL with the "
        "inertia-scaled PD teacher, beta = 1, 3 cycles x 30 epochs, readout on the normal "
        "equations with forgetting, velocities from the model-based observer: the shipped "
        "model general-2d-torque (seed 0: unseen md_02 at 0.18x speed 0.0133, md_03 at "
        "0.27x 0.0104)",
        {"plant.body": "2d-torque", **_TORQUE_FEL, "method.epochs": 30}),
    8: ("torque twin, 3D, joint-angle signals, trained on 240 s of motor babbling at peak "
        "speeds 0.5-4 rad/s then YMCA (within the torque limits), FEL with the "
        "inertia-scaled PD teacher at poles of 20 rad/s, beta = 1, 3 cycles x 15 epochs, "
        "readout on the normal equations with forgetting 0.9, velocities from the "
        "model-based observer: the shipped model general-3d-torque",
        {"plant.body": "3d-torque", **_TORQUE_FEL, "method.epochs": 15, "actuation.omega": 20.0,
         "method.fit.forgetting": 0.9}),
}
#: The same names for the torque bodies (``general``: the 2D body's).
TORQUE_PRESETS: dict[str, tuple[str, dict[str, Any]]] = {"general": TORQUE_GENERAL[4]}
#: The trained torque general models shipped beside :data:`SHIPPED`: name -> the body's
#: number of hinges; each file is ``skinny train --preset general --actuation torque
#: --dof D --seed 0``'s model.npz (the robot's sensing: encoder angles, velocities from
#: them), compressed, with its training metadata.
SHIPPED_TORQUE: dict[str, int] = {"general-2d-torque": 4, "general-3d-torque": 8}
#: Every shipped model's name.
SHIPPED_NAMES: tuple[str, ...] = (*SHIPPED, *SHIPPED_TORQUE)


#: What ``skinny train`` runs on a torque body without ``--preset``, per number of hinges:
#: (one-line reason, the dotted TrainConfig keys): ESN + FEL on the movement (YMCA unless
#: told) with the inertia-scaled PD teacher on the nominal model, beta = 1, 15 epochs of K
#: 1 -> 0, readout on the normal equations with forgetting, tested alone (K = 0), under the
#: robot's sensing with velocities from the model-based observer (the mismatch study's
#: ``esn`` rows, whose settings these are; the observer chosen on 3 seeds' YMCA test error
#: of both bodies). Under the flags and ``--config``; TrainConfig() itself keeps its
#: defaults.
_TORQUE_RECIPE = {"actuation": "torque", "actuation.feedback": "inertia-pd",
                  "actuation.sensing.velocity": "observer", "method": "new",
                  "method.beta": 1.0, "method.cycles": 3, "method.epochs": 15,
                  "method.fit": "forgetting", "test.gain": 0.0}
TORQUE_DEFAULTS: dict[int, tuple[str, dict[str, Any]]] = {
    4: ("torque twin, 2D: ESN + FEL with the inertia-scaled PD teacher on the nominal "
        "model (poles at 5 rad/s), beta = 1, 3 cycles x 15 epochs, readout on the normal "
        "equations with forgetting 0.8, velocities from the model-based observer",
        {"plant.body": "2d-torque", **_TORQUE_RECIPE}),
    8: ("torque twin, 3D: as 2D with 500 units, 6 cycles an epoch, the teacher's poles at "
        "20 rad/s and forgetting 0.9",
        {"plant.body": "3d-torque", **_TORQUE_RECIPE, "esn.n_reservoir": 500,
         "method.cycles": 6, "actuation.omega": 20.0, "method.fit.forgetting": 0.9}),
}


def torque_defaults(dof: int) -> dict[str, Any]:
    """A copy of the dotted keys ``skinny train`` sets first on the torque body of ``dof``
    hinges (:data:`TORQUE_DEFAULTS`; a body without its own: the 2D body's keys, on the
    body asked for)."""
    if dof in TORQUE_DEFAULTS:
        return dict(TORQUE_DEFAULTS[dof][1])
    return {k: v for k, v in TORQUE_DEFAULTS[4][1].items() if k != "plant.body"}


def _table(actuation: str) -> dict[str, tuple[str, dict[str, Any]]]:
    return TORQUE_PRESETS if actuation == "torque" else PRESETS


def _entry(name: str, actuation: str, dof: Any, signals: Any) -> tuple[str, dict[str, Any]]:
    table = _table(actuation)
    if name not in table:
        raise SkinnyInputError(f"unknown preset {name!r}; known: {', '.join(table)}")
    if name != "general" or (dof is None and (signals is None or actuation == "torque")):
        return table[name]
    try:
        dof = 4 if dof is None else int(dof)
    except (TypeError, ValueError):  # a bad dof is the config's own error, said there
        return table[name]
    if actuation == "torque":  # one per body, on joint-angle signals
        return TORQUE_GENERAL.get(dof, table[name])
    return GENERAL.get((dof, "joint" if signals is None else str(signals)), table[name])


def preset_fields(name: str, actuation: str = "velocity", *, dof: Any = None,
                  signals: Any = None, body: Any = None) -> dict[str, Any]:
    """A copy of the dotted TrainConfig keys preset ``name`` sets for ``actuation``
    (``TrainConfig().override(preset_fields(name))`` is the preset's config); ``general``
    on the velocity servo has one per number of hinges ``dof`` (4, 8) and ``signals``
    (joint, cartesian), None: 4 and joint. A ``body`` (a name) gives the number of hinges
    and the actuation of its MJCF."""
    if body is not None:
        skinny = body_of(body)
        dof, actuation = skinny.dof, skinny.actuation
    return dict(_entry(name, actuation, dof, signals)[1])


def describe(name: str, actuation: str = "velocity", *, dof: Any = None,
             signals: Any = None) -> str:
    return _entry(name, actuation, dof, signals)[0]


def model_name(dof: int, signals: str) -> str:
    """The shipped general model's name for a body and signals (``general-3d-cartesian``)."""
    return next(n for n, key in SHIPPED.items() if key == (dof, signals))


def model_path(model: str | Path) -> Path:
    """The file of a shipped model's name (:data:`SHIPPED`, :data:`SHIPPED_TORQUE`), else
    ``model`` as a path (a file of that name in the current folder comes first)."""
    path = Path(model)
    if str(model) in SHIPPED_NAMES and not path.exists():
        return Path(str(files("skinny_mj").joinpath("data", "models", f"{model}.npz")))
    return path
