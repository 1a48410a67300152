"""How the body is driven, and what each actuation adds to the one training path.

:func:`actuation_of` gives a run's :class:`VelocityActuation` (the thesis's servo: the
plain loop) or :class:`TorqueActuation` (the torque twin, :mod:`skinny_mj.training.torque`).
Each supplies the same parts, so :mod:`skinny_mj.training.loop` asks and never branches:

- ``n_extra_inputs`` and ``true_commands``: the ESN inputs the hook appends, and the
  inverse model's true target of a movement (the servo's analytic commands, the torque
  twin's inverse-dynamics torques);
- ``hook``: the rollout hook of a movement (:class:`skinny_mj.controllers.loop.Hook`; None
  for the servo);
- ``teacher_inputs`` and ``one_step``: the true-target architecture's extra
  teacher-forced inputs and its one-step position map (each None where the body has none);
- ``recorder``: FEL's per-cycle recorder (None, or the torque body's
  :class:`~skinny_mj.training.torque.ShareRecorder`) and ``recorded``, its metrics of a run;
- ``training_plant`` and ``test_plant``: the plant as it is (payload, masses, friction)
  and the robustness test's changes on top, made to a fresh plant;
- ``sensing_delay``: control steps by which the ESN's sensed input lags;
- ``test_figures``: a run's figures of the test cycle (None, or the torque figures);
- ``train_warnings``: MuJoCo warnings of the training plant (None for the servo).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from skinny_mj.controllers.methods import FELMethod
from skinny_mj.plant import ideal
from skinny_mj.plant.ideal import true_commands
from skinny_mj.training import torque
from skinny_mj.training.config import Torque, TrainConfig


@dataclass(frozen=True)
class VelocityActuation:
    """The velocity servo (the thesis's kinematic plant): the plain loop."""

    cfg: TrainConfig

    @property
    def n_extra_inputs(self) -> int:
        return 0

    def true_commands(self, trajectory, max_speed_rad_s: np.ndarray) -> np.ndarray:
        """(T-1, n_dof) the analytic velocity commands of ``trajectory``."""
        return true_commands(trajectory.angles, max_speed_rad_s, trajectory.dt)

    def hook(self, trajectory, max_speed_rad_s: np.ndarray, plant=None) -> None:
        return None

    def teacher_inputs(self, trajectory, max_speed_rad_s: np.ndarray) -> None:
        return None

    def one_step(self, trajectory, max_speed_rad_s: np.ndarray):
        """The kinematic one-step map of the true-target training's position error."""
        return ideal.one_step_positions(trajectory, self.cfg.plant.body, self.cfg.plant.signals,
                                        max_speed_rad_s)

    def recorder(self, method: FELMethod, n_runs: int) -> None:
        return None

    def recorded(self, recorder: Any, r: int) -> dict:
        return {}

    def test_plant(self, plant) -> None:
        """The servo's test plant is the nominal one."""

    def training_plant(self, plant) -> None:
        """The servo's training plant is the nominal one."""

    @property
    def sensing_delay(self) -> int:
        return 0

    def test_figures(self, hook: Any, rollout, plant, r: int) -> None:
        return None

    def train_warnings(self, run) -> None:
        return None


@dataclass(frozen=True)
class TorqueActuation:
    """The torque twin (:class:`skinny_mj.training.config.Torque`): the torque loop as the
    rollout hook, velocity inputs, the feedback share, the robustness test plant and the
    torque figures."""

    cfg: TrainConfig

    @property
    def settings(self) -> Torque:
        return self.cfg.actuation

    @property
    def n_extra_inputs(self) -> int:
        """:func:`skinny_mj.training.torque.n_extra_inputs`."""
        return torque.n_extra_inputs(self.cfg)

    def true_commands(self, trajectory, max_speed_rad_s: np.ndarray) -> np.ndarray:
        """(T-1, n_dof) :func:`skinny_mj.training.torque.true_torques` of ``trajectory``."""
        return torque.true_torques(self.cfg.plant.body, trajectory)

    def hook(self, trajectory, max_speed_rad_s: np.ndarray, plant=None):
        """:func:`skinny_mj.training.torque.hook_for`."""
        return torque.hook_for(self.cfg, trajectory, max_speed_rad_s, plant)

    def teacher_inputs(self, trajectory, max_speed_rad_s: np.ndarray) -> np.ndarray | None:
        """:func:`skinny_mj.training.torque.teacher_inputs`."""
        return torque.teacher_inputs(self.cfg, trajectory, max_speed_rad_s)

    def one_step(self, trajectory, max_speed_rad_s: np.ndarray) -> None:
        return None  # no kinematic one-step map for a torque

    def recorder(self, method: FELMethod, n_runs: int) -> torque.ShareRecorder:
        """The feedback's share of the command per epoch (:class:`ShareRecorder`)."""
        return torque.ShareRecorder(method.gains(), n_runs, method.learning_cycles,
                                    self.cfg.plant.body)

    def recorded(self, recorder: torque.ShareRecorder, r: int) -> dict:
        """Run r's training metrics of ``recorder``."""
        return recorder.metrics(r)

    def test_plant(self, plant) -> None:
        """The plant as it is plus the robustness test's changes
        (:func:`torque.change_plant`)."""
        torque.change_plant(self.settings, plant, test=True)

    def training_plant(self, plant) -> None:
        """The plant as it is (:func:`torque.change_plant`)."""
        torque.change_plant(self.settings, plant, test=False)

    @property
    def sensing_delay(self) -> int:
        """Control steps by which the sensing lags (:func:`torque.sensing_delay`)."""
        return torque.sensing_delay(self.settings)

    def test_figures(self, hook, rollout, plant, r: int) -> dict:
        """:func:`skinny_mj.training.torque.test_torques`."""
        return torque.test_torques(hook, rollout, plant, r)

    def train_warnings(self, run) -> int | None:
        """:func:`skinny_mj.training.torque.train_warnings`."""
        return torque.train_warnings(run)


Actuation = VelocityActuation | TorqueActuation


def actuation_of(cfg: TrainConfig) -> Actuation:
    """The actuation part of ``cfg``'s run."""
    return TorqueActuation(cfg) if isinstance(cfg.actuation, Torque) else VelocityActuation(cfg)
