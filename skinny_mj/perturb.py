"""A lasting change of the velocity-servo plant during performance (issue 16, item 4).

:class:`PerturbedPlant` wraps any :class:`controllers.plant.Plant` (e.g. a
:class:`skinny_mj.plant.BatchPlant`) and changes what a command does, per DOF:

    command sent to the servo = clip(gain * command, -1, 1) + offset

- ``gain`` (n_dof,): the actuator's effect; 0.7 = "actuator gain -30 %": every commanded
  joint speed, full scale included, is 30 % slower (the servo's max speed x 0.7);
- ``offset`` (n_dof,): a constant offset on a joint's command (a drifting motor: the
  joint turns at offset x full-scale speed when commanded to rest); the servo clips the
  sum to [-1, 1] as always.

The feedback controller is not told: :meth:`command_jacobian` stays the nominal
plant's (the controller's model of the arm is what it was), as for a real change.
``gain = 1, offset = 0`` (the defaults, or :meth:`undo`) passes commands through
unchanged, bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np


class PerturbedPlant:
    """A plant whose commands are scaled and offset per DOF (see the module docstring).

    Parameters
    ----------
    plant : the wrapped plant (R runs, n_dof commands).
    gain, offset : scalars or (n_dof,); defaults: no change.
    """

    def __init__(self, plant: Any, gain: float | np.ndarray = 1.0,
                 offset: float | np.ndarray = 0.0):
        self.plant = plant
        self.set(gain, offset)

    def set(self, gain: float | np.ndarray = 1.0, offset: float | np.ndarray = 0.0) -> None:
        """Change the plant (takes effect from the next step)."""
        n = self.plant.n_dof
        gain = np.broadcast_to(np.asarray(gain, float), (n,)).copy()
        offset = np.broadcast_to(np.asarray(offset, float), (n,)).copy()
        if not (np.all(np.isfinite(gain)) and np.all(gain >= 0)):
            raise ValueError(f"actuator gains must be finite and >= 0, got {gain}")
        if not (np.all(np.isfinite(offset)) and np.all(np.abs(offset) <= 1)):
            raise ValueError(f"command offsets must be in [-1, 1], got {offset}")
        self.gain, self.offset = gain, offset
        self.changed = bool(np.any(gain != 1.0) or np.any(offset != 0.0))

    def undo(self) -> None:
        """Back to the nominal plant."""
        self.set()

    def step(self, command: np.ndarray) -> np.ndarray:
        if not self.changed:
            return self.plant.step(command)
        sent = np.clip(np.asarray(command, float), -1.0, 1.0) * self.gain + self.offset
        return self.plant.step(np.clip(sent, -1.0, 1.0))

    def __getattr__(self, name: str) -> Any:  # the rest of the Plant protocol: as wrapped
        return getattr(self.plant, name)
