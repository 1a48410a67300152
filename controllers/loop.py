"""The closed loop's parts, typed: what the inverse model sees (``inputs``), where its
error signal comes from (a :class:`FeedbackController` or an actuation's :class:`Hook`),
an optional forward model, an optional per-step online learner, the sensory delay and the
learning rule a training refits the readout with.

A :class:`Loop` is built once from these parts; :func:`skinny_mj.controllers.rollout.rollout`,
:func:`skinny_mj.controllers.fel.train` and :func:`~skinny_mj.controllers.fel.evaluate` take it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.feedback import FeedbackController
from skinny_mj.controllers.learning import LearningRule

#: What the inverse model sees besides the forward model's prediction: the desired next
#: position and the sensed one (papers A, C, D, E), or the sensed one only (paper B).
INPUTS = ("desired+sensed", "sensed")


@runtime_checkable
class Hook(Protocol):
    """An actuation's part of the loop (the torque body's
    :class:`skinny_mj.controllers.torque_fel.TorqueLoop`): extra ESN inputs after all
    others, the motor error instead of the feedback controller's, a feed-forward added
    before the clip, a call after each step."""

    n_inputs: int  # extra ESN inputs per step

    def begin(self, plant, n_steps: int) -> None:
        """Called once after the plant's reset, for a cycle of ``n_steps`` states."""

    def inputs(self, t: int, plant) -> np.ndarray:
        """(R, n_inputs) extra ESN inputs at step t."""

    def u_error(self, t: int, desired: np.ndarray, sensed: np.ndarray, plant) -> np.ndarray:
        """(R, n_dof) motor error at state t (t = 0 .. T-1)."""

    def feedforward(self, t: int, plant) -> np.ndarray:
        """(R, n_dof) command added before the clip (not learned)."""

    def after_step(self, t: int, plant) -> None:
        """Called after the plant moved from state t to t+1."""


@runtime_checkable
class Forward(Protocol):
    """A forward model (:class:`skinny_mj.controllers.forward_model.ForwardModel`): its
    prediction p(t) is appended to the inverse model's input."""

    esn: ESN
    mode: str
    chained: bool

    def begin(self, plant) -> None: ...
    def step(self, position: np.ndarray, command: np.ndarray, noise: bool = True
             ) -> np.ndarray: ...
    def fit_rollout(self, ro, runs: np.ndarray | None = None): ...


@runtime_checkable
class Online(Protocol):
    """A per-step learner (:class:`skinny_mj.controllers.online.OnlineRLS`): at step t >= 1,
    once u_error(t) is known, ``update(state(t-1), y_ESN(t-1), y_est(t-1))``."""

    def update(self, state: np.ndarray, y_esn: np.ndarray, y_est: np.ndarray) -> None: ...


@dataclass(frozen=True)
class Loop:
    """The closed loop around the inverse model, built once.

    inputs : "desired+sensed" (ESN input [d(t+1); s_in(t)]) or "sensed" ([s_in(t)]); the
        forward model's p(t) and the hook's inputs are appended in both cases.
    feedback : the feedback controller (its u_error is the error signal unless ``hook``).
    hook : an actuation's :class:`Hook` (None: the plain velocity loop).
    forward : a :class:`Forward` model or None.
    online : an :class:`Online` learner updated inside the loop, or None.
    delay_steps : steps by which the ESN's sensed input s_in lags s(t) (paper A); the
        feedback controller always sees the undelayed s(t).
    target_lead : steps by which the error signal lags the arm (a sensing delay its teacher
        knows of): FEL pairs command(t) with u_error(t + 1 + target_lead)
        (:meth:`skinny_mj.controllers.rollout.Rollout.targets`); 0: u_error(t + 1).
    rule : the learning rule (:class:`skinny_mj.controllers.learning.LearningRule`) with
        which :func:`skinny_mj.controllers.fel.train` refits the readout; None: the
        thesis's fit of each learning cycle alone. One rule object serves one training (it
        may keep statistics between cycles). A rollout and a test do not use it.
    buffers : a dict the rollout keeps its arrays in and reuses on the next call with the
        same dict (fresh pages of a few MB per rollout cost about as much as the control
        step); the returned Rollout's arrays are then views that the next such call
        overwrites. None: fresh arrays. :func:`skinny_mj.controllers.fel.train` gives its
        loop one per training (:meth:`with_buffers`).
    """

    inputs: str = "desired+sensed"
    feedback: FeedbackController = field(default_factory=FeedbackController)
    hook: Hook | None = None
    forward: Forward | None = None
    online: Online | None = None
    delay_steps: int = 0
    target_lead: int = 0
    rule: LearningRule | None = None
    buffers: dict | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        if self.inputs not in INPUTS:
            raise ValueError(f"inputs must be one of {INPUTS}, got {self.inputs!r}")
        if self.delay_steps < 0:
            raise ValueError(f"delay must be >= 0 steps, got {self.delay_steps}")
        if self.target_lead < 0:
            raise ValueError(f"target lead must be >= 0 steps, got {self.target_lead}")
        if self.target_lead and self.online is not None:
            raise ValueError("a per-step learner takes u_error(t + 1) as its target; a "
                             "target lead needs a learning rule that fits the cycle")

    def with_buffers(self) -> Loop:
        """This loop with a fresh dict of reusable rollout arrays."""
        return dataclasses.replace(self, buffers={})

    def learning(self, online: Online | None) -> Loop:
        """This loop (same buffers) with ``online`` as its per-step learner."""
        return self if online is self.online else dataclasses.replace(self, online=online)
