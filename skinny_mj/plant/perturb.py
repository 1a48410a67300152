"""A lasting change of the plant during performance.

:class:`PerturbedPlant` wraps any :class:`skinny_mj.controllers.plant.Plant` (e.g. a
:class:`skinny_mj.plant.adapters.BatchPlant`) and changes what a command does, per DOF:

    command sent to the servo = clip(gain * command, -1, 1) + offset

- ``gain`` (n_dof,): the actuator's effect; 0.7 = "actuator gain -30 %": every commanded
  joint speed, full scale included, is 30 % slower (the servo's max speed x 0.7);
- ``offset`` (n_dof,): a constant offset on a joint's command (a drifting motor: the
  joint turns at offset x full-scale speed when commanded to rest); the servo clips the
  sum to [-1, 1] as always.

On a :class:`~skinny_mj.plant.adapters.BatchPlant` it also changes the body itself, in place in
the plant's ``MjModel`` (:class:`ModelChange`: the fields in which a variant model
differs from the nominal one), effective from the next reset (every cycle starts with
one):

- ``forearm``: the right forearm ``forearm`` x as long (:func:`lengthen_forearm`, a
  :class:`mujoco.MjSpec` variant of the body: the wrist, the hand and the forearm
  capsule's far end move out along the forearm);
- ``payload_kg``, ``mass_scale`` (the torque twin): a point mass at the right hand's
  centre of mass, every arm link's mass and inertia x ``mass_scale``, as
  :func:`perturb` makes the robustness test plant.

The feedback controller is not told: :meth:`command_jacobian` stays the nominal
plant's (the controller's model of the arm is what it was), as for a real change. With
a longer forearm the wrapped plant's Jacobian (from the real sites) has the forearm's
Cartesian rows x ``forearm`` (a segment's signals are its vector over the *nominal*
length); those rows are divided back, which is the nominal arm's Jacobian at the same
angles. ``gain = 1, offset = 0, forearm = 1, payload_kg = 0, mass_scale = 1`` (the
defaults, or :meth:`undo`) passes everything through unchanged, bit for bit.
"""

from __future__ import annotations

import copy
import functools
import types
from typing import Any

import mujoco
import numpy as np

from skinny_mj.plant import body
from skinny_mj.plant.body import BodyLike, body_of
from skinny_mj.plant.model import load_batch_model

#: the side whose forearm :func:`lengthen_forearm` lengthens by default
FOREARM_SIDE = "right"
#: Bodies whose mass and inertia ``actuation.test_mass_scale`` scales (both arms), and
#: the hand that carries ``actuation.test_payload_kg`` (a point mass at its centre of
#: mass: the hand's CoM and its inertia about the CoM are unchanged, only its mass grows).
ARM_BODIES = tuple(f"{side}_{seg}" for side in body.SIDES
                   for seg in ("upper_arm", "forearm", "hand"))
PAYLOAD_BODY = "right_hand"


def lengthen_forearm(spec: mujoco.MjSpec, factor: float, side: str = FOREARM_SIDE) -> None:
    """Edit one Skinny's spec in place: ``side``'s forearm ``factor`` x as long. The
    hand body (with the wrist site) moves out along the forearm, the forearm capsule's
    far end with it; masses stay (inertias follow the capsule's new shape on the
    velocity servo; the torque twin's explicit inertials stay nominal)."""
    if not (np.isfinite(factor) and factor > 0):
        raise ValueError(f"forearm factor must be > 0, got {factor}")
    geom = spec.geom(f"{side}_forearm")
    fromto = np.array(geom.fromto, float)
    fromto[3:] = fromto[:3] + factor * (fromto[3:] - fromto[:3])
    geom.fromto = fromto
    hand = spec.body(f"{side}_hand")
    hand.pos = factor * np.array(hand.pos, float)


def _array_fields(model: mujoco.MjModel) -> tuple[str, ...]:
    return tuple(n for n in dir(model) if not n.startswith("_")
                 and isinstance(getattr(model, n), np.ndarray))


_STAT_FIELDS = ("meaninertia", "meanmass", "meansize", "extent")


class ModelChange:
    """The fields in which ``variant`` differs from ``nominal`` (two compiled models of
    the same layout), to write into ``live`` (a plant's model, nominal so far) in
    place: :meth:`apply`, and :meth:`undo` back to ``live``'s own values. Fields that
    ``nominal`` and ``variant`` share (e.g. ``live``'s widened ctrl ranges) are never
    touched."""

    def __init__(self, live: mujoco.MjModel, nominal: mujoco.MjModel, variant: mujoco.MjModel):
        self.live = live
        self.fields = {}
        for name in _array_fields(nominal):
            old, new = getattr(nominal, name), getattr(variant, name)
            if old.shape != new.shape:
                raise ValueError(f"variant model differs in layout: {name} {old.shape} "
                                 f"vs {new.shape}")
            if not np.array_equal(old, new):
                self.fields[name] = (getattr(live, name).copy(), new.copy())
        self.stat = {n: (getattr(live.stat, n), getattr(variant.stat, n)) for n in _STAT_FIELDS}

    def apply(self) -> None:
        self._write(1)

    def undo(self) -> None:
        self._write(0)

    def _write(self, which: int) -> None:
        for name, values in self.fields.items():
            getattr(self.live, name)[...] = values[which]
        for name, values in self.stat.items():
            setattr(self.live.stat, name, values[which])


def perturb(plant, payload_kg: float = 0.0, mass_scale: float = 1.0,
            friction_nm: float = 0.0, damping_nm_s_rad: float = 0.0) -> None:
    """Change the plant's model fields in place (every copy of a batch): each arm
    link's ``body_mass`` and ``body_inertia`` x ``mass_scale`` (centres of mass kept),
    then ``payload_kg`` added to the right hand's mass at its centre of mass; every arm
    joint's Coulomb friction (``dof_frictionloss``) + ``friction_nm`` and viscous damping
    (``dof_damping``) + ``damping_nm_s_rad``; the derived constants are recomputed
    (``mj_setConst``). The controllers are not told."""
    if payload_kg == 0 and mass_scale == 1 and friction_nm == 0 and damping_nm_s_rad == 0:
        return
    model, data = (plant.model, plant.data) if hasattr(plant, "model") else \
        (plant.physics.model.ptr, plant.physics.data.ptr)
    for i in range(model.nbody):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, i) or ""
        base = name.rsplit("/", 1)[-1]
        if base in ARM_BODIES:
            model.body_mass[i] *= mass_scale
            model.body_inertia[i] *= mass_scale
        if base == PAYLOAD_BODY:
            model.body_mass[i] += payload_kg
    if friction_nm or damping_nm_s_rad:
        for j in range(model.njnt):
            base = (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.jnt_bodyid[j])
                    or "").rsplit("/", 1)[-1]
            if base in ARM_BODIES:
                adr = model.jnt_dofadr[j]
                model.dof_frictionloss[adr] += friction_nm
                model.dof_damping[adr] += damping_nm_s_rad
    mujoco.mj_setConst(model, data)


def forearm_change(plant: Any, factor: float) -> ModelChange:
    """The :class:`ModelChange` that lengthens ``plant``'s right forearms (every copy of
    a :class:`~skinny_mj.plant.adapters.BatchPlant`) ``factor`` x."""
    args = (plant.body, plant.n_runs)
    edit = functools.partial(lengthen_forearm, factor=factor)
    return ModelChange(plant.model, load_batch_model(*args), load_batch_model(*args, edit=edit))


def mass_change(plant: Any, payload_kg: float, mass_scale: float) -> ModelChange:
    """The :class:`ModelChange` of :func:`perturb` on
    ``plant``'s model (its present values are the nominal ones)."""
    variant = copy.copy(plant.model)  # a deep copy
    perturb(types.SimpleNamespace(model=variant, data=mujoco.MjData(variant)), payload_kg,
            mass_scale)
    return ModelChange(plant.model, plant.model, variant)


def forearm_rows(which: BodyLike, signals: str, side: str = FOREARM_SIDE) -> np.ndarray:
    """Indices of the Cartesian signals of ``side``'s forearm (wrist relative to elbow)."""
    if signals == "joint":
        return np.zeros(0, int)
    return np.array([i for i, n in enumerate(body_of(which).signal_names(signals))
                     if n.startswith(f"{side}_wrist_")])


class PerturbedPlant:
    """A plant whose commands are scaled and offset per DOF and whose body can change
    (see the module docstring).

    Parameters
    ----------
    plant : the wrapped plant (R runs, n_dof commands).
    gain, offset : scalars or (n_dof,); defaults: no change.
    """

    def __init__(self, plant: Any, gain: float | np.ndarray = 1.0,
                 offset: float | np.ndarray = 0.0):
        self.plant = plant
        self.forearm, self.payload_kg, self.mass_scale = 1.0, 0.0, 1.0
        self._model_change: ModelChange | None = None
        self.set(gain, offset)

    def set(self, gain: float | np.ndarray = 1.0, offset: float | np.ndarray = 0.0,
            forearm: float = 1.0, payload_kg: float = 0.0, mass_scale: float = 1.0) -> None:
        """Change the plant: commands from the next step, the body from the next reset."""
        n = self.plant.n_dof
        gain = np.broadcast_to(np.asarray(gain, float), (n,)).copy()
        offset = np.broadcast_to(np.asarray(offset, float), (n,)).copy()
        if not (np.all(np.isfinite(gain)) and np.all(gain >= 0)):
            raise ValueError(f"actuator gains must be finite and >= 0, got {gain}")
        if not (np.all(np.isfinite(offset)) and np.all(np.abs(offset) <= 1)):
            raise ValueError(f"command offsets must be in [-1, 1], got {offset}")
        self._set_body(float(forearm), float(payload_kg), float(mass_scale))
        self.gain, self.offset = gain, offset
        self.changed = bool(np.any(gain != 1.0) or np.any(offset != 0.0))

    def _set_body(self, forearm: float, payload_kg: float, mass_scale: float) -> None:
        if (forearm, payload_kg, mass_scale) == (self.forearm, self.payload_kg,
                                                 self.mass_scale):
            return
        if forearm != 1.0 and (payload_kg != 0.0 or mass_scale != 1.0):
            raise ValueError("change the forearm or the masses, not both at once")
        if not hasattr(self.plant, "model"):
            raise ValueError("body changes need a plant with an MjModel (BatchPlant)")
        if self._model_change is not None:
            self._model_change.undo()
            self._model_change = None
        if forearm != 1.0:
            self._model_change = forearm_change(self.plant, forearm)
        elif payload_kg != 0.0 or mass_scale != 1.0:
            self._model_change = mass_change(self.plant, payload_kg, mass_scale)
        if self._model_change is not None:
            self._model_change.apply()
        self.forearm, self.payload_kg, self.mass_scale = forearm, payload_kg, mass_scale

    def undo(self) -> None:
        """Back to the nominal plant."""
        self.set()

    def step(self, command: np.ndarray) -> np.ndarray:
        if not self.changed:
            return self.plant.step(command)
        sent = np.clip(np.asarray(command, float), -1.0, 1.0) * self.gain + self.offset
        return self.plant.step(np.clip(sent, -1.0, 1.0))

    def command_jacobian(self) -> np.ndarray:
        """The nominal arm's command Jacobian at the present angles (not told)."""
        jac = self.plant.command_jacobian()
        if self.forearm != 1.0:
            jac[:, forearm_rows(self.plant.body, self.plant.signals)] /= self.forearm
        return jac

    def __getattr__(self, name: str) -> Any:  # the rest of the Plant protocol: as wrapped
        return getattr(self.plant, name)
